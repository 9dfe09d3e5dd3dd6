"""The linear triangulation with one camera matrix scaled alone: the points, or an error naming the argument.

The DLT weighs each image's equations by its matrix's scale. Up to :data:`MAX_SCALE_RATIO` apart the points
of exact correspondences come back to 1e-9; beyond it the smaller camera's equations sink into the larger
one's rounding, and the call is refused naming that camera, where it used to return NaN silently.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import GeometryError
from egtviz.geometry.triangulation import MAX_SCALE_RATIO, triangulate_linear

try:
    from tests._twoview import make_two_view
except ImportError:  # run from inside tests/
    from _twoview import make_two_view


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), power=st.floats(-5.9, 5.9), which=st.sampled_from([0, 1]))
def test_one_camera_scaled_within_the_ratio_gives_the_points(seed: int, power: float, which: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 20)
    P = [scene.P1, scene.P2]
    top1, top2 = (float(np.abs(p).max()) for p in P)
    # the scale is measured between the two matrices as given: start from equal largest entries
    P = [scene.P1 / top1, scene.P2 / top2]
    P[which] = P[which] * 10.0**power
    X = triangulate_linear(P[0], P[1], scene.U1, scene.U2)
    np.testing.assert_allclose(X, scene.X, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("scale", [1e100, 1e-100, 1e10, 1e-10])
@pytest.mark.parametrize("which", ["P1", "P2"])
def test_one_camera_scaled_beyond_the_ratio_is_refused_by_name(scale: float, which: str) -> None:
    scene = make_two_view(np.random.default_rng(7), 10)
    P1, P2 = scene.P1 / np.abs(scene.P1).max(), scene.P2 / np.abs(scene.P2).max()
    if which == "P1":
        P1 = P1 * scale
    else:
        P2 = P2 * scale
    smaller = which if scale < 1.0 else ({"P1": "P2", "P2": "P1"}[which])
    with pytest.raises(GeometryError, match=rf"^{smaller}: .* times its scale"):
        triangulate_linear(P1, P2, scene.U1, scene.U2)


def test_the_same_points_at_scale_one_are_right() -> None:
    scene = make_two_view(np.random.default_rng(7), 10)
    X = triangulate_linear(scene.P1, scene.P2, scene.U1, scene.U2)
    assert np.isfinite(X).all()
    np.testing.assert_allclose(X, scene.X, rtol=1e-9, atol=1e-9)
    assert MAX_SCALE_RATIO == 1e6
