#!/usr/bin/python3
"""Work-precision study: error against wall time for every solver of rubdyn (and Siconos, when
validation/siconos/results.csv exists), on (a) the first 30 ms and (b) the full 0.5 s of the
reference case.

Error: against the event-driven run at rtol = 1e-13 (atol 1e-15 m), whose own accuracy is shown
by its difference to rtol = 1e-12 (printed in the table header; see also
validation/self-convergence). Two measures per run:
  orbit error  max over the 0.1 ms output grid of |r_r - r_r,ref| (rotor centre, metres)
  omega error  |omega(t_end) - omega_ref(t_end)| (rad/s)
Wall time: summary.json's wall_seconds (the integration loop including the writing of the
output rows, excluding start-up and case parsing), median of several runs (5 below 0.5 s,
3 below 3 s, else 1).

Writes results.csv, table.md and work-precision.png next to this script.
Usage: validation/work-precision/run.py [path/to/rubdyn] [--quick]
  --quick  fewer points and one repetition (a smoke run; do not commit its output)
"""
import csv
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import ROOT, grid_errors, machine, run_case, script_args, write_csv  # noqa: E402

RUBDYN, QUICK, OUT = script_args("work-precision")
DT = 1e-4

CASES = {"30ms": 0.03, "0.5s": 0.5}
EVENT_RTOLS = ["1e-5", "1e-6", "1e-7", "1e-8", "1e-9", "1e-10", "1e-11", "1e-12"]
FIXED = ["carp-onevc", "carp-qn", "mj", "mj-proj"]
# steps that divide the 0.1 ms output interval, so that every scheme writes the same grid
STEPS = {"30ms": ["1e-4", "2e-5", "1e-5", "5e-6", "2e-6", "1e-6", "5e-7", "2e-7", "1e-7", "5e-8"],
         "0.5s": ["1e-4", "2e-5", "1e-5", "5e-6", "2e-6", "1e-6", "5e-7", "2e-7", "1e-7"]}
if QUICK:
    EVENT_RTOLS = ["1e-6", "1e-9", "1e-12"]
    STEPS = {"30ms": ["1e-5", "1e-6"], "0.5s": ["1e-5"]}


def repetitions(wall):
    if QUICK:
        return 1
    return 5 if wall < 0.5 else 3 if wall < 3.0 else 1


def measure(name, args):
    """Runs once, then repeats for the median wall time; returns (summary, grid, walls)."""
    folder = os.path.join(OUT, name)
    summary, grid, _ = run_case(RUBDYN, folder, args, DT)
    walls = [summary["wall_seconds"]]
    for _ in range(repetitions(walls[0]) - 1):
        s, _, _ = run_case(RUBDYN, folder, args, DT)
        walls.append(s["wall_seconds"])
    return summary, grid, walls



def event_args(rtol):
    return ["--rtol", rtol, "--atol", "%.0e" % (float(rtol) * 1e-2)]


def run_all():
    rows, refs = [], {}
    for case, t_end in CASES.items():
        te = ["--t-end", repr(t_end)]
        ref_s, ref_g, _ = run_case(RUBDYN, os.path.join(OUT, case, "reference-rtol1e-13"),
                                   te + ["--rtol", "1e-13", "--atol", "1e-15"], DT)
        chk_s, chk_g, _ = run_case(RUBDYN, os.path.join(OUT, case, "check-rtol1e-12"),
                                   te + ["--rtol", "1e-12", "--atol", "1e-14"], DT)
        refs[case] = (ref_s, grid_errors(chk_g, ref_g), ref_g[max(ref_g)][2])
        jobs = [("event-bdf", "rtol", r, event_args(r) + ["--method", "bdf"])
                for r in EVENT_RTOLS]
        jobs += [("event-adams", "rtol", r, event_args(r) + ["--method", "adams"])
                 for r in EVENT_RTOLS]
        jobs += [(s, "h", h, ["--solver", s, "--h", h]) for s in FIXED for h in STEPS[case]]
        for solver, pname, pval, args in jobs:
            name = os.path.join(case, "%s-%s%s" % (solver, pname, pval))
            s, g, walls = measure(name, te + args)
            orbit, omega = grid_errors(g, ref_g)
            rows.append({
                "case": case, "solver": solver, "parameter": pname, "value": pval,
                "termination": s["termination"], "t_reached": s["t_reached"],
                "orbit_error": orbit, "omega_error": omega,
                "max_penetration": s["max_penetration"], "steps": s["steps"],
                "wall_median": statistics.median(walls), "wall_min": min(walls),
                "wall_max": max(walls), "repetitions": len(walls)})
            print("%-5s %-11s %s=%-6s %-10s orbit %.2e omega %.2e wall %.4f s (%d)" % (
                case, solver, pname, pval, s["termination"], orbit, omega,
                rows[-1]["wall_median"], len(walls)), flush=True)
    return rows, refs


