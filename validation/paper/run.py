#!/usr/bin/python3
"""The figure set of the paper's section 5, regenerated with rubdyn (one command).

Runs (into out/paper/) the reference case, the mu sweep, the k_s sweep and the k_s x m_s sweeps
with `rubdyn run`, `rubdyn sweep` and `rubdyn analyze`, then draws fig05 ... fig13 as PNG next to
this script and writes findings.md: the numbers behind the figures (whether omega is limited,
whip onsets, whirl frequencies against the Campbell modes, stiffness thresholds).
Then the same figures on cases/paper.toml in the paper's axes (t / t_ref, Omega / Omega_lim,
d_N / g0; paper_axes.py) into paper-case/.
Usage: validation/paper/run.py [path/to/rubdyn] [--quick] [--paper-case-only]
  --quick            shorter runs and coarser grids (a smoke run: do not commit its output)
  --paper-case-only  only the cases/paper.toml set (about 40 s)
"""
import csv
import json
import os
import subprocess
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import CASE, ROOT, machine, script_args  # noqa: E402
from paper_axes import figure_set  # noqa: E402

RUBDYN, QUICK, OUT = script_args("paper")
T_END = "0.1" if QUICK else "0.5"
K_REF, M_REF, OMEGA_LIM, TAU = 2.0e6, 2.0, 2110.0, 20.0
MUS = ["0", "0.1", "0.2", "0.22", "0.25"]
K_FACTORS = [1, 2, 4, 5.5, 8] if not QUICK else [1, 8]
K13 = [1, 2, 3, 4, 5.5, 7, 8.5, 10] if not QUICK else [1, 5.5]
M13 = [1, 2.10, 3.15] if not QUICK else [1]


def rubdyn(*args):
    subprocess.run([RUBDYN] + list(args), check=True, stdout=subprocess.DEVNULL)


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def col(rows, name):
    return np.array([float(r[name]) if r[name] not in ("", "nan") else np.nan for r in rows])


def run_and_analyze(name, extra):
    folder = os.path.join(OUT, name)
    subprocess.run([RUBDYN, "run", CASE, "--out", folder, "--quiet", "--t-end", T_END] + extra,
                   stdout=subprocess.DEVNULL)  # exit 3 (ended early) still leaves a folder
    rubdyn("analyze", folder)
    return folder


def sweep(name, varies, extra=()):
    folder = os.path.join(OUT, name)
    args = ["sweep", CASE, "--out", folder, "--quiet", "--t-end", T_END, "--jobs", "2"]
    for v in varies:
        args += ["--vary", v]
    subprocess.run([RUBDYN] + args + list(extra), stdout=subprocess.DEVNULL)
    return read_csv(os.path.join(folder, "sweep.csv"))


def series(folder):
    ts = read_csv(os.path.join(folder, "timeseries.csv"))
    de = read_csv(os.path.join(folder, "analysis", "derived.csv"))
    return ts, de


def whirl_peak(folder, t_from):
    """Median over spectrogram frames after t_from of the strongest frequency, and the Campbell
    f1b (negative) at those frames."""
    sg = read_csv(os.path.join(folder, "analysis", "spectrogram.csv"))
    cb = read_csv(os.path.join(folder, "analysis", "campbell.csv"))
    frames = {}
    for r in sg:
        t = float(r["t"])
        if t >= t_from:
            frames.setdefault(t, []).append((float(r["amplitude"]), float(r["f"])))
    if not frames:
        return None, None
    peaks = [max(v)[1] for v in frames.values()]
    f1b = [float(r["f1b"]) for r in cb if float(r["t"]) in frames]
    return float(np.median(peaks)), float(np.median(f1b))


