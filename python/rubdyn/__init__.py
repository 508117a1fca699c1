"""rubdyn from Python: reference solutions of rotor-stator rub.

    import rubdyn
    case = rubdyn.load_case("cases/reference.toml", overrides={"contact.mu": 0.25})
    res = rubdyn.run(case, t_end=0.1)          # the CLI's numbers, in numpy arrays
    res["omega"], res.events["kind"], res.summary["termination"]
    old = rubdyn.read("out/reference")          # an output folder written by `rubdyn run`
    print(rubdyn.compare(old, res).report)      # the measures of `rubdyn compare`

See python/README.md.
"""
import math
import numbers
import os
import re
from collections.abc import Mapping

from . import _core
from ._core import Case, Model, CaseError, ReadError
from .result import Result, read, PHASES, EVENT_FIELDS
from .orbits import Branch, Orbit, branch, orbit

__all__ = ["load_case", "parse_case", "run", "read", "analyze", "campbell", "compare", "solvers",
           "Case", "Model", "CaseError", "ReadError", "Result", "Comparison", "Analysis",
           "PHASES", "EVENT_FIELDS", "orbit", "Orbit", "branch", "Branch"]

# Arguments are checked here as strictly as the CLI checks its options: a wrong type is a
# TypeError, a wrong value a ValueError, each naming the argument (the case's own rules stay the
# C++ loader's: rubdyn.CaseError, as `rubdyn check` words them).

_KEY = re.compile(r"[A-Za-z0-9_]+\.[A-Za-z0-9_.]+\Z")  # section.key, as the case files spell them
_WORD = re.compile(r"[A-Za-z0-9_.+-]+\Z")  # a solver or method name: one bare word
_CONTROL = re.compile(r"[\x00-\x08\x0a-\x1f\x7f]")  # a line end or another control character


def _is_real(x):
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _real(x, what):
    """x as a float (int, float or numpy scalar; not bool), else TypeError naming `what`."""
    if not _is_real(x):
        raise TypeError(f"{what} must be a number, not {type(x).__name__}")
    return float(x)


def _finite(x, what):
    x = _real(x, what)
    if not math.isfinite(x):
        raise ValueError(f"{what} = {x}: must be finite")
    return x


def _path(x, what):
    if not isinstance(x, (str, os.PathLike)):
        raise TypeError(f"{what} must be a path (str or os.PathLike), not {type(x).__name__}")
    p = os.fspath(x)
    return os.fsdecode(p) if isinstance(p, bytes) else p


def _one_line(text, what):
    if _CONTROL.search(text):
        raise ValueError(f"{what} = {text!r}: must be one line without control characters")
    return text


def _window(window, what):
    """None or (t0, t1): two finite numbers with t0 < t1."""
    if window is None:
        return None
    if isinstance(window, (str, bytes)) or not hasattr(window, "__len__") or len(window) != 2:
        raise TypeError(f"{what} must be two times (t0, t1), not {window!r}")
    t0 = _finite(window[0], f"{what}[0]")
    t1 = _finite(window[1], f"{what}[1]")
    if not t0 < t1:
        raise ValueError(f"{what} = ({t0}, {t1}): t0 must be < t1")
    return t0, t1


