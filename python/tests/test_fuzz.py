"""Fuzzing and fault injection for the Python module, beside the CLI's (tests/fuzz): garbage
output folders (binary, empty, header-only, short rows, CRLF, NaN times, missing or broken
summary.json, truncated rows), seeded mutations of a folder's files, and bad arguments (types,
NaN/inf, huge values) for every entry point. Each case states its outcome: the result it gives,
or the exception type with a message naming the file and line or the argument. Never a crash,
never an internal KeyError/IndexError/UnicodeDecodeError. Deterministic: fixed seeds.
RUBDYN_FUZZ_ITERATIONS=N runs N mutations per file instead of the default (a longer campaign)."""
import json
import math
import os
import random
import re
import shutil
import warnings

import numpy as np
import pytest

import rubdyn
from conftest import REFERENCE

ITERATIONS = int(os.environ.get("RUBDYN_FUZZ_ITERATIONS", "40"))


def lines_of(path):
    with open(path, "rb") as f:
        return f.read().split(b"\n")


def write_lines(path, lines):
    with open(path, "wb") as f:
        f.write(b"\n".join(lines))


def set_field(path, line, column, value):
    """Field `column` (by header name) of line `line` (1 = header) of a CSV file set to value."""
    ls = lines_of(path)
    header = ls[0].split(b",")
    row = ls[line - 1].split(b",")
    row[header.index(column.encode())] = value
    ls[line - 1] = b",".join(row)
    write_lines(path, ls)


# --- garbage folders: each damage, its outcome in every reader -----------------------------------
# (name, damage(folder), outcome) where outcome is (exception type, regex of the message, the
# file it names, the line it names) or None when the folder reads (the test states what it gives).

def _binary(d):
    with open(d / "timeseries.csv", "wb") as f:
        f.write(b"\xff" + random.Random(1).randbytes(4000))


def _binary_row(d):
    with open(d / "timeseries.csv", "ab") as f:
        f.write(b"0.5," + bytes(b for b in range(256) if b != 10) + b"\n")


def _control_char(d):
    set_field(d / "timeseries.csv", 5, "omega", b"2000\x1b[31m")


def _latin1(d):  # a non-UTF-8 byte in a text field of events.csv
    set_field(d / "events.csv", 2, "note", b"\"caf\xe9\"")


def _nul_events(d):
    with open(d / "events.csv", "ab") as f:
        f.write(b"\x00\x00\x00\n")


def _empty(d):
    open(d / "timeseries.csv", "wb").close()


def _short_row(d):
    ls = lines_of(d / "timeseries.csv")
    ls[3] = b",".join(ls[3].split(b",")[:5])
    write_lines(d / "timeseries.csv", ls)


def _long_row(d):
    ls = lines_of(d / "timeseries.csv")
    ls[3] += b",1"
    write_lines(d / "timeseries.csv", ls)


def _nan_time(d):
    set_field(d / "timeseries.csv", 4, "t", b"nan")


def _inf_time(d):
    set_field(d / "timeseries.csv", 6, "t", b"inf")


def _back_in_time(d):
    set_field(d / "timeseries.csv", 6, "t", b"0")


def _not_a_number(d):
    set_field(d / "timeseries.csv", 4, "omega", b"0x1p3q")


def _bad_phase(d):
    set_field(d / "timeseries.csv", 4, "phase", b"flying")


def _nan_event_time(d):
    set_field(d / "events.csv", 2, "t", b"nan")


def _bad_event_kind(d):
    set_field(d / "events.csv", 2, "kind", b"bounce")


def _binary_summary(d):
    with open(d / "summary.json", "wb") as f:
        f.write(b"\xff\xfe{}")


def _garbage_summary(d):
    with open(d / "summary.json", "w") as f:
        f.write("{\"complete\": tru")


def _array_summary(d):
    with open(d / "summary.json", "w") as f:
        f.write("[1, 2]")


def _no_case(d):
    os.remove(d / "case.resolved.toml")


def _bad_case(d):
    with open(d / "case.resolved.toml", "a") as f:
        f.write("\n[bogus]\nx = 1\n")


def _timeseries_is_a_folder(d):
    os.remove(d / "events.csv")
    os.mkdir(d / "events.csv")


