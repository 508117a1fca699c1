#!/usr/bin/python3
"""rubdyn against the closed forms of docs/closed-forms.md (Jeffcott-Black model; the rolling
kinematics on the paper's rigid rotor too): runs rubdyn's event-driven solver on each closed
form's case, started on or near its steady state, and measures how close the runs get and how
fast (rubdyn_runs.py says what is measured and how).

  (a) rolling kinematics phi' = -(R/g0) Omega in every stick sample, rigid rotor and Jeffcott;
  (b) rigid stator, torque-driven rolling: Omega(t) against the exponential over the whole
      phase, the steady spin, whirl, N, F_T, the time constant; constant and linear torque;
  (c) Black's model, steady rolling on both branches of the bistable set BLACK_ROLL;
  (d) whip with frequency locking (BLACK_WHIP): locked whirl, N, the spin's rate, t_stick;
  (e) unbalance at a prescribed speed, rigid stator (UNB): N, delta, the drive torque, and
      which root attracts;
  (f) power balance over windows of whole whirl periods of the converged orbits.
Then the same comparisons at four tolerances (what the remaining differences are due to), the
decay rate of each approach against the orbit's eigenvalue.

Writes table.md and approach.png next to this script, the output folders to out/analytic/.
Usage: validation/analytic/run.py [path/to/rubdyn]       (about 1 minute on 2 cores)
"""
import datetime
import hashlib
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))
import closed_forms as cf  # noqa: E402
import rubdyn_runs as rr  # noqa: E402
from common import machine  # noqa: E402

ROOT = rr.ROOT
LADDER = [("default", rr.DEFAULT), ("1e-11", {"rtol": 1e-11, "atol": 1e-13}),
          ("tight", rr.TIGHT), ("1e-13", {"rtol": 1e-13, "atol": 1e-16})]
LOG = []


def say(msg):
    print(msg, flush=True)
    LOG.append(msg)


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def rubdyn_label(rubdyn):
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "src", "include"], cwd=ROOT,
                               capture_output=True, text=True).stdout.strip()
    except OSError:
        commit, dirty = "unknown", ""
    mtime = datetime.datetime.fromtimestamp(os.path.getmtime(rubdyn)).strftime("%Y-%m-%d %H:%M")
    return "%s (commit %s%s, binary built %s, sha256 %s)" % (
        os.path.relpath(rubdyn, ROOT), commit, ", src/include modified" if dirty else "",
        mtime, sha256(rubdyn)[:16])


# ---- formatting -----------------------------------------------------------------------------------
def g13(x):
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    return "%.13g" % x


