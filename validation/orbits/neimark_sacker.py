#!/usr/bin/python3
"""A Neimark-Sacker point of the paper's rotor in partial rub (cases/paper-partial-rub.toml at
600 rad/s; docs/orbits.md section 10): its orbit (an impact, a slide and a lift-off per period)
has an unstable complex pair, |mu| = 1.155, at the case's ring damping stator.c = 100 N s/m;
followed in stator.c (`rubdyn branch --vary stator.c`) the pair's modulus falls through 1, where
the orbit becomes stable (a Neimark-Sacker point: a torus is born or dies there). Checked:

1. the continuation locates it with the monodromies from the flow's sensitivities and with
   finite differences: the same point within their brackets and error bounds;
2. independent orbits (`rubdyn orbit --monodromy sensitivities` at rtol 1e-12) at the located
   value +- DELTA: the pair's modulus is above 1 below it and below 1 above it, and its linear
   zero lies within its error (from the two moduli's bounds) of the located value;
3. transients (rtol 1e-12) started on those two orbits displaced by 1e-5 along the real and the
   imaginary part of the pair's direction: the root of the summed squares of the displacements
   grows (below) or decays (above) per period by |mu| within the multiplier's error bound plus
   three standard errors of the fit (validation/orbits/paper_partial.py's method): the stability
   change is a motion's, not only the monodromy's.

Writes validation/orbits/neimark_sacker.md; exits 1 if a check fails (a ctest).

    validation/orbits/neimark_sacker.py [--cli build/rubdyn] [--out FILE]    # about 15 s
"""
import argparse
import csv
import json
import math
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "validation"))
import paper_partial as pp  # noqa: E402
from common import machine  # noqa: E402

KEY = "stator.c"
TO = 700.0      # the branch's end in stator.c [N s/m]
DELTA = 1.0     # the independent orbits' distance from the located point [N s/m]
# The transients: with |mu| this close to 1 the displacement neither grows nor decays much, so
# it is larger than paper_partial.py's (1e-5: the ratio r_k / (|mu|^k |v| eps) stays within 4e-6
# of 1 over 80 periods, measured; at 1e-6 the runs' noise at rtol 1e-12 shows, 3e-5) and the fit
# longer (periods 10 to 80)
EPS = 1e-5
K_FIT = (10, 80)


def branch(cli, out, frm, extra=()):
    cmd = [cli, "branch", pp.CASE, "--from", frm, "--vary", KEY, "--points", "120", "--ds-max",
           "10", "--to", repr(TO), "--out", out, *extra]
    t = time.perf_counter()
    pp.run(cmd)
    w = time.perf_counter() - t
    with open(os.path.join(out, "branch.json")) as f:
        j = json.load(f)
    with open(os.path.join(out, "branch.csv")) as f:
        rows = list(csv.DictReader(f))
    return j, rows, w, cmd


def orbit_near(cli, out, row, value):
    """`rubdyn orbit --monodromy sensitivities` at rtol 1e-12 with stator.c = value, from a branch
    point's state at its own section time (theta = omega t, as in the --from run)."""
    t0 = float(row["t0"])
    sets = [f"initial.{n}={float(row[n])!r}" for n in pp.NAMES]
    sets += [f"{KEY}={value!r}", f"run.t_start={t0!r}", f"run.t_end={t0 + 1.0!r}",
             f"initial.theta={pp.OMEGA * t0!r}"]
    cmd = [cli, "orbit", pp.CASE, "--out", out, "--monodromy", "sensitivities", "--rtol", "1e-12",
           "--atol", "1e-15"]
    for x in sets:
        cmd += ["--set", x]
    pp.run(cmd)
    with open(os.path.join(out, "orbit.json")) as f:
        return json.load(f)


def pair(o):
    """The complex multiplier of largest modulus with positive imaginary part."""
    return max((m for m in o["multipliers"] if m["im"] > 0), key=lambda m: m["abs"])


