#!/usr/bin/python3
"""The finite-element rotors of scripts/make-fe-rotor.py: the reference scene's frequencies with
12 to 96 elements, and the committed cases (cases/fe-runup.toml, cases/fe-two-seal.toml) run
with the event solver (BDF and Adams) and Moreau-Jean, against the event solver at rtol 1e-10,
atol 1e-13 (issue 32's reference setting). Writes validation/fe/cases.md.

    validation/fe/run_cases.py [build/rubdyn] [--quick]     # about 2 minutes of CPU; --quick: 1 round

CPU seconds (user + system of the rubdyn process, reading the matrices included) are the median
of 3 rounds; the machine is shared, so compare within one table.
"""
import math
import os
import statistics
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fe_common as fc  # noqa: E402


def frequencies():
    fe = fc.load_fe()
    desc = fc.description("fe-runup")
    rows = []
    for ne in (12, 24, 48, 96):
        r = fe.build(desc, ne)
        x = np.arange(0, r.n, 2)  # the x plane (x, dx of every node): each frequency once
        w2 = np.linalg.eigvals(np.linalg.solve(r.M[np.ix_(x, x)], r.K[np.ix_(x, x)])).real
        f = np.sqrt(np.sort(w2)) / (2 * math.pi)
        rows.append((ne, r.n, f[0], f[1], f[-1]))
    return rows


SOLVERS = [  # (label, arguments)
    ("event BDF, rtol 1e-8 (the case)", []),
    ("event Adams, rtol 1e-8", ["--method", "adams", "--set", "solver.contact_method=adams"]),
    ("mj h = 1e-6", ["--solver", "mj", "--h", "1e-6"]),
    ("mj h = 1e-5", ["--solver", "mj", "--h", "1e-5"]),
]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rubdyn = os.path.abspath(args[0] if args else os.path.join(fc.ROOT, "build", "rubdyn"))
    rounds = 1 if "--quick" in sys.argv else 3
    out = os.path.join(fc.ROOT, "out", "fe-cases")
    os.makedirs(out, exist_ok=True)
    lines = ["# The finite-element rotors: frequencies and the committed cases' runs", "",
             "Written by `validation/fe/run_cases.py` (do not edit by hand). Machine: "
             + fc.machine() + f"; CPU seconds: median of {rounds} round(s).", "",
             "## The reference scene's frequencies (cases/fe-runup/rotor.toml at rest, no ring)",
             "", "Issue 32's own calculation gave about 35 and 136 Hz, and 42, 109, 244 kHz for "
             "the highest mode with 12, 24, 48 elements; ours, from cases/fe-runup/rotor.toml "
             "(the issue's shaft, disc masses and bearings; the disc inertias ours), reproduce "
             "them (validation/fe/test_fe_rotor.py checks them):", "",
             "| elements | n | f1 [Hz] | f2 [Hz] | highest [kHz] |", "|---|---|---|---|---|"]
    for ne, n, f1, f2, fmax in frequencies():
        lines.append(f"| {ne} | {n} | {f1:.3f} | {f2:.3f} | {fmax / 1e3:.2f} |")
    for name in ("fe-runup", "fe-two-seal"):
        case = os.path.join(fc.ROOT, "cases", name + ".toml")
        desc = fc.description(name)
        le = desc["shaft"]["length"] / desc["shaft"].get("elements", 12)
        nodes = [round(s["z"] / le) for s in desc["seal"]]
        ref = os.path.join(out, name + "-ref")
        cpu_ref, s_ref = fc.timed_run(rubdyn, case, ref, ["--rtol", "1e-10"])
        lines += ["", f"## cases/{name}.toml over {s_ref['t_reached']:g} s", "",
                  f"Reference: event solver, BDF, rtol 1e-10, atol 1e-13: {s_ref['steps']} steps, "
                  f"{fc.events(s_ref)}; {cpu_ref:.2f} CPU s. Errors: the largest distance of the "
                  f"seal centre{'s' if len(nodes) > 1 else ''} (node{'s' if len(nodes) > 1 else ''} "
                  f"{', '.join(map(str, nodes))}) from the reference's over the 0.1 ms output "
                  "grid, and of omega.", "",
                  "| solver | CPU s | steps | events | seal orbit error [m] | omega error [rad/s] |",
                  "|---|---|---|---|---|---|"]
        for label, a in SOLVERS:
            folder = os.path.join(out, name + "-" + label.split(",")[0].replace(" ", "_")
                                  .replace("=", ""))
            cpus = []
            for _ in range(rounds):
                cpu, s = fc.timed_run(rubdyn, case, folder, a)
                cpus.append(cpu)
            orbit, om = fc.orbit_difference(folder, ref, nodes)
            lines.append(f"| {label} | {statistics.median(cpus):.2f} | {s['steps']} | "
                         f"{fc.events(s)} | {orbit:.2e} | {om:.1e} |")
        print("\n".join(lines[-len(SOLVERS) - 6:]))
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "cases.md")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", path)


if __name__ == "__main__":
    main()