GARBAGE = [
    ("binary", _binary, (rubdyn.ReadError, r"byte 0xff at column 1: not text", "timeseries.csv", 1)),
    ("binary row", _binary_row, (rubdyn.ReadError, r"byte 0x00 at column 5: not text",
                                 "timeseries.csv", "last")),
    ("control char", _control_char, (rubdyn.ReadError, r"byte 0x1b at column \d+: not text",
                                     "timeseries.csv", 5)),
    ("latin-1 note", _latin1, (rubdyn.ReadError, r"byte 0xe9 at column \d+: not text",
                               "events.csv", 2)),
    ("NUL in events", _nul_events, (rubdyn.ReadError, r"byte 0x00 at column 1", "events.csv",
                                    "last")),
    ("empty", _empty, (rubdyn.ReadError, r"empty file", "timeseries.csv", 1)),
    ("short row", _short_row, (rubdyn.ReadError, r"5 fields, the header has 21",
                               "timeseries.csv", 4)),
    ("long row", _long_row, (rubdyn.ReadError, r"22 fields, the header has 21",
                             "timeseries.csv", 4)),
    ("NaN time", _nan_time, (rubdyn.ReadError, r"'nan' is not a finite", "timeseries.csv", 4)),
    ("inf time", _inf_time, (rubdyn.ReadError, r"'inf' is not a finite", "timeseries.csv", 6)),
    ("time goes back", _back_in_time, (rubdyn.ReadError, r"t = 0 (goes back in time|decreases)",
                                       "timeseries.csv", 6)),
    ("not a number", _not_a_number, (rubdyn.ReadError, r"'0x1p3q' is not a number",
                                     "timeseries.csv", 4)),
    ("bad phase", _bad_phase, (rubdyn.ReadError, r"'flying' is not a phase", "timeseries.csv",
                               4)),
    ("NaN event time", _nan_event_time, (rubdyn.ReadError, r"'nan' is not a finite time",
                                         "events.csv", 2)),
    ("bad event kind", _bad_event_kind, (rubdyn.ReadError, r"'bounce' is not an event kind",
                                         "events.csv", 2)),
    ("binary summary", _binary_summary, (rubdyn.ReadError, r"byte 0xff at column 1: not text",
                                         "summary.json", 1)),
    ("garbage summary", _garbage_summary, (rubdyn.ReadError, r"not JSON", "summary.json", 1)),
    ("array summary", _array_summary, (rubdyn.ReadError, r"not a JSON object", "summary.json",
                                       1)),
    ("no case", _no_case, (rubdyn.ReadError, r"missing", "case.resolved.toml", 0)),
    ("bad case", _bad_case, (rubdyn.CaseError, r"bogus", "case.resolved.toml", None)),
    ("events is a folder", _timeseries_is_a_folder, (rubdyn.ReadError, r"cannot read",
                                                     "events.csv", 0)),
]


@pytest.fixture()
def damaged(small_out, tmp_path):
    def make(damage):
        d = tmp_path / "damaged"
        shutil.copytree(small_out, d)
        damage(d)
        return d
    return make


def _expected_line(d, file, line):
    if line == "last":  # the line the damage appended (the file ends with a line end)
        return len(lines_of(d / file)) - 1
    return line


@pytest.mark.parametrize("name, damage, outcome", GARBAGE, ids=[g[0] for g in GARBAGE])
def test_garbage_folder_read_and_analyze(damaged, name, damage, outcome):
    d = damaged(damage)
    exc, pattern, file, line = outcome
    for reader in (rubdyn.read, rubdyn.analyze):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            with pytest.raises(exc, match=pattern) as err:
                reader(d)
        path = str(d / file)
        assert str(err.value).startswith(path) or (exc is rubdyn.CaseError and
                                                   path in str(err.value)), str(err.value)
        if exc is rubdyn.ReadError:
            n = _expected_line(d, file, line)
            assert err.value.file == path and err.value.line == n
            assert str(err.value).startswith(f"{path}:{n}: " if n else f"{path}: ")
            assert str(err.value).isascii()


# `rubdyn compare` reads of a folder timeseries.csv (its numeric columns: phase is words, not
# compared) and events.csv (t and kind, as words): the other damages do not concern it.
NOT_READ_BY_COMPARE = {"bad phase", "bad event kind", "binary summary", "garbage summary",
                       "array summary", "no case", "bad case"}


