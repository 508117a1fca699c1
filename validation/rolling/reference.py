#!/usr/bin/python3
"""Independent reference for the rolling (dry whirl, "stick") regime of the rotor-stator model.

While the rotor rolls without slip inside the stator ring, both contact constraints are
holonomic: the gap is closed (|r| = g0, r = (x_r - x_s, y_r - y_s) = g0 (cos phi, sin phi)) and
the contact point does not slip (v_t = -g0 phi' - R_r omega = 0, which integrates to
phi = phi0 - (R_r/g0)(theta - theta0)). The motion then lives on a 5-dimensional configuration
manifold with minimal coordinates p = (x_b, y_b, theta, x_s, y_s):

    x_r = x_s + g0 cos phi,  y_r = y_s + g0 sin phi,
    q' = J(p) p',  q'' = J p'' + c(p, p'),  (J^T M J) p'' = J^T (f - M c)

(q = (x_b, y_b, x_r, y_r, theta, x_s, y_s), M(q) and f(q, v) the mass matrix and smooth forces of
the 7-dof model, Lagrangian of include/rubdyn/model/rotor_stator_model.hpp, eq. 11-16). This is an
ODE: no constraint, no projection, no event, no contact law. It shares nothing with rubdyn but
the model's parameters and a starting state (onset_state.json); the model's M and f are written
here from the formulas and checked against Lagrange's equations of the kinetic energy T written
independently (selftest).

The reduced mass matrix A = J^T M J is sparse: the (x_b, x_s) and (y_b, y_s) blocks are the same
constant 2x2 matrix B = [[M11, M12], [M12, m_s + M22]] and the only coupling is through theta,
so p'' is obtained by a scalar Schur complement on theta (rhs_fast). The generic route (build
M, J, c and solve the 5x5 system with numpy) is rhs_generic; the selftest checks they agree.

Integrators: an explicit 8th-order Runge-Kutta (the 12-stage 8th-order method of Dormand and
Prince, DOP853, tableau from scipy.integrate._ivp.dop853_coefficients) with a FIXED step and
compensated (Kahan) summation of the increments; and scipy's adaptive solve_ivp(DOP853) as a
second, independent check. The state carries theta - theta0 rather than theta (phi is 250 x that
angle; its round-off is 5x smaller that way) and the work W of the torque and the dampers
(dW/dt = tau_a omega - c_b |v_b|^2 - c_s |v_s|^2), so that the energy balance E - E0 - W = 0 is
checked along the solution.

Usage: validation/rolling/reference.py --selftest    (checks; about 10 s)
       validation/rolling/reference.py [--h H] [--t-end T]   (solution from onset_state.json)
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ONSET = os.path.join(HERE, "onset_state.json")
COORDS = ["x_b", "y_b", "x_r", "y_r", "theta", "x_s", "y_s"]
VELS = ["vx_b", "vy_b", "vx_r", "vy_r", "omega", "vx_s", "vy_s"]
XB, YB, XR, YR, TH, XS, YS = range(7)


class Model:
    """Parameters (SI) of the case and the 7-dof model written from its formulas."""

    def __init__(self, case):
        r, b, s = case["rotor"], case["bearing"], case["stator"]
        self.m = float(r["mass"])
        self.Jd, self.Jp = float(r["Jd"]), float(r["Jp"])
        self.l = float(r["L"]) - float(r["delta"])
        self.nu = float(r["d"]) / self.l
        self.R = float(r["radius"])
        self.kb, self.cb = float(b["k"]), float(b["c"])
        self.ms, self.ks, self.cs = float(s["mass"]), float(s["k"]), float(s["c"])
        self.g0 = float(s["gap"])
        self.mu = float(case["contact"]["mu"])
        self.g = float(case["loads"]["gravity"])
        self.tau = float(case["loads"]["torque"])
        l, nu, m = self.l, self.nu, self.m
        jl = self.Jd / l ** 2
        self.M11 = (1 - nu) ** 2 * m + jl
        self.M12 = nu * (1 - nu) * m - jl
        self.M22 = nu ** 2 * m + jl
        self.H = self.Jp / l ** 2
        self.kappa = self.R / self.g0           # phi' = -kappa omega
        self.mT = self.ms + self.M22            # stator + rotor point R, moving together
        det = self.M11 * self.mT - self.M12 ** 2
        self.B11, self.B12, self.B22 = self.mT / det, -self.M12 / det, self.M11 / det  # B^-1
        self.fyb0 = -(1 - nu) * m * self.g
        self.fyr0 = -nu * m * self.g

    # ---- 7-dof model (numpy, for checks and post-processing) ------------------------------
    def mass_matrix(self, q):
        M = np.zeros((7, 7))
        M[XB, XB] = M[YB, YB] = self.M11
        M[XR, XR] = M[YR, YR] = self.M22
        M[XB, XR] = M[XR, XB] = M[YB, YR] = M[YR, YB] = self.M12
        M[TH, TH] = self.Jp
        M[XS, XS] = M[YS, YS] = self.ms
        Hx = self.H * (q[XR] - q[XB]) / 2
        Hy = -self.H * (q[YR] - q[YB]) / 2
        M[XB, TH] = M[TH, XB] = Hy
        M[YB, TH] = M[TH, YB] = Hx
        M[XR, TH] = M[TH, XR] = -Hy
        M[YR, TH] = M[TH, YR] = -Hx
        return M

    def forces(self, q, v):
        Hw = self.H * v[TH]
        f = np.zeros(7)
        f[XB] = -Hw * (v[YB] - v[YR]) - self.cb * v[XB] - self.kb * q[XB]
        f[YB] = self.fyb0 - Hw * (v[XR] - v[XB]) - self.cb * v[YB] - self.kb * q[YB]
        f[XR] = -Hw * (v[YR] - v[YB])
        f[YR] = self.fyr0 - Hw * (v[XB] - v[XR])
        f[TH] = self.tau
        f[XS] = -self.cs * v[XS] - self.ks * q[XS]
        f[YS] = -self.cs * v[YS] - self.ks * q[YS]
        return f

    def potential(self, q):
        return (0.5 * self.kb * (q[XB] ** 2 + q[YB] ** 2)
                + self.m * self.g * (self.nu * q[YR] + (1 - self.nu) * q[YB])
                + 0.5 * self.ks * (q[XS] ** 2 + q[YS] ** 2))

    def energy(self, q, v):
        return 0.5 * v @ self.mass_matrix(q) @ v + self.potential(q)

    def power(self, v):
        """Power of the torque and of the dampers (the non-conservative smooth forces)."""
        return (self.tau * v[TH] - self.cb * (v[XB] ** 2 + v[YB] ** 2)
                - self.cs * (v[XS] ** 2 + v[YS] ** 2))

    def kinetic_lagrangian(self, q, v):
        """T(q, v) written directly from eq. 11 of the header (not from mass_matrix):
        2T = M11 (xb'^2+yb'^2) + M22 (xr'^2+yr'^2) + 2 M12 (xb' xr' + yb' yr') + Jp th'^2
             + H th' (u' w - w' u) + m_s (xs'^2+ys'^2),  u = x_r - x_b, w = y_r - y_b."""
        u, w = q[XR] - q[XB], q[YR] - q[YB]
        du, dw = v[XR] - v[XB], v[YR] - v[YB]
        two_t = (self.M11 * (v[XB] ** 2 + v[YB] ** 2) + self.M22 * (v[XR] ** 2 + v[YR] ** 2)
                 + 2 * self.M12 * (v[XB] * v[XR] + v[YB] * v[YR]) + self.Jp * v[TH] ** 2
                 + self.H * v[TH] * (du * w - dw * u) + self.ms * (v[XS] ** 2 + v[YS] ** 2))
        return 0.5 * two_t

    # ---- contact geometry --------------------------------------------------------------------
    def W(self, phi):
        """W_N and W_T at the contact angle phi (n = (cos phi, sin phi), t = (n_y, -n_x))."""
        nx, ny = math.cos(phi), math.sin(phi)
        WN = np.array([0, 0, -nx, -ny, 0, nx, ny], float)
        WT = np.array([0, 0, ny, -nx, -self.R, -ny, nx], float)
        return WN, WT

    # ---- reduced coordinates -----------------------------------------------------------------
    def full_state(self, y, phi0, th0):
        """(q, v) of the 7-dof model from the reduced state y (see rhs_fast)."""
        xb, yb, dth, xs, ys, vxb, vyb, w, vxs, vys = y[:10]
        phi = phi0 - self.kappa * dth
        co, s = math.cos(phi), math.sin(phi)
        q = np.array([xb, yb, xs + self.g0 * co, ys + self.g0 * s, th0 + dth, xs, ys])
        v = np.array([vxb, vyb, vxs + self.R * s * w, vys - self.R * co * w, w, vxs, vys])
        return q, v, phi

    def J_c(self, phi, w):
        """J (7x5) and c (7) at the contact angle phi and spin speed w."""
        co, s = math.cos(phi), math.sin(phi)
        J = np.zeros((7, 5))
        J[XB, 0] = J[YB, 1] = J[TH, 2] = J[XS, 3] = J[YS, 4] = 1.0
        J[XR, 2], J[XR, 3] = self.R * s, 1.0
        J[YR, 2], J[YR, 4] = -self.R * co, 1.0
        dphi = -self.kappa * w
        c = np.zeros(7)
        c[XR] = -self.g0 * co * dphi ** 2
        c[YR] = -self.g0 * s * dphi ** 2
        return J, c

    def rhs_generic(self, y, phi0, th0):
        """dy/dt by the textbook route: M, f, J, c built as matrices, (J^T M J) p'' solved."""
        q, v, phi = self.full_state(y, phi0, th0)
        J, c = self.J_c(phi, y[7])
        M = self.mass_matrix(q)
        pdd = np.linalg.solve(J.T @ M @ J, J.T @ (self.forces(q, v) - M @ c))
        return np.concatenate([y[5:10], pdd, [self.power(v)]])

    def contact_forces(self, y, dy, phi0, th0):
        """(F_N, F_T, |orthogonal residual|) from the state and its derivative: with
        a = J p'' + c, M a - f = W_N F_N + W_T F_T (W_N, W_T orthogonal); the residual is the
        part of M a - f outside span(W_N, W_T) (zero when the reduced equations hold)."""
        q, v, phi = self.full_state(y, phi0, th0)
        J, c = self.J_c(phi, y[7])
        a = J @ np.asarray(dy[5:10]) + c
        r = self.mass_matrix(q) @ a - self.forces(q, v)
        WN, WT = self.W(phi)
        FN, FT = WN @ r / (WN @ WN), WT @ r / (WT @ WT)
        return FN, FT, np.linalg.norm(r - WN * FN - WT * FT)

    def make_rhs(self, phi0):
        """The lean right-hand side: y = (x_b, y_b, theta - theta0, x_s, y_s, vx_b, vy_b, omega,
        vx_s, vy_s, W) as plain floats; returns dy/dt as a list. Same equations as rhs_generic,
        solved by block elimination: A = J^T M J has A12 = A15 = A24 = A45 = 0 and the constant
        blocks B on (x_b, x_s) and (y_b, y_s); the theta row couples them."""
        g0, R, kappa, H = self.g0, self.R, self.kappa, self.H
        M12, M22, Jp, R2M22 = self.M12, self.M22, self.Jp, self.R ** 2 * self.M22
        cb, kb, cs, ks, tau = self.cb, self.kb, self.cs, self.ks, self.tau
        fyb0, fyr0 = self.fyb0, self.fyr0
        B11, B12, B22 = self.B11, self.B12, self.B22
        cos, sin = math.cos, math.sin

        def rhs(y):
            xb, yb, dth, xs, ys, vxb, vyb, w, vxs, vys = y[:10]
            phi = phi0 - kappa * dth
            co, s = cos(phi), sin(phi)
            a, b = R * s, -R * co                    # J row x_r, y_r on theta
            xr, yr = xs + g0 * co, ys + g0 * s
            vxr, vyr = vxs + a * w, vys + b * w
            dphi2 = (kappa * w) ** 2
            cxr, cyr = -g0 * co * dphi2, -g0 * s * dphi2
            Hx, Hy = 0.5 * H * (xr - xb), -0.5 * H * (yr - yb)
            Hw = H * w
            # g = f - M c (M c: columns x_r and y_r of M times c_xr, c_yr)
            gxb = -Hw * (vyb - vyr) - cb * vxb - kb * xb - M12 * cxr
            gyb = fyb0 - Hw * (vxr - vxb) - cb * vyb - kb * yb - M12 * cyr
            gxr = -Hw * (vyr - vyb) - M22 * cxr
            gyr = fyr0 - Hw * (vxb - vxr) - M22 * cyr
            gth = tau + Hy * cxr + Hx * cyr
            gxs = -cs * vxs - ks * xs
            gys = -cs * vys - ks * ys
            # J^T g
            r1, r2, r3, r4, r5 = gxb, gyb, gth + a * gxr + b * gyr, gxs + gxr, gys + gyr
            # A entries coupling theta
            A13, A34 = Hy + a * M12, -Hy + a * M22
            A23, A35 = Hx + b * M12, -Hx + b * M22
            A33 = Jp - 2 * a * Hy - 2 * b * Hx + R2M22
            # B^-1 u_x, B^-1 u_y, B^-1 r_x, B^-1 r_y
            ux1, ux2 = B11 * A13 + B12 * A34, B12 * A13 + B22 * A34
            uy1, uy2 = B11 * A23 + B12 * A35, B12 * A23 + B22 * A35
            rx1, rx2 = B11 * r1 + B12 * r4, B12 * r1 + B22 * r4
            ry1, ry2 = B11 * r2 + B12 * r5, B12 * r2 + B22 * r5
            S = A33 - (A13 * ux1 + A34 * ux2) - (A23 * uy1 + A35 * uy2)
            thdd = (r3 - (A13 * rx1 + A34 * rx2) - (A23 * ry1 + A35 * ry2)) / S
            power = tau * w - cb * (vxb * vxb + vyb * vyb) - cs * (vxs * vxs + vys * vys)
            return [vxb, vyb, w, vxs, vys, rx1 - ux1 * thdd, ry1 - uy1 * thdd, thdd,
                    rx2 - ux2 * thdd, ry2 - uy2 * thdd, power]

        return rhs


