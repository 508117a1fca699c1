"""Contact planes in Python: Result.planes, Result.plane(k) (one plane's columns under the
one-plane names, its centres from the model), rubdyn.analyze(..., plane=k)."""
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
