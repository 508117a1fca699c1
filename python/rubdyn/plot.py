#!/usr/bin/python3
"""Figures of a run (matplotlib): each function takes a Result (rubdyn.run, rubdyn.read) or an
output folder and returns a Figure.

    omega(res)     omega(t) with omega_lim and the time it is passed
    orbit(res)     the relative orbit x_r - x_s, y_r - y_s inside the clearance circle
    contact(res)   d_N / g0 and F_N
    friction(res)  v_t and the friction torque over the driving torque
    timeline(res)  phases (free / slip+ / slip- / stick) as bands, events as marks by kind
    spectrogram(d) the orbit's spectrogram with the Campbell overlay, from `rubdyn analyze`

With several contact planes, orbit, contact, friction and timeline draw one plane: plane=k, or
a plane's view res.plane(k) (without either they refuse, naming the planes); omega draws plane 1's
phase bands. A fixed ring's centre is the origin (no x_s, y_s columns).

    python3 -m rubdyn.plot OUT_DIR [--png DIR]     writes every figure as PNG (default: OUT_DIR),
                                                   the spectrogram when OUT_DIR/analysis has one

Long runs are decimated for drawing (decimate()): per bin the first, last, min and max sample of
every drawn column, plus every sample at an event time; events and phase changes are drawn from the
full data, so none is lost.
"""
import argparse
import os
import sys

import numpy as np

from .result import PHASES, Result, read

# Phases: colours that stay distinct in grey scale print (light to dark), plus hatching in the
# timeline so that slip+ and slip- differ without colour.
PHASE_STYLE = {
    "free": dict(color="#e8e8e8", hatch=None),
    "slip+": dict(color="#f4a259", hatch="//"),
    "slip-": dict(color="#5b8fd1", hatch="\\\\"),
    "stick": dict(color="#2e7d32", hatch=None),
}
# Events: shape and colour, so that a black-and-white print still tells them apart.
EVENT_STYLE = {
    "impact": dict(marker="v", color="#c62828"),
    "liftoff": dict(marker="^", color="#6a1b9a"),
    "stick": dict(marker="s", color="#1b5e20"),
    "slip": dict(marker="D", color="#0d47a1"),
    "reversal": dict(marker="X", color="#ef6c00"),
    "grazing": dict(marker="o", color="#00838f"),
    "zeno": dict(marker="*", color="#000000"),
    "painleve": dict(marker="P", color="#ad1457"),
    "contact": dict(marker="|", color="#4e342e"),
    "release": dict(marker="_", color="#4e342e"),
}
# The rows of the timeline: always these (an empty row says "none"), then any other kind present.
TIMELINE_KINDS = ("impact", "liftoff", "stick", "slip", "zeno", "grazing", "painleve")


def _result(res):
    return res if isinstance(res, Result) else read(res)


def _one_plane(res, what, plane=None):
    """The Result of one contact plane that a figure of one plane draws: `res` itself when it is
    a plane's view (Result.plane), else its plane `plane` (default: the only one), with that
    plane's centres from the model (a fixed ring's centre is the origin: no x_s column). A run
    with several planes needs plane=k: drawing one of them unasked would be silent nonsense."""
    res = _result(res)
    k = res.__dict__.get("plane_index")
    if k is not None:
        if plane is not None and plane != k:
            raise ValueError(f"{what}: this result is plane {k}'s view; plane={plane!r} asked")
        return res
    n = res.planes
    if plane is None:
        if n != 1:
            raise ValueError(f"{what}: this run has {n} contact planes: give plane=k "
                             f"(1..{n}), or draw one plane's view res.plane(k); "
                             "write_all draws each")
        plane = 1
    if res.case is None:  # a Result made by hand: its own columns, the ring at the origin
        if n == 1 and plane == 1:
            return res
        raise ValueError(f"{what}: plane {plane!r} needs the run's case (Result.case)")
    return res.plane(plane)


