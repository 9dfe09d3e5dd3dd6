"""The drag's plain-float E and F equal the core's checked numpy functions (to 1e-12), signs included."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import DegenerateConfigurationError, Pose
from egtviz.geometry.epipolar import essential_from_poses, fundamental_from_essential
from egtviz.geometry.poses import rotx, roty, rotz
from egtviz.scene import derived

vectors = st.lists(st.floats(min_value=-3.0, max_value=3.0), min_size=3, max_size=3)


def _pose(rotvec: list[float], t: list[float]) -> Pose:
    return Pose(rotz(rotvec[0]) @ roty(rotvec[1]) @ rotx(rotvec[2]), np.array(t))


@settings(max_examples=200, deadline=None)
@given(vectors, vectors, vectors, vectors, st.floats(min_value=50.0, max_value=5000.0),
       st.floats(min_value=0.0, max_value=50.0))
def test_plain_float_e_and_f_equal_the_checked_functions(r1, t1, r2, t2, f, skew) -> None:
    p1, p2 = _pose(r1, t1), _pose(r2, t2)
    if np.linalg.norm(p1.t - p2.t) < 1e-3:
        return
    K1 = np.array([[f, skew, 320.0], [0.0, 1.1 * f, 240.0], [0.0, 0.0, 1.0]])
    K2 = np.array([[0.7 * f, 0.0, 100.0], [0.0, 0.7 * f, 90.0], [0.0, 0.0, 1.0]])
    E, F = derived._essential_and_fundamental(p1, p2, K1, K2)
    assert F is not None
    E_ref = essential_from_poses(p1, p2)
    np.testing.assert_allclose(E, E_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(F, fundamental_from_essential(E_ref, K1, K2), rtol=0, atol=1e-12)
    E_only, none = derived._essential_and_fundamental(p1, p2, None, K2)
    assert none is None
    np.testing.assert_array_equal(E_only, E)


def test_coincident_centres_are_refused() -> None:
    p = _pose([0.1, 0.2, 0.3], [1.0, 2.0, 3.0])
    with pytest.raises(DegenerateConfigurationError, match="centres coincide"):
        derived._essential_and_fundamental(p, p, None, None)
