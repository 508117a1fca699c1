#!/usr/bin/python3
"""Modal reduction ([reduction], docs/fe-rotors.md section 8) against the full model on issue 32's
run-up scene with 48 elements (n = 196): the seal orbit's and the spin's difference against the
number of modes kept, and the CPU time gained. Writes validation/fe/reduction.md.

    validation/fe/reduction.py [build/rubdyn] [--quick]    # about 2 minutes of CPU

Scenes: (A) cases/fe-runup.toml's run-up as committed (prescribed spin: the spin's difference is
that of the torque holding it, drive_torque); (B) the same rotor with the spin free, driven by
a constant torque of 362 N m (fe-two-seal's), where omega is an unknown, its contact phases
integrated by BDF (solver.contact_method, as in cases/fe-two-seal.toml), every model's in
minimal coordinates (solver.contact_phases = "auto"; their Newton systems banded for the full
model, dense for the reduced ones: docs/fe-rotors.md section 10). Both over 0.2 s, the event solver
with BDF at rtol 1e-8, atol 1e-13 (the cases' setting) for every model. The scale of the
integration error, below which a reduction's difference is not the reduction's: the
Craig-Bampton model with 20 modes at rtol 1e-10 against rtol 1e-8 (at 12 elements the full
model's rtol 1e-8 and 1e-10 runs differ by 7e-12 m, validation/fe/cases.md). CPU seconds: user +
system of the rubdyn process (reading the matrices and reducing included), and the run's own
wall time (summary.json's wall_seconds: the integration and its output, without the process's
set-up), each the median of 3 rounds (1 with --quick), every model writing the same columns
(output.coordinates = "contacts": the seal, the ring, the spin; the reduced models' default,
every coordinate below 64 of them, would write 58 columns against the full model's 18).
"""
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fe_common as fc  # noqa: E402

