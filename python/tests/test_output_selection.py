"""output.coordinates from Python (issue 32, item 6): rubdyn.run returns the columns the case
writes, as the CLI's files hold them; rubdyn.read reads a folder with a selection; the analysis
of either is the analysis of the run that wrote every coordinate (it reads the contacts' and the
spin's coordinates only)."""
import os

import numpy as np

import rubdyn
from conftest import SOURCE, run_cli

FE = os.path.join(SOURCE, "cases", "fe-runup.toml")
# 0.12 s of the run-up: the first impact (about 0.107 s) and contact after it
SELECT = ["run.t_end=0.12", "output.coordinates=x3, contacts"]


def test_run_returns_the_selected_columns_with_the_same_values():
    whole = rubdyn.run(rubdyn.load_case(FE, ["run.t_end=0.12"]))
    part_case = rubdyn.load_case(FE, SELECT)
    part = rubdyn.run(part_case)
    names = list(part.columns.keys())
    assert names == part_case.columns
    assert "x3" in names and "x6" in names and "x2" not in names and "vx2" not in names
    assert len(whole.columns) == len(names) + 2 * 49  # 52 coordinates, 3 written: 49 not
    for name in names:
        assert np.array_equal(part[name], whole[name]), name  # the same bits
    a, b = rubdyn.analyze(whole), rubdyn.analyze(part)
    assert repr(a.verdicts) == repr(b.verdicts)  # (repr: a NaN verdict equals itself)
    assert a.derived.keys() == b.derived.keys()
    for k in a.derived:
        x, y = np.asarray(a.derived[k]), np.asarray(b.derived[k])
        assert x.dtype == y.dtype and x.shape == y.shape, k
        assert (np.array_equal(x, y, equal_nan=True) if x.dtype.kind == "f"
                else np.array_equal(x, y)), k


def test_read_a_folder_with_a_selection(cli, tmp_path):
    out = tmp_path / "sel"
    p = run_cli(cli, "run", FE, "--quiet", "--out", str(out),
                *sum((["--set", s] for s in SELECT), []))
    assert p.returncode == 0, p.stderr
    res = rubdyn.read(str(out))
    mem = rubdyn.run(rubdyn.load_case(FE, SELECT))
    assert list(res.columns.keys()) == list(mem.columns.keys())
    for name in res.columns:
        assert np.array_equal(res[name], mem[name]), name
    assert os.path.exists(out / "state.csv")
