#!/usr/bin/python3
"""Which whirl definition matches the paper's whip onset (issue 14, item 5).

`rubdyn analyze` reports two backward-whirl onsets (include/rubdyn/analysis/postprocess.hpp):
  sign       precession-sign whirl: the first run of samples with backward precession covering
             one orbit revolution, in contact or in flight (partial contact allowed);
  sustained  the same, counting samples in contact only (the whip verdicts use this one).
The paper (section 5.2, Fig. 11-12, k_s* = 10, mu = 0.1) describes whip onset as a sequence:
  (1) while contact is partial the friction torque vanishes for short periods and stays below
      the drive;
  (2) contact becomes permanent (t > 0.45 t_ref);
  (3) then the precession becomes strictly negative and keeps decreasing: "dry whip" (0.5 t_ref);
  (4) the friction torque overcomes the drive and the speed decreases.
A definition matches when its onset sits at (2)-(3): in closed contact that stays closed, after
the partial-contact stage, and followed by (4). This script measures, for every run of a grid
that whirls backward by either definition, where each onset falls:
  in contact     the onset sample is in contact;
  closed 0.05    no lift-off in the 0.05 t_ref after the onset (the paper's gap between (2) and
                 (3) is 0.05 t_ref);
  lift-offs      before the speed peak, after the onset (the paper: none);
  lag            from the onset to the speed peak, in t_ref (runs whose speed peaks after the
                 onset; the paper: about 0 to 0.05, (3) and (4) nearly together);
and draws Fig. 11-12 of the reference case at k_s* = 10, mu = 0.1 (the paper's setup; cases/
paper.toml does not whip there, validation/calibration) with both onsets marked.

Grid: cases/reference.toml at mu = 0.1, k_s* = 7 ... 10 (step 0.5), and at k_s* = 1, mu = 0.17
... 0.25; cases/paper.toml at k_s* = 1, mu = 0.22 ... 0.30; runs of each case's run.t_end.
t_ref := t(Omega >= Omega_lim at mu = 0.1) / 0.76 for each case (as in claims.py).
Writes whirl.md and fig-whirl-ks10.png, fig-whirl-ks10-spectrogram.png here; runs go to
out/paper-whirl/. Usage: validation/paper/whirl.py [path/to/rubdyn] [--quick]. About 2 min on
2 cores.
"""
import os
import sys
import tomllib

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import ROOT, Campbell, Run, machine, read_csv, run_analyzed, script_args, sweep  # noqa: E402
from paper_axes import spectrogram_panel  # noqa: E402

RUBDYN, QUICK, OUT = script_args("paper-whirl")
T_LIM_TREF = 0.76
CLOSED_WINDOW = 0.05  # t_ref: the paper's gap between permanent contact and whip onset


def t_ref(case, spec):
    folder = run_analyzed(RUBDYN, case, os.path.join(OUT, os.path.basename(case) + "-tref"),
                          2 * spec["run"]["t_end"], ["contact.mu=0.1"])
    return Run(folder).a["t_omega_lim"] / T_LIM_TREF


def onset_index(r, column):
    """The first sample of a backward run of derived.csv's `column` (sustained or sign_run: both
    mark forward and backward runs, told apart by the sign of the precession against the spin)."""
    mark = np.array([int(x[column]) for x in read_csv(os.path.join(r.folder, "analysis",
                                                                   "derived.csv"))]) > 0
    idx = np.where(mark & (r.prec * r.omega < 0))[0]
    return int(idx[0]) if len(idx) else None


def onset_facts(r, i0, tref):
    """Where the onset at sample i0 falls in run r (see the module docstring)."""
    t0 = r.t[i0]
    i_pk = int(np.argmax(r.omega))
    t_pk = r.t[i_pk]
    peak_after = t_pk > t0 and i_pk < len(r.t) - 1  # a peak inside the run, after the onset
    return {
        "onset": t0 / tref,
        "in_contact": bool(r.contact[i0]),
        "closed": r.liftoffs(t0, t0 + CLOSED_WINDOW * tref) == 0,
        "liftoffs": r.liftoffs(t0, t_pk) if peak_after else None,
        "lag": (t_pk - t0) / tref if peak_after else None,
    }


