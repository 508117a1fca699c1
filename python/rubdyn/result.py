"""A run's output in numpy: the result of rubdyn.run and of rubdyn.read (an output folder)."""
import csv
import io
import json
import os
import warnings

import numpy as np

# Phase codes of the `phase` column (rubdyn::Phase), in order; the CSV writes the words.
PHASES = ("free", "slip+", "slip-", "stick")

from . import _core

#: events.csv's columns (the C++ column table, io/columns.hpp) and their numpy types (kinds and
#: phases are words, as in the CSV).
_EVENT_TEXT = {"kind": "U10", "phase_before": "U6", "phase_after": "U6", "witness": "O",
               "note": "O"}
EVENT_FIELDS = tuple((name, _EVENT_TEXT.get(name, "f8")) for name in _core.event_fields())


def _events_array(columns, n):
    ev = np.zeros(n, dtype=list(EVENT_FIELDS))
    for name, _ in EVENT_FIELDS:
        ev[name] = columns[name] if n else []
    return ev


class Result:
    """Samples by column name (timeseries.csv's names: t, x_b, ..., omega, ..., d_N, v_N, v_t,
    F_N, F_T, phase; phase as codes into PHASES), the events as a structured array (events.csv's
    columns) and the summary as a dict (summary.json's keys).

        res["omega"], res.t, res.columns.keys(), res.events["kind"], res.summary["complete"]
    """

    def __init__(self, columns, events, summary, case=None, source=None):
        self.columns = columns
        self.events = events
        self.summary = summary
        self.case = case
        self.source = source

    @classmethod
    def from_core(cls, columns, events, summary_json, case=None):
        n = len(events["t"])
        return cls(dict(columns), _events_array(events, n), json.loads(summary_json), case=case,
                   source=case.source if case is not None else None)

    def __getitem__(self, name):
        return self.columns[name]

    def __contains__(self, name):
        return name in self.columns

    def __getattr__(self, name):
        columns = self.__dict__.get("columns")
        if columns is not None and name in columns:
            return columns[name]
        raise AttributeError(name)

    def __len__(self):
        return len(self.columns["t"])

    def keys(self):
        return self.columns.keys()

    @property
    def phase_names(self):
        """The phase column as words (free, slip+, slip-, stick)."""
        return np.asarray(PHASES, dtype=object)[self.columns["phase"]]

    def to_pandas(self):
        """(samples, events) as pandas DataFrames (pandas is optional: ImportError without it).
        The samples' phase is a categorical of the words."""
        import pandas as pd
        df = pd.DataFrame({k: v for k, v in self.columns.items() if k != "phase"})
        df["phase"] = pd.Categorical.from_codes(self.columns["phase"], categories=list(PHASES))
        return df, pd.DataFrame(self.events)

    def __repr__(self):
        s = self.summary or {}
        return (f"<rubdyn.Result {len(self)} samples, {len(self.events)} events, "
                f"t_reached {s.get('t_reached')}, {s.get('termination')}>")


def _read_timeseries(path):
    """timeseries.csv -> dict of arrays. A last row cut by a run that died is dropped (warning).
    numpy's C text parser reads the numbers (the written doubles come back bit for bit: tested
    against rubdyn.run); the phase words become codes first."""
    with open(path, newline="") as f:
        header = f.readline().rstrip("\n").split(",")
        body = f.read()
    ncol = len(header)
    if body and not body.endswith("\n"):
        warnings.warn(f"{path}: the last row is incomplete (a run that ended abruptly): dropped",
                      RuntimeWarning, stacklevel=3)
        body = body[:body.rfind("\n") + 1]
    if "phase" in header:
        if header[-1] != "phase":
            raise ValueError(f"{path}: phase is expected as the last column")
        for code, word in enumerate(PHASES):
            body = body.replace(f",{word}\n", f",{code}\n")
    if not body:
        return {name: np.zeros(0, dtype=np.int8 if name == "phase" else float) for name in header}
    nrow = body.count("\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # text it cannot read: an error
        flat = np.fromstring(body.rstrip("\n").replace("\n", ","), dtype=float, sep=",")
    if flat.size != nrow * ncol:
        raise ValueError(f"{path}: {flat.size} numbers read, {nrow} rows x {ncol} columns "
                         "expected (a row with a wrong number of fields or a bad number)")
    data = flat.reshape(nrow, ncol)
    cols = {name: np.ascontiguousarray(data[:, j]) for j, name in enumerate(header)}
    if "phase" in cols:
        cols["phase"] = cols["phase"].astype(np.int8)
    return cols


def _read_events(path):
    """events.csv -> structured array (header-only file: an empty array)."""
    if not os.path.exists(path):
        return _events_array({}, 0)
    with open(path, newline="") as f:
        text = f.read()
    if text and not text.endswith("\n"):
        warnings.warn(f"{path}: the last row is incomplete: dropped", RuntimeWarning,
                      stacklevel=3)
        text = text[:text.rfind("\n") + 1]
    reader = csv.reader(io.StringIO(text))
    header = next(reader, None)
    rows = [r for r in reader if r]
    if header is None:
        return _events_array({}, 0)
    idx = {name: i for i, name in enumerate(header)}
    columns = {}
    for name, kind in EVENT_FIELDS:
        if name not in idx:
            columns[name] = [np.nan if kind == "f8" else ""] * len(rows)
            continue
        j = idx[name]
        if kind == "f8":
            columns[name] = [float(r[j]) if r[j] != "" else np.nan for r in rows]
        else:
            columns[name] = [r[j] for r in rows]
    return _events_array(columns, len(rows))


def read(out_dir):
    """Reads an output folder written by `rubdyn run` (timeseries.csv, events.csv, summary.json;
    .case from case.resolved.toml, None without it).
    A run that died keeps its rows: a cut last row is dropped with a warning, a missing
    summary.json gives summary None (with a warning)."""
    out_dir = os.fspath(out_dir)
    ts = os.path.join(out_dir, "timeseries.csv")
    if not os.path.exists(ts):
        raise FileNotFoundError(f"{out_dir}: no timeseries.csv (not a rubdyn output folder)")
    columns = _read_timeseries(ts)
    events = _read_events(os.path.join(out_dir, "events.csv"))
    summary = None
    sj = os.path.join(out_dir, "summary.json")
    if os.path.exists(sj):
        with open(sj) as f:
            summary = json.load(f)
    else:
        warnings.warn(f"{out_dir}: no summary.json (the run did not finish)", RuntimeWarning,
                      stacklevel=2)
    case = None
    resolved = os.path.join(out_dir, "case.resolved.toml")
    if os.path.exists(resolved):
        try:
            case = _core.load_case(resolved, [])
        except _core.CaseError as err:  # written by another version of rubdyn
            warnings.warn(f"{resolved}: not loaded ({err})", RuntimeWarning, stacklevel=2)
    return Result(columns, events, summary, case=case, source=out_dir)