def _case_value(res, name, default=None):
    # a plane's view (Result.plane) carries that plane's gap, radius and law
    info = res.__dict__.get("plane_info") if isinstance(res, Result) else None
    if info is not None and name in info:
        return info[name]
    case = getattr(res, "case", None)
    return getattr(case, name) if case is not None else default


def _plt():
    import matplotlib
    if "matplotlib.pyplot" not in sys.modules and not os.environ.get("DISPLAY"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _title(fig, res, what):
    name = _case_value(res, "name") or os.path.basename(str(res.source or "")) or "run"
    mu = _case_value(res, "mu")
    extra = f", mu = {mu:g}" if mu is not None else ""
    k = res.__dict__.get("plane_index") if isinstance(res, Result) else None
    if k is not None and res.case is not None and len(res.case.contacts) > 1:
        extra = f", plane {k}" + extra
    fig.suptitle(f"{what}: {name}{extra}", fontsize=11)


def decimate(res, columns, max_points=4000):
    """Indices of the samples to draw: the samples split into max_points / 4 bins, and per bin the
    first, last, argmin and argmax of every column in `columns`; every sample at an event time and
    at a phase change is kept too. All indices when the run is short."""
    t = res["t"]
    n = len(t)
    if n <= max_points:
        return np.arange(n)
    bins = max(1, max_points // 4)
    edges = np.linspace(0, n, bins + 1).astype(int)
    keep = [edges[:-1], np.maximum(edges[1:] - 1, 0)]
    starts = edges[:-1]
    for name in columns:
        y = np.asarray(res[name], dtype=float)
        # per-bin argmin/argmax via reduceat on (value, index) is not available: loop on bins of a
        # reshaped view when the bins are equal, else per bin (bins ~ 1000: cheap either way)
        lo = np.empty(bins, dtype=int)
        hi = np.empty(bins, dtype=int)
        for b in range(bins):
            seg = y[edges[b]:edges[b + 1]]
            if len(seg) == 0:
                lo[b] = hi[b] = starts[b]
                continue
            lo[b] = edges[b] + int(np.nanargmin(seg)) if np.any(~np.isnan(seg)) else edges[b]
            hi[b] = edges[b] + int(np.nanargmax(seg)) if np.any(~np.isnan(seg)) else edges[b]
        keep += [lo, hi]
    if res.events is not None and len(res.events):
        at_event = np.isin(t, res.events["t"])
        keep.append(np.flatnonzero(at_event))
    phase = res["phase"]
    change = np.flatnonzero(phase[1:] != phase[:-1])
    keep += [change, change + 1]
    return np.unique(np.concatenate(keep))


def _phase_runs(res):
    """(t_start, t_end, phase code) of every run of constant phase, from all samples."""
    t, phase = res["t"], res["phase"]
    if len(t) == 0:
        return []
    change = np.flatnonzero(phase[1:] != phase[:-1]) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [len(t)]])
    # a band runs from its first sample to the first sample of the next phase
    return [(t[s], t[min(e, len(t) - 1)], int(phase[s])) for s, e in zip(starts, ends)]


def _shade_phases(ax, res, alpha=0.35):
    for t0, t1, code in _phase_runs(res):
        name = PHASES[code]
        if name == "free":
            continue
        ax.axvspan(t0, t1, color=PHASE_STYLE[name]["color"], alpha=alpha, lw=0)


def _phase_legend_handles(alpha=1.0, res=None, free=True):
    """Patches of the phases (those present in res, when given; free only if free)."""
    from matplotlib.patches import Patch
    present = set(np.unique(res["phase"]).tolist()) if res is not None else set(range(len(PHASES)))
    return [Patch(facecolor=PHASE_STYLE[p]["color"], hatch=PHASE_STYLE[p]["hatch"],
                  edgecolor="0.3", alpha=alpha, label=p) for c, p in enumerate(PHASES)
            if c in present and (free or p != "free")]


