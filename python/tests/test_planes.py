"""Contact planes in Python: Result.planes, Result.plane(k) (one plane's columns under the
one-plane names, its centres from the model), rubdyn.analyze(..., plane=k)."""
import os

import numpy as np
import pytest

import rubdyn
from conftest import REFERENCE


@pytest.fixture(scope="module")
def ref():
    # 12 ms: the rotor lands at about 6 ms (impacts, slip, lift-offs)
    return rubdyn.run(REFERENCE, t_end=0.012)


def test_one_plane_view_is_the_result(ref):
    assert ref.planes == 1
    p = ref.plane(1)
    # plane_motion of the rigid rotor reads the coordinates x_r, y_r, x_s, y_s themselves: the
    # same doubles, not a recomputation
    for name in ("x_r", "y_r", "x_s", "y_s", "vx_r", "vy_r", "vx_s", "vy_s", "d_N", "phase"):
        assert np.array_equal(p[name], ref[name]), name
    assert p.plane_info["gap"] == ref.case.gap
    assert p.plane_info["mu"] == ref.case.mu
    assert len(p.events) == len(ref.events)


@pytest.mark.parametrize("k", [0, 2, -1, 1.0, True, "1"])
def test_no_such_plane(ref, k):
    with pytest.raises(ValueError, match="contact plane"):
        ref.plane(k)


def test_analyze_plane_one_is_the_default(ref):
    a, b = rubdyn.analyze(ref), rubdyn.analyze(ref, plane=1)
    assert a.verdicts == b.verdicts
    with pytest.raises(ValueError, match="plane 2"):
        rubdyn.analyze(ref, plane=2)
    with pytest.raises(TypeError, match="plane"):
        rubdyn.analyze(ref, plane=1.5)


def test_case_contacts(ref):
    c = ref.case.contacts
    assert len(c) == 1
    assert c[0]["gap"] == ref.case.gap and c[0]["radius"] == ref.case.radius


TWO_PLANE = REFERENCE.replace("reference.toml", "two-plane.toml")


@pytest.fixture(scope="module")
def two():
    # Moreau-Jean, 12 ms: both planes are hit (plane 2 at 6.00 ms, plane 1 at 6.07 ms)
    return rubdyn.run(TWO_PLANE, t_end=0.012)


def test_two_planes_views(two):
    assert two.planes == 2
    assert len(two.case.contacts) == 2
    p1, p2 = two.plane(1), two.plane(2)
    # the plane's own columns under the one-plane names
    assert np.array_equal(p2["d_N"], two["d_N_2"]) and np.array_equal(p2["phase"], two["phase_2"])
    assert np.array_equal(p1["F_N"], two["F_N_1"])
    # plane 2 sits halfway to the bearing (s = 0.2 / 0.4): its rotor point is the midpoint of
    # B and R, computed as (1 - s) x_b + s x_r by the model, the same doubles here
    assert np.array_equal(p2["x_r"], 0.5 * two["x_b"] + 0.5 * two["x_r"])
    assert np.array_equal(p2["x_s"], two["x_s_2"])
    # plane 1 at R: the coordinates themselves
    assert np.array_equal(p1["x_r"], two["x_r"])
    # the gap from the centres: g0 - |rotor point - ring| = d_N to round-off of O(1e-4) m
    # positions (1e-19 m): 1e-17 m
    r = np.hypot(p2["x_r"] - p2["x_s"], p2["y_r"] - p2["y_s"])
    assert np.max(np.abs(p2.plane_info["gap"] - r - p2["d_N"])) < 1e-17
    # each view keeps its contact's events only
    assert len(p1.events) + len(p2.events) == len(two.events)
    assert set(p2.events["contact"]) == {2}
    v1, v2 = rubdyn.analyze(two, plane=1), rubdyn.analyze(two, plane=2)
    assert v1.verdicts["events"] == v2.verdicts["events"] == len(two.events)
    assert v2.verdicts["min_dN_over_g0"] == pytest.approx(np.min(two["d_N_2"]) / 1e-4, rel=1e-12)