@pytest.mark.parametrize("name, damage, outcome", GARBAGE, ids=[g[0] for g in GARBAGE])
def test_garbage_folder_compare(damaged, small_out, name, damage, outcome):
    d = damaged(damage)
    exc, pattern, file, line = outcome
    if name in NOT_READ_BY_COMPARE:
        c = rubdyn.compare(d, small_out)
        assert c["columns"]["omega"]["sup"] == 0.0  # the same samples: no difference
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(rubdyn.ReadError) as err:
            rubdyn.compare(d, small_out)
        with pytest.raises(rubdyn.ReadError) as err_mixed:  # a path beside a Result
            rubdyn.compare(rubdyn.read(small_out), d)
    path = str(d / file)
    for e in (err.value, err_mixed.value):
        assert e.file == path and str(e).startswith(path) and str(e).isascii(), str(e)
        assert e.line == _expected_line(d, file, line), str(e)


def test_header_only_and_cut_folders_read_with_what_they_hold(damaged, small_out):
    whole = rubdyn.read(small_out)
    # header only: a run killed before its first sample reads as no rows
    d = damaged(lambda d: write_lines(d / "timeseries.csv",
                                      lines_of(d / "timeseries.csv")[:1] + [b""]))
    res = rubdyn.read(d)
    assert len(res) == 0 and list(res.columns) == list(whole.columns)
    with pytest.raises(ValueError, match="has no samples"):
        rubdyn.analyze(res)
    with pytest.raises(rubdyn.ReadError, match="0 samples: compare needs at least two"):
        rubdyn.compare(d, small_out)
    shutil.rmtree(d)
    # a cut last row (no line end) and no summary: the rows before it, two warnings
    d = damaged(lambda d: (open(d / "timeseries.csv", "r+b").truncate(
        os.path.getsize(d / "timeseries.csv") - 25), os.remove(d / "summary.json")))
    with pytest.warns(RuntimeWarning) as rec:
        res = rubdyn.read(d)
    notes = [str(w.message) for w in rec]
    assert any(re.search(r"timeseries.csv:\d+: the last row has no line end", n) for n in notes)
    assert any("no summary.json" in n for n in notes)
    assert res.summary is None and len(res) == len(whole) - 1
    assert np.array_equal(res["omega"], whole["omega"][:-1])
    shutil.rmtree(d)
    # empty events.csv and empty summary.json: no events, an incomplete run, with warnings
    d = damaged(lambda d: (open(d / "events.csv", "w").close(),
                           open(d / "summary.json", "w").close()))
    with pytest.warns(RuntimeWarning, match="summary.json: empty"):
        res = rubdyn.read(d)
    assert len(res.events) == 0 and res.summary is None and len(res) == len(whole)


def test_crlf_folder_reads_the_same_numbers(damaged, small_out):
    def crlf(d):
        for name in ("timeseries.csv", "events.csv", "summary.json"):
            data = (d / name).read_bytes()
            (d / name).write_bytes(data.replace(b"\n", b"\r\n"))
    d = damaged(crlf)
    whole, res = rubdyn.read(small_out), rubdyn.read(d)
    assert list(res.columns) == list(whole.columns)
    for name in whole.columns:
        assert np.array_equal(res[name], whole[name]), name
    assert list(res.events["note"]) == list(whole.events["note"])  # no '\r' kept
    assert res.summary == whole.summary
    assert rubdyn.analyze(d).verdicts == rubdyn.analyze(small_out).verdicts
    assert rubdyn.compare(d, small_out)["columns"]["omega"]["sup"] == 0.0


# --- seeded mutations: read gives a Result whose times are finite and ordered, or a ReadError
# naming a file of the folder and a line ----------------------------------------------------------

def _mutate(data, rng):
    """One random damage of a file's bytes (the kinds a crash, a disk or an editor makes)."""
    kind = rng.randrange(8)
    if not data:
        return bytes([rng.randrange(256)])
    i = rng.randrange(len(data))
    if kind == 0:  # flip a byte
        return data[:i] + bytes([rng.randrange(256)]) + data[i + 1:]
    if kind == 1:  # cut the file
        return data[:i]
    if kind == 2:  # delete a span
        return data[:i] + data[i + rng.randrange(1, 40):]
    if kind == 3:  # insert a token that has broken parsers
        tok = rng.choice([b",", b"\n", b"\r\n", b"nan", b"-inf", b"1e999", b"\"", b"\x00",
                          b"\xc3", b"\xef\xbb\xbf", b"0x10", b"", b",,,", b"-0"])
        return data[:i] + tok + data[i:]
    if kind == 4:  # duplicate a span (a row written twice)
        j = min(len(data), i + rng.randrange(1, 200))
        return data[:j] + data[i:j] + data[j:]
    if kind == 5:  # swap two lines
        ls = data.split(b"\n")
        a, b = rng.randrange(len(ls)), rng.randrange(len(ls))
        ls[a], ls[b] = ls[b], ls[a]
        return b"\n".join(ls)
    if kind == 6:  # replace a field by random printable text
        return data[:i] + bytes(rng.randrange(33, 127) for _ in range(rng.randrange(1, 8))) + \
            data[i + 1:]
    return data + bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64)))  # junk tail


