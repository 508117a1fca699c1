#!/usr/bin/python3
"""Siconos 4.4 (Debian's python3-siconos) as an external peer of rubdyn's fixed-step schemes.

1. Stock Siconos: MoreauJeanOSI (theta = 1/2) with TimeStepping, and the projected variant
   (MoreauJeanDirectProjectionOSI + TimeSteppingDirectProjection), on the reference case for
   (a) 30 ms and (b) 0.5 s, at h = 1e-5, 1e-6, 1e-7, each with two 2D friction contact solvers:
   Siconos' fc2d Lemke (default tolerance) and fc2d ENUM at tolerance 1e-12. Errors against
   rubdyn's event-driven reference (rtol 1e-13), measured exactly as in validation/work-precision.
   results.csv holds the peer's solver (PEER below) and is read by work-precision/run.py, which
   puts Siconos on the plot and checks goal (d).
2. Same scheme, two codes: Siconos configured to take exactly the steps rubdyn's mj and mj-proj
   take (relation linearised at the start of the step, M at the end of the step = rubdyn's
   solver.eta = 1, Euclidean projection metric = solver.projection = "identity"), compared with
   rubdyn at the same h, with both contact solvers. Written to agreement.csv.
3. The law audit: every contact problem Siconos solves in these runs (every Newton iteration of
   every step) is checked against the Coulomb-Signorini law independently of Siconos
   (model.law_check, residuals in m/s, tolerance model.LAW_TOL = 1e-12 m/s).
The runs that give the audit and the trajectories go through the audited contact problem (a
Python subclass, which costs time); the wall times come from a second, plain run of the peer's
solver, checked to give bitwise the same trajectory.

Runs of more than AUDIT_MAX_STEPS steps (0.5 s at h = 1e-7: 5 million) run only the peer's solver,
plainly (no audit, no second solver): the audited runs cost about twice the plain one's CPU
time and these four would take most of an hour on this machine; --full-audit runs them too.

Usage: validation/siconos/run.py [path/to/rubdyn] [--quick] [--short] [--full-audit]
                                 [--long-audit]
  --quick       30 ms only, h = 1e-5 and 1e-6 (a smoke run; do not commit its output)
  --short       30 ms only, all steps (prints the audit and the agreement; writes nothing)
  --long-audit  only the law audit of Lemke on 0.5 s at h = 1e-7 (stock mj and mj-proj): the
                runs the default leaves unaudited; prints, writes nothing (about 7 minutes each
                on this machine when it is busy)
Needs python3-siconos: scripts/install-deps.sh --peer
"""
import contextlib
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)
from common import CASE, grid_errors, machine, run_case, script_args, write_csv  # noqa: E402,E501

try:
    import siconos.kernel  # noqa: F401
except ImportError:
    sys.stderr.write("validation/siconos: python3-siconos is not installed; run "
                     "scripts/install-deps.sh --peer (Debian package python3-siconos)\n")
    sys.exit(2)
import model  # noqa: E402

RUBDYN, QUICK, OUT = script_args("siconos")
SHORT = "--short" in sys.argv
AUDIT_MAX_STEPS = None if "--full-audit" in sys.argv else 500000
DT = 1e-4
CASES = {"30ms": 0.03, "0.5s": 0.5}
STEPS = {"30ms": [1e-5, 1e-6, 1e-7], "0.5s": [1e-5, 1e-6, 1e-7]}
AGREE_STEPS = [1e-5, 1e-6]
if QUICK:
    CASES = {"30ms": 0.03}
    STEPS = {"30ms": [1e-5, 1e-6]}
    AGREE_STEPS = [1e-5]
if SHORT:
    CASES = {"30ms": 0.03}
# 2D friction contact solvers of Siconos' numerics: key -> (SICONOS_FRICTION_2D_<name>, its
# tolerance (None: Siconos' default, 1e-6 relative to |q|), label)
CONTACT_SOLVERS = {"lemke": ("LEMKE", None, "Lemke"), "enum": ("ENUM", 1e-12, "ENUM 1e-12")}
# the peer's contact solver: its runs go to results.csv and the first table
PEER = "lemke"
SCHEMES = (("siconos-mj", False), ("siconos-mj-proj", True))


