#!/usr/bin/python3
"""Rolling (dry whirl, stick) regime: rubdyn against an independent reference.

From the stick-onset state of onset_state.json (written by rubdyn, reference case at mu = 0.25,
see onset.py) the rotor rolls without slip inside the stator ring. reference.py integrates that
motion in its 5 minimal coordinates (an ODE: no constraint, no contact law) with an 8th-order
fixed-step Runge-Kutta method at two steps and with scipy's adaptive DOP853. This script runs
  1. the reference over the 30 ms window, at h and h/2 (self-difference), and scipy's DOP853;
  2. rubdyn's event-driven solver from the same state (time restarts at 0) at rtol = 1e-6 ...
     1e-12 (atol default; and a second series with atol = 1e-3 rtol);
  3. the fixed-step schemes carp-onevc, carp-qn, mj, mj-proj at h = 1e-6, 1e-7, 1e-8 and 1e-9
     (the last when the estimate from the 1e-8 run is under 10 minutes);
  4. (--full) the full case (0.5 s, mu = 0.25, the case's own initial state): omega(0.5 s) of
     every fixed-step scheme at h = 1e-6 ... 1e-9 (skipped when estimated over 10 minutes)
     against the event-driven run at rtol 1e-10 (checked against rtol 1e-12), and the reference
     integrated from the onset to 0.5 s against the event run's omega(0.5 s).
Errors against the reference on the 0.1 ms output grid: omega at 30 ms (absolute, relative) and
its sup over the grid, the orbit r = (x_r - x_s, y_r - y_s) at 30 ms and its sup [m].

Writes results.csv, table.md and rolling.png next to this script (with --quick: a smaller
subset, written to out/rolling/quick/ so that the committed tables are not replaced).
Usage: validation/rolling/run.py [path/to/rubdyn] [--quick] [--full] [--selftest]
"""
import argparse
import datetime
import math
import os
import shutil
import subprocess
import sys
import time
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)
from common import CASE, ROOT, machine, read_output, script_args, write_csv  # noqa: E402
import reference as ref  # noqa: E402
from onset import find_onset  # noqa: E402

DT = 1e-4                 # output grid [s]
WINDOW = 0.03             # s
H_REF = 1e-7              # reference step (and H_REF / 2)
EVENT_RTOLS = ["1e-6", "1e-8", "1e-10", "1e-12"]
FIXED = ["carp-onevc", "carp-qn", "mj", "mj-proj"]
STEPS = ["1e-6", "1e-7", "1e-8", "1e-9"]
MAX_RUN = 600.0           # s: longest single run allowed
FULL_T = 0.5
LOG = []


def say(msg):
    print(msg, flush=True)
    LOG.append(msg)


# ---- running rubdyn ---------------------------------------------------------------------------
def restart_sets(state):
    """--set arguments putting rubdyn in `state` (omega -> initial.omega0), all digits."""
    out = []
    for k in ref.COORDS + ref.VELS:
        key = "initial.omega0" if k == "omega" else "initial." + k
        out += ["--set", "%s=%r" % (key, state[k])]
    return out


def nudge(state, g0):
    """The state moved radially onto |(x_r - x_s, y_r - y_s)| = g0 exactly."""
    s = dict(state)
    sx, sy = s["x_r"] - s["x_s"], s["y_r"] - s["y_s"]
    f = g0 / math.hypot(sx, sy)
    s["x_r"], s["y_r"] = s["x_s"] + f * sx, s["y_s"] + f * sy
    return s


class Run:
    """One rubdyn run: summary, grid {k: row dict of floats}, events, process wall time."""

    def __init__(self, folder, summary, grid, events, wall, rc, stderr):
        self.folder, self.summary, self.grid, self.events = folder, summary, grid, events
        self.process_wall, self.rc, self.stderr = wall, rc, stderr

    @property
    def wall(self):
        return self.summary.get("wall_seconds", self.process_wall)


def rubdyn_run(rubdyn, name, args):
    folder = os.path.join(OUT, name)
    cmd = [rubdyn, "run", CASE, "--out", folder, "--quiet"] + args
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    if p.returncode not in (0, 3):
        return Run(folder, {}, {}, [], wall, p.returncode, p.stderr.strip())
    summary, grid, events = read_output(folder, DT, last=True)
    return Run(folder, summary, grid, events, wall, p.returncode, p.stderr.strip())


def check_case(run, case):
    """The run's resolved parameters are those of the reference (guards against case edits)."""
    with open(os.path.join(run.folder, "case.resolved.toml"), "rb") as f:
        resolved = tomllib.load(f)
    for sec, keys in case.items():
        for k, v in keys.items():
            if float(resolved[sec][k]) != float(v):
                raise SystemExit("%s: %s.%s = %r, reference uses %r"
                                 % (run.folder, sec, k, resolved[sec][k], v))


