#!/usr/bin/python3
"""Tests of the closed forms (closed_forms.py) and of the independent contact-phase simulation
(reference_sim.py). Run: /usr/bin/python3 -m pytest validation/analytic/test_closed_forms.py

Every tolerance is argued where it is used. Scales: double precision eps = 2.2e-16; DOP853 at
rtol = 1e-12 keeps the local error of every step below about 1e-12 of the state, and a smooth,
damped contact phase does not amplify it (the measured global errors below are 1e-13..1e-11).
"""
import cmath
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import closed_forms as cf  # noqa: E402
import reference_sim as rs  # noqa: E402

EPS = np.finfo(float).eps

# Rigid stator, constant torque: Omega_ss = 26.67 rad/s, w = -6667 rad/s, time constant 96.7 ms.
RIGID = {"rotor.mass": 5.0, "rotor.k": 5e6, "rotor.c": 300.0, "rotor.Jp": 0.06,
         "rotor.radius": 0.05, "stator.gap": 2e-4, "stator.rigid": True, "contact.mu": 0.3,
         "loads.torque": 20.0, "loads.gravity": 0.0}
# Sprung stator with two admissible, stable rolling orbits (w = -1370 and -5933 rad/s).
BLACK_ROLL = {"rotor.mass": 5.0, "rotor.k": 5e6, "rotor.c": 600.0, "rotor.Jp": 0.01,
              "rotor.radius": 0.05, "stator.mass": 2.0, "stator.k": 2e7, "stator.c": 400.0,
              "stator.gap": 5e-4, "contact.mu": 0.3, "loads.torque": 40.0, "loads.gravity": 0.0}
# Sprung, well damped stator (zeta_s = 0.2): three whip roots, the middle one stable.
BLACK_WHIP = {"rotor.mass": 5.0, "rotor.k": 5e6, "rotor.c": 300.0, "rotor.Jp": 0.06,
              "rotor.radius": 0.05, "stator.mass": 2.0, "stator.k": 2e7, "stator.c": 2500.0,
              "stator.gap": 2e-4, "contact.mu": 0.3, "loads.torque": 20.0, "loads.gravity": 0.0}
# Unbalance at a prescribed 1500 rad/s (1.5 x the rotor frequency), rigid stator: two rub orbits
# beside the free orbit (amplitude 1.44e-4 m < g0).
OMEGA_U = 1500.0
UNB = {"rotor.mass": 5.0, "rotor.k": 5e6, "rotor.c": 300.0, "rotor.Jp": 0.06,
       "rotor.radius": 0.05, "stator.gap": 2e-4, "stator.rigid": True, "contact.mu": 0.1,
       "loads.unbalance": 4e-4, "loads.unbalance_phase": 0.3, "loads.gravity": 0.0,
       "loads.spin": "prescribed", "loads.spin_accel": 0.0, "initial.omega0": OMEGA_U,
       "initial.theta": 0.0}
UNB_SPRUNG = dict(UNB, **{"stator.rigid": False, "stator.mass": 2.0, "stator.k": 2e7,
                          "stator.c": 400.0})


def K_direct(P, w):
    """Black's K written again, without closed_forms (the tests' independent evaluation)."""
    Dr = P["rotor.k"] - P["rotor.mass"] * w ** 2 + 1j * P["rotor.c"] * w
    if P.get("stator.rigid"):
        return Dr
    Ds = P["stator.k"] - P["stator.mass"] * w ** 2 + 1j * P["stator.c"] * w
    return 1.0 / (1.0 / Dr + 1.0 / Ds)


def energy_defect(S):
    """max |E - E0 - W| relative to the largest of E and the works (the integration check)."""
    d = S["E"] - S["E"][0] - S["W"].sum(axis=1)
    return np.max(np.abs(d)) / max(np.max(np.abs(S["E"])), np.max(np.abs(S["W"])))


def polar(S, rigid):
    """phi, phi', zeta = z_s e^{-i phi} of the samples."""
    q, v = S["q"], S["v"]
    zr = q[:, 0] + 1j * q[:, 1]
    vr = v[:, 0] + 1j * v[:, 1]
    zs = 0 * zr if rigid else q[:, 3] + 1j * q[:, 4]
    vs = 0 * zr if rigid else v[:, 3] + 1j * v[:, 4]
    r, rd = zr - zs, vr - vs
    phi = np.angle(r)
    phid = (np.conj(r) * rd).imag / np.abs(r) ** 2
    return phi, phid, zs * np.exp(-1j * phi)


# ---------------------------------------------------------------------------------------------
# 1. The model's equations are Lagrange's equations of T and V (docs/models.md, sections 1-2)
# ---------------------------------------------------------------------------------------------

def lagrange_forces(T, V, Q, q, v):
    """M and f = Q - dV/dq + dT/dq - (dM/dt) v from T(q, v), V(q), Q(q, v): M by polarization
    (T is quadratic in v), derivatives in q by the complex step (no cancellation)."""
    n, h = len(q), 1e-30

    def M_of(qq):
        E = np.eye(n)
        M = np.empty((n, n), dtype=complex)
        for i in range(n):
            M[i, i] = 2 * T(qq, E[i])
            for j in range(i):
                M[i, j] = M[j, i] = T(qq, E[i] + E[j]) - T(qq, E[i]) - T(qq, E[j])
        return M

    M = M_of(q.astype(complex)).real
    dT = np.array([T(q + 1j * h * e, v).imag / h for e in np.eye(n)])
    dV = np.array([V(q + 1j * h * e).imag / h for e in np.eye(n)])
    Mdot_v = (M_of(q + 1j * h * v) @ v).imag / h
    return M, Q(q, v) - dV + dT - Mdot_v