def grid_of(rows):
    """rows of model.simulate -> {k: (x_r, y_r, omega)} on the 0.1 ms grid, as common.run_case."""
    return {round(t / DT): (q[model.XR], q[model.YR], v[model.TH]) for t, q, v, _, _ in rows}


def hstr(h):
    return "%g" % h


def same_rows(a, b):
    """True when two runs' sampled rows are bitwise equal."""
    return len(a) == len(b) and all(
        x[0] == y[0] and (x[1] == y[1]).all() and (x[2] == y[2]).all() and x[3] == y[3]
        and x[4] == y[4] for x, y in zip(a, b))


@contextlib.contextmanager
def messages_to(path):
    """Siconos' C++ messages (file descriptors 1 and 2) written to the file path inside the
    block, the terminal's restored after it (also run_planes.py)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with open(path, "w") as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            yield
        finally:
            for fd, s in zip((1, 2), saved):
                os.dup2(s, fd)
                os.close(s)


def run_siconos(p, h, t_end, projected, frozen, cs, log):
    """The audited Siconos run with contact solver cs; returns (rows, info) with info["audit"]
    the LawAudit. Siconos' own messages go to the file log."""
    solver, tol, _ = CONTACT_SOLVERS[cs]
    with messages_to(log):
        rows, _, info = model.simulate(p, h, t_end, projected=projected, dt_out=DT,
                                       frozen=frozen, solver=solver, solver_tol=tol, audit=True)
    return rows, info