ELEMENTS = 48
SEAL = 24  # node of the mid-span seal with 48 elements
CB_MODES = [4, 8, 12, 16, 20, 30, 40, 60]
MODAL_MODES = [8, 12, 20, 30, 40, 60]
TARGET = ("craig-bampton", 20)  # issue 32: 1e-6 m at least 20x faster


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rubdyn = os.path.abspath(args[0] if args else os.path.join(fc.ROOT, "build", "rubdyn"))
    rounds = 1 if "--quick" in sys.argv else 3
    out = os.path.join(fc.ROOT, "out", "fe-reduction")
    os.makedirs(out, exist_ok=True)
    desc = os.path.join(fc.ROOT, "cases", "fe-runup", "rotor.toml")
    case_a = fc.make_case(desc, ELEMENTS, os.path.join(out, "fe-runup-48.toml"),
                          os.path.join(out, "m48"), "fe-runup-48")
    # scene B: the generated case with the prescribed run-up replaced by a constant torque
    with open(case_a) as f:
        text = f.read()
    # every model by BDF, the reduced ones too (the method the full model's stiffness chooses;
    # left to the models, the smallest reductions would be integrated by Adams)
    solver = '[solver]\nkind = "event"\n'
    assert solver in text
    text = text.replace(solver, solver + 'method = "bdf"\ncontact_method = "bdf"\n')
    with open(case_a, "w") as f:
        f.write(text)
    prescribed = 'spin = "prescribed"\nspin_accel = 1000.0\n'
    assert prescribed in text
    case_b = os.path.join(out, "fe-runup-48-torque.toml")
    with open(case_b, "w") as f:
        # (its contact phases by BDF too: with Adams there, the shaft's stiff modes cost hours
        # of CPU on the full model)
        f.write(text.replace(prescribed, "torque = 362.0\n")
                .replace('name = "fe-runup-48"', 'name = "fe-runup-48-torque"'))

    lines = ["# Modal reduction against the full model: issue 32's run-up, 48 elements (n = 196)",
             "", "Written by `validation/fe/reduction.py` (do not edit by hand). Machine: "
             + fc.machine() + f"; CPU seconds and the run's own seconds: median of "
             f"{rounds} round(s); every model writes the contacts' columns "
             "(`output.coordinates = \"contacts\"`).", "",
             "The rotor of cases/fe-runup/rotor.toml with 48 elements "
             f"(`scripts/make-fe-rotor.py cases/fe-runup/rotor.toml --elements {ELEMENTS}`), "
             "over 0.2 s, event solver, BDF, rtol 1e-8, atol 1e-13 for every model. Differences "
             f"against the full model: the largest distance of the seal centre (x{SEAL}, "
             f"y{SEAL}) over the 0.1 ms output grid, and of the spin's quantity. m: the reduced "
             "model's coordinates (2 physical: the seal's x, y). Highest kept: the highest "
             "kept mode (fixed-interface for Craig-Bampton: the seal held; free for modal)."]
    same_columns = ["--set", "output.coordinates=contacts"]

    def measured(case, folder, sets):
        """(median CPU s, median wall_seconds, summary) over the rounds."""
        cpus, walls = [], []
        for _ in range(rounds):
            cpu, s = fc.timed_run(rubdyn, case, folder, sets + same_columns)
            cpus.append(cpu)
            walls.append(s["wall_seconds"])
        return statistics.median(cpus), statistics.median(walls), s

    verdict = []
    for scene, case, column, unit in (
            ("A: prescribed run-up, 100 rad/s + 1000 rad/s^2 t (cases/fe-runup.toml)", case_a,
             "drive_torque", "N m"),
            ("B: the spin free, driven by 362 N m from 100 rad/s", case_b, "omega", "rad/s")):
        tag = "A" if case == case_a else "B"
        full = os.path.join(out, tag + "-full")
        cpu_full, wall_full, s_full = measured(case, full, [])
        lines += ["", f"## Scene {scene}", "",
                  f"Full model (n = 196): {cpu_full:.2f} CPU s (the run's own {wall_full:.3f} s), "
                  f"{s_full['steps']} steps, {fc.events(s_full)}."]
        # the integration error's scale: the CB-20 model at rtol 1e-10 against 1e-8
        a = os.path.join(out, tag + "-cb20-1e-8")
        b = os.path.join(out, tag + "-cb20-1e-10")
        cb20 = ["--set", "reduction.method=craig-bampton", "--set", "reduction.modes=20"]
        fc.timed_run(rubdyn, case, a, cb20 + same_columns)
        fc.timed_run(rubdyn, case, b, cb20 + same_columns + ["--rtol", "1e-10"])
        o, c = fc.orbit_difference(a, b, [SEAL], column=column)
        lines[-1] += (f" Integration error's scale: Craig-Bampton with 20 modes at rtol 1e-10 "
                      f"against 1e-8, {o:.2e} m and {c:.1e} {unit}.")
        lines += ["", f"| method | modes | m | highest kept [Hz] | CPU s | speed-up | run's own s "
                  f"| speed-up | steps | events | seal orbit difference [m] | {column} difference "
                  f"[{unit}] |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for method, modes_list in (("craig-bampton", CB_MODES), ("modal", MODAL_MODES)):
            for modes in modes_list:
                folder = os.path.join(out, f"{tag}-{method}-{modes}")
                sets = ["--set", f"reduction.method={method}", "--set", f"reduction.modes={modes}"]
                cpu, wall, s = measured(case, folder, sets)

                with open(os.path.join(folder, "reduction.json")) as f:
                    red = json.load(f)
                o, c = fc.orbit_difference(folder, full, [SEAL], column=column)
                lines.append(f"| {method} | {modes} | {red['reduced_size']} | "
                             f"{red['modes_hz'][-1]:.0f} | {cpu:.3f} | {cpu_full / cpu:.1f}x | "
                             f"{wall:.3f} | {wall_full / wall:.1f}x | "
                             f"{s['steps']} | {fc.events(s)} | {o:.2e} | {c:.2e} |")
                if (method, modes) == TARGET:
                    verdict.append((tag, o, cpu_full / cpu, wall_full / wall))
                print(lines[-1], flush=True)
    lines += ["", "## Issue 32's target", "",
              "A Craig-Bampton model of the 196-coordinate rotor with 20 modes reproduces the "
              "full model's seal orbit to 1e-6 m over the run-up at least 20x faster:", ""]
    for tag, o, speed, run_speed in verdict:
        ok = o <= 1e-6 and speed >= 20
        lines.append(f"- scene {tag}: {o:.2e} m, {speed:.1f}x faster in CPU time "
                     f"({run_speed:.1f}x in the run's own time): {'met' if ok else 'NOT met'}")
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "reduction.md")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", path)


if __name__ == "__main__":
    main()
