#!/usr/bin/python3
"""Independent simulation of the planar Jeffcott-Black model in permanent contact.

Written from the derivation of docs/models.md (sections 1, 3, 4), not from rubdyn's code. The
model: rotor centre z_r (mass m_r, spring k_r, damper c_r to ground), spin angle theta, polar
inertia J about the geometric centre, unbalance u_b at psi = theta + phi_u; stator z_s (m_s, k_s,
c_s) or rigid (z_s = 0); gravity g along -Y. q = (x_r, y_r, theta, x_s, y_s) (or (x_r, y_r, theta))
and M(q) q'' = f(t, q, v) + W_N F_N + W_T F_T.

Only contact phases are integrated: the gap stays closed, |z_r - z_s| = g0. Each phase is an
ODE in minimal coordinates of the chart s = (phi, theta, x_s, y_s), z_r = z_s + g0 e^{i phi}:
    slip (v_t != 0, F_T = -mu sign(v_t) F_N): p = (phi, theta, x_s, y_s)
    stick (v_t = 0, rolling):                   p = (theta - theta_a, x_s, y_s),
                                                phi = phi_a - (R/g0)(theta - theta_a)
with theta removed from p when the spin is prescribed (theta(t) = theta0 + omega0 (t - t_start)
+ alpha (t - t_start)^2 / 2) and the stator coordinates removed when it is rigid. With
s = S p + s0(t) (S constant), q = Q(s), v = Jq(s) s', a = Jq s'' + cq(s, s'), the unknowns
(p'', F_N, [F_T in stick], [tau_d when prescribed]) solve the square linear system
    M Jq S p'' - (W_N - mu sigma W_T) F_N            = f - M (Jq s2 + cq)   (slip, sigma = sign v_t)
    M Jq S p'' - W_N F_N - W_T F_T                   = f - M (Jq s2 + cq)   (stick)
(minus e_theta tau_d on the left when the spin is prescribed). No constraint is enforced
numerically: it holds by construction. The state carries the works of the drive, the dampers
and friction, so that E(t) - E(t0) = W(t) checks the integration.

Integration: scipy's DOP853 (rtol 1e-12 by default). A run is a sequence of phases: a slip phase
ends when v_t reaches 0 (then stick if |F_T| <= mu F_N there, else reversed slip), a stick phase
when |F_T| reaches mu F_N (then slip in the direction of F_T's push), any phase when F_N reaches
0 (lift-off: the run stops, free flight is not modelled here).
"""
import math

import numpy as np
from scipy.integrate import solve_ivp