def fig05(findings):
    ev = run_and_analyze("fig05-event", [])
    cv = run_and_analyze("fig05-carp-onevc", ["--solver", "carp-onevc", "--h", "1e-6"])
    fig, ax = plt.subplots(4, 1, figsize=(9, 11), sharex=True)
    for folder, label, style in [(ev, "event-driven (rtol 1e-10)", "k-"),
                                 (cv, "carp-onevc (h = 1e-6)", "C1--")]:
        ts, de = series(folder)
        t = col(ts, "t")
        ax[0].plot(t, col(ts, "omega"), style, lw=1, label=label)
        ax[1].plot(t, col(de, "dN_over_g0"), style, lw=0.8)
        ax[2].plot(t, col(ts, "v_t"), style, lw=0.8)
        ax[3].plot(t, col(de, "friction_torque_ratio"), style, lw=0.8)
    ax[0].axhline(OMEGA_LIM, color="r", ls=":", lw=0.8)
    for a, y in zip(ax, ["omega [rad/s]", "d_N / g0", "v_t [m/s]", "R_r F_T / tau_a"]):
        a.set_ylabel(y)
        a.grid(alpha=0.3)
    ax[0].legend()
    ax[3].set_xlabel("t [s]")
    fig.suptitle("Fig. 5: reference case (mu = 0.1)")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig05-reference.png"), dpi=100)
    plt.close(fig)
    for folder, label in [(ev, "event"), (cv, "carp-onevc h=1e-6")]:
        a = json.load(open(os.path.join(folder, "analysis", "analysis.json")))
        findings.append("Fig. 5 (%s): omega_max %.3f rad/s, omega_lim crossed at %s s, contact "
                        "fraction %.3f, max friction torque ratio %.4f, sustained backward whirl "
                        "fraction %.3f" % (label, a["omega_max"], a["t_omega_lim"],
                                           a["contact_fraction"], a["max_friction_torque_ratio"],
                                           a["backward_fraction"]))
    return ev


def fig06_07_09(findings):
    rows = sweep("mu", ["contact.mu=" + ",".join(MUS)])
    fig, ax = plt.subplots(3, 1, figsize=(9, 10), sharex=True)
    for r in rows:
        ts, de = series(r["folder"])
        t = col(de, "t")
        lab = "mu = %s" % r["contact.mu"]
        ax[0].plot(t, col(de, "omega"), lw=1, label=lab)
        pr = col(de, "precession_ratio")
        sus = col(de, "sustained") > 0
        ax[1].plot(t[sus], pr[sus], ".", ms=1.5, label=lab)
        ax[2].plot(t, col(de, "friction_torque_ratio"), lw=0.6, label=lab)
        findings.append(
            "Fig. 6-7, mu = %s: %s, omega_max %.1f rad/s, omega(t_end) %.1f rad/s, sustained "
            "backward whirl from %s s (whip from %s s), stick fraction %.3f, termination %s" % (
                r["contact.mu"], "limited" if r["limited"] == "yes" else "NOT limited",
                float(r["omega_max"]), float(r["omega_final"]), r["backward_onset"] or "never",
                r["whip_onset"] or "never", float(r["stick_fraction"]), r["termination"]))
    ax[0].axhline(OMEGA_LIM, color="r", ls=":", lw=0.8)
    ax[0].set_ylabel("omega [rad/s]")
    ax[1].set_ylabel("precession / omega\n(sustained whirl only)")
    ax[1].set_yscale("symlog", linthresh=0.1)
    ax[2].set_ylabel("R_r F_T / tau_a")
    ax[2].set_yscale("symlog", linthresh=1.0)
    for a in ax:
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    ax[2].set_xlabel("t [s]")
    fig.suptitle("Fig. 6-7: friction coefficient sweep (event-driven, rtol 1e-10)")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig06-07-mu-sweep.png"), dpi=100)
    plt.close(fig)
    whip = [r for r in rows if r["contact.mu"] == "0.2"]
    if whip:
        spectrogram_figure(whip[0]["folder"], "fig09-spectrogram-mu0.2.png",
                           "Fig. 9: spectrogram of x_r + i y_r, mu = 0.2", findings,
                           whip[0]["whip_onset"])
    return rows


