#!/usr/bin/python3
"""Stage 2b of the calibration: the parameters that neither the Campbell targets of stage 1 nor
the stage-2 grid touch, and that the paper does not give: the rotor radius R_r (rotor.radius,
lever of the friction torque), the stator damping c_s (stator.c), the driving torque tau_a
(loads.torque, which sets t_ref against the period of the dynamics) and Omega_lim / Omega_0
(run.omega_lim; omega0 stays at its stage-1 value, which f2f = 190 Hz is read at).

Question: does any combination make the paper case limited at k_s* = 8 and 10 but not at 4 and 5
(mu = 0.1, T7), with the stage-2 targets T1-T3 kept?

Screen (phase A, cheap: mu = 0.1 runs slip, they do not roll): every (R_r, c_s, tau_a) point runs
k_s* = 1, 4, 5, 8, 10 at mu = 0.1, long enough to cover 1.6 t_ref at the largest Omega_lim of the
grid. Omega_lim only moves the analysis (the model does not contain it; the solver only adds a
step boundary where it locates the crossing of the case's value), so each run is read at every
Omega_lim of the grid on the output grid: t_ref = (first output time with omega >= Omega_lim in
the k_s* = 1 run) / 0.76, and each verdict is read over [0, 1.6 t_ref]. Phase B (expensive:
mu >= 0.2 rolls) runs mu = 0, 0.2, 0.22, 0.25 only at the points whose phase-A verdicts make
k_s* = 8 or 10 limited, so T2-T5 are known there.
Phase D runs the point that comes closest to being limited at k_s* = 8 or 10 over the initial-state
ensemble of validation/ensemble/run.py, so that a 'never limited' verdict is not an accident of one
initial state. Phase C: the stator mass, each value with its own stage-1 refit. Phase E: which
stage-1 value removes the reference case's whip.
Choice rule: a point would replace stage 2's case only if it met T7 together with T1-T3 and kept
these verdicts over the ensemble; fit.py stops with a message if any point meets them (adopting
one is not written: no point has needed it), otherwise the exploration is stage-3 evidence.

Usage: validation/calibration/stage2b.py [path/to/rubdyn] [--quick] (on cases/paper.toml; runs go
to out/calibration/stage2b). fit.py calls explore() in its stage 3.
"""
import math
import os
import sys
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from common import ROOT, Run, script_args, sweep  # noqa: E402

T_REF_ANCHOR = 0.76
T_RUN = 1.6
TOL_T = 0.1
KS = [1, 4, 5, 8, 10]
MUS_B = [0.0, 0.2, 0.22, 0.25]


def grids(quick):
    if quick:
        return [0.03, 0.08], [0, 300], [10, 40], [1.055]
    return ([0.03, 0.05, 0.08], [0, 30, 100, 300], [5, 10, 20, 40], [1.03, 1.055, 1.11])


class Cut:
    """A Run read over [0, T] only."""

    def __init__(self, run, T):
        self.r, self.T = run, T
        self.m = run.t <= T

    def omega_max(self):
        return float(np.max(self.r.omega[self.m]))

    def ends_in_contact(self):
        return bool(self.r.contact[self.m][-1])

    def last_liftoff(self):
        t = [float(e["t"]) for e in self.r.events
             if e["kind"] in ("liftoff", "release") and float(e["t"]) <= self.T]
        return max(t) if t else 0.0

    def sign_settles(self, sign):
        p, t = self.r.prec[self.m], self.r.t[self.m]
        ok = ~np.isnan(p)
        bad = ok & (np.sign(p) != sign)
        if not ok.any() or bad[np.where(ok)[0][-1]]:
            return None
        idx = np.where(bad)[0]
        return t[idx[-1]] if len(idx) else t[0]

    def whip_onset(self):
        w = self.r.a.get("whip_onset")
        return w if w is not None and w <= self.T else None


def t_cross(run, omega_lim):
    i = np.where(run.omega >= omega_lim)[0]
    return float(run.t[i[0]]) if len(i) else None


def t_end_for(case, tau, ratio_max):
    """Run length covering 1.6 t_ref at the largest Omega_lim: the free acceleration time
    Jp (Omega_lim - Omega_0) / tau_a (friction only slows it: at mu = 0.1 it takes a few % of
    tau_a), with a 25 % margin for that."""
    om0 = case["initial"]["omega0"]
    return 1.25 * T_RUN / T_REF_ANCHOR * case["rotor"]["Jp"] * om0 * (ratio_max - 1) / tau


