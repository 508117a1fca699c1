#!/usr/bin/python3
"""rubdyn's runs against the closed forms of docs/closed-forms.md: one test per closed form,
each a few rubdyn runs (well under 10 s), failing when rubdyn departs from the closed form.

Run through ctest (tests/CMakeLists.txt, which names the CLI), or by hand:
    RUBDYN_CLI=build/rubdyn /usr/bin/python3 -m pytest validation/analytic/test_runs.py
The runs and measurements are those of run.py (rubdyn_runs.py), at its solver setting TIGHT
(rtol 1e-12, atol 1e-15 m); the measured values quoted in the comments are from table.md.

Every test can fail: with RUBDYN_ANALYTIC_PERTURB="key=value" every rubdyn run gets that --set
override while the closed forms keep the nominal parameters (README.md lists the perturbations
tried and what each test then reports).

Where the tolerances come from. The comparisons end on a steady orbit that attracts (or follow
an exact solution through a whole phase), so the difference left is the integration error in
the steady state: CVODES keeps the local error of a step near rtol (1e-12) of the state, and a
mode damped at the rate lambda sums about 1 / (lambda h) steps of it (h the step): 20-50 us
steps and lambda = 37-106 1/s give 200-1500 steps, a relative difference of 1e-10 to 1e-9, which
is what the tolerance ladder of table.md shows (section 4: it falls with rtol, 3e-7 at the
default 1e-10, 4e-10 at 1e-12, 1e-11 at 1e-13 for N on Black's high branch). The bounds below
sit a few times above the measured values and far below the 1e-8 the issue asks for where the
run allows it.
"""
import math
import os
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import closed_forms as cf  # noqa: E402
import rubdyn_runs as rr  # noqa: E402

RUBDYN = os.environ.get("RUBDYN_CLI", os.path.join(rr.ROOT, "build", "rubdyn"))

# ctest names the CLI (RUBDYN_CLI): then it must be there; by hand without it, the tests skip
pytestmark = pytest.mark.skipif("RUBDYN_CLI" not in os.environ and not os.path.isfile(RUBDYN),
                                reason="no rubdyn CLI (set RUBDYN_CLI)")


def q(st, prefix):
    """The study's quantity named prefix, or else the one whose name starts with it (exactly
    one)."""
    found = [x for x in st.quantities if x.name == prefix] or \
        [x for x in st.quantities if x.name.startswith(prefix)]
    assert len(found) == 1, (prefix, [x.name for x in st.quantities])
    return found[0]


def check(st, bounds):
    """Every (prefix, bound) of bounds: the relative difference of that quantity <= bound.
    Collects every failure into one message."""
    bad = []
    for prefix, bound in bounds:
        x = q(st, prefix)
        if not (x.rel is not None and x.rel <= bound):
            bad.append("%s: closed form %r, rubdyn %r, relative difference %s > %g"
                       % (x.name, x.closed, x.measured, x.rel, bound))
    assert not bad, "%s departs from the closed form:\n  %s" % (st.title, "\n  ".join(bad))


# ---- (a) ----------------------------------------------------------------------------------------
def test_rolling_kinematics(tmp_path):
    """phi' = -(R/g0) Omega (1.1) at every stick sample: the paper's rigid rotor (reference.toml,
    mu = 0.25, it rolls from 0.116 s) and a Jeffcott rotor rolling with gravity and an
    unbalance (not steady). R and g0 are the case files' nominal values."""
    rig = rr.study_rolling_rigid_rotor(RUBDYN, str(tmp_path), t_end=0.2)
    jef = rr.study_rolling_jeffcott(RUBDYN, str(tmp_path), t_end=0.1)
    for st, n_min in ((rig, 800), (jef, 1000)):
        assert st.status == "ok", (st.title, st.notes)
        # the run must roll: 0.116-0.2 s is 840 samples of 0.1 ms, the Jeffcott run 1001
        assert st.kin["samples"] >= n_min, (st.title, st.kin["samples"])
        # In the reduced stick chart the identity holds by construction: what is left is the
        # rounding of the samples (17 digits) through r = z_r - z_s (|z| / |r| up to about 5)
        # and the atan2 geometry, measured 6e-16 .. 1e-15. 1e-12 is a thousand times that and
        # a thousand times below the 1e-9 the issue asks for; a wrong R/g0 (a gap or radius
        # off by 1e-9) or a slip of the contact point would exceed it.
        check(st, [("phi' + (R/g0) Omega", 1e-12),
                   # the integrated form, relative to the angle the orbit turned (1e3-1e4 rad):
                   # measured 6e-17 .. 3e-16, the rounding of theta (17 digits) times R/g0
                   ("phi - phi_a + (R/g0)(theta - theta_a)", 1e-13),
                   # on the contact circle: rounding of the chart's embedding (measured 4e-16)
                   ("|r| - g0", 1e-14),
                   ("v_t column", 1e-14)])


