"""Periodic orbits: rubdyn.orbit, the `rubdyn orbit` command in numpy (docs/orbits.md)."""
import json
import numbers

import numpy as np

from . import _core
from .result import Result


class Orbit(dict):
    """orbit.json of `rubdyn orbit` as a dict (outcome, converged, message, period, t0, section,
    newton, state, monodromy, multipliers, stability, stability_reason, events_per_period,
    phase_time, events, sequence, runs, wall_seconds), with numpy views of it:

        orb.multipliers   complex array, largest |.| first
        orb.errors        their error bounds
        orb.monodromy     the monodromy matrix in the section's coordinates
        orb.state         {coordinate or rate name: value} at t0
        orb.run           the sampled period as a Result (orbit.csv's columns, its events)
        orb.exit_code     what the CLI would exit with (0 converged, 3, 4)
    """

    def __init__(self, data, run, monodromy, exit_code):
        super().__init__(data)
        self.run = run
        self.monodromy = monodromy
        self.exit_code = exit_code

    @property
    def converged(self):
        return self["converged"]

    @property
    def stability(self):
        return self["stability"]

    @property
    def period(self):
        return self["period"]

    @property
    def state(self):
        return self["state"]

    @property
    def multipliers(self):
        return np.array([complex(m["re"], m["im"]) for m in self["multipliers"]], dtype=complex)

    @property
    def errors(self):
        return np.array([m["error"] for m in self["multipliers"]], dtype=float)

    def direction(self, k):
        """The k-th multiplier's eigenvector (0-based, largest |.| first) as {name: complex}."""
        return {name: complex(re, im)
                for name, (re, im) in self["multipliers"][k]["direction"].items()}

    def __repr__(self):
        return (f"Orbit({self['outcome']}, period {self['period']:.6g} s, {self['stability']}, "
                f"{len(self['multipliers'])} multipliers)")


def _count(value, name, least, who="orbit"):
    if not isinstance(value, numbers.Integral) or isinstance(value, bool):
        raise TypeError(f"{who}: {name} must be an int, not {type(value).__name__}")
    if value < least:
        raise ValueError(f"{who}: {name} = {value}: must be >= {least}")
    return int(value)


def _case_with(case, overrides, rtol, atol, who):
    """The Case (or the case file at a path) with the overrides and the runs' rtol, atol."""
    from . import Case, load_case, _path, _override_list, _real
    if not isinstance(case, Case):
        case = load_case(_path(case, f"{who}: case (a Case or a path)"))
    sets = _override_list(overrides)
    for name, key, value in (("rtol", "solver.rtol", rtol), ("atol", "solver.atol", atol)):
        if value is not None:
            sets.append(f"{key}={_real(value, f'{who}: {name}')!r}")
    return _core.with_overrides(case, sets) if sets else case


def orbit(case, periods=1, settle=0, tol=1e-8, max_iter=20, samples=200, rtol=None, atol=None,
          overrides=None, period=None, monodromy="differences"):
    """The case's forced orbit, as `rubdyn orbit CASE` finds it (the same C++ search and the same
    orbit.json), returned as an Orbit; nothing is written.

    case: a Case or a path. periods: k, the period is 2 pi k / omega0. period: a free spin's
    orbit (loads.spin = "torque", autonomous): the guess of its period [s]. settle: periods of a
    transient run before Newton. tol: Newton's tolerance (scaled by the gap and gap x omega0).
    rtol, atol: the runs' tolerances (overrides of solver.rtol, solver.atol). monodromy:
    "differences" (finite differences of the return map) or "sensitivities" (the flow's
    variational equations and saltation matrices), as --monodromy. A case without a
    prescribed constant spin raises rubdyn.CaseError, as the CLI exits 2; a search that does not
    converge returns an Orbit whose outcome says why (exit_code 3)."""
    from . import _finite
    case = _case_with(case, overrides, rtol, atol, "orbit")
    tol = _finite(tol, "orbit: tol")
    if not tol > 0:
        raise ValueError(f"orbit: tol = {tol}: must be > 0")
    if period is not None:
        period = _finite(period, "orbit: period")
    if monodromy not in ("differences", "sensitivities"):
        raise ValueError(f"orbit: monodromy = {monodromy!r}: must be \"differences\" or "
                         "\"sensitivities\"")
    text, columns, events, summary_json, monodromy, code = _core.orbit(
        case, _count(periods, "periods", 1), _count(settle, "settle", 0), tol,
        _count(max_iter, "max_iter", 1), _count(samples, "samples", 1),
        float("nan") if period is None else period, monodromy == "sensitivities")
    run = Result.from_core(columns, events, summary_json, case=case)
    return Orbit(json.loads(text), run, np.asarray(monodromy), code)