# ---- the fixed-step 8th-order Runge-Kutta ------------------------------------------------------
def dop853_tableau():
    from scipy.integrate._ivp import dop853_coefficients as d
    n = d.N_STAGES  # 12: the 8th-order method (the extra stages are for dense output)
    return np.array(d.A[:n, :n]), np.array(d.B), np.array(d.C[:n])


def rk_fixed(rhs, y0, h, n_steps, every, on_step=None):
    """Integrates y' = rhs(y) (autonomous) with n_steps fixed steps h of the explicit 12-stage
    8th-order Runge-Kutta method, compensated summation. Returns the states at steps 0, every,
    2 every, ... (array). on_step(k, y, k1) is called at every step k with k1 = rhs(y_k)."""
    A, B, C = dop853_tableau()
    s = len(B)
    rows = [np.array(A[i, :i]) for i in range(s)]
    y = np.array(y0, float)
    comp = np.zeros_like(y)
    K = np.zeros((s, y.size))
    out = [y.copy()]
    hB = h * B
    for k in range(n_steps):
        K[0] = rhs(y.tolist())
        if on_step is not None:
            on_step(k, y, K[0])
        for i in range(1, s):
            K[i] = rhs((y + h * (rows[i] @ K[:i])).tolist())
        # Kahan: y + incr with the lost low-order bits carried to the next step
        incr = hB @ K - comp
        ynew = y + incr
        comp = (ynew - y) - incr
        y = ynew
        if (k + 1) % every == 0:
            out.append(y.copy())
    if on_step is not None:
        on_step(n_steps, y, np.array(rhs(y.tolist())))
    return np.array(out)