class JeffcottBlack:
    """The model's M(q), f(t, q, v), contact kinematics and energy, from case keys."""

    def __init__(self, params):
        p = dict(params)
        self.m_r, self.k_r = p["rotor.mass"], p["rotor.k"]
        self.c_r, self.J, self.R = p.get("rotor.c", 0.0), p["rotor.Jp"], p["rotor.radius"]
        self.rigid = bool(p.get("stator.rigid", False))
        self.m_s = 0.0 if self.rigid else p["stator.mass"]
        self.k_s = 0.0 if self.rigid else p["stator.k"]
        self.c_s = 0.0 if self.rigid else p.get("stator.c", 0.0)
        self.g0, self.mu = p["stator.gap"], p.get("contact.mu", 0.0)
        self.g = p.get("loads.gravity", 0.0)    # 0 unless given (the closed forms need 0)
        self.u_b, self.phi_u = p.get("loads.unbalance", 0.0), p.get("loads.unbalance_phase", 0.0)
        self.spin = p.get("loads.spin", "torque")
        self.tau_a = p.get("loads.torque", 0.0)
        self.law = p.get("loads.torque_law", "constant")
        self.Omega_0 = p.get("loads.torque_free_speed")
        self.alpha = p.get("loads.spin_accel", 0.0)
        self.t_start = p.get("run.t_start", 0.0)
        self.theta_start = p.get("initial.theta", 0.0)
        self.omega_start = p.get("initial.omega0", 0.0)
        self.n = 3 if self.rigid else 5
        if self.spin not in ("torque", "prescribed") or self.law not in ("constant", "linear"):
            raise ValueError("loads.spin or loads.torque_law not understood")
        if self.J <= self.u_b ** 2 / self.m_r:
            raise ValueError("rotor.Jp must exceed loads.unbalance^2 / rotor.mass (J_G > 0)")

    # drive -------------------------------------------------------------------------------
    def torque(self, Omega):
        """tau(Omega): constant tau_a, or the turbine line tau_a (1 - Omega / Omega_0)."""
        if self.law == "linear":
            return self.tau_a * (1.0 - Omega / self.Omega_0)
        return self.tau_a

    def prescribed(self, t):
        """theta(t), Omega(t), alpha of the prescribed spin."""
        dt = t - self.t_start
        return (self.theta_start + self.omega_start * dt + 0.5 * self.alpha * dt * dt,
                self.omega_start + self.alpha * dt, self.alpha)

    # Lagrangian mechanics -------------------------------------------------------------------
    def mass_matrix(self, q):
        psi = q[2] + self.phi_u
        M = np.diag([self.m_r, self.m_r, self.J] + ([] if self.rigid else [self.m_s, self.m_s]))
        M[0, 2] = M[2, 0] = -self.u_b * math.sin(psi)
        M[1, 2] = M[2, 1] = self.u_b * math.cos(psi)
        return M

    def smooth_forces(self, t, q, v, drive=True):
        """f of M q'' = f + W_N F_N + W_T F_T; with drive=False the drive torque is left out."""
        psi, Om = q[2] + self.phi_u, v[2]
        cb = self.u_b * Om * Om
        f = np.empty(self.n)
        f[0] = -self.c_r * v[0] - self.k_r * q[0] + cb * math.cos(psi)
        f[1] = -self.c_r * v[1] - self.k_r * q[1] - self.m_r * self.g + cb * math.sin(psi)
        f[2] = -self.u_b * self.g * math.cos(psi) + (
            self.torque(Om) if (drive and self.spin == "torque") else 0.0)
        if not self.rigid:
            f[3] = -self.c_s * v[3] - self.k_s * q[3]
            f[4] = -self.c_s * v[4] - self.k_s * q[4] - self.m_s * self.g
        return f

    def contact(self, q, v):
        """d_N, W_N, W_T, v_N, v_t (n from the stator centre to the rotor, t = (n_y, -n_x))."""
        rx, ry = q[0] - (0 if self.rigid else q[3]), q[1] - (0 if self.rigid else q[4])
        rho = math.hypot(rx, ry)
        nx, ny = rx / rho, ry / rho
        tx, ty = ny, -nx
        WN = np.zeros(self.n)
        WT = np.zeros(self.n)
        WN[:2] = (-nx, -ny)
        WT[:3] = (tx, ty, -self.R)
        if not self.rigid:
            WN[3:] = (nx, ny)
            WT[3:] = (-tx, -ty)
        return self.g0 - rho, WN, WT, WN @ v, WT @ v

    def energy(self, q, v):
        """T + V (T the full kinetic energy, with the spin, also when it is prescribed)."""
        T = 0.5 * v @ self.mass_matrix(q) @ v
        V = 0.5 * self.k_r * (q[0] ** 2 + q[1] ** 2) + self.g * (
            self.m_r * q[1] + self.u_b * math.sin(q[2] + self.phi_u))
        if not self.rigid:
            V += 0.5 * self.k_s * (q[3] ** 2 + q[4] ** 2) + self.g * self.m_s * q[4]
        return T + V

    def damper_power(self, v):
        P = -self.c_r * (v[0] ** 2 + v[1] ** 2)
        if not self.rigid:
            P -= self.c_s * (v[3] ** 2 + v[4] ** 2)
        return P


