#!/usr/bin/python3
"""Tests of the several-plane closed forms (planes.py, docs/closed-forms.md section 8).
Run: /usr/bin/python3 -m pytest validation/analytic/test_planes.py

Scales: every quantity is computed by a few complex 2x2 / KxK solves and products, so round-off
is a few eps = 2.2e-16 times the condition number of the receptance matrix (below 1e3 on these
rotors): a relative residual below 1e-12 is 5e3 eps, far above that and far below any modelling
error.
"""
import copy
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import planes as pl  # noqa: E402

# The paper's reference rotor (cases/reference.toml: m, Jd, Jp, L, delta, d, k_b, c_b) with two
# planes: the seal at R (p = l = 0.4 m) and a second seal halfway to the bearing, with the same
# radius / gap (250), each on its own sprung ring.
TWO = {"rotor.mass": 5.0, "rotor.Jd": 0.035, "rotor.Jp": 0.06, "rotor.L": 0.5,
       "rotor.delta": 0.1, "rotor.d": 0.3, "bearing.k": 5e6, "bearing.c": 300.0,
       "loads.torque": 20.0,
       "planes": [{"position": 0.4, "radius": 0.05, "gap": 2e-4, "mu": 0.5, "stator_mass": 2.0,
                   "stator_k": 2e6, "stator_c": 100.0},
                  {"position": 0.2, "radius": 0.025, "gap": 1e-4, "mu": 0.5, "stator_mass": 1.0,
                   "stator_k": 4e6, "stator_c": 50.0}]}

OMEGAS = [5.0, 20.0, 40.0, 150.0]


def one_plane():
    p = copy.deepcopy(TWO)
    p["planes"] = [p["planes"][0]]
    return p


def rigid_second():
    p = copy.deepcopy(TWO)
    p["planes"][1] = {"position": 0.2, "radius": 0.025, "gap": 1e-4, "mu": 0.5,
                      "stator_rigid": True}
    return p


@pytest.mark.parametrize("make", [lambda: TWO, one_plane, rigid_second])
def test_orbit_solves_the_real_equations(make):
    """The complex solution (8.2) satisfies the equations of motion written in real coordinates
    (equation_residual: a second statement of the model) at every time of the orbit."""
    p = make()
    for Om in OMEGAS:
        o = pl.rolling(p, Om)
        for t in np.linspace(0.0, 2e-3, 9):
            res, _ = pl.equation_residual(p, o, t)
            assert res < 1e-12, (Om, t, res)  # relative to the largest contact force (see top)


def test_split_plane_halves_the_forces():
    """Two planes at the same position, each with half of one ring (mass, k, c halved, same gap
    and radius), are the one plane: each carries exactly half of its force. An exact identity of
    (8.2) (Gamma's 2x2 block has equal entries, the rings' compliances double)."""
    p1 = one_plane()
    p2 = copy.deepcopy(p1)
    half = dict(p1["planes"][0])
    for k in ("stator_mass", "stator_k", "stator_c"):
        half[k] = half[k] / 2
    p2["planes"] = [dict(half), dict(half)]
    for Om in OMEGAS:
        a, b = pl.rolling(p1, Om), pl.rolling(p2, Om)
        for k in (0, 1):
            assert b["P"][k] == pytest.approx(a["P"][0] / 2, rel=1e-12)  # round-off (top)
        assert b["torque"] == pytest.approx(a["torque"], rel=1e-12)


@pytest.mark.parametrize("make", [lambda: TWO, one_plane, rigid_second])
def test_torque_is_the_dampers_power(make):
    """Power balance on the rolling orbit (docs/closed-forms.md section 6): friction does no work
    in rolling and the gyroscopic forces none ever, so the drive's power tau Omega equals what
    the bearing and ring dampers dissipate, w^2 (c_b |Z_b|^2 + sum c_s |S_k|^2). An independent
    check of (8.4): the torque comes from the theta row, the dissipation from the amplitudes."""
    p = make()
    for Om in OMEGAS:
        o = pl.rolling(p, Om)
        w = o["w"]
        diss = w * w * p["bearing.c"] * abs(o["Z_b"]) ** 2
        for k, plane in enumerate(p["planes"]):
            if not plane.get("stator_rigid", False):
                diss += w * w * plane["stator_c"] * abs(o["S"][k]) ** 2
        assert o["torque"] * Om == pytest.approx(diss, rel=1e-10)  # round-off of |Z|^2 sums