# ---- the rolling solution from a stick-onset state ---------------------------------------------
def load_onset(path=ONSET):
    with open(path) as f:
        return json.load(f)


def reduced_initial(model, state):
    """Reduced initial state y0, phi0, theta0 from a 7-dof state dict; also the residuals of
    the constraints in the given state (gap, v_N, v_t) for the record."""
    sx, sy = state["x_r"] - state["x_s"], state["y_r"] - state["y_s"]
    phi0 = math.atan2(sy, sx)
    th0 = state["theta"]
    y0 = [state["x_b"], state["y_b"], 0.0, state["x_s"], state["y_s"],
          state["vx_b"], state["vy_b"], state["omega"], state["vx_s"], state["vy_s"], 0.0]
    rho = math.hypot(sx, sy)
    nx, ny = sx / rho, sy / rho
    dvx, dvy = state["vx_r"] - state["vx_s"], state["vy_r"] - state["vy_s"]
    resid = {"d_N": model.g0 - rho, "v_N": -(nx * dvx + ny * dvy),
             "v_t": ny * dvx - nx * dvy - model.R * state["omega"]}
    return y0, phi0, th0, resid


class Solution:
    """Samples of the reference on the output grid t_k = k dt: t, q (7), v (7), phi, W, and
    along every step F_N, F_T (min F_N, max |F_T| / F_N, min cone margin)."""

    def __init__(self, model, phi0, th0, t, Y, stats):
        self.model, self.phi0, self.th0, self.t, self.Y = model, phi0, th0, t, Y
        self.q, self.v = [], []
        for y in Y:
            q, v, _ = model.full_state(y, phi0, th0)
            self.q.append(q)
            self.v.append(v)
        self.q, self.v = np.array(self.q), np.array(self.v)
        self.W = Y[:, 10]
        self.stats = stats

    def omega(self):
        return self.v[:, TH]

    def orbit(self):
        """(x_r - x_s, y_r - y_s) on the grid [m]."""
        return self.q[:, [XR, YR]] - self.q[:, [XS, YS]]

    def energy_residual(self):
        """E(t) - E(0) - W(t) on the grid [J]."""
        E = np.array([self.model.energy(q, v) for q, v in zip(self.q, self.v)])
        return E - E[0] - self.W