def siconos_rows():
    """Siconos points written by validation/siconos/run.py (same error measures)."""
    path = os.path.join(ROOT, "validation", "siconos", "results.csv")
    if not os.path.exists(path):
        return []
    out = []
    with open(path) as f:
        for r in csv.DictReader(f):
            case = {0.03: "30ms", 0.5: "0.5s"}.get(round(float(r["t_end"]), 6))
            if case is None:
                continue
            out.append({"case": case, "solver": r["solver"], "parameter": "h", "value": r["h"],
                        "termination": "completed", "t_reached": float(r["t_end"]),
                        "orbit_error": float(r["orbit_error"]),
                        "omega_error": float(r["omega_error"]),
                        "max_penetration": float(r["max_penetration"]), "steps": "",
                        "wall_median": float(r["wall_seconds"]),
                        "wall_min": float(r["wall_seconds"]),
                        "wall_max": float(r["wall_seconds"]), "repetitions": 1})
    return out


def event_wall_for(rows, case, metric, level):
    """Cheapest event-driven (BDF or Adams) run of `case` whose error is at most `level`."""
    ok = [r for r in rows if r["case"] == case and r["solver"].startswith("event")
          and r["termination"] == "completed" and r[metric] <= level]
    return min(ok, key=lambda r: r["wall_median"]) if ok else None


def goals(rows):
    lines = []
    a = [r for r in rows if r["case"] == "30ms" and r["solver"].startswith("event")
         and r["orbit_error"] <= 1e-9 and r["omega_error"] <= 1e-6]
    if a:
        best = min(a, key=lambda r: r["wall_median"])
        lines.append("(a) 30 ms, orbit error <= 1e-9 m and omega error <= 1e-6 rad/s: %s rtol %s, "
                     "orbit %.2e m, omega %.2e rad/s, %.1f ms wall (goal: <= 20 ms): %s" % (
                         best["solver"], best["value"], best["orbit_error"],
                         best["omega_error"], 1e3 * best["wall_median"],
                         "met" if best["wall_median"] <= 0.02 else "NOT met"))
    else:
        lines.append("(a) 30 ms: no event-driven run reached 1e-9 m and 1e-6 rad/s: NOT met")
    b = [r for r in rows if r["case"] == "0.5s" and r["solver"].startswith("event")
         and r["omega_error"] <= 1e-6]
    if b:
        best = min(b, key=lambda r: r["wall_median"])
        lines.append("(b) 0.5 s, omega error <= 1e-6 rad/s: %s rtol %s, omega %.2e rad/s, "
                     "orbit %.2e m, %.1f ms wall (goal: <= 250 ms): %s" % (
                         best["solver"], best["value"], best["omega_error"],
                         best["orbit_error"], 1e3 * best["wall_median"],
                         "met" if best["wall_median"] <= 0.25 else "NOT met"))
    else:
        lines.append("(b) 0.5 s: no event-driven run reached 1e-6 rad/s: NOT met")
    # (c): for every other solver's point, the cheapest event run at least as accurate in both
    # measures; the speed-up is the ratio of the median walls
    worst = None
    for r in rows:
        if r["solver"].startswith("event") or r["termination"] != "completed":
            continue
        ok = [e for e in rows if e["case"] == r["case"] and e["solver"].startswith("event")
              and e["termination"] == "completed" and e["orbit_error"] <= r["orbit_error"]
              and e["omega_error"] <= r["omega_error"]]
        if not ok:
            lines.append("(c) no event-driven run is as accurate as %s %s h=%s" % (
                r["case"], r["solver"], r["value"]))
            continue
        e = min(ok, key=lambda x: x["wall_median"])
        ratio = r["wall_median"] / e["wall_median"]
        if worst is None or ratio < worst[0]:
            worst = (ratio, r, e)
    if worst:
        ratio, r, e = worst
        lines.append("(c) smallest speed-up of the event-driven solver over any other point at "
                     "equal or better accuracy (orbit and omega): %.1fx (%s %s h=%s, %.3g s, vs "
                     "%s rtol %s, %.3g s): %s" % (
                         ratio, r["case"], r["solver"], r["value"], r["wall_median"],
                         e["solver"], e["value"], e["wall_median"],
                         "met" if ratio > 1 else "NOT met"))
    # (c) crossover: per case, the most accurate fixed-step point that the event-driven solver
    # does not beat (slower at equal or better accuracy on both measures, or never as accurate);
    # below its orbit error the event-driven solver is the fastest at every point
    for case in CASES:
        lost = []
        for r in rows:
            if (r["case"] != case or r["solver"].startswith("event") or
                    r["solver"].startswith("siconos") or r["termination"] != "completed"):
                continue
            ok = [e for e in rows if e["case"] == case and e["solver"].startswith("event")
                  and e["termination"] == "completed" and e["orbit_error"] <= r["orbit_error"]
                  and e["omega_error"] <= r["omega_error"]]
            if not ok or min(e["wall_median"] for e in ok) >= r["wall_median"]:
                lost.append(r)
        if not lost:
            lines.append("(c) crossover, %s: the event-driven solver is faster than every "
                         "fixed-step point at equal or better accuracy" % case)
        else:
            r = min(lost, key=lambda x: x["orbit_error"])
            lines.append("(c) crossover, %s: the event-driven solver is the fastest at every "
                         "fixed-step point with an orbit error below %.1e m; above it %d points "
                         "are cheaper (the most accurate: %s h=%s, orbit %.1e m, omega %.1e "
                         "rad/s, %.3g s)" % (case, r["orbit_error"], len(lost), r["solver"],
                                             r["value"], r["orbit_error"], r["omega_error"],
                                             r["wall_median"]))
    sic = [r for r in rows if r["solver"] == "siconos-mj" and float(r["value"]) == 1e-7]
    for r in sic:
        # the cheapest event-driven run at least as accurate on both measures
        ok = [e for e in rows if e["case"] == r["case"] and e["solver"].startswith("event")
              and e["termination"] == "completed" and e["orbit_error"] <= r["orbit_error"]
              and e["omega_error"] <= r["omega_error"]]
        if ok:
            e = min(ok, key=lambda x: x["wall_median"])
            ratio = r["wall_median"] / e["wall_median"]
            lines.append("(d) %s: Siconos MJ h = 1e-7 reaches orbit error %.2e m and omega error "
                         "%.2e rad/s in %.3g s; the event-driven solver is at least as accurate "
                         "on both in %.3g s (%s rtol %s): %.0fx (goal: >= 1000x): %s" % (
                             r["case"], r["orbit_error"], r["omega_error"], r["wall_median"],
                             e["wall_median"], e["solver"], e["value"], ratio,
                             "met" if ratio >= 1000 else "NOT met"))
    if not sic:
        lines.append("(d) no Siconos MJ run at h = 1e-7 in validation/siconos/results.csv")
    return lines