def phase_a(rubdyn, path, out, quick):
    case = tomllib.load(open(path, "rb"))
    k_ref = case["stator"]["k"]
    radii, cs, taus, ratios = grids(quick)
    runs = {}  # (R_r, c_s, tau) -> {k_s*: Run}
    nruns = 0
    wall = 0.0
    for tau in taus:
        rows = sweep(rubdyn, path, os.path.join(out, "A-tau%g" % tau),
                     t_end_for(case, tau, max(ratios)),
                     ["rotor.radius=" + ",".join("%g" % r for r in radii),
                      "stator.c=" + ",".join("%g" % c for c in cs),
                      "stator.k=" + ",".join("%.9g" % (k * k_ref) for k in KS)],
                     ["contact.mu=0.1", "loads.torque=%g" % tau])
        for r in rows:
            key = (float(r["rotor.radius"]), float(r["stator.c"]), tau)
            runs.setdefault(key, {})[round(float(r["stator.k"]) / k_ref, 2)] = Run(r["folder"])
            nruns += 1
            wall += float(r["wall_seconds"] or 0)
    return case, runs, ratios, nruns, wall


def verdicts_a(case, kruns, ratio):
    """T1 and T7-T9 of one point at Omega_lim = ratio Omega_0 (None: mu = 0.1 never reaches it,
    or the run is too short for 1.6 t_ref)."""
    oml = ratio * case["initial"]["omega0"]
    tc = t_cross(kruns[1], oml)
    if tc is None:
        return None
    tref = tc / T_REF_ANCHOR
    T = T_RUN * tref
    if kruns[1].t[-1] < T * (1 - 1e-9):
        return None
    cut = {k: Cut(r, T) for k, r in kruns.items()}
    lim = {k: c.omega_max() < oml for k, c in cut.items()}
    m = {"t_ref": tref, "lim": lim, "omega_lim": oml}
    m["T1"] = bool(np.max(kruns[1].ftr[cut[1].m]) < 1) and not lim[1]
    m["T7"] = (not lim[4]) and (not lim[5]) and lim[8] and lim[10]
    c10 = cut[10]
    m["T8"] = c10.ends_in_contact() and abs(c10.last_liftoff() / tref - 0.45) <= TOL_T
    neg = c10.sign_settles(-1)
    m["T9"] = neg is not None and abs(neg / tref - 0.5) <= TOL_T
    m["whip"] = {k: (c.whip_onset() / tref if c.whip_onset() is not None else None)
                 for k, c in cut.items()}
    m["wmax"] = {k: c.omega_max() / oml for k, c in cut.items()}
    return m


def phase_b(rubdyn, path, out, case, points):
    """mu = 0, 0.2, 0.22, 0.25 (k_s* = 1) at the given (R_r, c_s, tau) points."""
    res = {}
    ratios_max = max(r for _, _, _, r in points) if points else 1.0
    for i, (rr, cs, tau, _) in enumerate(sorted({p[:3] + (0,) for p in points})):
        rows = sweep(rubdyn, path, os.path.join(out, "B-%d" % i),
                     t_end_for(case, tau, ratios_max),
                     ["contact.mu=" + ",".join("%g" % m for m in MUS_B)],
                     ["rotor.radius=%g" % rr, "stator.c=%g" % cs, "loads.torque=%g" % tau])
        res[(rr, cs, tau)] = {float(r["contact.mu"]): Run(r["folder"]) for r in rows}
    return res


def verdicts_b(mruns, r01, tref, oml):
    T = T_RUN * tref
    cut = {mu: Cut(r, T) for mu, r in mruns.items()}
    lim = {mu: c.omega_max() < oml for mu, c in cut.items()}
    m = {"T2": (not lim[0.2]) and (not lim[0.22]) and lim[0.25]}
    r0 = mruns[0.0]
    c0 = r0.contact & cut[0.0].m
    m["T3"] = bool(np.nanmean(r0.prec[c0]) > 0) if c0.any() else False
    c1 = Cut(r01, T)
    m["T4"] = c1.ends_in_contact() and abs(c1.last_liftoff() / tref - 0.80) <= TOL_T
    neg = c1.sign_settles(-1)
    m["T5"] = neg is not None and abs(neg / tref - 1.3) <= TOL_T
    sel = cut[0.0].m & (r0.t >= 0.9 * tref)
    m["T6"] = float(r0.contact[sel].mean()) < 0.05
    m["lim_mu"] = [mu for mu in sorted(lim) if lim[mu]]
    return m


def ms_grid(quick):
    """Phase C grid: m_s (each with its own stage-1 refit), R_r, tau_a; c_s = 100 N s/m."""
    if quick:
        return [1.0], [0.05], [20]
    return [0.5, 1.0, 4.0, 8.0], [0.05, 0.08], [10, 20]


