#!/usr/bin/python3
"""Robustness suite (issue 12): exit 0 means a complete, correct result.

Tries what a new user (or a fault) does to rubdyn and checks the output contract: bad input exits
2 naming the key and writes nothing; numerical trouble exits 3 with "complete": false and no raw
SUNDIALS text; SIGINT/SIGTERM exit 4 with "interrupted"; a failed write exits 5 naming the file
(or 2 when the run cannot start); a killed run's folder is read by the tools and restarts.
Writes table.md and table.csv next to this script.
Usage: validation/robustness/run.py [path/to/rubdyn] (default build/rubdyn).
"""
import glob
import json
import os
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import CASE, ROOT, machine, read_output, write_csv  # noqa: E402

RUBDYN = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "rubdyn")
OUT = os.path.join(ROOT, "out", "robustness")
ROWS = []

# Every key of the reference case with values that break its rule (or any rule). (rotor.Jp =
# 4294967297, once accepted and slow, is now refused: a rigid body has Jp <= 2 Jd.)
BAD_VALUES = ["nan", "inf", "-inf", "1e309", "'text'", "[1]", "true"]
INTEGER_KEYS = {"solver.itmax", "output.every"}
INTEGER_BAD = ["4294967297", "-4294967295", "2.5"]
KEYS = ["rotor.mass", "rotor.Jd", "rotor.Jp", "rotor.L", "rotor.delta", "rotor.d",
        "rotor.radius", "bearing.k", "bearing.c", "stator.mass", "stator.k", "stator.c",
        "stator.gap", "contact.mu", "contact.e_n", "contact.e_t", "loads.gravity",
        "loads.torque", "initial.x_r", "initial.omega0", "run.t_start", "run.t_end",
        "run.omega_lim", "solver.rtol", "solver.atol", "solver.max_events_per_second",
        "solver.h", "solver.itmax", "solver.qn_tol", "solver.theta", "solver.eta", "output.dt",
        "output.every"]
NEGATIVE_OK = {"loads.torque", "initial.x_r", "initial.omega0"}  # any finite value is valid


def folder(name):
    d = os.path.join(OUT, name.replace(" ", "_").replace("/", "_").replace("'", "")
                     .replace("=", "_"))
    shutil.rmtree(d, ignore_errors=True)
    return d


def run(args, timeout=120, env_prefix=None):
    cmd = [RUBDYN] + args
    if env_prefix:
        cmd = ["bash", "-c", env_prefix + " exec \"$@\"", "bash"] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, errors="replace")
    return p.returncode, p.stderr