def spectrogram_figure(folder, png, title, findings, onset):
    sg = read_csv(os.path.join(folder, "analysis", "spectrogram.csv"))
    cb = read_csv(os.path.join(folder, "analysis", "campbell.csv"))
    t = np.unique(col(sg, "t"))
    f = np.unique(col(sg, "f"))
    a = col(sg, "amplitude").reshape(len(t), len(f))
    fig, ax = plt.subplots(figsize=(9, 6))
    keep = np.abs(f) <= 600
    im = ax.pcolormesh(t, f[keep], 20 * np.log10(a[:, keep].T + 1e-16), shading="auto",
                       cmap="viridis", vmin=20 * np.log10(a.max() + 1e-16) - 80)
    fig.colorbar(im, ax=ax, label="amplitude [dB re 1 m]")
    tc = col(cb, "t")
    # frames whose samples alias the orbit's whirl (rubdyn analyze: campbell.csv's undersampled,
    # f_whirl): hatched, so that no one reads their stripes as spectrum
    bad = col(cb, "undersampled") > 0.5
    if bad.any():
        half = 0.5 * (tc[1] - tc[0]) if len(tc) > 1 else 0.0
        first = np.flatnonzero(bad)[0]
        for k in np.flatnonzero(bad):
            ax.axvspan(tc[k] - half, tc[k] + half, facecolor="0.85", alpha=0.85, hatch="//",
                       edgecolor="0.4", lw=0, label=None if k != first else
                       "undersampled (whirl up to %.3g kHz)" % (col(cb, "f_whirl")[bad].max() / 1e3))
    for name, style in [("f1f", "w--"), ("f1b", "w-"), ("f2f", "r--"), ("f2b", "r-")]:
        ax.plot(tc, col(cb, name), style, lw=0.8, label=name + " (Campbell)")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("f [Hz] (negative: backward whirl)")
    ax.set_ylim(-600, 600)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, png), dpi=100)
    plt.close(fig)
    if onset:
        pk, f1b = whirl_peak(folder, float(onset))
        if pk is not None:
            findings.append("%s: strongest frequency after the whip onset (%.4f s): median "
                            "%.1f Hz; Campbell f1b there: %.1f Hz" % (
                                png, float(onset), pk, f1b))


def fig10_11_12(findings):
    ks = ",".join("%g" % (K_REF * k) for k in K_FACTORS)
    rows = sweep("ks", ["stator.k=" + ks])
    fig, ax = plt.subplots(2, 1, figsize=(9, 8), sharex=True)
    for r in rows:
        ts, de = series(r["folder"])
        t = col(de, "t")
        lab = "k_s = %g k_ref" % (float(r["stator.k"]) / K_REF)
        ax[0].plot(t, col(de, "omega"), lw=1, label=lab)
        pr = col(de, "precession_ratio")
        sus = col(de, "sustained") > 0
        ax[1].plot(t[sus], pr[sus], ".", ms=1.5, label=lab)
        findings.append(
            "Fig. 10-11, mu = 0.1, k_s = %g k_ref: %s, omega_max %.1f rad/s, sustained backward "
            "whirl from %s s" % (float(r["stator.k"]) / K_REF,
                                 "limited" if r["limited"] == "yes" else "NOT limited",
                                 float(r["omega_max"]), r["backward_onset"] or "never"))
    ax[0].axhline(OMEGA_LIM, color="r", ls=":", lw=0.8)
    ax[0].set_ylabel("omega [rad/s]")
    ax[1].set_ylabel("precession / omega\n(sustained whirl only)")
    ax[1].set_yscale("symlog", linthresh=0.1)
    for a in ax:
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    ax[1].set_xlabel("t [s]")
    fig.suptitle("Fig. 10-11: stator stiffness sweep, mu = 0.1 (event-driven)")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig10-11-ks-sweep.png"), dpi=100)
    plt.close(fig)
    stiff = rows[-1]
    spectrogram_figure(stiff["folder"], "fig12-spectrogram-stiff.png",
                       "Fig. 12: spectrogram, mu = 0.1, k_s = %g k_ref"
                       % (float(stiff["stator.k"]) / K_REF), findings,
                       stiff["backward_onset"])


