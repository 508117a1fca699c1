#!/usr/bin/python3
"""Validate your own time-stepping scheme against rubdyn's event-driven reference.

The model, reached from Python (rubdyn.Model):
    M(q) dv/dt = f(t, q, v) + W_N(q) F_N + W_T(q) F_T,   dq/dt = v
    model.mass_matrix(q), model.smooth_forces(t, q, v), model.contact(q, v) -> d_N, W_N, W_T,
    v_N, v_t; model.mu; case.q0, case.v0.
The scheme below is a user's: Moreau-Jean (theta = 1) with Coulomb friction solved by
enumeration of stick / slip+ / slip-, plastic impacts (e_n = 0, the reference case's). Replace
`my_step` with yours. Then: run the reference once, run your scheme for several h, compare with
rubdyn.compare (the measures of `rubdyn compare`) and plot the error against h.

    PYTHONPATH=build/python /usr/bin/python3 examples/validate_my_stepper.py [--png order.png]
"""
import argparse

import numpy as np

import rubdyn


def my_step(model, t, q, v, h):
    """One step of Moreau-Jean (theta = 1) with one frictional contact; returns (q, v)."""
    M = model.mass_matrix(q)
    f = model.smooth_forces(t, q, v)
    v_free = v + h * np.linalg.solve(M, f)
    k = model.contact(q + 0.5 * h * v, v)  # contact active if the gap closes within the step
    if not (k["normal_defined"] and k["d_N"] <= 0.0):
        return q + h * v_free, v_free
    W = np.column_stack([k["W_N"], k["W_T"]])
    MiW = np.linalg.solve(M, W)
    D = W.T @ MiW                      # Delassus matrix (2x2)
    u = W.T @ v_free                   # free (v_N, v_t)
    mu = model.mu
    P = np.linalg.solve(D, -u)         # stick: v_N+ = v_t+ = 0
    if not (P[0] >= 0.0 and abs(P[1]) <= mu * P[0]):
        for s in (1.0, -1.0):          # slip with v_t+ of sign s: P_T = -s mu P_N, v_N+ = 0
            P_N = -u[0] / (D[0, 0] - s * mu * D[0, 1])
            P = np.array([P_N, -s * mu * P_N])
            if P_N >= 0.0 and s * (u[1] + D[1] @ P) >= 0.0:
                break
        else:
            P = np.zeros(2)            # no consistent contact: let the contact open
    v_new = v_free + MiW @ P
    return q + h * v_new, v_new


def run_my_scheme(case, model, h, t_end):
    n = int(round(t_end / h))
    q, v = np.array(case.q0), np.array(case.v0)
    out = np.empty((n + 1, 1 + 2 * model.num_dofs))
    out[0] = np.concatenate([[0.0], q, v])
    for i in range(n):
        q, v = my_step(model, i * h, q, v, h)
        out[i + 1] = np.concatenate([[(i + 1) * h], q, v])
    names = ["t"] + model.position_names + model.rate_names
    return {name: out[:, j] for j, name in enumerate(names)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", default="cases/reference.toml")
    ap.add_argument("--t-end", type=float, default=0.03, help="first impact at ~6 ms")
    ap.add_argument("--h", type=float, nargs="+", default=[4e-5, 2e-5, 1e-5, 5e-6])
    ap.add_argument("--png", default="validate_my_stepper.png")
    a = ap.parse_args()

    case = rubdyn.load_case(a.case, overrides={"run.t_end": a.t_end})
    model = rubdyn.Model(case)
    ref = rubdyn.run(case, rtol=1e-12)   # the event-driven reference, tight tolerance
    print(f"reference: {len(ref.events)} events, {ref.summary['termination']}")
    errors = {"x_r": [], "y_r": [], "omega": []}
    for h in a.h:
        mine = run_my_scheme(case, model, h, a.t_end)
        c = rubdyn.compare(ref, mine, name_a="reference", name_b=f"h={h:g}")
        # rms over time, not sup: omega jumps at impacts (friction impulse), and a sup is then the
        # jump itself wherever the two solutions date it differently, whatever h
        for col in errors:
            errors[col].append(c["columns"][col]["rms"])
        print(f"h = {h:8.2e}  rms x_r {errors['x_r'][-1]:.3e} m  "
              f"rms omega {errors['omega'][-1]:.3e} rad/s")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5), layout="constrained")
    h = np.array(a.h)
    for col, unit in (("x_r", "m"), ("y_r", "m"), ("omega", "rad/s")):
        e = np.array(errors[col])
        ax.loglog(h, e, "o-", label=f"rms of {col} - reference [{unit}]")
        ax.loglog(h, e[-1] * (h / h[-1]), "k:", lw=0.8)  # slope 1 through the finest point
    ax.set_xlabel("h [s]")
    ax.set_ylabel("error (rms over [0, t_end])")
    ax.set_title("My scheme against the event-driven reference (dotted: order 1)", fontsize=10)
    ax.grid(which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(a.png, dpi=130)
    print(f"order plot: {a.png}")


if __name__ == "__main__":
    main()
