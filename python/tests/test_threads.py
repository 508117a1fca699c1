"""rubdyn.run releases the GIL: Python keeps running while a case runs. (That two cases on two
threads take less wall time than one after the other is a speed measurement: it is made by
bench/python_threads.py, not by a test, on a machine whose cores are shared.)"""
import os
import threading
import time

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


def test_ctrl_c_ends_a_run_with_keyboard_interrupt(tmp_path):
    # A run of 2 s of rolling (several seconds of wall time) in a child process; SIGINT once the
    # run has started must end it at its next sample and raise KeyboardInterrupt there, long
    # before the run would have completed (a completed run prints "completed").
    import signal
    import subprocess
    import sys
    script = tmp_path / "child.py"
    script.write_text(
        "import sys, rubdyn\n"
        f"case = rubdyn.load_case({str(REFERENCE)!r}, "
        "overrides={'contact.mu': 0.25, 'run.t_end': 2.0})\n"
        "print('started', flush=True)\n"
        "try:\n"
        "    rubdyn.run(case)\n"
        "    print('completed', flush=True)\n"
        "except KeyboardInterrupt:\n"
        "    print('KeyboardInterrupt', flush=True)\n")
    child = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True,
                             env=dict(os.environ))
    assert child.stdout.readline().strip() == "started"
    time.sleep(0.3)  # inside rubdyn.run (loading the case came before "started")
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=120)
    assert out.strip() == "KeyboardInterrupt", out
    assert child.returncode == 0
