#!/usr/bin/python3
"""What writing every coordinate costs a wide model (issue 32, item 6): the finite-element run-up
of cases/fe-runup/rotor.toml with 12, 24, 48, 96 elements (n = 52 .. 388 coordinates), 0.2 s,
the event solver as the case runs it, once with output.coordinates = "all" and once with
"contacts" (the default above 64 coordinates: the seal node, its ring, the spin; the full state in
state.csv at the first sample, each event and the last sample). CPU seconds (user + system of
the child, the median of --rounds runs, the two settings alternating), the bytes written, and a
check that the columns both write are the same bits. Writes bench/FE_OUTPUT.md.

    bench/fe_output.py [--cli build/rubdyn] [--rounds 3] [--elements 12 24 48 96]
"""
import argparse
import csv
import os
import statistics
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "validation", "fe"))
import fe_common  # noqa: E402


def columns(path):
    """A CSV file's columns by name, as the text written."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])}


def written(folder):
    """Bytes of timeseries.csv and state.csv (absent: 0)."""
    return sum(os.path.getsize(os.path.join(folder, f)) for f in ("timeseries.csv", "state.csv")
               if os.path.exists(os.path.join(folder, f)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "rubdyn"))
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--elements", type=int, nargs="+", default=[12, 24, 48, 96])
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "FE_OUTPUT.md"))
    a = ap.parse_args()
    desc = os.path.join(ROOT, "cases", "fe-runup", "rotor.toml")
    settings = {"all": ["--set", 'output.coordinates="all"'],
                "contacts": ["--set", 'output.coordinates="contacts"']}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for e in a.elements:
            case = fe_common.make_case(desc, e, os.path.join(tmp, f"e{e}.toml"),
                                       os.path.join(tmp, f"e{e}"), f"e{e}")
            cpu = {k: [] for k in settings}
            for _ in range(a.rounds):
                for k, args in settings.items():
                    c, s = fe_common.timed_run(a.cli, case, os.path.join(tmp, f"{k}{e}"), args)
                    cpu[k].append(c)
            full, thin = (columns(os.path.join(tmp, f"{k}{e}", "timeseries.csv"))
                          for k in ("all", "contacts"))
            same = all(full[name] == thin[name] for name in thin)
            r = {"e": e, "n": 4 * (e + 1), "steps": s["steps"], "same": same,
                 "cols": (len(full), len(thin))}
            for k in settings:
                r[k] = {"cpu": statistics.median(cpu[k]),
                        "bytes": written(os.path.join(tmp, f"{k}{e}"))}
            rows.append(r)
            print(f"e{e}: all {r['all']['cpu']:.2f} s {r['all']['bytes']} B, contacts "
                  f"{r['contacts']['cpu']:.2f} s {r['contacts']['bytes']} B, same bits {same}",
                  flush=True)
    lines = [
        "# Output of wide models: every coordinate against the contacts'",
        "",
        "Written by `bench/fe_output.py` (do not edit by hand). Machine: "
        f"{fe_common.machine()}; CPU seconds (user + system), the median of {a.rounds} run(s), "
        "the two settings alternating.",
        "",
        "The scene of bench/FE_SCALING.md (the FE run-up, 0.2 s, output every 0.1 ms, the event "
        "solver at the case's rtol 1e-8). `all`: timeseries.csv holds every coordinate and its "
        "rate; `contacts` (the default above 64 coordinates): the seal node's x, y, the ring, "
        "the spin, and state.csv the full state at the first sample, each event and the last "
        "sample. Bytes: timeseries.csv + state.csv. Same bits: every column `contacts` writes "
        "equals `all`'s, row by row, as text.",
        "",
        "| n | steps | columns all / contacts | all CPU s | contacts CPU s | ratio | all MB | "
        "contacts MB | same bits |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        al, co = r["all"], r["contacts"]
        lines.append(f"| {r['n']} | {r['steps']} | {r['cols'][0]} / {r['cols'][1]} | "
                     f"{al['cpu']:.2f} | {co['cpu']:.2f} | {co['cpu'] / al['cpu']:.2f} | "
                     f"{al['bytes'] / 1e6:.1f} | {co['bytes'] / 1e6:.2f} | "
                     f"{'yes' if r['same'] else 'NO'} |")
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {a.out}")
    return 0 if all(r["same"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