@pytest.mark.parametrize("rigid", [False, True])
def test_jeffcott_equations_are_lagrange(rigid):
    P = dict(BLACK_ROLL, **{"loads.unbalance": 3e-3, "loads.unbalance_phase": 0.7,
                            "loads.gravity": 9.81, "stator.rigid": rigid,
                            "loads.torque_law": "linear", "loads.torque_free_speed": 300.0})
    m = rs.JeffcottBlack(P)
    eps = P["loads.unbalance"] / P["rotor.mass"]
    JG = P["rotor.Jp"] - P["rotor.mass"] * eps ** 2     # J is about the geometric centre

    def T(q, v):  # the mass centre z_G = z_r + eps e^{i psi} moves with it (real, complex-safe)
        psi = q[2] + P["loads.unbalance_phase"]
        xg = v[0] - eps * v[2] * np.sin(psi)
        yg = v[1] + eps * v[2] * np.cos(psi)
        t = 0.5 * P["rotor.mass"] * (xg * xg + yg * yg) + 0.5 * JG * v[2] ** 2
        return t if rigid else t + 0.5 * P["stator.mass"] * (v[3] ** 2 + v[4] ** 2)

    def V(q):
        yG = q[1] + eps * np.sin(q[2] + P["loads.unbalance_phase"])
        V_ = 0.5 * P["rotor.k"] * (q[0] ** 2 + q[1] ** 2) + 9.81 * P["rotor.mass"] * yG
        if not rigid:
            V_ += 0.5 * P["stator.k"] * (q[3] ** 2 + q[4] ** 2) + 9.81 * P["stator.mass"] * q[4]
        return V_

    def Q(q, v):
        tau = P["loads.torque"] * (1 - v[2] / P["loads.torque_free_speed"])
        Qr = [-P["rotor.c"] * v[0], -P["rotor.c"] * v[1], tau]
        return np.array(Qr + ([] if rigid else [-P["stator.c"] * v[3], -P["stator.c"] * v[4]]))

    rng = np.random.default_rng(1)
    for _ in range(5):
        q = rng.normal(size=m.n) * [1e-3, 1e-3, 3.0, 1e-3, 1e-3][:m.n]
        v = rng.normal(size=m.n) * [1.0, 1.0, 200.0, 1.0, 1.0][:m.n]
        M, f = lagrange_forces(T, V, Q, q, v)
        # M by polarization loses at most eps * (largest entry) per entry; a wrong sign or a
        # missing u_b coupling is an O(u_b) = 3e-3 error, 1e10 times the tolerance.
        assert np.max(np.abs(M - m.mass_matrix(q))) <= 50 * EPS * np.max(np.abs(M))
        fs = m.smooth_forces(0.0, q, v)
        # f sums terms up to u_b Omega^2 and k_r q (~1e4 N): rounding ~1e-12 relative to them.
        scale = max(np.max(np.abs(f)), P["rotor.k"] * 1e-3)
        assert np.max(np.abs(f - fs)) <= 1e-12 * scale


def rigid_rotor_M_f(P, q, v):
    """The paper's rigid rotor with a mass unbalance, transcribed from docs/models.md section 2:
    q = (x_b, y_b, x_r, y_r, theta, x_s, y_s); M(q) and f(q, v) (no contact)."""
    m, Jd, Jp = P["rotor.mass"], P["rotor.Jd"], P["rotor.Jp"]
    l = P["rotor.L"] - P["rotor.delta"]
    nu = P["rotor.d"] / l
    ub, g = P["loads.unbalance"], P["loads.gravity"]
    psi = q[4] + P["loads.unbalance_phase"]
    M11, M12, M22, H = (1 - nu) ** 2 * m + Jd / l ** 2, nu * (1 - nu) * m - Jd / l ** 2, \
        nu ** 2 * m + Jd / l ** 2, Jp / l ** 2
    Hx, Hy = H * (q[2] - q[0]) / 2, -H * (q[3] - q[1]) / 2
    M = np.zeros((7, 7))
    for a, b in [(0, 0), (1, 1)]:
        M[a, b] = M11
    M[2, 2] = M[3, 3] = M22
    M[0, 2] = M[2, 0] = M[1, 3] = M[3, 1] = M12
    M[4, 4] = Jp
    M[5, 5] = M[6, 6] = P["stator.mass"]
    th = [Hy - (1 - nu) * ub * math.sin(psi), Hx + (1 - nu) * ub * math.cos(psi),
          -Hy - nu * ub * math.sin(psi), -Hx + nu * ub * math.cos(psi)]
    M[4, :4] = M[:4, 4] = th
    G = np.zeros((7, 7))
    for (i, j, s) in [(0, 1, 1), (0, 3, -1), (1, 0, -1), (1, 2, 1), (2, 1, -1), (2, 3, 1),
                      (3, 0, 1), (3, 2, -1)]:
        G[i, j] = s * H
    Om = v[4]
    f = -Om * G @ v
    f[:2] += -P["bearing.c"] * v[:2] - P["bearing.k"] * q[:2]
    f[5:] += -P["stator.c"] * v[5:] - P["stator.k"] * q[5:]
    f[1] -= (1 - nu) * m * g
    f[3] -= nu * m * g
    f[4] += P["loads.torque"] - ub * g * math.cos(psi)
    cen = ub * Om * Om
    f[:4] += cen * np.array([(1 - nu) * math.cos(psi), (1 - nu) * math.sin(psi),
                             nu * math.cos(psi), nu * math.sin(psi)])
    return M, f


