"""Helpers of the finite-element rotor studies (validation/fe): the script that writes the rotors,
runs timed in CPU seconds, and the seal orbits read back on the output grid."""
import importlib.util
import json
import os
import resource
import subprocess
import sys
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.dirname(HERE))
from common import machine  # noqa: E402,F401  (re-exported for the scripts)


def load_fe():
    """scripts/make-fe-rotor.py as a module."""
    spec = importlib.util.spec_from_file_location(
        "make_fe_rotor", os.path.join(ROOT, "scripts", "make-fe-rotor.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def description(name):
    with open(os.path.join(ROOT, "cases", name, "rotor.toml"), "rb") as f:
        return tomllib.load(f)


def make_case(desc_path, elements, case, matrices, name):
    """scripts/make-fe-rotor.py on a description with this many elements into case/matrices."""
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make-fe-rotor.py"), desc_path,
                    "--elements", str(elements), "--case", case, "--matrices", matrices,
                    "--name", name], check=True, stdout=subprocess.DEVNULL)
    return case


def timed_run(rubdyn, case, out, args):
    """`rubdyn run case --out out args`: (CPU seconds of the child, user + system; summary)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([rubdyn, "run", case, "--out", out, "--quiet", *args],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise RuntimeError(f"rubdyn run {case} {' '.join(args)}: exit {p.returncode}: {p.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(os.path.join(out, "summary.json")) as f:
        return cpu, json.load(f)


def grid(folder, columns, dt=1e-4):
    """{column: array} on the output grid k dt (the event solver also writes rows at its events;
    of two rows at one time the last, after the event), and the grid's t."""
    d = np.genfromtxt(os.path.join(folder, "timeseries.csv"), delimiter=",", names=True)
    keep = np.r_[d["t"][1:] != d["t"][:-1], True]
    keep &= np.abs(d["t"] / dt - np.round(d["t"] / dt)) < 1e-6
    d = d[keep]
    return d["t"], {c: d[c] for c in columns}


def orbit_difference(a, b, nodes, dt=1e-4, column="omega"):
    """The largest distance between two runs' seal centres (x_k, y_k of each node k) over their
    common grid times, the largest over the nodes; and the largest difference of `column`
    (omega; drive_torque at a prescribed spin) over the same times."""
    cols = [f"{c}{k}" for k in nodes for c in ("x", "y")]
    ta, ga = grid(a, cols + [column], dt)
    tb, gb = grid(b, cols + [column], dt)
    ka, kb = np.round(ta / dt).astype(int), np.round(tb / dt).astype(int)
    common, ia, ib = np.intersect1d(ka, kb, return_indices=True)
    worst = 0.0
    for k in nodes:
        d = np.hypot(ga[f"x{k}"][ia] - gb[f"x{k}"][ib], ga[f"y{k}"][ia] - gb[f"y{k}"][ib])
        worst = max(worst, float(d.max()))
    return worst, float(np.max(np.abs(ga[column][ia] - gb[column][ib])))


def events(summary):
    e = summary["events"]
    return ", ".join(f"{n} {k}" for k, n in e.items() if n)


def node_difference(a, b, cols):
    """The largest distance between two runs' points (cols = their x and y columns) over the
    times both wrote (the output grid: the event solvers' rows at events fall on other times;
    of two rows at one time the last, after the event)."""
    def rows(folder):
        d = np.genfromtxt(os.path.join(folder, "timeseries.csv"), delimiter=",", names=True)
        keep = np.r_[d["t"][1:] != d["t"][:-1], True]
        return d[keep]
    da, db = rows(a), rows(b)
    common, ia, ib = np.intersect1d(da["t"], db["t"], return_indices=True)
    x, y = cols
    return float(np.max(np.hypot(da[x][ia] - db[x][ib], da[y][ia] - db[y][ib])))
