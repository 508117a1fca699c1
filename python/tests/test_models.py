"""The models of the registry, seen from Python (rubdyn.Model), against their equations written
independently: the Jeffcott-Black rotor against validation/analytic/reference_sim.py and the
rigid rotor with an unbalance against validation/analytic's transcription of docs/models.md
(both checked there against Lagrange's equations of T and V by complex-step derivatives)."""
import math
import os
import shutil
import sys

import numpy as np
import pytest

import rubdyn
from conftest import SOURCE, run_cli

sys.path.insert(0, os.path.join(SOURCE, "validation", "analytic"))
import reference_sim as rs  # noqa: E402
from test_closed_forms import rigid_rotor_M_f  # noqa: E402

EPS = np.finfo(float).eps


def case_from_keys(keys, kind):
    """A case of `kind` from {"section.key": value}, with the run keys every case needs."""
    sections = {}
    for k, v in keys.items():
        sec, key = k.split(".")
        sections.setdefault(sec, {})[key] = v
    sections.setdefault("run", {}).update({"t_end": 0.01, "omega_lim": 2000.0})
    lines = [f'[model]\nkind = "{kind}"']
    for sec, kv in sections.items():
        lines.append(f"[{sec}]")
        for key, v in kv.items():
            if isinstance(v, bool):
                lines.append(f"{key} = {'true' if v else 'false'}")
            elif isinstance(v, str):
                lines.append(f'{key} = "{v}"')
            else:
                lines.append(f"{key} = {v!r}")
    return rubdyn.parse_case("\n".join(lines), source=f"<{kind}>")


JEFFCOTT = {"rotor.mass": 5.0, "rotor.k": 5e6, "rotor.c": 600.0, "rotor.Jp": 0.01,
            "rotor.radius": 0.05, "stator.mass": 2.0, "stator.k": 2e7, "stator.c": 400.0,
            "stator.gap": 5e-4, "contact.mu": 0.3, "loads.torque": 40.0,
            "loads.gravity": 9.81, "loads.unbalance": 3e-3, "loads.unbalance_phase": 0.7,
            "loads.torque_law": "linear", "loads.torque_free_speed": 300.0}


@pytest.mark.parametrize("rigid", [False, True])
def test_jeffcott_model_is_the_independent_one(rigid):
    keys = dict(JEFFCOTT, **{"stator.rigid": rigid})
    if rigid:
        for k in ("stator.mass", "stator.k", "stator.c"):
            del keys[k]
    model = rubdyn.Model(case_from_keys(keys, "jeffcott"))
    ref = rs.JeffcottBlack(keys)
    assert model.num_dofs == ref.n == (3 if rigid else 5)
    assert model.position_names == ["x_r", "y_r", "theta"] + ([] if rigid else ["x_s", "y_s"])
    rng = np.random.default_rng(5)
    for _ in range(20):
        q = rng.normal(size=ref.n) * [2e-4, 2e-4, 3.0, 1e-5, 1e-5][:ref.n]
        v = rng.normal(size=ref.n) * [1.0, 1.0, 200.0, 0.1, 0.1][:ref.n]
        # the same formulas evaluated in another order: rounding, a few ulps of the largest term
        M = model.mass_matrix(q)
        assert np.max(np.abs(M - ref.mass_matrix(q))) <= 4 * EPS * np.max(np.abs(M))
        f = model.smooth_forces(0.0, q, v)
        scale = max(np.max(np.abs(f)), keys["rotor.k"] * 2e-4)
        assert np.max(np.abs(f - ref.smooth_forces(0.0, q, v))) <= 1e-13 * scale
        k = model.contact(q, v)
        d_N, WN, WT, vN, vt = ref.contact(q, v)
        assert abs(k["d_N"] - d_N) <= 4 * EPS * keys["stator.gap"]
        assert np.max(np.abs(k["W_N"] - WN)) <= 4 * EPS and np.max(np.abs(k["W_T"] - WT)) <= 4 * EPS
        assert abs(k["v_N"] - vN) <= 1e-14 and abs(k["v_t"] - vt) <= 1e-13  # |v_t| ~ R omega ~ 10
        E = model.kinetic_energy(q, v) + model.potential_energy(q)
        assert abs(E - ref.energy(q, v)) <= 1e-13 * max(abs(E), 1.0)