# ---- (b) ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("law", ["constant", "linear"])
def test_rigid_stator_rolling(tmp_path, law):
    """Rigid stator, torque-driven rolling from Omega = 10 rad/s: Omega(t) is the exponential
    (2.4) over the whole phase, and the steady spin, whirl, N, F_T and time constant."""
    st = rr.study_rigid_rolling(RUBDYN, str(tmp_path), law)
    assert st.status == "ok", st.notes
    assert set(st.output.phase) == {"stick"}            # rolls throughout, as (2.4) assumes
    check(st, [
        # The phase is one smooth exponential in one coordinate: the global error stays at a
        # few rtol (measured 2e-13 and 2.7e-13 over 30 time constants); 1e-11 leaves room for
        # 50x and is 1e3 below the 1e-8 (the default rtol 1e-10 gives 4e-11 / 1.5e-10:
        # the ladder in table.md).
        ("Omega(t) - exponential", 1e-11),
        # After 30 time constants the exact solution is 0.625 e^-30 = 6e-14 (constant) or
        # 0.375 e^-30 (linear) from the steady state: these are the steady values themselves
        # (measured 3e-14 .. 1.2e-13)
        ("Omega_ss", 1e-11), ("whirl w = phi'", 1e-11), ("N", 1e-11), ("F_T", 1e-11),
        # the polar angle's slope over the last 0.1 s (100 whirl turns; measured 6e-14, 2.6e-13)
        ("whirl w from the polar angle", 1e-11),
        # N = g0 (m_r (R Omega / g0)^2 - k_r) at every sample is exact in rolling (2.1): rounding
        # (measured 1.3e-15)
        ("N(t) - (2.1)", 1e-13),
        # the fitted time constant, from samples whose departure from Omega_ss is above 1e-7
        # of it: the fit inherits the 1e-13 error of the samples over a 1e-7 signal at its
        # tail, 1e-6 worst case, measured 9e-13 / 6e-13 (the signal is mostly far larger)
        ("time constant T_c", 1e-10), ("the same fit's Omega_ss", 1e-11),
    ])
    # the run reaches 1e-8 when the exact solution does: within one output interval
    pred = cf.rolling_rigid_stator_spin(
        *[rr.rigid_params(law)[k] for k in ("rotor.mass", "rotor.c", "rotor.Jp",
                                            "rotor.radius", "loads.torque")],
        rr.OMEGA_START_RIGID, st.output.t, Omega_0=rr.rigid_closed(rr.rigid_params(law))[1])
    x = q(st, "Omega_ss")
    t_ex = rr.time_to_reach(st.output.t, rr.rel(pred, x.closed), 1e-8)
    assert abs(x.t_reach(1e-8) - t_ex) <= 1.01 * rr.DT


# ---- (c) ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("branch", [0, 1], ids=["low", "high"])
def test_black_rolling(tmp_path, branch):
    """Black's model, steady rolling (3.1) on each branch of the bistable set BLACK_ROLL, started
    off the orbit (1e-3 g0 and 1e-3 in r' and the spin): rubdyn returns to the branch it starts
    near, at the rate of the orbit's slowest eigenvalue."""
    st = rr.study_black_rolling(RUBDYN, str(tmp_path), branch)
    assert st.status == "ok", st.notes
    assert set(st.output.phase) == {"stick"}
    # The steady integration error (module docstring): measured 1e-11 .. 1.2e-10 (low branch),
    # 5e-12 .. 3.8e-10 (high); the bound 3e-9 is 8x the largest and 3x below the 1e-8.
    # A wrong branch is O(1) away; a receptance term off by 1e-7 shifts the root by about that.
    check(st, [("Omega", 3e-9), ("whirl w = phi'", 3e-9), ("N", 3e-9), ("F_T", 3e-9),
               ("stator orbit", 3e-9), ("whirl w from the polar angle", 3e-9)])
    # it gets there: within 1e-8 by 0.5 s (measured 0.30 s low, 0.17 s high; the linear
    # estimate ln(3e-3 / 1e-8) / 36.8 1/s = 0.34 s for the slower branch)
    for name in ("Omega", "N"):
        t8 = q(st, name).t_reach(1e-8)
        assert t8 is not None and t8 <= 0.5, (name, t8)
    # at the rate of the slowest eigenvalue of the orbit in its frame, from the independent
    # simulation's vector field (36.76 and 42.11 1/s): measured ratios 0.9998 and 1.003 for
    # Omega. 5 %: the envelope fit over 1e-5 .. 3e-9 still holds a trace of the next modes
    # (71-116 1/s); a rate from a different model (a damping or inertia off by 5 %) fails.
    P = dict(rr.BLACK_ROLL, **{"loads.unbalance": 0.0})
    lam = -max(rr.orbit_eigen(P, st.root, "stick").real)
    x = q(st, "Omega")
    rate = rr.approach_rate(x.t, x.dev)
    assert rate is not None and abs(rate / lam - 1) <= 0.05, (rate, lam)