def fig08(findings):
    folder = os.path.join(OUT, "campbell")
    rubdyn("campbell", CASE, "--out", folder, "--omega-max", "2500")
    rows = read_csv(os.path.join(folder, "campbell.csv"))
    om = col(rows, "omega_rad_s")
    fig, ax = plt.subplots(figsize=(8, 5))
    for name in ["f1b", "f1f", "f2b", "f2f"]:
        ax.plot(om, col(rows, name), label=name)
    ax.axvline(OMEGA_LIM, color="r", ls=":", lw=0.8, label="omega_lim")
    ax.set_xlabel("spin speed [rad/s]")
    ax.set_ylabel("f [Hz]")
    ax.legend()
    ax.grid(alpha=0.3)
    ax.set_title("Fig. 8: Campbell diagram of the coupled rotor-stator system")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig08-campbell.png"), dpi=100)
    plt.close(fig)
    i = int(np.argmin(np.abs(om - OMEGA_LIM)))
    findings.append("Fig. 8: at omega = %.1f rad/s: f1b %.2f Hz, f1f %.2f Hz, f2b %.2f Hz, "
                    "f2f %.2f Hz" % (om[i], col(rows, "f1b")[i], col(rows, "f1f")[i],
                                     col(rows, "f2b")[i], col(rows, "f2f")[i]))


def fig13(findings):
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    ks = ",".join("%g" % (K_REF * k) for k in K13)
    ms = ",".join("%g" % (M_REF * m) for m in M13)
    for ax, mu in zip(axes, ["0.1", "0.17"]):
        solvers = [("event", [])]
        if mu == "0.1":
            solvers.append(("carp-onevc", ["--solver", "carp-onevc", "--h", "1e-6"]))
        for solver, extra in solvers:
            rows = sweep("fig13-mu%s-%s" % (mu, solver), ["contact.mu=" + mu,
                                                          "stator.mass=" + ms,
                                                          "stator.k=" + ks], extra)
            for m in M13:
                pts = [r for r in rows if abs(float(r["stator.mass"]) - M_REF * m) < 1e-9]
                k = [float(r["stator.k"]) / K_REF for r in pts]
                w = [float(r["omega_max"]) for r in pts]
                ax.plot(k, w, "o-" if solver == "event" else "x--",
                        label="m_s* = %g (%s)" % (m, solver))
                lim = [kk for kk, r in zip(k, pts) if r["limited"] == "yes"]
                ended = [r["termination"] for r in pts if r["termination"] != "completed"]
                findings.append(
                    "Fig. 13, mu = %s, m_s* = %g, %s: omega_max %s rad/s for k_s/k_ref = %s; "
                    "limited (omega_max < omega_lim) for k_s/k_ref in %s%s" % (
                        mu, m, solver, ", ".join("%.1f" % x for x in w),
                        ", ".join("%g" % x for x in k), lim or "none",
                        "; runs ended early: %s" % ended if ended else ""))
        ax.axhline(OMEGA_LIM, color="r", ls=":", lw=0.8)
        ax.set_xlabel("k_s / k_ref")
        ax.set_title("mu = %s" % mu)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("max omega [rad/s]")
    fig.suptitle("Fig. 13: maximum spin speed vs stator stiffness for three stator masses")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig13-omega-max.png"), dpi=100)
    plt.close(fig)


K13C = [5 + 0.25 * i for i in range(21)] if not QUICK else [5, 8.5]


