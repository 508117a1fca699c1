#!/usr/bin/python3
"""Siconos 4.4 against rubdyn's Moreau-Jean on the rotor rubbing at two planes
(cases/two-plane.toml: two frictional contacts, each with its own sprung ring).

Per step h (1e-5, 1e-6), over 30 ms:
1. Same scheme, two codes: Siconos (model_planes.py: MoreauJeanOSI(0.5), FrictionContact(2),
   Newton tolerance 1e-12, every relation frozen at the start of the step) against rubdyn
   `--solver mj --set solver.eta=1` (M at the end of the step, as Siconos): the largest
   difference of the orbit at R (x_r, y_r), of each ring's centre and of the whole state on the
   0.1 ms grid, the omega difference, the impacts, contacts and releases per plane in each code
   (and whether they fall on the same steps), the wall times.
2. Stock Siconos (relations re-evaluated at every Newton iterate) against the same rubdyn run and
   against rubdyn's default mj (eta = 1/2): the O(h) difference of two first-order schemes.
Each Siconos configuration runs with its 2D friction solver as in model.py (Lemke, Siconos'
default tolerance) and with SICONOS_FRICTION_2D_ENUM at a tolerance of 1e-12 (and, frozen, 1e-14):
every step's contact solution is audited against the Coulomb-Signorini law of its own problem
(model_planes.law_residual), and the first step that violates it is replayed (diagnose): that is
where the Lemke runs leave rubdyn (README, "Two contacts").

Usage: validation/siconos/run_planes.py [path/to/rubdyn] [--quick]
  --quick  10 ms only (a smoke run: prints, writes nothing)
Writes validation/siconos/table-planes.md; rubdyn's output folders go to out/siconos-planes/.
Needs python3-siconos: scripts/install-deps.sh --peer
"""
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)
from common import ROOT, grid_errors, machine, read_output, read_rows, script_args  # noqa: E402

try:
    import siconos.kernel  # noqa: F401
except ImportError:
    sys.stderr.write("validation/siconos: python3-siconos is not installed; run "
                     "scripts/install-deps.sh --peer (Debian package python3-siconos)\n")
    sys.exit(2)
import model_planes  # noqa: E402
from run import hstr, messages_to, siconos_version  # noqa: E402

RUBDYN, QUICK, OUT = script_args("siconos-planes")
CASE = os.path.join(ROOT, "cases", "two-plane.toml")
DT = 1e-4
T_END = 0.01 if QUICK else 0.03
STEPS = [1e-5, 1e-6]
KINDS = ("impact", "contact", "release")


def run_rubdyn(folder, args):
    """rubdyn run of the two-plane case; returns (summary, grid, events) with grid[k] the row
    at t = k DT as {column: value} and events as dicts (t, kind, contact 1-based)."""
    subprocess.run([RUBDYN, "run", CASE, "--out", folder, "--quiet", "--t-end", repr(T_END)]
                   + args, check=True, stdout=subprocess.DEVNULL)
    summary, grid, _ = read_output(folder, DT)
    events = [{"t": float(r["t"]), "kind": r["kind"], "contact": int(r["contact"])}
              for r in read_rows(os.path.join(folder, "events.csv"))]
    return summary, grid, events


def rubdyn_events(events, K, h):
    """Per plane: {kind: [step index]} for the kinds of KINDS (rubdyn logs at the step's end)."""
    out = [{k: [] for k in KINDS} for _ in range(K)]
    for e in events:
        if e["kind"] in KINDS:
            out[e["contact"] - 1][e["kind"]].append(round(e["t"] / h))
    return out


def siconos_events(info, h):
    return [{k: [round(t / h) for t in ev[k]] for k in KINDS} for ev in info["events"]]


def coords(p):
    """The output columns of q in rubdyn's names, in Siconos' dof order."""
    names = ["x_b", "y_b", "x_r", "y_r", "theta"]
    for k, g in enumerate(p["planes"]):
        if g["ring"] >= 0:
            names += ["x_s_%d" % (k + 1), "y_s_%d" % (k + 1)]
    return names


