"""The paper's figures in the paper's own axes (t / t_ref, Omega / Omega_lim, d_N / g0, Hz) for
one case; validation/paper/run.py calls figure_set() for cases/paper.toml.

t_ref := t(Omega >= Omega_lim at mu = 0.1) / 0.76, as in claims.py. Runs: event-driven (the
case's tolerances) unless a panel names a fixed-step scheme (h = 1e-6). Precession is the raw
v_prec of `rubdyn analyze` (every sample, not only sustained whirl). Spectrograms: z = x_r + i y_r,
frame mean removed, Hann window, frames of 0.08 s with half overlap (common.spectrogram), over
the whole frequency range of the Campbell curves (f2f included), the four curves at each frame's
mean speed on top (backward ones negative)."""
import os
import tomllib

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from common import (UNDERSAMPLED_FRACTION, Campbell, Run, run_analyzed, spectrogram,  # noqa: E402
                    sweep, whirl_scale)

T_LIM_TREF = 0.76
T_RUN_TREF = 1.6
T_LONG_TREF = 3.0


def figure_set(rubdyn, case, out, figdir, quick=False):
    """Draws fig05 ... fig12 for `case` into figdir; returns findings lines."""
    os.makedirs(figdir, exist_ok=True)
    spec = tomllib.load(open(case, "rb"))
    oml, g0, tau = spec["run"]["omega_lim"], spec["stator"]["gap"], spec["loads"]["torque"]
    k_ref = spec["stator"]["k"]
    tc = Run(run_analyzed(rubdyn, case, os.path.join(out, "tref"), 2 * spec["run"]["t_end"],
                          ["contact.mu=0.1"])).a["t_omega_lim"]
    tref = tc / T_LIM_TREF
    T = (0.5 if quick else T_RUN_TREF) * tref
    name = spec.get("name", "case")
    findings = ["%s: t_ref = %.4g s, runs of %.2f t_ref" % (name, tref, T / tref)]
    cb = Campbell(rubdyn, case, os.path.join(out, "campbell"), 1.2 * oml)
    cb10 = Campbell(rubdyn, case, os.path.join(out, "campbell-ks10"), 1.2 * oml,
                    ["stator.k=%.9g" % (10 * k_ref)])

    def save(fig, png):
        fig.tight_layout()
        fig.savefig(os.path.join(figdir, png), dpi=90)
        plt.close(fig)

    # Fig. 5: the reference run, four panels
    r = Run(run_analyzed(rubdyn, case, os.path.join(out, "fig05"), T, ["contact.mu=0.1"]))
    fig, ax = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    t = r.t / tref
    ax[0].plot(t, r.omega / oml, "k-", lw=1)
    ax[0].axhline(1, color="r", ls=":", lw=0.8)
    ax[1].plot(t, dn(r, g0), "k-", lw=0.6)
    ax[2].plot(t, r.v_t, "k-", lw=0.6)
    ax[3].plot(t, r.ftr, "k-", lw=0.6)
    for a, y in zip(ax, ["Omega / Omega_lim", "d_N / g0", "v_t [m/s]", "R_r F_T / tau_a"]):
        a.set_ylabel(y)
        a.grid(alpha=0.3)
    ax[3].set_xlabel("t / t_ref")
    fig.suptitle("Fig. 5 (%s): mu = 0.1, event-driven" % name)
    save(fig, "fig05.png")

    # Fig. 6-7: mu sweep; speed, raw precession, friction torque, contact
    mus = [0, 0.1, 0.2, 0.22, 0.25]
    rows = sweep(rubdyn, case, os.path.join(out, "mu"), T,
                 ["contact.mu=" + ",".join("%g" % m for m in mus)])
    runs = {float(x["contact.mu"]): Run(x["folder"]) for x in rows}
    fig, ax = plt.subplots(4, 1, figsize=(8, 11), sharex=True)
    for mu, rr in runs.items():
        tt = rr.t / tref
        ax[0].plot(tt, rr.omega / oml, lw=1, label="mu = %g" % mu)
        if mu in (0, 0.1, 0.2, 0.25):
            ax[1].plot(tt, rr.prec, lw=0.5, label="mu = %g" % mu)
            ax[2].plot(tt, rr.ftr, lw=0.5, label="mu = %g" % mu)
            ax[3].plot(tt, dn(rr, g0), lw=0.5, label="mu = %g" % mu)
    ax[0].axhline(1, color="r", ls=":", lw=0.8)
    ax[1].set_yscale("symlog", linthresh=10)
    ax[2].set_yscale("symlog", linthresh=1)  # the stick onset at mu = 0.25 reaches 4e4 tau_a
    for a, y in zip(ax, ["Omega / Omega_lim", "v_prec [rad/s] (raw)", "R_r F_T / tau_a",
                         "d_N / g0"]):
        a.set_ylabel(y)
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    ax[3].set_xlabel("t / t_ref")
    fig.suptitle("Fig. 6-7 (%s): friction coefficient" % name)
    save(fig, "fig06-07.png")

    # Fig. 9a-c: spectrograms mu = 0, 0.1 and the longer mu = 0.25 run
    # In rolling the orbit whirls at R_r / g0 times the spin (250 x: 84 kHz at Omega_lim), far
    # above the Nyquist frequency of output.dt = 1e-4 (5 kHz): sampled there, every rolling
    # frame aliases into broadband stripes. This run is written every DT_ROLL: Nyquist frequency
    # 2 x the fastest whirl, so the spectrogram reads through the rolling phase.
    whirl_max = spec["rotor"]["radius"] / g0 * 1.05 * oml / (2 * np.pi)
    dt_roll = 1.0 / (4.0 * whirl_max)
    long25 = Run(run_analyzed(rubdyn, case, os.path.join(out, "mu0.25-long"),
                              (1 if quick else T_LONG_TREF) * tref,
                              ["contact.mu=0.25", "output.dt=%.3g" % dt_roll]))
    fmax = 1.15 * max(cb("f2f", oml), cb("f2b", 0))
    for tag, rr in (("a-mu0", runs[0.0]), ("b-mu0.1", runs[0.1]), ("c-mu0.25-long", long25)):
        spectrogram_panel(rr, cb, tref, fmax, "Fig. 9%s (%s)" % (tag, name),
                          os.path.join(figdir, "fig09%s.png" % tag))

    # Fig. 10: k_s sweep at mu = 0.1; Fig. 11-12 at k_s* = 10
    ks = [4, 5, 8, 10]
    rows = sweep(rubdyn, case, os.path.join(out, "ks"), T,
                 ["stator.k=" + ",".join("%.9g" % (k * k_ref) for k in ks)], ["contact.mu=0.1"])
    fig, ax = plt.subplots(figsize=(8, 4))
    for x in rows:
        rr = Run(x["folder"])
        ax.plot(rr.t / tref, rr.omega / oml, lw=1,
                label="k_s* = %g" % round(float(x["stator.k"]) / k_ref, 2))
    ax.axhline(1, color="r", ls=":", lw=0.8)
    ax.set_xlabel("t / t_ref")
    ax.set_ylabel("Omega / Omega_lim")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Fig. 10 (%s): stator stiffness, mu = 0.1" % name)
    save(fig, "fig10.png")
    stiff = {}
    for solver in ("carp-onevc", "mj-proj", "event"):
        extra = [] if solver == "event" else ["--solver", solver, "--h", "1e-6"]
        stiff[solver] = Run(run_analyzed(rubdyn, case, os.path.join(out, "ks10-" + solver), T,
                                         ["contact.mu=0.1", "stator.k=%.9g" % (10 * k_ref)],
                                         extra))
    fig, ax = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    for solver, style in (("carp-onevc", "C0-"), ("mj-proj", "C1-"), ("event", "k:")):
        rr = stiff[solver]
        ax[0].plot(rr.t / tref, rr.ftr, style, lw=0.6, label=solver)
        ax[1].plot(rr.t / tref, rr.prec, style, lw=0.5, label=solver)
        ax[2].plot(rr.t / tref, rr.v_t, style, lw=0.5, label=solver)
    ax[1].set_yscale("symlog", linthresh=10)
    for a, y in zip(ax, ["R_r F_T / tau_a", "v_prec [rad/s] (raw)", "v_t [m/s]"]):
        a.set_ylabel(y)
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    ax[2].set_xlabel("t / t_ref")
    fig.suptitle("Fig. 11 (%s): k_s* = 10, mu = 0.1 (fixed-step h = 1e-6)" % name)
    save(fig, "fig11.png")
    spectrogram_panel(stiff["event"], cb10, tref, 1.15 * max(cb10("f2f", oml), cb10("f2b", 0)),
                      "Fig. 12 (%s): k_s* = 10, mu = 0.1" % name,
                      os.path.join(figdir, "fig12.png"))

    # penetration of the time-steppers and the orbits (reference run)
    fig, ax = plt.subplots(1, 2, figsize=(12, 5))
    for solver in ("carp-onevc", "mj", "mj-proj"):
        rr = Run(run_analyzed(rubdyn, case, os.path.join(out, "pen-" + solver), T,
                              ["contact.mu=0.1"], ["--solver", solver, "--h", "1e-6"]))
        ax[0].semilogy(rr.t / tref, np.maximum(-dn(rr, g0), 1e-16), lw=0.5, label=solver)
        findings.append("%s: max penetration %s g0 (h = 1e-6, mu = 0.1)" % (
            solver, "%.3g" % max(0.0, float(np.max(-dn(rr, g0))))))
    ax[0].set_xlabel("t / t_ref")
    ax[0].set_ylabel("penetration -d_N / g0 (floored at 1e-16)")
    ax[0].legend(fontsize=8)
    ax[0].grid(alpha=0.3)
    for mu, rr in runs.items():
        ax[1].plot(rr.x / g0, rr.y / g0, lw=0.4, label="mu = %g" % mu)
    ax[1].set_aspect("equal")
    ax[1].set_xlabel("x_r / g0")
    ax[1].set_ylabel("y_r / g0")
    ax[1].legend(fontsize=7)
    fig.suptitle("%s: time-stepper penetration and rotor orbits" % name)
    save(fig, "penetration-orbits.png")
    fig13(rubdyn, case, out, spec, T, oml, findings, quick)
    save(plt.gcf(), "fig13.png")
    findings.append("tau_a = %g N m; figures in %s" % (tau, os.path.basename(figdir)))
    return findings


