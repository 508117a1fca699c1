"""Regressions of issue 22 (the Python surface as careful as the CLI): a loaded case is a
snapshot, overrides cannot smuggle keys, arguments are checked with exceptions naming them,
compare and analyze never crash on empty or NaN input. The garbage-folder and argument fuzzing
is test_fuzz.py."""
import shutil

import numpy as np
import pytest

import rubdyn
from conftest import REFERENCE, run_cli


def test_a_loaded_case_is_a_snapshot_of_its_file(tmp_path):
    path = tmp_path / "case.toml"
    text = open(REFERENCE).read()
    assert "mu  = 0.1" in text
    path.write_text(text)
    case = rubdyn.load_case(path, overrides={"run.t_end": 0.002})
    # the file changes after loading: another mu, and a section the loader refuses
    path.write_text(text.replace("mu  = 0.1", "mu  = 0.3") + "\n[bogus]\nx = 1\n")
    with pytest.raises(rubdyn.CaseError, match="bogus"):
        rubdyn.load_case(path)  # (the edit is one the loader sees)
    # run's options re-parse the case with more overrides: from the snapshot, not the file
    res = rubdyn.run(case, t_end=0.001)
    assert res.summary["complete"]
    assert res.case["contact.mu"] == 0.1 and res.case["run.t_end"] == 0.001
    assert case.path == str(path) and case.source == str(path)


@pytest.mark.parametrize("overrides, where", [
    (["contact.mu=0.3\ncontact.e_n=0.5"], r"overrides\[0\]"),
    ({"contact.mu": "0.3\ncontact.e_n=0.5"}, r"overrides\['contact.mu'\]"),
    (["contact.mu=0.3\r"], r"overrides\[0\]"),
])
def test_overrides_cannot_smuggle_a_second_key(overrides, where):
    # before: the first form set mu = 0.3 and dropped e_n = 0.5 without a word
    with pytest.raises(ValueError, match=where + ".*one line without control characters"):
        rubdyn.load_case(REFERENCE, overrides=overrides)


def test_the_cli_refuses_the_smuggled_override_too(cli):
    p = run_cli(cli, "check", REFERENCE, "--set", "contact.mu=0.3\ncontact.e_n=0.5")
    assert p.returncode == 2
    assert ("--set: (override) = \"contact.mu=0.3\\ncontact.e_n=0.5\": an override is one line"
            in p.stderr)


@pytest.mark.parametrize("overrides", ["contact.mu=0.3", b"contact.mu=0.3", 5,
                                       {"contact.mu=0.3"}])
def test_overrides_must_be_a_dict_or_a_list(overrides):
    # before: a str was iterated into one override per character
    with pytest.raises(TypeError, match="overrides must be a dict"):
        rubdyn.load_case(REFERENCE, overrides=overrides)


@pytest.mark.parametrize("overrides, exc, match", [
    ({"contact.mu": [0.3]}, TypeError, r"overrides\['contact.mu'\] must be a bool, int, float"),
    ({"contact.mu": None}, TypeError, r"overrides\['contact.mu'\] must be a bool, int, float"),
    ({"contact.mu=0.3": 1}, ValueError, r"key 'contact.mu=0.3' must read section.key"),
    ({"contact mu": 1}, ValueError, r"key 'contact mu' must read section.key"),
    ({3: 1}, TypeError, r"key 3 must be a str"),
    ([3], TypeError, r"overrides\[0\] must be a str"),
    ({"contact.mu": float("nan")}, rubdyn.CaseError, r"contact.mu = nan: must be a finite"),
    ({"contact.mu": np.float64("inf")}, rubdyn.CaseError, r"contact.mu = inf: must be a finite"),
])
def test_override_values_are_checked(overrides, exc, match):
    with pytest.raises(exc, match=match):
        rubdyn.load_case(REFERENCE, overrides=overrides)