class Phase:
    """One contact phase: mode 'stick', 'slip-' (v_t < 0, F_T = +mu F_N) or 'slip+'
    (v_t > 0, F_T = -mu F_N); anchor (t_a, phi_a, theta_a) for stick."""

    def __init__(self, model, mode, anchor=(0.0, 0.0, 0.0)):
        self.m, self.mode = model, mode
        self.t_a, self.phi_a, self.theta_a = anchor
        self.stick = mode == "stick"
        self.sigma = {"stick": 0, "slip-": -1, "slip+": 1}[mode]
        self.presc = model.spin == "prescribed"
        ns = 2 if model.rigid else 4           # chart s = (phi, theta[, x_s, y_s])
        cols = []                               # columns of S (one per free coordinate)
        if not self.stick:
            cols.append(np.eye(ns)[0])                                   # phi
        if not self.presc:
            e = np.eye(ns)[1].copy()
            if self.stick:
                e[0] = -model.R / model.g0                               # theta - theta_a
            cols.append(e)
        for j in range(2, ns):
            cols.append(np.eye(ns)[j])                                   # x_s, y_s
        self.S = np.array(cols).T.reshape(ns, len(cols))
        self.k = len(cols)
        self.ns = ns

    def affine(self, t):
        """s0(t), s1(t), s2(t): the parts of s, s', s'' not carried by p."""
        m, ns = self.m, self.ns
        s0, s1, s2 = np.zeros(ns), np.zeros(ns), np.zeros(ns)
        kr = m.R / m.g0
        if self.stick:
            s0[0], s0[1] = self.phi_a, self.theta_a
        if self.presc:
            th, Om, al = m.prescribed(t)
            if self.stick:
                # theta(t) - theta_a without the round-off of a large theta
                ta, ts = self.t_a, m.t_start
                dth = (t - ta) * (m.omega_start + 0.5 * m.alpha * (t + ta - 2 * ts))
                s0[0] = self.phi_a - kr * dth
                s1[0], s2[0] = -kr * Om, -kr * al
            s0[1], s1[1], s2[1] = th, Om, al
        return s0, s1, s2

    def embed(self, t, p, pd):
        """q, v, Jq, cq, s2 from the reduced state."""
        m = self.m
        s0, s1, s2 = self.affine(t)
        s = self.S @ p + s0
        sd = self.S @ pd + s1
        phi, phid = s[0], sd[0]
        c, sn = math.cos(phi), math.sin(phi)
        g0 = m.g0
        Jq = np.zeros((m.n, self.ns))
        Jq[0, 0], Jq[1, 0], Jq[2, 1] = -g0 * sn, g0 * c, 1.0
        q = np.empty(m.n)
        q[0], q[1], q[2] = g0 * c, g0 * sn, s[1]
        if not m.rigid:
            Jq[0, 2] = Jq[3, 2] = Jq[1, 3] = Jq[4, 3] = 1.0
            q[0] += s[2]
            q[1] += s[3]
            q[3], q[4] = s[2], s[3]
        v = Jq @ sd
        cq = np.zeros(m.n)
        cq[0], cq[1] = -g0 * c * phid * phid, -g0 * sn * phid * phid
        return q, v, Jq, cq, s2

    def solve(self, t, p, pd):
        """p'', F_N, F_T, tau_d (0 unless prescribed) and the contact quantities at (t, p, p')."""
        m = self.m
        q, v, Jq, cq, s2 = self.embed(t, p, pd)
        M = m.mass_matrix(q)
        f = m.smooth_forces(t, q, v)
        dN, WN, WT, vN, vt = m.contact(q, v)
        cols = [M @ Jq @ self.S]
        if self.stick:
            cols += [-WN[:, None], -WT[:, None]]
        else:
            cols += [-(WN - m.mu * self.sigma * WT)[:, None]]
        if self.presc:
            cols.append(-np.eye(m.n)[:, 2:3])
        A = np.hstack(cols)
        x = np.linalg.solve(A, f - M @ (Jq @ s2 + cq))
        pdd = x[:self.k]
        FN = x[self.k]
        FT = x[self.k + 1] if self.stick else -m.mu * self.sigma * FN
        tau_d = x[-1] if self.presc else 0.0
        return pdd, FN, FT, tau_d, q, v, vt, dN, vN

    def rhs(self, t, y):
        k = self.k
        p, pd = y[:k], y[k:2 * k]
        pdd, FN, FT, tau_d, q, v, vt, _, _ = self.solve(t, p, pd)
        Om = v[2]
        P_drive = (tau_d if self.presc else self.m.torque(Om)) * Om
        return np.concatenate([pd, pdd, [P_drive, self.m.damper_power(v), FT * vt]])

    def from_full(self, t, q, v):
        """Reduced state of a full (q, v) on the contact circle (least squares on v)."""
        m = self.m
        rx, ry = q[0] - (0 if m.rigid else q[3]), q[1] - (0 if m.rigid else q[4])
        phi = math.atan2(ry, rx)
        if self.stick:
            self.t_a, self.phi_a, self.theta_a = t, phi, q[2]
        pfull = [phi, q[2]] + ([] if m.rigid else [q[3], q[4]])
        p = np.linalg.lstsq(self.S, np.array(pfull) - self.affine(t)[0], rcond=None)[0]
        if self.stick and not self.presc:
            p[0] = 0.0
        qq, _, Jq, _, _ = self.embed(t, p, np.zeros(self.k))
        JS = Jq @ self.S
        s1v = Jq @ self.affine(t)[1]
        pd = np.linalg.lstsq(JS, v - s1v, rcond=None)[0] if self.k else np.zeros(0)
        return p, pd