def test_rigid_rotor_with_unbalance_is_lagrange():
    P = {"rotor.mass": 5.0, "rotor.Jd": 0.035, "rotor.Jp": 0.06, "rotor.L": 0.5,
         "rotor.delta": 0.1, "rotor.d": 0.3, "bearing.k": 5e6, "bearing.c": 300.0,
         "stator.mass": 2.0, "stator.k": 2e6, "stator.c": 100.0, "loads.gravity": 9.81,
         "loads.torque": 20.0, "loads.unbalance": 2e-3, "loads.unbalance_phase": -1.1}
    m, Jd, Jp = P["rotor.mass"], P["rotor.Jd"], P["rotor.Jp"]
    l = P["rotor.L"] - P["rotor.delta"]
    nu, eps = P["rotor.d"] / l, P["loads.unbalance"] / P["rotor.mass"]

    def zG(q, v):  # position and velocity of the mass centre, unbalance included
        psi = q[4] + P["loads.unbalance_phase"]
        x = nu * q[2] + (1 - nu) * q[0] + eps * np.cos(psi)
        y = nu * q[3] + (1 - nu) * q[1] + eps * np.sin(psi)
        vx = nu * v[2] + (1 - nu) * v[0] - eps * v[4] * np.sin(psi)
        vy = nu * v[3] + (1 - nu) * v[1] + eps * v[4] * np.cos(psi)
        return x, y, vx, vy

    def T(q, v):  # rigid body (paper eq. 8) with theta_x = -(y_r - y_b)/l, theta_y = (x_r - x_b)/l
        _, _, vx, vy = zG(q, v)
        tx, ty = -(q[3] - q[1]) / l, (q[2] - q[0]) / l
        txd, tyd = -(v[3] - v[1]) / l, (v[2] - v[0]) / l
        return (0.5 * m * (vx * vx + vy * vy) + 0.5 * Jd * (txd ** 2 + tyd ** 2)
                + 0.5 * (Jp - m * eps ** 2) * v[4] ** 2 + 0.5 * Jp * v[4] * (txd * ty - tyd * tx)
                + 0.5 * P["stator.mass"] * (v[5] ** 2 + v[6] ** 2))

    def V(q):  # the stator's weight is carried by its support (no stator gravity term)
        _, y, _, _ = zG(q, q)
        return (0.5 * P["bearing.k"] * (q[0] ** 2 + q[1] ** 2)
                + 0.5 * P["stator.k"] * (q[5] ** 2 + q[6] ** 2) + m * P["loads.gravity"] * y)

    def Q(q, v):
        c_b, c_s = P["bearing.c"], P["stator.c"]
        return np.array([-c_b * v[0], -c_b * v[1], 0, 0, P["loads.torque"], -c_s * v[5],
                         -c_s * v[6]])

    rng = np.random.default_rng(2)
    for _ in range(5):
        q = rng.normal(size=7) * [1e-3, 1e-3, 1e-3, 1e-3, 3.0, 1e-3, 1e-3]
        v = rng.normal(size=7) * [1.0, 1.0, 1.0, 1.0, 500.0, 1.0, 1.0]
        M, f = lagrange_forces(T, V, Q, q, v)
        Md, fd = rigid_rotor_M_f(P, q, v)
        # as in the Jeffcott test: rounding only (an error of the docs is O(u_b) or O(H q))
        assert np.max(np.abs(M - Md)) <= 50 * EPS * np.max(np.abs(M))
        assert np.max(np.abs(f - fd)) <= 1e-12 * max(np.max(np.abs(f)), 5e6 * 1e-3)


# ---------------------------------------------------------------------------------------------
# 2. Contact kinematics and the rolling identity (docs/models.md section 4)
# ---------------------------------------------------------------------------------------------

def test_contact_kinematics_signs():
    m = rs.JeffcottBlack(BLACK_ROLL)
    R = m.R
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = rng.normal(size=5) * [4e-4, 4e-4, 2.0, 1e-4, 1e-4]
        v = rng.normal(size=5) * [1.0, 1.0, 100.0, 0.5, 0.5]
        dN, WN, WT, vN, vt = m.contact(q, v)
        r = complex(q[0] - q[3], q[1] - q[4])
        n = r / abs(r)
        # W_N is the gradient of d_N: central differences with h = 1e-6 |r| have a truncation
        # error ~(h/|r|)^2 = 1e-12 and a rounding error ~eps g0 / h ~ 2e-10 (W_N is O(1))
        h = 1e-6 * abs(r)
        fd = np.array([(m.contact(q + h * e, v)[0] - m.contact(q - h * e, v)[0]) / (2 * h)
                       for e in np.eye(5)])
        assert np.max(np.abs(fd - WN)) <= 1e-9
        # the sign convention: n points from the stator centre to the rotor, W_N = -n on the rotor
        assert abs(complex(WN[0], WN[1]) + n) <= 1e-15 and abs(complex(WN[3], WN[4]) - n) <= 1e-15
        # v_t: the velocity of the rotor's material point at the contact, z_r' + i Omega R n,
        # relative to the (non-rotating) stator's, projected on t = -i n
        vP = complex(v[0], v[1]) + 1j * v[2] * R * n - complex(v[3], v[4])
        t = -1j * n
        assert abs((np.conj(t) * vP).real - vt) <= 1e-14 * (abs(vP) + abs(R * v[2]))
        assert abs((np.conj(n) * vP).real + vN) <= 1e-14 * (abs(vP) + abs(R * v[2]))
        # torque of F_T t applied at z_r + R n about z_r is (R n) x (F_T t) = -R F_T = W_T,theta F_T
        cross = (R * n.real) * t.imag - (R * n.imag) * t.real
        assert abs(cross - WT[2]) <= 1e-15


