#!/usr/bin/python3
"""Writes validation/rolling/onset_state.json, the starting state of validation/rolling.

It is the state rubdyn wrote at the onset of the first long stick (rolling) phase of the
reference case at mu = 0.25, stored with the case's parameters and where it came from.

It runs `rubdyn run cases/reference.toml --set contact.mu=0.25 --t-end T_SOURCE` into
out/rolling/source, finds the first "stick" event in events.csv whose phase lasts at least
MIN_STICK (the next event, or the end of the run), and takes the timeseries.csv row at that event
time whose phase is "stick" (the state after the switch; the row before it, phase slip, is the
state before). All digits are kept (the CSV holds round-trip decimal numbers).

Usage: validation/rolling/onset.py [path/to/rubdyn]
The committed onset_state.json is the fixed starting point of the study; re-running this script
is only needed when the source run itself is to be renewed.
"""
import argparse
import csv
import datetime
import json
import math
import os
import subprocess
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import ROOT  # noqa: E402

T_SOURCE = 0.15       # s: the first long stick phase starts at 0.116 s (and lasts to 0.5 s)
MIN_STICK = 0.03      # s: the study's window
MU = "0.25"
COORDS = ["x_b", "y_b", "x_r", "y_r", "theta", "x_s", "y_s"]
VELS = ["vx_b", "vy_b", "vx_r", "vy_r", "omega", "vx_s", "vy_s"]


def find_onset(folder, min_stick=MIN_STICK):
    """The first stick phase of at least min_stick in a rubdyn output folder: returns
    (t, state dict, event row, end of the phase, whether an event ended it)."""
    with open(os.path.join(folder, "events.csv")) as f:
        events = list(csv.DictReader(f))
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    t_reached = summary["t_reached"]
    onset = None
    for i, e in enumerate(events):
        if e["kind"] != "stick":
            continue
        t = float(e["t"])
        t_next = float(events[i + 1]["t"]) if i + 1 < len(events) else t_reached
        if t_next - t >= min_stick:
            onset = (t, e, t_next, i + 1 < len(events))
            break
    if onset is None:
        raise SystemExit("no stick phase of %g s in %s" % (min_stick, folder))
    t, event, t_next, ended = onset
    row = None
    with open(os.path.join(folder, "timeseries.csv")) as f:
        for r in csv.DictReader(f):
            if float(r["t"]) == t and r["phase"] == "stick":
                row = r
                break
    if row is None:
        raise SystemExit("no timeseries row with phase stick at t = %r" % t)
    return t, {k: float(row[k]) for k in COORDS + VELS}, event, t_next, ended


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rubdyn", nargs="?", default=os.path.join(ROOT, "build", "rubdyn"),
                    help="path to rubdyn (default build/rubdyn)")
    rubdyn = os.path.abspath(ap.parse_args().rubdyn)
    folder = os.path.join(ROOT, "out", "rolling", "source")
    args = ["run", "cases/reference.toml", "--set", "contact.mu=" + MU, "--t-end",
            repr(T_SOURCE), "--out", "out/rolling/source", "--quiet"]
    subprocess.run([rubdyn] + args, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    t, state, event, t_next, ended = find_onset(folder)
    with open(os.path.join(folder, "case.resolved.toml"), "rb") as f:
        case = tomllib.load(f)
    g0, R = case["stator"]["gap"], case["rotor"]["radius"]
    sx, sy = state["x_r"] - state["x_s"], state["y_r"] - state["y_s"]
    rho = math.hypot(sx, sy)
    nx, ny = sx / rho, sy / rho
    dvx, dvy = state["vx_r"] - state["vx_s"], state["vy_r"] - state["vy_s"]
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                                text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    doc = {
        "what": "state of the reference case at mu = 0.25 written by rubdyn at the onset of its "
                "first stick (rolling) phase of at least %g s; the starting state of "
                "validation/rolling" % MIN_STICK,
        "source": {
            "command": "build/rubdyn " + " ".join(args),
            "rubdyn_commit": commit,
            "date": datetime.date.today().isoformat(),
            "t_onset": t,
            "event": dict({k: event[k] for k in ("kind", "phase_before", "phase_after", "witness")},
                          F_N=float(event["F_N"]), F_T=float(event["F_T"])),
            "stick_phase_until": t_next,
            "stick_phase_until_is": "next event" if ended else "end of the source run",
            "row": "timeseries.csv row at t_onset with phase = stick (after the switch)",
        },
        "state": state,
        "constraint_residuals": {
            "d_N": g0 - rho,
            "v_N": -(nx * dvx + ny * dvy),
            "v_t": ny * dvx - nx * dvy - R * state["omega"],
            "rho_minus_g0": rho - g0,
        },
        "case": {k: case[k] for k in ("rotor", "bearing", "stator", "contact", "loads")},
    }
    with open(os.path.join(HERE, "onset_state.json"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    print(json.dumps(doc["source"], indent=1))
    print(json.dumps(doc["constraint_residuals"], indent=1))


if __name__ == "__main__":
    main()