def test_rigid_rotor_with_unbalance_is_the_transcription():
    keys = {"rotor.mass": 5.0, "rotor.Jd": 0.035, "rotor.Jp": 0.06, "rotor.L": 0.5,
            "rotor.delta": 0.1, "rotor.d": 0.3, "rotor.radius": 0.05, "bearing.k": 5e6,
            "bearing.c": 300.0, "stator.mass": 2.0, "stator.k": 2e6, "stator.c": 100.0,
            "stator.gap": 2e-4, "contact.mu": 0.1, "loads.gravity": 9.81, "loads.torque": 20.0,
            "loads.unbalance": 2e-3, "loads.unbalance_phase": -1.1}
    model = rubdyn.Model(case_from_keys(keys, "rigid-rotor"))
    rng = np.random.default_rng(2)
    for _ in range(20):
        q = rng.normal(size=7) * [1e-3, 1e-3, 1e-4, 1e-4, 3.0, 1e-4, 1e-4]
        v = rng.normal(size=7) * [1.0, 1.0, 1.0, 1.0, 500.0, 1.0, 1.0]
        M_ref, f_ref = rigid_rotor_M_f(keys, q, v)
        M = model.mass_matrix(q)
        assert np.max(np.abs(M - M_ref)) <= 8 * EPS * np.max(np.abs(M))
        f = model.smooth_forces(0.0, q, v)
        # terms up to the gyroscopic H omega v ~ 1e3 N and k_b q ~ 5e3 N: rounding 1e-13 of them
        assert np.max(np.abs(f - f_ref)) <= 1e-12 * max(np.max(np.abs(f)), 5e3)
        # the structured products and solves are M's
        x = rng.normal(size=7)
        assert np.allclose(M @ np.linalg.solve(M, x), x, rtol=0, atol=1e-12)


def test_jeffcott_linearisation_and_columns():
    keys = dict(JEFFCOTT)
    case = case_from_keys(keys, "jeffcott")
    model = rubdyn.Model(case)
    tied = model.linearize("tied")
    assert tied["names"] == ["x_r", "y_r"] and tied["nodes"] == [(0, 1)]
    assert tied["M"][0, 0] == keys["rotor.mass"] + keys["stator.mass"]
    assert tied["K"][1, 1] == keys["rotor.k"] + keys["stator.k"]
    assert not tied["G"].any()  # the planar Jeffcott rotor has no gyroscopic coupling
    free = model.linearize("free")
    assert free["names"] == ["x_r", "y_r", "x_s", "y_s"]
    # one column table: the case's and the model's columns are the same
    assert case.columns == model.columns
    assert model.columns[:6] == ["t", "x_r", "y_r", "theta", "x_s", "y_s"]
    assert model.columns[-6:] == ["d_N", "v_N", "v_t", "F_N", "F_T", "phase"]
    # the Campbell diagram of the tied pair: one forward and one backward mode at
    # sqrt((k_r + k_s) / (m_r + m_s)) / 2 pi, whatever the spin
    d = rubdyn.campbell(case, points=3)
    f_c = math.sqrt((keys["rotor.k"] + keys["stator.k"]) /
                    (keys["rotor.mass"] + keys["stator.mass"])) / (2 * math.pi)
    assert d["labels"] == ["f1b", "f1f"] and d["labels_ok"]
    assert np.allclose(d["f1b"], f_c, rtol=1e-12) and np.allclose(d["f1f"], f_c, rtol=1e-12)


