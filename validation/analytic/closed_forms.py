#!/usr/bin/python3
"""Closed forms of rotor-stator rub for the Jeffcott-Black model (docs/closed-forms.md).

Every function returns plain numbers (dicts of named floats), solved to full double precision:
polynomial equations are solved by numpy.roots on a frequency-scaled polynomial, and every
real root is then polished by Newton's method on the original (rational) equation; the
residual after polishing is returned with each root.

Conventions (docs/models.md, section 4): z = x + i y; r = z_r - z_s = g0 n on the contact
circle, n = e^{i phi}; t = (n_y, -n_x) = -i n; v_t = t . r' - R Omega = -g0 phi' - R Omega on the
circle; the force of the stator on the rotor is -F_N n + F_T t; sliding: F_T = -mu sign(v_t) F_N.
A steady contact orbit whirls at w = phi' (w < 0: backward). Gravity is 0 in every closed form.

Parameters are passed as a dict keyed by rubdyn's case keys:
    rotor.mass m_r, rotor.k k_r, rotor.c c_r, rotor.Jp J, rotor.radius R,
    stator.mass m_s, stator.k k_s, stator.c c_s, stator.gap g0, stator.rigid (bool),
    contact.mu mu, loads.torque tau_a, loads.torque_law ("constant" | "linear"),
    loads.torque_free_speed Omega_0, loads.unbalance u_b, loads.unbalance_phase phi_u.
Keys a function does not need may be absent.
"""
import math

import numpy as np
from numpy.polynomial import polynomial as npoly

__all__ = [
    "short", "dynamic_stiffness", "receptance", "receptance_derivative", "frequencies",
    "rolling_whirl", "rolling_rigid_stator", "rolling_rigid_stator_spin",
    "rolling_rigid_stator_prescribed", "rigid_stator_slip_whirl", "black_rolling_roots",
    "black_whip_roots", "whip_stick_time", "unbalance_full_rub_roots", "contact_orbit_state",
    "unbalance_orbit_state", "orbit_powers",
]


def short(params):
    """The case keys as short names (m_r, k_r, c_r, J, R, m_s, k_s, c_s, g0, mu, rigid, ...)."""
    p = params
    s = {
        "m_r": p.get("rotor.mass"), "k_r": p.get("rotor.k"), "c_r": p.get("rotor.c", 0.0),
        "J": p.get("rotor.Jp"), "R": p.get("rotor.radius"), "g0": p.get("stator.gap"),
        "rigid": bool(p.get("stator.rigid", False)),
        "m_s": p.get("stator.mass"), "k_s": p.get("stator.k"), "c_s": p.get("stator.c", 0.0),
        "mu": p.get("contact.mu"), "tau": p.get("loads.torque"),
        "torque_law": p.get("loads.torque_law", "constant"),
        "Omega_0": p.get("loads.torque_free_speed"),
        "u_b": p.get("loads.unbalance", 0.0), "phi_u": p.get("loads.unbalance_phase", 0.0),
    }
    return s


def dynamic_stiffness(m, k, c, w):
    """D(w) = k - m w^2 + i c w: the complex force per unit complex displacement of a circular
    orbit z = A e^{i w t} of a mass-spring-damper (w may be an array)."""
    return k - m * w * w + 1j * c * w


def _num_den(s):
    """K = num / den as complex polynomials in w (ascending coefficients)."""
    Dr = np.array([s["k_r"], 1j * s["c_r"], -s["m_r"]], dtype=complex)
    if s["rigid"]:
        return Dr, np.array([1.0 + 0j])
    Ds = np.array([s["k_s"], 1j * s["c_s"], -s["m_s"]], dtype=complex)
    return npoly.polymul(Dr, Ds), npoly.polyadd(Dr, Ds)