def _override_text(value, what):
    """A Python value as the TOML text of an override: bool, integer, real or one-line string."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        # the shortest repr reads back to the same double; nan and inf are refused by the case's
        # rules (CaseError "must be a finite number", as `rubdyn check --set` says)
        return repr(float(value))
    if isinstance(value, str):
        _one_line(value, what)
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise TypeError(f"{what} must be a bool, int, float or str, not {type(value).__name__}")


def _override_list(overrides, what="overrides"):
    """{"contact.mu": 0.25} or ["contact.mu=0.25"] -> ["contact.mu=0.25"] (values as TOML)."""
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        out = []
        for key, value in overrides.items():
            if not isinstance(key, str):
                raise TypeError(f"{what}: key {key!r} must be a str 'section.key'")
            if not _KEY.match(key):
                raise ValueError(f"{what}: key {key!r} must read section.key (letters, digits, "
                                 "'_' and '.')")
            out.append(f"{key}={_override_text(value, f'{what}[{key!r}]')}")
        return out
    if isinstance(overrides, (str, bytes)) or not isinstance(overrides, (list, tuple)):
        raise TypeError(f"{what} must be a dict {{'section.key': value}} or a list of "
                        f"'section.key=value' strings, not {type(overrides).__name__}")
    out = []
    for i, o in enumerate(overrides):
        if not isinstance(o, str):
            raise TypeError(f"{what}[{i}] must be a str 'section.key=value', not "
                            f"{type(o).__name__}")
        out.append(_one_line(o, f"{what}[{i}]"))
    return out


def load_case(path, overrides=None):
    """Reads, overrides and validates a case file. overrides: {"section.key": value} or a list of
    "section.key=value" (the CLI's --set). Raises rubdyn.CaseError (a ValueError) listing every
    problem as the CLI does (file:line: key = value: rule); its .issues holds them as dicts."""
    return _core.load_case(_path(path, "load_case: path"), _override_list(overrides))


def parse_case(text, source="<string>", overrides=None):
    """The same from TOML text; `source` names it in messages."""
    if not isinstance(text, str):
        raise TypeError(f"parse_case: text must be a str, not {type(text).__name__}")
    if not isinstance(source, str):
        raise TypeError(f"parse_case: source must be a str, not {type(source).__name__}")
    return _core.parse_case(text, source, _override_list(overrides))


def run(case, solver=None, rtol=None, atol=None, h=None, t_end=None, method=None,
        output_every=None, overrides=None, progress=None, progress_interval=0.1):
    """Runs a case as `rubdyn run` does and returns a Result (arrays in memory, nothing written).

    case: a Case, or a path to a case file. Solver options become the CLI's overrides
    (solver.kind, solver.method, solver.rtol, solver.atol, solver.h, run.t_end, output.every),
    validated like the file. progress(t, events, omega, phase) is called from the running thread
    at most every progress_interval seconds of wall time. The GIL is released during the run, so
    that several cases can run on threads."""
    if not isinstance(case, Case):
        case = load_case(_path(case, "run: case (a Case or a path)"))
    sets = _override_list(overrides)
    for name, key, value in (("solver", "solver.kind", solver), ("method", "solver.method", method),
                             ("rtol", "solver.rtol", rtol), ("atol", "solver.atol", atol),
                             ("h", "solver.h", h), ("t_end", "run.t_end", t_end),
                             ("output_every", "output.every", output_every)):
        if value is None:
            continue
        if key in ("solver.kind", "solver.method"):
            # as cmd_run.cpp writes them: "solver.kind=" + text, a bare word read as a string
            if not isinstance(value, str):
                raise TypeError(f"run: {name} must be a str, not {type(value).__name__}")
            if not _WORD.match(value):
                raise ValueError(f"run: {name} = {value!r}: must be one word (a name from "
                                 "rubdyn.solvers())")
            sets.append(f"{key}={value}")
        elif key == "output.every":
            if not isinstance(value, numbers.Integral) or isinstance(value, bool):
                raise TypeError(f"run: output_every must be an int, not {type(value).__name__}")
            sets.append(f"{key}={int(value)}")
        else:
            # a float's repr is its shortest round-trip text, so it reads back to the same
            # double; nan and inf are refused by the case's rules (CaseError)
            sets.append(f"{key}={_real(value, f'run: {name}')!r}")
    if progress is not None and not callable(progress):
        raise TypeError(f"run: progress must be callable or None, not {type(progress).__name__}")
    progress_interval = _finite(progress_interval, "run: progress_interval")
    if progress_interval < 0:
        raise ValueError(f"run: progress_interval = {progress_interval}: must be >= 0 [s]")
    if sets:
        case = _core.with_overrides(case, sets)
    # an option the chosen solver does not read is refused, as `rubdyn run` refuses it (the
    # solver registry says which keys each solver reads)
    entry = next(e for e in _core.solvers() if e["name"] == case.solver)
    for key, value in (("solver.rtol", rtol), ("solver.atol", atol), ("solver.method", method),
                       ("solver.h", h), ("output.every", output_every)):
        reads = entry["fixed_step"] if key == "output.every" else key in entry["keys"]
        if value is not None and not reads:
            users = [e["name"] for e in _core.solvers()
                     if (e["fixed_step"] if key == "output.every" else key in e["keys"])]
            raise ValueError(f"solver {case.solver} does not read {key} "
                             f"(it applies to: {', '.join(users)})")
    columns, events, summary_json = _core.run(case, progress, progress_interval)
    return Result.from_core(columns, events, summary_json, case=case)


def solvers():
    """The solver registry: a list of dicts name, summary, fixed_step, keys (the [solver] keys
    the solver reads), as the case file and the CLI know them."""
    return _core.solvers()


def campbell(case, omega_max=None, points=201, damped=False):
    """Campbell diagram of the coupled system (rubdyn campbell): dict of numpy arrays omega [rad/s],
    f1b, f1f, f2b, f2f [Hz] (zeta_* when damped), labels_ok, csv (campbell.csv's text) and tied
    (False: the free modes, drawn where no tied system exists, e.g. a fixed ring)."""
    if not isinstance(case, Case):
        case = load_case(_path(case, "campbell: case (a Case or a path)"))
    if omega_max is not None:
        omega_max = _finite(omega_max, "campbell: omega_max")
        if not omega_max > 0:
            raise ValueError(f"campbell: omega_max = {omega_max}: must be > 0 [rad/s]")
    if not isinstance(points, numbers.Integral) or isinstance(points, bool):
        raise TypeError(f"campbell: points must be an int, not {type(points).__name__}")
    if not 2 <= points <= _CAMPBELL_MAX_POINTS:  # rubdyn campbell --points' range
        raise ValueError(f"campbell: points = {points}: must lie in [2, {_CAMPBELL_MAX_POINTS}]")
    return _core.campbell(case, omega_max, int(points), bool(damped))


_CAMPBELL_MAX_POINTS = 100000  # as src/app/cmd_campbell.cpp (kMaxPoints)


class Comparison(dict):
    """comparison_json of `rubdyn compare` as a dict (t0, t1, points, columns{name: sup, rms,
    t_sup}, missing_columns, matched_events, max_event_shift, unmatched_a, unmatched_b), and
    .report, the CLI's text."""

    def __init__(self, data, report):
        super().__init__(data)
        self.report = report

    def __str__(self):
        return self.report


_STANDARD_COLUMNS = ("omega", "x_r", "y_r", "x_s", "y_s", "d_N")  # compared by compare.cpp


def _as_series(x, name):
    """(name, t, names, values, events) from a path (read by the C++ reader of `rubdyn
    compare`), a Result, a mapping of arrays or a structured array. Lengths, times and NaN are
    checked by compare_solutions (C++), which names `name`."""
    import warnings
    import numpy as np
    if isinstance(x, (str, os.PathLike)):
        path = _path(x, name)
        t, names, values, events, notes = _core.read_solution(path)
        for note in notes:
            warnings.warn(note, RuntimeWarning, stacklevel=3)
        return path, t, names, values, events
    events = []
    if isinstance(x, Result):
        cols = x.columns
        if x.events is not None and len(x.events):
            events = [(float(t), str(k)) for t, k in zip(x.events["t"], x.events["kind"])]
    elif isinstance(x, Mapping):
        cols = x
    elif isinstance(x, np.ndarray) and x.dtype.names:
        cols = {n: x[n] for n in x.dtype.names}
    else:
        raise TypeError(f"compare: {name} must be a Result, an output folder, a CSV file, a "
                        f"mapping of arrays with 't' or a structured array, not "
                        f"{type(x).__name__}")
    if "t" not in cols:
        raise ValueError(f"compare: {name} has no column 't'")
    t = np.asarray(cols["t"])
    if t.dtype.kind not in "fiu" or t.ndim != 1:
        raise ValueError(f"compare: {name}['t'] must be a one-dimensional array of numbers "
                         f"(dtype {t.dtype}, shape {t.shape})")
    names, values = [], []
    for key in cols.keys():
        if key in ("t", "phase", "events"):
            continue
        v = np.asarray(cols[key])
        if v.dtype.kind not in "fiu" or v.ndim == 0:
            if key in _STANDARD_COLUMNS:
                raise TypeError(f"compare: {name}[{key!r}] must be an array of numbers (dtype "
                                f"{v.dtype}, shape {v.shape})")
            continue  # words (or a scalar) are not a series to compare
        if v.shape != t.shape:
            raise ValueError(f"compare: {name}[{key!r}] has shape {v.shape}, {name}['t'] "
                             f"{t.shape}")
        names.append(str(key))
        values.append(v.astype(float))
    return name, t.astype(float), names, values, events


class Analysis:
    """What `rubdyn analyze` finds in a run. .verdicts: analysis.json's keys (limited,
    t_omega_lim, backward_onset, whip_onset, sign_backward_onset, permanent_contact_onset, the
    fractions, ...); .derived: derived.csv's columns (precession, whirl and regime as words,
    sustained and sign_run as 0/1, ...). Definitions: include/rubdyn/analysis/postprocess.hpp."""

    def __init__(self, verdicts, derived):
        self.verdicts = verdicts
        self.derived = derived

    def __getitem__(self, key):
        return self.verdicts[key]

    def __repr__(self):
        v = self.verdicts
        return (f"<rubdyn.Analysis limited={v['limited']} backward_onset={v['backward_onset']} "
                f"whip_onset={v['whip_onset']}>")


def analyze(result, min_turns=1.0, t_window=None, plane=1):
    """`rubdyn analyze` on a Result (of rubdyn.run, or rubdyn.read of an output folder, which
    needs its case.resolved.toml) or on an output folder's path: the same verdicts and derived
    quantities as the CLI's analysis.json and derived.csv (one C++ definition), computed in
    memory, nothing written. min_turns: orbit revolutions for a sustained whirl; t_window:
    (t0, t1) to analyse a part of the run; plane: the contact plane analysed (1-based; with
    several planes the CLI writes plane k's files in analysis/plane_k/). Returns an Analysis."""
    import json
    import numpy as np
    if isinstance(result, (str, os.PathLike)):
        result = read(result)
    if not isinstance(result, Result):
        raise TypeError(f"analyze: result must be a Result or an output folder, not "
                        f"{type(result).__name__}")
    if result.case is None:
        raise ValueError("analyze needs the run's case (rubdyn.read found no case.resolved.toml)")
    min_turns = _real(min_turns, "analyze: min_turns")  # its rule: the CLI's (--min-turns)
    t0, t1 = _window(t_window, "analyze: t_window") or (None, None)
    columns = {}
    for k, v in result.columns.items():
        a = np.asarray(v)
        if a.dtype.kind not in "fiub":
            raise TypeError(f"analyze: column {k!r} must be numbers (dtype {a.dtype})")
        columns[k] = a.astype(float)
    n_events = 0 if result.events is None else len(result.events)
    if "t" in columns and len(columns["t"]) == 0:
        raise ValueError(f"analyze: result ({result.source}) has no samples")
    if isinstance(plane, bool) or not isinstance(plane, (int, np.integer)):
        raise TypeError(f"analyze: plane must be an integer (1-based), not {plane!r}")
    text, derived = _core.analyze(result.case, columns, n_events, min_turns, t0, t1,
                                  "analyze: result", int(plane))
    for key in ("sustained", "sign_run"):
        derived[key] = derived[key].astype(bool)
    return Analysis(json.loads(text), derived)


def compare(a, b, window=None, event_tol=1e-3, name_a=None, name_b=None):
    """`rubdyn compare` on two solutions, each a Result, an output folder or CSV file (path), or a
    mapping of arrays with 't' (plus any of omega, x_r, y_r, x_s, y_s, d_N) and an optional
    'events' entry ignored. The measures are the C++ ones (one definition). Returns a Comparison."""
    import json
    window = _window(window, "compare: window")
    event_tol = _finite(event_tol, "compare: event_tol")
    if not event_tol > 0:
        raise ValueError(f"compare: event_tol = {event_tol}: must be > 0 [s]")
    for n, v in (("name_a", name_a), ("name_b", name_b)):
        if v is not None and not isinstance(v, str):
            raise TypeError(f"compare: {n} must be a str, not {type(v).__name__}")
    sa = _as_series(a, name_a or "a")
    sb = _as_series(b, name_b or "b")
    text, report = _core.compare_series(*sa, *sb, window, event_tol)
    return Comparison(json.loads(text), report)