def test_two_planes_figures(two, tmp_path):
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import rubdyn.plot as rp
    paths = [os.path.basename(p) for p in rp.write_all(two, str(tmp_path))]
    for name in ("orbit_1.png", "orbit_2.png", "contact_2.png", "timeline_2.png", "omega.png"):
        assert name in paths, paths


def _figure_tests(res, tmp_path=None):
    """Every figure of a run draws data; with several planes each figure of one plane takes
    plane=k and refuses, naming the planes, without it. With tmp_path, write_all too."""
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import rubdyn.plot as rp
    for name, make in rp.FIGURES.items():
        planes = [None] if res.planes == 1 or name == "omega" else range(1, res.planes + 1)
        for k in planes:
            fig = make(res) if k is None else make(res, plane=k)
            assert sum(len(ax.lines) for ax in fig.axes) > 0, (name, k)
            plt.close(fig)
        if res.planes > 1 and name != "omega":
            with pytest.raises(ValueError, match=f"{res.planes} contact planes"):
                make(res)
    if tmp_path is None:
        return []
    paths = rp.write_all(res, str(tmp_path))
    assert paths and all(os.path.getsize(p) > 0 for p in paths)
    return [os.path.basename(p) for p in paths]


def test_figures_of_a_rigid_stator_jeffcott_run(tmp_path):
    # a fixed ring has no coordinates (no x_s column: KeyError 'x_s' before); its centre is the
    # origin, the orbit the disc's own
    path = os.path.join(os.path.dirname(REFERENCE), "jeffcott.toml")
    text = open(path).read()
    a = text.index("[stator]")
    b = text.index("\n[", a)
    stator = "\n".join(line for line in text[a:b].split("\n")
                       if not line.split("=")[0].strip() in ("mass", "k", "c"))
    text = text[:a] + stator.replace("[stator]", "[stator]\nrigid = true", 1) + text[b:]
    res = rubdyn.run(rubdyn.parse_case(text, path), t_end=0.02)
    assert "x_s" not in res
    names = _figure_tests(res, tmp_path)
    assert "orbit.png" in names
    p = res.plane(1)
    assert np.array_equal(p["x_s"], np.zeros(len(res)))


def test_figures_of_a_two_contact_matrices_run(tmp_path):
    # two [[contact_node]]s: phase_1, phase_2 and no phase column (KeyError 'phase' before)
    res = rubdyn.run(os.path.join(os.path.dirname(REFERENCE), "matrices-two-plane.toml"),
                     t_end=0.012)
    assert res.planes == 2 and "phase" not in res
    names = _figure_tests(res, tmp_path)
    for name in ("omega.png", "orbit_1.png", "orbit_2.png", "contact_2.png", "timeline_2.png"):
        assert name in names, names


@pytest.mark.parametrize("spin", [(0.0, 0.0), (0.0, 1e5), (1000.0, -1e5)])
def test_prescribed_spin_two_planes_views(spin):
    # a prescribed spin on the two-plane rotor (held at 0, ramped up, ramped down through 0):
    # plane 2's centres come from the wrapped model ("does not locate its centres" before)
    text = open(TWO_PLANE).read().replace("torque  = 20.0", 'spin = "prescribed"')
    case = rubdyn.parse_case(text, TWO_PLANE, overrides={"initial.omega0": spin[0],
                                                         "loads.spin_accel": spin[1]})
    res = rubdyn.run(case, t_end=0.012)
    assert res.summary["complete"]
    p2 = res.plane(2)
    assert np.array_equal(p2["x_r"], 0.5 * res["x_b"] + 0.5 * res["x_r"])
    assert rubdyn.analyze(res, plane=2).verdicts["events"] == len(res.events)
    if spin[1] < 0:  # (the figures once: they cost seconds)
        _figure_tests(res)