def receptance(params, w):
    """Black's combined dynamic stiffness K(w) = D_r D_s / (D_r + D_s) (D_r for a rigid
    stator). On a steady contact orbit, the force of the stator on the rotor is K(w) r."""
    s = short(params)
    Dr = dynamic_stiffness(s["m_r"], s["k_r"], s["c_r"], w)
    if s["rigid"]:
        return Dr
    Ds = dynamic_stiffness(s["m_s"], s["k_s"], s["c_s"], w)
    return Dr * Ds / (Dr + Ds)


def receptance_derivative(params, w):
    """dK/dw (K is holomorphic in w: d Im K / dw = Im dK/dw for real w)."""
    s = short(params)
    Dr = dynamic_stiffness(s["m_r"], s["k_r"], s["c_r"], w)
    dDr = -2 * s["m_r"] * w + 1j * s["c_r"]
    if s["rigid"]:
        return dDr
    Ds = dynamic_stiffness(s["m_s"], s["k_s"], s["c_s"], w)
    dDs = -2 * s["m_s"] * w + 1j * s["c_s"]
    K = Dr * Ds / (Dr + Ds)
    return K * K * (dDr / (Dr * Dr) + dDs / (Ds * Ds))


def frequencies(params):
    """Undamped reference frequencies [rad/s]: rotor w_r = sqrt(k_r/m_r), stator w_s, and the
    pinned rotor-stator frequency w_c = sqrt((k_r + k_s)/(m_r + m_s)) (pole of K)."""
    s = short(params)
    f = {"w_r": math.sqrt(s["k_r"] / s["m_r"])}
    if not s["rigid"]:
        f["w_s"] = math.sqrt(s["k_s"] / s["m_s"])
        f["w_c"] = math.sqrt((s["k_r"] + s["k_s"]) / (s["m_r"] + s["m_s"]))
    return f


def _band(params, w):
    f = frequencies(params)
    a = abs(w)
    if "w_s" not in f:
        return "above w_r" if a > f["w_r"] else "below w_r"
    lo, hi = min(f["w_r"], f["w_s"]), max(f["w_r"], f["w_s"])
    if a < lo:
        return "below min(w_r, w_s)"
    if a < f["w_c"]:
        return "low: between min(w_r, w_s) and w_c"
    if a < hi:
        return "between w_c and max(w_r, w_s)"
    return "high: above max(w_r, w_s)"


def _real_roots(coef, scale):
    """Real roots of the real polynomial sum coef[n] w^n, found on w = scale x."""
    c = np.array([cn * scale ** n for n, cn in enumerate(coef)], dtype=float)
    while len(c) > 1 and abs(c[-1]) <= 1e-14 * np.max(np.abs(c)):
        c = c[:-1]  # a structurally vanishing leading coefficient (round-off only)
    if len(c) < 2:
        return []
    x = np.roots(c[::-1])
    return [scale * xi.real for xi in x if abs(xi.imag) <= 1e-6 * max(1.0, abs(xi))]


def _newton(g, dg, w, iters=50):
    """Newton polish of a root of g; stops when the step is below 1e-16 |w| or stalls."""
    for _ in range(iters):
        d = dg(w)
        if d == 0:
            break
        step = g(w) / d
        w -= step
        if abs(step) <= 4e-16 * abs(w):
            break
    return w


# ---------------------------------------------------------------------------------------------
# Rolling kinematics and the rigid stator
# ---------------------------------------------------------------------------------------------

def rolling_whirl(R, g0, Omega):
    """Whirl speed of rolling without slip: phi' = -(R / g0) Omega (from v_t = -g0 phi' -
    R Omega = 0)."""
    return -(R / g0) * Omega