def test_rolling_identity_in_stick():
    """In stick, the rotor's contact point moves with the stator's and phi' = -(R/g0) Omega.
    Checked on a sprung-stator rolling run: the chart ties phi to theta through S; a wrong sign
    there or in W_T would leave a relative velocity of order g0 |phi'| ~ 1 m/s."""
    P = BLACK_ROLL
    root = cf.black_rolling_roots(P)[0]
    m = rs.JeffcottBlack(P)
    q, v = rs.state_from_keys(m, cf.contact_orbit_state(P, root["w"], root["Omega"]))
    q[[0, 3]] += 2e-6        # translate rotor and stator together: still rolling, not steady
    res = rs.simulate(m, q, v, 0.0, 0.02, mode="stick", t_eval=np.linspace(0, 0.02, 41))
    S = res.samples()
    assert res.termination == "t_end" and set(S["mode"]) == {"stick"}
    _, phid, _ = polar(S, False)
    Om = S["v"][:, 2]
    # phi' from positions and velocities (atan2 geometry), Omega from the spin: both rounding
    assert np.max(np.abs(phid + (m.R / m.g0) * Om)) <= 1e-12 * np.max(np.abs(phid))
    assert np.max(np.abs(S["v_t"])) <= 1e-12 * m.R * np.max(np.abs(Om))
    assert np.all(S["F_N"] > 0) and np.all(np.abs(S["F_T"]) <= m.mu * S["F_N"])
    assert energy_defect(S) <= 1e-10


# ---------------------------------------------------------------------------------------------
# 3. Rigid stator, rolling (docs/closed-forms.md section 2)
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("law", ["constant", "linear"])
def test_rigid_stator_rolling_exponential(law):
    P = dict(RIGID)
    Om0 = None
    if law == "linear":
        P.update({"loads.torque_law": "linear", "loads.torque_free_speed": 40.0})
        Om0 = 40.0
    args = [P[k] for k in ("rotor.mass", "rotor.k", "rotor.c", "rotor.Jp", "rotor.radius",
                           "stator.gap", "loads.torque")]
    cfr = cf.rolling_rigid_stator(*args, Omega_0=Om0, mu=P["contact.mu"])
    m = rs.JeffcottBlack(P)
    Om_start = 10.0
    keys = cf.contact_orbit_state(P, cf.rolling_whirl(m.R, m.g0, Om_start), Om_start)
    q, v = rs.state_from_keys(m, keys)
    t = np.linspace(0, 5 * cfr["time_constant"], 21)
    res = rs.simulate(m, q, v, 0.0, t[-1], t_eval=t)
    S = res.samples()
    assert res.termination == "t_end" and set(S["mode"]) == {"stick"}
    ex = cf.rolling_rigid_stator_spin(P["rotor.mass"], P["rotor.c"], P["rotor.Jp"], m.R,
                                      P["loads.torque"], Om_start, S["t"], Omega_0=Om0)
    # the simulation integrates the full 3-dof stick dynamics (no reduced equation); DOP853 at
    # rtol 1e-12 over ~0.5 s of a first-order decay: global error ~1e-12 relative
    assert np.max(np.abs(S["v"][:, 2] / ex - 1)) <= 1e-10
    # measured time constant from the sample at t = 2 T_c (decay e^-2: no cancellation)
    j = 8
    Tm = -S["t"][j] / math.log((S["v"][j, 2] - cfr["Omega"]) / (Om_start - cfr["Omega"]))
    assert abs(Tm / cfr["time_constant"] - 1) <= 1e-9   # 1e-11 error / (Omega - Omega_ss) ~ 10
    # N = g0 (m_r w^2 - k_r) with w = -(R/g0) Omega at every instant of rolling (rounding)
    k = m.R / m.g0
    Om = S["v"][-1, 2]
    assert abs(S["F_N"][-1] - m.g0 * (m.m_r * (k * Om) ** 2 - m.k_r)) <= 1e-9 * S["F_N"][-1]
    assert energy_defect(S) <= 1e-10


def test_rigid_stator_rolling_prescribed_ramp():
    alpha, Om_start = 200.0, 10.0
    P = dict(RIGID, **{"loads.spin": "prescribed", "loads.spin_accel": alpha,
                       "initial.omega0": Om_start, "initial.theta": 0.4})
    m = rs.JeffcottBlack(P)
    keys = cf.contact_orbit_state(P, cf.rolling_whirl(m.R, m.g0, Om_start), Om_start,
                                  phi0=1.0, theta0=0.4)
    q, v = rs.state_from_keys(m, keys)
    t = np.linspace(0, 0.1, 11)
    res = rs.simulate(m, q, v, 0.0, t[-1], t_eval=t)
    S = res.samples()
    assert res.termination == "t_end" and set(S["mode"]) == {"stick"}
    ex = cf.rolling_rigid_stator_prescribed(m.m_r, m.k_r, m.c_r, m.J, m.R, m.g0, Om_start,
                                            alpha, S["t"])
    # with theta and the contact fully prescribed, the forces are a 3x3 linear solve: rounding
    for key, col in (("tau_d", "tau_d"), ("N", "F_N"), ("F_T", "F_T")):
        assert np.max(np.abs(S[col] / ex[key] - 1)) <= 1e-12
    assert energy_defect(S) <= 1e-12


