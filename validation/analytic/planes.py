#!/usr/bin/python3
"""Closed forms of the rigid rotor in contact at several planes, in phase (docs/closed-forms.md,
section 8): the steady orbit on which every plane's contact point rolls (dry-friction whirl at
every plane), the contact forces it takes, and the spin a constant torque settles at.

The model is rubdyn's rigid rotor (docs/models.md, section 0; the paper's eq. 9-16) with
`[[plane]]` tables: q = (x_b, y_b, x_r, y_r, theta, stators...), l = L - delta, nu = d / l,
    M11 = (1-nu)^2 m + Jd/l^2,  M12 = nu (1-nu) m - Jd/l^2,  M22 = nu^2 m + Jd/l^2,  H = Jp/l^2,
plane k at axial distance p_k from the bearing B: its rotor point z_k = (1 - s_k) z_b + s_k z_r,
s_k = p_k / l; its ring on (m_s, k_s, c_s) or fixed. Gravity 0, no unbalance (the orbits are
then exactly circular and steady).

Parameters: a dict with the case keys rotor.mass, rotor.Jd, rotor.Jp, rotor.L, rotor.delta,
rotor.d, bearing.k, bearing.c, and "planes": a list of dicts with position, radius, gap, mu,
stator_mass, stator_k, stator_c, stator_rigid (the [[plane]] keys).

Conventions as in closed_forms.py: z = x + i y; n = e^{i phi} the direction from a ring's centre
to its rotor point; the force of ring k on the rotor is F_k = -(F_N,k + i F_T,k) n;
v_t,k = -g_k phi' - R_k Omega on the contact circle.
"""
import numpy as np

__all__ = ["rotor_terms", "receptance_matrix", "orbit", "rolling", "rolling_speeds",
           "orbit_state", "equation_residual"]


def rotor_terms(p):
    """l, nu, M11, M12, M22, H and each plane's s_k."""
    m, Jd, Jp = p["rotor.mass"], p["rotor.Jd"], p["rotor.Jp"]
    l = p["rotor.L"] - p["rotor.delta"]
    nu = p["rotor.d"] / l
    jl = Jd / (l * l)
    return {"l": l, "nu": nu, "M11": (1 - nu) ** 2 * m + jl, "M12": nu * (1 - nu) * m - jl,
            "M22": nu * nu * m + jl, "H": Jp / (l * l),
            "s": [pl["position"] / l for pl in p["planes"]]}


def _rotor_stiffness(p, w, Omega):
    """The rotor's 2x2 complex dynamic stiffness on (Z_b, Z_r) for an orbit z = Z e^{i w t} at the
    spin Omega: D Z = the complex forces on the rows z_b, z_r (docs/closed-forms.md, 8.1)."""
    t = rotor_terms(p)
    gy = t["H"] * Omega * w
    kb, cb = p["bearing.k"], p["bearing.c"]
    return np.array([[kb + 1j * cb * w - w * w * t["M11"] + gy, -w * w * t["M12"] - gy],
                     [-w * w * t["M12"] - gy, -w * w * t["M22"] + gy]], dtype=complex)


def _stator_compliance(pl, w):
    """1 / D_s(w) of a sprung ring, 0 for a fixed one."""
    if pl.get("stator_rigid", False):
        return 0j
    return 1.0 / (pl["stator_k"] - pl["stator_mass"] * w * w + 1j * pl["stator_c"] * w)


def receptance_matrix(p, w, Omega):
    """Gamma(w, Omega) = A^T D^{-1} A + diag(1 / D_s,k): the receptance across the contacts
    (Black's 1/K for one plane at R on a Jeffcott rotor). A = [a_1 .. a_K], a_k = (1 - s_k, s_k)."""
    t = rotor_terms(p)
    A = np.array([[1 - s for s in t["s"]], t["s"]], dtype=complex)
    C = A.T @ np.linalg.solve(_rotor_stiffness(p, w, Omega), A)
    return C + np.diag([_stator_compliance(pl, w) for pl in p["planes"]])


