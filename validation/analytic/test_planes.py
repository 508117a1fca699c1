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
