"""Poses and the pin-hole camera: identities over random input, and error paths."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import GeometryError, Intrinsics, PinholeCamera, Pose
from egtviz.geometry.poses import (
    EGT_CAMERA_BASE,
    egt_rotation_from_ypr,
    look_at,
    matrix_from_quat_wxyz,
    rotx,
    roty,
    rotz,
    skew,
    ypr_from_egt_rotation,
)

angles = st.floats(-np.pi, np.pi, allow_nan=False)
seeds = st.integers(0, 2**32 - 1)


def random_rotation(rng):
    q = rng.normal(size=4)
    return matrix_from_quat_wxyz(q)


@given(angles)
def test_elementary_rotations_are_right_handed(a):
    # The rotation of the x axis by a about z lands at (cos a, sin a, 0); likewise cyclically.
    np.testing.assert_allclose(rotz(a) @ [1, 0, 0], [np.cos(a), np.sin(a), 0], atol=1e-12)
    np.testing.assert_allclose(rotx(a) @ [0, 1, 0], [0, np.cos(a), np.sin(a)], atol=1e-12)
    np.testing.assert_allclose(roty(a) @ [0, 0, 1], [np.sin(a), 0, np.cos(a)], atol=1e-12)


def test_egt_base_looks_along_world_y_with_v_down():
    # f_Rt2H with R = I: optical axis (3rd column) +y, image v axis (2nd column) -z.
    np.testing.assert_allclose(EGT_CAMERA_BASE[:, 2], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(EGT_CAMERA_BASE[:, 1], [0, 0, -1], atol=1e-15)


@settings(max_examples=100)
@given(st.floats(-3, 3), st.floats(-1.5, 1.5), st.floats(-3, 3))
def test_ypr_round_trip(yaw, pitch, roll):
    R = egt_rotation_from_ypr(yaw, pitch, roll)
    np.testing.assert_allclose(egt_rotation_from_ypr(*ypr_from_egt_rotation(R)), R, atol=1e-9)


def test_yaw_pans_about_the_camera_vertical():
    # A positive yaw turns the optical axis from +y towards +x, keeping it horizontal.
    p = Pose.from_egt(egt_rotation_from_ypr(np.pi / 6, 0, 0), [0, 0, 0])
    np.testing.assert_allclose(p.R[:, 2], [0.5, np.sqrt(3) / 2, 0], atol=1e-12)


@settings(max_examples=50)
@given(seeds)
def test_pose_inverse_compose_and_quaternion(seed):
    rng = np.random.default_rng(seed)
    p = Pose(random_rotation(rng), rng.normal(size=3))
    X = rng.normal(size=(10, 3))
    np.testing.assert_allclose(p.to_world(p.to_local(X)), X, atol=1e-12)
    np.testing.assert_allclose(p.compose(p.inverse()).matrix, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(matrix_from_quat_wxyz(p.quat_wxyz), p.R, atol=1e-12)
    np.testing.assert_allclose(skew(X[0]) @ X[1], np.cross(X[0], X[1]), atol=1e-12)


@settings(max_examples=50)
@given(seeds)
def test_projection_then_back_projection_returns_the_ray(seed):
    rng = np.random.default_rng(seed)
    cam = PinholeCamera(
        Pose(random_rotation(rng), rng.normal(size=3)),
        Intrinsics(0.008, (1e5, 1.1e5), (300.0, 250.0), 2.0, 640, 480),
    )
    d_cam = np.column_stack([rng.uniform(-0.3, 0.3, (20, 2)), np.ones(20)]) * rng.uniform(1, 10, (20, 1))
    X = cam.pose.to_world(d_cam)
    proj = cam.project(X)
    assert proj.in_front.all()
    rays = cam.back_project(proj.pixels)
    expected = (X - cam.center) / np.linalg.norm(X - cam.center, axis=1, keepdims=True)
    np.testing.assert_allclose(rays, expected, atol=1e-9)
    # Same pixels through the 3x4 matrix P.
    m = np.column_stack([X, np.ones(len(X))]) @ cam.P.T
    np.testing.assert_allclose(m[:, :2] / m[:, 2:], proj.pixels, rtol=1e-10)


def test_points_behind_the_camera_have_no_pixel():
    cam = PinholeCamera(look_at([0, 0, 0], [0, 1, 0]))
    proj = cam.project([[0, 5, 0], [0, -5, 0], [0, 0, 1], [100, 1, 0]])
    assert proj.in_front.tolist() == [True, False, False, True]
    assert np.isnan(proj.pixels[1]).all() and np.isnan(proj.pixels[2]).all()
    assert proj.in_image.tolist() == [True, False, False, False]
    np.testing.assert_allclose(proj.pixels[0], [320, 240])


def test_frustum_corners_project_to_image_corners():
    cam = PinholeCamera(look_at([1, 2, 3], [0, 10, 0]))
    corners = cam.frustum_corners(2.0)
    np.testing.assert_allclose(cam.project(corners).pixels, [[0, 0], [640, 0], [640, 480], [0, 480]], atol=1e-9)
    np.testing.assert_allclose(cam.pose.to_local(corners)[:, 2], 2.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"focal_length": 0.0}, "focal_length"),
        ({"focal_length": float("nan")}, "focal_length"),
        ({"pixels_per_metre": (1e5, -1.0)}, "pixels_per_metre"),
        ({"width": 0}, "width"),
        ({"height": 2.5}, "height"),
    ],
)
def test_bad_intrinsics_are_refused(kwargs, match):
    with pytest.raises(GeometryError, match=match):
        Intrinsics(**kwargs)


def test_bad_input_messages_name_the_argument():
    cam = PinholeCamera()
    with pytest.raises(GeometryError, match=r"X_world: expected shape \(N, 3\)"):
        cam.project(np.zeros((4, 2)))
    with pytest.raises(GeometryError, match="X_world: contains NaN"):
        cam.project([[0, np.nan, 1]])
    with pytest.raises(GeometryError, match="R: expected a 3x3 rotation"):
        Pose(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(GeometryError, match="K: calibration matrix is not invertible"):
        Intrinsics.from_K(np.diag([1.0, 0.0, 1.0]))
    with pytest.raises(GeometryError, match="H: expected shape"):
        Pose.from_matrix(np.eye(3))


def test_pose_check_false_trusts_its_inputs_and_the_checked_path_still_refuses():
    """``check=False`` is the per-drag fast path: the arrays are copied read-only, not re-orthonormalised."""
    from egtviz.geometry import GeometryError, Pose
    from egtviz.geometry.poses import rotz

    R = rotz(0.3)
    fast = Pose(R, [1.0, 2.0, 3.0], check=False)
    slow = Pose(R, [1.0, 2.0, 3.0])
    assert np.array_equal(fast.R, R) and np.allclose(fast.R, slow.R, atol=1e-15)
    assert not fast.R.flags.writeable and not fast.t.flags.writeable
    R[0, 0] = 5.0  # the caller's array is not shared
    assert fast.R[0, 0] != 5.0
    with pytest.raises(GeometryError, match="R"):
        Pose(np.diag([1.0, 1.0, 2.0]), np.zeros(3))
