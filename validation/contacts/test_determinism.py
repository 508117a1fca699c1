#!/usr/bin/python3
"""Same input, same bits: the K-contact scenes (and one case of each model) run several times in
separate processes under different conditions give byte-identical timeseries.csv and events.csv
and the same summary.json up to its wall-clock fields:
  - plain;
  - with an environment larger by 64 kB (it moves the stack and the heap's start) and ASLR on,
    while a sibling process keeps both cores busy (the machine's load);
  - with ASLR off (setarch -R), when the kernel lets us;
  - as points of a sweep with 1 and with 2 parallel runs (threads).
Run through ctest (tests/CMakeLists.txt) with RUBDYN_CLI naming the binary; about 20 s.
"""
import filecmp
import json
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLI = os.environ.get("RUBDYN_CLI", os.path.join(ROOT, "build", "rubdyn"))
C = lambda name: os.path.join(ROOT, "cases", name)  # noqa: E731

# (name, case, arguments): the cascades, the stick release, four contacts with a fixed ring, and
# one case of each model (K = 1 rigid rotor, Jeffcott, matrices with two nodes)
SCENES = [
    ("two-plane-cascade", C("two-plane-cascade.toml"), ["--t-end", "0.012", "--rtol", "1e-10",
                                                        "--atol", "1e-14"]),
    ("stick-release", C("two-plane-cascade.toml"),
     ["--t-end", "0.009", "--set", "initial.omega0=0.1", "--set", "loads.torque=0", "--set",
      "plane.2.mu=0.5"]),
    ("four-plane", C("four-plane.toml"), ["--t-end", "0.012", "--rtol", "1e-10", "--atol",
                                          "1e-13"]),
    ("reference", C("reference.toml"), ["--t-end", "0.03"]),
    ("jeffcott", C("jeffcott.toml"), ["--t-end", "0.03"]),
    ("matrices-two-plane", C("matrices-two-plane.toml"), ["--t-end", "0.012", "--solver", "event"]),
]
# summary.json fields that hold wall-clock measurements (everything else must be equal)
WALL = {"wall_seconds", "phase_wall", "cost_per_step", "phase_cost"}


def run(folder, case, args, env=None, prefix=()):
    r = subprocess.run(list(prefix) + [CLI, "run", case, "--out", folder, "--quiet"] + args,
                       env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert r.returncode == 0, r.stderr


def summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        s = json.load(f)
    return {k: v for k, v in s.items() if k not in WALL and "wall" not in k}


def same(a, b):
    for name in ("timeseries.csv", "events.csv"):
        assert filecmp.cmp(os.path.join(a, name), os.path.join(b, name), shallow=False), \
            "%s differs between %s and %s" % (name, a, b)
    assert summary(a) == summary(b)


def aslr_off_works():
    try:
        return subprocess.run(["setarch", "-R", "true"], capture_output=True).returncode == 0
    except OSError:
        return False


@pytest.fixture(scope="module")
def tmp():
    d = tempfile.mkdtemp(prefix="rubdyn-determinism-")
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.mark.parametrize("name,case,args", SCENES, ids=[s[0] for s in SCENES])
def test_separate_processes_give_the_same_bits(tmp, name, case, args):
    plain = os.path.join(tmp, name, "plain")
    run(plain, case, args)
    # a larger environment, ASLR on, both cores kept busy by a sibling process
    env = dict(os.environ)
    env["RUBDYN_DETERMINISM_PADDING"] = "x" * 65536
    # two spinning processes of their own (no children: killing them leaves nothing behind)
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        loaded = os.path.join(tmp, name, "loaded")
        run(loaded, case, args, env=env)
    finally:
        for b in busy:
            b.kill()
            b.wait()
    same(plain, loaded)
    if aslr_off_works():
        fixed = os.path.join(tmp, name, "no-aslr")
        run(fixed, case, args, prefix=("setarch", "-R"))
        same(plain, fixed)


def test_sweep_points_are_the_same_with_one_and_two_threads(tmp):
    # the two-plane cascade and the stick release as points of one sweep (plane 2's mu)
    case = C("two-plane-cascade.toml")
    args = ["--t-end", "0.009", "--rtol", "1e-10", "--atol", "1e-14", "--vary",
            "plane.2.mu=0.15,0.5", "--quiet"]
    outs = []
    for jobs in ("1", "2"):
        out = os.path.join(tmp, "sweep-%s" % jobs)
        r = subprocess.run([CLI, "sweep", case, "--out", out, "--jobs", jobs] + args,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        assert r.returncode == 0, r.stderr
        outs.append(out)
    points = sorted(p for p in os.listdir(outs[0]) if os.path.isdir(os.path.join(outs[0], p)))
    assert len(points) == 2
    for p in points:
        same(os.path.join(outs[0], p), os.path.join(outs[1], p))