def solve_fixed(model, state, t_end, h, dt, force_every=1):
    """The reference by the fixed-step 8th-order RK: samples every dt (dt / h an integer), and
    the contact forces at every force_every-th step."""
    y0, phi0, th0, _ = reduced_initial(model, state)
    n = round(t_end / h)
    every = round(dt / h)
    assert abs(n * h - t_end) < 1e-9 * t_end and abs(every * h - dt) < 1e-9 * dt
    rhs = model.make_rhs(phi0)
    st = {"min_F_N": math.inf, "max_F_T_over_F_N": 0.0, "min_cone_margin": math.inf,
          "max_force_residual": 0.0, "t_min_cone_margin": 0.0}

    def on_step(k, y, k1):
        if k % force_every:
            return
        FN, FT, res = model.contact_forces(y, k1, phi0, th0)
        st["min_F_N"] = min(st["min_F_N"], FN)
        st["max_F_T_over_F_N"] = max(st["max_F_T_over_F_N"], abs(FT) / FN)
        margin = (model.mu * FN - abs(FT)) / (model.mu * FN)
        if margin < st["min_cone_margin"]:
            st["min_cone_margin"], st["t_min_cone_margin"] = margin, k * h
        st["max_force_residual"] = max(st["max_force_residual"], res / abs(FN))

    t0 = time.perf_counter()
    Y = rk_fixed(rhs, y0, h, n, every, on_step)
    st["wall_seconds"] = time.perf_counter() - t0
    st["steps"] = n
    t = np.arange(len(Y)) * dt
    return Solution(model, phi0, th0, t, Y, st)