def phase_c(rubdyn, path, out, quick):
    """m_s moves the Campbell frequencies (the stator is tied to the rotor there): every m_s gets
    its own stage-1 refit (fit.stage1 on the reference case with that m_s), then k_s* = 1, 4, 5,
    8, 10 at mu = 0.1, read as phase A (T1, T7)."""
    import copy
    import fit  # noqa: E402 (fit.py imports this module: import here, not at the top)
    ref = tomllib.load(open(fit.REFERENCE, "rb"))
    case = tomllib.load(open(path, "rb"))
    masses, radii, taus = ms_grid(quick)
    _, _, _, ratios = grids(quick)
    rows_out, n = [], 0
    for ms in masses:
        r = copy.deepcopy(ref)
        r["stator"]["mass"] = ms
        p = fit.stage1(r, [])[0]
        sets = ["stator.mass=%g" % ms, "contact.mu=0.1", "stator.c=100"] + [
            "%s.%s=%.9g" % (sec, k, p[sec][k]) for sec, k in fit.FREE
            if (sec, k) != ("stator", "k")]
        cp = copy.deepcopy(case)
        cp["rotor"]["Jp"] = p["rotor"]["Jp"]
        for tau in taus:
            rows = sweep(rubdyn, path, os.path.join(out, "C-ms%g-tau%g" % (ms, tau)),
                         t_end_for(cp, tau, max(ratios)),
                         ["rotor.radius=" + ",".join("%g" % x for x in radii),
                          "stator.k=" + ",".join("%.9g" % (k * p["stator"]["k"]) for k in KS)],
                         sets + ["loads.torque=%g" % tau])
            runs = {}
            for row in rows:
                runs.setdefault(float(row["rotor.radius"]), {})[
                    round(float(row["stator.k"]) / p["stator"]["k"], 2)] = Run(row["folder"])
                n += 1
            for rr, kr in runs.items():
                for ratio in ratios:
                    v = verdicts_a(cp, kr, ratio)
                    rows_out.append(((ms, rr, tau, ratio), p, v))
    return rows_out, n


N_ENS = 8          # ensemble members, as validation/ensemble/run.py
D_OMEGA = 0.1      # rad/s, largest omega0 perturbation
R_OFF = 1e-7       # m, rotor released this far off centre at R


def member_sets(omega0, k, n):
    """Member k = 1..n of validation/ensemble/run.py's ensemble: omega0 + 0.1 (2 (k - 1) / (n - 1)
    - 1) rad/s and the rotor 0.1 um off centre in the direction 2 pi (k - 1) / n."""
    om = D_OMEGA * (2 * (k - 1) / (n - 1) - 1) if n > 1 else D_OMEGA
    a = 2 * math.pi * (k - 1) / n
    return ["initial.omega0=%.10g" % (omega0 + om), "initial.x_r=%.6g" % (R_OFF * math.cos(a)),
            "initial.y_r=%.6g" % (R_OFF * math.sin(a))]


def phase_d(rubdyn, path, out, case, key, quick):
    """The verdicts at k_s* = 4, 5, 8, 10 (mu = 0.1) of one point over the initial-state
    ensemble: {k_s*: [limited?, ...]}, [whirl at k_s* = 8 or 10?, ...] over the members."""
    rr, cs, tau, ratio = key
    n = N_ENS if not quick else 2
    k_ref = case["stator"]["k"]
    lim, whirl = {k: [] for k in KS}, []
    for m in range(1, n + 1):
        rows = sweep(rubdyn, path, os.path.join(out, "D-m%02d" % m),
                     t_end_for(case, tau, ratio),
                     ["stator.k=" + ",".join("%.9g" % (k * k_ref) for k in KS)],
                     ["contact.mu=0.1", "rotor.radius=%g" % rr, "stator.c=%g" % cs,
                      "loads.torque=%g" % tau] + member_sets(case["initial"]["omega0"], m, n))
        kr = {round(float(r["stator.k"]) / k_ref, 2): Run(r["folder"]) for r in rows}
        v = verdicts_a(case, kr, ratio)
        if v is None:
            continue
        for k in KS:
            lim[k].append(v["lim"][k])
        whirl.append(v["whip"][8] is not None or v["whip"][10] is not None)
    return lim, whirl, n