class Result:
    def __init__(self):
        self.segments = []   # (phase, solve_ivp solution)
        self.events = []     # (t, kind, detail)
        self.termination = None

    def samples(self):
        """Concatenated samples: dict of arrays t, q, v, F_N, F_T, tau_d, v_t, d_N, v_N, E, W,
        mode (each row from the phase that produced it)."""
        rows = []
        for ph, sol in self.segments:
            k = ph.k
            for j, t in enumerate(sol.t):
                y = sol.y[:, j]
                pdd, FN, FT, tau_d, q, v, vt, dN, vN = ph.solve(t, y[:k], y[k:2 * k])
                rows.append((t, q, v, FN, FT, tau_d, vt, dN, vN, ph.m.energy(q, v),
                             y[2 * k:], ph.mode))
        keys = ["t", "q", "v", "F_N", "F_T", "tau_d", "v_t", "d_N", "v_N", "E", "W", "mode"]
        out = {key: [r[i] for r in rows] for i, key in enumerate(keys)}
        for key in keys[:-1]:
            out[key] = np.array(out[key])
        return out


def _events(ph):
    k = ph.k

    def lift(t, y):
        return ph.solve(t, y[:k], y[k:2 * k])[1]
    lift.terminal, lift.direction = True, -1
    evs = [lift]
    if ph.stick:
        def up(t, y):
            r = ph.solve(t, y[:k], y[k:2 * k])
            return ph.m.mu * r[1] - r[2]
        def down(t, y):
            r = ph.solve(t, y[:k], y[k:2 * k])
            return ph.m.mu * r[1] + r[2]
        up.terminal = down.terminal = True
        up.direction = down.direction = -1
        evs += [up, down]
    else:
        def vt0(t, y):
            return ph.solve(t, y[:k], y[k:2 * k])[6]
        vt0.terminal, vt0.direction = True, -ph.sigma
        evs.append(vt0)
    return evs


def initial_mode(model, t, q, v, tol=1e-9):
    """stick if |v_t| <= tol (|R Omega| + |t . r'|) and stick is admissible, else slip by sign."""
    _, _, WT, _, vt = model.contact(q, v)
    scale = abs(model.R * v[2]) + abs(WT[:2] @ v[:2]) + 1e-300
    if abs(vt) <= tol * scale:
        ph = Phase(model, "stick")
        p, pd = ph.from_full(t, q, v)
        _, FN, FT, *_ = ph.solve(t, p, pd)
        if abs(FT) <= model.mu * FN:
            return "stick"
        return "slip-" if FT > 0 else "slip+"
    return "slip-" if vt < 0 else "slip+"


def simulate(model, q0, v0, t0, t_end, mode=None, rtol=1e-12, atol_scale=1e-14, t_eval=None,
             max_phases=50, switch=True):
    """Integrates contact phases from (q0, v0) at t0 to t_end. mode: initial phase (default:
    from v_t). switch=False stops at the first end of phase instead of continuing. atol is
    atol_scale times the typical size of each component (g0, g0 w, ...). Returns a Result."""
    res = Result()
    q, v, t = np.asarray(q0, float), np.asarray(v0, float), t0
    mode = mode or initial_mode(model, t, q, v)
    W0 = np.zeros(3)
    for _ in range(max_phases):
        ph = Phase(model, mode)
        p, pd = ph.from_full(t, q, v)
        y0 = np.concatenate([p, pd, W0])
        scale = np.concatenate([np.maximum(np.abs(p), model.g0), np.maximum(np.abs(pd), 1e-3),
                                [1.0, 1.0, 1.0]])
        te = None if t_eval is None else [x for x in t_eval if t <= x <= t_end]
        sol = solve_ivp(ph.rhs, (t, t_end), y0, method="DOP853", rtol=rtol,
                        atol=atol_scale * scale, events=_events(ph), t_eval=te)
        if te is not None and len(sol.t) == 0:
            sol.t, sol.y = np.array([t]), y0[:, None]
        res.segments.append((ph, sol))
        if sol.status != 1:
            res.termination = "t_end" if sol.status == 0 else "failed: " + sol.message
            return res
        ie = next(i for i, te_ in enumerate(sol.t_events) if len(te_))
        tev, yev = sol.t_events[ie][0], sol.y_events[ie][0]
        k = ph.k
        _, FN, FT, _, q, v, vt, _, _ = ph.solve(tev, yev[:k], yev[k:2 * k])
        W0 = yev[2 * k:]
        t = tev
        if ie == 0:
            res.events.append((t, "lift-off", mode))
            res.termination = "lift-off"
            return res
        if ph.stick:
            new = "slip-" if ie == 1 else "slip+"    # F_T reached +mu F_N (v_t < 0) or -mu F_N
        else:
            new = initial_mode(model, t, q, v, tol=math.inf)   # v_t = 0: stick if admissible
            if new == mode:
                new = "slip+" if mode == "slip-" else "slip-"
        res.events.append((t, mode + " -> " + new, mode))
        if not switch:
            res.termination = "phase end"
            return res
        mode = new
    res.termination = "too many phases"
    return res