def orbit(p, w, Omega):
    """The steady orbit with every plane in contact, in phase, whirling at w with the spin Omega:
    contact forces P_k = F_N,k + i F_T,k = -(Gamma^{-1} g)_k, rotor amplitudes Z_b, Z_r, ring
    amplitudes S_k (phase reference: n = 1 at t = 0)."""
    t = rotor_terms(p)
    g = np.array([pl["gap"] for pl in p["planes"]], dtype=complex)
    P = -np.linalg.solve(receptance_matrix(p, w, Omega), g)
    A = np.array([[1 - s for s in t["s"]], t["s"]], dtype=complex)
    Z = -np.linalg.solve(_rotor_stiffness(p, w, Omega), A @ P)
    S = np.array([P[k] * _stator_compliance(pl, w) for k, pl in enumerate(p["planes"])])
    return {"w": w, "Omega": Omega, "P": P, "F_N": P.real, "F_T": P.imag, "Z_b": Z[0],
            "Z_r": Z[1], "S": S}


def rolling(p, Omega):
    """Rolling at every plane: w = -R_k Omega / g_k, the same for all planes (R_k / g_k must be
    equal: in phase, rolling everywhere needs it). Adds the torque the orbit takes,
    sum_k R_k F_T,k (the theta row in steady state), and whether the forces are admissible:
    F_N,k > 0 and |F_T,k| <= mu_k F_N,k at every plane."""
    ratios = [pl["radius"] / pl["gap"] for pl in p["planes"]]
    if max(ratios) - min(ratios) > 1e-12 * max(ratios):
        raise ValueError(f"rolling at every plane in phase needs equal radius / gap: {ratios}")
    w = -ratios[0] * Omega
    o = orbit(p, w, Omega)
    o["torque"] = float(sum(pl["radius"] * o["F_T"][k] for k, pl in enumerate(p["planes"])))
    o["admissible"] = bool(all(o["F_N"][k] > 0 and abs(o["F_T"][k]) <= pl["mu"] * o["F_N"][k]
                               for k, pl in enumerate(p["planes"])))
    return o


def rolling_speeds(p, tau, Omega_lo, Omega_hi, n=4000):
    """The spins Omega in [Omega_lo, Omega_hi] at which the rolling orbit takes the torque tau
    (a constant drive settles there if the orbit is stable): sign changes of
    torque(Omega) - tau on a grid of n points, each refined by bisection to round-off."""
    f = lambda Om: rolling(p, Om)["torque"] - tau  # noqa: E731
    grid = np.linspace(Omega_lo, Omega_hi, n)
    vals = [f(x) for x in grid]
    roots = []
    for a, b, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
        if fa == 0.0:
            roots.append(a)
        if fa * fb >= 0:
            continue
        for _ in range(200):
            c = 0.5 * (a + b)
            fc = f(c)
            if c in (a, b):
                break
            if fa * fc <= 0:
                b, fb = c, fc
            else:
                a, fa = c, fc
        roots.append(0.5 * (a + b))
    return roots


def orbit_state(p, o, theta0=0.0):
    """The orbit's state at t = 0 as rubdyn case keys (initial.*): rotor (x_b, y_b, x_r, y_r),
    spin, each sprung ring's x_s_k, y_s_k (1-based k), velocities i w Z."""
    w = o["w"]
    d = {"initial.theta": theta0, "initial.omega0": o["Omega"]}
    for name, Z in (("b", o["Z_b"]), ("r", o["Z_r"])):
        d[f"initial.x_{name}"] = Z.real
        d[f"initial.y_{name}"] = Z.imag
        d[f"initial.vx_{name}"] = (1j * w * Z).real
        d[f"initial.vy_{name}"] = (1j * w * Z).imag
    for k, pl in enumerate(p["planes"]):
        if pl.get("stator_rigid", False):
            continue
        S = o["S"][k]
        d[f"initial.x_s_{k + 1}"] = S.real
        d[f"initial.y_s_{k + 1}"] = S.imag
        d[f"initial.vx_s_{k + 1}"] = (1j * w * S).real
        d[f"initial.vy_s_{k + 1}"] = (1j * w * S).imag
    return d