def fig13_certified(findings):
    """The mu = 0.1 stiffness threshold on a fine grid (5 ... 10 k_ref, step 0.25), every point
    certified: the event-driven run (rtol 1e-10) re-run at rtol 1e-12, carp-onevc at h = 1e-6
    re-run at h = 1e-7 (rubdyn sweep --certify)."""
    ks = ",".join("%g" % (K_REF * k) for k in K13C)
    ms = ",".join("%g" % (M_REF * m) for m in M13)
    fig, axes = plt.subplots(1, len(M13), figsize=(6 * len(M13), 5), sharey=True, squeeze=False)
    for solver, extra, tight_name in (("event", [], "rtol 1e-12"),
                                      ("carp-onevc", ["--solver", "carp-onevc", "--h", "1e-6"],
                                       "h = 1e-7")):
        rows = sweep("fig13c-%s" % solver, ["stator.mass=" + ms, "stator.k=" + ks],
                     ["--set", "contact.mu=0.1", "--certify"] + extra)
        base_name = "rtol 1e-10" if solver == "event" else "h = 1e-6"
        for ax, m in zip(axes[0], M13):
            pts = [r for r in rows if abs(float(r["stator.mass"]) - M_REF * m) < 1e-9]
            k = [float(r["stator.k"]) / K_REF for r in pts]
            w = [float(r["omega_max"]) for r in pts]
            wt = [float(r["tight_omega_max"]) for r in pts]
            style = {"event": ("k", "o"), "carp-onevc": ("C0", "x")}[solver]
            ax.plot(k, w, "-", color=style[0], marker=style[1], ms=4,
                    label="%s %s" % (solver, base_name))
            ax.plot(k, wt, ":", color=style[0], marker=style[1], ms=7, mfc="none",
                    label="%s %s (certification)" % (solver, tight_name))
            bad = [(kk, ww) for kk, ww, r in zip(k, w, pts) if r["certified"] != "yes"]
            if bad:
                ax.plot([b[0] for b in bad], [b[1] for b in bad], "s", ms=11, mfc="none",
                        color="r" if solver == "event" else "C1",
                        label="%s: verdict depends on tolerance" % solver)
            limited = [kk for kk, r in zip(k, pts) if r["limited"] == "yes"]
            certified_limited = [kk for kk, r in zip(k, pts)
                                 if r["limited"] == "yes" and r["certified"] == "yes"]
            uncertain = [kk for kk, r in zip(k, pts) if r["certified"] != "yes"]
            dev = max(abs(a - b) for a, b in zip(w, wt))
            findings.append(
                "Fig. 13 certified, mu = 0.1, m_s* = %g, %s: limited for k_s/k_ref in %s; "
                "certified limited: %s; verdict depends on the tolerance (%s vs %s) at %s; "
                "largest |omega_max - omega_max(certification)| = %.3g rad/s" % (
                    m, solver, fmt_list(limited), fmt_list(certified_limited), base_name,
                    tight_name, fmt_list(uncertain), dev))
    for ax, m in zip(axes[0], M13):
        ax.axhline(OMEGA_LIM, color="r", ls=":", lw=0.8)
        ax.set_xlabel("k_s / k_ref")
        ax.set_title("mu = 0.1, m_s* = %g" % m)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("max omega [rad/s]")
    fig.suptitle("Fig. 13 (mu = 0.1), fine stiffness grid with certified verdicts")
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig13-certified-mu0.1.png"), dpi=100)
    plt.close(fig)


def fmt_list(xs):
    return "[" + ", ".join("%g" % x for x in xs) + "]" if xs else "none"


def paper_case():
    """The figure set on cases/paper.toml in the paper's axes (paper_axes.py), into
    validation/paper/paper-case/ with its own findings.md."""
    case = os.path.join(ROOT, "cases", "paper.toml")
    if not os.path.exists(case):
        return
    figdir = os.path.join(HERE, "paper-case")
    lines = figure_set(RUBDYN, case, os.path.join(OUT, "paper-case"), figdir, QUICK)
    with open(os.path.join(figdir, "findings.md"), "w") as f:
        f.write("# cases/paper.toml in the paper's axes\n\nGenerated by `validation/paper/run.py`%s"
                " (paper_axes.py). Machine: %s.\n\n" % (" --quick" if QUICK else "", machine()))
        for line in lines:
            f.write("- %s\n" % line)


def main():
    os.makedirs(OUT, exist_ok=True)
    paper_case()
    if "--paper-case-only" in sys.argv:
        return
    findings = []
    fig08(findings)
    fig05(findings)
    fig06_07_09(findings)
    fig10_11_12(findings)
    fig13(findings)
    fig13_certified(findings)
    with open(os.path.join(HERE, "findings.md"), "w") as f:
        f.write("# Numbers behind the figures\n\nGenerated by `validation/paper/run.py`%s "
                "(t_end = %s s). Machine: %s.\n\n" % (" --quick" if QUICK else "", T_END,
                                                      machine()))
        for line in findings:
            f.write("- %s\n" % line)
    print(open(os.path.join(HERE, "findings.md")).read())


if __name__ == "__main__":
    main()
