"""The convention lens: the true geometry with every toggle off, and each classic mistake, against matrices
built here by hand from the cameras' K, R and t (docs/conventions.md)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.scene import SCENES, PinholeSpec, Scene, SceneError
from egtviz.scene.lens import LensToggles, lens_view


def skew(t):
    return np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])


def unit(M):
    return M / np.linalg.norm(M)


def same_up_to_sign(A, B):
    return np.allclose(A, B, atol=1e-9) or np.allclose(A, -B, atol=1e-9)


def parts(scene):
    """K1, K2, R, t of the drawn pair, straight from the specs' poses and intrinsics."""
    a, b = (scene.camera(n) for n in scene.drawn_pair)
    R1, R2 = a.pose.R, b.pose.R
    R = R2.T @ R1
    t = R2.T @ (np.array(a.position) - np.array(b.position))
    return a.intrinsics.K, b.intrinsics.K, R, t


def pair(yaw2=-25.0, pos2=(3.5, -7.5, 2.5), pitch2=-10.0, roll2=0.0, k2=None):
    cams = (PinholeSpec("cam1", (-3, -8, 1.5), (20.5, -3.3, 0)),
            PinholeSpec("cam2", pos2, (yaw2, pitch2, roll2), **(k2 or {})))
    return Scene(cameras=cams, points=SCENES["default"]().points)


def test_all_toggles_off_is_the_true_geometry_with_zero_residuals():
    scene = SCENES["default"]()
    view = lens_view(scene)
    K1, K2, R, t = parts(scene)
    assert same_up_to_sign(view.F, unit(np.linalg.inv(K2).T @ skew(t) @ R @ np.linalg.inv(K1)))
    assert same_up_to_sign(view.F, view.F_true)
    assert np.max(np.abs(view.residuals)) < 1e-12
    assert np.max(view.distances1_px) < 1e-9 and np.max(view.distances2_px) < 1e-9
    assert np.allclose(view.F @ view.e1, 0, atol=1e-12) and np.allclose(view.F.T @ view.e2, 0, atol=1e-12)


@settings(max_examples=40)
@given(st.floats(-60, 60), st.floats(-20, 20), st.floats(-30, 30), st.floats(-2, 6), st.floats(0.004, 0.02))
def test_the_true_lens_has_zero_residuals_for_any_pair(yaw, pitch, roll, x, focal):
    scene = pair(yaw, (x, -7.0, 2.0), pitch, roll, {"focal_length": focal, "principal_point": (300.0, 260.0)})
    view = lens_view(scene)
    seen = np.isfinite(view.distances2_px)
    assert np.all(view.distances2_px[seen] < 1e-6) and np.all(view.distances1_px[seen] < 1e-6)


@pytest.mark.parametrize("toggle", ["f_transposed", "r_tx", "k_transposed", "opengl_axes"])
@pytest.mark.parametrize("yaw2", [-25.0, -5.0, 12.0])
def test_each_mistake_breaks_the_residuals_of_a_generic_pair(toggle, yaw2):
    view = lens_view(pair(yaw2), LensToggles(**{toggle: True}))
    assert np.max(view.distances2_px) > 1.0, toggle
    assert np.max(np.abs(view.residuals)) > 1e-6


def test_each_mistake_is_the_matrix_it_names():
    scene = pair(k2={"principal_point": (300.0, 250.0), "focal_length": 0.01})
    K1, K2, R, t = parts(scene)
    K2iT = np.linalg.inv(K2).T
    D = np.diag([1.0, -1.0, -1.0])
    expected = {
        "f_transposed": (K2iT @ skew(t) @ R @ np.linalg.inv(K1)).T,
        "r_tx": K2iT @ R @ skew(t) @ np.linalg.inv(K1),
        "k_transposed": K2iT @ skew(t) @ R @ K1.T,
        "opengl_axes": K2iT @ skew(D @ t) @ (D @ R @ D) @ np.linalg.inv(K1),
    }
    for toggle, F in expected.items():
        assert same_up_to_sign(lens_view(scene, LensToggles(**{toggle: True})).F, unit(F)), toggle
    # E for the OpenGL axes is D E D (the cross product of a rotated vector: [D t]x = D [t]x D, det D = 1).
    view = lens_view(scene, LensToggles(opengl_axes=True))
    assert same_up_to_sign(view.E, unit(D @ skew(t) @ R @ D))


def test_the_wrong_singular_vector_swaps_the_epipoles_but_keeps_the_lines():
    scene = SCENES["default"]()
    true = lens_view(scene)
    wrong = lens_view(scene, LensToggles(wrong_singular_vector=True))
    assert np.allclose(wrong.e1, true.e2) and np.allclose(wrong.e2, true.e1)
    assert np.max(wrong.distances2_px) < 1e-9  # the lines are right: only the drawn epipoles move
    # ... and no longer on the lines: the drawn e2 is off the lines of image 2
    assert np.max(np.abs(wrong.lines2 @ wrong.e2)) > 1.0


def test_toggles_compose_and_are_checked():
    scene = pair()
    both = lens_view(scene, LensToggles(f_transposed=True, r_tx=True))
    K1, K2, R, t = parts(scene)
    assert same_up_to_sign(both.F, unit((np.linalg.inv(K2).T @ R @ skew(t) @ np.linalg.inv(K1)).T))
    assert LensToggles(r_tx=True).any and not LensToggles().any
    with pytest.raises(SceneError, match="r_tx: expected true or false"):
        LensToggles(r_tx=1)


def test_the_lens_needs_a_pinhole_pair():
    with pytest.raises(SceneError, match="pin-hole pair"):
        lens_view(SCENES["panoramic"]())
    with pytest.raises(SceneError, match="two cameras"):
        lens_view(SCENES["example1"]())
    coincident = Scene(cameras=(PinholeSpec("a", (0, 0, 0)), PinholeSpec("b", (0, 0, 0), (10, 0, 0))))
    with pytest.raises(SceneError, match="centres coincide"):
        lens_view(coincident)
