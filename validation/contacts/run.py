#!/usr/bin/python3
"""Several contacts, exact by the law: the event-driven engine measured on the K-contact cases.
Writes table.md and results.csv next to this script.

1. Self-convergence: cases/two-plane.toml, cases/two-plane-cascade.toml and cases/four-plane.toml
   over 0.1 s at rtol = 1e-10 ... 1e-13 with atol = 1e-16: the largest difference of any position
   coordinate (x_*, y_*) on the output grid between successive tolerances, and of omega.
2. atol: the same cases at rtol 1e-12 with atol = 1e-14, 1e-15, 1e-16 and 1e-20, against atol
   1e-16.
3. The law at every sample and event of each run: the largest cone excess |F_T| - mu F_N and the
   most negative F_N of a closed contact, relative to the run's largest normal force, the
   largest |v_t| of a sticking contact and |d_N| of a closed one (complementarity: an open
   contact has no force by construction).
4. The stick release of cases/two-plane-cascade.toml at omega0 = 0.1 rad/s, no torque and
   plane 2's mu = 0.5: when plane 1 leaves stick and when it sticks again, at every rtol.
5. The cascade limit against Moreau-Jean (an independent scheme): from the event solver's state
   at 7.8 ms of cases/two-plane-cascade.toml, omega(10 ms) - omega(7.8 ms) by the event solver
   (rtol 1e-12) and by mj at h = 1e-7, 1e-8 and 1e-9 s.
Usage: validation/contacts/run.py [path/to/rubdyn] [--quick]   (about 3 min on 2 cores)
"""
import csv
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import ROOT, machine, read_output, read_rows, script_args, write_csv  # noqa: E402

RUBDYN, QUICK, OUT = script_args("contacts")
CASES = ["two-plane", "two-plane-cascade", "four-plane"]
T_END = "0.03" if QUICK else "0.1"
RTOLS = ["1e-10", "1e-11", "1e-12"] if QUICK else ["1e-10", "1e-11", "1e-12", "1e-13"]
ATOLS = ["1e-14", "1e-15", "1e-16", "1e-20"]


