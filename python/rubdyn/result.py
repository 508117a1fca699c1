"""A run's output in numpy: the result of rubdyn.run and of rubdyn.read (an output folder)."""
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
    # with several contacts events.csv has a `contact` column (1-based) after the others
    fields = list(EVENT_FIELDS) + ([("contact", "i8")] if "contact" in columns else [])
    ev = np.zeros(n, dtype=fields)
    for name, _ in fields:
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
    def planes(self):
        """The number of contact planes (columns d_N_1 ... d_N_K with several, d_N with one)."""
        if "phase" in self.columns:
            return 1
        k = 0
        while f"phase_{k + 1}" in self.columns:
            k += 1
        return k

    def plane(self, k):
        """Contact plane k (1-based) as a Result with one plane's columns under the one-plane
        names: d_N, v_N, v_t, F_N, F_T, phase of plane k; x_r, y_r, vx_r, vy_r its rotor point and
        x_s, y_s, vx_s, vy_s its ring's centre (from the model: LagrangianModel::plane_motion,
        which interpolates the rotor between its coordinates for a [[plane]]); the events of
        that contact only; .plane_info its gap, radius and law. Every other column as in this
        Result. A one-plane Result's plane(1) has the same columns, the centres recomputed."""
        n = self.planes
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= k <= n:
            raise ValueError(f"plane {k!r}: this result has {n} contact plane(s), numbered 1..{n}")
        if self.case is None:
            raise ValueError("plane() needs the run's case (rubdyn.read found no "
                             "case.resolved.toml)")
        cols = dict(self.columns)
        if n > 1:
            for base in ("d_N", "v_N", "v_t", "F_N", "F_T", "phase"):
                cols[base] = self.columns[f"{base}_{k}"]
        numeric = {name: np.asarray(v, dtype=float) for name, v in self.columns.items()}
        cols.update(_core.plane_columns(self.case, numeric, int(k)))
        events = self.events
        if events is not None and n > 1 and "contact" in events.dtype.names:
            events = events[events["contact"] == k]
        view = Result(cols, events, self.summary, case=self.case, source=self.source)
        view.plane_index = int(k)
        view.plane_info = self.case.contacts[k - 1]
        return view

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


def read(out_dir):
    """Reads an output folder written by `rubdyn run` (timeseries.csv, events.csv, summary.json,
    case.resolved.toml) through the C++ reader the CLI uses (io/output_reader.hpp), so the columns
    are the model's column table and the numbers come back bit for bit.
    A run that died keeps its rows: a cut last row is dropped with a warning, a missing (or
    empty) summary.json gives summary None (with a warning). A folder without timeseries.csv is
    FileNotFoundError; a malformed file (not text, a short row, a field that is not a number, a
    time that is not finite or goes back, a summary.json that is not JSON) is rubdyn.ReadError,
    a ValueError whose message and .file, .line name the file and line."""
    if not isinstance(out_dir, (str, os.PathLike)):
        raise TypeError(f"read: out_dir must be a path (str or os.PathLike), not "
                        f"{type(out_dir).__name__}")
    out_dir = os.fsdecode(os.fspath(out_dir))
    if not os.path.exists(os.path.join(out_dir, "timeseries.csv")):
        raise FileNotFoundError(f"{out_dir}: no timeseries.csv (not a rubdyn output folder)")
    columns, events, summary_json, notes = _core.read_run(out_dir)
    for note in notes:
        warnings.warn(note, RuntimeWarning, stacklevel=2)
    summary_path = os.path.join(out_dir, "summary.json")
    summary = None
    if summary_json is not None:
        try:
            summary = json.loads(summary_json)
        except ValueError as e:
            raise _read_error(summary_path, getattr(e, "lineno", 0), f"not JSON: {e}") from None
        if not isinstance(summary, dict):
            raise _read_error(summary_path, 1, "not a JSON object")
    elif not os.path.exists(summary_path):  # (an empty one: the reader's warning above)
        warnings.warn(f"{out_dir}: no summary.json (the run did not finish)", RuntimeWarning,
                      stacklevel=2)
    case = _core.load_case(os.path.join(out_dir, "case.resolved.toml"), [])
    return Result(dict(columns), _events_array(events, len(events["t"])), summary, case=case,
                  source=out_dir)


def _read_error(file, line, problem):
    """rubdyn.ReadError as the C++ reader raises it: "file:line: problem", .file, .line."""
    err = _core.ReadError(f"{file}:{line}: {problem}" if line else f"{file}: {problem}")
    err.file, err.line = file, line
    return err
