"""The module rubdyn: loading errors as the CLI reports them, runs bitwise equal to the CLI's
output folder, reading folders (cut rows, header-only events), compare and campbell as the C++
tools compute them, the model's mechanics."""
import csv
import json
import math
import shutil
import warnings

import numpy as np
import pytest

import rubdyn
from conftest import REFERENCE, run_cli

IGNORED_SUMMARY_KEYS = {"wall_seconds", "phase_wall_seconds"}  # wall clock: differs run to run


def same_bits(a, b):
    """Bitwise equality of two float arrays (0.0 and -0.0 differ; NaN equals NaN)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return False
    return bool(np.all((a.view(np.int64) == b.view(np.int64)) | (np.isnan(a) & np.isnan(b))))


# --- loading -----------------------------------------------------------------------------------

def test_load_case_gives_a_validated_case():
    case = rubdyn.load_case(REFERENCE, overrides={"contact.mu": 0.25, "run.t_end": 0.2})
    assert case.name == "reference"
    assert case.mu == 0.25 and case.t_end == 0.2
    assert "mu = 0.25" in case.to_toml()


def test_invalid_override_raises_the_cli_message(cli, tmp_path):
    sets = ["contact.mu=-1", "rotor.bogus=2"]
    with pytest.raises(rubdyn.CaseError) as err:
        rubdyn.load_case(REFERENCE, overrides=sets)
    assert isinstance(err.value, ValueError)
    p = run_cli(cli, "check", REFERENCE, "--set", sets[0], "--set", sets[1])
    assert p.returncode == 2
    # the CLI prints exactly the exception's text (main.cpp: fprintf("%s\n", e.what()))
    assert p.stderr.strip() == str(err.value).strip()
    keys = {i["key"]: i for i in err.value.issues}
    assert set(keys) == {"contact.mu", "rotor.bogus"}
    assert keys["contact.mu"]["file"] == "--set" and keys["contact.mu"]["value"] == "-1"


def test_invalid_file_names_file_line_key_and_rule(tmp_path):
    bad = tmp_path / "bad.toml"
    text = open(REFERENCE).read().replace("gap  = 2.0e-4", "gap  = -2.0e-4")
    assert text != open(REFERENCE).read()
    bad.write_text(text)
    line = 1 + text[:text.index("gap  = -2.0e-4")].count("\n")
    with pytest.raises(rubdyn.CaseError) as err:
        rubdyn.load_case(bad)
    issue = [i for i in err.value.issues if i["key"] == "stator.gap"][0]
    assert issue["file"] == str(bad) and issue["line"] == line
    assert f"{bad}:{line}: stator.gap = " in str(err.value)


def test_missing_file_and_bad_solver_option_raise():
    with pytest.raises(rubdyn.CaseError):
        rubdyn.load_case("/nonexistent/case.toml")
    case = rubdyn.load_case(REFERENCE)
    with pytest.raises(rubdyn.CaseError, match="solver.rtol"):
        rubdyn.run(case, rtol=-1.0)
    with pytest.raises(rubdyn.CaseError, match="solver.kind"):
        rubdyn.run(case, solver="rk4")


def test_an_option_the_solver_does_not_read_is_refused_as_by_the_cli(cli, tmp_path):
    # the registry's solvers, and the refusal `rubdyn run` gives for --h with the event solver
    names = [e["name"] for e in rubdyn.solvers()]
    assert names[0] == "event" and "mj" in names
    case = rubdyn.load_case(REFERENCE, overrides={"run.t_end": 0.001})
    with pytest.raises(ValueError, match="solver event does not read solver.h"):
        rubdyn.run(case, h=1e-6)
    with pytest.raises(ValueError, match="solver mj does not read solver.rtol"):
        rubdyn.run(case, solver="mj", rtol=1e-8)
    proc = run_cli(cli, "run", REFERENCE, "--h", "1e-6", "--out", str(tmp_path / "x"))
    assert proc.returncode == 2 and "solver event does not read solver.h" in proc.stderr


# --- runs equal to the CLI's, bit for bit -------------------------------------------------------

def test_run_equals_the_cli_bitwise(cli_reference_out):
    res = rubdyn.run(rubdyn.load_case(REFERENCE), t_end=0.1, rtol=1e-9)
    cli = rubdyn.read(cli_reference_out)
    assert res.summary["complete"] and len(res.events) > 3  # impacts, slip, lift-offs
    assert list(res.columns) == list(cli.columns)  # same names, same order as timeseries.csv
    for name in res.columns:
        assert same_bits(res[name], cli[name]), name
    for name, kind in rubdyn.EVENT_FIELDS:
        if kind == "f8":
            assert same_bits(res.events[name], cli.events[name]), name
        else:
            assert list(res.events[name]) == list(cli.events[name]), name
    for key in res.summary:
        if key not in IGNORED_SUMMARY_KEYS:
            assert res.summary[key] == cli.summary[key], key
    assert set(res.summary) == set(cli.summary)


def test_run_fixed_step_equals_the_cli_bitwise(cli, tmp_path):
    out = tmp_path / "mj"
    p = run_cli(cli, "run", REFERENCE, "--solver", "mj", "--h", "1e-5", "--t-end", "0.02",
                "--out", str(out), "--quiet")
    assert p.returncode == 0, p.stderr
    res = rubdyn.run(REFERENCE, solver="mj", h=1e-5, t_end=0.02)
    folder = rubdyn.read(out)
    assert res.summary["solver"] == "mj"
    for name in res.columns:
        assert same_bits(res[name], folder[name]), name


def test_read_a_jeffcott_folder_equals_the_run_bitwise(cli, tmp_path):
    # the Jeffcott rotor at a prescribed speed: 5 coordinates and the drive_torque column, read
    # by the C++ reader through the model's column table
    text = open(REFERENCE.replace("reference.toml", "jeffcott.toml")).read()
    assert "torque    = 20.0" in text
    case_file = tmp_path / "jeffcott_prescribed.toml"
    case_file.write_text(text.replace("torque    = 20.0", 'spin = "prescribed"'))
    out = tmp_path / "jeffcott"
    p = run_cli(cli, "run", str(case_file), "--t-end", "0.03", "--out", str(out), "--quiet")
    assert p.returncode == 0, p.stderr
    folder = rubdyn.read(out)
    res = rubdyn.run(str(case_file), t_end=0.03)
    assert folder.case.kind == "jeffcott" and folder.case["loads.spin"] == "prescribed"
    assert list(folder.columns) == list(res.columns) == folder.case.columns
    assert "drive_torque" in folder.columns and "x_b" not in folder.columns
    for name in res.columns:
        assert same_bits(res[name], folder[name]), name
    assert len(folder.events) == len(res.events) > 0
    for name, kind in rubdyn.EVENT_FIELDS:
        if kind == "f8":
            assert same_bits(res.events[name], folder.events[name]), name
        else:
            assert list(res.events[name]) == list(folder.events[name]), name
    for key in res.summary:
        if key not in IGNORED_SUMMARY_KEYS:
            assert res.summary[key] == folder.summary[key], key


def test_read_a_malformed_folder_names_file_line_and_column(cli_reference_out, tmp_path):
    bad = tmp_path / "bad"
    shutil.copytree(cli_reference_out, bad)
    ts = bad / "timeseries.csv"
    lines = ts.read_text().split("\n")
    header = lines[0].split(",")
    row = lines[3].split(",")
    row[header.index("omega")] = "fast"
    lines[3] = ",".join(row)
    ts.write_text("\n".join(lines))
    with pytest.raises(ValueError, match=r"timeseries.csv:4: column omega: 'fast' is not a number"):
        rubdyn.read(bad)
    with pytest.raises(FileNotFoundError):
        rubdyn.read(tmp_path / "nothing")


def test_case_values_are_the_resolved_keys():
    ref = rubdyn.load_case(REFERENCE)
    text = open(REFERENCE.replace("reference.toml", "jeffcott.toml")).read()
    stator = text[text.index("[stator]"):text.index("gap  = 2.0e-4")]
    jc = rubdyn.parse_case(text.replace(stator, "[stator]\nrigid = true\n"))
    assert ref.kind == "rigid-rotor" and jc.kind == "jeffcott"
    # the keys of case.resolved.toml, with the values it writes
    for case in (ref, jc):
        values = case.values()
        resolved = [line.split(" = ")[0] for line in case.to_toml().splitlines()
                    if " = " in line and not line.startswith("name")]
        assert [k.split(".")[1] for k in values] == resolved
    assert jc["stator.rigid"] is True and "stator.mass" not in jc.values()
    assert ref["bearing.k"] == 5e6 and jc["rotor.mass"] == 5.0
    with pytest.raises(KeyError, match="not a key of this jeffcott case"):
        jc["bearing.k"]


def test_progress_is_called_and_its_exception_raised():
    calls = []
    rubdyn.run(REFERENCE, t_end=0.01, progress=lambda *a: calls.append(a), progress_interval=0)
    assert calls and calls[0][3] == "free" and 0 < calls[-1][0] <= 0.01

    def stop(*_):
        raise KeyError("from the callback")
    with pytest.raises(KeyError, match="from the callback"):
        rubdyn.run(REFERENCE, t_end=0.01, progress=stop)


def test_result_accessors():
    res = rubdyn.run(REFERENCE, t_end=0.03)
    assert res.t is res["t"] and len(res) == len(res.t)
    assert set(res.phase_names) <= set(rubdyn.PHASES)
    assert res.events.dtype.names == tuple(n for n, _ in rubdyn.EVENT_FIELDS)
    try:
        import pandas  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError):
            res.to_pandas()
    else:
        df, ev = res.to_pandas()
        assert len(df) == len(res) and len(ev) == len(res.events)


# --- reading output folders ---------------------------------------------------------------------

def test_read_a_cut_last_row_warns_and_drops_it(cli_reference_out, tmp_path):
    cut = tmp_path / "cut"
    shutil.copytree(cli_reference_out, cut)
    ts = cut / "timeseries.csv"
    text = ts.read_text()
    ts.write_text(text[:-40])  # a run killed while writing a row
    (cut / "summary.json").unlink()  # ... before its summary
    whole = rubdyn.read(cli_reference_out)
    with pytest.warns(RuntimeWarning):
        part = rubdyn.read(cut)
    assert part.summary is None
    assert len(part) == len(whole) - 1
    assert same_bits(part["omega"], whole["omega"][:-1])


def test_read_header_only_events(cli_reference_out, tmp_path):
    quiet = tmp_path / "quiet"
    shutil.copytree(cli_reference_out, quiet)
    ev = quiet / "events.csv"
    ev.write_text(ev.read_text().split("\n")[0] + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = rubdyn.read(quiet)
    assert len(res.events) == 0 and res.events.dtype.names[0] == "t"


# --- compare and campbell: the C++ tools ---------------------------------------------------------

def test_compare_matches_the_cli(cli, cli_reference_out, tmp_path):
    other = tmp_path / "rtol8"
    p = run_cli(cli, "run", REFERENCE, "--t-end", "0.1", "--rtol", "1e-8", "--out", str(other),
                "--quiet")
    assert p.returncode == 0, p.stderr
    js = tmp_path / "cmp.json"
    p = run_cli(cli, "compare", str(cli_reference_out), str(other), "--json", str(js))
    assert p.returncode == 0, p.stderr
    expected = json.loads(js.read_text())
    got = rubdyn.compare(str(cli_reference_out), str(other))
    assert dict(got) == expected and got.report == p.stdout
    # the same measures from results in memory and from a folder read in Python: the columns are
    # the same doubles, so every number is equal (the names of a and b aside)
    mem = rubdyn.compare(rubdyn.read(cli_reference_out),
                         rubdyn.run(REFERENCE, t_end=0.1, rtol=1e-8))
    for key in ("t0", "t1", "points", "columns", "missing_columns", "max_event_shift"):
        assert mem[key] == expected[key], key
    assert len(mem["matched_events"]) == len(expected["matched_events"]) > 0


def test_compare_plain_arrays():
    t = np.linspace(0.0, 1.0, 11)
    a = {"t": t, "omega": np.zeros_like(t)}
    b = {"t": t, "omega": 2.0 * t}
    c = rubdyn.compare(a, b)
    # sup |b - a| = 2 at t = 1 exactly. rms: the trapezoidal rule (compare.hpp) on 4 t^2 over
    # 10 intervals of 0.1 gives 4 (1/3 + 0.1^2/6) = 4 (1/3 + 1/600); equal to 1e-12 relative
    # (a dozen roundings in the sums, each 1e-16).
    assert c["columns"]["omega"]["sup"] == 2.0 and c["columns"]["omega"]["t_sup"] == 1.0
    assert math.isclose(c["columns"]["omega"]["rms"], math.sqrt(4 * (1 / 3 + 1 / 600)),
                        rel_tol=1e-12)


def test_campbell_matches_the_cli(cli, tmp_path):
    p = run_cli(cli, "campbell", REFERENCE, "--out", str(tmp_path), "--points", "21")
    assert p.returncode == 0, p.stderr
    d = rubdyn.campbell(REFERENCE, points=21)
    assert d["csv"] == (tmp_path / "campbell.csv").read_text()
    assert d["labels_ok"] and len(d["omega"]) == 21 and d["omega"][-1] == 2110.0


# --- the model ----------------------------------------------------------------------------------

def test_model_mechanics_agree_with_a_run():
    case = rubdyn.load_case(REFERENCE)
    model = rubdyn.Model(case)
    res = rubdyn.run(case, t_end=0.03)
    i = int(np.argmax(res.phase != 0))  # a sample in contact
    assert res.phase[i] != 0
    assert model.num_dofs == 7 and model.position_names[4] == "theta"
    q = np.array([res[n][i] for n in model.position_names])
    v = np.array([res[n][i] for n in model.rate_names])
    M = model.mass_matrix(q)
    assert M.shape == (7, 7) and np.array_equal(M, M.T)
    assert np.all(np.linalg.eigvalsh(M) > 0)
    k = model.contact(q, v)
    # the run's samples are computed by the same C++ contact kinematics from the same doubles
    assert k["d_N"] == res.d_N[i] and k["v_N"] == res.v_N[i] and k["v_t"] == res.v_t[i]
    # v_N = W_N . v and v_t = W_T . v (contact_kinematics.hpp); the sums of 7 products agree to
    # a few ulps of the largest product (|W_T| ~ R_r, omega ~ 2000 rad/s: ~100 m/s), 1e-12 abs.
    assert abs(k["W_N"] @ v - k["v_N"]) < 1e-12 and abs(k["W_T"] @ v - k["v_t"]) < 1e-12
    f = model.smooth_forces(0.0, q, v)
    # f = f_ext - (omega G + D) v - K q + gyroscopic: at least its torque row is tau_a
    assert f[4] == case.torque
    assert model.gap == case.gap and model.mu == case.mu


# --- analyze: the CLI's verdicts, in memory ---------------------------------------------------

def test_analyze_equals_the_cli(cli, tmp_path):
    # mu = 0.25 whips from about 0.067 s: the verdicts compared below are not all empty
    out = tmp_path / "whip"
    p = run_cli(cli, "run", REFERENCE, "--t-end", "0.1", "--set", "contact.mu=0.25", "--out",
                str(out), "--quiet")
    assert p.returncode == 0, p.stderr
    p = run_cli(cli, "analyze", str(out))
    assert p.returncode == 0, p.stderr
    with open(out / "analysis" / "analysis.json") as f:
        expected = json.load(f)
    assert expected["whip_onset"] is not None and expected["sign_backward_onset"] is not None
    res = rubdyn.run(rubdyn.load_case(REFERENCE, {"contact.mu": 0.25}), t_end=0.1)
    # the run equals the CLI's bit for bit (test_run_equals_the_cli_bitwise) and both sides
    # print the same doubles in shortest round-trip form: the verdicts are equal, not close
    for a in (rubdyn.analyze(res), rubdyn.analyze(out)):
        for key, value in expected.items():
            # the spectrum, the spectrogram and its aliasing marks are part of the files
            # `analyze` writes, not of the verdicts (rubdyn.analyze computes no spectra)
            if not key.startswith("spectr"):
                assert a.verdicts[key] == value, key
        with open(out / "analysis" / "derived.csv") as f:
            rows = list(csv.DictReader(f))
        assert len(rows) == len(a.derived["t"])
        for name in ("t", "precession", "friction_torque_ratio"):
            np.testing.assert_array_equal(a.derived[name],
                                          np.array([float(r[name]) for r in rows]))
        assert list(a.derived["whirl"]) == [r["whirl"] for r in rows]
        assert list(a.derived["sustained"]) == [r["sustained"] == "1" for r in rows]
        assert list(a.derived["sign_run"]) == [r["sign_run"] == "1" for r in rows]


def test_analyze_options_and_window():
    res = rubdyn.run(rubdyn.load_case(REFERENCE), t_end=0.02)
    with pytest.raises(ValueError, match="min-turns"):
        rubdyn.analyze(res, min_turns=0)
    a = rubdyn.analyze(res, t_window=(0.005, 0.015))
    assert a["t0"] == 0.005 and a["t1"] == 0.015
    res.case = None
    with pytest.raises(ValueError, match="case"):
        rubdyn.analyze(res)