def grid_runs():
    """[(label, case name, Run, t_ref)] for every run of the grid."""
    out = []
    ref = os.path.join(ROOT, "cases", "reference.toml")
    paper = os.path.join(ROOT, "cases", "paper.toml")
    studies = [
        (ref, "ks-mu0.1", "stator.k", [7, 7.5, 8, 8.5, 9, 9.5, 10] if not QUICK else [8.5, 10],
         ["contact.mu=0.1"], True),
        (ref, "mu-ks1", "contact.mu",
         [0.17, 0.18, 0.19, 0.2, 0.21, 0.22, 0.25] if not QUICK else [0.2], [], False),
        (paper, "mu-ks1", "contact.mu",
         [0.22, 0.23, 0.24, 0.25, 0.27, 0.3] if not QUICK else [0.25], [], False),
    ]
    for case, name, key, values, sets, scaled in studies:
        spec = tomllib.load(open(case, "rb"))
        tref = t_ref(case, spec)
        k_ref = spec["stator"]["k"]
        vals = [v * k_ref for v in values] if scaled else values
        rows = sweep(RUBDYN, case, os.path.join(OUT, os.path.basename(case) + "-" + name),
                     spec["run"]["t_end"], [key + "=" + ",".join("%.9g" % v for v in vals)], sets)
        for v, row in zip(values, rows):
            label = "%s, %s = %g%s" % (spec.get("name", os.path.basename(case)),
                                       "k_s*" if scaled else "mu", v,
                                       ", mu = 0.1" if scaled else "")
            out.append((label, os.path.basename(case), Run(row["folder"]), tref))
    return out


def fmt(x, spec="%.3f"):
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return spec % x


def table(runs):
    lines = ["| run | sign onset | in contact | closed %.2f | lift-offs to peak | lag to peak | "
             "sustained onset | in contact | closed %.2f | lift-offs to peak | lag to peak | "
             "permanent contact from |" % (CLOSED_WINDOW, CLOSED_WINDOW),
             "|---|" + "---|" * 11]
    stats = {"sign": [], "sustained": []}
    for label, _, r, tref in runs:
        a = r.a
        if a["sign_backward_onset"] is None and a["backward_onset"] is None:
            continue
        cells = [label]
        for name, key, column in (("sign", "sign_backward_onset", "sign_run"),
                                  ("sustained", "backward_onset", "sustained")):
            if a[key] is None:
                cells += ["none", "-", "-", "-", "-"]
                continue
            i0 = onset_index(r, column)
            assert i0 is not None and r.t[i0] == a[key], (label, key)  # derived.csv = analysis
            f = onset_facts(r, i0, tref)
            stats[name].append(f)
            cells += [fmt(f["onset"]), fmt(f["in_contact"]), fmt(f["closed"]),
                      fmt(f["liftoffs"], "%d"), fmt(f["lag"])]
        pc = a["permanent_contact_onset"]
        cells.append(fmt(pc / tref if pc is not None else None))
        lines.append("| " + " | ".join(cells) + " |")
    return lines, stats


def summary(stats):
    lines = ["| definition | runs | onset in contact | closed for %.2f t_ref after | no lift-off "
             "before the speed peak | median lag to the peak [t_ref] |" % CLOSED_WINDOW,
             "|---|---|---|---|---|---|"]
    for name, fs in stats.items():
        n = len(fs)
        lags = [f["lag"] for f in fs if f["lag"] is not None]
        peaked = [f for f in fs if f["liftoffs"] is not None]
        lines.append("| %s | %d | %d | %d | %d of %d | %s |" % (
            name, n, sum(f["in_contact"] for f in fs), sum(f["closed"] for f in fs),
            sum(f["liftoffs"] == 0 for f in peaked), len(peaked),
            "%.3f" % np.median(lags) if lags else "-"))
    return lines