def _log_if_wide(ax, y, phase, linthresh):
    """symlog y axis when the largest |y| exceeds 1e3 times the median |y| of some contact phase
    (rolling: forces 1e5 times those of sliding), so that every phase stays readable."""
    y = np.abs(np.asarray(y, dtype=float))
    medians = [np.median(y[(phase == c) & (y > 0)]) for c in range(1, len(PHASES))
               if np.any((phase == c) & (y > 0))]
    if medians and np.nanmax(y) > 1e3 * max(min(medians), linthresh):
        ax.set_yscale("symlog", linthresh=linthresh)
        ax.set_ylabel(ax.get_ylabel() + " (symlog)")


def omega(res, max_points=4000):
    """omega(t) [rad/s] with omega_lim and the time it is passed (summary.t_omega_lim). With
    several contact planes the phase bands under it are plane 1's."""
    res = _result(res)
    if res.__dict__.get("plane_index") is None and res.planes > 1:
        res = res.plane(1)
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.2), layout="constrained")
    i = decimate(res, ["omega"], max_points)
    _shade_phases(ax, res)
    ax.plot(res["t"][i], res["omega"][i], color="k", lw=1.0, label="omega")
    lim = _case_value(res, "omega_lim")
    if lim is not None:
        ax.axhline(lim, color="#c62828", ls="--", lw=1.0, label=f"omega_lim = {lim:g} rad/s")
    t_lim = (res.summary or {}).get("t_omega_lim")
    if t_lim is not None:
        ax.axvline(t_lim, color="#c62828", ls=":", lw=1.0, label=f"passed at {t_lim:.4f} s")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("omega [rad/s]")
    ax.grid(alpha=0.3)
    handles, _ = ax.get_legend_handles_labels()
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.04 * (hi - lo))  # omega_lim may be the top of the data
    # below the axes: the phase bands leave no empty corner when the rotor rolls
    ax.legend(handles=handles + _phase_legend_handles(0.35, res, free=False), fontsize=8,
              loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=6, frameon=False)
    _title(fig, res, "Spin speed")
    return fig


def orbit(res, max_points=20000, plane=None):
    """The rotor centre relative to the stator centre (x_r - x_s, y_r - y_s) [um], coloured by phase,
    inside the clearance circle of radius g0 (a fixed ring's centre is the origin). With several
    contact planes, plane=k draws plane k's (or pass res.plane(k))."""
    res = _one_plane(res, "orbit", plane)
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 6), layout="constrained")
    zero = np.zeros(len(res))
    dx = (res["x_r"] - (res["x_s"] if "x_s" in res else zero)) * 1e6
    dy = (res["y_r"] - (res["y_s"] if "y_s" in res else zero)) * 1e6
    res_rel = Result({"t": res["t"], "dx": dx, "dy": dy, "phase": res["phase"]}, res.events,
                     res.summary)
    i = decimate(res_rel, ["dx", "dy"], max_points)
    g0 = _case_value(res, "gap")
    if g0 is not None:
        a = np.linspace(0, 2 * np.pi, 721)
        ax.plot(g0 * 1e6 * np.cos(a), g0 * 1e6 * np.sin(a), color="0.2", lw=1.5)
    # Lines join samples in free flight only: in contact the orbit lies on the circle and, while
    # rolling, whirls R_r / g0 times faster than the spin (far beyond the output rate), so
    # lines between contact samples would be chords that fill the disc.
    ph = res["phase"][i]
    free_line = np.where(ph == 0, 1.0, np.nan)
    ax.plot(dx[i] * free_line, dy[i] * free_line, color="0.55", lw=0.6, zorder=1)
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color="0.2", lw=1.5, label=f"clearance g0 = {g0 * 1e6:g} um")] \
        if g0 is not None else []
    for code, name in enumerate(PHASES):
        m = ph == code
        if np.any(m):
            color = PHASE_STYLE[name]["color"] if name != "free" else "0.45"
            ax.plot(dx[i][m], dy[i][m], ls="none", marker=".", ms=2.5, color=color, zorder=2)
            handles.append(Line2D([], [], ls="none", marker="o", ms=5, color=color, label=name))
    ax.plot(dx[0], dy[0], "o", color="k", ms=5, zorder=3)
    ax.plot(dx[-1], dy[-1], "s", color="k", ms=5, zorder=3)
    handles += [Line2D([], [], ls="none", marker="o", color="k", ms=5, label="start"),
                Line2D([], [], ls="none", marker="s", color="k", ms=5, label="end")]
    ax.set_aspect("equal")
    ax.set_xlabel("x_r - x_s [um]")
    ax.set_ylabel("y_r - y_s [um]")
    ax.grid(alpha=0.3)
    ax.legend(handles=handles, loc="upper right", fontsize=8)
    _title(fig, res, "Orbit relative to the stator")
    return fig


