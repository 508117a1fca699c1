#!/usr/bin/python3
"""Cost per step against the rotor's size (issue 32's targets): the finite-element run-up of
cases/fe-runup/rotor.toml (scripts/make-fe-rotor.py) with 12, 24, 48, 96 elements (n = 52, 100,
196, 388 coordinates), 0.2 s through the first critical speed into rub at the mid-span seal.
Per size: the event solver as a user runs it (the case's rtol 1e-8, the method chosen by
default), Moreau-Jean at h = 1e-6 and 1e-5 s, each timed in CPU seconds (user + system of the
child, the median of --rounds runs), and each one's seal orbit error against the event solver
at rtol 1e-10 (one run). Writes bench/FE_SCALING.md.

    bench/fe_scaling.py [--cli build/rubdyn] [--rounds 3] [--elements 12 24 48 96]
"""
import argparse
import os
import statistics
import sys
import tempfile
import tomllib

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "validation", "fe"))
import fe_common  # noqa: E402


def seal_columns(case):
    """The seal node's (x, y) column names of a generated case."""
    with open(case, "rb") as f:
        c = tomllib.load(f)
    names = [s.strip() for s in c["rotor"]["coordinates"].split(",")]
    node = c["contact_node"]
    return names[node["x"]], names[node["y"]]


def timed(cli, case, out, args, rounds):
    """The median CPU seconds of `rounds` runs and the last run's summary."""
    cpus = []
    summary = None
    for _ in range(rounds):
        cpu, summary = fe_common.timed_run(cli, case, out, args)
        cpus.append(cpu)
    return statistics.median(cpus), summary


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "rubdyn"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--elements", type=int, nargs="+", default=[12, 24, 48, 96])
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "FE_SCALING.md"))
    a = ap.parse_args()
    desc = os.path.join(ROOT, "cases", "fe-runup", "rotor.toml")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for e in a.elements:
            case = fe_common.make_case(desc, e, os.path.join(tmp, f"e{e}.toml"),
                                       os.path.join(tmp, f"e{e}"), f"e{e}")
            cols = seal_columns(case)
            ref = os.path.join(tmp, f"ref{e}")
            ref_cpu, ref_s = fe_common.timed_run(a.cli, case, ref,
                                                 ["--set", "solver.rtol=1e-10"])
            r = {"e": e, "ref_cpu": ref_cpu, "ref_steps": ref_s["steps"]}
            runs = {"event": [],
                    "mj6": ["--set", 'solver.kind="mj"', "--set", "solver.h=1e-6"],
                    "mj5": ["--set", 'solver.kind="mj"', "--set", "solver.h=1e-5"]}
            # the slopes taken for metres (rotor.rotations undeclared): one run, to show what
            # the declaration gains
            metres_cpu, metres_s = fe_common.timed_run(a.cli, case, os.path.join(tmp, f"m{e}"),
                                                       ["--set", 'rotor.rotations=""'])
            r["metres"] = {"cpu": metres_cpu, "steps": metres_s["steps"],
                           "err": fe_common.node_difference(os.path.join(tmp, f"m{e}"), ref,
                                                            cols)}
            for name, args in runs.items():
                out = os.path.join(tmp, f"{name}{e}")
                cpu, s = timed(a.cli, case, out, args, a.rounds)
                r[name] = {"cpu": cpu, "steps": s["steps"],
                           "err": fe_common.node_difference(out, ref, cols),
                           "summary": s}
                print(f"e{e} {name}: {cpu:.2f} CPU s, {s['steps']} steps, "
                      f"error {r[name]['err']:.2e} m", flush=True)
            with open(case, "rb") as f:
                c = tomllib.load(f)
            r["n"] = len(c["rotor"]["coordinates"].split(","))
            rows.append(r)
    base = rows[0]["event"]["cpu"] / rows[0]["event"]["steps"]
    lines = [
        "# Cost per step against the rotor's size: the FE run-up with 12 to 96 elements",
        "",
        "Written by `bench/fe_scaling.py` (do not edit by hand). Machine: "
        f"{fe_common.machine()}; CPU seconds (user + system), the median of {a.rounds} "
        "run(s); errors: the largest distance of the seal centre from the event solver's at "
        "rtol 1e-10 (atol 1e-13) over the 0.1 ms output grid.",
        "",
        "The scene: cases/fe-runup/rotor.toml's shaft (scripts/make-fe-rotor.py) with E "
        "elements, n = 4 (E + 1) coordinates, a prescribed run-up from 100 rad/s at 1000 "
        "rad/s^2 over 0.2 s through the first critical speed (35 Hz) into rub at the mid-span "
        "seal. The event solver as the case runs it: rtol 1e-8, atol 1e-13, the method "
        "chosen by the model's stiffness (BDF here), contact phases in minimal coordinates "
        "(their Newton systems banded: docs/fe-rotors.md section 10), the "
        "slopes declared as rotations (`rotor.rotations = \"dx*, dy*\"`, as the script writes "
        "them; the last column: the same run with the slopes taken for metres, "
        "`--set rotor.rotations=\"\"`, one run).",
        "",
        "| n | event CPU s | steps | us/step | per step / n = "
        f"{rows[0]['n']} | error [m] | mj h = 1e-6 CPU s | error [m] | mj h = 1e-5 CPU s | "
        "error [m] | reference CPU s (steps) | slopes as metres: CPU s, steps, error [m] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        ev, m6, m5 = r["event"], r["mj6"], r["mj5"]
        per = ev["cpu"] / ev["steps"]
        lines.append(
            f"| {r['n']} | {ev['cpu']:.2f} | {ev['steps']} | {1e6 * per:.0f} | "
            f"{per / base:.2f} | {ev['err']:.1e} | {m6['cpu']:.2f} | {m6['err']:.1e} | "
            f"{m5['cpu']:.2f} | {m5['err']:.1e} | {r['ref_cpu']:.1f} ({r['ref_steps']}) | "
            f"{r['metres']['cpu']:.2f}, {r['metres']['steps']}, {r['metres']['err']:.1e} |")
    lines += ["", "Issue 32's targets, from the rows above:", "",
              "| n | per step / n = 52 (target <= 8 at n = 388) | event / mj h=1e-6 time "
              "(target < 1) | mj h=1e-6 / event error (target >= 100) | event / mj h=1e-5 "
              "time (target <= 2) |", "|---|---|---|---|---|"]
    for r in rows:
        ev, m6, m5 = r["event"], r["mj6"], r["mj5"]
        per = ev["cpu"] / ev["steps"]
        lines.append(f"| {r['n']} | {per / base:.2f} | {ev['cpu'] / m6['cpu']:.2f} | "
                     f"{m6['err'] / max(ev['err'], 1e-300):.0f} | {ev['cpu'] / m5['cpu']:.2f} |")
    lines += ["", "Steps of the event solver per phase (free flight, slip; summary.json):", ""]
    for r in rows:
        s = r["event"]["summary"]
        ps = s["phase_steps"]
        lines.append(f"- n = {r['n']}: " + ", ".join(f"{k} {v}" for k, v in ps.items() if v) +
                     f"; {s['jac_evals']} Jacobians, {s['newton_iters']} Newton iterations; "
                     f"steps rejected: {s['err_test_fails']} by the error test, "
                     f"{s['conv_fails']} by Newton's convergence")
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