def state_from_keys(model, keys):
    """(q, v) from rubdyn's initial.* case keys."""
    g = lambda k: keys.get("initial." + k, 0.0)
    q = [g("x_r"), g("y_r"), g("theta")] + ([] if model.rigid else [g("x_s"), g("y_s")])
    v = [g("vx_r"), g("vy_r"), g("omega0")] + ([] if model.rigid else [g("vx_s"), g("vy_s")])
    return np.array(q, float), np.array(v, float)


# ---------------------------------------------------------------------------------------------
# Linear stability of a steady orbit (a relative equilibrium), in the frame of the orbit
# ---------------------------------------------------------------------------------------------

def orbit_vector_field(model, mode, xi):
    """Vector field of the invariant coordinates of a contact phase (g = 0):
    torque drive, u_b = 0:  xi = (Omega | phi', zeta, eta)      stick | slip
    prescribed constant speed (alpha = 0), slip:  xi = (delta, phi', zeta, eta)
    with zeta = z_s e^{-i phi}, eta = z_s' e^{-i phi} (absent for a rigid stator), delta =
    psi - phi. The state is rebuilt with phi = 0 (the dynamics are invariant under rotation)."""
    m = model
    presc = m.spin == "prescribed"
    if m.g != 0 or (presc and (mode == "stick" or m.alpha != 0)) or (not presc and m.u_b != 0):
        raise ValueError("no relative equilibrium: needs g = 0, and u_b = 0 (torque drive) "
                         "or slip at a constant prescribed speed")
    ph = Phase(m, mode, (0.0, 0.0, 0.0))
    i0 = 1 if presc else 0
    lateral = xi[i0 + 1:]
    if m.rigid:
        zeta = eta = 0j
    else:
        zeta, eta = complex(lateral[0], lateral[1]), complex(lateral[2], lateral[3])
    t = 0.0
    if presc:
        # the time at which psi = theta(t) + phi_u equals delta
        t = m.t_start + (xi[0] - m.phi_u - m.theta_start) / m.omega_start
        p = [0.0]
        pd = [xi[1]]
    elif mode == "stick":
        p, pd = [0.0], [xi[0]]
    else:
        # theta and Omega do not enter the lateral slip dynamics when u_b = 0 (the mode fixes
        # the sign of F_T): any value will do
        p, pd = [0.0, 0.0], [xi[0], 0.0]
    if not m.rigid:
        p += [zeta.real, zeta.imag]
        pd += [eta.real, eta.imag]
    p, pd = np.array(p), np.array(pd)
    pdd, *_ = ph.solve(t, p, pd)
    if mode == "stick":
        phid = -m.R / m.g0 * xi[0]
        head = [pdd[0]]
    elif presc:
        phid = xi[1]
        head = [m.prescribed(t)[1] - phid, pdd[0]]
    else:
        phid = xi[0]
        head = [pdd[0]]
    if m.rigid:
        return np.array(head)
    a_s = complex(pdd[-2], pdd[-1])
    dz = eta - 1j * phid * zeta
    de = a_s - 1j * phid * eta
    return np.array(head + [dz.real, dz.imag, de.real, de.imag])


def orbit_eigenvalues(model, mode, xi, rel_step=1e-6):
    """Eigenvalues of the Jacobian (central differences) of orbit_vector_field at xi, and the
    residual of the vector field there (0 on an exact steady orbit). Steps are rel_step times
    the component's scale."""
    xi = np.asarray(xi, float)
    n = len(xi)
    g0 = model.g0
    scales = []
    presc = model.spin == "prescribed"
    for j in range(n):
        if presc and j == 0:
            scales.append(1.0)
        elif j < (2 if presc else 1):
            scales.append(max(abs(xi[j]), 1.0))
        elif j < (4 if presc else 3):
            scales.append(g0)
        else:
            scales.append(g0 * max(abs(xi[1 if presc else 0]), 1.0))
    F0 = orbit_vector_field(model, mode, xi)
    Jm = np.empty((n, n))
    for j in range(n):
        h = rel_step * scales[j]
        e = np.zeros(n)
        e[j] = h
        Jm[:, j] = (orbit_vector_field(model, mode, xi + e)
                    - orbit_vector_field(model, mode, xi - e)) / (2 * h)
    return np.linalg.eigvals(Jm), F0