def contact(res, max_points=4000, plane=None):
    """d_N / g0 and the normal force F_N [N] against time (of plane k with plane=k when there
    are several)."""
    res = _one_plane(res, "contact", plane)
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, layout="constrained")
    i = decimate(res, ["d_N", "F_N"], max_points)
    g0 = _case_value(res, "gap") or 1.0
    for ax in (a1, a2):
        _shade_phases(ax, res)
        ax.grid(alpha=0.3)
    a1.plot(res["t"][i], res["d_N"][i] / g0, color="k", lw=0.8)
    a1.set_ylabel("d_N / g0 [-]" if g0 != 1.0 else "d_N [m]")
    a1.axhline(0.0, color="0.3", lw=0.6)
    a2.plot(res["t"][i], res["F_N"][i], color="#c62828", lw=0.8)
    a2.set_ylabel("F_N [N]")
    _log_if_wide(a2, res["F_N"], res["phase"], 1.0)
    a2.set_xlabel("t [s]")
    a1.legend(handles=_phase_legend_handles(0.35, res, free=False), loc="best", fontsize=8)
    _title(fig, res, "Gap and normal force")
    return fig


def friction(res, max_points=4000, plane=None):
    """v_t [m/s] and the friction torque R_r F_T over the driving torque tau_a (braking > 0), of
    plane k with plane=k when there are several."""
    res = _one_plane(res, "friction", plane)
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, layout="constrained")
    i = decimate(res, ["v_t", "F_T"], max_points)
    for ax in (a1, a2):
        _shade_phases(ax, res)
        ax.grid(alpha=0.3)
    a1.plot(res["t"][i], res["v_t"][i], color="k", lw=0.8)
    a1.axhline(0.0, color="0.3", lw=0.6)
    a1.set_ylabel("v_t [m/s]")
    r_r, tau = _case_value(res, "radius"), _case_value(res, "torque")
    # (a prescribed spin has no driving torque: NaN, its holding torque is an output)
    if r_r is not None and tau and np.isfinite(tau):
        # W_T has -R_r on theta (contact_kinematics.hpp): the friction torque on the spin is
        # -R_r F_T; braking (against a positive tau_a) is drawn positive.
        ratio = r_r * res["F_T"] / tau
        a2.plot(res["t"][i], ratio[i], color="#0d47a1", lw=0.8)
        a2.set_ylabel("R_r F_T / tau_a [-]")
        peak = float(np.nanmax(np.abs(ratio))) if len(ratio) else 0.0
        if peak > 0.3:  # the stall line, unless it would squash a small ratio to a flat line
            a2.axhline(1.0, color="#c62828", ls="--", lw=1.0, label="friction torque = tau_a")
            a2.legend(loc="best", fontsize=8)
        else:
            a2.text(0.01, 0.95, f"max {peak:.3g}: friction torque well below tau_a",
                    transform=a2.transAxes, va="top", fontsize=8,
                    bbox=dict(facecolor="white", edgecolor="0.7", alpha=0.9))
        _log_if_wide(a2, ratio, res["phase"], 1.0)
    else:
        a2.plot(res["t"][i], res["F_T"][i], color="#0d47a1", lw=0.8)
        a2.set_ylabel("F_T [N]")
    a2.set_xlabel("t [s]")
    a1.legend(handles=_phase_legend_handles(0.35, res, free=False), loc="best", fontsize=8)
    _title(fig, res, "Sliding speed and friction torque")
    return fig