def figures(runs):
    """Fig. 11-12 of the reference case at k_s* = 10, mu = 0.1 with both onsets."""
    pick = [x for x in runs if x[1] == "reference.toml" and "k_s* = 10," in x[0]]
    if not pick:
        return None
    label, _, r, tref = pick[0]
    ref = os.path.join(ROOT, "cases", "reference.toml")
    spec = tomllib.load(open(ref, "rb"))
    oml, g0 = spec["run"]["omega_lim"], spec["stator"]["gap"]
    a = r.a
    marks = [(a["sign_backward_onset"], "C0", "--", "sign-whirl onset"),
             (a["backward_onset"], "C3", "-", "sustained-whirl onset"),
             (a["permanent_contact_onset"], "0.4", ":", "permanent contact from")]
    t = r.t / tref
    fig, ax = plt.subplots(4, 1, figsize=(9, 11), sharex=True)
    ax[0].plot(t, r.omega / oml, "k-", lw=1)
    ax[0].axhline(1, color="r", ls=":", lw=0.8)
    ax[1].plot(t, r.ftr, "k-", lw=0.5)
    ax[1].axhline(1, color="r", ls=":", lw=0.8)
    ax[2].plot(t, r.prec, "k-", lw=0.5)
    ax[2].set_yscale("symlog", linthresh=10)
    ax[3].plot(t, r.dN / g0, "k-", lw=0.5)
    for axis, y in zip(ax, ["Omega / Omega_lim", "R_r F_T / tau_a", "v_prec [rad/s] (raw)",
                            "d_N / g0"]):
        axis.set_ylabel(y)
        axis.grid(alpha=0.3)
        for tm, c, ls, name in marks:
            if tm is not None:
                axis.axvline(tm / tref, color=c, ls=ls, lw=1.2, label=name)
    ax[0].legend(fontsize=8, loc="lower center")
    ax[3].set_xlabel("t / t_ref")
    fig.suptitle("Fig. 11 with both whirl onsets: %s (event-driven)" % label)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "fig-whirl-ks10.png"), dpi=90)
    plt.close(fig)
    cb10 = Campbell(RUBDYN, ref, os.path.join(OUT, "campbell-ks10"), 1.2 * oml,
                    ["stator.k=%.9g" % (10 * spec["stator"]["k"])])
    png = os.path.join(HERE, "fig-whirl-ks10-spectrogram.png")
    spectrogram_panel(r, cb10, tref, 1.15 * max(cb10("f2f", oml), cb10("f2b", 0)),
                      "Fig. 12 with both whirl onsets: %s" % label, png,
                      [m for m in marks if m[0] is not None])
    # the same onsets from the paper's two solvers (h = 1e-6), as in its Fig. 11
    solvers = [("event", r)]
    for solver in ("carp-onevc", "mj-proj"):
        folder = run_analyzed(RUBDYN, ref, os.path.join(OUT, "ks10-" + solver),
                              spec["run"]["t_end"],
                              ["contact.mu=0.1", "stator.k=%.9g" % (10 * spec["stator"]["k"])],
                              ["--solver", solver, "--h", "1e-6"])
        solvers.append((solver + " (h = 1e-6)", Run(folder)))
    rows = ["| solver | sign onset | sustained onset | permanent contact from | speed peak |",
            "|---|---|---|---|---|"]
    for name, rr in solvers:
        a = rr.a
        rows.append("| %s | %s | %s | %s | %s |" % (
            name, *[fmt(a[k] / tref if a[k] is not None else None)
                    for k in ("sign_backward_onset", "backward_onset", "permanent_contact_onset")],
            fmt(rr.t[int(np.argmax(rr.omega))] / tref)))
    return label, rows


def main():
    os.makedirs(OUT, exist_ok=True)
    runs = grid_runs()
    rows, stats = table(runs)
    fig = figures(runs)
    with open(os.path.join(HERE, "whirl.md"), "w") as f:
        f.write("# Whirl definition: which onset matches the paper's whip onset\n\n"
                "Generated by `validation/paper/whirl.py`%s. Machine: %s. Times in t_ref of each "
                "case.\n\n" % (" --quick" if QUICK else "", machine()))
        f.write("## Summary\n\n" + "\n".join(summary(stats)) + "\n\n")
        if fig:
            f.write("## Fig. 11-12 setup: %s\n\n"
                    "Times in t_ref; fig-whirl-ks10.png and fig-whirl-ks10-spectrogram.png mark "
                    "the event-driven run's onsets.\n\n" % fig[0])
            f.write("\n".join(fig[1]) + "\n\n")
        f.write("## Every run that whirls backward\n\n" + "\n".join(rows) + "\n")
    print(open(os.path.join(HERE, "whirl.md")).read())


if __name__ == "__main__":
    main()