def siconos_run(path, *args, **kw):
    """model_planes.simulate with Siconos' C++ messages (its stdout and stderr) sent to the file
    path; returns simulate's result and the counts of the messages that report a failed contact
    solve ("output message from numerics solver is equal to 1") and a Newton loop that reached
    its iteration limit."""
    with messages_to(path):
        out = model_planes.simulate(*args, **kw)
    with open(path) as log:
        text = log.read()
    return out, text.count("numerics solver is equal to 1"), text.count("max. number of iter")


def diagnose(first_bad, h):
    """Replays the first contact problem whose Siconos-Lemke solution violates the law: the
    LCP that Siconos' fc2d Lemke solves (fc2d_tolcp) by Siconos' lexicographic Lemke (its info
    and LCP residual), and the problem by Siconos' fc2d ENUM with tolerance 1e-12 (its law
    residual). Returns a dict for the table."""
    import numpy as np
    import siconos.numerics as sn
    step, (W, q, mu, r) = first_bad
    m = len(q)
    out = {"t": step * h, "contacts": m // 2, "q_norm": float(np.linalg.norm(q)),
           "lemke_r": r.tolist(), "lemke_res": model_planes.law_residual(W, q, mu, r)}
    fc = sn.FrictionContactProblem(2, m // 2, W, q, mu)
    lcp = sn.LCP(np.eye(3 * (m // 2)), np.zeros(3 * (m // 2)))
    sn.fc2d_tolcp(fc, lcp)
    z = np.zeros(3 * (m // 2))
    w = np.zeros(3 * (m // 2))
    so = sn.SolverOptions(sn.SICONOS_LCP_LEMKE)
    out["lcp_info"] = sn.linearComplementarity_driver(lcp, z, w, so)
    A = np.array(lcp.M)
    ww = A @ z + np.array(lcp.q).ravel()
    out["lcp_z_max"] = float(abs(z).max())
    out["lcp_residual"] = float(max(abs(np.minimum(z, ww))))
    r2 = np.zeros(m)
    u2 = np.zeros(m)
    so = sn.SolverOptions(sn.SICONOS_FRICTION_2D_ENUM)
    so.dparam[0] = 1e-12
    out["enum_info"] = sn.fc2d_driver(sn.FrictionContactProblem(2, m // 2, W, q, mu), r2, u2, so)
    out["enum_r"] = r2.tolist()
    out["enum_res"] = model_planes.law_residual(W, q, mu, r2)
    return out


def differences(p, rows, grid, t_max=math.inf):
    """Siconos rows against a rubdyn grid: (orbit at R, omega at the last sample as
    common.grid_errors), the largest |z_s,k difference| per sprung ring, the largest difference
    of any coordinate and of any velocity, over the common 0.1 ms samples."""
    names = coords(p)
    sg = {round(t / DT): (q, v) for t, q, v, _ in rows}
    common = sorted(k for k in set(sg) & set(grid) if k * DT < t_max)
    orbit, omega = grid_errors({k: (sg[k][0][2], sg[k][0][3], sg[k][1][4]) for k in common},
                               {k: (grid[k]["x_r"], grid[k]["y_r"], grid[k]["omega"])
                                for k in common})
    rings = []
    for g in p["planes"]:
        d = g["ring"]
        if d < 0:
            rings.append(float("nan"))
            continue
        rings.append(max(math.hypot(sg[k][0][d] - grid[k][names[d]],
                                    sg[k][0][d + 1] - grid[k][names[d + 1]]) for k in common))
    dq = max(abs(sg[k][0][i] - grid[k][n]) for k in common for i, n in enumerate(names)
             if n != "theta")
    vnames = ["v" + n if n != "theta" else "omega" for n in names]
    dv = max(abs(sg[k][1][i] - grid[k][n]) for k in common for i, n in enumerate(vnames))
    return {"orbit": orbit, "omega": omega, "rings": rings, "dq": dq, "dv": dv}


VARIANTS = (  # (key, label, frozen, 2D friction solver, its tolerance)
    ("frozen", "Siconos frozen, Lemke", True, "LEMKE", None),
    ("frozen_enum", "Siconos frozen, ENUM 1e-12", True, "ENUM", 1e-12),
    ("frozen_enum14", "Siconos frozen, ENUM 1e-14", True, "ENUM", 1e-14),
    ("stock", "Siconos stock, Lemke", False, "LEMKE", None),
    ("stock_enum", "Siconos stock, ENUM 1e-12", False, "ENUM", 1e-12),
)


def main():
    p = model_planes.load_case(CASE)
    p["plugin"] = model_planes.build_plugin(p, os.path.join(OUT, "plugin"))
    K = len(p["planes"])
    results = []
    for h in STEPS:
        base = os.path.join(OUT, "h" + hstr(h))
        s_eta1, g_eta1, e_eta1 = run_rubdyn(os.path.join(base, "rubdyn-mj-eta1"),
                                            ["--solver", "mj", "--set", "solver.eta=1",
                                             "--h", repr(h)])
        s_def, g_def, _ = run_rubdyn(os.path.join(base, "rubdyn-mj"),
                                     ["--solver", "mj", "--h", repr(h)])
        ev_r = rubdyn_events(e_eta1, K, h)
        r = {"h": h, "steps": int(round(T_END / h)), "rubdyn_wall": s_eta1["wall_seconds"],
             "rubdyn_default_wall": s_def["wall_seconds"], "ev_rubdyn": ev_r, "v": {}}
        print("h=%-6s rubdyn mj eta=1: events per plane (impact/contact/release) %s, wall %.3f s"
              % (hstr(h), counts(ev_r), r["rubdyn_wall"]), flush=True)
        for key, label, frozen, solver, tol in VARIANTS:
            (rows, wall, info), fails, newton_max = siconos_run(
                os.path.join(base, "siconos-%s.stderr" % key), p, h, T_END, dt_out=DT,
                frozen=frozen, solver=solver, solver_tol=tol, audit=True)
            ev = siconos_events(info, h)
            x = {"label": label, "wall": wall, "info": info, "ev": ev, "fails": fails,
                 "newton_max": newton_max,
                 "eta1": differences(p, rows, g_eta1), "default": differences(p, rows, g_def),
                 "same_steps": [all(ev_r[k][y] == ev[k][y] for y in KINDS) for k in range(K)]}
            if info["first_bad"] is not None:
                # the agreement up to the first step whose contact solve violates the law
                x["before_bad"] = differences(p, rows, g_eta1, info["first_bad"][0] * h)
                x["diagnosis"] = diagnose(info["first_bad"], h)
                g = x["diagnosis"]
                print("h=%-6s %-26s first law violation at t = %.6f s (%d contacts, |q| = %.1f):"
                      " Siconos r = %s, residual %.1e / %.1e m/s; its LCP by Lemke: info %d, "
                      "max z %.2e, LCP residual %.1e; fc2d ENUM 1e-12: info %d, r = %s, residual "
                      "%.1e / %.1e m/s; orbit difference before it %.2e m" % (
                          hstr(h), label, g["t"], g["contacts"], g["q_norm"],
                          fmt_r(g["lemke_r"]), g["lemke_res"][0], g["lemke_res"][1],
                          g["lcp_info"], g["lcp_z_max"], g["lcp_residual"], g["enum_info"],
                          fmt_r(g["enum_r"]), g["enum_res"][0], g["enum_res"][1],
                          x["before_bad"]["orbit"]), flush=True)
            r["v"][key] = x
            d = x["eta1"]
            print("h=%-6s %-26s vs rubdyn mj eta=1: orbit %.2e m, rings %s m, any coordinate "
                  "%.2e m, any velocity %.2e, omega %.2e rad/s; events %s, same steps %s; law "
                  "residual %.1e / %.1e m/s on %d steps; Siconos-reported solver failures %d, "
                  "Newton at its limit %d; stray P_T %.1e; wall %.3f s" % (
                      hstr(h), label, d["orbit"], " ".join("%.2e" % y for y in d["rings"]),
                      d["dq"], d["dv"], d["omega"], counts(ev), x["same_steps"],
                      info["law_residual"][0], info["law_residual"][1], info["law_bad_steps"],
                      fails, newton_max, info["stray_P_T"], wall), flush=True)
            if not frozen:
                d = x["default"]
                print("h=%-6s %-26s vs rubdyn mj (eta=1/2): orbit %.2e m, rings %s m, omega "
                      "%.2e rad/s" % (hstr(h), label, d["orbit"],
                                      " ".join("%.2e" % y for y in d["rings"]), d["omega"]),
                      flush=True)
        results.append(r)
    if QUICK:
        print("quick run: nothing written")
        return
    write_table(p, results)


def fmt_r(r):
    return "(" + ", ".join("%.3e" % x for x in r) + ")"


def counts(ev):
    return "[" + ", ".join("/".join(str(len(e[k])) for k in KINDS) for e in ev) + "]"


def rings(d):
    return " | ".join("%.2e" % x for x in d["rings"])


def write_table(p, results):
    K = len(p["planes"])
    keys = [v[0] for v in VARIANTS]
    with open(os.path.join(HERE, "table-planes.md"), "w") as f:
        w = f.write
        w("# Siconos 4.4 against rubdyn, two frictional contacts (generated by "
          "validation/siconos/run_planes.py)\n\n")
        w("Machine: %s. Siconos %s (Debian python3-siconos). Case cases/two-plane.toml, %g ms, "
          "9 dofs, planes at s = %s. One run per point (the machine is shared).\n\n"
          % (machine(), siconos_version(), 1e3 * T_END,
             ", ".join("%g" % g["s"] for g in p["planes"])))
        w("Siconos: MoreauJeanOSI(0.5), FrictionContact(2), Newton tolerance 1e-12. *frozen*: "
          "both relations linearised at the start of the step (the scheme of rubdyn's mj); "
          "*stock*: re-evaluated at every Newton iterate. 2D friction solver: *Lemke* "
          "(SICONOS_FRICTION_2D_LEMKE with Siconos' default tolerance 1e-6, as model.py) or "
          "*ENUM tol* (SICONOS_FRICTION_2D_ENUM with its tolerance, relative to |q| of the "
          "contact problem, set to tol). *Law residual*: the largest distance of Siconos' "
          "impulses from the Coulomb-Signorini law of the step's own contact problem, as a "
          "velocity (model_planes.law_residual: Signorini / Coulomb), and the number of steps "
          "where it exceeds 1e-12 m/s. *Failures*: the contact solves that Siconos itself "
          "reports as failed (its warning 'output message from numerics solver is equal to "
          "1'); *Newton at 50 iterations*: its warning that the Newton loop stopped at its "
          "limit.\n\n")
        w("## Same scheme, two codes: against rubdyn `--solver mj --set solver.eta=1`\n\n"
          "Largest differences over the 0.1 ms grid (omega: at the last sample).\n\n")
        w("| h [s] | Siconos | orbit at R [m] | ring 1 [m] | ring 2 [m] | any coordinate [m] | "
          "any velocity [m/s, rad/s] | omega [rad/s] | law residual [m/s] | steps > 1e-12 | "
          "failures | Newton at 50 iterations |\n" + "|---" * 12 + "|\n")
        for r in results:
            for key in keys:
                x = r["v"][key]
                d = x["eta1"]
                w("| %s | %s | %.2e | %s | %.2e | %.2e | %.2e | %.1e / %.1e | %d | %d | %d |\n"
                  % (hstr(r["h"]), x["label"], d["orbit"], rings(d), d["dq"], d["dv"],
                     d["omega"], x["info"]["law_residual"][0], x["info"]["law_residual"][1],
                     x["info"]["law_bad_steps"], x["fails"], x["newton_max"]))
        w("\n### The first contact solve that violates the law\n\nFor each run with a law "
          "residual above 1e-12 m/s: its first such step, the orbit difference to rubdyn up to "
          "that step, Siconos' impulses r = (r_N, r_T) per contact, and that problem solved "
          "again: the LCP of Siconos' Lemke (fc2d_tolcp) by Siconos' lexicographic Lemke (its "
          "info at the default tolerance, its largest variable, its complementarity residual "
          "|min(z, w)|), and the problem by fc2d ENUM at 1e-12.\n\n")
        w("| h [s] | Siconos | t [s] | orbit diff. before [m] | norm of q | Siconos r | law "
          "residual [m/s] | LCP Lemke: info, max z, residual | ENUM 1e-12 r | its law "
          "residual [m/s] "
          "|\n|---|---|---|---|---|---|---|---|---|---|\n")
        for r in results:
            for key in keys:
                x = r["v"][key]
                if "diagnosis" not in x:
                    continue
                g = x["diagnosis"]
                w("| %s | %s | %.6f | %.2e | %.1f | %s | %.1e / %.1e | %d, %.2e, %.1e | %s | "
                  "%.1e / %.1e |\n" % (
                      hstr(r["h"]), x["label"], g["t"], x["before_bad"]["orbit"], g["q_norm"],
                      fmt_r(g["lemke_r"]), g["lemke_res"][0], g["lemke_res"][1],
                      g["lcp_info"], g["lcp_z_max"], g["lcp_residual"], fmt_r(g["enum_r"]),
                      g["enum_res"][0], g["enum_res"][1]))
        w("\n### Events per plane\n\nImpact / contact / release as rubdyn's fixed-step run loop "
          "logs them (events.csv: a plane is closed in a step when its impulse is not zero; "
          "free to closed with v_N < 0 at the start of the step is an impact, otherwise a "
          "contact; closed to free a release), and the same rule on Siconos' impulses (lambda(1)"
          " of each interaction, closed when P_N > 0). *same*: every event of the plane on the "
          "same step index as rubdyn's. Closed steps: the steps with P_N > 0.\n\n")
        w("| h [s] | plane | rubdyn | " + " | ".join(
            "%s | same | closed steps" % v[1] for v in VARIANTS) + " |\n|---|---|---|" +
            "---|---|---|" * len(VARIANTS) + "\n")
        for r in results:
            for k in range(K):
                cells = []
                for key in keys:
                    x = r["v"][key]
                    cells.append("%s | %s | %d" % (
                        counts([x["ev"][k]])[1:-1], "yes" if x["same_steps"][k] else "no",
                        x["info"]["events"][k]["closed_steps"]))
                w("| %s | %d | %s | %s |\n" % (hstr(r["h"]), k + 1,
                                               counts([r["ev_rubdyn"][k]])[1:-1],
                                               " | ".join(cells)))
        w("\n### Wall times\n\nStepping loops only (Siconos: its Python-driven loop as in "
          "model.py, plug-in compilation and the law audit excluded; rubdyn: its summary's "
          "wall_seconds, output included).\n\n| h [s] | steps | rubdyn mj eta=1 [s] | " +
          " | ".join("%s [s]" % v[1] for v in VARIANTS) + " |\n|---|---|---|" +
          "---|" * len(VARIANTS) + "\n")
        for r in results:
            w("| %s | %d | %.3f | %s |\n" % (
                hstr(r["h"]), r["steps"], r["rubdyn_wall"],
                " | ".join("%.3f" % r["v"][key]["wall"] for key in keys)))
        w("\n## Stock Siconos against rubdyn at the same h\n\nStock Siconos against rubdyn's mj "
          "with eta = 1 (as in the first table) and with its default eta = 1/2.\n\n| h [s] | "
          "Siconos | rubdyn | orbit at R [m] | ring 1 [m] | ring 2 [m] | omega [rad/s] |\n"
          "|---|---|---|---|---|---|---|\n")
        for r in results:
            for key in keys:
                if not key.startswith("stock"):
                    continue
                x = r["v"][key]
                for which, what in (("eta1", "mj, eta = 1"), ("default", "mj")):
                    d = x[which]
                    w("| %s | %s | %s | %.2e | %s | %.2e |\n" % (
                        hstr(r["h"]), x["label"], what, d["orbit"], rings(d), d["omega"]))


if __name__ == "__main__":
    main()