def run(name, case, args, t_end=T_END):
    folder = os.path.join(OUT, name)
    t0 = time.perf_counter()
    r = subprocess.run([RUBDYN, "run", os.path.join(ROOT, "cases", case + ".toml"), "--out",
                        folder, "--quiet", "--solver", "event", "--t-end", t_end] + args,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode not in (0, 3):
        raise RuntimeError("rubdyn run %s: exit %d: %s" % (name, r.returncode, r.stderr))
    return folder, time.perf_counter() - t0


def positions(grid):
    k0 = min(grid)
    return [c for c in grid[k0] if c.startswith(("x_", "y_"))]


def difference(fa, fb):
    """(largest position difference [m] on the common grid, omega difference at the end
    [rad/s]). Velocities are compared at the end, not on the grid: a sample inside a cascade
    (between a push-off and its collapse) sees the pushed-off contact flying in one run and
    already collapsed in the other, a difference of the order of the push-off speed that the
    collapse removes at the cascade's end (contact_decisions.hpp); positions differ only by the
    flight's height."""
    _, ga, _ = read_output(fa)
    _, gb, _ = read_output(fb)
    common = sorted(set(ga) & set(gb))
    cols = positions(ga)
    dq = max(abs(ga[k][c] - gb[k][c]) for k in common for c in cols)
    end = max(common)
    dw = abs(ga[end]["omega"] - gb[end]["omega"])
    return dq, dw


def law(folder):
    """The law at every sample and event: (cone excess, -min F_N, max |v_t| in stick, max |d_N|
    closed), the first two relative to the largest normal force."""
    rows = read_rows(os.path.join(folder, "timeseries.csv"))
    evs = read_rows(os.path.join(folder, "events.csv"))
    with open(os.path.join(folder, "case.resolved.toml")) as f:
        text = f.read()
    header = list(rows[0])
    ks = sorted({c.rsplit("_", 1)[1] for c in header if c.startswith("F_N_")}) or [""]
    mus = []
    import tomllib
    case = tomllib.loads(text)
    planes = case.get("plane", [])
    for i, k in enumerate(ks):
        mus.append(planes[i]["mu"] if planes else case["contact"]["mu"])
    suf = lambda k: ("_" + k) if k else ""  # noqa: E731
    F_scale = max(max(float(r["F_N" + suf(k)]) for r in rows) for k in ks)
    cone = neg = vt = dn = 0.0
    for r in rows:
        for k, mu in zip(ks, mus):
            ph = r["phase" + suf(k)]
            if ph == "free":
                continue
            FN, FT = float(r["F_N" + suf(k)]), float(r["F_T" + suf(k)])
            cone = max(cone, (abs(FT) - mu * FN) / F_scale)
            neg = max(neg, -FN / F_scale)
            dn = max(dn, abs(float(r["d_N" + suf(k)])))
            if ph == "stick":
                vt = max(vt, abs(float(r["v_t" + suf(k)])))
    for e in evs:
        k = int(e.get("contact") or 1) - 1
        if e["phase_after"] in ("", "free") or not e["F_N"]:
            continue
        FN, FT = float(e["F_N"]), float(e["F_T"])
        cone = max(cone, (abs(FT) - mus[k] * FN) / F_scale)
        neg = max(neg, -FN / F_scale)
    return cone, neg, vt, dn


def events(folder):
    return read_rows(os.path.join(folder, "events.csv"))


def main():
    out_rows, lines = [], []
    lines += ["# Several contacts, exact by the law", "",
              "Machine: %s. Generated by `validation/contacts/run.py`%s (the event solver, %s s)."
              % (machine(), " --quick" if QUICK else "", T_END), ""]
    # 1. self-convergence
    lines += ["## 1. Self-convergence (atol 1e-16)", "",
              "Largest difference of any position coordinate on the output grid, and of omega at "
              "the end, against the next tighter rtol; events; steps; wall time.", "",
              "| case | rtol | vs rtol | position [m] | omega at the end [rad/s] | events | steps | wall [s] |",
              "|---|---|---|---|---|---|---|---|"]
    folders = {}
    for case in CASES:
        for rtol in RTOLS:
            f, wall = run("%s-rtol%s" % (case, rtol), case, ["--rtol", rtol, "--atol", "1e-16"])
            folders[(case, rtol)] = (f, wall)
        for a, b in zip(RTOLS, RTOLS[1:]):
            fa, wall = folders[(case, a)]
            dq, dw = difference(fa, folders[(case, b)][0])
            with open(os.path.join(fa, "summary.json")) as fs:
                s = json.load(fs)
            lines.append("| %s | %s | %s | %.2g | %.2g | %d | %d | %.3f |" % (
                case, a, b, dq, dw, sum(s["events"].values()), s["steps"], wall))
            out_rows.append({"study": "self-convergence", "case": case, "rtol": a, "atol": "1e-16",
                             "against": b, "position": dq, "omega": dw})
    # 2. atol
    lines += ["", "## 2. atol (rtol 1e-12)", "",
              "| case | atol | position vs atol 1e-16 [m] | omega at the end [rad/s] | termination |",
              "|---|---|---|---|---|"]
    for case in CASES:
        ref = folders[(case, "1e-12")][0]
        for atol in ATOLS:
            if atol == "1e-16":
                continue
            f, _ = run("%s-atol%s" % (case, atol), case, ["--rtol", "1e-12", "--atol", atol])
            with open(os.path.join(f, "summary.json")) as fs:
                s = json.load(fs)
            dq, dw = difference(f, ref)
            lines.append("| %s | %s | %.2g | %.2g | %s |" % (case, atol, dq, dw,
                                                            s["termination"]))
            out_rows.append({"study": "atol", "case": case, "rtol": "1e-12", "atol": atol,
                             "against": "atol 1e-16", "position": dq, "omega": dw})
    # 3. the law
    lines += ["", "## 3. The law at every sample and event", "",
              "| case | rtol | cone excess / F_max | -min F_N / F_max | max abs v_t in stick [m/s] |"
              " max abs d_N closed [m] |", "|---|---|---|---|---|---|"]
    stick_case = ["--set", "initial.omega0=0.1", "--set", "loads.torque=0", "--set",
                  "plane.2.mu=0.5"]
    law_runs = [(c, r, folders[(c, r)][0]) for c in CASES for r in RTOLS]
    for rtol in RTOLS:
        f, _ = run("stick-release-rtol%s" % rtol, "two-plane-cascade",
                   stick_case + ["--rtol", rtol, "--atol", "1e-16"], t_end="0.02")
        law_runs.append(("two-plane-cascade, stick release", rtol, f))
    for case, rtol, f in law_runs:
        cone, neg, vt, dn = law(f)
        lines.append("| %s | %s | %.2g | %.2g | %.2g | %.2g |" % (case, rtol, cone, neg, vt, dn))
    # 4. the stick release
    lines += ["", "## 4. The stick release (two-plane-cascade, omega0 0.1 rad/s, no torque, "
              "plane 2 mu 0.5)", "",
              "| rtol | plane 1 leaves stick [s] | plane 1 sticks again [s] | events |",
              "|---|---|---|---|"]
    for rtol in RTOLS:
        ev = events(os.path.join(OUT, "stick-release-rtol%s" % rtol))
        p1 = [e for e in ev if e["contact"] == "1" and 0.0069 < float(e["t"]) < 0.0085]
        leave = next((e["t"] for e in p1 if e["kind"] == "slip"), "-")
        back = next((e["t"] for e in p1 if e["kind"] == "stick"), "-")
        lines.append("| %s | %s | %s | %d |" % (rtol, leave, back, len(ev)))
    # 5. the cascade limit against Moreau-Jean
    lines += ["", "## 5. The first cascade against Moreau-Jean", "",
              "From the event solver's state at 7.8 ms (rtol 1e-12): omega(10 ms) - omega(7.8 ms).",
              "", "| solver | omega(10 ms) - omega(7.8 ms) [rad/s] | difference to the event "
              "solver [rad/s] | wall [s] |", "|---|---|---|---|"]
    start, _ = run("cascade-event", "two-plane-cascade", ["--rtol", "1e-12", "--atol", "1e-16"],
                   t_end="0.0078")
    dw = {}
    ref, wall = run("cascade-event-on", "two-plane-cascade",
                    ["--rtol", "1e-12", "--atol", "1e-16", "--from", start, "--at", "0.0078"],
                    t_end="0.01")
    def omega_gain(folder):
        rows = read_rows(os.path.join(folder, "timeseries.csv"))
        return float(rows[-1]["omega"]) - float(rows[0]["omega"])
    dw["event"] = omega_gain(ref)
    lines.append("| event rtol 1e-12 | %.10g | 0 | %.2f |" % (dw["event"], wall))
    hs = ["1e-7", "1e-8"] if QUICK else ["1e-7", "1e-8", "1e-9"]
    for h in hs:
        f = os.path.join(OUT, "cascade-mj-h%s" % h)
        t0 = time.perf_counter()
        r = subprocess.run([RUBDYN, "run", os.path.join(ROOT, "cases", "two-plane-cascade.toml"),
                            "--out", f, "--quiet", "--solver", "mj", "--h", h, "--from", start,
                            "--at", "0.0078", "--t-end", "0.01", "--set", "output.dt=2.2e-3"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if r.returncode not in (0, 3):
            raise RuntimeError(r.stderr)
        dw[h] = omega_gain(f)
        lines.append("| mj h = %s | %.10g | %.3g | %.2f |" % (h, dw[h], dw[h] - dw["event"],
                                                            time.perf_counter() - t0))
    lines += ["", "Moreau-Jean's difference to the event solver falls tenfold with h (first order, as "
              "its impacts are located only to a step): it converges to the event solver's cascade "
              "collapse, whose error is of second order in the push-off speed."]
    with open(os.path.join(HERE, "table.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    write_csv(os.path.join(HERE, "results.csv"), out_rows)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