STYLE = {"event-bdf": ("k", "o"), "event-adams": ("0.45", "s"), "carp-onevc": ("C0", "^"),
         "carp-qn": ("C1", "v"), "mj": ("C2", "D"), "mj-proj": ("C3", "P"),
         "siconos-mj": ("C4", "x"), "siconos-mj-proj": ("C5", "+")}


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 2, figsize=(12, 9))
    for i, case in enumerate(CASES):
        for j, (metric, label) in enumerate([("orbit_error", "max orbit error [m]"),
                                             ("omega_error", "|omega(t_end) error| [rad/s]")]):
            ax = axes[i][j]
            for solver, (color, marker) in STYLE.items():
                pts = [r for r in rows if r["case"] == case and r["solver"] == solver
                       and r["termination"] == "completed" and r[metric] > 0]
                if not pts:
                    continue
                pts.sort(key=lambda r: r["wall_median"])
                ax.loglog([r["wall_median"] for r in pts], [r[metric] for r in pts],
                          color=color, marker=marker, label=solver)
            ax.set_xlabel("wall time, median [s]")
            ax.set_ylabel(label)
            ax.set_title("reference case, first %s" % case if case == "30ms"
                         else "reference case, full 0.5 s")
            ax.grid(True, which="both", alpha=0.3)
            if metric == "orbit_error" and case == "30ms":
                ax.axhline(1e-9, color="r", lw=0.8, ls=":")
                ax.axvline(0.02, color="r", lw=0.8, ls=":")
            if metric == "omega_error":
                ax.axhline(1e-6, color="r", lw=0.8, ls=":")
                if case == "0.5s":
                    ax.axvline(0.25, color="r", lw=0.8, ls=":")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("rubdyn work-precision (%s)" % machine(), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    rows, refs = run_all()
    rows += siconos_rows()
    write_csv(os.path.join(HERE, "results.csv"), rows)
    plot(rows, os.path.join(HERE, "work-precision.png"))
    with open(os.path.join(HERE, "table.md"), "w") as f:
        f.write("# Work-precision, reference case\n\n")
        f.write("Generated by `validation/work-precision/run.py`. Machine: %s.\n\n" % machine())
        for case, (ref_s, (o, w), om) in refs.items():
            f.write("- %s: reference = event-driven rtol 1e-13 (%d steps, %.3f s wall), omega(t_end)"
                    " = %.10f rad/s; its difference to rtol 1e-12: orbit %.1e m, omega %.1e rad/s."
                    "\n" % (case, ref_s["steps"], ref_s["wall_seconds"], om, o, w))
        f.write("\n## Speed goals (issue 5)\n\n")
        for line in goals(rows):
            f.write("- %s\n" % line)
        f.write("\n## All points\n\n| case | solver | rtol / h | termination | orbit error [m] | "
                "omega error [rad/s] | penetration [m] | steps | wall median [s] | runs |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write("| %s | %s | %s | %s | %.2e | %.2e | %.1e | %s | %.4g | %d |\n" % (
                r["case"], r["solver"], r["value"], r["termination"], r["orbit_error"],
                r["omega_error"], r["max_penetration"], r["steps"], r["wall_median"],
                r["repetitions"]))
    print(open(os.path.join(HERE, "table.md")).read())


if __name__ == "__main__":
    main()