@pytest.mark.parametrize("file, seed", [("timeseries.csv", 22), ("events.csv", 23),
                                        ("summary.json", 24)])
def test_mutated_folders_read_or_raise_a_read_error(small_out, tmp_path, file, seed):
    rng = random.Random(seed)
    original = (small_out / file).read_bytes()
    outcomes = {"read": 0, "error": 0}
    for it in range(ITERATIONS):
        d = tmp_path / f"m{it}"
        shutil.copytree(small_out, d)
        data = original
        for _ in range(rng.randrange(1, 4)):
            data = _mutate(data, rng)
        (d / file).write_bytes(data)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                res = rubdyn.read(d)
        except rubdyn.ReadError as e:
            outcomes["error"] += 1
            assert e.file in {str(d / f) for f in os.listdir(d)}, (it, str(e))
            assert str(e).startswith(f"{e.file}:{e.line}: " if e.line else f"{e.file}: "), str(e)
            assert str(e).isascii()
        else:
            outcomes["read"] += 1
            t = res["t"]
            assert np.all(np.isfinite(t)) and np.all(np.diff(t) >= 0), it
            assert all(math.isfinite(x) for x in res.events["t"]), it
            assert res.summary is None or isinstance(res.summary, dict)
            if len(t) >= 2:  # what read accepts, analyze and compare take
                try:
                    rubdyn.analyze(res)
                except ValueError as e:  # only: the window has nothing to analyse
                    assert "does not overlap" in str(e), str(e)
                rubdyn.compare(res, res)
        shutil.rmtree(d)
    # both outcomes occur: the mutations reach the checks and leave some folders readable
    assert outcomes["error"] > 0 and (outcomes["read"] > 0 or file == "timeseries.csv"), outcomes


# --- bad arguments: every entry point, every kind of bad value -----------------------------------

NOT_NUMBERS = ["1e-8", b"1", [1e-8], (1,), {"x": 1}, None, 1j, True, object()]
NOT_FINITE = [math.nan, math.inf, -math.inf, np.float64("nan"), np.float32("inf")]


@pytest.mark.parametrize("option", ["rtol", "atol", "t_end"])
def test_run_numeric_options_fuzz(option):
    key = {"rtol": "solver.rtol", "atol": "solver.atol", "t_end": "run.t_end"}[option]
    for value in NOT_NUMBERS:
        if value is None:
            continue  # None means: the case's own value
        with pytest.raises(TypeError, match=f"run: {option} must be a number"):
            rubdyn.run(REFERENCE, **{option: value})
    for value in NOT_FINITE:
        with pytest.raises(rubdyn.CaseError, match=f"{re.escape(key)} = -?(nan|inf): must be a "
                                                   "finite number"):
            rubdyn.run(REFERENCE, **{option: value})
    with pytest.raises(rubdyn.CaseError, match=f"{re.escape(key)} = -1e\\+300"):
        rubdyn.run(REFERENCE, **{option: -1e300})
    with pytest.raises(rubdyn.CaseError, match=r"run.t_end = 1e\+300: the run would write"):
        rubdyn.run(REFERENCE, t_end=1e300)  # huge: refused before a row is written


def test_override_fuzz():
    rng = random.Random(2022)
    for _ in range(200):
        text = "".join(rng.choice("abc.=_ 0123456789\"'\\[]{}#") for _ in range(rng.randrange(12)))
        ctl = chr(rng.choice(list(range(0, 9)) + list(range(10, 32)) + [127]))
        i = rng.randrange(len(text) + 1)
        bad = text[:i] + ctl + text[i:]
        # a control character anywhere, in either form: ValueError naming the entry
        with pytest.raises(ValueError, match=r"overrides\[0\] = .*one line"):
            rubdyn.load_case(REFERENCE, overrides=[bad])
        with pytest.raises(ValueError, match=r"overrides\['contact.mu'\] = .*one line"):
            rubdyn.load_case(REFERENCE, overrides={"contact.mu": bad})
        # without it: a case or the loader's CaseError (never another exception)
        try:
            rubdyn.load_case(REFERENCE, overrides=[text])
        except rubdyn.CaseError as e:  # every issue names a key and states a rule
            assert e.issues and all(i["key"] and i["rule"] for i in e.issues), str(e)
        try:
            rubdyn.load_case(REFERENCE, overrides={"contact.mu": text})
        except rubdyn.CaseError as e:
            assert [i["key"] for i in e.issues] == ["contact.mu"], str(e)