# ---- (d) ----------------------------------------------------------------------------------------
def test_whip_locked(tmp_path):
    """Whip with frequency locking (4.1)-(4.3), the stable middle root of BLACK_WHIP: started on
    the orbit at 10 rad/s, the locked whirl and N through the slip, Omega linear in t (the
    exponential of the linear torque law), the time it sticks; started off the orbit at 60 rad/s,
    it locks onto the root while the spin falls."""
    for law in ("constant", "linear"):
        ex = rr.study_whip_exact(RUBDYN, str(tmp_path), law=law)
        assert ex.status == "ok", ex.notes
        assert ex.output.first_event("stick") is not None
        # On the orbit from t = 0, in an 18 ms (15 ms, linear law) slip phase: the integration
        # error of 1400 steps, measured 1.4e-11 .. 1.5e-11 (w), 6.8e-11 .. 7.4e-11 (N), 7.2e-11
        # .. 7.9e-11 (stator), 3.1e-11 .. 4.7e-11 (Omega / Omega0); the default rtol gives
        # 4e-8 .. 3e-7. 1e-9: 10x the measured, 10x below the 1e-8.
        # t_stick: the event is where v_t = -g0 phi' - R Omega reaches 0; Omega falls at 209
        # rad/s^2, so an error dOmega moves it by dOmega / 209 s: 4.7e-11 x 10 rad/s / 209 /
        # 0.018 s = 1.2e-10 relative (measured 1.4e-10, 1.1e-10); bound 1e-9.
        check(ex, [("t_stick", 1e-9), ("locked whirl w during the slip", 1e-9),
                   ("N during the slip", 1e-9), ("Omega(t) - ", 1e-9), ("stator orbit", 1e-9)])
    ap = rr.study_whip_approach(RUBDYN, str(tmp_path))
    assert ap.status == "ok", ap.notes
    assert set(ap.output.phase[ap.output.t < 0.25]) == {"slip-"}   # whips until it sticks
    # converged (lambda = -106 1/s: 1e-3 -> 1e-10 in 0.15 s), the steady error: measured
    # 9e-12 (w), 1.3e-10 (N), 1.6e-10 (stator), 5.5e-11 (the spin's rate), 7.6e-11 (t_stick
    # predicted from the state at 0.2 s: the error of N integrated over 58 ms); bound 1e-9
    check(ap, [("locked whirl w", 1e-9), ("N", 1e-9), ("stator orbit", 1e-9),
               ("dOmega/dt", 1e-9), ("t_stick from the state", 1e-9)])
    # the frequency is locked independently of the spin: Omega fell from 60 to 19 rad/s while
    # the whirl stayed within 1e-8 of w (from 0.09 s, measured)
    x = q(ap, "locked whirl w")
    assert x.t_reach(1e-8) is not None and x.t_reach(1e-8) <= 0.12
    om = ap.output.col["omega"]
    assert om[0] - om[np.searchsorted(ap.output.t, 0.2)] > 40.0