def test_rigid_stator_rolling_needs_zero_gravity():
    """With gravity the rolling spin is not the exponential: m_r g R cos(phi) adds a torque at
    the whirl frequency, (J + m_r R^2) Omega' + c_r R^2 Omega = tau + m_r g R cos(phi), so Omega
    oscillates with amplitude m_r g R / |i w (J + m_r R^2) + c_r R^2| (5.1e-3 rad/s here)."""
    P = dict(RIGID, **{"loads.gravity": 9.81})
    m = rs.JeffcottBlack(P)
    cfr = cf.rolling_rigid_stator(m.m_r, m.k_r, m.c_r, m.J, m.R, m.g0, P["loads.torque"])
    Om = cfr["Omega"]
    q, v = rs.state_from_keys(m, cf.contact_orbit_state(P, cfr["w"], Om))
    res = rs.simulate(m, q, v, 0.0, 0.02, t_eval=np.linspace(0, 0.02, 401))
    S = res.samples()
    amp = m.m_r * 9.81 * m.R / abs(1j * cfr["w"] * cfr["effective_inertia"] + m.c_r * m.R ** 2)
    dev = np.max(np.abs(S["v"][:, 2] - Om))
    # started at the steady spin, the deviation is the forced oscillation plus its start-up
    # transient (same size, decaying in 97 ms): between 0.5 and 2.5 amplitudes
    assert 0.5 * amp <= dev <= 2.5 * amp
    assert dev > 1e4 * 1e-10 * Om   # far above what the closed forms are compared to
    assert energy_defect(S) <= 1e-10


# ---------------------------------------------------------------------------------------------
# 4. Black's model: rolling roots and which attract (docs/closed-forms.md section 3)
# ---------------------------------------------------------------------------------------------

def test_black_rolling_roots_equations_and_completeness():
    for P in (BLACK_ROLL, BLACK_WHIP, dict(BLACK_ROLL, **{"loads.torque_law": "linear",
                                                        "loads.torque_free_speed": 200.0})):
        roots = cf.black_rolling_roots(P)
        R, g0, tau = P["rotor.radius"], P["stator.gap"], P["loads.torque"]
        lin = P.get("loads.torque_law") == "linear"

        def g(w):
            Om = -g0 / R * w
            ta = tau * (1 - Om / P["loads.torque_free_speed"]) if lin else tau
            return K_direct(P, w).imag + ta / (R * g0)
        for r in roots:
            # Newton-polished: |g| is rounding in Im K (terms ~|K| ~ 1e7) over tau/(R g0) ~ 4e6
            assert abs(g(r["w"])) <= 1e-12 * abs(K_direct(P, r["w"]))
            gK = g0 * K_direct(P, r["w"])
            assert abs(r["N"] + gK.real) <= 1e-12 * abs(gK)
            assert abs(r["Omega"] + g0 / R * r["w"]) <= EPS * abs(r["Omega"]) * 4
        # completeness: every sign change of g on a fine grid of w < 0 is a root found
        w = -np.geomspace(1.0, 1e3 * math.sqrt(P["rotor.k"] / P["rotor.mass"]), 400001)
        gv = np.array([g(x) for x in w[::50]])
        changes = np.sum(np.sign(gv[1:]) != np.sign(gv[:-1]))
        assert changes == len([r for r in roots if r["w"] < 0])


def test_black_rolling_reduces_to_rigid_stator():
    """With a rigid stator (K = D_r) the general rolling condition gives section 2's steady
    state: one root, w = -(R/g0) tau / (c_r R^2), N = g0 (m_r w^2 - k_r) (rounding only)."""
    roots = cf.black_rolling_roots(RIGID)
    ref = cf.rolling_rigid_stator(*[RIGID[k] for k in ("rotor.mass", "rotor.k", "rotor.c",
                                                        "rotor.Jp", "rotor.radius", "stator.gap",
                                                        "loads.torque")])
    assert len(roots) == 1
    for key in ("w", "Omega", "N", "F_T"):
        assert abs(roots[0][key] / ref[key] - 1) <= 1e-14


def test_black_rolling_is_bistable():
    roots = [r for r in cf.black_rolling_roots(BLACK_ROLL) if r["contact"] and r["stick"]]
    f = cf.frequencies(BLACK_ROLL)
    assert len(roots) == 2
    assert min(f["w_r"], f["w_s"]) < abs(roots[0]["w"]) < f["w_c"]
    assert abs(roots[1]["w"]) > max(f["w_r"], f["w_s"])


def field_scales(m, w, head, presc=False):
    """Scales of orbit_vector_field's components: the head (Omega' or phi''; with a prescribed
    spin delta' ~ |w| first), zeta' ~ g0 |w|, eta' ~ g0 w^2."""
    lat = [] if m.rigid else [m.g0 * abs(w)] * 2 + [m.g0 * w * w] * 2
    return np.array(([abs(w)] if presc else []) + [head] + lat)


def _xi(root_w, keys, head):
    zs = complex(keys["initial.x_s"], keys["initial.y_s"])
    return head + [zs.real, zs.imag, (1j * root_w * zs).real, (1j * root_w * zs).imag]


