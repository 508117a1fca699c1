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