def phase_e(rubdyn, path, out):
    """Which stage-1 parameter removes the reference case's whip: cases/reference.toml at
    k_s* = 8 and 10 (its own k_s), mu = 0.1, its own run.t_end, with one of Jd, Jp, k_b, c_b set to
    the paper case's value at a time. Returns [(changed key or None, {k_s*: whirl onset [s] or
    None})]."""
    import fit  # noqa: E402
    ref = tomllib.load(open(fit.REFERENCE, "rb"))
    paper = tomllib.load(open(path, "rb"))
    out_rows = []
    for sk in [None, ("rotor", "Jd"), ("rotor", "Jp"), ("bearing", "k"), ("bearing", "c")]:
        sets = ["contact.mu=0.1"]
        if sk:
            sets.append("%s.%s=%.9g" % (sk[0], sk[1], paper[sk[0]][sk[1]]))
        rows = sweep(rubdyn, fit.REFERENCE, os.path.join(out, "E-%s" % (
            "%s.%s" % sk if sk else "reference")), ref["run"]["t_end"],
            ["stator.k=%.9g,%.9g" % (8 * ref["stator"]["k"], 10 * ref["stator"]["k"])], sets)
        out_rows.append((("%s.%s = %g" % (sk[0], sk[1], paper[sk[0]][sk[1]])) if sk else None,
                         {round(float(r["stator.k"]) / ref["stator"]["k"]): (
                             float(r["whip_onset"]) if r["whip_onset"] else None)
                          for r in rows}))
    return out_rows