def timeline(res, plane=None):
    """Phases as bands (free / slip+ / slip- / stick, colour and hatching) and every event as a
    mark on the row of its kind (count in the label); the legend sits below the axes. With
    several contact planes, plane=k draws plane k's phases and events."""
    res = _one_plane(res, "timeline", plane)
    plt = _plt()
    ev = res.events if res.events is not None else np.zeros(0, dtype=[("t", "f8"), ("kind", "U10")])
    present = [k for k in dict.fromkeys(ev["kind"]) if k not in TIMELINE_KINDS]
    kinds = list(TIMELINE_KINDS) + present
    fig, (band, ax) = plt.subplots(
        2, 1, figsize=(9, 1.2 + 0.35 * len(kinds) + 1.2), sharex=True, layout="constrained",
        gridspec_kw=dict(height_ratios=[1, max(2, 0.45 * len(kinds))]))
    for t0, t1, code in _phase_runs(res):
        st = PHASE_STYLE[PHASES[code]]
        band.axvspan(t0, t1, facecolor=st["color"], hatch=st["hatch"], edgecolor="0.3", lw=0)
    band.set_yticks([])
    band.set_ylabel("phase", rotation=0, ha="right", va="center")
    for row, kind in enumerate(kinds):
        st = EVENT_STYLE.get(kind, dict(marker="o", color="k"))
        t = ev["t"][ev["kind"] == kind]
        ax.plot(t, np.full(len(t), row), ls="none", ms=7, mfc=st["color"], mec="k", mew=0.5,
                marker=st["marker"])
        ax.axhline(row, color="0.85", lw=0.6, zorder=0)
    ax.set_yticks(range(len(kinds)))
    counts = {k: int(np.sum(ev["kind"] == k)) for k in kinds}
    ax.set_yticklabels([f"{k} ({counts[k]})" for k in kinds])
    ax.set_ylim(len(kinds) - 0.5, -0.5)
    ax.set_xlabel("t [s]")
    t_all = res["t"]
    if len(t_all):
        ax.set_xlim(t_all[0], t_all[-1])
    ax.grid(axis="x", alpha=0.3)
    band.legend(handles=_phase_legend_handles(), loc="lower center", bbox_to_anchor=(0.5, 1.0),
                ncol=4, fontsize=9, frameon=False)
    _title(fig, res, "Phases and events")
    return fig


