#!/usr/bin/python3
"""`rubdyn branch` on cases/full-rub.toml in the spin speed (docs/orbits.md, section 10): the
sprung ring's forward full annular rub from 1500 rad/s up through the fold where the stable and
the saddle branch meet, and down the saddle branch to where its contact force vanishes (the
orbit lifts off: the branch of sliding orbits ends). Compared with the closed form
(docs/closed-forms.md 5.1, validation/analytic/closed_forms.py): the fold where the
discriminant of (5.2) vanishes, the speed where the smaller root's N = 0, and every point's
normal force against the root of its branch. Writes validation/orbits/branch.md, branch.png
and multipliers.png (validation/orbits/plot.py).

    validation/orbits/branch.py [--cli build/rubdyn]     # about 10 s
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.optimize import brentq

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "validation", "analytic"))
sys.path.insert(0, os.path.join(ROOT, "validation"))
import closed_forms as cf  # noqa: E402
from common import machine  # noqa: E402
from test_closed_forms import UNB_SPRUNG  # noqa: E402

import plot  # noqa: E402  (validation/orbits/plot.py)


def discriminant(P, om):
    s = cf.short(P)
    U = s["u_b"] * om * om
    K = cf.receptance(P, om)
    Dr = cf.dynamic_stiffness(s["m_r"], s["k_r"], s["c_r"], om)
    Ds = cf.dynamic_stiffness(s["m_s"], s["k_s"], s["c_s"], om)
    rhs = (U * abs(Ds / (Dr + Ds))) ** 2
    a, b, mu = s["g0"] * K.real, s["g0"] * K.imag, s["mu"]
    A2, A1, A0 = 1 + mu * mu, 2 * (a + mu * b), a * a + b * b - rhs
    return A1 * A1 - 4 * A2 * A0


def landing(end, rows):
    """How the branch's end was seen: the corrector converged on an orbit with other events (the
    last row), or its iterates reached one and no step converged (no row: the events are in the
    special's text)."""
    last = float(rows[end["between"][0]]["initial.omega0"])
    if end["between"][1] is not None:
        return (f"the events change between {last:.6f} and {end['value']:.6f} rad/s, where the "
                "corrector lands on an orbit in free flight throughout "
                f"(`{rows[-1]['events']}`)")
    m = re.search(r"has the events \[(.*?)\]", end["how"])
    it = re.search(r"the corrector's iterate at ([-0-9.e+]+)", end["how"])
    return (f"the last smooth orbit at {last:.6f} rad/s (F_N >= "
            f"{float(rows[end['between'][0]]['F_N_min']):.3g} N); beyond it no corrector step "
            f"converges, its iterate at {float(it.group(1)) if it else float('nan'):.6f} rad/s "
            f"being a motion in free flight throughout (`{m.group(1) if m else '?'}`)")


def located(end, graze):
    """The lift-off located by extrapolating F_N_min to zero (continuation.cpp), if it was."""
    if "extrapolated to zero" not in end["how"]:
        return "not located (no extrapolation from the last points)"
    return (f"located by extrapolating the contact force's minimum to zero from the last smooth "
            f"points at {end['value']:.7f} rad/s (its two estimates {end['spread']:.1e} rad/s "
            f"apart), {end['value'] - graze:+.1e} rad/s from the closed form")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "rubdyn"))
    ap.add_argument("--out", default=HERE)
    a = ap.parse_args()
    P = UNB_SPRUNG
    fold = brentq(lambda om: discriminant(P, om), 1700.0, 1900.0, xtol=1e-12)
    graze = brentq(lambda om: cf.unbalance_full_rub_roots(P, om)["roots"][1]["N"], 1250.0,
                   1400.0, xtol=1e-12)
    case = os.path.join(ROOT, "cases", "full-rub.toml")
    with tempfile.TemporaryDirectory() as tmp:
        d = os.path.join(tmp, "branch")
        cmd = [a.cli, "branch", case, "--vary", "initial.omega0", "--points", "200", "--ds-max",
               "3", "--out", d]
        t = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t
        if p.returncode != 0:
            raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
        with open(os.path.join(d, "branch.json")) as f:
            meta = json.load(f)
        with open(os.path.join(d, "branch.csv")) as f:
            rows = list(csv.DictReader(f))
        plot.plot_branch(d)
        for name in ("branch.png", "multipliers.png"):
            os.replace(os.path.join(d, name), os.path.join(a.out, name))
    folds = [s for s in meta["specials"] if s["kind"] == "fold"]
    ends = [s for s in meta["specials"] if s["kind"] == "events_change"]
    # every analysed point's normal force against its branch's root (larger before the fold)
    fold_after = folds[0]["between"][0] if folds else len(rows)
    dev, dev_far = 0.0, 0.0
    for i, r in enumerate(rows):
        if not r["mu1_re"]:
            continue
        om = float(r["initial.omega0"])
        roots = cf.unbalance_full_rub_roots(P, om)["roots"]
        if len(roots) < 2:
            continue
        N = roots[0]["N"] if i <= fold_after else roots[1]["N"]
        e = abs(float(r["F_N_max"]) - N) / max(N, 1.0)
        dev = max(dev, e)
        if abs(om - fold) > 5.0 and N > 100.0:
            dev_far = max(dev_far, e)
    stab = [r["stability"] for r in rows if r["mu1_re"]]
    stable_idx = [i for i, r in enumerate(rows) if r["stability"] == "stable"]
    before = all(i <= fold_after for i in stable_idx)
    und = [r for r in rows if r["mu1_re"] and r["stability"] == "undecided"]
    und_fn = max((float(r["F_N_max"]) for r in und), default=0.0)
    errs = [float(r["mu1_error"]) for r in und] or [0.0]
    und_err = (min(errs), max(errs))
    lines = [
        "# rubdyn branch: the full rub's fold and the end of its saddle branch",
        "",
        "Generated by `validation/orbits/branch.py` (docs/orbits.md, section 10): `" +
        " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c
                 for c in cmd[:-2]) + "`, compared with the closed form of "
        "docs/closed-forms.md 5.1 (the set UNB_SPRUNG). Machine: " + machine() + ".",
        "",
        f"- points: {len(rows)}, outcome `{meta['outcome']}`, {meta['runs']} runs of the return "
        f"map, {meta['wall_seconds']:.2f} s (the command: {wall:.2f} s wall), i.e. "
        f"{meta['wall_seconds'] / len(rows) * 1e3:.0f} ms a point.",
        f"- fold: located at {folds[0]['value']:.10f} rad/s; closed form (the discriminant of "
        f"(5.2) vanishes) {fold:.10f} rad/s; difference {folds[0]['value'] - fold:.2e} rad/s "
        f"({(folds[0]['value'] - fold) / fold:.1e} relative). {folds[0]['how']}."
        if folds else "- fold: NOT FOUND",
        f"- end of the saddle branch: {landing(ends[0], rows)}: the free unbalance orbit, which "
        f"the saddle branch "
        f"meets where its contact force vanishes; closed form: the smaller root's N = 0 (the free "
        f"orbit's amplitude equals the gap) at {graze:.7f} rad/s. The lift-off "
        f"{located(ends[0], graze)}."
        if ends else "- end: " + meta["outcome"],
        f"- stability along the branch: {stab.count('stable')} stable points "
        f"({'all' if before else 'NOT all'} before the fold), {stab.count('unstable')} unstable, "
        f"{len(und)} undecided: the last before the lift-off, F_N <= {und_fn:.2g} N, where the "
        f"monodromy's error bound ({und_err[0]:.2g} .. {und_err[1]:.2g}) reaches the unit circle "
        "(the return map is far from linear at the differences' steps there).",
        f"- normal force against the closed-form root of its branch: at most {dev_far:.1e} "
        f"relative away from the fold (more than 5 rad/s) and N > 100 N; {dev:.1e} over all "
        "points (near the fold N depends on the speed as a square root, near the lift-off it "
        "tends to 0).",
        "",
        "![branch](branch.png) ![multipliers](multipliers.png)",
        "",
    ]
    with open(os.path.join(a.out, "branch.md"), "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))
    if not folds or abs(folds[0]["value"] / fold - 1) > 1e-6 or not before:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