def explore(rubdyn, path, out, quick):
    """Runs phases A and B; returns (lines for results.md, summary dict)."""
    case, runs, ratios, nA, wallA = phase_a(rubdyn, path, out, quick)
    table = {}
    for key, kr in runs.items():
        for ratio in ratios:
            table[key + (ratio,)] = verdicts_a(case, kr, ratio)
    valid = {k: v for k, v in table.items() if v is not None}
    t1 = {k: v for k, v in valid.items() if v["T1"]}
    any810 = {k: v for k, v in t1.items() if v["lim"][8] or v["lim"][10]}
    cand = {k: v for k, v in t1.items() if v["T7"]}
    # phase B where k_s* = 8 or 10 is limited (the candidates first)
    bpts = sorted(any810)
    bres = phase_b(rubdyn, path, out, case, bpts) if bpts else {}
    nB = 4 * len(bres)
    full = {}
    for k in bpts:
        v = dict(valid[k])
        v.update(verdicts_b(bres[k[:3]], runs[k[:3]][1], v["t_ref"], v["omega_lim"]))
        v["met"] = sum(bool(v["T%d" % i]) for i in range(1, 10))
        full[k] = v
    radii, cs, taus, _ = grids(quick)
    lines = ["- **Stage 2b: the parameters no earlier stage touched** (`stage2b.py`). rotor.radius "
             "in %s m, stator.c in %s N s/m, loads.torque in %s N m, each run at k_s* = %s and "
             "mu = 0.1 (%d runs, %.0f s of run wall time) and read at run.omega_lim / omega0 in %s "
             "(t_ref from each point's own crossing at k_s* = 1, verdicts over 1.6 t_ref). Of %d "
             "(R_r, c_s, tau_a, Omega_lim) points, %d can be read (mu = 0.1 reaches Omega_lim and "
             "the run covers 1.6 t_ref), %d meet T1, %d of these are limited at k_s* = 8 or 10, "
             "%d meet T7 (k_s* = 4, 5 not limited, 8, 10 limited)." % (
                 radii, cs, taus, KS, nA, wallA, ratios, len(table), len(valid), len(t1),
                 len(any810), len(cand))]
    # per k_s*: how often it is limited / whips, over the T1 points
    for k in KS[1:]:
        nl = sum(v["lim"][k] for v in t1.values())
        nw = sum(v["whip"][k] is not None for v in t1.values())
        lines[-1] += " k_s* = %d: limited at %d, sustained backward whirl at %d;" % (k, nl, nw)
    lines[-1] = lines[-1].rstrip(";") + "."
    if full:
        lines += ["", "  Points limited at k_s* = 8 or 10 (phase B: mu = 0, 0.2, 0.22, 0.25 run "
                  "there, %d runs):" % nB, "",
                  "  | R_r | c_s | tau_a | Omega_lim/Omega_0 | t_ref [s] | limited k_s* | "
                  "limited mu | " + " | ".join("T%d" % i for i in range(1, 10)) + " | met |",
                  "  |---|---|---|---|---|---|---|" + "---|" * 9 + "---|"]
        for k in sorted(full, key=lambda k: (-full[k]["met"], k)):
            v = full[k]
            lines.append("  | %g | %g | %g | %g | %.4g | %s | %s | " % (
                k[0], k[1], k[2], k[3], v["t_ref"],
                [kk for kk in KS if v["lim"][kk]], v["lim_mu"]) +
                " | ".join("yes" if v["T%d" % i] else "-" for i in range(1, 10)) +
                " | %d |" % v["met"])
    ok = {k: v for k, v in full.items() if v["T1"] and v["T2"] and v["T3"] and v["T7"]}
    # Omega_max / Omega_lim at k_s* = 8 and 10 over the T1 points: how close the rest come
    if t1:
        best = min(t1, key=lambda k: min(t1[k]["wmax"][8], t1[k]["wmax"][10]))
        lines += ["", "  Smallest Omega_max / Omega_lim at k_s* = 8 or 10 over the T1 points: "
                  "%.4f (R_r = %g, c_s = %g, tau_a = %g, Omega_lim / Omega_0 = %g)." % (
                      min(t1[best]["wmax"][8], t1[best]["wmax"][10]), *best)]
    # phase D: the closest point over the initial-state ensemble (a 'never limited' verdict is
    # worth as much as a limited one only if a 5e-5 perturbation does not flip it)
    if t1:
        dl, dw, dn = phase_d(rubdyn, path, out, case, best, quick)
        lines += ["", "  That point over the initial-state ensemble of validation/ensemble/run.py "
                  "(%d members: omega0 +- %g rad/s, rotor %g um off centre): limited at k_s* = %s "
                  "in %s of %d members; sustained backward whirl at k_s* = 8 or 10 in %d." % (
                      dn, D_OMEGA, R_OFF * 1e6, ", ".join("%d" % k for k in KS[1:]),
                      ", ".join("%d" % sum(dl[k]) for k in KS[1:]), len(dw), sum(dw))]
    # phase C: the stator mass, with its stage-1 refit
    crows, nC = phase_c(rubdyn, path, out, quick)
    masses, cr, ct = ms_grid(quick)
    cv = [v for _, _, v in crows if v is not None]
    ct1 = [v for v in cv if v["T1"]]
    lines += ["", "- **Stage 2b, stator mass** (last: m_s moves the Campbell frequencies, so each "
              "value gets its own stage-1 refit): stator.mass in %s kg (refit Jd %s kg m^2, "
              "stator.k %s N/m), rotor.radius in %s m, loads.torque in %s N m, stator.c = 100 "
              "N s/m, k_s* = %s at mu = 0.1 (%d runs), read at the same Omega_lim / Omega_0: of "
              "%d points %d can be read, %d meet T1, limited at k_s* = 8 at %d, at 10 at %d, T7 "
              "met at %d; sustained backward whirl at k_s* = 8 or 10 in %d." % (
                  masses, sorted({"%.4g" % p["rotor"]["Jd"] for _, p, _ in crows}),
                  sorted({"%.4g" % p["stator"]["k"] for _, p, _ in crows}), cr, ct, KS, nC,
                  len(crows), len(cv), len(ct1), sum(v["lim"][8] for v in ct1),
                  sum(v["lim"][10] for v in ct1), sum(v["T7"] for v in ct1),
                  sum(v["whip"][8] is not None or v["whip"][10] is not None for v in ct1))]
    if ct1:
        wm = min(min(v["wmax"][8], v["wmax"][10]) for v in ct1)
        lines[-1] += " Smallest Omega_max / Omega_lim at k_s* = 8 or 10: %.4f." % wm
    # phase E: why the paper case has no whip where the reference case has one
    erows = phase_e(rubdyn, path, out)

    def onsets(d):
        return ", ".join("k_s* = %d: %s" % (k, "whirl from %.3f s" % d[k] if d[k] is not None
                                            else "no whirl") for k in sorted(d))
    lines += ["", "- **Where the whip went.** cases/reference.toml at mu = 0.1 (its run.t_end), "
              "sustained backward whirl: %s. With one stage-1/stage-2 value of the paper case "
              "at a time: %s." % (onsets(erows[0][1]), "; ".join(
                  "%s: %s" % (name, onsets(d)) for name, d in erows[1:]))]
    return lines, {"ok": ok, "nC": nC, "E": erows, "full": full, "table": table, "nA": nA,
                   "nB": nB, "wallA": wallA}


def main():
    rubdyn, quick, out = script_args("calibration")
    lines, s = explore(rubdyn, os.path.join(ROOT, "cases", "paper.toml"),
                       os.path.join(out, "stage2b"), quick)
    print("\n".join(lines))
    print("T1-T3 + T7 at:", sorted(s["ok"]))


if __name__ == "__main__":
    main()
