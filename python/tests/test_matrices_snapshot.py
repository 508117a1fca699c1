"""A matrices case in Python is a snapshot of its matrix files, and a run folder of it stands
alone (issue 34): editing M.npy after load_case changes no run of the case (nor of the cases
made from it with more overrides), and rubdyn.read reads a folder whose original matrix files
are gone (the run's copies beside case.resolved.toml)."""
import os
import shutil

import numpy as np

import rubdyn
from conftest import SOURCE


def _copy_case(tmp_path):
    shutil.copytree(os.path.join(SOURCE, "cases", "matrices-paper"), tmp_path / "matrices-paper")
    shutil.copy(os.path.join(SOURCE, "cases", "matrices-paper.toml"), tmp_path)
    return tmp_path / "matrices-paper.toml"


def test_case_is_a_snapshot_of_its_matrix_files(tmp_path):
    path = _copy_case(tmp_path)
    case = rubdyn.load_case(str(path))
    before = rubdyn.run(case, t_end=0.01)
    # a heavier rotor on disk (still a mass matrix), after the case was loaded
    m = tmp_path / "matrices-paper" / "M.npy"
    np.save(m, 1.5 * np.load(m))
    after = rubdyn.run(case, t_end=0.01)
    for name in before.keys():
        assert np.array_equal(before[name], after[name]), name
    # and a case made from it with more overrides (the snapshot shared)
    other = rubdyn.run(case, t_end=0.01, overrides={"contact.mu": 0.1})
    assert np.array_equal(other["x_r"], before["x_r"])
    # a case loaded now reads the new file: another motion
    fresh = rubdyn.run(rubdyn.load_case(str(path)), t_end=0.01)
    assert not np.array_equal(fresh["x_r"], before["x_r"])


def test_read_a_moved_folder_without_its_matrix_files(cli, tmp_path):
    path = _copy_case(tmp_path / "src")
    out = tmp_path / "out"
    import subprocess
    p = subprocess.run([cli, "run", str(path), "--t-end", "0.01", "--out", str(out), "--quiet"],
                       capture_output=True, text=True, check=False)
    assert p.returncode == 0, p.stderr
    ref = rubdyn.read(str(out))
    shutil.rmtree(tmp_path / "src")
    moved = tmp_path / "elsewhere"
    shutil.move(str(out), str(moved))
    res = rubdyn.read(str(moved))
    assert np.array_equal(res["x_r"], ref["x_r"])
    assert res.case.kind == "matrices"
    assert rubdyn.analyze(res).verdicts["events"] == len(res.events)