def solve_scipy(model, state, t_end, dt, rtol=1e-13, atol=1e-20):
    """The same reduced equations by scipy's adaptive DOP853, restarted at every output time
    (the samples are integration end points, not dense-output interpolants)."""
    from scipy.integrate import solve_ivp
    y0, phi0, th0, _ = reduced_initial(model, state)
    rhs = model.make_rhs(phi0)
    n = round(t_end / dt)
    Y, nfev, steps = [np.array(y0)], 0, 0
    t0 = time.perf_counter()
    for k in range(n):
        sol = solve_ivp(lambda t, y: rhs(y.tolist()), (k * dt, (k + 1) * dt), Y[-1],
                        method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError("solve_ivp: " + sol.message)
        Y.append(sol.y[:, -1])
        nfev += sol.nfev
        steps += len(sol.t) - 1
    wall = time.perf_counter() - t0
    return Solution(model, phi0, th0, np.arange(n + 1) * dt, np.array(Y),
                    {"wall_seconds": wall, "nfev": int(nfev), "steps": int(steps),
                     "rtol": rtol, "atol": atol})


# ---- self-test -------------------------------------------------------------------------------
def selftest(verbose=True, out=None):
    """Checks: (1) M and f against Lagrange's equations of T (eq. 11) and V by finite
    differences; (2) J and c by finite differences of the map p -> q, rolling condition
    J^T W_N = J^T W_T = 0; (3) the lean rhs against the generic one; (4) the order of the fixed-
    step RK on an ODE with a known solution; (5) a short rolling solution: energy balance,
    contact forces in span(W_N, W_T). Returns True when all pass; the report lines are appended
    to the list out when given."""
    ok = True
    rng = np.random.default_rng(1)
    model = Model(load_onset()["case"])

    def note(line):
        if verbose:
            print(line)
        if out is not None:
            out.append(line)

    def report(name, value, tol):
        nonlocal ok
        good = value <= tol
        ok &= good
        note("  %-62s %.2e  (<= %.0e) %s" % (name, value, tol, "ok" if good else "FAIL"))

    print("selftest")
    # (1) Lagrange's equations. T is quadratic in v with M linear in q: finite differences of
    # T in q are exact up to round-off, and M_ij follows from T by polarization.
    worst_m = worst_f = 0.0
    for _ in range(5):
        q = rng.normal(size=7) * 1e-4
        q[TH] = rng.normal() * 100
        v = rng.normal(size=7) * 0.5
        v[TH] = 2000 + rng.normal() * 100
        T = lambda qq, vv: model.kinetic_lagrangian(qq, vv)  # noqa: E731
        E = np.eye(7)
        Mt = np.array([[T(q, E[i] + E[j]) - T(q, E[i]) - T(q, E[j]) if i != j else 2 * T(q, E[i])
                        for j in range(7)] for i in range(7)])
        worst_m = max(worst_m, np.abs(Mt - model.mass_matrix(q)).max())
        # d/dt dT/dv - dT/dq + dV/dq = Q (Q: torque and dampers), with
        # d/dt dT/dv = M a + (sum_k dM/dq_k v_k) v. T and M are linear and V quadratic in q:
        # central differences are exact for any step, so a large one keeps round-off low
        eps = 1e-1
        dTdq = np.array([(T(q + eps * E[k], v) - T(q - eps * E[k], v)) / (2 * eps)
                         for k in range(7)])
        dVdq = np.array([(model.potential(q + eps * E[k]) - model.potential(q - eps * E[k]))
                         / (2 * eps) for k in range(7)])
        Mdot = sum((model.mass_matrix(q + eps * E[k]) - model.mass_matrix(q - eps * E[k]))
                   / (2 * eps) * v[k] for k in range(7))
        Q = np.zeros(7)
        Q[TH] = model.tau
        Q[[XB, YB]] = -model.cb * v[[XB, YB]]
        Q[[XS, YS]] = -model.cs * v[[XS, YS]]
        f_lagrange = Q - dVdq + dTdq - Mdot @ v
        worst_f = max(worst_f, np.abs(f_lagrange - model.forces(q, v)).max()
                      / np.abs(model.forces(q, v)).max())
    report("(1) M(q) vs polarization of T (eq. 11) [kg]", worst_m, 1e-14)
    report("(1) f(q,v) vs Lagrange's equations of T, V (relative)", worst_f, 1e-11)

    # (2) J and c: q(p) along p(s) = p + s p' + s^2/2 p''; dq/ds = J p', d2q/ds2 = J p'' + c.
    worst_j = worst_c = worst_w = 0.0
    for _ in range(5):
        # theta0 small: an offset of theta only (q_theta = theta0 + p_theta), and a large one
        # would drown the second differences of q_theta in round-off
        phi0, th0 = rng.uniform(-3, 3), rng.uniform(-1, 1)
        p = np.concatenate([rng.normal(size=2) * 1e-4, [rng.uniform(-1, 1)],
                            rng.normal(size=2) * 1e-4])
        dp = np.concatenate([rng.normal(size=2), [rng.uniform(-2000, 2000)], rng.normal(size=2)])
        ddp = rng.normal(size=5) * 1e3

        def qmap(pp):
            y = np.concatenate([pp, np.zeros(5)])
            return model.full_state(y, phi0, th0)[0]

        # scale s with the fastest angle rate (phi' = kappa * omega ~ 5e5 rad/s): phi moves by
        # 1e-2 rad; Richardson extrapolation leaves O(s^4) truncation (smaller s: round-off)
        s = 1e-2 / (model.kappa * abs(dp[2]))
        path = lambda ss: qmap(p + ss * dp + 0.5 * ss * ss * ddp)  # noqa: E731
        d1 = (path(s) - path(-s)) / (2 * s)
        d1b = (path(s / 2) - path(-s / 2)) / s
        d1 = d1b + (d1b - d1) / 3                     # Richardson: O(s^4)
        d2 = (path(s) - 2 * path(0) + path(-s)) / s ** 2
        d2b = (path(s / 2) - 2 * path(0) + path(-s / 2)) / (s / 2) ** 2
        d2 = d2b + (d2b - d2) / 3
        phi = phi0 - model.kappa * p[2]
        J, c = model.J_c(phi, dp[2])
        worst_j = max(worst_j, np.abs(d1 - J @ dp).max() / np.abs(J @ dp).max())
        worst_c = max(worst_c, np.abs(d2 - (J @ ddp + c)).max() / np.abs(J @ ddp + c).max())
        WN, WT = model.W(phi)
        worst_w = max(worst_w, np.abs(J.T @ WN).max(), np.abs(J.T @ WT).max())
    report("(2) J p' vs finite differences of q(p) (relative)", worst_j, 1e-9)
    report("(2) J p'' + c vs finite differences of q(p) (relative)", worst_c, 1e-7)
    report("(2) J^T W_N, J^T W_T (rolling: v_N = v_t = 0 on J p')", worst_w, 1e-15)

    # (3) lean rhs vs generic
    onset = load_onset()
    y0, phi0, th0, _ = reduced_initial(model, onset["state"])
    rhs = model.make_rhs(phi0)
    worst = 0.0
    for _ in range(20):
        y = np.array(y0) + np.concatenate([rng.normal(size=2) * 1e-4, [rng.uniform(0, 50)],
                                           rng.normal(size=2) * 1e-4, rng.normal(size=5) * 10,
                                           [0.0]])
        y[7] = y0[7] + rng.normal() * 500
        a, b = np.array(rhs(y.tolist())), model.rhs_generic(y, phi0, th0)
        worst = max(worst, np.abs(a - b).max() / np.abs(b).max())
    report("(3) lean rhs vs generic (J^T M J) p'' = J^T (f - M c) (relative)", worst, 1e-12)

    # (4) order of the fixed-step RK on y' = -2 t y^2 (y = 1/(1+t^2)) and a rotation at rate 7
    def test_rhs(y):
        t, u, x1, x2 = y
        return [1.0, -2 * t * u * u, -7 * x2, 7 * x1]

    errs = []
    for h in (0.2, 0.1, 0.05):
        Y = rk_fixed(test_rhs, [0.0, 1.0, 1.0, 0.0], h, round(3 / h), round(3 / h))
        t_e = 3.0
        errs.append(max(abs(Y[-1][1] - 1 / (1 + t_e ** 2)),
                        math.hypot(Y[-1][2] - math.cos(7 * t_e), Y[-1][3] - math.sin(7 * t_e))))
    orders = [math.log2(errs[i] / errs[i + 1]) for i in range(2)]
    note("  (4) RK errors at h = 0.2, 0.1, 0.05: %s; observed orders %s"
         % (", ".join("%.2e" % e for e in errs), ", ".join("%.2f" % o for o in orders)))
    report("(4) |observed order - 8| (h = 0.1 -> 0.05)", abs(orders[1] - 8), 0.3)

    # (5) a short rolling solution from the onset state: energy balance and force residual
    sol = solve_fixed(model, onset["state"], 1e-3, 5e-8, 1e-4, force_every=10)
    res = np.abs(sol.energy_residual()).max()
    E0 = model.energy(sol.q[0], sol.v[0])
    report("(5) 1 ms rolling, h = 5e-8: |E - E0 - W| / E0", res / E0, 1e-12)
    report("(5) 1 ms rolling: |M a - f - W_N F_N - W_T F_T| / F_N", sol.stats["max_force_residual"],
           1e-9)
    note("  (5) min F_N %.4e N, max |F_T|/F_N %.3e (mu = %g)"
         % (sol.stats["min_F_N"], sol.stats["max_F_T_over_F_N"], model.mu))
    print("selftest: %s" % ("passed" if ok else "FAILED"))
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--selftest", action="store_true", help="run the checks and exit")
    ap.add_argument("--h", type=float, default=1e-7, help="fixed step [s]")
    ap.add_argument("--t-end", type=float, default=0.03, help="window [s]")
    args = ap.parse_args()
    if args.selftest:
        sys.exit(0 if selftest() else 1)
    onset = load_onset()
    model = Model(onset["case"])
    sol = solve_fixed(model, onset["state"], args.t_end, args.h, 1e-4, force_every=10)
    print("omega(t_end) = %r rad/s, orbit = %r m" % (sol.omega()[-1], tuple(sol.orbit()[-1])))
    print(json.dumps(sol.stats, indent=1))


if __name__ == "__main__":
    main()
