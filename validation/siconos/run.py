#!/usr/bin/python3
"""Siconos 4.4 (Debian's python3-siconos) as an external peer of rubdyn's fixed-step schemes.

1. Stock Siconos: MoreauJeanOSI (theta = 1/2) with TimeStepping, and the projected variant
   (MoreauJeanDirectProjectionOSI + TimeSteppingDirectProjection), 2D friction contact solved by
   Lemke, on the reference case for (a) 30 ms and (b) 0.5 s, at h = 1e-5, 1e-6, 1e-7. Errors
   against rubdyn's event-driven reference (rtol 1e-13), measured exactly as in
   validation/work-precision; results.csv is read by work-precision/run.py, which puts Siconos
   on the plot and checks goal (d).
2. Same scheme, two codes: Siconos configured to take exactly the steps rubdyn's mj and mj-proj
   take (relation linearised at the start of the step, M at the end of the step = rubdyn's
   solver.eta = 1, Euclidean projection metric = solver.projection = "identity"), compared with
   rubdyn at the same h. Written to agreement.csv.

Usage: validation/siconos/run.py [path/to/rubdyn] [--quick]
  --quick  30 ms only, h = 1e-5 and 1e-6 (a smoke run; do not commit its output)
Needs python3-siconos: scripts/install-deps.sh --peer
"""
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
DT = 1e-4
CASES = {"30ms": 0.03, "0.5s": 0.5}
STEPS = {"30ms": [1e-5, 1e-6, 1e-7], "0.5s": [1e-5, 1e-6, 1e-7]}
AGREE_STEPS = [1e-5, 1e-6]
if QUICK:
    CASES = {"30ms": 0.03}
    STEPS = {"30ms": [1e-5, 1e-6]}
    AGREE_STEPS = [1e-5]


def grid_of(rows):
    """rows of model.simulate -> {k: (x_r, y_r, omega)} on the 0.1 ms grid, as common.run_case."""
    return {round(t / DT): (q[model.XR], q[model.YR], v[model.TH]) for t, q, v, _, _ in rows}



def hstr(h):
    return "%g" % h


def main():
    p = model.load_case(CASE)
    p["plugin"] = model.build_plugin(p, os.path.join(OUT, "plugin"))
    results, agreement, refs = [], [], {}
    for case, t_end in CASES.items():
        te = ["--t-end", repr(t_end)]
        ref_s, ref_g, _ = run_case(RUBDYN, os.path.join(OUT, case, "reference-rtol1e-13"),
                                   te + ["--rtol", "1e-13", "--atol", "1e-15"], DT)
        refs[case] = ref_s
        for h in STEPS[case]:
            # rubdyn's mj at the same h (its defaults: eta = 1/2, relation at q_i)
            mj_s, mj_g, _ = run_case(RUBDYN, os.path.join(OUT, case, "rubdyn-mj-h" + hstr(h)),
                                     te + ["--solver", "mj", "--h", repr(h)], DT)
            for solver, projected in (("siconos-mj", False), ("siconos-mj-proj", True)):
                rows, wall, info = model.simulate(p, h, t_end, projected=projected, dt_out=DT)
                g = grid_of(rows)
                orbit, omega = grid_errors(g, ref_g)
                d_mj = grid_errors(g, mj_g)
                path = os.path.join(OUT, case, "%s-h%s.csv" % (solver, hstr(h)))
                model.write_timeseries(path, rows, p)
                results.append({
                    "solver": solver, "h": hstr(h), "t_end": t_end, "wall_seconds": wall,
                    "omega_error": omega, "orbit_error": orbit,
                    "max_penetration": info["max_penetration"], "steps": info["steps"],
                    "newton_iterations": info["newton_iterations"],
                    "orbit_diff_rubdyn_mj": d_mj[0], "omega_diff_rubdyn_mj": d_mj[1],
                    "rubdyn_mj_wall_seconds": mj_s["wall_seconds"],
                    "rubdyn_mj_orbit_error": grid_errors(mj_g, ref_g)[0]})
                print("%-5s %-16s h=%-6s orbit %.2e omega %.2e pen %.1e wall %.3f s "
                      "(rubdyn mj: %.3f s); vs rubdyn mj: orbit %.2e omega %.2e" % (
                          case, solver, hstr(h), orbit, omega, info["max_penetration"], wall,
                          mj_s["wall_seconds"], d_mj[0], d_mj[1]), flush=True)
    # Same scheme in both codes (30 ms)
    t_end = 0.03
    for h in AGREE_STEPS:
        for scheme, projected, extra in (
                ("mj", False, ["--set", "solver.eta=1"]),
                ("mj-proj", True, ["--set", "solver.eta=1", "--set", "solver.projection=identity"])):
            _, g_r, _ = run_case(RUBDYN, os.path.join(OUT, "agree", "rubdyn-%s-h%s" % (
                scheme, hstr(h))), ["--t-end", "0.03", "--solver", scheme, "--h", repr(h)] + extra,
                DT)
            rows, _, _ = model.simulate(p, h, t_end, projected=projected, dt_out=DT, frozen=True)
            d = grid_errors(grid_of(rows), g_r)
            rows_stock, _, _ = model.simulate(p, h, t_end, projected=projected, dt_out=DT)
            d_stock = grid_errors(grid_of(rows_stock), g_r)
            agreement.append({"scheme": scheme, "h": hstr(h), "t_end": t_end,
                              "orbit_diff_same_scheme": d[0], "omega_diff_same_scheme": d[1],
                              "orbit_diff_stock_siconos": d_stock[0],
                              "omega_diff_stock_siconos": d_stock[1]})
            print("agree %-7s h=%-6s same scheme: orbit %.2e m omega %.2e rad/s; stock Siconos: "
                  "orbit %.2e m omega %.2e rad/s" % (scheme, hstr(h), d[0], d[1], d_stock[0],
                                                     d_stock[1]), flush=True)
    # Cost of driving the time loop from Python: the same stock run by Siconos' own C++ loop
    h = 1e-6
    _, wall_py, _ = model.simulate(p, h, 0.03, dt_out=DT)
    wall_cpp = model.simulate_native_loop(p, h, 0.03)
    if QUICK:
        print("quick run: nothing written")
        return
    write_csv(os.path.join(HERE, "results.csv"), results)
    write_csv(os.path.join(HERE, "agreement.csv"), agreement)
    write_table(results, agreement, refs, wall_py, wall_cpp)