def test_compare_array_fuzz():
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 1.0, 50)
    good = {"t": t, "omega": np.sin(t)}
    for it in range(150):
        n = int(rng.integers(0, 6)) if rng.random() < 0.2 else int(rng.integers(2, 60))
        ta = np.sort(rng.uniform(0.0, 1.0, n))
        omega = rng.normal(size=n)
        kind = it % 6
        if kind == 1 and n:
            ta[rng.integers(n)] = rng.choice([np.nan, np.inf, -np.inf])
        elif kind == 2 and n > 2:
            ta = ta[::-1].copy()
        elif kind == 3:
            omega = omega[:max(0, n - int(rng.integers(1, 3)))]
        elif kind == 4 and n:
            omega[rng.integers(n)] = np.nan  # a NaN value: a difference, not an error
        a = {"t": ta, "omega": omega}
        window = None
        if kind == 5:
            window = tuple(rng.choice([np.nan, np.inf, 0.2, 0.8, -1.0], 2))
        ok_t = n >= 2 and np.all(np.isfinite(ta)) and np.all(np.diff(ta) >= 0)
        ok_window = window is None or (all(map(math.isfinite, window)) and window[0] < window[1])
        if not ok_t or len(omega) != n or not ok_window:
            with pytest.raises(ValueError, match=r"compare: (a|window)") as err:
                rubdyn.compare(a, good, window=window)
            assert "compare: " in str(err.value)
            continue
        try:
            c = rubdyn.compare(a, good, window=window)
        except ValueError as e:  # the only refusal left: no common time in the window
            assert "share no time" in str(e), str(e)
            continue
        if kind == 4:
            assert c["columns"]["omega"]["non_finite"] >= 0  # counted when the NaN is inside
        assert c["points"] >= 1


def test_entry_points_refuse_wrong_types():
    case = rubdyn.load_case(REFERENCE)
    calls = [
        (lambda: rubdyn.load_case(3), TypeError, "load_case: path must be a path"),
        (lambda: rubdyn.load_case(None), TypeError, "load_case: path must be a path"),
        (lambda: rubdyn.parse_case(b"[run]"), TypeError, "parse_case: text must be a str"),
        (lambda: rubdyn.parse_case("", source=3), TypeError, "parse_case: source must be a str"),
        (lambda: rubdyn.run(3.5), TypeError, r"run: case \(a Case or a path\) must be a path"),
        (lambda: rubdyn.read(None), TypeError, "read: out_dir must be a path"),
        (lambda: rubdyn.read("/nonexistent/run"), FileNotFoundError, "no timeseries.csv"),
        (lambda: rubdyn.analyze(3), TypeError, "analyze: result must be a Result"),
        (lambda: rubdyn.compare(3, 4), TypeError, "compare: a must be a Result"),
        (lambda: rubdyn.compare("/nonexistent.csv", {"t": [0, 1]}), rubdyn.ReadError,
         "/nonexistent.csv: cannot read"),
        (lambda: rubdyn.campbell(case, points="201"), TypeError, "campbell: points must be an int"),
        (lambda: rubdyn.campbell(case, omega_max=math.inf), ValueError, "omega_max = inf"),
        (lambda: rubdyn.campbell(case, omega_max=1e300, points=True), TypeError, "points"),
        (lambda: rubdyn.load_case(REFERENCE, overrides={"contact.mu": 1e400}), rubdyn.CaseError,
         "contact.mu = inf"),
    ]
    for call, exc, match in calls:
        with pytest.raises(exc, match=match):
            call()


def test_binary_case_file_is_a_case_error(tmp_path):
    for i, data in enumerate([random.Random(5).randbytes(500), b"\xff\xfe[run]\n",
                              b"[run]\nt_end = 0.1\n\x00", b"name = \"\xe9\"\n"]):
        p = tmp_path / f"bin{i}.toml"
        p.write_bytes(data)
        with pytest.raises(rubdyn.CaseError) as err:
            rubdyn.load_case(p)
        assert str(p) in str(err.value)