def growth(cli, tmp, tag, o, value):
    """The transients' growth per period along the pair's direction (fit over K_FIT)."""
    T = 2 * math.pi / pp.OMEGA
    names = list(o["state"].keys())
    x = np.array([o["state"][n] / pp.scale(n) for n in names])
    mu = pair(o)
    v = np.array([complex(*mu["direction"][n]) / pp.scale(n) for n in names])
    extra = [f"{KEY}={value!r}"]
    kmax = K_FIT[1]
    base = pp.transient(cli, os.path.join(tmp, tag + "b"), o, x, T, kmax, extra)
    sre = pp.transient(cli, os.path.join(tmp, tag + "r"), o, x + EPS * v.real, T, kmax,
                       extra) - base
    sim = pp.transient(cli, os.path.join(tmp, tag + "i"), o, x + EPS * v.imag, T, kmax,
                       extra) - base
    r = np.sqrt(np.sum(sre ** 2, axis=1) + np.sum(sim ** 2, axis=1))
    ks = np.arange(K_FIT[0], K_FIT[1] + 1)
    c, cov = np.polyfit(ks, np.log(r[ks]), 1, cov=True)
    g = math.exp(c[0])
    # (the fit's standard error of the growth, from its residuals: the runs' noise)
    return g, g * math.sqrt(cov[0, 0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "rubdyn"))
    ap.add_argument("--out", default=os.path.join(HERE, "neimark_sacker.md"))
    a = ap.parse_args()
    fails = []
    with tempfile.TemporaryDirectory() as tmp:
        tr = os.path.join(tmp, "transient")
        pp.run([a.cli, "run", pp.CASE, "--out", tr, "--quiet"])
        js, rows, ws, cmd = branch(a.cli, os.path.join(tmp, "bs"), tr,
                                   ["--monodromy", "sensitivities"])
        jd, rows_d, wd, _ = branch(a.cli, os.path.join(tmp, "bd"), tr)
        ns = {}
        for name, j in (("sensitivities", js), ("differences", jd)):
            found = [s for s in j["specials"] if s["kind"] == "neimark_sacker"]
            if len(found) != 1:
                raise SystemExit(f"{name}: {len(found)} Neimark-Sacker points: {j['specials']}")
            ns[name] = found[0]
        lam = ns["sensitivities"]["value"]
        i, k = ns["sensitivities"]["between"]
        # 2. independent orbits on either side, from the branch points around it
        below = orbit_near(a.cli, os.path.join(tmp, "below"), rows[i], lam - DELTA)
        above = orbit_near(a.cli, os.path.join(tmp, "above"), rows[k], lam + DELTA)
        for o in (below, above):
            if o["outcome"] != "converged" or o["sequence"] != "free | impact liftoff | free":
                fails.append(f"an orbit near the point: {o['outcome']}, {o['sequence']}")
        mb, ma = pair(below), pair(above)
        zero = lam - DELTA + 2 * DELTA * (mb["abs"] - 1) / (mb["abs"] - ma["abs"])
        slope = (ma["abs"] - mb["abs"]) / (2 * DELTA)
        # the zero's error: the moduli's bounds over the slope, and the curvature of |mu| over
        # the interval (its second difference along the branch, times DELTA^2 / 2, over the slope)
        curv = 0.0
        mods = [(float(r[KEY]), max(abs(complex(float(r[f"mu{j}_re"]), float(r[f"mu{j}_im"])))
                                    for j in range(1, 13) if r.get(f"mu{j}_re")))
                for r in rows[max(0, i - 2):k + 3]]
        if len(mods) >= 3:
            c = np.polyfit([m[0] for m in mods], [m[1] for m in mods], 2)[0]
            curv = abs(c) * DELTA ** 2
        zero_bound = (mb["error"] + ma["error"]) / abs(slope) + curv / abs(slope)

        def located_error(name, rs):
            """A located value's error: its branch's monodromy error (the largest multiplier's
            bound at the two points around it) over the slope, and its bracket."""
            b0, b1 = ns[name]["between"]
            e = max(float(rs[b0]["mu1_error"]), float(rs[b1]["mu1_error"]))
            return e / abs(slope) + ns[name]["spread"]

        err_s, err_d = located_error("sensitivities", rows), located_error("differences", rows_d)
        if not (mb["abs"] > 1 > ma["abs"]):
            fails.append(f"|mu| {mb['abs']:.6f} below and {ma['abs']:.6f} above: not across 1")
        if abs(zero - lam) > zero_bound + err_s:
            fails.append(f"the orbits' zero {zero:.6f} is {abs(zero - lam):.1e} from the located "
                         f"{lam:.6f} (bound {zero_bound + err_s:.1e})")
        ld = ns["differences"]["value"]
        if abs(ld - lam) > err_s + err_d:
            fails.append(f"the differences' point {ld:.6f} is {abs(ld - lam):.1e} from the "
                         f"sensitivities' (bound {err_s + err_d:.1e})")
        # 3. transients on either side
        gb, sb = growth(a.cli, tmp, "gb", below, lam - DELTA)
        ga, sa = growth(a.cli, tmp, "ga", above, lam + DELTA)
        for g, sg, m, side in ((gb, sb, mb, "below"), (ga, sa, ma, "above")):
            if abs(g - m["abs"]) > m["error"] + 3 * sg:
                fails.append(f"{side}: transient growth {g:.8f} per period against |mu| = "
                             f"{m['abs']:.8f} (bound {m['error']:.1e} + 3 x {sg:.1e})")
        if not (gb > 1 > ga):
            fails.append(f"transients grow by {gb:.8f} below and {ga:.8f} above")
    lines = [
        "# A Neimark-Sacker point of the paper's rotor in partial rub",
        "",
        "Generated by `validation/orbits/neimark_sacker.py` (docs/orbits.md, section 10) on "
        "`cases/paper-partial-rub.toml` (600 rad/s, gravity on, an unbalance of 5e-5 kg m): the "
        f"orbit followed in the ring's damping `{KEY}` from the case's 100 N s/m (`" +
        " ".join("RUN" if c == tr else os.path.relpath(c, ROOT) if c.startswith(ROOT) else c
                 for c in cmd[:-4]) +
        " [--monodromy sensitivities]`, RUN the case's transient run). Machine: " + machine() +
        ".",
        "",
        "| monodromy | points | runs | wall [s] | Neimark-Sacker point [N s/m] | bracket | how |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, j, w in (("sensitivities", js, ws), ("differences", jd, wd)):
        s = ns[name]
        lines.append(f"| {name} | {j['points']} | {j['runs']} | {w:.1f} | {s['value']:.6f} | "
                     f"{s['spread']:.1e} | {s['how']} |")
    lines += [
        "",
        f"The two located values differ by {abs(ld - lam):.1e} N s/m; their errors (the "
        "branch's monodromy error bound at the points around the crossing over the modulus' slope, "
        f"and the bracket): {err_s:.1e} (sensitivities, rtol 1e-10) and {err_d:.1e} (differences). "
        "Along the branch the "
        f"pair's modulus goes from {float(rows[0]['mu_max_abs']):.6f} (stator.c = 100) through 1 "
        f"(slope {slope:.3e} per N s/m there); the angle of the pair at the crossing, "
        f"{math.atan2(mb['im'], mb['re']):.4f} rad, is the rotation per period of the motion on "
        "the torus born there.",
        "",
        "Independent orbits (`rubdyn orbit --monodromy sensitivities`, rtol 1e-12) and transients "
        f"(rtol 1e-12, displaced by {EPS:g} along the pair's direction, growth per period fitted "
        f"over periods {K_FIT[0]} to {K_FIT[1]}) at the located value -+ {DELTA:g} N s/m:",
        "",
        "| stator.c [N s/m] | pair | abs(mu) | its error bound | transients' growth per period "
        "(standard error) | difference |",
        "|---|---|---|---|---|---|",
    ]
    for val, m, g, sg in ((lam - DELTA, mb, gb, sb), (lam + DELTA, ma, ga, sa)):
        lines.append(f"| {val:.4f} | {m['re']:+.6f} {m['im']:+.6f}i | {m['abs']:.8f} | "
                     f"{m['error']:.1e} | {g:.8f} ({sg:.1e}) | {abs(g - m['abs']):.1e} |")
    lines += [
        "",
        f"The moduli's linear zero: {zero:.6f} N s/m, {abs(zero - lam):.1e} from the located value "
        f"(bound {zero_bound + err_s:.1e}: the moduli's error bounds and the curvature of abs(mu) "
        "over the interval, over the slope, and the located value's error).",
        "",
    ]
    pp.write_report(a.out, lines, fails)


if __name__ == "__main__":
    main()