def rolling_rigid_stator(m_r, k_r, c_r, J, R, g0, tau, Omega_0=None, mu=None):
    """Torque-driven rolling inside a rigid stator (u_b = 0, g = 0).

    Reduced equation (docs/closed-forms.md, section 2): (J + m_r R^2) Omega' + c_r R^2 Omega =
    tau(Omega). Constant torque (Omega_0 None): Omega_ss = tau / (c_r R^2), time constant
    (J + m_r R^2) / (c_r R^2). Linear law tau = tau_a (1 - Omega / Omega_0): Omega_ss =
    tau_a / (c_r R^2 + tau_a / Omega_0), time constant (J + m_r R^2) / (c_r R^2 + tau_a / Omega_0).
    Steady whirl w = -(R/g0) Omega_ss, normal force N = g0 (m_r w^2 - k_r), friction force
    F_T = tau(Omega_ss) / R = c_r R Omega_ss (stator on rotor along t = -i n)."""
    Ie = J + m_r * R * R
    damp = c_r * R * R + (0.0 if Omega_0 is None else tau / Omega_0)
    Om = tau / damp
    w = rolling_whirl(R, g0, Om)
    N = g0 * (m_r * w * w - k_r)
    FT = c_r * R * Om
    out = {"Omega": Om, "w": w, "N": N, "F_T": FT, "time_constant": Ie / damp,
           "effective_inertia": Ie, "torque": tau * (1 - (0 if Omega_0 is None else Om / Omega_0)),
           "Omega_min_contact": (g0 / R) * math.sqrt(k_r / m_r)}
    if mu is not None:
        out["stick_margin"] = mu * N - abs(FT)  # >= 0: rolling admissible at the steady state
    return out


def rolling_rigid_stator_spin(m_r, c_r, J, R, tau, Omega_start, t, Omega_0=None):
    """Omega(t) in rolling from Omega(0) = Omega_start (exact exponential, rigid stator, g = 0)."""
    Ie = J + m_r * R * R
    damp = c_r * R * R + (0.0 if Omega_0 is None else tau / Omega_0)
    Om = tau / damp
    return Om + (Omega_start - Om) * np.exp(-np.asarray(t, dtype=float) * damp / Ie)


def rolling_rigid_stator_prescribed(m_r, k_r, c_r, J, R, g0, omega0, alpha, t):
    """Rolling inside a rigid stator with the spin prescribed, Omega(t) = omega0 + alpha t
    (t measured from t_start; u_b = 0, g = 0): the drive torque that holds it,
    tau_d = (J + m_r R^2) alpha + c_r R^2 Omega, the friction force F_T = m_r R alpha +
    c_r R Omega and N = g0 (m_r w^2 - k_r) with w = -(R/g0) Omega."""
    Om = omega0 + alpha * np.asarray(t, dtype=float)
    w = rolling_whirl(R, g0, Om)
    return {"Omega": Om, "w": w, "N": g0 * (m_r * w * w - k_r),
            "F_T": m_r * R * alpha + c_r * R * Om,
            "tau_d": (J + m_r * R * R) * alpha + c_r * R * R * Om}


# ---------------------------------------------------------------------------------------------
# Black's model: rolling (dry whirl) and whip (backward slip)
# ---------------------------------------------------------------------------------------------

def _orbit_forces(params, w):
    K = receptance(params, w)
    g0 = params["stator.gap"]
    return K, -g0 * K.real, -g0 * K.imag  # K, N, F_T (F_T along t = -i n, stator on rotor)