def fig13(rubdyn, case, out, spec, T, oml, findings, quick):
    """Omega_max / Omega_lim against k_s* for m_s* = 1, 2.10, 3.15: (a) mu = 0.1 with the
    event-driven solver, carp-onevc and mj-proj (h = 1e-6); (b) mu = 0.17, event-driven."""
    k_ref, m_ref = spec["stator"]["k"], spec["stator"]["mass"]
    ks = [1, 2, 3, 4, 5, 5.5, 6, 7, 8, 9, 10] if not quick else [1, 10]
    ms = [1, 2.10, 3.15] if not quick else [1]
    varies = ["stator.mass=" + ",".join("%.9g" % (m * m_ref) for m in ms),
              "stator.k=" + ",".join("%.9g" % (k * k_ref) for k in ks)]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    for ax, mu, solvers in ((axes[0], 0.1, ("event", "carp-onevc", "mj-proj")),
                            (axes[1], 0.17, ("event",))):
        for solver, style in zip(solvers, ("-o", "--x", ":s")):
            extra = [] if solver == "event" else ["--solver", solver, "--h", "1e-6"]
            rows = sweep(rubdyn, case, os.path.join(out, "fig13-mu%g-%s" % (mu, solver)), T,
                         varies, ["contact.mu=%g" % mu], extra)
            for i, m in enumerate(ms):
                pts = [r for r in rows if abs(float(r["stator.mass"]) / m_ref - m) < 1e-9]
                w = [float(r["omega_max"]) / oml for r in pts]
                ax.plot(ks, w, style, color="C%d" % i, ms=4,
                        label="m_s* = %g, %s" % (m, solver))
                lim = [k for k, r in zip(ks, pts) if r["limited"] == "yes"]
                findings.append("Fig. 13, mu = %g, m_s* = %g, %s: limited for k_s* in %s" % (
                    mu, m, solver, lim or "none"))
        ax.axhline(1, color="r", ls=":", lw=0.8)
        ax.set_xlabel("k_s*")
        ax.set_title("Fig. 13%s: mu = %g" % ("a" if mu == 0.1 else "b", mu))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    axes[0].set_ylabel("max Omega / Omega_lim")