def replay(bad):
    """A violating problem (t, W, q, mu, r) solved again by fc2d ENUM at 1e-12: its law residual
    and impulses, next to Siconos' r and residual."""
    import numpy as np
    import siconos.numerics as sn
    t, W, q, mu, r = bad
    m = len(q)
    r2 = np.zeros(m)
    u2 = np.zeros(m)
    so = sn.SolverOptions(sn.SICONOS_FRICTION_2D_ENUM)
    so.dparam[0] = 1e-12
    info = sn.fc2d_driver(sn.FrictionContactProblem(2, m // 2, W, q, np.array(mu, float)), r2,
                          u2, so)
    return {"t": t, "q_norm": float(np.linalg.norm(q)), "r": list(r),
            "res": model.law_check(W, q, mu, r), "enum_info": info, "enum_r": list(r2),
            "enum_res": model.law_check(W, q, mu, r2)}


def audit_line(label, info):
    a = info["audit"].summary()
    return ("audit %-40s solves %8d (steps %8d, Newton it. %8d) violations %d (steps %d) "
            "residual max %.1e m/s (Signorini %.1e, cone %.1e, friction %.1e) failures %d" % (
                label, a["law_solves"], a["law_steps"], info["newton_iterations"],
                a["law_violations"], a["law_violating_steps"], a["law_residual_max"],
                a["law_signorini_max"], a["law_cone_max"], a["law_friction_max"],
                a["contact_solver_failures"]))


def audit_entry(case, scheme, h, cs, info):
    a = info["audit"]
    e = {"case": case, "scheme": scheme, "h": hstr(h), "contact_solver": cs,
         "newton_iterations": info["newton_iterations"], **a.summary()}
    if a.worst_bad is not None:
        e["worst"] = replay(a.worst_bad)
        e["first"] = replay(a.first_bad)
    return e


def long_audit():
    """The law audit of the Lemke runs that main() leaves unaudited (0.5 s at h = 1e-7)."""
    p = model.load_case(CASE)
    p["plugin"] = model.build_plugin(p, os.path.join(OUT, "plugin"))
    h, t_end = 1e-7, 0.5
    os.makedirs(os.path.join(OUT, "0.5s"), exist_ok=True)
    for solver, projected in SCHEMES:
        name = "%s-lemke-h%s" % (solver, hstr(h))
        _, info = run_siconos(p, h, t_end, projected, False, "lemke",
                              os.path.join(OUT, "0.5s", name + ".log"))
        print(audit_line("0.5s %s" % name, info), flush=True)
        a = info["audit"]
        if a.worst_bad is not None:
            for which, bad in (("first", a.first_bad), ("worst", a.worst_bad)):
                x = replay(bad)
                print("  %s violation: t = %.7f s, r = %s, residual %.1e m/s; ENUM 1e-12: r = %s, "
                      "residual %.1e m/s" % (which, x["t"], fmt_r(x["r"]), max(x["res"]),
                                             fmt_r(x["enum_r"]), max(x["enum_res"])), flush=True)


def main():
    if "--long-audit" in sys.argv:
        long_audit()
        return
    p = model.load_case(CASE)
    p["plugin"] = model.build_plugin(p, os.path.join(OUT, "plugin"))
    results, agreement, audits, refs, stock = [], [], [], {}, {}
    for case, t_end in CASES.items():
        te = ["--t-end", repr(t_end)]
        ref_s, ref_g, _ = run_case(RUBDYN, os.path.join(OUT, case, "reference-rtol1e-13"),
                                   te + ["--rtol", "1e-13", "--atol", "1e-15"], DT)
        refs[case] = ref_s
        for h in STEPS[case]:
            # rubdyn's mj at the same h (its defaults: eta = 1/2, relation at q_i)
            mj_s, mj_g, _ = run_case(RUBDYN, os.path.join(OUT, case, "rubdyn-mj-h" + hstr(h)),
                                     te + ["--solver", "mj", "--h", repr(h)], DT)
            audited = AUDIT_MAX_STEPS is None or round(t_end / h) <= AUDIT_MAX_STEPS
            for solver, projected in SCHEMES:
                for cs in CONTACT_SOLVERS if audited else [PEER]:
                    name = "%s-%s-h%s" % (solver, cs, hstr(h))
                    wall = float("nan")
                    if audited:
                        rows, info = run_siconos(p, h, t_end, projected, False, cs,
                                                 os.path.join(OUT, case, name + ".log"))
                        print(audit_line("%s %s" % (case, name), info), flush=True)
                        audits.append(audit_entry(case, solver, h, cs, info))
                        stock[(t_end, h, solver, cs)] = rows
                    else:
                        rows, wall, info = model.simulate(
                            p, h, t_end, projected=projected, dt_out=DT,
                            solver=CONTACT_SOLVERS[cs][0], solver_tol=CONTACT_SOLVERS[cs][1])
                    if cs == PEER and audited:
                        # the timed run: plain FrictionContact, same trajectory to the bit
                        rows_t, wall, _ = model.simulate(
                            p, h, t_end, projected=projected, dt_out=DT,
                            solver=CONTACT_SOLVERS[cs][0], solver_tol=CONTACT_SOLVERS[cs][1])
                        if not same_rows(rows, rows_t):
                            sys.exit("the audited and the plain run of %s differ" % name)
                    g = grid_of(rows)
                    orbit, omega = grid_errors(g, ref_g)
                    d_mj = grid_errors(g, mj_g)
                    model.write_timeseries(os.path.join(OUT, case, name + ".csv"), rows, p)
                    a = info["audit"].summary() if audited else {
                        "law_solves": "", "law_violations": "", "law_residual_max": ""}
                    results.append({
                        "solver": solver, "h": hstr(h), "t_end": t_end, "wall_seconds": wall,
                        "omega_error": omega, "orbit_error": orbit,
                        "max_penetration": info["max_penetration"], "steps": info["steps"],
                        "newton_iterations": info["newton_iterations"],
                        "orbit_diff_rubdyn_mj": d_mj[0], "omega_diff_rubdyn_mj": d_mj[1],
                        "rubdyn_mj_wall_seconds": mj_s["wall_seconds"],
                        "rubdyn_mj_orbit_error": grid_errors(mj_g, ref_g)[0],
                        "contact_solver": CONTACT_SOLVERS[cs][2],
                        "law_solves": a["law_solves"], "law_violations": a["law_violations"],
                        "law_residual_max": a["law_residual_max"]})
                    print("%-5s %-16s %-10s h=%-6s orbit %.2e omega %.2e pen %.1e wall %.3f s "
                          "(rubdyn mj: %.3f s); vs rubdyn mj: orbit %.2e omega %.2e" % (
                              case, solver, cs, hstr(h), orbit, omega, info["max_penetration"],
                              wall, mj_s["wall_seconds"], d_mj[0], d_mj[1]), flush=True)
                # the two contact solvers' trajectories against each other
                d_ls = ("", "")
                if audited:
                    d_ls = grid_errors(grid_of(stock[(t_end, h, solver, "lemke")]),
                                       grid_of(stock[(t_end, h, solver, "enum")]))
                for r in results[-(len(CONTACT_SOLVERS) if audited else 1):]:
                    r["orbit_diff_lemke_enum"], r["omega_diff_lemke_enum"] = d_ls
    # Same scheme in both codes (30 ms)
    t_end = 0.03
    for h in AGREE_STEPS:
        for scheme, projected, extra in (
                ("mj", False, ["--set", "solver.eta=1"]),
                ("mj-proj", True, ["--set", "solver.eta=1", "--set", "solver.projection=identity"])):
            _, g_r, _ = run_case(RUBDYN, os.path.join(OUT, "agree", "rubdyn-%s-h%s" % (
                scheme, hstr(h))), ["--t-end", "0.03", "--solver", scheme, "--h", repr(h)] + extra,
                DT)
            for cs in CONTACT_SOLVERS:
                name = "frozen-%s-%s-h%s" % (scheme, cs, hstr(h))
                rows, info = run_siconos(p, h, t_end, projected, True, cs,
                                         os.path.join(OUT, "agree", name + ".log"))
                print(audit_line(name, info), flush=True)
                audits.append(audit_entry("30ms", "frozen " + scheme, h, cs, info))
                d = grid_errors(grid_of(rows), g_r)
                d_stock = grid_errors(grid_of(stock[(t_end, h, "siconos-" + scheme, cs)]), g_r)
                agreement.append({"scheme": scheme, "h": hstr(h), "t_end": t_end,
                                  "contact_solver": CONTACT_SOLVERS[cs][2],
                                  "orbit_diff_same_scheme": d[0], "omega_diff_same_scheme": d[1],
                                  "orbit_diff_stock_siconos": d_stock[0],
                                  "omega_diff_stock_siconos": d_stock[1],
                                  "law_solves": info["audit"].solves,
                                  "law_violations": info["audit"].violations,
                                  "law_residual_max": info["audit"].worst})
                print("agree %-7s %-10s h=%-6s same scheme: orbit %.2e m omega %.2e rad/s; stock "
                      "Siconos: orbit %.2e m omega %.2e rad/s" % (
                          scheme, cs, hstr(h), d[0], d[1], d_stock[0], d_stock[1]), flush=True)
    if QUICK or SHORT:
        print("quick/short run: nothing written")
        return
    # Cost of driving the time loop from Python: the same stock run by Siconos' own C++ loop
    h = 1e-6
    solver, tol, _ = CONTACT_SOLVERS[PEER]
    _, wall_py, _ = model.simulate(p, h, 0.03, dt_out=DT, solver=solver, solver_tol=tol)
    wall_cpp = model.simulate_native_loop(p, h, 0.03, solver, tol)
    peer = CONTACT_SOLVERS[PEER][2]
    write_csv(os.path.join(HERE, "results.csv"),
              [r for r in results if r["contact_solver"] == peer])
    write_csv(os.path.join(HERE, "agreement.csv"), agreement)
    write_table(results, agreement, audits, refs, wall_py, wall_cpp)


def fmt_row(r):
    return ("| %s | %s | %s | %.2e | %.2e | %.1e | %.3g | %.2e | %.2e | %.3g |" % (
        {0.03: "30 ms", 0.5: "0.5 s"}[r["t_end"]], r["solver"], r["h"], r["orbit_error"],
        r["omega_error"], r["max_penetration"], r["wall_seconds"], r["orbit_diff_rubdyn_mj"],
        r["rubdyn_mj_orbit_error"], r["rubdyn_mj_wall_seconds"]))


def fmt_r(r):
    return "(" + ", ".join("%.4e" % x for x in r) + ")"


def write_table(results, agreement, audits, refs, wall_py, wall_cpp):
    peer = CONTACT_SOLVERS[PEER][2]
    labels = [c[2] for c in CONTACT_SOLVERS.values()]
    with open(os.path.join(HERE, "table.md"), "w") as f:
        w = f.write
        w("# Siconos 4.4 against rubdyn (generated by validation/siconos/run.py)\n\n")
        w("Machine: %s. Siconos %s (Debian python3-siconos). One run per point (the\n"
          "machine is shared: compare ratios).\n\n" % (machine(), siconos_version()))
        for case, s in refs.items():
            w("- %s: reference = rubdyn event-driven rtol 1e-13, omega(t_end) = %.10f "
              "rad/s, %.3f s wall.\n" % (case, s["omega_final"], s["wall_seconds"]))
        w("- Siconos' 2D friction contact solver: *Lemke* (SICONOS_FRICTION_2D_LEMKE, Siconos' "
          "default tolerance 1e-6 relative to |q|) or *ENUM 1e-12* (SICONOS_FRICTION_2D_ENUM, "
          "tolerance 1e-12). The peer (first table, results.csv): **%s**.\n" % peer)
        w("- Python drives Siconos' time loop here; the same stock MJ run (30 ms, h = 1e-6, %s)"
          " takes %.3f s in this loop and %.3f s in Siconos' own C++ loop "
          "(TimeStepping::run): the Python share is %.0f %%.\n\n" % (
              peer, wall_py, wall_cpp, 100 * max(0.0, wall_py - wall_cpp) / wall_py))
        w("## Law audit: every contact problem Siconos solved\n\nEvery call of Siconos' "
          "FrictionContact::compute with a non-empty index set (one per Newton iteration), "
          "checked independently of Siconos (model.law_check, from its W, q and impulses r, "
          "u = W r + q): Signorini |min(u_N, W_NN r_N)|, cone W_TT max(0, |r_T| - mu r_N), "
          "friction |W_TT r_T - clip(W_TT r_T - u_T, +-mu W_TT r_N)| (sticking, and sliding "
          "against the friction impulse), in m/s. A solve violates the law when its largest "
          "residual exceeds %g m/s (model.LAW_TOL: 50x the round-off of the 100 m/s sliding "
          "speed). *Failures*: solves Siconos itself reports as failed (info != 0).\n\n"
          % model.LAW_TOL)
        w("| case | scheme | h [s] | contact solver | Newton iterations | solves checked | "
          "steps with a solve | violating solves | violating steps | largest residual [m/s] | "
          "Signorini / cone / friction [m/s] | failures |\n|" + "---|" * 12 + "\n")
        for a in audits:
            w("| %s | %s | %s | %s | %d | %d | %d | %d | %d | %.1e | %.1e / %.1e / %.1e | %d |\n"
              % (a["case"], a["scheme"], a["h"], CONTACT_SOLVERS[a["contact_solver"]][2],
                 a["newton_iterations"], a["law_solves"], a["law_steps"], a["law_violations"],
                 a["law_violating_steps"], a["law_residual_max"], a["law_signorini_max"],
                 a["law_cone_max"], a["law_friction_max"], a["contact_solver_failures"]))
        tot = {}
        for a in audits:
            t = tot.setdefault(a["contact_solver"], [0, 0, 0.0])
            t[0] += a["law_solves"]
            t[1] += a["law_violations"]
            t[2] = max(t[2], a["law_residual_max"])
        skipped = ["%s %s h = %s" % ({0.03: "30 ms", 0.5: "0.5 s"}[r["t_end"]], r["solver"], r["h"])
                   for r in results if r["law_solves"] == ""]
        if skipped:
            w("\nNot audited (more than %d steps; run.py --full-audit runs them): %s, %s only."
              "\n" % (AUDIT_MAX_STEPS, ", ".join(skipped), peer))
        w("\nIn all: " + "; ".join("%s %d solves checked, %d violating, largest residual %.1e m/s"
                                    % (CONTACT_SOLVERS[k][2], v[0], v[1], v[2])
                                    for k, v in tot.items()) + ".\n")
        bad = [a for a in audits if "worst" in a]
        if bad:
            w("\nThe violating solves: the first and the worst per run, Siconos' impulses r = "
              "(r_N, r_T), and the same problem by fc2d ENUM at 1e-12.\n\n| case | scheme | h "
              "[s] | contact solver | which | t [s] | norm of q | Siconos r | its residual "
              "[m/s] | ENUM r | its residual [m/s] |\n|" + "---|" * 11 + "\n")
            for a in bad:
                for which in ("first", "worst"):
                    x = a[which]
                    w("| %s | %s | %s | %s | %s | %.7f | %.1f | %s | %.1e | %s | %.1e |\n" % (
                        a["case"], a["scheme"], a["h"], CONTACT_SOLVERS[a["contact_solver"]][2],
                        which, x["t"], x["q_norm"], fmt_r(x["r"]), max(x["res"]),
                        fmt_r(x["enum_r"]), max(x["enum_res"])))
        w("\n## Stock Siconos (%s) against the event-driven reference, and against rubdyn's mj "
          "at the same h\n\n" % peer)
        w("| case | solver | h [s] | orbit error [m] | omega error [rad/s] | max "
          "penetration [m] | wall [s] | orbit diff. to rubdyn mj [m] | rubdyn mj orbit "
          "error [m] | rubdyn mj wall [s] |\n|" + "---|" * 10 + "\n")
        for r in results:
            if r["contact_solver"] == peer:
                w(fmt_row(r) + "\n")
        w("\n## The two contact solvers side by side (stock Siconos)\n\n| case | solver | h [s] |"
          + "".join(" orbit error, %s [m] |" % l for l in labels)
          + "".join(" orbit diff. to rubdyn mj, %s [m] |" % l for l in labels)
          + "".join(" omega diff. to rubdyn mj, %s [rad/s] |" % l for l in labels)
          + " Lemke - ENUM, orbit on the grid [m] |\n|" + "---|" * (4 + 3 * len(labels)) + "\n")
        keyed = {(r["t_end"], r["h"], r["solver"], r["contact_solver"]): r for r in results}
        for r in results:
            if r["contact_solver"] != labels[0] or r["orbit_diff_lemke_enum"] == "":
                continue
            rr = [keyed[(r["t_end"], r["h"], r["solver"], l)] for l in labels]
            w("| %s | %s | %s |%s%s%s %.2e |\n" % (
                {0.03: "30 ms", 0.5: "0.5 s"}[r["t_end"]], r["solver"], r["h"],
                "".join(" %.2e |" % x["orbit_error"] for x in rr),
                "".join(" %.2e |" % x["orbit_diff_rubdyn_mj"] for x in rr),
                "".join(" %.2e |" % x["omega_diff_rubdyn_mj"] for x in rr),
                r["orbit_diff_lemke_enum"]))
        w("\n## Same scheme, two codes (30 ms)\n\nSiconos with the relation frozen at the "
          "start of the step (positions in the system's z vector) against rubdyn with "
          "solver.eta = 1 (and solver.projection = identity for mj-proj); *stock*: stock Siconos "
          "against the same rubdyn run. Both contact solvers side by side.\n\n")
        w("| scheme | h [s] |" + "".join(" orbit diff., %s [m] |" % l for l in labels)
          + "".join(" omega diff., %s [rad/s] |" % l for l in labels)
          + "".join(" stock: orbit diff., %s [m] |" % l for l in labels)
          + "".join(" stock: omega diff., %s [rad/s] |" % l for l in labels)
          + "\n|" + "---|" * (2 + 4 * len(labels)) + "\n")
        ak = {(a["scheme"], a["h"], a["contact_solver"]): a for a in agreement}
        for a in agreement:
            if a["contact_solver"] != labels[0]:
                continue
            aa = [ak[(a["scheme"], a["h"], l)] for l in labels]
            w("| %s | %s |%s\n" % (a["scheme"], a["h"], "".join(
                " %.2e |" % x[k] for k in ("orbit_diff_same_scheme", "omega_diff_same_scheme",
                                          "orbit_diff_stock_siconos",
                                          "omega_diff_stock_siconos") for x in aa)))


def siconos_version():
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"],
                             capture_output=True, text=True, check=True).stdout
        return out.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


if __name__ == "__main__":
    main()