@pytest.mark.parametrize("branch", [0, 1])
def test_black_rolling_branch_attracts(branch):
    P = BLACK_ROLL
    root = [r for r in cf.black_rolling_roots(P) if r["contact"] and r["stick"]][branch]
    m = rs.JeffcottBlack(P)
    keys = cf.contact_orbit_state(P, root["w"], root["Omega"], phi0=0.5)
    xi = _xi(root["w"], cf.contact_orbit_state(P, root["w"], root["Omega"]), [root["Omega"]])
    ev, F0 = rs.orbit_eigenvalues(m, "stick", xi)
    # the closed-form orbit is an equilibrium of the simulation's own vector field (rounding
    # only: forces ~1e4 N through a 5x5 solve)
    assert np.max(np.abs(F0 / field_scales(m, root["w"], P["loads.torque"] / m.J))) <= 1e-12
    lam = max(ev.real)
    assert lam < 0          # both branches are stable here (bistability)
    q, v = rs.state_from_keys(m, keys)
    d0 = 1e-3 * m.g0
    q[[0, 3]] += d0          # translate rotor and stator: a rolling state off the orbit
    v[[1, 4]] += d0 * abs(root["w"])
    t_end = math.log(1e5) / -lam
    res = rs.simulate(m, q, v, 0.0, t_end, mode="stick", t_eval=[0.0, t_end])
    S = res.samples()
    assert res.termination == "t_end"
    _, _, zeta = polar(S, False)
    zs0 = complex(keys["initial.x_s"], keys["initial.y_s"]) * cmath.exp(-0.5j)
    err0 = abs(zeta[0] - zs0) / abs(zs0)
    err = max(abs(zeta[-1] - zs0) / abs(zs0), abs(S["v"][-1, 2] / root["Omega"] - 1),
              abs(S["F_N"][-1] / root["N"] - 1))
    # linear theory: err <= kappa err0 e^{lam t_end} = kappa 1e-5 err0; err0 ~ 4e-3 and kappa
    # (the eigenvector basis' condition) below 100 gives err <= 4e-6. A wrong branch would
    # leave err = O(1).
    assert err0 > 1e-3
    assert err <= 100 * 1e-5 * err0
    assert energy_defect(S) <= 1e-10


# ---------------------------------------------------------------------------------------------
# 5. Whip (backward slip) (docs/closed-forms.md section 4)
# ---------------------------------------------------------------------------------------------

def test_black_whip_roots_and_stability():
    P = BLACK_WHIP
    roots = cf.black_whip_roots(P)
    mu = P["contact.mu"]
    assert len(roots) == 3
    m = rs.JeffcottBlack(P)
    lams = []
    for r in roots:
        K = K_direct(P, r["w"])
        assert abs(K.imag - mu * K.real) <= 1e-13 * abs(K)     # polished root: rounding of K
        keys = cf.contact_orbit_state(P, r["w"], 10 * r["Omega_stick"])
        ev, F0 = rs.orbit_eigenvalues(m, "slip-", _xi(r["w"], keys, [r["w"]]))
        assert np.max(np.abs(F0 / field_scales(m, r["w"], r["w"] ** 2))) <= 1e-12
        lams.append(max(ev.real))
    # the middle root is stable, the outer two are not (their margins are > 50 1/s, far above
    # the ~1e-4 1/s error of the difference Jacobian)
    assert lams[1] < -50 and lams[0] > 50 and lams[2] > 50
    # the same set with a lightly damped stator: the middle root is unstable
    P2 = dict(P, **{"stator.c": 400.0})
    r = cf.black_whip_roots(P2)[1]
    m2 = rs.JeffcottBlack(P2)
    keys = cf.contact_orbit_state(P2, r["w"], 1.0)
    ev, _ = rs.orbit_eigenvalues(m2, "slip-", _xi(r["w"], keys, [r["w"]]))
    assert max(ev.real) > 50


@pytest.mark.parametrize("which", [0, 1, 2])
def test_black_whip_attracts_or_repels(which):
    P = BLACK_WHIP
    r = cf.black_whip_roots(P)[which]
    m = rs.JeffcottBlack(P)
    Om_start = 30.0                      # R Omega = 1.5 m/s > g0 |w| (<= 1.04 m/s): v_t < 0
    keys = cf.contact_orbit_state(P, r["w"], Om_start)
    q, v = rs.state_from_keys(m, keys)
    d0 = 1e-6 * m.g0
    q[[0, 3]] += d0
    t_end = 0.05
    res = rs.simulate(m, q, v, 0.0, t_end, mode="slip-", switch=False,
                      t_eval=np.linspace(0, t_end, 6))
    S = res.samples()
    _, phid, zeta = polar(S, False)
    zs0 = complex(keys["initial.x_s"], keys["initial.y_s"])
    dist = np.abs(zeta - zs0) / abs(zs0) + np.abs(phid / r["w"] - 1)
    if which == 1:
        # stable (lambda = -106 1/s): 0.05 s divide the distance by e^5.3 = 200; kappa < 20
        assert res.termination == "t_end"
        assert dist[-1] <= dist[0] / 10
    else:
        # unstable (lambda = +189 and +2506 1/s): the distance grows by e^9 or more, or the
        # orbit is left through lift-off or stick before t_end
        assert res.termination != "t_end" or dist[-1] >= 100 * dist[0]


@pytest.mark.parametrize("law", ["constant", "linear"])
def test_whip_stick_time(law):
    P = dict(BLACK_WHIP)
    if law == "linear":
        P.update({"loads.torque_law": "linear", "loads.torque_free_speed": 50.0})
    r = cf.black_whip_roots(P)[1]
    m = rs.JeffcottBlack(P)
    Om_start = 10.0
    ts = cf.whip_stick_time(P, r, Om_start)
    assert 0 < ts["t_stick"] < 0.05
    q, v = rs.state_from_keys(m, cf.contact_orbit_state(P, r["w"], Om_start))
    t = np.linspace(0, 0.9 * ts["t_stick"], 10)
    res = rs.simulate(m, q, v, 0.0, 1.0, mode="slip-", switch=False, t_eval=t)
    S = res.samples()
    assert res.termination == "phase end"
    # J Omega' = tau(Omega) - mu R N_w exactly on the orbit: linear in t, or exponential
    if law == "constant":
        Om = Om_start + ts["Omega_rate"] * S["t"]
    else:
        Om = ts["Omega_inf"] + (Om_start - ts["Omega_inf"]) * np.exp(-S["t"] / ts["time_constant"])
    # the orbit is exact from t = 0 and stable, so N = N_w to the integration error (1e-12)
    # and Omega follows to that level; the event time is located to ~1e-15 s by the root finder
    assert np.max(np.abs(S["v"][:, 2] - Om)) <= 1e-10 * Om_start
    assert abs(res.events[0][0] / ts["t_stick"] - 1) <= 1e-9
    # at that instant the rotor rolls: stick is admissible (|F_T| <= mu N at v_t = 0)
    assert res.events[0][1] == "slip- -> stick"


