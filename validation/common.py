"""Helpers shared by the validation scripts: running rubdyn into an output folder and reading
it back, and naming the machine a table was measured on."""
import csv
import io
import json
import math
import os
import platform
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASE = os.path.join(ROOT, "cases", "reference.toml")


def machine():
    """CPU model and architecture, for the tables' headers."""
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return "%s, %s, %d cores" % (cpu, platform.machine(), os.cpu_count() or 0)


def read_output(folder, dt=1e-4, last=False):
    """Reads an output folder: (summary dict, grid, events) with grid[k] = {column: value} for
    the rows at t = k dt (the output grid; at an event on a grid time the row before the event,
    or with last=True the one after it) and events as (t, kind)."""
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    grid = {}
    for r in read_rows(os.path.join(folder, "timeseries.csv")):
        t = float(r["t"])
        k = round(t / dt)
        if abs(t - k * dt) < 1e-9 and (last or k not in grid):
            grid[k] = {c: float(v) for c, v in r.items() if c != "phase"}
    events = [(float(r["t"]), r["kind"]) for r in read_rows(os.path.join(folder, "events.csv"))]
    return summary, grid, events


def read_rows(path):
    """The rows of a CSV file written by rubdyn, as dicts. rubdyn ends every row with a line end:
    a last row without one was cut by a kill (it may hold a truncated number) and is dropped
    with a warning on stderr. An empty file (a killed run of an older rubdyn) has no rows."""
    with open(path, newline="") as f:
        text = f.read()
    if text and not text.endswith("\n"):
        cut = text.rfind("\n") + 1
        print("warning: %s: the last row has no line end (the run was cut short): ignored" % path,
              file=sys.stderr)
        text = text[:cut]
    return list(csv.DictReader(io.StringIO(text)))


def run_case(rubdyn, folder, args, dt=1e-4):
    """Runs `rubdyn run` on the reference case into folder; returns (summary dict, grid) with
    grid[k] = (x_r, y_r, omega) at t = k dt (the output grid; event rows are skipped), and the
    list of events as (t, kind)."""
    subprocess.run([rubdyn, "run", CASE, "--out", folder, "--quiet"] + args, check=True,
                   stdout=subprocess.DEVNULL)
    summary, rows, events = read_output(folder, dt)
    grid = {k: (r["x_r"], r["y_r"], r["omega"]) for k, r in rows.items()}
    return summary, grid, events


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def script_args(name):
    """The command line of the study scripts: `run.py [path/to/rubdyn] [--quick]`. Returns
    (rubdyn, quick, out) with out = ROOT/out/<name>."""
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rubdyn = args[0] if args else os.path.join(ROOT, "build", "rubdyn")
    return rubdyn, "--quick" in sys.argv, os.path.join(ROOT, "out", name)


def grid_errors(grid, ref):
    """(orbit error, omega error) of a grid {k: (x_r, y_r, omega)} against a reference grid: the
    largest |r_r - r_r,ref| over the common sample times, and |omega - omega_ref| at the
    reference's last sample (nan when the run does not reach it)."""
    common = sorted(set(grid) & set(ref))
    orbit = max(math.hypot(grid[k][0] - ref[k][0], grid[k][1] - ref[k][1]) for k in common)
    kmax = max(ref)
    omega = abs(grid[kmax][2] - ref[kmax][2]) if kmax in grid else float("nan")
    return orbit, omega
