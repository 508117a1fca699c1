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


def _count(value, name, least):
    if not isinstance(value, numbers.Integral) or isinstance(value, bool):
        raise TypeError(f"orbit: {name} must be an int, not {type(value).__name__}")
    if value < least:
        raise ValueError(f"orbit: {name} = {value}: must be >= {least}")
    return int(value)


def orbit(case, periods=1, settle=0, tol=1e-8, max_iter=20, samples=200, rtol=None, atol=None,
          overrides=None, period=None):
    """The case's forced orbit, as `rubdyn orbit CASE` finds it (the same C++ search and the same
    orbit.json), returned as an Orbit; nothing is written.

    case: a Case or a path. periods: k, the period is 2 pi k / omega0. period: a free spin's
    orbit (loads.spin = "torque", autonomous): the guess of its period [s]. settle: periods of a
    transient run before Newton. tol: Newton's tolerance (scaled by the gap and gap x omega0).
    rtol, atol: the runs' tolerances (overrides of solver.rtol, solver.atol). A case without a
    prescribed constant spin raises rubdyn.CaseError, as the CLI exits 2; a search that does not
    converge returns an Orbit whose outcome says why (exit_code 3)."""
    from . import Case, load_case, _path, _override_list, _finite, _real
    if not isinstance(case, Case):
        case = load_case(_path(case, "orbit: case (a Case or a path)"))
    sets = _override_list(overrides)
    for name, key, value in (("rtol", "solver.rtol", rtol), ("atol", "solver.atol", atol)):
        if value is not None:
            sets.append(f"{key}={_real(value, f'orbit: {name}')!r}")
    if sets:
        case = _core.with_overrides(case, sets)
    tol = _finite(tol, "orbit: tol")
    if not tol > 0:
        raise ValueError(f"orbit: tol = {tol}: must be > 0")
    if period is not None:
        period = _finite(period, "orbit: period")
    text, columns, events, summary_json, monodromy, code = _core.orbit(
        case, _count(periods, "periods", 1), _count(settle, "settle", 0), tol,
        _count(max_iter, "max_iter", 1), _count(samples, "samples", 1),
        float("nan") if period is None else period)
    run = Result.from_core(columns, events, summary_json, case=case)
    return Orbit(json.loads(text), run, np.asarray(monodromy), code)