def black_rolling_roots(params, tau=None):
    """Every steady rolling orbit (torque-driven spin, u_b = 0, g = 0).

    Rolling ties w = -(R/g0) Omega; the spin balance 0 = tau(Omega) - R F_T with
    F_T = -g0 Im K(w) gives Im K(w) = -tau(Omega) / (R g0). With tau(Omega) = tau_a (constant)
    or tau_a (1 - Omega / Omega_0) (loads.torque_law = "linear") this is a polynomial equation
    of degree <= 5 in w (times |D_r + D_s|^2). Returns every real root as a dict: w, Omega, N,
    F_T, ratio F_T / N, band label, contact (N > 0), stick (|F_T| <= mu N, if contact.mu is
    given), residual |Im K + tau/(R g0)| / (tau/(R g0)) after Newton polishing. Sorted by |w|."""
    s = short(params)
    tau_a = s["tau"] if tau is None else tau
    R, g0 = s["R"], s["g0"]
    linear = s["torque_law"] == "linear"
    Om0 = s["Omega_0"]
    num, den = _num_den(s)
    P = npoly.polymul(num, np.conj(den))   # K = P / |den|^2 for real w
    Q = npoly.polymul(den, np.conj(den)).real
    # tau(w) / (R g0) as a polynomial in w (Omega = -(g0/R) w)
    tl = np.array([tau_a / (R * g0)] + ([tau_a / (R * g0) * g0 / (R * Om0)] if linear else []))
    coef = npoly.polyadd(P.imag, npoly.polymul(tl, Q))
    scale = frequencies(params)["w_r"]

    def taus(w):
        Om = -(g0 / R) * w
        return tau_a * (1 - Om / Om0) if linear else tau_a

    def g(w):
        return receptance(params, w).imag + taus(w) / (R * g0)

    def dg(w):
        return receptance_derivative(params, w).imag + (
            tau_a * g0 / (R * Om0) / (R * g0) if linear else 0.0)

    roots = []
    for w in sorted(_real_roots(coef, scale), key=abs):
        w = _newton(g, dg, w)
        K, N, FT = _orbit_forces(params, w)
        ref = abs(taus(w)) / (R * g0)
        r = {"w": w, "Omega": -(g0 / R) * w, "N": N, "F_T": FT,
             "ratio": FT / N if N != 0 else math.inf, "band": _band(params, w),
             "contact": N > 0, "torque": taus(w),
             "residual": abs(g(w)) / ref if ref > 0 else abs(g(w))}
        if s["mu"] is not None:
            r["stick"] = bool(N > 0 and abs(FT) <= s["mu"] * N)
        roots.append(r)
    return _dedupe(roots)


def _dedupe(roots):
    out = []
    for r in roots:
        if not any(abs(r["w"] - o["w"]) <= 1e-10 * abs(o["w"]) for o in out):
            out.append(r)
    return out


def black_whip_roots(params, mu=None):
    """Every steady whip orbit (backward whirl with slip, v_t < 0, F_T = +mu N; u_b = 0, g = 0).

    F_T = -g0 Im K(w), N = -g0 Re K(w) and F_T = mu N give Im K(w) = mu Re K(w): a polynomial
    equation of degree <= 6 in w, independent of the spin. Returns every real root with w < 0
    and N > 0 as a dict: w, N, F_T, Omega_stick = g0 |w| / R (below this spin the slip would
    reverse: v_t = g0 |w| - R Omega), band, residual |Im K - mu Re K| / |K| after polishing.
    For a rigid stator the one root is w = -(c_r + sqrt(c_r^2 + 4 mu^2 m_r k_r)) / (2 mu m_r) and
    its growth rate in the contact dynamics is sqrt(c_r^2 + 4 mu^2 m_r k_r) / m_r > 0 (unstable,
    docs/closed-forms.md, section 4)."""
    s = short(params)
    mu = s["mu"] if mu is None else mu
    num, den = _num_den(s)
    P = npoly.polymul(num, np.conj(den))
    coef = (P * (1 - 1j * mu)).imag          # Im[(1 - i mu) K] |den|^2 = Im K - mu Re K
    scale = frequencies(params)["w_r"]

    def g(w):
        K = receptance(params, w)
        return K.imag - mu * K.real

    def dg(w):
        d = receptance_derivative(params, w)
        return d.imag - mu * d.real

    roots = []
    for w in sorted(_real_roots(coef, scale), key=abs):
        w = _newton(g, dg, w)
        K, N, FT = _orbit_forces(params, w)
        if not (w < 0 and N > 0):
            continue
        r = {"w": w, "N": N, "F_T": FT, "Omega_stick": s["g0"] * abs(w) / s["R"],
             "band": _band(params, w), "residual": abs(g(w)) / abs(K)}
        if s["rigid"]:
            disc = math.sqrt(s["c_r"] ** 2 + 4 * mu * mu * s["m_r"] * s["k_r"])
            r["growth_rate"] = disc / s["m_r"]
        roots.append(r)
    return _dedupe(roots)