def test_rolling_speeds_take_the_torque():
    """Each root of (8.4) takes the drive torque to round-off (bisection to the last bit)."""
    roots = pl.rolling_speeds(TWO, 20.0, 1.0, 500.0)
    assert roots, "the two-plane rotor rolls somewhere under 20 N m"
    for Om in roots:
        assert pl.rolling(TWO, Om)["torque"] == pytest.approx(20.0, rel=1e-12)


def test_unequal_ratios_refused():
    """In phase, rolling at every plane needs the same radius / gap."""
    p = copy.deepcopy(TWO)
    p["planes"][1]["gap"] = 2e-4
    with pytest.raises(ValueError):
        pl.rolling(p, 20.0)


# ---- rubdyn on the orbit -------------------------------------------------------------------
RUBDYN = os.environ.get("RUBDYN_CLI", os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                   "..", "..", "build", "rubdyn"))


def orbit_case(p, o, solver, h, t_end):
    """A rubdyn case (TOML text) of the rotor p started on the orbit o at the prescribed spin."""
    import math
    lines = ['name = "two-plane-rolling"', "[rotor]"]
    for k in ("mass", "Jd", "Jp", "L", "delta", "d"):
        lines.append(f"{k} = {p['rotor.' + k]!r}")
    lines += ["[bearing]", f"k = {p['bearing.k']!r}", f"c = {p['bearing.c']!r}"]
    for pl_ in p["planes"]:
        lines.append("[[plane]]")
        lines += [f"{k} = {str(v).lower() if isinstance(v, bool) else repr(v)}"
                  for k, v in pl_.items()]
    lines += ["[loads]", "gravity = 0.0", 'spin = "prescribed"', "spin_accel = 0.0", "[initial]"]
    for k, v in pl.orbit_state(p, o).items():
        lines.append(f"{k.split('.', 1)[1]} = {float(v)!r}")
    assert all(math.isfinite(float(v)) for v in pl.orbit_state(p, o).values())
    lines += ["[run]", f"t_end = {t_end!r}", "omega_lim = 1e4", "[solver]", f'kind = "{solver}"',
              f"h = {h!r}", "[output]", "dt = 1e-5"]
    return "\n".join(lines) + "\n"


