"""rubdyn from Python: reference solutions of rotor-stator rub.

    import rubdyn
    case = rubdyn.load_case("cases/reference.toml", overrides={"contact.mu": 0.25})
    res = rubdyn.run(case, t_end=0.1)          # the CLI's numbers, in numpy arrays
    res["omega"], res.events["kind"], res.summary["termination"]
    old = rubdyn.read("out/reference")          # an output folder written by `rubdyn run`
    print(rubdyn.compare(old, res).report)      # the measures of `rubdyn compare`

See python/README.md.
"""
import os

from . import _core
from ._core import Case, Model, CaseError
from .result import Result, read, PHASES, EVENT_FIELDS

__all__ = ["load_case", "parse_case", "run", "read", "analyze", "campbell", "compare", "solvers",
           "Case", "Model", "CaseError", "Result", "Comparison", "Analysis", "PHASES",
           "EVENT_FIELDS"]


def _override_list(overrides):
    """{"contact.mu": 0.25} or ["contact.mu=0.25"] -> ["contact.mu=0.25"] (values as TOML)."""
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        out = []
        for key, value in overrides.items():
            if isinstance(value, bool):
                text = "true" if value else "false"
            elif isinstance(value, str):
                text = '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
            else:
                text = repr(value)  # shortest repr: reads back to the same double
            out.append(f"{key}={text}")
        return out
    return [str(o) for o in overrides]


def load_case(path, overrides=None):
    """Reads, overrides and validates a case file. overrides: {"section.key": value} or a list of
    "section.key=value" (the CLI's --set). Raises rubdyn.CaseError (a ValueError) listing every
    problem as the CLI does (file:line: key = value: rule); its .issues holds them as dicts."""
    return _core.load_case(os.fspath(path), _override_list(overrides))


def parse_case(text, source="<string>", overrides=None):
    """The same from TOML text; `source` names it in messages."""
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
        case = load_case(case)
    sets = _override_list(overrides)
    for key, value in (("solver.kind", solver), ("solver.method", method),
                       ("solver.rtol", rtol), ("solver.atol", atol), ("solver.h", h),
                       ("run.t_end", t_end), ("output.every", output_every)):
        if value is None:
            continue
        # as cmd_run.cpp writes them: "solver.kind=" + text (a bare word is read as a string);
        # a float's repr is its shortest round-trip text, so it reads back to the same double
        sets.append(f"{key}={value}" if isinstance(value, str) else f"{key}={value!r}")
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
    columns, events, summary_json = _core.run(case, progress, float(progress_interval))
    return Result.from_core(columns, events, summary_json, case=case)


def solvers():
    """The solver registry: a list of dicts name, summary, fixed_step, keys (the [solver] keys
    the solver reads), as the case file and the CLI know them."""
    return _core.solvers()


def campbell(case, omega_max=None, points=201, damped=False):
    """Campbell diagram of the coupled system (rubdyn campbell): dict of numpy arrays omega [rad/s],
    f1b, f1f, f2b, f2f [Hz] (zeta_* when damped), labels_ok, and csv (campbell.csv's text)."""
    if not isinstance(case, Case):
        case = load_case(case)
    return _core.campbell(case, omega_max, int(points), bool(damped))


class Comparison(dict):
    """comparison_json of `rubdyn compare` as a dict (t0, t1, points, columns{name: sup, rms,
    t_sup}, missing_columns, matched_events, max_event_shift, unmatched_a, unmatched_b), and
    .report, the CLI's text."""

    def __init__(self, data, report):
        super().__init__(data)
        self.report = report

    def __str__(self):
        return self.report


def _as_series(x, name):
    """(name, t, names, values, events) from a Result, a mapping of arrays or an array."""
    import numpy as np
    events = []
    if isinstance(x, Result):
        cols = x.columns
        if x.events is not None and len(x.events):
            events = [(float(t), str(k)) for t, k in zip(x.events["t"], x.events["kind"])]
    elif hasattr(x, "keys"):
        cols = x
    else:
        arr = np.asarray(x, dtype=float)
        if arr.dtype.names:
            cols = {n: arr[n] for n in arr.dtype.names}
        else:
            raise TypeError("compare: give a Result, an output folder, a CSV file, a mapping of "
                            "arrays with 't' or a structured array")
    if "t" not in cols:
        raise ValueError(f"compare: {name} has no column 't'")
    t = np.asarray(cols["t"], dtype=float)
    names, values = [], []
    for key in cols.keys():
        if key == "t" or key == "phase":
            continue
        v = np.asarray(cols[key])
        if v.dtype.kind not in "fiu" or v.shape != t.shape:
            continue
        names.append(str(key))
        values.append(v.astype(float))
    return name, t, names, values, events


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


def analyze(result, min_turns=1.0, t_window=None):
    """`rubdyn analyze` on a Result (of rubdyn.run, or rubdyn.read of an output folder, which
    needs its case.resolved.toml) or on an output folder's path: the same verdicts and derived
    quantities as the CLI's analysis.json and derived.csv (one C++ definition), computed in
    memory, nothing written. min_turns: orbit revolutions for a sustained whirl; t_window:
    (t0, t1) to analyse a part of the run. Returns an Analysis."""
    import json
    import numpy as np
    if isinstance(result, (str, os.PathLike)):
        result = read(result)
    if result.case is None:
        raise ValueError("analyze needs the run's case (rubdyn.read found no case.resolved.toml)")
    t0, t1 = (None, None) if t_window is None else (float(t_window[0]), float(t_window[1]))
    columns = {k: np.asarray(v, dtype=float) for k, v in result.columns.items()}
    text, derived = _core.analyze(result.case, columns, len(result.events), float(min_turns),
                                  t0, t1)
    for key in ("sustained", "sign_run"):
        derived[key] = derived[key].astype(bool)
    return Analysis(json.loads(text), derived)


def compare(a, b, window=None, event_tol=1e-3, name_a=None, name_b=None):
    """`rubdyn compare` on two solutions, each a Result, an output folder or CSV file (path), or a
    mapping of arrays with 't' (plus any of omega, x_r, y_r, x_s, y_s, d_N) and an optional
    'events' entry ignored. The measures are the C++ ones (one definition). Returns a Comparison."""
    import json
    window = None if window is None else (float(window[0]), float(window[1]))
    if isinstance(a, (str, os.PathLike)) and isinstance(b, (str, os.PathLike)):
        text, report = _core.compare_paths(os.fspath(a), os.fspath(b), window, float(event_tol))
        return Comparison(json.loads(text), report)
    sa = _load_for_compare(a, name_a or "a")
    sb = _load_for_compare(b, name_b or "b")
    text, report = _core.compare_series(*sa, *sb, window, float(event_tol))
    return Comparison(json.loads(text), report)


def _load_for_compare(x, name):
    if isinstance(x, (str, os.PathLike)):
        p = os.fspath(x)
        x = read(p) if os.path.isdir(p) else _read_plain_csv(p)
        name = p
    return _as_series(x, name)


def _read_plain_csv(path):
    import numpy as np
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=float)
    return {n: np.atleast_1d(data[n]) for n in data.dtype.names}