def rigid_stator_slip_whirl(m_r, k_r, c_r, mu, w_start, t):
    """Whirl speed w(t) = phi'(t) of backward slip (v_t < 0, F_T = +mu N) in a rigid stator
    (u_b = 0, g = 0). The tangential equation m_r w' = -c_r w - mu m_r w^2 + mu k_r is a Riccati
    equation with the constant roots w_-, w_+ (w_- < 0 < w_+); its solution is
        (w - w_-) / (w - w_+) = C e^{lambda t},  lambda = mu (w_+ - w_-) = sqrt(c_r^2 +
        4 mu^2 m_r k_r) / m_r,
    valid while N = g0 (m_r w^2 - k_r) > 0 and v_t = -g0 w - R Omega < 0. Independent of Omega."""
    disc = math.sqrt(c_r * c_r + 4 * mu * mu * m_r * k_r)
    wm = -(c_r + disc) / (2 * mu * m_r)
    wp = (2 * mu * k_r) / (c_r + disc)          # = (-c_r + disc) / (2 mu m_r), no cancellation
    lam = disc / m_r
    C = (w_start - wm) / (w_start - wp)
    E = C * np.exp(lam * np.asarray(t, dtype=float))
    return (wm - wp * E) / (1 - E), {"w_minus": wm, "w_plus": wp, "growth_rate": lam}


def whip_stick_time(params, root, Omega_start, tau=None, mu=None):
    """Time for a locked whip (u_b = 0, g = 0) to reach v_t = 0. In whip F_T = mu N_w is
    constant, so J Omega' = tau(Omega) - mu R N_w exactly. Constant torque: Omega is linear in
    t; linear law: Omega relaxes exponentially to Omega_0 (1 - mu R N_w / tau_a) with time
    constant J Omega_0 / tau_a. Returns {"t_stick", "Omega_rate" (constant law)} with t_stick =
    inf when Omega never reaches Omega_stick = g0 |w| / R (and v_t stays < 0)."""
    s = short(params)
    tau_a = s["tau"] if tau is None else tau
    mu = s["mu"] if mu is None else mu
    J, R, Nw, Ost = s["J"], s["R"], root["N"], root["Omega_stick"]
    if s["torque_law"] == "linear":
        Of = s["Omega_0"]
        Oinf = Of * (1 - mu * R * Nw / tau_a)
        Tc = J * Of / tau_a
        ratio = (Ost - Oinf) / (Omega_start - Oinf)
        t = -Tc * math.log(ratio) if 0 < ratio < 1 else math.inf
        return {"t_stick": t, "Omega_inf": Oinf, "time_constant": Tc}
    rate = (tau_a - mu * R * Nw) / J
    t = (Ost - Omega_start) / rate if rate != 0 else math.inf
    return {"t_stick": t if t >= 0 else math.inf, "Omega_rate": rate}


# ---------------------------------------------------------------------------------------------
# Unbalance at a prescribed constant speed: forward synchronous full annular rub
# ---------------------------------------------------------------------------------------------