class Branch(dict):
    """branch.json of `rubdyn branch` as a dict (key, from, outcome, message, points, specials:
    kind, value, spread, between, how; runs, wall_seconds), with branch.csv as columns:

        br.table          {column: numpy array} (text columns, stability and events, as lists)
        br[br["key"]]     the varied key's values, one per point (also br.values)
        br.specials       the located folds, period doublings, Neimark-Sacker points, and the
                          events change (grazing or lift-off) that ends a smooth branch
        br.exit_code      what the CLI would exit with (0, 3, 4)
    """

    def __init__(self, data, table, exit_code, texts=None):
        super().__init__(data)
        self.table = table
        self.exit_code = exit_code
        # (branch.json, branch.csv, the resolved case): what branch(resume=, switch=) reads back
        self._texts = texts

    @property
    def values(self):
        return self.table[self["key"]]

    @property
    def specials(self):
        return self["specials"]

    def __repr__(self):
        return (f"Branch({self['key']} from {self['from']:.10g}: {self['points']} points, "
                f"{self['outcome']}, {len(self['specials'])} special points)")


_TEXT_COLUMNS = ("stability", "events")


def _branch_table(text):
    """branch.csv's text as {column: numpy array of floats, or a list for the text columns}."""
    import csv
    import io
    rows = list(csv.reader(io.StringIO(text)))
    header, body = rows[0], rows[1:]
    table = {}
    for i, name in enumerate(header):
        col = [r[i] for r in body]
        table[name] = (col if name in _TEXT_COLUMNS else
                       np.array([float(x) if x else np.nan for x in col], dtype=float))
    return table


def branch(case, vary, to=None, points=200, ds=0.5, ds_max=3.0, scale=None, down=False, tol=1e-8,
           max_iter=20, samples=200, rtol=None, atol=None, overrides=None, periods=1, period=None,
           monodromy="differences", resume=None, switch=None, special=None, switch_offset=None,
           switch_eps=0.05):
    """The case's forced orbit followed in the case key `vary` (e.g. "initial.omega0"), as
    `rubdyn branch CASE --vary KEY` follows it (the same C++ continuation, branch.json and
    branch.csv), returned as a Branch; nothing is written.

    to: stop beyond this value. points: points on the branch, the first included. ds, ds_max:
    the first and the largest arclength step. scale: the key's unit in the arclength (None: 1 %
    of its value). down: the first step decreases the key. tol, max_iter, samples, periods,
    period (a free spin's autonomous orbits: the first one's period guess [s]) and monodromy
    ("differences" or "sensitivities"): as orbit(). resume: a Branch of this call's case and
    settings, continued from its last point to `points` in all (returned as it is when it has
    ended or has its points), as --resume. switch: a Branch of this case with a period doubling:
    the branch of twice its period that leaves it (special: the doubling's index among its
    specials, None: the first; switch_offset: the first orbit's distance from it in the key,
    None: tried from half the distance of the points around it; switch_eps: the step along the
    multiplier -1's direction), as --switch. Bad input raises rubdyn.CaseError, as the CLI
    exits 2."""
    from . import _finite
    case = _case_with(case, overrides, rtol, atol, "branch")
    if not isinstance(vary, str):
        raise TypeError(f"branch: vary must be a case key (str), not {type(vary).__name__}")
    tol = _finite(tol, "branch: tol")
    if not tol > 0:
        raise ValueError(f"branch: tol = {tol}: must be > 0")
    if monodromy not in ("differences", "sensitivities"):
        raise ValueError(f"branch: monodromy = {monodromy!r}: must be \"differences\" or "
                         "\"sensitivities\"")
    if resume is not None and switch is not None:
        raise ValueError("branch: resume and switch: one or the other")
    earlier = resume if resume is not None else switch
    if earlier is not None and (not isinstance(earlier, Branch) or earlier._texts is None):
        raise TypeError("branch: resume and switch take a Branch that rubdyn.branch returned")
    if switch is None and (special is not None or switch_offset is not None):
        raise ValueError("branch: special and switch_offset need switch")
    text, csv_text, code, resolved = _core.branch(
        case, vary, float("nan") if to is None else _finite(to, "branch: to"),
        _count(points, "points", 1, "branch"), _finite(ds, "branch: ds"),
        _finite(ds_max, "branch: ds_max"), 0.0 if scale is None else _finite(scale, "branch: scale"),
        bool(down), tol, _count(max_iter, "max_iter", 1, "branch"),
        _count(samples, "samples", 1, "branch"), _count(periods, "periods", 1, "branch"),
        float("nan") if period is None else _finite(period, "branch: period"),
        monodromy == "sensitivities", None if earlier is None else earlier._texts,
        resume is not None, -1 if special is None else _count(special, "special", 0, "branch"),
        float("nan") if switch_offset is None else _finite(switch_offset, "branch: switch_offset"),
        _finite(switch_eps, "branch: switch_eps"))
    return Branch(json.loads(text), _branch_table(csv_text), code, (text, csv_text, resolved))