def dn(run, g0):
    """d_N / g0 (timeseries.csv column d_N)."""
    return run.dN / g0


def spectrogram_panel(run, cb, tref, fmax, title, path, marks=()):
    """marks: vertical lines (t [s], colour, line style, label) drawn on top."""
    tc, oc, f, a = spectrogram(run)
    fw, fnyq = whirl_scale(run)
    keep = np.abs(f) <= fmax
    fig, ax = plt.subplots(figsize=(9, 6))
    db = 20 * np.log10(a[:, keep].T + 1e-16)
    im = ax.pcolormesh(tc / tref, f[keep], db, shading="auto", cmap="viridis",
                       vmin=db.max() - 80)
    fig.colorbar(im, ax=ax, label="amplitude [dB re 1 m]")
    # frames whose samples alias the orbit's whirl (rolling whirls at R_r / g0 times the spin):
    # hatched, so that no one reads their stripes as spectrum
    bad = fw > UNDERSAMPLED_FRACTION * fnyq
    if bad.any():
        half = 0.5 * (tc[1] - tc[0]) if len(tc) > 1 else 0.0
        for k in np.flatnonzero(bad):
            ax.axvspan((tc[k] - half) / tref, (tc[k] + half) / tref, facecolor="0.85", alpha=0.85,
                       hatch="//", edgecolor="0.4", lw=0,
                       label=None if k != np.flatnonzero(bad)[0] else
                       "undersampled: whirl up to %.3g kHz > Nyquist/2 = %.3g kHz"
                       % (fw[bad].max() / 1e3, 0.5 * fnyq / 1e3))
    for nm, style, sign in (("f1f", "w--", 1), ("f2f", "r--", 1), ("f1b", "w-", -1),
                            ("f2b", "r-", -1)):
        ax.plot(tc / tref, sign * cb(nm, oc), style, lw=0.8, label=nm)
    for tm, c, ls, name in marks:
        ax.axvline(tm / tref, color=c, ls=ls, lw=1.2, label=name)
    ax.set_xlabel("t / t_ref")
    ax.set_ylabel("f [Hz] (negative: backward)")
    ax.set_ylim(-fmax, fmax)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