def unbalance_full_rub_roots(params, Omega, u_b=None, mu=None):
    """Forward synchronous full annular rub at a prescribed constant speed Omega > 0 (g = 0).

    The orbit whirls with the spin (phi' = Omega), so v_t = -(g0 + R) Omega < 0 and F_T = +mu N.
    With U = u_b Omega^2 and K = K(Omega), the force balance gives
        [g0 Re K + N]^2 + [g0 Im K + mu N]^2 = U^2 |D_s / (D_r + D_s)|^2,
    for a rigid stator (K = D_r, right side U^2)
        [g0 (k_r - m_r Omega^2) + N]^2 + [g0 c_r Omega + mu N]^2 = (u_b Omega^2)^2,
    a quadratic in N. Returns its real roots (larger first) as dicts: N, F_T = mu N, delta =
    psi - phi (angle from the contact direction n to the unbalance, psi = theta + phi_u), tau_d
    (the drive torque that holds the speed), contact (N > 0), residual (of the quadratic,
    relative to its right side), and for a rigid stator 'stable': True for a node/focus of the
    contact dynamics (cos delta + mu sin delta > 0; it is always the larger root), False for a
    saddle. Also the amplitude of the free (contact-less) unbalance orbit of the rotor."""
    s = short(params)
    u_b = s["u_b"] if u_b is None else u_b
    mu = s["mu"] if mu is None else mu
    g0, R = s["g0"], s["R"]
    U = u_b * Omega * Omega
    K = receptance(params, Omega)
    Dr = dynamic_stiffness(s["m_r"], s["k_r"], s["c_r"], Omega)
    if s["rigid"]:
        rhs = U * U
        Ds = None
        free = U / abs(Dr)
    else:
        Ds = dynamic_stiffness(s["m_s"], s["k_s"], s["c_s"], Omega)
        rhs = (U * abs(Ds / (Dr + Ds))) ** 2
        free = U / abs(Dr)  # rotor orbit amplitude without contact (the stator stays at rest)
    a, b = g0 * K.real, g0 * K.imag
    # (1 + mu^2) N^2 + 2 (a + mu b) N + (a^2 + b^2 - rhs) = 0
    A2, A1, A0 = 1 + mu * mu, 2 * (a + mu * b), a * a + b * b - rhs
    disc = A1 * A1 - 4 * A2 * A0
    out = {"roots": [], "free_orbit_amplitude": free, "K": K}
    if disc < 0:
        return out
    sq = math.sqrt(disc)
    q = -0.5 * (A1 + math.copysign(sq, A1))   # no cancellation
    cand = sorted({q / A2, A0 / q} if q != 0 else {0.0}, reverse=True)

    def res(N):
        return ((a + N) ** 2 + (b + mu * N) ** 2 - rhs) / rhs

    for N in cand:
        for _ in range(3):  # Newton on the quadratic itself (one step is usually enough)
            d = 2 * (a + N) + 2 * mu * (b + mu * N)
            if d == 0:
                break
            N -= ((a + N) ** 2 + (b + mu * N) ** 2 - rhs) / d
        F = -N * (1 + 1j * mu)                # stator on rotor, in units of n
        # contact direction relative to the unbalance: e^{i delta} = D_r (g0 - F/K) / U
        e = Dr * (g0 - F / K) / U
        delta = math.atan2(e.imag, e.real)
        zr = (F + U * np.exp(1j * delta)) / Dr   # rotor centre, in the frame of n (phi = 0)
        zs = 0j if s["rigid"] else -F / Ds
        tau_d = u_b * (-(Omega ** 2) * zr * np.exp(-1j * delta)).imag + R * mu * N
        r = {"N": N, "F_T": mu * N, "delta": delta, "tau_d": tau_d, "contact": N > 0,
             "residual": abs(res(N)), "phase_residual": abs(abs(e) - 1.0),
             "z_r": complex(zr), "z_s": complex(zs)}
        if s["rigid"]:
            r["stable"] = bool(math.cos(delta) + mu * math.sin(delta) > 0)
        out["roots"].append(r)
    return out


# ---------------------------------------------------------------------------------------------
# Initial states on the steady orbits, as rubdyn case keys
# ---------------------------------------------------------------------------------------------

def _state_keys(params, zr, zs, w, Omega, theta):
    d = {"initial.x_r": zr.real, "initial.y_r": zr.imag, "initial.theta": theta,
         "initial.vx_r": (1j * w * zr).real, "initial.vy_r": (1j * w * zr).imag,
         "initial.omega0": Omega}
    if not short(params)["rigid"]:
        d.update({"initial.x_s": zs.real, "initial.y_s": zs.imag,
                  "initial.vx_s": (1j * w * zs).real, "initial.vy_s": (1j * w * zs).imag})
    return d