def restart(rubdyn, name, args):
    """rubdyn from the onset state over the window; nudges the state onto the constraint once
    if rubdyn rejects it for penetration (and says so)."""
    base = ["--set", "contact.mu=%r" % CASE_PARAMS["contact"]["mu"], "--t-end", repr(WINDOW)]
    r = rubdyn_run(rubdyn, name, base + restart_sets(STATE) + args)
    if r.rc == 2 and "penetrat" in r.stderr.lower():
        say("  %s: rubdyn rejected the onset state (%s); retrying with the state nudged radially "
            "onto rho = g0" % (name, r.stderr.splitlines()[-1]))
        NOTES.add("rubdyn rejected the onset state for penetration; the runs used the state "
                  "nudged radially onto rho = g0 (x_r, y_r scaled about the stator centre)")
        r = rubdyn_run(rubdyn, name, base + restart_sets(nudge(STATE, MODEL.g0)) + args)
    if r.rc not in (0, 3):
        raise SystemExit("%s: rubdyn exit code %d: %s" % (name, r.rc, r.stderr))
    check_case(r, CASE_PARAMS)
    return r


# ---- error measures -----------------------------------------------------------------------------
def errors(run, sol):
    """Errors of a rubdyn run against a reference Solution on the common grid."""
    n = len(sol.t) - 1
    ks = [k for k in range(n + 1) if k in run.grid]
    om = np.array([run.grid[k]["omega"] for k in ks])
    orb = np.array([[run.grid[k]["x_r"] - run.grid[k]["x_s"],
                     run.grid[k]["y_r"] - run.grid[k]["y_s"]] for k in ks])
    dom = om - sol.omega()[ks]
    dorb = np.hypot(*(orb - sol.orbit()[ks]).T)
    reached = ks[-1] == n
    w_ref = sol.omega()[n]
    return {
        "omega_end": om[-1] if reached else float("nan"),
        "omega_err": abs(dom[-1]) if reached else float("nan"),
        "omega_err_signed": dom[-1] if reached else float("nan"),
        "omega_rel_err": abs(dom[-1]) / abs(w_ref) if reached else float("nan"),
        "omega_err_sup": float(np.abs(dom).max()),
        "orbit_err": dorb[-1] if reached else float("nan"),
        "orbit_err_sup": float(dorb.max()),
    }


def sol_errors(a, b):
    """Same measures between two reference Solutions on the same grid (a against b)."""
    dom = a.omega() - b.omega()
    dorb = np.hypot(*(a.orbit() - b.orbit()).T)
    return {"omega_end": a.omega()[-1], "omega_err": abs(dom[-1]),
            "omega_err_signed": dom[-1], "omega_rel_err": abs(dom[-1]) / abs(b.omega()[-1]),
            "omega_err_sup": float(np.abs(dom).max()), "orbit_err": dorb[-1],
            "orbit_err_sup": float(dorb.max())}


def run_row(part, solver, variant, param, run, errs):
    s = run.summary
    ev = s.get("events", {})
    pt = s.get("phase_time", {})
    total = sum(pt.values()) or float("nan")
    return dict({"part": part, "solver": solver, "variant": variant, "param": param},
                **errs,
                wall_seconds=run.wall, steps=s.get("steps", ""),
                energy_residual=s.get("energy_residual", float("nan")),
                energy_residual_rel=abs(s.get("energy_residual", float("nan")))
                / s.get("energy_initial", float("nan")),
                max_penetration=s.get("max_penetration", float("nan")),
                stick_fraction=pt.get("stick", float("nan")) / total,
                events=" ".join("%s %d" % (k, v) for k, v in ev.items() if v),
                termination=s.get("termination", ""))