def equation_residual(p, o, t):
    """An independent check of the orbit: the rigid rotor's equations of motion in real
    coordinates, written from the Lagrangian (models.md, section 0) rather than from the complex
    derivation, at time t on the orbit:
        M q'' + (Omega G + D) q' + K q - sum_k (W_N,k F_N,k + W_T,k F_T,k) = 0
    (lateral rows x_b, y_b, x_r, y_r and each ring's rows; the theta row: tau - sum R_k F_T,k,
    returned apart), with W_N, W_T of each plane's contact computed from the positions (the gap
    direction n, t = (n_y, -n_x)). Returns (max |lateral residual| / force scale, theta row)."""
    tt = rotor_terms(p)
    w, Om = o["w"], o["Omega"]
    e = np.exp(1j * w * t)
    zb, zr = o["Z_b"] * e, o["Z_r"] * e
    vb, vr = 1j * w * zb, 1j * w * zr
    ab, ar = -w * w * zb, -w * w * zr
    x = np.array([zb.real, zb.imag, zr.real, zr.imag])
    v = np.array([vb.real, vb.imag, vr.real, vr.imag])
    a = np.array([ab.real, ab.imag, ar.real, ar.imag])
    M = np.array([[tt["M11"], 0, tt["M12"], 0], [0, tt["M11"], 0, tt["M12"]],
                  [tt["M12"], 0, tt["M22"], 0], [0, tt["M12"], 0, tt["M22"]]])
    H = tt["H"]
    # gyroscopic forces Omega G v from T_gyro = H/2 theta' (u' w - w' u), u = x_r - x_b,
    # w = y_r - y_b: rows x_b: -H Omega w', y_b: +H Omega u', x_r: +H Omega w', y_r: -H Omega u'
    du, dw = v[2] - v[0], v[3] - v[1]
    gyro = H * Om * np.array([-dw, du, dw, -du])
    K = np.diag([p["bearing.k"], p["bearing.k"], 0, 0])
    D = np.diag([p["bearing.c"], p["bearing.c"], 0, 0])
    res = M @ a + gyro + D @ v + K @ x
    scale = 0.0
    ring_res = []
    for k, pl in enumerate(p["planes"]):
        s = tt["s"][k]
        zk = (1 - s) * zb + s * zr
        zs = o["S"][k] * e
        r = zk - zs
        n = r / abs(r)
        # force on the rotor -F_N n + F_T t, t = (n_y, -n_x) = -i n
        F = -o["F_N"][k] * n + o["F_T"][k] * (-1j * n)
        gen = np.array([(1 - s) * F.real, (1 - s) * F.imag, s * F.real, s * F.imag])
        res -= gen
        scale = max(scale, abs(o["P"][k]))
        if not pl.get("stator_rigid", False):
            acc = -w * w * zs
            vs = 1j * w * zs
            lhs = pl["stator_mass"] * acc + pl["stator_c"] * vs + pl["stator_k"] * zs
            ring_res.append(abs(lhs + F))  # the ring feels -F
        # the orbit's gap: |r| = g_k
        ring_res.append(abs(abs(r) - pl["gap"]) * pl["stator_k"] if not pl.get(
            "stator_rigid", False) else abs(abs(r) - pl["gap"]) * p["bearing.k"])
    theta_row = None
    if "loads.torque" in p:
        theta_row = p["loads.torque"] - sum(pl["radius"] * o["F_T"][k]
                                            for k, pl in enumerate(p["planes"]))
    return max(np.max(np.abs(res)), max(ring_res)) / scale, theta_row


if __name__ == "__main__":
    import json
    import sys
    p = json.load(open(sys.argv[1]))
    Om = float(sys.argv[2])
    o = rolling(p, Om)
    print(json.dumps({k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in o.items()
                      if not isinstance(v, complex)}, default=lambda z: [z.real, z.imag],
                     indent=1))