def summary(d):
    try:
        with open(os.path.join(d, "summary.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def record(category, scenario, expected, got, ok, note=""):
    ROWS.append({"category": category, "scenario": scenario, "expected": expected,
                 "outcome": got, "ok": ok, "note": note.strip().replace("\n", " ")[:160]})


def last_time(d):
    """Time of the last complete row of d/timeseries.csv (as written: 17 digits)."""
    with open(os.path.join(d, "timeseries.csv")) as f:
        text = f.read()
    rows = text[:text.rfind("\n")].splitlines()
    return float(rows[-1].split(",")[0])


def expect_bad_input(category, scenario, args, must_name):
    d = folder(category + "-" + scenario)
    rc, err = run(args + ["--out", d])
    ok = rc == 2 and must_name in err and not os.path.exists(d)
    record(category, scenario, "exit 2, names %s, nothing written" % must_name,
           "exit %d%s" % (rc, ", folder written" if os.path.exists(d) else ""), ok,
           err.splitlines()[-1] if err else "")


def bad_keys():
    for key in KEYS:
        values = list(BAD_VALUES)
        if key not in NEGATIVE_OK:
            values.append("-1")
        if key in INTEGER_KEYS:
            values += INTEGER_BAD
        for v in values:
            # (--t-end would override a bad run.t_end: it is applied after --set)
            short = [] if key == "run.t_end" else ["--t-end", "0.001"]
            expect_bad_input("bad case value", "%s=%s" % (key, v),
                             ["run", CASE] + short + ["--set", "%s=%s" % (key, v)], key)


def bad_options():
    cases = [
        ("--h 1e-300 (1e297 steps)", ["--solver", "mj", "--t-end", "1e-3", "--h", "1e-300"],
         "solver.h"),
        ("--h 0.1 > t_end", ["--solver", "mj", "--t-end", "1e-3", "--h", "0.1"], "solver.h"),
        ("--h 4e-3 (2.5 steps)", ["--solver", "mj", "--t-end", "0.01", "--h", "4e-3"],
         "solver.h"),
        ("--h 1e-20", ["--solver", "mj", "--t-end", "0.01", "--h", "1e-20"], "solver.h"),
        ("--solver ''", ["--solver", ""], "solver.kind"),
        ("--h with the event solver", ["--h", "1e-6"], "--h"),
        ("--rtol with mj", ["--solver", "mj", "--rtol", "1e-8"], "--rtol"),
        ("t_end = 1e300", ["--t-end", "1e300"], "run.t_end"),
        ("output.dt = 1e-300", ["--set", "output.dt=1e-300"], "output.dt"),
        ("--set ''", ["--set", ""], "override"),
        ("--at without --from", ["--at", "0.01"], "--at"),
    ]
    for name, args, key in cases:
        expect_bad_input("bad option", name, ["run", CASE] + args, key)
    for name, path, what in [("a directory", "/tmp", "directory"),
                             ("/dev/zero", "/dev/zero", "is a device")]:
        rc, err = run(["check", path])
        record("bad option", "case file is " + name, "exit 2, says what it is",
               "exit %d" % rc, rc == 2 and what in err, err.splitlines()[-1] if err else "")


def corpus():
    for path in sorted(glob.glob(os.path.join(ROOT, "tests", "fuzz", "corpus", "*.toml"))):
        d = folder("corpus-" + os.path.basename(path))
        rc, err = run(["run", path, "--out", d])
        record("corpus of bad case files", os.path.basename(path), "exit 2, nothing written",
               "exit %d" % rc, rc == 2 and not os.path.exists(d),
               err.splitlines()[-1] if err else "")


def numerical():
    # (initial.omega0 = 1e300 is refused as input now: an initial rim speed above 2e4 m/s)
    for s in ["initial.vy_r=1e150", "loads.torque=1e300", "loads.gravity=1e300"]:
        d = folder("numerical-" + s)
        rc, err = run(["run", CASE, "--t-end", "0.01", "--quiet", "--set", s, "--out", d])
        sm = summary(d)
        ok = rc == 3 and sm is not None and sm["complete"] is False and "[CVODES" not in err
        record("numerical fault", s, "exit 3, complete false, no CVODES text",
               "exit %d, %s" % (rc, sm["termination"] if sm else "no summary"), ok,
               sm["message"] if sm else err)


def wait_rows(d, limit=60.0):
    t0 = time.time()
    path = os.path.join(d, "timeseries.csv")
    while time.time() - t0 < limit:
        if os.path.exists(path) and os.path.getsize(path) >= 8192:
            return
        time.sleep(0.01)


def interruptions():
    for sig, solver in [(signal.SIGINT, "event"), (signal.SIGTERM, "event"),
                        (signal.SIGINT, "mj"), (signal.SIGTERM, "mj"),
                        (signal.SIGKILL, "event"), (signal.SIGKILL, "mj")]:
        name = "%s during a %s run" % (sig.name, solver)
        d = folder("signal-" + name)
        p = subprocess.Popen([RUBDYN, "run", CASE, "--t-end", "1000", "--solver", solver,
                              "--quiet", "--out", d], stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
        wait_rows(d)
        p.send_signal(sig)
        rc = p.wait(timeout=120)
        sm = summary(d)
        if sig == signal.SIGKILL:
            expected = "killed; analyze, compare, read_output and --from accept the folder"
            a_rc, a_err = run(["analyze", d, "--out", os.path.join(d, "an")])
            c_rc, _ = run(["compare", d, d])
            # on for 10 ms past the last complete sample (a whole number of mj steps of 1e-6 s)
            t_end = "%.17g" % (last_time(d) + 0.01)
            r_rc, r_err = run(["run", CASE, "--t-end", t_end, "--solver", solver, "--from", d,
                               "--quiet", "--out", d + "-restart"], timeout=300)
            # plain mj allows O(h) penetration: a restart from a state inside the stator is
            # refused like any initial penetration (README), which is the expected outcome
            refused_inside = r_rc == 2 and "penetrates the stator" in r_err
            try:
                # the reader needs summary.json; a killed run has none: give it an empty one
                read_ok = True
                if not os.path.exists(os.path.join(d, "summary.json")):
                    with open(os.path.join(d, "summary.json"), "w") as f:
                        f.write("{}")
                read_output(d)
            except Exception:  # noqa: BLE001
                read_ok = False
            ok = (rc == -signal.SIGKILL and a_rc == 0 and c_rc == 0 and read_ok
                  and (r_rc == 0 or refused_inside))
            got = "analyze %d, compare %d, restart %d%s, read_output %s" % (
                a_rc, c_rc, r_rc, " (state inside the stator: refused)" if refused_inside else "",
                "ok" if read_ok else "FAILED")
            note = "warning: %s" % ("yes" if "no line end" in a_err else "none (row complete)")
        else:
            expected = "exit 4, complete false, interrupted"
            ok = rc == 4 and sm is not None and sm["termination"] == "interrupted" \
                and sm["complete"] is False
            got = "exit %d, %s" % (rc, sm["termination"] if sm else "no summary")
            note = sm["message"] if sm else ""
            a_rc, _ = run(["analyze", d, "--out", os.path.join(d, "an")])
            ok = ok and a_rc == 0
            got += ", analyze %d" % a_rc
        record("interruption", name, expected, got, ok, note)


def faults():
    # a full device from the start
    d = folder("fault-dev-full")
    os.makedirs(d)
    os.symlink("/dev/full", os.path.join(d, "timeseries.csv"))
    rc, err = run(["run", CASE, "--t-end", "0.03", "--quiet", "--out", d])
    record("write fault", "timeseries.csv -> /dev/full", "exit 2 naming the file, no summary",
           "exit %d" % rc, rc == 2 and "timeseries.csv" in err and summary(d) is None,
           err.splitlines()[-1] if err else "")
    # a file size limit reached during the run
    d = folder("fault-fsize")
    rc, err = run(["run", CASE, "--t-end", "1", "--quiet", "--out", d],
                  env_prefix="ulimit -f 100; trap '' XFSZ;")
    sm = summary(d)
    record("write fault", "file size limit (ulimit -f 100) during the run",
           "exit 5 naming the file, output_failure",
           "exit %d, %s" % (rc, sm["termination"] if sm else "no summary"),
           rc == 5 and sm is not None and sm["termination"] == "output_failure"
           and "timeseries.csv" in err, sm["message"] if sm else err)
    # two runs into one folder at once
    d = folder("fault-two-runs")
    p = subprocess.Popen([RUBDYN, "run", CASE, "--t-end", "1000", "--quiet", "--out", d],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wait_rows(d)
    rc, err = run(["run", CASE, "--t-end", "0.01", "--quiet", "--out", d])
    p.send_signal(signal.SIGINT)
    first = p.wait(timeout=120)
    record("write fault", "a second run into a folder in use", "exit 2 saying so; first run intact",
           "exit %d (first run: exit %d)" % (rc, first),
           rc == 2 and "in use" in err and first == 4, err.splitlines()[-1] if err else "")
    # an old summary.json that cannot be removed
    d = folder("fault-stale-summary")
    os.makedirs(os.path.join(d, "summary.json", "x"))
    rc, err = run(["run", CASE, "--t-end", "0.01", "--quiet", "--out", d])
    record("write fault", "old summary.json cannot be removed", "exit 2, nothing written",
           "exit %d" % rc, rc == 2 and not os.path.exists(os.path.join(d, "timeseries.csv")),
           err.splitlines()[-1] if err else "")


def sweeps():
    base = ["sweep", CASE, "--t-end", "0.001", "--quiet"]
    for name, args, what in [
            ("1e6 points", ["--vary", "contact.mu=0:0.2:1000", "--vary", "stator.k=1e6:3e6:1000"],
             "limit"),
            ("two 1e5-value lists (1e10 points)",
             ["--vary", "contact.mu=0:0.2:100000", "--vary", "stator.k=1e6:3e6:100000"], "limit"),
            ("--min-turns -1", ["--vary", "contact.mu=0.1,0.2", "--min-turns", "-1"],
             "--min-turns"),
            ("one key varied twice", ["--vary", "contact.mu=0.1", "--vary", "contact.mu=0.2"],
             "twice"),
            ("--shard 99999999999/99999999999",
             ["--vary", "contact.mu=0.1", "--shard", "99999999999/99999999999"], "--shard")]:
        d = folder("sweep-" + name)
        rc, err = run(base + args + ["--out", d])
        record("sweep options", name, "exit 2 before any point", "exit %d" % rc,
               rc == 2 and what in err and not os.path.exists(d),
               err.splitlines()[-1] if err else "")


def readers():
    d = folder("readers")
    os.makedirs(d)
    with open(os.path.join(d, "only_t.csv"), "w") as f:
        f.write("t\n0\n1\n")
    with open(os.path.join(d, "a.csv"), "w") as f:
        f.write("t,x_r\n0,0\n1,1\n2,2\n")
    with open(os.path.join(d, "b.csv"), "w") as f:
        f.write("t,x_r\n0,0\n1,nan\n2,2\n")
    rc, err = run(["compare", os.path.join(d, "a.csv"), os.path.join(d, "only_t.csv")])
    record("readers", "compare with nothing comparable", "exit 2", "exit %d" % rc, rc == 2,
           err.splitlines()[-1] if err else "")
    p = subprocess.run([RUBDYN, "compare", os.path.join(d, "a.csv"), os.path.join(d, "b.csv")],
                       capture_output=True, text=True)
    record("readers", "compare with a NaN in x_r", "the NaN is a difference (sup inf)",
           "exit %d" % p.returncode, p.returncode == 0 and " inf " in p.stdout
           and "not finite" in p.stdout, "")


def main():
    os.makedirs(OUT, exist_ok=True)
    t0 = time.time()
    for part in (bad_keys, bad_options, corpus, numerical, interruptions, faults, sweeps, readers):
        part()
        print("%-14s %d checks so far, %d failed" % (part.__name__, len(ROWS),
                                                      sum(not r["ok"] for r in ROWS)), flush=True)
    write_csv(os.path.join(HERE, "table.csv"), ROWS)
    cats = []
    for r in ROWS:
        if r["category"] not in cats:
            cats.append(r["category"])
    with open(os.path.join(HERE, "table.md"), "w") as f:
        f.write("# Robustness suite\n\nGenerated by `validation/robustness/run.py` in %.0f s. "
                "Machine: %s.\n\nExit codes (README.md): 0 complete, 2 bad input / folder in "
                "use or not preparable (nothing written), 3 numerical early end, 4 interrupted, "
                "5 a write failed.\n\n"
                "Found while building the suite: rotor.Jp = 4294967297 once made the event "
                "solver crawl inside its first output interval; it is now refused (a rigid body "
                "has Jp <= 2 Jd), and every run ends in bounded time (README.md, Termination "
                "reasons and guards).\n\n" % (time.time() - t0, machine()))
        f.write("| category | tried | failed |\n|---|---|---|\n")
        for c in cats:
            rows = [r for r in ROWS if r["category"] == c]
            f.write("| %s | %d | %d |\n" % (c, len(rows), sum(not r["ok"] for r in rows)))
        f.write("| **all** | %d | %d |\n\n" % (len(ROWS), sum(not r["ok"] for r in ROWS)))
        f.write("## Every interruption, fault, numerical and sweep scenario\n\n"
                "| category | scenario | expected | outcome | ok | message |\n"
                "|---|---|---|---|---|---|\n")
        for r in ROWS:
            if r["category"] in ("bad case value", "corpus of bad case files") and r["ok"]:
                continue  # counted above; failures are listed
            f.write("| %s | %s | %s | %s | %s | %s |\n" % (
                r["category"], r["scenario"].replace("|", "\\|"), r["expected"], r["outcome"],
                "yes" if r["ok"] else "**NO**", r["note"].replace("|", "\\|")))
    print(open(os.path.join(HERE, "table.md")).read())
    return 0 if all(r["ok"] for r in ROWS) else 1


if __name__ == "__main__":
    sys.exit(main())
