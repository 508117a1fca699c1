"""rubdyn.orbit: the same search and the same orbit.json as `rubdyn orbit` (docs/orbits.md),
the sampled period as a Result, bad input as rubdyn.CaseError."""
import csv
import json
import os

import numpy as np
import pytest

import rubdyn
from conftest import SOURCE, run_cli

FULL_RUB = os.path.join(SOURCE, "cases", "full-rub.toml")
JEFFCOTT = os.path.join(SOURCE, "cases", "jeffcott.toml")


def test_orbit_is_the_cli_orbit(cli, tmp_path):
    out = tmp_path / "o"
    p = run_cli(cli, "orbit", FULL_RUB, "--out", str(out))
    assert p.returncode == 0, p.stderr
    with open(out / "orbit.json") as f:
        from_cli = json.load(f)
    orb = rubdyn.orbit(FULL_RUB)
    assert orb.exit_code == 0 and orb.converged and orb.stability == "stable"
    # the same deterministic search: every key equal but the wall clock
    a, b = dict(orb), from_cli
    a.pop("wall_seconds")
    b.pop("wall_seconds")
    assert a == b
    # numpy views
    assert orb.multipliers.shape == (6,) and np.all(np.abs(orb.multipliers) < 1)
    assert np.all(np.abs(orb.multipliers) + orb.errors < 1)
    assert orb.monodromy.shape == (6, 6)
    # the multipliers are the matrix's eigenvalues (LAPACK here, Eigen there: to round-off)
    assert np.allclose(np.sort_complex(np.linalg.eigvals(orb.monodromy)),
                       np.sort_complex(orb.multipliers), rtol=0, atol=1e-12)
    # the sampled period: orbit.csv's rows, bit for bit
    with open(out / "orbit.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(orb.run)
    for name in ("t", "x_r", "vy_s", "F_N"):
        assert np.array_equal(np.array([float(r[name]) for r in rows]), orb.run[name])
    assert orb.state["x_r"] == orb.run["x_r"][0]


def test_orbit_from_sensitivities_is_the_cli_orbit(cli, tmp_path):
    out = tmp_path / "s"
    p = run_cli(cli, "orbit", FULL_RUB, "--out", str(out), "--monodromy", "sensitivities")
    assert p.returncode == 0, p.stderr
    with open(out / "orbit.json") as f:
        from_cli = json.load(f)
    orb = rubdyn.orbit(FULL_RUB, monodromy="sensitivities")
    a, b = dict(orb), from_cli
    a.pop("wall_seconds")
    b.pop("wall_seconds")
    assert a == b
    assert orb["monodromy"]["method"].startswith("sensitivities")
    with pytest.raises(ValueError):
        rubdyn.orbit(FULL_RUB, monodromy="adjoint")


def test_orbit_refuses_a_case_without_a_prescribed_spin():
    with pytest.raises(rubdyn.CaseError) as e:
        rubdyn.orbit(JEFFCOTT)
    assert "loads.spin" in str(e.value)
    with pytest.raises(ValueError):
        rubdyn.orbit(FULL_RUB, periods=0)
    with pytest.raises(TypeError):
        rubdyn.orbit(FULL_RUB, max_iter=1.5)


def test_orbit_that_does_not_converge_says_so():
    orb = rubdyn.orbit(FULL_RUB, tol=1e-15, max_iter=2)
    assert orb["outcome"] == "no_convergence" and orb.exit_code == 3
    assert orb.stability == "undecided"
    assert len(orb["newton"]) == 3 and len(orb.run) > 100


def assert_cli_branch(br, out):
    """The Branch is the CLI's folder `out`: branch.json but for the wall clock, and branch.csv
    column by column, bit for bit (the CLI writes shortest round-trip digits)."""
    with open(out / "branch.json") as f:
        from_cli = json.load(f)
    a, b = dict(br), from_cli
    a.pop("wall_seconds")
    b.pop("wall_seconds")
    assert a == b
    with open(out / "branch.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(br.table) == list(rows[0].keys())
    for name, col in br.table.items():
        if isinstance(col, list):
            assert col == [r[name] for r in rows], name
        else:
            assert np.array_equal(col, [float(r[name]) if r[name] else np.nan for r in rows],
                                  equal_nan=True), name


def test_branch_is_the_cli_branch(cli, tmp_path):
    """rubdyn.branch: the same continuation, branch.json and branch.csv as `rubdyn branch`."""
    out = tmp_path / "b"
    p = run_cli(cli, "branch", FULL_RUB, "--vary", "initial.omega0", "--points", "4", "--out",
                str(out))
    assert p.returncode == 0, p.stderr
    br = rubdyn.branch(FULL_RUB, "initial.omega0", points=4)
    assert br.exit_code == 0 and br["outcome"] == "max_points" and br["points"] == 4
    assert_cli_branch(br, out)
    assert br.values[0] == 1500.0 and np.all(np.diff(br.values) > 0)
    assert br.table["stability"] == ["stable"] * 4
    # bad input: the CLI's exit 2 is rubdyn.CaseError
    with pytest.raises(rubdyn.CaseError, match="vary|key"):
        rubdyn.branch(FULL_RUB, "rotor.nonsense", points=2)
    with pytest.raises(ValueError, match="branch: points"):
        rubdyn.branch(FULL_RUB, "initial.omega0", points=0)


def test_branch_resume_and_method_as_the_cli(cli, tmp_path):
    """rubdyn.branch(resume=) continues a Branch as `rubdyn branch --resume` continues its
    folder: the same points, bit for bit; monodromy="sensitivities" as --monodromy."""
    out = tmp_path / "b"
    common = ["branch", FULL_RUB, "--vary", "initial.omega0", "--monodromy", "sensitivities",
              "--out", str(out)]
    for extra in (["--points", "3"], ["--points", "6", "--resume"]):
        p = run_cli(cli, *common, *extra)
        assert p.returncode == 0, p.stderr
    first = rubdyn.branch(FULL_RUB, "initial.omega0", points=3, monodromy="sensitivities")
    br = rubdyn.branch(FULL_RUB, "initial.omega0", points=6, monodromy="sensitivities",
                       resume=first)
    assert br["monodromy"] == "sensitivities" and br["points"] == 6
    assert br["started"].startswith("resumed from its point 2")
    assert_cli_branch(br, out)
    # another case's branch, or another method: rubdyn.CaseError, as the CLI's exit 2
    with pytest.raises(rubdyn.CaseError, match="another case"):
        rubdyn.branch(FULL_RUB, "initial.omega0", points=6, monodromy="sensitivities",
                      resume=first, rtol=1e-9)
    with pytest.raises(rubdyn.CaseError, match="monodromies"):
        rubdyn.branch(FULL_RUB, "initial.omega0", points=6, resume=first)
    with pytest.raises(ValueError, match="one or the other"):
        rubdyn.branch(FULL_RUB, "initial.omega0", resume=first, switch=first)
