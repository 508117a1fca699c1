#!/usr/bin/python3
"""Instructions per integrator step of the event solver, this tree against a commit: the count of
executed instructions (valgrind's cachegrind, "I refs") does not depend on the machine's load,
which on the shared 2-core machines moves wall-clock ratios by +-40 % from round to round
(bench/RESULTS.md), while a speed target such as "within +5 %" needs a few percent.

    bench/instructions.py --before REF      # builds both CLIs (Release), about 10 minutes

Both CLIs (this tree's in build-bench, REF's in build-bench/before, checked out in
build-bench/before-src as bench/run.sh does) run each scene twice under valgrind: to its end time
and to a start-up time a few steps in; the difference of the two counts over the difference of
their integrator steps is the cost of a step in that scene, with reading the case, building the
solver and writing the last files taken out (writing the output rows of the interval stays in,
the same rows for both). Writes bench/INSTRUCTIONS.md.

Instructions are not time: a cache miss or a division costs more than an addition. They measure
the work the code does, which is what a restructuring changes; bench/RESULTS.md has the times.
"""
import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "validation"))
from common import machine  # noqa: E402

sys.path.insert(0, os.path.join(ROOT, "validation", "fe"))
from fe_common import node_difference  # noqa: E402

# (label, case, arguments, end time, start-up time): the scenes of bench/RESULTS.md, as cases
SCENES = [
    ("reference, mu = 0.1 (free flight and slip)", "reference.toml", [], 0.5, 0.002),
    ("reference, mu = 0.25 (whip, then rolling: 77 % stick)", "reference.toml",
     ["--set", "contact.mu=0.25"], 0.5, 0.002),
    ("Jeffcott-Black (cases/jeffcott.toml)", "jeffcott.toml", [], 0.2, 0.002),
    ("two planes (cases/two-plane.toml, K = 2)", "two-plane.toml", ["--solver", "event"], 0.05,
     0.002),
]


def build(src, build_dir):
    subprocess.run(["cmake", "-S", src, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
                    "-DRUBDYN_BUILD_BENCH=ON", "-DRUBDYN_BUILD_TESTS=OFF"], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", build_dir, "-j2", "--target", "rubdyn"], check=True,
                   stdout=subprocess.DEVNULL)
    return os.path.join(build_dir, "rubdyn")


def count(cli, case, args, t_end):
    """(instructions, integrator steps) of one run under cachegrind (case: a path)."""
    with tempfile.TemporaryDirectory() as out:
        p = subprocess.run(["valgrind", "--tool=cachegrind", "--cache-sim=no",
                            "--cachegrind-out-file=/dev/null", cli, "run",
                            case, "--t-end", repr(t_end), "--out",
                            os.path.join(out, "o"), "--quiet", *args],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if p.returncode != 0:
            raise RuntimeError(f"{cli} run {case} {args}: exit {p.returncode}: {p.stderr[-2000:]}")
        m = re.search(r"I\s+refs:\s+([0-9,]+)", p.stderr)
        with open(os.path.join(out, "o", "summary.json")) as f:
            steps = json.load(f)["steps"]
    return int(m.group(1).replace(",", "")), steps


def error(cli, case, args, t_end, ref):
    """The largest distance of the rotor's centre (x_r, y_r) from the reference run's over the
    output grid (a native run, not under valgrind)."""
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([cli, "run", case, "--t-end", repr(t_end), "--out", out + "/o", "--quiet",
                        *args], check=True, stdout=subprocess.DEVNULL)
        return node_difference(out + "/o", ref, ("x_r", "y_r"))


def per_step(cli, case, args, t_end, t_start):
    i1, s1 = count(cli, case, args, t_end)
    i0, s0 = count(cli, case, args, t_start)
    return (i1 - i0) / (s1 - s0), s1


def main():
    if "--before" not in sys.argv:
        sys.exit("usage: bench/instructions.py --before REF")
    ref = sys.argv[sys.argv.index("--before") + 1]
    os.chdir(ROOT)
    src = os.path.join("build-bench", "before-src")
    subprocess.run(["git", "worktree", "prune"], check=True)
    if os.path.isdir(src):
        subprocess.run(["git", "-C", src, "checkout", "--quiet", "--detach", ref], check=True)
    else:
        subprocess.run(["git", "worktree", "add", "--quiet", "--detach", src, ref], check=True)
    before = build(src, os.path.join("build-bench", "before"))
    after = build(".", "build-bench")
    sha = lambda *a: subprocess.run(["git", *a, "rev-parse", "--short", "HEAD"], check=True,
                                    capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", "src", "include"]).returncode
    after_sha = sha() + ("+changes" if dirty else "")
    rows, per = [], {}
    refdir = tempfile.mkdtemp()
    for label, case, args, t_end, t0 in SCENES:
        # the reference: this tree at rtol 1e-12, atol 1e-14
        ref = os.path.join(refdir, "ref")
        subprocess.run([after, "run", os.path.join("cases", case), "--t-end", repr(t_end), "--out",
                        ref, "--quiet", "--rtol", "1e-12", "--atol", "1e-14", *args], check=True,
                       stdout=subprocess.DEVNULL)
        eb = error(before, os.path.join(src, "cases", case), args, t_end, ref)
        ea = error(after, os.path.join("cases", case), args, t_end, ref)
        # each CLI reads its own tree's case
        b, sb = per_step(before, os.path.join(src, "cases", case), args, t_end, t0)
        a, sa = per_step(after, os.path.join("cases", case), args, t_end, t0)
        per[label] = a
        rows.append(f"| {label} | {t_end:g} s | {sb} | {sa} | {eb:.1e} | {ea:.1e} | {b:,.0f} | "
                    f"{a:,.0f} | {a / b:.3f} |")
        print(rows[-1], flush=True)
    one, two = per[SCENES[0][0]], per[SCENES[3][0]]
    lines = ["# Instructions per integrator step", "",
             f"Generated by `bench/instructions.py --before {ref}` (valgrind {valgrind()}, "
             f"cachegrind's I refs). Before: {sha('-C', src)} ({ref}); after: {after_sha}. Machine: "
             + machine() + " (the counts do not depend on it, nor on its load).", "",
             "Per step: (instructions to the end time - instructions to 2 ms) / (steps to the "
             "end time - steps to 2 ms), the event solver at the cases' tolerances (rtol 1e-10). "
             "Errors: the largest distance of the rotor's centre (x_r, y_r) from this tree's run "
             "at rtol 1e-12, atol 1e-14 over the output grid; where the steps differ, the error "
             "control differs, and the errors say what the steps bought.", "",
             "| scene | end | steps before | steps after | error before [m] | error after [m] | "
             "instructions/step before | after | after / before |",
             "|---|---|---|---|---|---|---|---|---|", *rows, "",
             f"Two planes against one (after): {two:,.0f} against {one:,.0f} instructions per "
             f"step, {two / one:.2f}x."]
    with open(os.path.join(HERE, "INSTRUCTIONS.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote bench/INSTRUCTIONS.md")


def valgrind():
    return subprocess.run(["valgrind", "--version"], capture_output=True,
                          text=True).stdout.strip().removeprefix("valgrind-")


if __name__ == "__main__":
    main()
