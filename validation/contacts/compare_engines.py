#!/usr/bin/python3
"""The comparison runs: the same runs with two rubdyn binaries (a build of an earlier commit and
this tree's), output compared bit for bit; where they differ, the largest difference of the
positions on the output grid, set against the run's own self-convergence level (the same run of
the new binary at rtol / 10) for the event solver. Writes compare.md next to this script.

Usage: validation/contacts/compare_engines.py BEFORE_RUBDYN [AFTER_RUBDYN] [--quick]
  e.g. git worktree add --detach /tmp/before b7381b8 &&
       cmake -S /tmp/before -B /tmp/before/build -DCMAKE_BUILD_TYPE=Release \
             -DRUBDYN_BUILD_TESTS=OFF -DRUBDYN_BUILD_PYTHON=OFF &&
       cmake --build /tmp/before/build -j2 --target rubdyn &&
       validation/contacts/compare_engines.py /tmp/before/build/rubdyn
"""
import filecmp
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import ROOT, machine, read_output  # noqa: E402

C = lambda name: os.path.join(ROOT, "cases", name)  # noqa: E731

# (name, case, extra arguments): K = 1 on every model and formulation, every fixed-step scheme,
# and the K-contact cases
RUNS = [
    ("reference event rtol 1e-10", C("reference.toml"), ["--t-end", "0.1"]),
    ("reference event rtol 1e-12", C("reference.toml"), ["--t-end", "0.1", "--rtol", "1e-12",
                                                         "--atol", "1e-14"]),
    ("reference event projection", C("reference.toml"),
     ["--t-end", "0.1", "--set", "solver.contact_phases=\"projection\""]),
    ("reference event mu 0.25 (rolling)", C("reference.toml"),
     ["--t-end", "0.1", "--set", "contact.mu=0.25"]),
    ("reference event e_n 0.5", C("reference.toml"), ["--t-end", "0.1", "--set", "contact.e_n=0.5"]),
    ("reference event bdf", C("reference.toml"), ["--t-end", "0.1", "--method", "bdf"]),
    ("reference mj", C("reference.toml"), ["--t-end", "0.05", "--solver", "mj"]),
    ("reference mj-proj", C("reference.toml"), ["--t-end", "0.05", "--solver", "mj-proj"]),
    ("reference carp-onevc", C("reference.toml"), ["--t-end", "0.05", "--solver", "carp-onevc"]),
    ("reference carp-qn", C("reference.toml"), ["--t-end", "0.05", "--solver", "carp-qn"]),
    ("jeffcott event", C("jeffcott.toml"), ["--t-end", "0.05"]),
    ("jeffcott event, prescribed speed", "PRESCRIBED",
     ["--t-end", "0.05", "--set", "loads.spin=\"prescribed\"", "--set", "loads.spin_accel=100"]),
    ("jeffcott mj", C("jeffcott.toml"), ["--t-end", "0.05", "--solver", "mj"]),
    ("matrices-paper event", C("matrices-paper.toml"), ["--t-end", "0.05"]),
    ("paper event", C("paper.toml"), ["--t-end", "0.05"]),
    ("two-plane event", C("two-plane.toml"), ["--t-end", "0.05", "--solver", "event"]),
    ("two-plane mj", C("two-plane.toml"), ["--t-end", "0.03"]),
    ("two-plane mj-proj", C("two-plane.toml"), ["--t-end", "0.03", "--solver", "mj-proj"]),
    ("two-plane carp-onevc", C("two-plane.toml"), ["--t-end", "0.03", "--solver", "carp-onevc"]),
    ("matrices-two-plane event", C("matrices-two-plane.toml"), ["--t-end", "0.03", "--solver",
                                                                 "event"]),
]


def prescribed_case(out):
    """cases/jeffcott.toml without its torque (a prescribed spin does not read it): the
    projection formulation's path (a prescribed-spin model has no chart)."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "jeffcott-prescribed.toml")
    with open(C("jeffcott.toml")) as f:
        text = [l for l in f if not l.startswith("torque ")]
    with open(path, "w") as f:
        f.writelines(text)
    return path


def run(rubdyn, case, args, folder):
    r = subprocess.run([rubdyn, "run", case, "--out", folder, "--quiet"] + args,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode not in (0, 3):
        raise RuntimeError("%s %s: exit %d: %s" % (rubdyn, args, r.returncode, r.stderr))


def position_columns(row):
    return [c for c in row if c.startswith(("x_", "y_"))]


def max_position_difference(a, b):
    _, ga, _ = read_output(a)
    _, gb, _ = read_output(b)
    common = sorted(set(ga) & set(gb))
    cols = position_columns(ga[common[0]])
    return max(abs(ga[k][c] - gb[k][c]) for k in common for c in cols)


def tighter(args):
    """The same arguments at rtol / 10 (atol / 10) for the self-convergence level."""
    out, i = [], 0
    rtol, atol = 1e-10, 1e-12
    while i < len(args):
        if args[i] == "--rtol":
            rtol = float(args[i + 1])
            i += 2
            continue
        if args[i] == "--atol":
            atol = float(args[i + 1])
            i += 2
            continue
        out.append(args[i])
        i += 1
    return out + ["--rtol", "%.0e" % (rtol / 10), "--atol", "%.0e" % (atol / 10)]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    before = args[0]
    after = args[1] if len(args) > 1 else os.path.join(ROOT, "build", "rubdyn")
    out = os.path.join(ROOT, "out", "compare-engines")
    lines = ["# The comparison runs: %s against %s" % (os.path.relpath(after, ROOT), before), "",
             "Machine: %s. Generated by `validation/contacts/compare_engines.py`." % machine(), "",
             "| run | timeseries.csv | events.csv | largest position difference [m] | "
             "self-convergence level (rtol / 10) [m] |", "|---|---|---|---|---|"]
    for name, case, extra in RUNS:
        if case == "PRESCRIBED":
            case = prescribed_case(out)
        slug = name.replace(" ", "_").replace(",", "").replace("(", "").replace(")", "")
        fa, fb = os.path.join(out, slug, "before"), os.path.join(out, slug, "after")
        run(before, case, extra, fa)
        run(after, case, extra, fb)
        same_ts = filecmp.cmp(os.path.join(fa, "timeseries.csv"),
                              os.path.join(fb, "timeseries.csv"), shallow=False)
        same_ev = filecmp.cmp(os.path.join(fa, "events.csv"), os.path.join(fb, "events.csv"),
                              shallow=False)
        diff = level = ""
        if not (same_ts and same_ev):
            diff = "%.2g" % max_position_difference(fa, fb)
            if "event" in name:
                ft = os.path.join(out, slug, "tight")
                run(after, case, tighter(extra), ft)
                level = "%.2g" % max_position_difference(fb, ft)
        lines.append("| %s | %s | %s | %s | %s |" % (
            name, "identical" if same_ts else "differs", "identical" if same_ev else "differs",
            diff or "0", level or "-"))
        print(lines[-1], flush=True)
    with open(os.path.join(HERE, "compare.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