def test_rigid_stator_whip_riccati():
    P = dict(RIGID)
    m = rs.JeffcottBlack(P)
    r = cf.black_whip_roots(P)[0]
    mu = P["contact.mu"]
    w_start = r["w"] * (1 + 1e-6)        # |w| above the root: the whirl runs away (N grows)
    Om_start = 60.0                      # R Omega = 3 m/s: v_t < 0 while |w| < 1.5e4 rad/s
    keys = cf.contact_orbit_state(P, w_start, Om_start)
    q, v = rs.state_from_keys(m, keys)
    t = np.linspace(0, 0.02, 21)
    res = rs.simulate(m, q, v, 0.0, t[-1], mode="slip-", switch=False, t_eval=t)
    S = res.samples()
    _, phid, _ = polar(S, True)
    ex, info = cf.rigid_stator_slip_whirl(m.m_r, m.k_r, m.c_r, mu, w_start, S["t"])
    assert abs(info["w_minus"] / r["w"] - 1) <= 1e-14
    lam = info["growth_rate"]
    assert abs(lam / r["growth_rate"] - 1) <= 1e-14
    # an integration error made at time s (about rtol |w| = 1e-9 rad/s per unit of time) is
    # amplified by e^{lam (t - s)} <= e^{lam t}: the bound is 1e-12 |w| e^{lam t} (measured:
    # 4e-14 |w| e^{lam t}). A growth rate wrong by 1% would miss by 1e-2 lam t |w - w_-|, 25 rad/s.
    assert np.all(np.abs(phid - ex) <= 1e-12 * abs(r["w"]) * np.exp(lam * S["t"]))
    dep = np.abs(phid - r["w"])
    assert dep[-1] > 1e4 * dep[0]          # it leaves (e^{603 x 0.02} = 1.7e5)


# ---------------------------------------------------------------------------------------------
# 6. Unbalance at a prescribed speed (docs/closed-forms.md section 5)
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("P", [UNB, UNB_SPRUNG], ids=["rigid", "sprung"])
def test_unbalance_roots_force_balance(P):
    out = cf.unbalance_full_rub_roots(P, OMEGA_U)
    assert len(out["roots"]) == 2 and all(r["contact"] for r in out["roots"])
    assert out["free_orbit_amplitude"] < P["stator.gap"]   # coexists with the free orbit
    U = P["loads.unbalance"] * OMEGA_U ** 2
    mu, g0, Om = P["contact.mu"], P["stator.gap"], OMEGA_U
    Dr = P["rotor.k"] - P["rotor.mass"] * Om ** 2 + 1j * P["rotor.c"] * Om
    m = rs.JeffcottBlack(P)
    for r in out["roots"]:
        n = 1.0                                            # the frame of the contact direction
        F = (-r["N"] - 1j * mu * r["N"]) * n              # F_T = +mu N since v_t < 0
        ub = U * cmath.exp(1j * r["delta"])                # unbalance force at psi = delta
        zr, zs = r["z_r"], r["z_s"]
        scale = abs(Dr * zr) + U + abs(F)
        assert abs(Dr * zr - F - ub) <= 1e-13 * scale     # rotor: D_r z_r = F + U e^{i psi}
        if not P.get("stator.rigid"):
            Ds = P["stator.k"] - P["stator.mass"] * Om ** 2 + 1j * P["stator.c"] * Om
            assert abs(Ds * zs + F) <= 1e-13 * (abs(Ds * zs) + abs(F))
        assert abs(zr - zs - g0) <= 1e-13 * g0             # on the contact circle, along n
        # the drive torque equals the dissipation per radian (power balance, section 6)
        diss = m.c_r * Om ** 2 * abs(zr) ** 2 + m.c_s * Om ** 2 * abs(zs) ** 2 \
            + mu * r["N"] * (g0 + m.R) * Om
        assert abs(r["tau_d"] * Om / diss - 1) <= 1e-12
        # the simulation's vector field vanishes there (theta prescribed, slip with v_t < 0)
        xi = [r["delta"], Om] + ([] if m.rigid else [zs.real, zs.imag, (1j * Om * zs).real,
                                                      (1j * Om * zs).imag])
        ev, F0 = rs.orbit_eigenvalues(m, "slip-", xi)
        assert np.max(np.abs(F0 / field_scales(m, Om, Om ** 2, presc=True))) <= 1e-12
        stable = max(ev.real) < 0
        assert stable == (r is out["roots"][0])          # the larger N attracts, the other not
        if m.rigid:
            assert r["stable"] == stable
            # rigid stator: lambda^2 + gamma lambda + kappa = 0, gamma = c_r/m_r + 2 mu Omega
            gam = m.c_r / m.m_r + 2 * mu * Om
            assert abs(sum(ev).real + gam) <= 1e-6 * gam


