#!/usr/bin/python3
"""Speed-up of two threads running two cases through the Python module (the GIL is released
during a run): the ratio (two cases on two threads) / (the two one after the other), median of 5
attempts, with the machine and its load. About 0.5 on two idle cores; 1 or more if the GIL were
held. Usage: PYTHONPATH=build/python bench/python_threads.py
"""
import os
import statistics
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "validation"))
import rubdyn  # noqa: E402
from common import machine  # noqa: E402

REFERENCE = os.path.join(os.path.dirname(HERE), "cases", "reference.toml")
OVERRIDES = {"contact.mu": 0.25, "run.t_end": 0.25}


def timed_run(case, out, i):
    t0 = time.perf_counter()
    out[i] = rubdyn.run(case)
    return time.perf_counter() - t0


def main():
    cases = [rubdyn.load_case(REFERENCE, overrides=OVERRIDES),
             rubdyn.load_case(REFERENCE, overrides=dict(OVERRIDES, **{"contact.mu": 0.26}))]
    ratios = []
    for _ in range(5):
        alone, out = [None, None], [None, None]
        serial = sum(timed_run(c, alone, i) for i, c in enumerate(cases))
        threads = [threading.Thread(target=timed_run, args=(c, out, i))
                   for i, c in enumerate(cases)]
        t0 = time.perf_counter()
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        ratios.append((time.perf_counter() - t0) / serial)
    print(f"machine: {machine()}; load average {os.getloadavg()}")
    print(f"two threads / one after the other: median {statistics.median(ratios):.2f} "
          f"(attempts {', '.join(f'{r:.2f}' for r in ratios)})")


if __name__ == "__main__":
    main()