# ---- (e) ----------------------------------------------------------------------------------------
def test_unbalance_prescribed_speed(tmp_path):
    """Unbalance at the prescribed 1500 rad/s, rigid stator (UNB): forward synchronous full
    annular rub on the larger root of the quadratic (5.1), which attracts from both sides; the
    smaller root is a saddle (one side lifts off, the other goes to the larger root)."""
    st = rr.study_unbalance(RUBDYN, str(tmp_path))
    assert st.status == "ok", st.notes
    # The larger root attracts at -180 1/s (+-920i): from 1e-4 off, 0.2 s is e^-36, so what is
    # left is the steady integration error: measured 1.0e-11 .. 1.3e-11 (N, F_T, tau_d),
    # 1e-13 .. 1e-12 (w = Omega), 2.2e-10 (delta, 0.34 rad: 7e-11 rad); at the default rtol
    # 3e-8 and 4e-7 (table.md, section 4). Bounds 1e-10 (1e-9 for delta): about 8x the measured.
    # The prescribed speed itself is exact (the spin is not integrated): rounding only.
    bounds = []
    for sgn in ("+", "-"):
        sfx = " (start %s1e-4)" % sgn
        bounds += [("N" + sfx, 1e-10), ("F_T = mu N" + sfx, 1e-10),
                   ("whirl w = phi' = Omega" + sfx, 1e-10), ("delta = psi - phi" + sfx, 1e-9),
                   ("drive torque tau_d" + sfx, 1e-10),
                   ("spin Omega (prescribed)" + sfx, 1e-14)]
    check(st, bounds)
    # at the rate of the orbit's eigenvalues (-180 +- 920i 1/s, from the independent
    # simulation's vector field; measured ratio within 1 %): 5 % as for (c)
    lam = -max(rr.unbalance_eigen(rr.unb_params(), st.roots[0], rr.OMEGA_U).real)
    x = q(st, "N (start +1e-4)")
    rate = rr.approach_rate(x.t, x.dev)
    assert rate is not None and abs(rate / lam - 1) <= 0.05, (rate, lam)
    # which root attracts (5.2): from the smaller root one side lifts off and the other ends
    # on the larger root (N within 1e-6 after 0.2 s: the saddle's unstable rate 774 1/s takes
    # it off in about 30 ms, then -180 1/s)
    outs = st.outs
    lifted = [outs[("smaller", s)].first_event("liftoff") is not None for s in (1, -1)]
    assert sorted(lifted) == [False, True], lifted
    stay = [outs[("smaller", s)] for s, lf in zip((1, -1), lifted) if not lf][0]
    big = st.roots[0]
    assert abs(stay.col["F_N"][-1] / big["N"] - 1) <= 1e-6


# ---- (f) ----------------------------------------------------------------------------------------
def test_power_balance(tmp_path):
    """Over windows of whole whirl periods of converged orbits, the drive's mean power equals
    the mean dissipation, and friction does no work in rolling (section 6): rigid-stator
    rolling, both Black rolling branches, the locked whip (whose spin energy falls:
    drive + dampers + friction = d(J Omega^2 / 2)/dt) and the unbalance's forward rub at a
    prescribed speed (friction takes most of the drive's power)."""
    out = str(tmp_path)
    rig = rr.study_rigid_rolling(RUBDYN, out, "constant")
    rolls = [rr.study_black_rolling(RUBDYN, out, b) for b in (0, 1)]
    whip = rr.study_whip_approach(RUBDYN, out)
    unb = rr.study_unbalance(RUBDYN, out)
    st = rr.study_power(RUBDYN, out, rig, rolls, whip, unb_st=unb)
    assert st.status == "ok", st.notes
    assert unb.status == "ok", unb.notes
    bounds = []
    labels = ["rigid-stator rolling", "Black rolling low", "Black rolling high", "whip"]
    for lab in labels + ["unbalance"]:
        bounds += [
            # the mean drive power against tau Omega of the closed form (whip: tau times the
            # mean of the linear spin): the steady error of Omega, measured <= 1.8e-10
            ("%s: mean drive power" % lab, 1e-9),
            # the dissipation and the energy balance over the window hold to the steady
            # integration error too (the numerical orbit's power defect): measured 1.1e-9 and
            # 1.0e-9 on the low rolling branch (4e-11 .. 2e-10 elsewhere), 9e-8 at rtol 1e-10
            # (table.md, section 4); bound 3e-9
            ("%s: mean dissipation" % lab, 3e-9),
            ("%s: (W_torque + W_damping" % lab, 3e-9),
            # the same balance from the sampled powers (trapezoid on the 0.1 ms grid: the
            # powers are constant on a steady orbit, and linear in t in the whip)
            ("%s: sampled powers" % lab, 3e-9)]
        if lab == "unbalance":
            # forward rub: friction takes 99.8 % of the drive's power (mu N (g0 + R) Omega
            # against tau_d Omega), the rest the rotor's damper; measured 1.1e-12
            bounds += [("unbalance: W_friction / W_torque", 1e-9)]
        elif lab != "whip":
            # rolling: v_t = 0 by construction, so friction's work is rounding (measured 3e-17
            # of the drive's); a slipping contact would give mu N |v_t| / (tau Omega)
            bounds += [("%s: W_friction / W_torque" % lab, 1e-14),
                       ("%s: dE over the window" % lab, 1e-9)]
        else:
            # whip: friction's work -mu N_w (R Omega - g0 |w|) and the spin's energy change,
            # against the closed forms with the steady error (measured 3e-11, 1.7e-10)
            bounds += [("whip: W_friction / W_torque", 1e-9),
                       ("whip: dE over the window", 1e-9)]
    check(st, bounds)
    # rolling and the windows never left stick / slip
    for label, o in st.runs:
        assert len(set(o.phase)) == 1, (label, set(o.phase))
    assert math.isfinite(q(st, "whip: W_friction").measured)