def test_unbalance_stability_rule_rigid_stator():
    """The rule 'stable iff cos delta + mu sin delta > 0, i.e. the larger N' against the
    eigenvalues of the simulation's vector field, over speeds through the resonance (where
    delta crosses pi/2 and a sign error in the rule would show) and several mu and u_b."""
    checked = 0
    for Om in np.linspace(600.0, 2500.0, 20):
        for mu in (0.05, 0.3, 0.8):
            for ub in (1e-4, 4e-4, 2e-3):
                P = dict(UNB, **{"contact.mu": mu, "loads.unbalance": ub, "initial.omega0": Om})
                m = rs.JeffcottBlack(P)
                for k, r in enumerate(cf.unbalance_full_rub_roots(P, Om)["roots"]):
                    if not r["contact"]:
                        continue
                    ev, _ = rs.orbit_eigenvalues(m, "slip-", [r["delta"], Om])
                    # 2x2 Jacobian: det = kappa, trace = -gamma; |kappa| is far from 0 except
                    # at a fold (double root), which the grid does not hit
                    assert r["stable"] == (max(ev.real) < 0) == (k == 0)
                    checked += 1
    assert checked > 60


def test_unbalance_larger_root_attracts_smaller_is_saddle():
    P = UNB
    out = cf.unbalance_full_rub_roots(P, OMEGA_U)
    big, small = out["roots"]
    m = rs.JeffcottBlack(P)
    outcomes = []
    for root, sgn in ((big, 1), (big, -1), (small, 1), (small, -1)):
        q, v = rs.state_from_keys(m, cf.unbalance_orbit_state(P, OMEGA_U, root))
        v[:2] *= 1 + sgn * 1e-4          # whirl slightly faster / slower than the spin
        res = rs.simulate(m, q, v, 0.0, 0.1, mode="slip-", switch=False, t_eval=[0.0, 0.1])
        S = res.samples()
        outcomes.append((res.termination, S["F_N"][-1]))
        assert energy_defect(S) <= 1e-10
    # larger root, both sides: back to it (lambda = -180 1/s: 0.1 s divides the 1e-4 start
    # by e^18; the remaining error is integration-level)
    for term, N in outcomes[:2]:
        assert term == "t_end" and abs(N / big["N"] - 1) <= 1e-9
    # smaller root: one side of the saddle lifts off, the other goes to the larger root
    terms = sorted(o[0] for o in outcomes[2:])
    assert terms == ["lift-off", "t_end"]
    N_end = [N for term, N in outcomes[2:] if term == "t_end"][0]
    assert abs(N_end / big["N"] - 1) <= 1e-6


# ---------------------------------------------------------------------------------------------
# 7. Power balance on steady orbits (docs/closed-forms.md section 6)
# ---------------------------------------------------------------------------------------------

def test_power_balance_closed_forms():
    P = BLACK_ROLL
    for r in cf.black_rolling_roots(P):
        keys = cf.contact_orbit_state(P, r["w"], r["Omega"])
        zr = abs(complex(keys["initial.x_r"], keys["initial.y_r"]))
        zs = abs(complex(keys["initial.x_s"], keys["initial.y_s"]))
        pw = cf.orbit_powers(P, r["w"], zr, zs, r["Omega"], r["torque"], r["F_T"])
        assert pw["v_t"] == pytest.approx(0.0, abs=1e-15 * P["rotor.radius"] * r["Omega"] * 10)
        # tau Omega = dissipation: terms ~tau Omega; rounding of |z|^2 w^2 ~1e-15 relative
        assert abs(pw["sum"]) <= 1e-12 * abs(pw["drive"])
    P = BLACK_WHIP
    for r in cf.black_whip_roots(P):
        keys = cf.contact_orbit_state(P, r["w"], 20.0)
        zr = abs(complex(keys["initial.x_r"], keys["initial.y_r"]))
        zs = abs(complex(keys["initial.x_s"], keys["initial.y_s"]))
        pw = cf.orbit_powers(P, r["w"], zr, zs, 20.0, P["loads.torque"], r["F_T"])
        # in a locked whip the sum is the rate of the spin energy, Omega (tau - mu R N_w)
        rate = 20.0 * (P["loads.torque"] - P["contact.mu"] * P["rotor.radius"] * r["N"])
        assert abs(pw["sum"] - rate) <= 1e-12 * (abs(pw["drive"]) + abs(pw["friction"]))


def test_power_balance_over_a_window():
    """On the converged rolling orbit the works over a window balance: drive = dampers, and
    friction does no work. The window is not a whole number of periods: on a steady orbit
    the powers are constant, the mean over any window is the steady one."""
    P = BLACK_ROLL
    root = cf.black_rolling_roots(P)[0]
    m = rs.JeffcottBlack(P)
    q, v = rs.state_from_keys(m, cf.contact_orbit_state(P, root["w"], root["Omega"]))
    t_end = 0.013
    res = rs.simulate(m, q, v, 0.0, t_end, mode="stick", t_eval=[0.0, t_end])
    S = res.samples()
    Wd, Wc, Wf = S["W"][-1]
    assert Wd == pytest.approx(P["loads.torque"] * root["Omega"] * t_end, rel=1e-10)
    # started exactly on the orbit: the state stays on it to the integration error (1e-12),
    # so the works balance to that relative level; friction: v_t = 0 to rounding (1e-16 m/s)
    assert abs(Wd + Wc) <= 1e-10 * Wd
    assert abs(Wf) <= 1e-12 * Wd
    assert abs(S["E"][-1] - S["E"][0]) <= 1e-10 * Wd
