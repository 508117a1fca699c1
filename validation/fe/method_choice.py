#!/usr/bin/python3
"""The event solver's multistep method chosen by the model (solver.method = "auto",
include/rubdyn/hybrid/method_choice.hpp): the stiffness ratio of models from the paper's rigid
rotor to the 52-coordinate finite-element shaft, and the cost and error of both families on each,
so that the threshold (kStiffRatio = 100, our calibration) is seen to choose the cheaper one.
Writes validation/fe/method_choice.md.

    validation/fe/method_choice.py [build/rubdyn] [--quick]    # about 3 minutes of CPU

Every model runs its own scene with Adams (free flight and contact phases) and with BDF, at the
same tolerances, and against the same model with BDF at a hundredth of that rtol, at most 1e-10
(errors: the largest
distance of the contact node's centre over the output grid). CPU seconds (user + system of the
rubdyn process) are the median of 3 rounds (1 with --quick); the machine is shared, so compare
within one row.
"""
import os
import re
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fe_common as fc  # noqa: E402

ADAMS = ["--method", "adams", "--set", "solver.contact_method=adams"]
BDF = ["--method", "bdf", "--set", "solver.contact_method=bdf"]


def models():
    """(label, case, extra arguments, the contact node's (x, y) column names, rtol, t_end)."""
    fe = os.path.join(fc.ROOT, "cases", "fe-runup.toml")
    seal = ("x6", "y6")
    cb = lambda m: ["--set", "reduction.method=craig-bampton", "--set", f"reduction.modes={m}"]
    rigid = ("x_r", "y_r")
    yield ("reference case (rigid rotor, 500 ms)", os.path.join(fc.ROOT, "cases", "reference.toml"),
           ["--t-end", "0.5"], rigid, "1e-10")
    yield ("Jeffcott-Black (cases/jeffcott.toml)", os.path.join(fc.ROOT, "cases", "jeffcott.toml"),
           [], ("x_r", "y_r"), "1e-10")
    for m in (4, 8, 12, 20, 30):
        yield (f"fe-runup, Craig-Bampton {m} modes", fe, cb(m), seal, "1e-8")
    yield ("fe-runup, full (n = 52)", fe, [], seal, "1e-8")
    out = os.path.join(fc.ROOT, "out", "method-choice")
    desc = os.path.join(fc.ROOT, "cases", "fe-runup", "rotor.toml")
    fe24 = fc.make_case(desc, 24, os.path.join(out, "fe-runup-24.toml"), os.path.join(out, "m24"),
                        "fe-runup-24")
    yield ("fe-runup, 24 elements (n = 100)", fe24, [], ("x12", "y12"), "1e-8")


def ratio(summary):
    m = re.search(r"ratio ([0-9.e+-]+)", summary["options"].get("stiffness", ""))
    return float(m.group(1)) if m else float("nan")


def chosen(summary):
    return summary["options"]["free_flight"]


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rubdyn = os.path.abspath(args[0] if args else os.path.join(fc.ROOT, "build", "rubdyn"))
    rounds = 1 if "--quick" in sys.argv else 3
    out = os.path.join(fc.ROOT, "out", "method-choice")
    os.makedirs(out, exist_ok=True)
    lines = ["# The event solver's method chosen by the model's stiffness", "",
             "Written by `validation/fe/method_choice.py` (do not edit by hand). Machine: "
             + fc.machine() + f"; CPU seconds: median of {rounds} round(s).", "",
             "`solver.method = \"auto\"` (the default) integrates a model by BDF when the ratio of "
             "its fastest time scale to its slowest frequency exceeds 100 "
             "(include/rubdyn/hybrid/method_choice.hpp; the threshold is our calibration, this "
             "table its evidence), by Adams otherwise. Each model runs its scene with both "
             "families at the case's tolerances; errors are the largest distance of the contact "
             "node's centre from the same model's BDF run at a hundredth of the row's rtol (at most "
             "1e-10) over the output grid "
             "(the rigid rotor: its disc centre).", "",
             "| model | ratio | auto chooses | Adams CPU s | Adams steps | Adams error [m] | "
             "BDF CPU s | BDF steps | BDF error [m] | cheaper |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    wrong = []
    for label, case, extra, cols, rtol in models():
        tag = re.sub(r"[^A-Za-z0-9]+", "_", label).strip("_")
        ref = os.path.join(out, tag + "-ref")
        # the reference: BDF at a hundredth of the row's rtol (at most 1e-10)
        ref_rtol = "%g" % min(1e-10, float(rtol) / 100)
        fc.timed_run(rubdyn, case, ref, extra + BDF + ["--rtol", ref_rtol])
        row = {}
        for fam, a in (("adams", ADAMS), ("bdf", BDF)):
            folder = os.path.join(out, f"{tag}-{fam}")
            cpus = []
            for _ in range(rounds):
                cpu, s = fc.timed_run(rubdyn, case, folder, extra + a + ["--rtol", rtol])
                cpus.append(cpu)
            err = fc.node_difference(folder, ref, cols)
            row[fam] = (statistics.median(cpus), s["steps"], err)
        _, s_auto = fc.timed_run(rubdyn, case, os.path.join(out, tag + "-auto"), extra)
        cheaper = min(row, key=lambda k: row[k][0])
        if chosen(s_auto) != cheaper:
            wrong.append(label)
        a, b = row["adams"], row["bdf"]
        lines.append(f"| {label} | {ratio(s_auto):.3g} | {chosen(s_auto)} | {a[0]:.2f} | {a[1]} | "
                     f"{a[2]:.1e} | {b[0]:.2f} | {b[1]} | {b[2]:.1e} | {cheaper} "
                     f"({max(a[0], b[0]) / max(min(a[0], b[0]), 1e-9):.2f}x) |")
        print(lines[-1], flush=True)
    lines += ["", "The choice is the cheaper family on every model." if not wrong else
              "Models where the other family was cheaper on this machine: " + ", ".join(wrong)
              + " (see their CPU ratio: near 1, the choice costs little either way)."]
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "method_choice.md")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", path)


if __name__ == "__main__":
    main()