# ---- parts --------------------------------------------------------------------------------------
def part1(quick):
    """The reference at H and H/2 and scipy's DOP853."""
    h = H_REF * (2 if quick else 1)
    say("part 1: reduced reference, RK8 fixed step h = %g and %g, scipy DOP853" % (h, h / 2))
    coarse = ref.solve_fixed(MODEL, STATE, WINDOW, h, DT, force_every=1)
    say("  h = %g: %.1f s" % (h, coarse.stats["wall_seconds"]))
    fine = ref.solve_fixed(MODEL, STATE, WINDOW, h / 2, DT, force_every=1)
    say("  h = %g: %.1f s" % (h / 2, fine.stats["wall_seconds"]))
    rows = [dict({"part": "1-reference", "solver": "rk8-fixed", "variant": "vs h/2",
                  "param": "h=%g" % h}, **sol_errors(coarse, fine),
                 wall_seconds=coarse.stats["wall_seconds"], steps=coarse.stats["steps"],
                 energy_residual=coarse.energy_residual()[-1],
                 energy_residual_rel=abs(coarse.energy_residual()[-1])
                 / MODEL.energy(coarse.q[0], coarse.v[0]),
                 stick_fraction=1.0, events="", termination="completed"),
            dict({"part": "1-reference", "solver": "rk8-fixed", "variant": "the reference",
                  "param": "h=%g" % (h / 2)}, **sol_errors(fine, fine),
                 wall_seconds=fine.stats["wall_seconds"], steps=fine.stats["steps"],
                 energy_residual=fine.energy_residual()[-1],
                 energy_residual_rel=abs(fine.energy_residual()[-1])
                 / MODEL.energy(fine.q[0], fine.v[0]),
                 stick_fraction=1.0, events="", termination="completed")]
    sp = None
    if not quick:
        sp = ref.solve_scipy(MODEL, STATE, WINDOW, DT, rtol=1e-13, atol=1e-20)
        say("  scipy DOP853 rtol 1e-13: %.1f s" % sp.stats["wall_seconds"])
        rows.append(dict({"part": "1-reference", "solver": "scipy-dop853",
                          "variant": "vs rk8 h/2", "param": "rtol=1e-13"},
                         **sol_errors(sp, fine), wall_seconds=sp.stats["wall_seconds"],
                         steps=sp.stats["steps"], energy_residual=sp.energy_residual()[-1],
                         energy_residual_rel=abs(sp.energy_residual()[-1])
                         / MODEL.energy(sp.q[0], sp.v[0]),
                         stick_fraction=1.0, events="", termination="completed"))
    ulp = None
    if not quick:
        # conditioning: the same (coarse) integration from omega0 moved by one ulp
        st = dict(STATE)
        st["omega"] = float(np.nextafter(st["omega"], math.inf))
        pert = ref.solve_fixed(MODEL, st, WINDOW, h, DT, force_every=100)
        say("  h = %g, omega0 + 1 ulp: %.1f s" % (h, pert.stats["wall_seconds"]))
        ulp = {"omega_sup": float(np.abs(pert.omega() - coarse.omega()).max()),
               "omega_end": float(abs(pert.omega()[-1] - coarse.omega()[-1])),
               "orbit_sup": float(np.hypot(*(pert.orbit() - coarse.orbit()).T).max()),
               "d_omega0": st["omega"] - STATE["omega"]}
    info = {"h": h, "coarse": coarse.stats, "fine": fine.stats, "ulp": ulp,
            "energy_residual_max": float(np.abs(fine.energy_residual()).max()),
            "E0": MODEL.energy(fine.q[0], fine.v[0]),
            "omega_end": fine.omega()[-1], "orbit_end": fine.orbit()[-1].tolist(),
            "scipy": sp.stats if sp else None,
            "self_diff_omega_sup": float(np.abs(coarse.omega() - fine.omega()).max()),
            "self_diff_orbit_sup": float(np.hypot(*(coarse.orbit() - fine.orbit()).T).max()),
            "scipy_diff_omega_sup": float(np.abs(sp.omega() - fine.omega()).max()) if sp
            else None,
            "scipy_diff_orbit_sup": float(np.hypot(*(sp.orbit() - fine.orbit()).T).max()) if sp
            else None}
    return fine, rows, info