def test_numpy_numbers_are_override_values():
    case = rubdyn.load_case(REFERENCE, overrides={"contact.mu": np.float64(0.25),
                                                  "output.every": np.int64(3)})
    assert case.mu == 0.25 and case["output.every"] == 3


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"t_end": "0.01\nrun.t_end=5"}, TypeError, "run: t_end must be a number, not str"),
    ({"t_end": True}, TypeError, "run: t_end must be a number, not bool"),
    ({"rtol": [1e-8]}, TypeError, "run: rtol must be a number, not list"),
    ({"solver": "mj\nsolver.h=1e-6"}, ValueError, "run: solver = .*must be one word"),
    ({"solver": "mj=x"}, ValueError, "run: solver = .*must be one word"),
    ({"method": 3}, TypeError, "run: method must be a str"),
    ({"output_every": 2.5}, TypeError, "run: output_every must be an int"),
    ({"progress": 3}, TypeError, "run: progress must be callable"),
    ({"progress_interval": float("nan")}, ValueError, "run: progress_interval = nan"),
    ({"progress_interval": -1}, ValueError, "run: progress_interval = -1.0: must be >= 0"),
    ({"rtol": float("nan")}, rubdyn.CaseError, "solver.rtol = nan: must be a finite number"),
    ({"t_end": float("inf")}, rubdyn.CaseError, "run.t_end = inf: must be a finite number"),
])
def test_run_options_are_checked(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        rubdyn.run(REFERENCE, **kwargs)


def test_compare_empty_arrays_raise_instead_of_crashing():
    # before: a segmentation fault (front() of an empty vector in compare_solutions)
    t = np.linspace(0.0, 1.0, 5)
    empty = {"t": np.array([]), "omega": np.array([])}
    with pytest.raises(ValueError, match="compare: a: 0 samples: compare needs at least two"):
        rubdyn.compare(empty, {"t": t, "omega": t})
    with pytest.raises(ValueError, match="compare: b: 0 samples"):
        rubdyn.compare({"t": t, "omega": t}, empty)


def test_compare_a_header_only_folder_raises_instead_of_crashing(small_out, tmp_path):
    # before: rubdyn.read accepted the folder (a run killed before its first sample, 0 rows) and
    # compare of its Result crashed the interpreter
    dead = tmp_path / "dead"
    shutil.copytree(small_out, dead)
    ts = dead / "timeseries.csv"
    ts.write_text(ts.read_text().split("\n")[0] + "\n")
    (dead / "summary.json").unlink()
    with pytest.warns(RuntimeWarning, match="no summary.json"):
        res = rubdyn.read(dead)
    assert len(res) == 0
    ok = rubdyn.read(small_out)
    with pytest.raises(ValueError, match="compare: a: 0 samples"):
        rubdyn.compare(res, ok)
    with pytest.raises(rubdyn.ReadError, match=r"timeseries.csv: 0 samples") as err:
        rubdyn.compare(dead, ok)
    assert err.value.file == str(ts)
    with pytest.raises(ValueError, match="has no samples"):
        rubdyn.analyze(res)


@pytest.mark.parametrize("a, match", [
    ({"t": np.array([0.0, np.nan, 1.0]), "omega": np.zeros(3)}, r"compare: a: t\[1\] = nan"),
    ({"t": np.array([0.0, 2.0, 1.0]), "omega": np.zeros(3)}, r"compare: a: t\[2\] = 1 < t\[1\]"),
    ({"t": np.array([0.0, 1.0, 2.0]), "omega": np.zeros(2)},
     r"compare: a\['omega'\] has shape \(2,\), a\['t'\] \(3,\)"),
    ({"t": np.zeros((2, 2)), "omega": np.zeros(2)}, r"a\['t'\] must be a one-dimensional"),
    ({"omega": np.zeros(3)}, r"compare: a has no column 't'"),
])
def test_compare_array_inputs_are_checked(a, match):
    t = np.linspace(0.0, 2.0, 5)
    with pytest.raises(ValueError, match=match):
        rubdyn.compare(a, {"t": t, "omega": t})


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"window": (np.nan, 1.0)}, ValueError, r"compare: window\[0\] = nan: must be finite"),
    ({"window": (0.0, np.inf)}, ValueError, r"compare: window\[1\] = inf: must be finite"),
    ({"window": (1.0, 0.5)}, ValueError, r"compare: window = \(1.0, 0.5\): t0 must be < t1"),
    ({"window": (0.5, 0.5)}, ValueError, r"t0 must be < t1"),
    ({"window": (5.0, 6.0)}, ValueError, r"share no time inside the window \[5, 6\]"),
    ({"window": 1.0}, TypeError, r"compare: window must be two times"),
    ({"window": "01"}, TypeError, r"compare: window must be two times"),
    ({"event_tol": np.nan}, ValueError, r"compare: event_tol = nan: must be finite"),
    ({"event_tol": 0}, ValueError, r"compare: event_tol = 0.0: must be > 0"),
    ({"event_tol": "1e-3"}, TypeError, r"compare: event_tol must be a number"),
    ({"name_a": 3}, TypeError, r"compare: name_a must be a str"),
])
def test_compare_window_and_tolerance_are_checked(kwargs, exc, match):
    t = np.linspace(0.0, 2.0, 5)
    with pytest.raises(exc, match=match):
        rubdyn.compare({"t": t, "omega": t}, {"t": t, "omega": t}, **kwargs)


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"t_window": (np.nan, 0.004)}, ValueError, r"analyze: t_window\[0\] = nan: must be finite"),
    ({"t_window": (0.004, 0.001)}, ValueError, r"analyze: t_window = .*t0 must be < t1"),
    ({"t_window": 0.004}, TypeError, r"analyze: t_window must be two times"),
    ({"min_turns": "1"}, TypeError, r"analyze: min_turns must be a number"),
    ({"min_turns": np.nan}, ValueError, r"--min-turns = nan"),
])
def test_analyze_arguments_are_checked(small_out, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        rubdyn.analyze(small_out, **kwargs)


def test_analyze_refuses_nan_times_in_memory(small_out):
    res = rubdyn.read(small_out)
    rubdyn.analyze(res)  # the unperturbed result is analysed
    res.columns["t"] = res.columns["t"].copy()
    res.columns["t"][7] = np.nan
    # before: analysed as if nothing were wrong
    with pytest.raises(ValueError, match="analyze: result: sample 7: t = nan is not finite"):
        rubdyn.analyze(res)


@pytest.mark.parametrize("kwargs, exc, match", [
    ({"points": 1}, ValueError, r"campbell: points = 1: must lie in \[2, 100000\]"),
    ({"points": 10 ** 9}, ValueError, r"campbell: points = 1000000000"),
    ({"points": 2.5}, TypeError, r"campbell: points must be an int"),
    ({"omega_max": np.nan}, ValueError, r"campbell: omega_max = nan: must be finite"),
    ({"omega_max": -1.0}, ValueError, r"campbell: omega_max = -1.0: must be > 0"),
])
def test_campbell_arguments_are_checked_as_the_cli_does(cli, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        rubdyn.campbell(REFERENCE, **kwargs)
    # the CLI's range for --points (src/app/cmd_campbell.cpp), which Python repeats
    p = run_cli(cli, "campbell", REFERENCE, "--points", "100001", "--out", "/nonexistent")
    assert p.returncode == 2 and "must lie in [2, 100000]" in p.stderr