def test_campbell_of_a_rigid_stator_and_of_a_fixed_ring_is_the_clis(cli, tmp_path):
    """Issue 34: rubdyn.campbell took the tied linearisation only: a Jeffcott rotor in a rigid
    stator (tied: nothing left to vibrate, size 0) died with SIGSEGV, and a [[plane]] with a
    fixed ring (no tied system) was refused although `rubdyn campbell` draws its free modes."""
    keys = {k: v for k, v in JEFFCOTT.items()
            if k not in ("stator.mass", "stator.k", "stator.c")}
    keys["stator.rigid"] = True
    case = case_from_keys(keys, "jeffcott")
    d = rubdyn.campbell(case, points=3)
    assert d["tied"] is False and d["labels"] == ["f1b", "f1f"] and d["labels_ok"]
    # the rotor alone: sqrt(k_r / m_r) / 2 pi, forward = backward (rtol: the eigen solver's
    # round-off, 1e-12 is far above it)
    f_r = math.sqrt(keys["rotor.k"] / keys["rotor.mass"]) / (2 * math.pi)
    assert np.allclose(d["f1b"], f_r, rtol=1e-12) and np.allclose(d["f1f"], f_r, rtol=1e-12)
    # a fixed ring at plane 2: the CLI's campbell.csv, to the bit
    text = open(os.path.join(SOURCE, "cases", "two-plane.toml")).read()
    ring = "stator_mass  = 1.0\nstator_k     = 4.0e6\nstator_c     = 50.0\n"
    assert ring in text
    path = tmp_path / "fixed.toml"
    path.write_text(text.replace(ring, "stator_rigid = true\n"))
    d = rubdyn.campbell(rubdyn.load_case(path), points=7)
    assert d["tied"] is False
    p = run_cli(cli, "campbell", str(path), "--points", "7", "--out", str(tmp_path / "c"))
    assert "no contact" in p.stdout
    assert (tmp_path / "c" / "campbell.csv").read_text() == d["csv"]


def test_campbell_of_an_odd_n_says_odd(tmp_path):
    """Issue 34: a matrices rotor of odd size has no whirl pairs: the error says so."""
    for name, rows in (("M.csv", "2,0,0\n0,2,0\n0,0,2\n"), ("Z.csv", "0,0,0\n0,0,0\n0,0,0\n"),
                       ("K.csv", "1e6,0,0\n0,1e6,0\n0,0,1e6\n")):
        (tmp_path / name).write_text(rows)
    path = tmp_path / "odd.toml"
    path.write_text('[model]\nkind = "matrices"\n[rotor]\nM = "M.csv"\nC = "Z.csv"\nK = "K.csv"\n'
                    'G = "Z.csv"\nJp = 0.06\n[contact_node]\nx = 0\ny = 1\nradius = 0.05\n'
                    'gap = 2e-4\n[stator]\nrigid = true\n[contact]\nmu = 0.1\n[loads]\ngravity = 0.0\ntorque = 1.0\n[run]\nt_end = 0.01\n'
                    'omega_lim = 100.0\n')
    with pytest.raises(rubdyn.CaseError, match=r"rotor.M = .*n = 3 is odd"):
        rubdyn.campbell(rubdyn.load_case(path))


def test_an_absurd_npy_shape_is_a_case_error_not_memory_error(tmp_path):
    """Issue 34: a .npy header declaring 2^32 x 2^32 entries without data gave MemoryError."""
    shutil.copytree(os.path.join(SOURCE, "cases", "matrices-paper"), tmp_path / "matrices-paper")
    shutil.copy(os.path.join(SOURCE, "cases", "matrices-paper.toml"), tmp_path / "case.toml")
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (4294967296, 4294967296), }"
    header += " " * (63 - (10 + len(header)) % 64) + "\n"
    (tmp_path / "huge.npy").write_bytes(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little")
                                        + header.encode())
    with pytest.raises(rubdyn.CaseError, match=r"rotor.M = .*huge.npy.*declares"):
        rubdyn.load_case(tmp_path / "case.toml", overrides={"rotor.M": "huge.npy"})