def run_orbit(tmp_path, p, o, solver, h, t_end=0.005):
    import csv
    import subprocess
    case = tmp_path / f"roll-{solver}-{h}.toml"
    case.write_text(orbit_case(p, o, solver, h, t_end))
    out = tmp_path / f"out-{solver}-{h}"
    r = subprocess.run([RUBDYN, "run", str(case), "--out", str(out), "--quiet"],
                       capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stderr
    with open(out / "timeseries.csv") as f:
        rows = list(csv.DictReader(f))
    return rows


@pytest.mark.skipif(not os.path.isfile(RUBDYN), reason="no rubdyn CLI (set RUBDYN_CLI)")
def test_mj_proj_converges_to_the_two_plane_rolling_orbit(tmp_path):
    """Moreau-Jean (projected) with two contacts, started on the closed-form orbit of the
    two-plane rotor rolling at both planes (prescribed spin 40 rad/s, whirl -1e4 rad/s, mu 0.5
    at both planes so that the joint stick holds): both planes stick at every sample, and each
    plane's F_N and F_T converge to (8.3) as h falls.
    The scheme is first order: its tangential force error is O(h) of the normal force (the
    friction is 0.8 % of F_N on this orbit, so F_T is the sensitive one). Measured over 5 ms
    (8 whirl periods, t > 1 ms): h = 1e-6 s, F_N 1.7e-4 relative, |F_T error| 5.2e-3 F_N;
    h = 2.5e-7 s, 1.9e-5 and 1.3e-3 F_N. The test asks for convergence (the error falls by at
    least 3 when h falls by 4: first order with a margin) and for the finer run's F_N within
    1e-4 (5x the measured 1.9e-5): a wrong W at a plane, a wrong interpolation weight or a
    contact solved apart from the other would leave an O(1) error that does not fall with h."""
    p = TWO
    p = copy.deepcopy(p)
    for plane in p["planes"]:
        plane["mu"] = 0.5
    o = pl.rolling(p, 40.0)
    assert o["admissible"]
    errs = {}
    for h in (1e-6, 2.5e-7):
        rows = run_orbit(tmp_path, p, o, "mj-proj", h)
        late = [r for r in rows if float(r["t"]) > 1e-3]
        e = []
        for k in (1, 2):
            assert all(r[f"phase_{k}"] == "stick" for r in late), (h, k)
            FN = np.array([float(r[f"F_N_{k}"]) for r in late])
            FT = np.array([float(r[f"F_T_{k}"]) for r in late])
            e.append((np.max(np.abs(FN / o["F_N"][k - 1] - 1)),
                      np.max(np.abs(FT - o["F_T"][k - 1])) / o["F_N"][k - 1]))
        errs[h] = e
    for k in range(2):
        for j in range(2):
            assert errs[1e-6][k][j] > 3 * errs[2.5e-7][k][j], (k, j, errs)
        assert errs[2.5e-7][k][0] < 1e-4, errs


@pytest.mark.skipif(not os.path.isfile(RUBDYN), reason="no rubdyn CLI (set RUBDYN_CLI)")
def test_event_solver_reproduces_the_two_plane_rolling_orbit(tmp_path):
    """The event-driven solver with two contacts (src/hybrid/event_driven.cpp), started on the
    closed-form orbit of the two-plane rotor rolling at both planes (the case of the test above):
    both planes stick at every sample, and each plane's F_N and F_T are (8.3) to the integrator's
    tolerance. Both planes stick at a prescribed spin: the phase is integrated in minimal
    coordinates, the rolling constraint rheonomic (docs/minimal-coordinates.md 4.1). Measured
    over 5 ms: the largest relative F_N error and |F_T error| / F_N over both planes, 1.4e-8 at
    rtol 1e-8, 8.5e-10 at rtol 1e-10, 3.2e-12 at rtol 1e-12 (with the projection formulation:
    3.6e-9, 1.5e-10, 3.2e-12). The test: at rtol 1e-12 every error below 1e-10 (30x the
    measured) and at least 10x below the rtol 1e-10 run's (measured 270x)."""
    p = copy.deepcopy(TWO)
    for plane in p["planes"]:
        plane["mu"] = 0.5
    o = pl.rolling(p, 40.0)
    assert o["admissible"]
    errs = {}
    for rtol in (1e-10, 1e-12):
        case = tmp_path / f"roll-event-{rtol}.toml"
        case.write_text(orbit_case(p, o, "event", 1e-6, 0.005).replace(
            "h = 1e-06", f"rtol = {rtol!r}\natol = {rtol * 1e-3!r}"))
        out = tmp_path / f"out-event-{rtol}"
        import csv
        import subprocess
        r = subprocess.run([RUBDYN, "run", str(case), "--out", str(out), "--quiet"],
                           capture_output=True, text=True, check=False)
        assert r.returncode == 0, r.stderr
        with open(out / "timeseries.csv") as f:
            rows = list(csv.DictReader(f))
        e = 0.0
        for k in (1, 2):
            assert all(r[f"phase_{k}"] == "stick" for r in rows), (rtol, k)
            FN = np.array([float(r[f"F_N_{k}"]) for r in rows])
            FT = np.array([float(r[f"F_T_{k}"]) for r in rows])
            e = max(e, np.max(np.abs(FN / o["F_N"][k - 1] - 1)),
                    np.max(np.abs(FT - o["F_T"][k - 1])) / o["F_N"][k - 1])
        errs[rtol] = e
    assert errs[1e-12] < 1e-10, errs
    assert errs[1e-10] > 10 * errs[1e-12], errs