def contact_orbit_state(params, w, Omega, phi0=0.0, theta0=0.0):
    """State on the steady contact orbit of whirl speed w (u_b = 0, g = 0) with the contact
    direction at polar angle phi0: r = g0 e^{i phi0}, force on the rotor F = K(w) r, rotor
    z_r = F / D_r(w), stator z_s = -F / D_s(w) (0 if rigid), velocities i w z. Omega is the
    spin: -(g0/R) w for rolling, anything with R Omega > g0 |w| for a backward whip. Returns
    the rubdyn case keys initial.* (no stator keys for a rigid stator)."""
    s = short(params)
    r = s["g0"] * np.exp(1j * phi0)
    if s["rigid"]:
        zr, zs = r, 0j
    else:
        F = receptance(params, w) * r
        zr = F / dynamic_stiffness(s["m_r"], s["k_r"], s["c_r"], w)
        zs = -F / dynamic_stiffness(s["m_s"], s["k_s"], s["c_s"], w)
        zr = zs + r  # exact on the circle (equal to F / D_r up to round-off)
    return _state_keys(params, complex(zr), complex(zs), w, Omega, theta0)


def unbalance_orbit_state(params, Omega, root, theta0=0.0):
    """State at t_start on the forward synchronous rub orbit `root` (one of
    unbalance_full_rub_roots(...)["roots"]) with the spin angle theta0: the unbalance is at
    psi0 = theta0 + phi_u and the contact direction at phi0 = psi0 - delta."""
    s = short(params)
    phi0 = theta0 + s["phi_u"] - root["delta"]
    rot = np.exp(1j * phi0)
    zs = root["z_s"] * rot
    zr = zs + s["g0"] * rot
    return _state_keys(params, complex(zr), complex(zs), Omega, Omega, theta0)


def orbit_powers(params, w, zr_amp, zs_amp, Omega, drive_torque, F_T):
    """Powers on a steady circular orbit (mean = instantaneous): drive tau Omega, dampers
    -c_r w^2 |z_r|^2 - c_s w^2 |z_s|^2, friction F_T v_t with v_t = -g0 w - R Omega. Their sum is
    zero on every steady orbit with a constant spin (docs/closed-forms.md, section 6)."""
    s = short(params)
    P_drive = drive_torque * Omega
    P_damp = -s["c_r"] * (w * zr_amp) ** 2 - (0.0 if s["rigid"] else s["c_s"] * (w * zs_amp) ** 2)
    v_t = -s["g0"] * w - s["R"] * Omega
    P_fric = F_T * v_t
    return {"drive": P_drive, "dampers": P_damp, "friction": P_fric, "v_t": v_t,
            "sum": P_drive + P_damp + P_fric}


def _main(argv):
    """closed_forms.py key=value ... [Omega=...]: prints, as JSON, every closed form that the
    given case keys allow (rolling / whip roots with a torque; the unbalance's rub roots with
    loads.unbalance and Omega, the prescribed speed)."""
    import json
    params, Omega = {}, None
    for a in argv:
        k, _, v = a.partition("=")
        val = {"true": True, "false": False}.get(v.lower(), v)
        if isinstance(val, str):
            try:
                val = float(val)
            except ValueError:
                pass
        if k == "Omega":
            Omega = val
        else:
            params[k] = val
    s = short(params)
    out = {"frequencies": frequencies(params)}
    if s["tau"] is not None:
        if s["rigid"] and s["torque_law"] == "constant":
            out["rolling_rigid_stator"] = rolling_rigid_stator(
                s["m_r"], s["k_r"], s["c_r"], s["J"], s["R"], s["g0"], s["tau"], mu=s["mu"])
        out["rolling_roots"] = black_rolling_roots(params)
    if s["mu"] is not None:
        out["whip_roots"] = black_whip_roots(params)
    if Omega is not None and s["u_b"]:
        rub = unbalance_full_rub_roots(params, Omega)
        out["unbalance_rub"] = {"roots": rub["roots"],
                                "free_orbit_amplitude": rub["free_orbit_amplitude"]}

    def plain(x):
        if isinstance(x, complex):
            return [x.real, x.imag]
        if isinstance(x, np.generic):
            return x.item()
        raise TypeError(type(x))
    print(json.dumps(out, indent=1, default=plain))


if __name__ == "__main__":
    import sys
    _main(sys.argv[1:])