def spectrogram(analysis_dir, f_max=None):
    """The orbit's spectrogram (whirl frequency: forward > 0, backward < 0) with the Campbell
    frequencies at each frame's spin speed, from the folder `rubdyn analyze` writes (default
    OUT_DIR/analysis: spectrogram.csv, campbell.csv). Amplitudes on a log colour scale."""
    import matplotlib.patheffects as pe
    from matplotlib.colors import LogNorm
    plt = _plt()
    d = np.loadtxt(os.path.join(analysis_dir, "spectrogram.csv"), delimiter=",", skiprows=1,
                   ndmin=2)
    t, f = np.unique(d[:, 0]), np.unique(d[:, 1])
    amp = np.full((len(f), len(t)), np.nan)
    amp[np.searchsorted(f, d[:, 1]), np.searchsorted(t, d[:, 0])] = d[:, 2]
    fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    positive = amp[np.isfinite(amp) & (amp > 0)]
    top = positive.max() if positive.size else 1.0
    # four decades below the peak: the whirl lines stand out, the windowing floor does not
    mesh = ax.pcolormesh(t, f, np.where(amp > 0, amp, np.nan), shading="nearest", cmap="magma_r",
                         norm=LogNorm(vmin=top * 1e-4, vmax=top))
    fig.colorbar(mesh, ax=ax, label="orbit amplitude [m]")
    cp = os.path.join(analysis_dir, "campbell.csv")
    if os.path.exists(cp):
        c = np.genfromtxt(cp, delimiter=",", names=True)
        for name, style in (("f1f", "-"), ("f2f", "--"), ("f1b", "-"), ("f2b", "--")):
            color = "#1565c0" if name.endswith("f") else "#2e7d32"
            # a white halo: the first modes (about +-100 Hz) lie on the darkest part
            ax.plot(c["t"], c[name], ls=style, color=color, lw=1.6,
                    path_effects=[pe.Stroke(linewidth=3.2, foreground="white"), pe.Normal()],
                    label=f"Campbell {name} ({'forward' if name.endswith('f') else 'backward'})")
        if "undersampled" in (c.dtype.names or ()):
            # frames whose samples alias the orbit's whirl (rolling whirls at R_r / g0 times the
            # spin): hatched, so that no one reads their stripes as spectrum
            bad = np.atleast_1d(c["undersampled"]) > 0.5
            tc = np.atleast_1d(c["t"])
            half = 0.5 * (tc[1] - tc[0]) if len(tc) > 1 else 0.0
            for i, k in enumerate(np.flatnonzero(bad)):
                ax.axvspan(tc[k] - half, tc[k] + half, facecolor="0.85", alpha=0.85, hatch="//",
                           edgecolor="0.4", lw=0, label=None if i else
                           "undersampled: the whirl (up to %.3g kHz) aliases; a smaller "
                           "output.dt reads it" % (np.atleast_1d(c["f_whirl"])[bad].max() / 1e3))
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8,
                  frameon=False)
    if f_max is not None:
        ax.set_ylim(-f_max, f_max)
    ax.axhline(0.0, color="0.5", lw=0.5)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("whirl frequency [Hz] (forward > 0)")
    fig.suptitle(f"Spectrogram of the orbit with the Campbell frequencies: "
                 f"{os.path.basename(os.path.dirname(os.path.abspath(analysis_dir)))}",
                 fontsize=11)
    return fig


FIGURES = {"omega": omega, "orbit": orbit, "contact": contact, "friction": friction,
           "timeline": timeline}


def write_all(res, out_dir, dpi=130):
    """Writes every figure as out_dir/<name>.png; returns the paths. With several contact
    planes, the figures of one plane (orbit, contact, friction, timeline, spectrogram) are drawn
    for each plane k as <name>_k.png (Result.plane), the spin once."""
    plt = _plt()
    res = _result(res)
    os.makedirs(out_dir, exist_ok=True)
    paths = []

    def save(fig, name):
        path = os.path.join(out_dir, f"{name}.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        paths.append(path)

    planes = res.planes
    for name, make in FIGURES.items():
        if planes <= 1:
            save(make(res), name)
            continue
        if name == "omega":  # one spin; the phase bands drawn under it are plane 1's
            save(make(res.plane(1)), name)
            continue
        for k in range(1, planes + 1):
            save(make(res.plane(k)), f"{name}_{k}")
    analysis = os.path.join(str(res.source or ""), "analysis")
    for k in range(1, max(planes, 1) + 1):
        # written by `rubdyn analyze OUT_DIR`: plane 1 in analysis/, plane k in analysis/plane_k
        folder = analysis if k == 1 else os.path.join(analysis, f"plane_{k}")
        if res.source and os.path.exists(os.path.join(folder, "spectrogram.csv")):
            save(spectrogram(folder), "spectrogram" if planes <= 1 else f"spectrogram_{k}")
    return paths


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python3 -m rubdyn.plot",
                                 description="Figures of a rubdyn output folder (PNG)")
    ap.add_argument("out_dir", help="output folder written by `rubdyn run`")
    ap.add_argument("--png", metavar="DIR", help="where to write the PNGs (default: OUT_DIR)")
    a = ap.parse_args(argv)
    for p in write_all(read(a.out_dir), a.png or a.out_dir):
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