def contact_phases_variants(rubdyn):
    """['reduced', 'projection'] when the binary has solver.contact_phases, else [None]."""
    p = subprocess.run([rubdyn, "check", CASE, "--set", "solver.contact_phases=reduced"],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return ["reduced", "projection"] if p.returncode == 0 else [None]


def part2(rubdyn, sol, quick):
    rtols = ["1e-6", "1e-10"] if quick else EVENT_RTOLS
    variants = contact_phases_variants(rubdyn)
    say("part 2: event-driven solver, contact phases: %s"
        % ("reduced and projection" if variants[0] else "the binary's default (no "
           "solver.contact_phases key in this binary)"))
    rows = []
    for cp in variants:
        cp_args = ["--set", "solver.contact_phases=" + cp] if cp else []
        for atol_mode in (["default"] if quick else ["default", "1e-3 rtol"]):
            for rtol in rtols:
                args = ["--rtol", rtol] + cp_args
                if atol_mode != "default":
                    args += ["--atol", "%.0e" % (float(rtol) * 1e-3)]
                name = "event-%s-rtol%s-atol%s" % (cp or "default", rtol,
                                                   "default" if atol_mode == "default"
                                                   else "scaled")
                r = restart(rubdyn, os.path.join("window", name), args)
                label = r.summary.get("options", {}).get("contact_phases", cp or "default")
                variant = "%s, atol %s" % (label, "default (%g)" % r.summary["options"]["atol"]
                                           if atol_mode == "default" else atol_mode)
                row = run_row("2-event", "event", variant, "rtol=" + rtol, r, errors(r, sol))
                rows.append(row)
                say("  %-44s rtol %-6s omega err %.3e (rel %.2e)  orbit err %.3e m  %6.2f s"
                    % (variant, rtol, row["omega_err"], row["omega_rel_err"],
                       row["orbit_err_sup"], row["wall_seconds"]))
    return rows


def part3(rubdyn, sol, quick):
    steps = ["1e-6", "1e-7"] if quick else STEPS
    say("part 3: fixed-step schemes from the onset state")
    rows, per_step = [], {}
    for scheme in FIXED:
        last = None
        for h in steps:
            n = round(WINDOW / float(h))
            if last is not None:
                est = last[0] / last[1] * n
                if est > MAX_RUN:
                    say("  %-10s h %s: skipped (estimated %.0f s from h = %s > %.0f s)"
                        % (scheme, h, est, last[2], MAX_RUN))
                    rows.append({"part": "3-fixed", "solver": scheme, "variant": "",
                                 "param": "h=" + h, "termination": "skipped: estimated %.0f s"
                                 % est})
                    continue
            r = restart(rubdyn, os.path.join("window", "%s-h%s" % (scheme, h)),
                        ["--solver", scheme, "--h", h])
            row = run_row("3-fixed", scheme, "", "h=" + h, r, errors(r, sol))
            rows.append(row)
            steps_done = r.summary.get("steps", n) or n
            last = (r.wall, steps_done, h)
            per_step[(scheme, h)] = r.wall / steps_done
            say("  %-10s h %-5s omega err %.3e (rel %.2e)  orbit err %.3e m  stick %.2f  %7.2f s"
                % (scheme, h, row["omega_err"], row["omega_rel_err"], row["orbit_err_sup"],
                   row["stick_fraction"], row["wall_seconds"]))
    return rows, per_step


def part4(rubdyn, per_step):
    say("part 4: full case, %g s at mu = %r from the case's initial state"
        % (FULL_T, CASE_PARAMS["contact"]["mu"]))
    rows = []

    def one(name, args, t_end=FULL_T):
        base = ["--set", "contact.mu=%r" % CASE_PARAMS["contact"]["mu"], "--t-end", repr(t_end)]
        r = rubdyn_run(rubdyn, os.path.join("full", name), base + args)
        if r.rc not in (0, 3):
            raise SystemExit("%s: rubdyn exit code %d: %s" % (name, r.rc, r.stderr))
        return r

    ev = one("event-rtol1e-10", ["--rtol", "1e-10"])
    w_ref = ev.summary["omega_final"]
    say("  event rtol 1e-10 (%s): omega(0.5 s) = %.10g rad/s, %.1f s"
        % (ev.summary["options"].get("contact_phases"), w_ref, ev.wall))
    chk = one("event-rtol1e-12", ["--rtol", "1e-12"])
    say("  event rtol 1e-12: omega(0.5 s) = %.10g rad/s, %.1f s" % (chk.summary["omega_final"],
                                                                    chk.wall))

    def full_row(solver, param, r):
        s = r.summary
        w = s.get("omega_final", float("nan")) if s.get("t_reached") == FULL_T else float("nan")
        pt = s.get("phase_time", {})
        return {"part": "4-full", "solver": solver, "variant": "", "param": param,
                "omega_end": w, "omega_err": abs(w - w_ref),
                "omega_err_signed": w - w_ref, "omega_rel_err": abs(w - w_ref) / abs(w_ref),
                "wall_seconds": r.wall, "steps": s.get("steps", ""),
                "energy_residual": s.get("energy_residual", float("nan")),
                "energy_residual_rel": abs(s.get("energy_residual", float("nan")))
                / s.get("energy_initial", float("nan")),
                "max_penetration": s.get("max_penetration", float("nan")),
                "stick_fraction": pt.get("stick", float("nan")) / (sum(pt.values()) or 1),
                "events": " ".join("%s %d" % (k, v) for k, v in s.get("events", {}).items()
                                   if v),
                "termination": s.get("termination", "")}

    label = ev.summary["options"].get("contact_phases", "default")
    rows.append(dict(full_row("event", "rtol=1e-10 (reference)", ev), variant=label))
    rows.append(dict(full_row("event", "rtol=1e-12", chk), variant=label))
    for cp in contact_phases_variants(rubdyn):
        if cp is None:
            continue
        r = one("event-%s-rtol1e-10" % cp, ["--rtol", "1e-10", "--set",
                                            "solver.contact_phases=" + cp])
        lab = r.summary["options"].get("contact_phases", cp)
        if lab != label:
            rows.append(dict(full_row("event", "rtol=1e-10", r), variant=lab))
            say("  event %s rtol 1e-10: omega(0.5 s) = %.10g rad/s, %.1f s"
                % (lab, r.summary["omega_final"], r.wall))
    for scheme in FIXED:
        for h in STEPS:
            n = round(FULL_T / float(h))
            est = None
            if float(h) <= 1e-8:
                # per-step cost: the larger of the stick window's (part 3) and that of a probe
                # over the first 10 ms of the full case (free flight, impacts, sliding)
                probe = one("probe-%s-h%s" % (scheme, h),
                            ["--solver", scheme, "--h", h], t_end=0.01)
                c = max(per_step.get((scheme, h), 0.0),
                        probe.wall / max(probe.summary.get("steps", 1), 1))
                est = c * n
                if est > MAX_RUN:
                    say("  %-10s h %s: skipped (estimated %.0f s > %.0f s)"
                        % (scheme, h, est, MAX_RUN))
                    rows.append({"part": "4-full", "solver": scheme, "variant": "",
                                 "param": "h=" + h,
                                 "termination": "skipped: estimated %.0f s" % est})
                    continue
            r = one("%s-h%s" % (scheme, h), ["--solver", scheme, "--h", h])
            row = full_row(scheme, "h=" + h, r)
            rows.append(row)
            say("  %-10s h %-5s omega(0.5 s) %.6g rad/s  rel dev %.3e  stick %.2f  %7.1f s%s"
                % (scheme, h, row["omega_end"], row["omega_rel_err"], row["stick_fraction"],
                   row["wall_seconds"], "" if est is None else " (estimated %.0f s)" % est))
    return rows, ev, chk


def part4b(ev):
    """The reference from the stick onset of the full event run itself (its first stick phase
    of at least WINDOW) to 0.5 s, against that run's omega(0.5 s): an independent check of the
    long stick phase of the full-case reference."""
    t_on, state, _, t_next, _ = find_onset(ev.folder, WINDOW)
    if t_next < FULL_T:
        say("  the stick phase of the full event run ends at %.6f s, before %g s: the reference "
            "stops there" % (t_next, FULL_T))
    span = t_next - t_on
    out = {}
    for hh in (4e-7, 2e-7):
        n = math.ceil(span / hh)
        sol = ref.solve_fixed(MODEL, state, span, span / n, span, force_every=10)
        sol.stats.update(h=span / n, t_onset=t_on, t_end=t_next,
                         d_t_onset=t_on - ONSET["source"]["t_onset"],
                         d_omega_onset=state["omega"] - STATE["omega"])
        out[hh] = sol
        say("  reference from the full run's onset t = %.9f s to %g s, h = %.3g: omega = %.12g "
            "rad/s, min F_N %.3e N, max |F_T|/F_N %.2e, %.0f s"
            % (t_on, t_next, span / n, sol.omega()[-1], sol.stats["min_F_N"],
               sol.stats["max_F_T_over_F_N"], sol.stats["wall_seconds"]))
    return out


# ---- outputs ------------------------------------------------------------------------------------
def fmt(x, f="%.3e"):
    if x is None or x == "" or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f % x


def plot(rows, full_rows, path, unc=None):
    """unc: (omega relative, orbit) uncertainty of the reference, drawn as dashed lines."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    floor = 1e-17
    ncol = 3 if full_rows else 2
    fig, axes = plt.subplots(1, ncol, figsize=(5.2 * ncol, 5.6))
    series = {}
    for r in rows:
        if r.get("termination", "").startswith("skipped") or r["part"] == "1-reference" and \
                r["variant"] == "the reference":
            continue
        key = (r["solver"] + ("" if not r["variant"] else ", " + r["variant"])
               if r["part"] != "3-fixed" else r["solver"])
        series.setdefault(key, []).append(r)
    markers = {"carp-onevc": "v", "carp-qn": "^", "mj": "s", "mj-proj": "D"}
    colors = {"carp-onevc": "tab:pink", "carp-qn": "tab:gray", "mj": "tab:olive",
              "mj-proj": "tab:cyan"}
    event_colors = iter(["tab:red", "tab:orange", "tab:blue", "tab:purple", "tab:green",
                         "tab:brown"])
    for key in series:
        if key not in colors:
            colors[key] = (next(event_colors) if key.startswith("event") else
                           "dimgray" if key.startswith("scipy") else "black")
    for ax, col, lab in ((axes[0], "omega_rel_err", "|omega - omega_ref| / omega_ref at 30 ms"),
                         (axes[1], "orbit_err_sup", "sup |r - r_ref| over the window [m]")):
        for key, rs in series.items():
            xs = [r["wall_seconds"] for r in rs]
            ys = [max(r[col], floor) for r in rs]
            m = markers.get(key, "o" if key.startswith("event") else "*")
            ax.loglog(xs, ys, marker=m, label=key, color=colors[key],
                      linestyle="-" if len(rs) > 1 else "none",
                      markersize=11 if m == "*" else 6)
            for r, x, y in zip(rs, xs, ys):
                ax.annotate(r["param"].split("=")[1], (x, y), fontsize=6,
                            textcoords="offset points", xytext=(3, 3))
        if unc:
            ax.axhline(max(unc[0 if col == "omega_rel_err" else 1], floor), color="black",
                       linestyle="--", linewidth=0.8)
            ax.annotate("reference uncertainty", (1, max(unc[0 if col == "omega_rel_err"
                                                              else 1], floor)),
                        xycoords=("axes fraction", "data"), ha="right", va="bottom",
                        fontsize=7)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel(lab)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_title("rolling window (30 ms from the stick onset)")
    axes[1].set_title("orbit r = (x_r - x_s, y_r - y_s)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=7, frameon=False)
    if full_rows:
        ax = axes[2]
        for scheme in FIXED:
            rs = [r for r in full_rows if r["solver"] == scheme and "omega_end" in r]
            if rs:
                ax.loglog([float(r["param"][2:]) for r in rs],
                          [max(r["omega_rel_err"], floor) for r in rs],
                          marker=markers[scheme], label=scheme)
        ax.axhline(0.01, color="k", linestyle=":", label="1 %")
        ax.set_xlabel("h [s]")
        ax.set_ylabel("|omega(0.5 s) - omega_event| / omega_event")
        ax.set_title("full case, omega(0.5 s) vs event rtol 1e-10")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout(rect=(0, 0.14, 1, 1))
    fig.savefig(path, dpi=130)


def write_table(path, command, info, rows, full, timing, selftest_lines=()):
    p1 = [r for r in rows if r["part"] == "1-reference"]
    p2 = [r for r in rows if r["part"] == "2-event"]
    p3 = [r for r in rows if r["part"] == "3-fixed"]
    L = []
    L.append("# Rolling (stick) regime: rubdyn against an independent reference\n")
    L.append("Generated by `%s` on %s. Machine: %s. rubdyn: `%s` (commit %s%s).\n"
             % (command, datetime.date.today().isoformat(), machine(), RUBDYN_LABEL[0],
                RUBDYN_LABEL[1], RUBDYN_LABEL[2]))
    L.append("Start: `onset_state.json`, the state rubdyn wrote at the stick onset t = %r s of "
             "`%s`; time restarts at 0, window %g s, output grid %g s.\n"
             % (ONSET["source"]["t_onset"], ONSET["source"]["command"], WINDOW, DT))
    for n in sorted(NOTES):
        L.append("**Note:** %s.\n" % n)
    L.append("## 1. The reference (reduced 5-coordinate equations)\n")
    if selftest_lines:
        L.append("`reference.py --selftest` (run first; see README.md for what each check is):\n")
        L.append("```\n%s\n```\n" % "\n".join(line.strip() for line in selftest_lines))
    fine = info["fine"]
    L.append("RK8 (DOP853 tableau, fixed step) at h = %g and h/2 = %g; the h/2 solution is the "
             "reference. omega(30 ms) = %r rad/s, orbit(30 ms) = (%r, %r) m.\n"
             % (info["h"], info["h"] / 2, info["omega_end"], info["orbit_end"][0],
                info["orbit_end"][1]))
    L.append("| quantity | value |\n|---|---|")
    L.append("| self-difference h vs h/2: omega, sup over the grid [rad/s] | %s |"
             % fmt(info["self_diff_omega_sup"]))
    L.append("| self-difference h vs h/2: orbit, sup over the grid [m] | %s |"
             % fmt(info["self_diff_orbit_sup"]))
    if info["scipy"]:
        L.append("| scipy solve_ivp DOP853 (rtol 1e-13, atol 1e-20) vs RK8 h/2: omega sup "
                 "[rad/s] | %s |" % fmt(info["scipy_diff_omega_sup"]))
        L.append("| scipy DOP853 vs RK8 h/2: orbit sup [m] | %s |"
                 % fmt(info["scipy_diff_orbit_sup"]))
    if info["ulp"]:
        u = info["ulp"]
        L.append("| conditioning: omega0 + 1 ulp (%.1e rad/s), same h: omega difference at 30 "
                 "ms, sup [rad/s] | %s, %s |" % (u["d_omega0"], fmt(u["omega_end"]),
                                                 fmt(u["omega_sup"])))
        L.append("| conditioning: omega0 + 1 ulp: orbit difference, sup [m] | %s |"
                 % fmt(u["orbit_sup"]))
    L.append("| energy balance max over the grid abs(E - E0 - W) [J] (E0 = %.6g J) | %s |"
             % (info["E0"], fmt(info["energy_residual_max"])))
    L.append("| min F_N over every step [N] | %s |" % fmt(fine["min_F_N"]))
    L.append("| max abs(F_T) / F_N over every step (mu = %g) | %s |"
             % (MODEL.mu, fmt(fine["max_F_T_over_F_N"])))
    L.append("| min cone margin (mu F_N - abs(F_T)) / (mu F_N), at t [s] | %s at %.6f |"
             % (fmt(fine["min_cone_margin"], "%.6f"), fine["t_min_cone_margin"]))
    L.append("| max abs(M a - f - W_N F_N - W_T F_T) / F_N | %s |"
             % fmt(fine["max_force_residual"]))
    L.append("| wall time h, h/2%s [s] | %.1f, %.1f%s |"
             % (", scipy" if info["scipy"] else "", info["coarse"]["wall_seconds"],
                fine["wall_seconds"],
                ", %.1f" % info["scipy"]["wall_seconds"] if info["scipy"] else ""))
    L.append("")
    head = ("| %s | omega(30 ms) [rad/s] | omega error [rad/s] | relative | sup omega error "
            "[rad/s] | orbit error at 30 ms [m] | sup orbit error [m] | steps | wall [s] | "
            "energy residual [J] | max penetration [m] | stick fraction | events |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|")

    def line(first, r):
        if r.get("termination", "").startswith("skipped"):
            return "| %s | %s ||||||||||||" % (first, r["termination"])
        return "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            first, fmt(r["omega_end"], "%.10f"), fmt(r["omega_err"]), fmt(r["omega_rel_err"]),
            fmt(r["omega_err_sup"]), fmt(r["orbit_err"]), fmt(r["orbit_err_sup"]),
            r["steps"], fmt(r["wall_seconds"], "%.2f"), fmt(r["energy_residual"], "%.3g"),
            fmt(r["max_penetration"], "%.2e"), fmt(r["stick_fraction"], "%.3f"),
            r["events"] or "-")

    L.append("| reference run | difference to RK8 h/2 ... |\n|---|---|")
    for r in p1:
        if r["variant"] != "the reference":
            L.append("| %s %s | omega at 30 ms %s rad/s, sup %s; orbit at 30 ms %s m, sup %s; "
                     "%s steps, %.1f s |" % (r["solver"], r["param"], fmt(r["omega_err"]),
                                             fmt(r["omega_err_sup"]), fmt(r["orbit_err"]),
                                             fmt(r["orbit_err_sup"]), r["steps"],
                                             r["wall_seconds"]))
    L.append("\n## 2. rubdyn, event-driven, from the onset state (30 ms)\n")
    L.append("Errors against the reference; energy residual from summary.json "
             "(`energy_residual`: dE - work of torque, dampers, friction, impacts).\n")
    L.append(head % "contact phases, atol, rtol")
    for r in p2:
        L.append(line("%s, %s" % (r["variant"], r["param"]), r))
    L.append("\n## 3. rubdyn, fixed-step schemes, from the onset state (30 ms)\n")
    L.append(head % "scheme, h")
    for r in p3:
        L.append(line("%s, %s" % (r["solver"], r["param"]), r))
    L.append("\n## 4. Full case (0.5 s, mu = %r, the case's initial state)\n"
             % CASE_PARAMS["contact"]["mu"])
    if full is None:
        L.append("Not run (`run.py --full`).\n")
    else:
        full_rows, ev, chk, b = full
        w_ref = ev.summary["omega_final"]
        L.append("Reference: event-driven (contact phases %s) at rtol 1e-10, omega(0.5 s) = %r "
                 "rad/s, %.1f s wall, %d steps. Check: rtol 1e-12 gives %r rad/s (relative "
                 "difference %.2e), %.1f s.\n"
                 % (ev.summary["options"].get("contact_phases", "default"), w_ref, ev.wall,
                    ev.summary["steps"], chk.summary["omega_final"],
                    abs(chk.summary["omega_final"] - w_ref) / w_ref, chk.wall))
        if b:
            hs = sorted(b)
            st = b[hs[0]].stats
            L.append("Independent check of its stick phase: from that run's own stick onset "
                     "(t = %r s; %.2e s and %.2e rad/s from onset_state.json's) to %g s the "
                     "reduced reference gives omega = %r rad/s (RK8, h = %.3g; h = %.3g differs "
                     "by %.1e rad/s): relative difference to the event run %.2e. Along the way "
                     "min F_N %.3e N, max abs(F_T)/F_N %.2e (stick holds).\n"
                     % (st["t_onset"], st["d_t_onset"], st["d_omega_onset"], st["t_end"],
                        b[hs[0]].omega()[-1], st["h"], b[hs[1]].stats["h"],
                        abs(b[hs[0]].omega()[-1] - b[hs[1]].omega()[-1]),
                        abs(b[hs[0]].omega()[-1] - w_ref) / w_ref,
                        st["min_F_N"], st["max_F_T_over_F_N"]))
        L.append("| solver | h [s] or rtol | omega(0.5 s) [rad/s] | relative deviation | max "
                 "penetration [m] | stick fraction | events | steps | wall [s] |\n"
                 "|---|---|---|---|---|---|---|---|---|")
        for r in full_rows:
            if r.get("termination", "").startswith("skipped"):
                L.append("| %s | %s | %s |||||||" % (r["solver"], r["param"], r["termination"]))
                continue
            L.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                r["solver"] + (" (%s)" % r["variant"] if r["variant"] else ""), r["param"],
                fmt(r["omega_end"], "%.6f"), fmt(r["omega_rel_err"]),
                fmt(r["max_penetration"], "%.2e"), fmt(r["stick_fraction"], "%.3f"),
                r["events"] or "-", r["steps"], fmt(r["wall_seconds"], "%.1f")))
        L.append("\n| scheme | largest h with omega(0.5 s) within 1 % of the event reference |"
                 "\n|---|---|")
        for scheme in FIXED:
            rs = [r for r in full_rows if r["solver"] == scheme and "omega_end" in r]
            rs.sort(key=lambda r: float(r["param"][2:]))
            best = None  # largest h such that it and every smaller h run are within 1 %
            for r in rs:
                if not r["omega_rel_err"] <= 0.01:
                    break
                best = r
            tried = ", ".join(r["param"][2:] for r in rs)
            L.append("| %s | %s |" % (scheme, best["param"][2:] + " s" if best else
                                      "none of the h run (%s)" % tried))
    L.append("\n## Run times\n\n| part | wall [s] |\n|---|---|")
    for k, v in timing:
        L.append("| %s | %.0f |" % (k, v))
    L.append("")
    with open(path, "w") as f:
        f.write("\n".join(L))


def sha256(path):
    import hashlib
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def rubdyn_label(rubdyn):
    rel = os.path.relpath(rubdyn, ROOT)
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "src", "include"], cwd=ROOT,
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit, dirty = "unknown", ""
    mtime = datetime.datetime.fromtimestamp(os.path.getmtime(rubdyn)).strftime("%Y-%m-%d %H:%M")
    return rel, commit, (", with uncommitted changes in src/ or include/" if dirty else "") + \
        ", binary built %s, sha256 %s" % (mtime, sha256(rubdyn)[:16])


# ---- main ---------------------------------------------------------------------------------------
def main():
    global OUT, ONSET, STATE, CASE_PARAMS, MODEL, NOTES, RUBDYN_LABEL
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 epilog="Parts 1-3 take about 8 minutes on 2 cores, --full adds "
                                 "about 17.")
    ap.add_argument("rubdyn", nargs="?", help="path to rubdyn (default build/rubdyn)")
    ap.add_argument("--quick", action="store_true", help="a smaller subset (smoke run; output "
                    "to out/rolling/quick)")
    ap.add_argument("--full", action="store_true", help="also part 4, the full 0.5 s case")
    ap.add_argument("--selftest", action="store_true", help="run reference.py's checks only")
    args = ap.parse_args()
    if args.selftest:
        sys.exit(0 if ref.selftest() else 1)
    rubdyn_default, _, OUT = script_args("rolling")
    rubdyn = os.path.abspath(args.rubdyn or rubdyn_default)
    RUBDYN_LABEL = rubdyn_label(rubdyn)
    # run a private copy: the binary may be rebuilt while this script runs
    os.makedirs(os.path.join(OUT, "bin"), exist_ok=True)
    copy = os.path.join(OUT, "bin", "rubdyn")
    shutil.copy2(rubdyn, copy)
    digest0 = sha256(copy)
    say("rubdyn: %s (sha256 %s), run as %s" % (rubdyn, digest0[:16], os.path.relpath(copy, ROOT)))
    rubdyn = copy
    dest = os.path.join(OUT, "quick") if args.quick else HERE
    os.makedirs(dest, exist_ok=True)
    ONSET = ref.load_onset()
    STATE = ONSET["state"]
    CASE_PARAMS = ONSET["case"]
    MODEL = ref.Model(CASE_PARAMS)
    NOTES = set()
    command = "validation/rolling/run.py" + (" --quick" if args.quick else "") + \
        (" --full" if args.full else "")
    selftest_lines = []
    if not ref.selftest(verbose=False, out=selftest_lines):
        raise SystemExit("reference selftest failed (run reference.py --selftest)")
    timing = []
    t0 = time.perf_counter()
    sol, rows, info = part1(args.quick)
    timing.append(("1. reference (RK8 at h and h/2, scipy DOP853)", time.perf_counter() - t0))
    t0 = time.perf_counter()
    rows += part2(rubdyn, sol, args.quick)
    timing.append(("2. event-driven, 30 ms", time.perf_counter() - t0))
    t0 = time.perf_counter()
    r3, per_step = part3(rubdyn, sol, args.quick)
    rows += r3
    timing.append(("3. fixed-step schemes, 30 ms", time.perf_counter() - t0))
    full = None
    if args.full:
        t0 = time.perf_counter()
        full_rows, ev, chk = part4(rubdyn, per_step)
        timing.append(("4. full case (0.5 s), rubdyn runs", time.perf_counter() - t0))
        t0 = time.perf_counter()
        b = part4b(ev)
        timing.append(("4. reference from the onset to 0.5 s (two steps)",
                       time.perf_counter() - t0))
        full = (full_rows, ev, chk, b)
        rows += full_rows
        rows += [{"part": "4-full", "solver": "reference-rk8",
                  "variant": "from the event run's stick onset",
                  "param": "h=%.3g" % s.stats["h"], "omega_end": s.omega()[-1],
                  "omega_err": abs(s.omega()[-1] - ev.summary["omega_final"]),
                  "omega_err_signed": s.omega()[-1] - ev.summary["omega_final"],
                  "omega_rel_err": abs(s.omega()[-1] - ev.summary["omega_final"])
                  / ev.summary["omega_final"], "wall_seconds": s.stats["wall_seconds"],
                  "steps": s.stats["steps"], "stick_fraction": 1.0,
                  "termination": "completed"} for s in b.values()]
    timing.append(("total", sum(v for _, v in timing)))
    if sha256(rubdyn) != digest0:
        NOTES.add("the copy of the rubdyn binary changed while this script ran: the rubdyn "
                  "rows may come from two builds")
        say("WARNING: %s changed during the run" % rubdyn)
    fields = ["part", "solver", "variant", "param", "omega_end", "omega_err", "omega_err_signed",
              "omega_rel_err", "omega_err_sup", "orbit_err", "orbit_err_sup", "wall_seconds",
              "steps", "energy_residual", "energy_residual_rel", "max_penetration",
              "stick_fraction", "events",
              "termination"]
    write_csv(os.path.join(dest, "results.csv"),
              [{k: (repr(r[k]) if isinstance(r.get(k), float) else r.get(k, ""))
                for k in fields} for r in rows])
    write_table(os.path.join(dest, "table.md"), command, info, rows, full, timing,
                selftest_lines)
    diffs = [r for r in rows if r["part"] == "1-reference" and r["variant"] != "the reference"]
    unc = (max(r["omega_err"] for r in diffs) / abs(info["omega_end"]),
           max(r["orbit_err_sup"] for r in diffs))
    plot([r for r in rows if r["part"] != "4-full"], full[0] if full else None,
         os.path.join(dest, "rolling.png"), unc)
    with open(os.path.join(OUT, "run.log"), "w") as f:
        f.write("\n".join(LOG) + "\n")
    say("wrote %s/{results.csv, table.md, rolling.png}" % os.path.relpath(dest, ROOT))


if __name__ == "__main__":
    main()
