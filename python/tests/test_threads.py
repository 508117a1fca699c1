"""rubdyn.run releases the GIL: Python keeps running while a case runs, and two cases on two
threads take less wall time than one after the other."""
import os
import threading
import time

import pytest

import rubdyn
from conftest import REFERENCE

# mu = 0.25 rolls (stick) after about 0.12 s: about 0.5 s of wall time for 0.25 s simulated, long
# enough against thread start-up and scheduling (milliseconds), short enough for the test suite.
OVERRIDES = {"contact.mu": 0.25, "run.t_end": 0.25}


def timed_run(case, out, i):
    t0 = time.perf_counter()
    out[i] = rubdyn.run(case)
    return time.perf_counter() - t0


def test_python_runs_while_a_case_runs():
    case = rubdyn.load_case(REFERENCE, overrides=OVERRIDES)
    out = [None]
    worker = threading.Thread(target=timed_run, args=(case, out, 0))
    t0 = time.perf_counter()
    beats, last, max_gap = 0, t0, 0.0  # from before the start: the worker may take the GIL first
    worker.start()
    while worker.is_alive():
        time.sleep(0.001)
        now = time.perf_counter()
        max_gap, last = max(max_gap, now - last), now
        beats += 1
    worker.join()
    duration = time.perf_counter() - t0
    assert out[0].summary["complete"]
    # With the GIL held for the run the main thread would not run at all until it ends: one gap
    # as long as the run. Released, the gaps are the 1 ms sleep plus scheduling (a few ms, tens
    # on a loaded machine); half the run's duration (about 0.25 s) separates the two.
    assert duration > 0.1, "the run is too short to tell"
    assert beats > 10 and max_gap < 0.5 * duration, (beats, max_gap, duration)


def test_two_threads_run_two_cases_faster_than_one_after_the_other():
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    if (cores or 1) < 2:
        pytest.skip("fewer than 2 cores: threads cannot run cases in parallel")
    cases = [rubdyn.load_case(REFERENCE, overrides=OVERRIDES),
             rubdyn.load_case(REFERENCE, overrides=dict(OVERRIDES, **{"contact.mu": 0.26}))]
    ratios = []
    # Ratio = (two cases on two threads) / (the two one after the other). The GIL held during a
    # run serialises the threads: ratio >= 1 whatever the load. Released, on two idle cores the
    # ratio is about 0.5; the machine's cores are shared (builds of other jobs), which can push
    # one measurement towards 1, so the best of up to three attempts is taken and must be < 0.8.
    # A retry cannot hide a held GIL: no attempt of a serialised run beats 1 by 20 % (unless the
    # load drops by as much between the two halves of one attempt, which three attempts make
    # unlikely, and which the heartbeat test above does not depend on).
    for _ in range(3):
        alone, out = [None, None], [None, None]
        serial = sum(timed_run(c, alone, i) for i, c in enumerate(cases))
        threads = [threading.Thread(target=timed_run, args=(c, out, i))
                   for i, c in enumerate(cases)]
        t0 = time.perf_counter()
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        parallel = time.perf_counter() - t0
        assert all(r is not None and r.summary["complete"] for r in out)
        # runs are independent (no global state, simulate.hpp): the same doubles on threads
        for a, b in zip(alone, out):
            assert a["omega"].tobytes() == b["omega"].tobytes()
        ratios.append(parallel / serial)
        if ratios[-1] < 0.8:
            break
    if min(ratios) >= 0.8 and os.getloadavg()[0] > cores + 1:
        # more runnable tasks than cores besides our two threads: no parallel gain can show
        pytest.skip(f"machine saturated (load {os.getloadavg()[0]:.1f} on {cores} cores): "
                    f"ratios {ratios}")
    assert min(ratios) < 0.8, ratios