def e2(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return "%.1e" % x


def reach_cell(q, level, predicted=None):
    if not q.reach or q.t is None:
        return "-"
    t = q.t_reach(level)
    if t is None:
        cell = "not reached: ends at %.1e" % q.dev[-1]
    else:
        cell = "%.4f" % t
    if predicted is not None:
        cell += " (%s)" % ("%.4f" % predicted if predicted is not None else "-")
    return cell


# ---- the studies ----------------------------------------------------------------------------------
def short_status(st):
    if st is None:
        return "-"
    for n in st.notes:
        if "CV_TOO_MUCH_ACC" in n:
            t = n.split("at t = ")[1].split(" s")[0]
            return "stopped at t = %.3g s: CV_TOO_MUCH_ACC" % float(t)
    return st.status


def rigid_predicted(st):
    """The exact solution's deviations (section 2.2-2.3) on the run's sample times: the times
    the closed form itself takes to come within 1e-6 and 1e-8 of its steady state."""
    P = rr.rigid_params(st.key.split("-")[1])
    s = cf.short(P)
    cfr, Om0 = rr.rigid_closed(P)
    t = st.output.t
    Om = cf.rolling_rigid_stator_spin(s["m_r"], s["c_r"], s["J"], s["R"], s["tau"],
                                      rr.OMEGA_START_RIGID, t, Omega_0=Om0)
    dOm = (cfr["Omega"] - Om) / cfr["time_constant"]
    w = -(s["R"] / s["g0"]) * Om
    series = {"Omega_ss": Om, "whirl w = phi'": w, "N": s["g0"] * (s["m_r"] * w * w - s["k_r"]),
              "F_T": s["m_r"] * s["R"] * dOm + s["c_r"] * s["R"] * Om}
    ss = {"Omega_ss": cfr["Omega"], "whirl w = phi'": cfr["w"], "N": cfr["N"],
          "F_T": cfr["F_T"]}
    out = {}
    for q in st.quantities:
        for k, y in series.items():
            if q.name.startswith(k) and q.reach:
                d = rr.rel(y, ss[k])
                out[q.name] = (rr.time_to_reach(t, d, 1e-6), rr.time_to_reach(t, d, 1e-8))
    return out


def all_studies(rubdyn, out, tol, with_power=True, with_kinematics=True):
    S = {}
    S["rigid-constant"] = rr.study_rigid_rolling(rubdyn, out, "constant", tol)
    S["rigid-linear"] = rr.study_rigid_rolling(rubdyn, out, "linear", tol)
    S["black-low"] = rr.study_black_rolling(rubdyn, out, 0, tol)
    S["black-high"] = rr.study_black_rolling(rubdyn, out, 1, tol)
    S["black-low-exact"] = rr.study_black_rolling(rubdyn, out, 0, tol, exact=True)
    S["black-high-exact"] = rr.study_black_rolling(rubdyn, out, 1, tol, exact=True)
    S["whip-exact"] = rr.study_whip_exact(rubdyn, out, tol)
    S["whip-exact-linear"] = rr.study_whip_exact(rubdyn, out, tol, law="linear")
    S["whip-approach"] = rr.study_whip_approach(rubdyn, out, tol)
    S["unbalance"] = rr.study_unbalance(rubdyn, out, tol)
    if with_power:
        S["power"] = rr.study_power(rubdyn, out, S["rigid-constant"],
                                    [S["black-low"], S["black-high"]], S["whip-approach"], tol,
                                    unb_st=S["unbalance"])
    if with_kinematics:
        S["kin-rigid-rotor"] = rr.study_rolling_rigid_rotor(rubdyn, out, tol)
        S["kin-rigid-rotor-projection"] = rr.study_rolling_rigid_rotor(
            rubdyn, out, rr.DEFAULT, t_end=0.2, phases="projection")
        S["kin-jeffcott"] = rr.study_rolling_jeffcott(rubdyn, out, tol)
        S["kin-jeffcott-projection"] = rr.study_rolling_jeffcott(rubdyn, out, tol,
                                                                 phases="projection")
        S["kin-jeffcott-pooled"] = rr.kinematics_of(
            [S[k] for k in ("rigid-constant", "rigid-linear", "black-low", "black-high",
                            "black-low-exact", "black-high-exact", "whip-exact",
                            "whip-exact-linear", "whip-approach")],
            "Rolling kinematics, Jeffcott: the stick samples of every run of (b)-(d)",
            "kinematics-jeffcott-pooled")
    return S


SECTIONS = [
    ("(a) rolling kinematics phi' = -(R/g0) Omega (1.1)",
     ["kin-rigid-rotor", "kin-rigid-rotor-projection", "kin-jeffcott", "kin-jeffcott-projection",
      "kin-jeffcott-pooled"]),
    ("(b) rigid stator, torque-driven rolling (2.4), constant torque", ["rigid-constant"]),
    ("(b) rigid stator, rolling, linear torque law (2.3), Omega_0 = 40 rad/s", ["rigid-linear"]),
    ("(c) Black's model, rolling (3.1), low branch (w = -1370 rad/s)", ["black-low",
                                                                        "black-low-exact"]),
    ("(c) Black's model, rolling (3.1), high branch (w = -5933 rad/s)", ["black-high",
                                                                         "black-high-exact"]),
    ("(d) whip, locked frequency (4.1)-(4.3), middle root (w = -1537 rad/s)",
     ["whip-exact", "whip-exact-linear", "whip-approach"]),
    ("(e) unbalance at a prescribed speed (5.1), rigid stator, larger root", ["unbalance"]),
    ("(f) power balance (section 6) over whole whirl periods", ["power"]),
]


# ---- the figure ------------------------------------------------------------------------------------
def plot(S, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    floor = 1e-17
    panels = [
        ("(b) rigid stator, constant torque", ["rigid-constant"]),
        ("(b) rigid stator, linear torque", ["rigid-linear"]),
        ("(c) Black rolling, low branch", ["black-low", "black-low-exact"]),
        ("(c) Black rolling, high branch", ["black-high", "black-high-exact"]),
        ("(d) whip, started on the orbit (slip until t_stick)", ["whip-exact",
                                                                  "whip-exact-linear"]),
        ("(d) whip, started off the orbit (slip until t_stick)", ["whip-approach"]),
        ("(e) unbalance, prescribed speed", ["unbalance"]),
        ("(a) rolling kinematics", ["kin-rigid-rotor", "kin-jeffcott",
                                    "kin-rigid-rotor-projection"]),
    ]
    fig, axes = plt.subplots(2, 4, figsize=(22, 10))
    for ax, (title, keys) in zip(axes.flat, panels):
        n = 0
        for key in keys:
            st = S.get(key)
            if st is None:
                continue
            exact = key.endswith("-exact") or key == "whip-exact"
            for q in st.quantities:
                if q.t is None or q.name.startswith("whirl w from"):
                    continue
                lab = q.name.split(",")[0].replace(" (positions", "")[:48]
                if key.startswith("kin-"):
                    lab = st.title.split(", ", 1)[1] if ", " in st.title else st.title
                    lab = lab.replace("Jeffcott (Black rolling branch with gravity and "
                                      "unbalance)", "Jeffcott, g and u_b on")
                lab += " (on the orbit)" if exact and key != "whip-exact" else ""
                lab += " (linear law)" if key == "whip-exact-linear" else ""
                ls = ":" if exact and key != "whip-exact" else "-"
                ls = "--" if key == "whip-exact-linear" else ls
                ax.semilogy(q.t, np.maximum(q.dev, floor), lw=0.8, ls=ls, label=lab)
                n += 1
        if n == 0:
            st = S.get(keys[0])
            ax.set_yscale("log")
            note = "; ".join(st.notes) if st else ""
            words, lines = note.split(), [""]
            for wd in words:
                if len(lines[-1]) + len(wd) > 48:
                    lines.append("")
                lines[-1] += (" " if lines[-1] else "") + wd
            ax.text(0.5, 0.5, "\n".join(lines), ha="center", va="center",
                    transform=ax.transAxes, fontsize=8)
        for lev in (1e-6, 1e-8):
            ax.axhline(lev, color="k", lw=0.6, ls="--")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("|rubdyn - closed form| / |closed form|")
        ax.set_ylim(1e-17, 10)
        ax.grid(True, which="major", alpha=0.3)
        if n:
            ax.legend(fontsize=6, loc="upper right")
    fig.suptitle("rubdyn's approach to the closed forms (event-driven, rtol %g, atol %g; "
                 "dashed: 1e-6 and 1e-8)" % (rr.TIGHT["rtol"], rr.TIGHT["atol"]), fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=110)


# ---- the table ---------------------------------------------------------------------------------------
def run_ids(S):
    """R1, R2, ... for every run folder, in the order of the sections, owned by the study that
    ran it (the pooled kinematics study only reads the runs of (b)-(d))."""
    ids, rows = {}, []
    order = [k for _, keys in SECTIONS[1:] + SECTIONS[:1] for k in keys]
    for key in order:
        st = S.get(key)
        if st is None or key == "kin-jeffcott-pooled":
            continue
        for label, o in st.runs:
            if o.folder not in ids:
                ids[o.folder] = "R%d" % (len(ids) + 1)
                rows.append((ids[o.folder], st, label, o))
    for key in order:
        st = S.get(key)
        if st is None:
            continue
            for label, o in st.runs:
                if o.folder in ids:
                    continue
                ids[o.folder] = "R%d" % (len(ids) + 1)
                rows.append((ids[o.folder], st, label, o))
    return ids, rows


def write_table(path, S, ladder, rates, label, wall_total):
    ids, runs = run_ids(S)
    L = ["# rubdyn against the closed forms (docs/closed-forms.md)\n"]
    L.append("Generated by `validation/analytic/run.py` on %s in %.0f s. Machine: %s. rubdyn: "
             "`%s`.\n" % (datetime.date.today().isoformat(), wall_total, machine(), label))
    L.append("Every run is `rubdyn run` (event-driven solver, CVODES Adams in every phase, "
             "contact phases in reduced coordinates unless said) with rtol %g and atol %g m "
             "(velocities: atol x 1e3 /s) unless said, output every %g s, gravity 0 and no "
             "unbalance except where said; the runs are listed in section 2 with their "
             "settings and wall times. **Relative difference**: |rubdyn - closed form| / "
             "|closed form| at the last sample of the run (or of the slip phase), unless the "
             "quantity says *largest*. **Reaches 1e-6 / 1e-8 at**: the first sample time after "
             "which the relative difference stays below the level to the end of the run "
             "(t = 0 at the start); in parentheses, for (b), the time the exact solution itself "
             "takes. '-': not a quantity with an approach.\n"
             % (rr.TIGHT["rtol"], rr.TIGHT["atol"], rr.DT))
    L.append("## 1. The comparison\n")
    L.append("| closed form | quantity | closed form | rubdyn | relative difference | reaches "
             "1e-6 at [s] | reaches 1e-8 at [s] | run |")
    L.append("|---|---|---|---|---|---|---|---|")
    for title, keys in SECTIONS:
        first = True
        for key in keys:
            st = S.get(key)
            if st is None:
                continue
            pred = rigid_predicted(st) if key.startswith("rigid-") else {}
            rid = ", ".join(ids[o.folder] for _, o in st.runs)
            if st.status == "refused":
                L.append("| %s | all | - | - | - | refused | refused | %s |"
                         % (title, rid))
                L.append("| | | | | | | | *%s* |" % "; ".join(st.notes).replace("|", "/"))
                continue
            start = ""
            if key.endswith("-exact") and len(keys) == 1:
                start = " (started on the orbit)"
            if len(keys) > 1:
                L.append("| %s | ***%s*** | | | | | | |" % (title if first else "", st.title))
                first = False
            for q in st.quantities:
                p = pred.get(q.name, (None, None))
                L.append("| %s | %s%s | %s | %s | %s | %s | %s | %s |" % (
                    title if first else "", q.name, start, g13(q.closed), g13(q.measured),
                    e2(q.rel), reach_cell(q, 1e-6, p[0] if pred else None),
                    reach_cell(q, 1e-8, p[1] if pred else None),
                    ", ".join(ids[f] for f in q.runs) if q.runs else rid))
                first = False
            if st.status not in ("ok",):
                L.append("| | *%s: %s* | | | | | | |" % (st.status, "; ".join(st.notes)))
    L.append("")
    notes = [n for k in ("whip-exact", "unbalance") if k in S for n in S[k].notes]
    for n in notes:
        L.append("- %s" % n)
    L.append("")
    L.append("## 2. The runs\n")
    L.append("| run | what | start | simulated [s] | settings | steps | wall [s] | termination |")
    L.append("|---|---|---|---|---|---|---|---|")
    for rid, st, lab, o in runs:
        sm = o.summary
        L.append("| %s | %s | %s | %.6g to %.6g | %s | %d | %.3f | %s |" % (
            rid, st.title, lab, sm["t_start"], sm["t_reached"], rr.settings(o), sm["steps"],
            o.wall, sm["termination"]))
    L.append("")
    L.append("Command of each run: `rubdyn run CASE --out DIR --quiet --t-end T --rtol R --atol A "
             "--set initial.KEY=VALUE ...` with CASE the case text in the output folder's parent "
             "(`out/analytic/NAME.toml`: cases/jeffcott.toml with the closed form's keys "
             "written over it) and the initial state of closed_forms.py; the windows of (f) add "
             "`--from DIR --at T1`.\n")
    L.append("## 3. How fast the runs approach the orbits\n")
    L.append("Decay rate of the relative difference (slope of the log of its envelope, the "
             "bound it stays under, while it falls from 1e-5 to 3e-9: the slowest mode "
             "dominates there and the integration error does not yet) against the slowest "
             "eigenvalue of the orbit in its own frame, from the independent simulation's "
             "vector field (`reference_sim.orbit_eigenvalues`, which the runs do not use), and "
             "for the rigid stator against 1/T_c. The starts off the orbit translate rotor and "
             "stator by 1e-3 g0 and scale r' (and, rolling, the spin) by 1 + 1e-3: the "
             "translation alone (black-high-translated: 1e-3 g0, r' and spin unchanged) barely "
             "excites the high rolling branch's slowest (real) mode, and the approach runs at "
             "the next ones.\n")
    L.append("| run | quantity | measured rate [1/s] | slowest rate: 1/T_c or -max Re(eigenvalue) "
             "[1/s] | ratio | every -Re(eigenvalue) [1/s] |")
    L.append("|---|---|---|---|---|---|")
    for r in rates:
        L.append("| %s | %s | %s | %.4f | %s | %s |" % (
            r[0], r[1], "%.4f" % r[2] if r[2] else "-", r[3],
            "%.4f" % (r[2] / r[3]) if r[2] else "-", r[4]))
    L.append("")
    L.append("## 4. What the remaining differences are due to: the solver's tolerance\n")
    L.append("The same runs at four settings (rtol / atol on positions); relative difference at "
             "the end of each run (*largest* where the quantity says so). Steps and wall time "
             "of each run in the last rows.\n")
    head = " | ".join("rtol %g, atol %g" % (t["rtol"], t["atol"]) for _, t in LADDER)
    L.append("| run | quantity | %s |" % head)
    L.append("|---|---|%s" % ("---|" * len(LADDER)))
    for key, names in ladder["rows"]:
        for name in names:
            cells = []
            for lab, _ in LADDER:
                st = ladder["S"][lab].get(key)
                if st is None or st.status != "ok":
                    cells.append(short_status(st))
                    continue
                q = next((x for x in st.quantities if x.name == name), None)
                cells.append(e2(q.rel) if q is not None else "-")
            L.append("| %s | %s | %s |" % (key, name, " | ".join(cells)))
        cells = []
        for lab, _ in LADDER:
            st = ladder["S"][lab].get(key)
            if st is None or st.status in ("refused", "skipped"):
                cells.append(short_status(st))
                continue
            cells.append("; ".join("%d steps, %.3f s%s" % (
                o.summary["steps"], o.wall, "" if o.summary["complete"] else
                ", " + o.summary["termination"]) for _, o in st.runs))
        L.append("| %s | steps, wall | %s |" % (key, " | ".join(cells)))
    L.append("")
    stopped = []
    for lab, _ in LADDER:
        tol = dict(LADDER)[lab]
        for key, st in ladder["S"][lab].items():
            for rl, o in st.runs:
                if not o.summary["complete"]:
                    stopped.append((lab, tol, key, o))
    if stopped:
        L.append("Runs that stopped early:\n")
        L.append("| setting | run | stopped at t [s] | message |")
        L.append("|---|---|---|---|")
        for lab, tol, key, o in stopped:
            L.append("| rtol %g, atol %g | %s | %.6g | %s |" % (
                tol["rtol"], tol["atol"], key, o.summary["t_reached"], o.summary["message"]))
        L.append("")
    # Long rolling phases: in a stick phase rubdyn integrates theta - theta_a (theta_a: the spin
    # angle where the phase began) with an absolute error weight (rtol g0 + atol) / R, while the
    # coordinate's rounding grows like eps |theta - theta_a|. CVODES stops with CV_TOO_MUCH_ACC
    # once eps times the weighted RMS norm of the state exceeds 1, unless the weights are floored
    # at the state's round-off (src/hybrid/decision_tolerances.hpp, kRoundoffFloor).
    L.append("Long rolling phases (not closed forms: the rigid stator of (b) driven at 2000 N m, "
             "rolling at 2600-2667 rad/s from the start, at the default tolerances for 100 s and "
             "at rtol 1e-12 for 1 s). eps |theta - theta_a| / weight above about 2-3 (the square "
             "root of the number of CVODES components) is where a run without the round-off "
             "floor of the error weights stopped with CV_TOO_MUCH_ACC (at 77 s and 0.093 s):\n")
    L.append("| setting | run | t reached [s] | termination | steps | theta - theta_a [rad] | "
             "weight (rtol g0 + atol) / R [rad] | eps abs(theta - theta_a) / weight | "
             "Omega at the end / (tau / (c_r R^2)) - 1 |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for tol, key, o in ladder.get("limit", []):
        c = o.case
        w = (tol["rtol"] * c["stator"]["gap"] + tol["atol"]) / c["rotor"]["radius"]
        stick = np.where(o.phase == "stick")[0]
        dth = (o.col["theta"][stick[-1]] - o.col["theta"][stick[0]]) if len(stick) else 0.0
        om_ss = c["loads"]["torque"] / (c["rotor"]["c"] * c["rotor"]["radius"] ** 2)
        L.append("| rtol %g, atol %g | %s | %.6g | %s | %d | %.4g | %.3g | %.2f | %.1e |" % (
            tol["rtol"], tol["atol"], key, o.summary["t_reached"], o.summary["termination"],
            o.summary["steps"], dth, w, 2.220446049250313e-16 * abs(dth) / w,
            o.col["omega"][-1] / om_ss - 1))
    L.append("")
    L.append("## 5. Log\n")
    L.append("```\n%s\n```" % "\n".join(LOG))
    with open(path, "w") as f:
        f.write("\n".join(L) + "\n")


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rubdyn = os.path.abspath(args[0] if args else os.path.join(ROOT, "build", "rubdyn"))
    out = os.path.join(ROOT, "out", "analytic")
    if os.path.isdir(out):
        shutil.rmtree(out)
    os.makedirs(os.path.join(out, "bin"))
    label = rubdyn_label(rubdyn)
    copy = os.path.join(out, "bin", "rubdyn")   # the binary may be rebuilt while this runs
    shutil.copy2(rubdyn, copy)
    say("rubdyn: %s, run as %s" % (label, os.path.relpath(copy, ROOT)))
    t0 = time.perf_counter()
    S = all_studies(copy, out, rr.TIGHT)
    for key, st in S.items():
        say("%-28s %-10s %d runs, %.2f s wall%s" % (key, st.status, len(st.runs),
                                                    sum(o.wall for _, o in st.runs),
                                                    "" if not st.notes else
                                                    ": " + "; ".join(st.notes)))
    # approach rates against the eigenvalues
    rates = []
    S["black-high-translated"] = rr.study_black_rolling(copy, out, 1, rr.TIGHT, eps=0.0)
    for key, mode in (("black-low", "stick"), ("black-high", "stick"),
                      ("black-high-translated", "stick"), ("whip-approach", "slip-")):
        st = S[key]
        P = rr.whip_params() if mode == "slip-" else dict(rr.BLACK_ROLL,
                                                          **{"loads.unbalance": 0.0})
        ev = rr.orbit_eigen(P, st.root, mode)
        lam = max(ev.real)
        every = ", ".join("%.2f" % x for x in sorted(set(np.round(-ev.real, 6))))
        for q in st.quantities:
            if q.t is not None and q.reach:
                rates.append((key, q.name, rr.approach_rate(q.t, q.dev), -lam, every))
    if S["unbalance"].status == "ok":
        st = S["unbalance"]
        ev = rr.unbalance_eigen(rr.unb_params(), st.roots[0], rr.OMEGA_U)
        every = ", ".join("%.2f" % x for x in sorted(set(np.round(-ev.real, 6))))
        for q in st.quantities:
            if q.t is not None and q.reach and "prescribed" not in q.name:
                rates.append(("unbalance", q.name, rr.approach_rate(q.t, q.dev), -max(ev.real),
                              every + " (pair: +-%.1f i)" % abs(ev.imag).max()))
    for key in ("rigid-constant", "rigid-linear"):
        st = S[key]
        q = st.quantities[1]
        rates.append((key, q.name, rr.approach_rate(q.t, q.dev), 1 / st.closed["time_constant"],
                      "(one mode: the exponential)"))
    # the tolerance ladder (no power windows, no rigid-rotor kinematics)
    ladder = {"S": {}, "rows": []}
    for lab, tol in LADDER:
        sub = os.path.join(out, "tolerance", lab)
        ladder["S"][lab] = all_studies(copy, sub, tol, with_kinematics=False)
        say("tolerance %-8s rtol %g atol %g: done" % (lab, tol["rtol"], tol["atol"]))
    for key in ("rigid-constant", "rigid-linear", "black-low", "black-high", "black-low-exact",
                "black-high-exact", "whip-exact", "whip-exact-linear", "whip-approach",
                "unbalance", "power"):
        names = [q.name for q in ladder["S"]["tight"][key].quantities
                 if "polar angle" not in q.name and "fit" not in q.name.lower()
                 and "sampled powers" not in q.name and "W_friction / W" not in q.name]
        ladder["rows"].append((key, names))
    # the same stop in a long rolling phase at the default tolerances: the rigid stator driven
    # at 2000 N m, rolling at 2600-2667 rad/s (the angle grows 100 times faster than in (b))
    P = dict(rr.rigid_params("constant"), **{"loads.torque": 2000.0})
    s = cf.short(P)
    keys = cf.contact_orbit_state(P, cf.rolling_whirl(s["R"], s["g0"], 2600.0), 2600.0)
    case = rr.write_case(os.path.join(out, "limit"), P, "rigid_rolling_fast")
    ladder["limit"] = []
    for lab, tol, t_end in (("default", rr.DEFAULT, 100.0), ("tight", rr.TIGHT, 1.0)):
        o = rr.run(copy, case, os.path.join(out, "limit", lab), rr.initial_sets(keys),
                   t_end=t_end, **tol)
        ladder["limit"].append((tol, "rigid stator, 2000 N m, 2600 rad/s, to %g s" % t_end, o))
        say("limit run %s: %s at t = %.6g s" % (lab, o.summary["termination"],
                                                 o.summary["t_reached"]))
    wall = time.perf_counter() - t0
    plot(S, os.path.join(HERE, "approach.png"))
    write_table(os.path.join(HERE, "table.md"), S, ladder, rates, label, wall)
    say("wrote validation/analytic/table.md and approach.png (%.0f s)" % wall)


if __name__ == "__main__":
    main()
