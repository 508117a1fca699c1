#!/usr/bin/python3
"""`rubdyn orbit` against the closed form of the unbalance's forward synchronous full annular rub
at a prescribed speed (docs/closed-forms.md, section 5; docs/orbits.md): both roots, rigid and
sprung ring, at the case default rtol 1e-10 and at 1e-12. The reference multipliers are
exp(lambda T) of the eigenvalues of the orbit's equilibrium in the rotating frame, from the
independent contact-phase simulation validation/analytic/reference_sim.py (its own equations,
linearised by central differences), not from rubdyn. Writes validation/orbits/table.md.

    validation/orbits/run.py [--cli build/rubdyn]      # about 2 s
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "validation", "analytic"))
sys.path.insert(0, os.path.join(ROOT, "validation"))
import closed_forms as cf  # noqa: E402
import reference_sim as rs  # noqa: E402
import rubdyn_runs as rr  # noqa: E402
from common import machine  # noqa: E402
from test_closed_forms import BLACK_ROLL, K_direct, OMEGA_U, UNB, UNB_SPRUNG  # noqa: E402


def orbit(cli, case, sets, out, rtol, atol, extra=()):
    cmd = [cli, "orbit", case, "--out", out, "--rtol", repr(rtol), "--atol", repr(atol), *extra]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in (0, 3):
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    with open(os.path.join(out, "orbit.json")) as f:
        return json.load(f), p.returncode


def reference_multipliers(P, root, T):
    m = rs.JeffcottBlack(P)
    zs = root["z_s"]
    xi = [root["delta"], OMEGA_U] + ([] if m.rigid else [zs.real, zs.imag,
                                                          (1j * OMEGA_U * zs).real,
                                                          (1j * OMEGA_U * zs).imag])
    ev, _ = rs.orbit_eigenvalues(m, "slip-", xi)
    return ev, np.exp(ev * T)


def compare(d, ref):
    """The largest distance of orbit.json's multipliers to the nearest reference, the largest
    error bound and their largest ratio."""
    mus = np.array([complex(m["re"], m["im"]) for m in d["multipliers"]])
    errs = np.array([m["error"] for m in d["multipliers"]])
    dist = np.array([np.min(np.abs(ref - mu)) for mu in mus])
    return float(np.max(dist)), float(np.max(errs)), float(np.max(dist / errs))


SENS = ["--monodromy", "sensitivities"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "rubdyn"))
    ap.add_argument("--out", default=os.path.join(HERE, "table.md"))
    a = ap.parse_args()
    T = 2 * math.pi / OMEGA_U
    rows = []
    worst_ratio = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for label, P in (("rigid", UNB), ("sprung", UNB_SPRUNG)):
            case = rr.write_case(tmp, P, "unb_" + label)
            roots = cf.unbalance_full_rub_roots(P, OMEGA_U)["roots"]
            for which, root in zip(("larger", "smaller"), roots):
                keys = cf.unbalance_orbit_state(P, OMEGA_U, root)
                sets = rr.initial_sets(keys)
                exact = np.array([keys[k] for k in ("initial.x_r", "initial.y_r")])
                ev, ref = reference_multipliers(P, root, T)
                expected = "stable" if max(ev.real) < 0 else "unstable"
                for rtol, atol in ((1e-10, 1e-12), (1e-12, 1e-15)):
                    out = os.path.join(tmp, f"{label}_{which}_{rtol:g}")
                    d, rc = orbit(a.cli, case, sets, out, rtol, atol)
                    # the computed map's noise floor: Newton pushed below it (8 iterations)
                    f, _ = orbit(a.cli, case, sets, out + "_floor", rtol, atol,
                                 ["--tol", "1e-15", "--max-iter", "8"])
                    floor = min(h["residual"] for h in f["newton"])
                    mus = np.array([complex(m["re"], m["im"]) for m in d["multipliers"]])
                    errs = np.array([m["error"] for m in d["multipliers"]])
                    dist = np.array([np.min(np.abs(ref - mu)) for mu in mus])
                    ratio = float(np.max(dist / errs))
                    worst_ratio = max(worst_ratio, ratio)
                    g0 = P["stator.gap"]
                    x0 = np.array([d["state"]["x_r"], d["state"]["y_r"]])
                    rows.append([
                        label, which, f"{root['N']:.3f}", f"{rtol:g}", d["outcome"],
                        str(len(d["newton"]) - 1), f"{d['residual']:.1e}", f"{floor:.1e}",
                        f"{np.max(np.abs(x0 - exact)) / g0:.1e}",
                        f"{np.max(np.abs(mus)):.6f}", f"{np.max(dist):.1e}",
                        f"{np.max(errs):.1e}", f"{ratio:.2f}", d["stability"], expected,
                        str(d["runs"]), f"{d['wall_seconds']:.3f}"])
                    # the same orbit, its monodromy from the flow's sensitivities
                    sd, _ = orbit(a.cli, case, sets, out + "_sens", rtol, atol, SENS)
                    sdist, serr, sratio = compare(sd, ref)
                    worst_ratio = max(worst_ratio, sratio)
                    rows[-1] += [f"{sdist:.1e}", f"{serr:.1e}", f"{sratio:.2f}",
                                 sd["stability"]]
                    if d["stability"] != expected or sd["stability"] != expected:
                        print(f"MISMATCH {label} {which} rtol {rtol}: {d['stability']}, "
                              f"{sd['stability']} != {expected}", file=sys.stderr)
        # Black's rolling orbits (closed-forms.md 3.3, both branches): autonomous orbits from a
        # period guess 1 % off; the reference: exp(lambda T) of reference_sim's stick-phase
        # eigenvalues, and the trivial multiplier 1
        P = dict(BLACK_ROLL, **{"loads.unbalance": 0.0})  # cases/jeffcott.toml has one
        case_b = rr.write_case(tmp, P, "black_roll")
        m = rs.JeffcottBlack(P)
        black = []
        roots = [r for r in cf.black_rolling_roots(P) if r["contact"] and r["stick"]]
        for which, root in zip(("low", "high"), roots):
            keys = cf.contact_orbit_state(P, root["w"], root["Omega"])
            zs = complex(keys["initial.x_s"], keys["initial.y_s"])
            w = root["w"]
            ev, _ = rs.orbit_eigenvalues(m, "stick", [root["Omega"], zs.real, zs.imag,
                                                      (1j * w * zs).real, (1j * w * zs).imag])
            Tw = 2 * math.pi / abs(w)
            ref = np.append(np.exp(ev * Tw), 1.0)
            for rtol, atol in ((1e-10, 1e-12), (1e-12, 1e-15)):
                out = os.path.join(tmp, f"black_{which}_{rtol:g}")
                d, rc = orbit(a.cli, case_b, rr.initial_sets(keys), out, rtol, atol,
                              ["--period", repr(1.01 * Tw)])
                mus = np.array([complex(x["re"], x["im"]) for x in d["multipliers"]])
                errs = np.array([x["error"] for x in d["multipliers"]])
                dist = np.array([np.min(np.abs(ref - mu)) for mu in mus])
                ratio = float(np.max(dist / errs))
                worst_ratio = max(worst_ratio, ratio)
                triv = d["trivial_multiplier"]
                sd, _ = orbit(a.cli, case_b, rr.initial_sets(keys), out + "_sens", rtol, atol,
                              ["--period", repr(1.01 * Tw)] + SENS)
                sdist, serr, sratio = compare(sd, ref)
                worst_ratio = max(worst_ratio, sratio)
                black.append([which, f"{w:.3f}", f"{rtol:g}", d["outcome"],
                              str(len(d["newton"]) - 1), f"{d['period'] / Tw - 1:.1e}",
                              f"{abs(mus[triv['index']] - 1):.1e}",
                              f"{errs[triv['index']]:.1e}", str(triv["is_one"]).lower(),
                              f"{np.max(dist):.1e}", f"{ratio:.2f}", d["stability"],
                              "stable" if max(ev.real) < 0 else "unstable", str(d["runs"]),
                              f"{sdist:.1e}", f"{serr:.1e}", f"{sratio:.2f}", sd["stability"]])
                if (d["stability"] != black[-1][12] or sd["stability"] != black[-1][12]
                        or not triv["is_one"]):
                    print(f"MISMATCH black {which} rtol {rtol}", file=sys.stderr)
                    worst_ratio = max(worst_ratio, 2.0)
        # the low rolling orbit continued down in the torque (an autonomous branch): its end,
        # where the stick breaks, against the closed form's slip onset: |F_T| = tau / R reaches
        # mu F_N, F_N = g0 |Re K(w)|, i.e. -Im K(w) = mu |Re K(w)|, tau = -R g0 Im K(w)
        low = roots[0]
        keys = cf.contact_orbit_state(P, low["w"], low["Omega"])
        Tw = 2 * math.pi / abs(low["w"])
        bfolder = os.path.join(tmp, "black_branch")
        cmd = [a.cli, "branch", case_b, "--vary", "loads.torque", "--period", repr(1.01 * Tw),
               "--points", "40", "--down", "--out", bfolder]
        for x in rr.initial_sets(keys):
            cmd += ["--set", x]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode not in (0, 3):
            raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
        with open(os.path.join(bfolder, "branch.json")) as f:
            bj = json.load(f)
        R, g0b, mu = P["rotor.radius"], P["stator.gap"], P["contact.mu"]
        h = lambda w: -K_direct(P, w).imag - mu * abs(K_direct(P, w).real)  # noqa: E731
        w = low["w"]
        for _ in range(60):
            dq = 1e-7 * abs(w)
            w -= h(w) / ((h(w + dq) - h(w - dq)) / (2 * dq))
        tau_c = -R * g0b * K_direct(P, w).imag
        end = bj["specials"][-1] if bj["specials"] else None
        slip_ok = (end is not None and "slip onset" in end["how"]
                   and abs(end["value"] - tau_c) <= end["spread"] + 1e-4)
        if not slip_ok:
            print(f"MISMATCH black branch end: {end} against {tau_c}", file=sys.stderr)
            worst_ratio = max(worst_ratio, 2.0)
        # a start off the orbit: cases/full-rub.toml (the sprung ring's larger root) with x_r
        # moved 0.57 g0 inwards (a free start, an impact, then sliding)
        full = os.path.join(ROOT, "cases", "full-rub.toml")
        off, _ = orbit(a.cli, full, ["initial.x_r=0.0003"], os.path.join(tmp, "off"), 1e-10,
                       1e-12)
    head = ["ring", "root", "N [N]", "rtol", "outcome", "Newton it.", "residual",
            "residual floor",
            "abs(x_r - closed form) / g0", "max abs(mu)", "max abs(mu - exp(lambda T))",
            "max error bound", "distance / bound", "verdict", "expected", "runs", "wall [s]",
            "sens.: max abs(mu - exp(lambda T))", "sens.: max error bound",
            "sens.: distance / bound", "sens.: verdict"]
    lines = [
        "# rubdyn orbit against the closed form of the full annular rub",
        "",
        "Generated by `validation/orbits/run.py` (docs/orbits.md). The unbalance's forward "
        "synchronous full annular rub at a prescribed 1500 rad/s (docs/closed-forms.md section 5, "
        "the sets UNB and UNB_SPRUNG of validation/analytic/test_closed_forms.py), each root "
        "started from its closed-form state (`unbalance_orbit_state`). The reference multipliers "
        "are exp(lambda T) of the eigenvalues of the orbit in the rotating frame from the "
        "independent simulation `validation/analytic/reference_sim.py` (`orbit_eigenvalues`); "
        "each rubdyn multiplier is matched to the nearest. `distance / bound` <= 1 means the "
        "reported error bound covers the true error. The columns `sens.` are the same orbit "
        "with `--monodromy sensitivities` (the variational equations and saltation matrices, "
        "docs/orbits.md section 7) instead of finite differences. Expected verdict: stable iff every "
        "eigenvalue has a negative real part. Machine: " + machine() + ".",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    lines += ["", f"Largest distance / bound (both tables): {worst_ratio:.2f}. `residual floor`: the "
              "smallest residual Newton reaches with --tol 1e-15 in 8 iterations, i.e. the "
              "computed map's noise (the default tol, 1e-8, must lie above it).", ""]
    bhead = ["branch", "w [rad/s]", "rtol", "outcome", "Newton it.", "period / (2 pi / abs(w)) - 1",
             "abs(trivial - 1)", "its error bound", "trivial is 1", "max abs(mu - exp(lambda T))",
             "distance / bound", "verdict", "expected", "runs",
             "sens.: max abs(mu - exp(lambda T))", "sens.: max error bound",
             "sens.: distance / bound", "sens.: verdict"]
    lines += [
        "Black's rolling orbits (docs/closed-forms.md 3.3, the set BLACK_ROLL, both branches of "
        "the bistable sprung stator under a torque of 40 N m) as autonomous orbits: "
        "`rubdyn orbit CASE --period T0` from the closed-form state with T0 1 % above the whirl "
        "period 2 pi / abs(w); the reference multipliers are exp(lambda T) of reference_sim's "
        "stick-phase eigenvalues (`orbit_eigenvalues(m, \"stick\", ...)`) and the trivial 1.",
        "",
        "| " + " | ".join(bhead) + " |",
        "|" + "---|" * len(bhead),
    ]
    lines += ["| " + " | ".join(r) + " |" for r in black]
    lines += [""]
    lines += [
        "Black's low rolling orbit continued down in the torque as a branch of autonomous "
        "orbits (`rubdyn branch CASE --vary loads.torque --period T0 --down`, docs/orbits.md "
        f"section 10): {bj['points']} points, outcome `{bj['outcome']}`; the stick breaks into "
        f"slip at {end['value']:.7f} N m (located from the friction cone's margin, estimates "
        f"{end['spread']:.1e} apart) against the closed form's {tau_c:.7f} N m "
        "(-Im K(w) = mu |Re K(w)|): "
        f"{abs(end['value'] - tau_c):.1e} N m apart.", ""]
    its = [h["jacobian"] for h in off["newton"]]
    lines += [
        "A start off the orbit: `rubdyn orbit cases/full-rub.toml --set initial.x_r=0.0003` "
        "(x_r moved 0.57 g0 inwards: a free start, an impact, then sliding): "
        f"{off['outcome']}, {its.count('fixed point (the phases at t0 and t0 + T differ)')} "
        f"fixed-point step(s) and {len(its) - 1 - its.count('fixed point (the phases at t0 and t0 + T differ)')} "
        f"Newton iteration(s), {off['runs']} runs, verdict {off['stability']}.", ""]
    with open(a.out, "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))
    if worst_ratio > 1 or any(r[13] != r[14] or r[20] != r[14] for r in rows):
        raise SystemExit(1)


if __name__ == "__main__":
    main()