def fmt_row(r):
    return ("| %s | %s | %s | %.2e | %.2e | %.1e | %.3g | %.2e | %.2e | %.3g |" % (
        {0.03: "30 ms", 0.5: "0.5 s"}[r["t_end"]], r["solver"], r["h"], r["orbit_error"],
        r["omega_error"], r["max_penetration"], r["wall_seconds"], r["orbit_diff_rubdyn_mj"],
        r["rubdyn_mj_orbit_error"], r["rubdyn_mj_wall_seconds"]))


def write_table(results, agreement, refs, wall_py, wall_cpp):
    with open(os.path.join(HERE, "table.md"), "w") as f:
        f.write("# Siconos 4.4 against rubdyn (generated by validation/siconos/run.py)\n\n")
        f.write("Machine: %s. Siconos %s (Debian python3-siconos). One run per point (the\n"
                "machine is shared: compare ratios).\n\n" % (machine(), siconos_version()))
        for case, s in refs.items():
            f.write("- %s: reference = rubdyn event-driven rtol 1e-13, omega(t_end) = %.10f "
                    "rad/s, %.3f s wall.\n" % (case, s["omega_final"], s["wall_seconds"]))
        f.write("- Python drives Siconos' time loop here; the same stock MJ run (30 ms, h = 1e-6)"
                " takes %.3f s in this loop and %.3f s in Siconos' own C++ loop "
                "(TimeStepping::run): the Python share is %.0f %%.\n\n" % (
                    wall_py, wall_cpp, 100 * max(0.0, wall_py - wall_cpp) / wall_py))
        f.write("## Stock Siconos against the event-driven reference, and against rubdyn's mj "
                "at the same h\n\n")
        f.write("| case | solver | h [s] | orbit error [m] | omega error [rad/s] | max "
                "penetration [m] | wall [s] | orbit diff. to rubdyn mj [m] | rubdyn mj orbit "
                "error [m] | rubdyn mj wall [s] |\n|" + "---|" * 10 + "\n")
        for r in results:
            f.write(fmt_row(r) + "\n")
        f.write("\n## Same scheme, two codes (30 ms)\n\nSiconos with the relation frozen at the "
                "start of the step (positions in the system's z vector) against rubdyn with "
                "solver.eta = 1 (and solver.projection = identity for mj-proj); the last two "
                "columns: stock Siconos against the same rubdyn run.\n\n")
        f.write("| scheme | h [s] | orbit diff. [m] | omega diff. [rad/s] | stock: orbit diff. "
                "[m] | stock: omega diff. [rad/s] |\n|---|---|---|---|---|---|\n")
        for a in agreement:
            f.write("| %s | %s | %.2e | %.2e | %.2e | %.2e |\n" % (
                a["scheme"], a["h"], a["orbit_diff_same_scheme"], a["omega_diff_same_scheme"],
                a["orbit_diff_stock_siconos"], a["omega_diff_stock_siconos"]))


def siconos_version():
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"],
                             capture_output=True, text=True, check=True).stdout
        return out.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


if __name__ == "__main__":
    main()
