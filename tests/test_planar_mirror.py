"""Planar mirrors: reflections, virtual cameras, and the skew-symmetric F of direct and reflected images.

Golden values are derived by hand in the comments; the properties (an
involution with determinant -1, the projection identity of a virtual camera,
the skew-symmetric F) hold for any correct implementation.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from egtviz.egt import (
    GeometryError,
    f_3Drandpoint,
    f_epipole,
    f_Festim,
    f_perspproj,
    f_reflcamera,
    f_reflFestim,
    f_reflmatrix,
    f_reflpersproj,
    f_reflpoint,
    f_Rt2H,
    rotox,
    rotoy,
)
from egtviz.geometry.pinhole import Intrinsics, PinholeCamera
from egtviz.geometry.planar_mirror import PlaneMirror, fundamental_from_reflections, mirror_fundamental
from egtviz.geometry.poses import Pose

K = np.array([[700.0, 0, 640], [0, 700.0, 480], [0, 0, 1]])
unit = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)


def test_reflmatrix_by_hand():
    # The plane y = 0: y changes sign.
    np.testing.assert_allclose(f_reflmatrix([0, -1, 0], 0), np.diag([1.0, -1.0, 1.0, 1.0]), atol=1e-15)
    # EGT's example N = (1, 1, 0), ds = 5: the plane x + y = 5 sqrt 2 (after normalising N). The point
    # (-10, 30, 0) has x + y = 20, so it moves by -(20 - 5 sqrt 2)(1, 1): (-30 + 5 sqrt 2, 10 + 5 sqrt 2, 0).
    Xr = f_reflpoint([1, 1, 0], 5, [-10, 30, 0])
    np.testing.assert_allclose(Xr[:, 0], [-30 + 5 * np.sqrt(2), 10 + 5 * np.sqrt(2), 0], atol=1e-12)


@given(unit, st.floats(-5, 5))
def test_reflection_is_an_involution_with_det_minus_one(n, d):
    D = f_reflmatrix(np.array(n), d)
    np.testing.assert_allclose(D @ D, np.eye(4), atol=1e-12)
    assert abs(np.linalg.det(D[:3, :3]) + 1) < 1e-12
    # Points of the plane n.X = d stay put.
    nn = np.array(n) / np.linalg.norm(n)
    P = d * nn + np.cross(nn, [0.3, -0.2, 0.9])
    np.testing.assert_allclose(f_reflpoint(n, d, P)[:, 0], P, atol=1e-12)


def camera_and_points():
    H = f_Rt2H(rotoy(23 * np.pi / 180) @ rotox(0.1), [0.6, -2.8, -0.5])
    P = f_3Drandpoint(20, [2.8, -1.0, 0.0], 0.8, rng=4)
    return H, P


def test_virtual_camera_sees_the_real_scene_as_the_camera_sees_the_reflection():
    H, P = camera_and_points()
    n, d = [0, -1, 0], 0.0
    Hv = f_reflcamera(n, d, H)
    assert abs(np.linalg.det(Hv[:3, :3]) + 1) < 1e-12
    np.testing.assert_allclose(Hv, f_reflmatrix(n, d) @ H, atol=1e-15)
    np.testing.assert_allclose(f_perspproj(P, Hv, K), f_perspproj(f_reflpoint(n, d, P), H, K), atol=1e-9)


def test_reflpersproj_mirror_points_are_on_the_plane_and_image_where_the_reflection_does():
    H, P = camera_and_points()
    n, d = np.array([0.0, -1.0, 0.0]), 0.0
    U, M = f_reflpersproj(n, d, H, K, P)
    assert U.shape == (2, 20) and M.shape == (3, 20)
    assert not np.isnan(U).any()
    np.testing.assert_allclose(M.T @ n, d, atol=1e-12)
    # The light path camera -> mirror point -> X: the mirror point images where the reflected point does.
    np.testing.assert_allclose(f_perspproj(M, H, K), U, atol=1e-8)
    # Margins: only mirror points with x in [x0, 10) are kept.
    x0 = float(np.median(M[0]))
    U2, M2 = f_reflpersproj(n, d, H, K, P, 1e-4, [x0, 10.0])
    kept = ~np.isnan(M2[0])
    np.testing.assert_array_equal(kept, (M[0] >= x0 - 1e-4) & (M[0] < 10.0 + 1e-4))
    np.testing.assert_array_equal(np.isnan(U2[0]), ~kept)
    assert 0 < kept.sum() < 20
    # A point behind the mirror (other side from the camera) is not seen.
    U3, _ = f_reflpersproj(n, d, H, K, [1.0, 3.0, 0.0])
    assert np.isnan(U3).all()


def test_mirror_F_is_the_skew_matrix_of_the_normal_vanishing_point():
    H, P = camera_and_points()
    n, d = np.array([0.0, -1.0, 0.0]), 0.0
    U = f_perspproj(P, H, K)
    Ur = f_perspproj(f_reflpoint(n, d, P), H, K)
    F = f_reflFestim(U, Ur)
    np.testing.assert_allclose(F, -F.T, atol=1e-14)
    h, hr = np.vstack([U, np.ones(20)]), np.vstack([Ur, np.ones(20)])
    np.testing.assert_allclose(np.einsum("in,ij,jn->n", hr, F, h), 0, atol=1e-9)
    # By hand: e = K R^T n, the vanishing point of the mirror normal; F = [e]_x up to scale.
    e = K @ H[:3, :3].T @ n
    Fe = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    Fe /= np.linalg.norm(Fe)
    assert min(np.abs(F - Fe).max(), np.abs(F + Fe).max()) < 1e-9
    camera = PinholeCamera(Pose.from_matrix(H), Intrinsics.from_K(K))
    Fm = mirror_fundamental(camera, PlaneMirror(n, d))
    assert min(np.abs(F - Fm).max(), np.abs(F + Fm).max()) < 1e-9
    # Raw pixels (algorithm 1) give the same F on exact data.
    F1 = f_reflFestim(U, Ur, 1)
    assert min(np.abs(F1 - F).max(), np.abs(F1 + F).max()) < 1e-9


@given(unit, st.integers(0, 1000))
def test_reflFestim_on_noisy_data_stays_skew_and_close(n, seed):
    rng = np.random.default_rng(seed)
    H = f_Rt2H(rotoy(rng.uniform(-0.5, 0.5)), [0, -4, 0])
    nn = np.array(n) / np.linalg.norm(n)
    d = float(nn @ [0, 3, 0])  # the plane passes through (0, 3, 0), in front of the camera
    P = np.array([0, 1.5, 0])[:, None] + rng.uniform(-0.5, 0.5, (3, 30))
    camera = PinholeCamera(Pose.from_matrix(H), Intrinsics.from_K(K))
    mirror = PlaneMirror(nn, d)
    Pr = f_reflpoint(nn, d, P)
    U, Ur = f_perspproj(P, H, K), f_perspproj(Pr, H, K)
    ok = np.isfinite(U).all(axis=0) & np.isfinite(Ur).all(axis=0) & (np.abs(U - Ur).sum(axis=0) > 5)
    if ok.sum() < 4:
        return
    F = fundamental_from_reflections(U[:, ok].T + rng.normal(0, 0.1, (ok.sum(), 2)), Ur[:, ok].T)
    np.testing.assert_allclose(F, -F.T, atol=1e-14)
    # The exact pairs lie within a pixel of the estimated lines (0.1 px noise); the exact F fits them exactly.
    h, hr = np.vstack([U[:, ok], np.ones(ok.sum())]), np.vstack([Ur[:, ok], np.ones(ok.sum())])
    for G, bound in ((F, 1.0), (mirror_fundamental(camera, mirror), 1e-6)):
        lines = G @ h
        dist = np.abs(np.sum(hr * lines, axis=0)) / np.hypot(lines[0], lines[1])
        assert dist.max() < bound


def test_egt_mirror_demo_two_virtual_cameras_epipolar_geometry():
    # EGT 2.0's camProjection demo: two mirrors through the origin, F estimated from the two reflections
    # equals the F of the two virtual cameras.
    H = f_Rt2H(rotoy(-23 * np.pi / 180), [0.6, -2.8, -1.0])
    P = f_3Drandpoint(20, [0.5, -1.0, 0.0], 0.5, rng=9)
    n1, n2 = [0, -1, 0], [np.sin(np.pi / 4), -np.cos(np.pi / 4), 0]
    U1, _ = f_reflpersproj(n1, 0, H, K, P)
    U2, _ = f_reflpersproj(n2, 0, H, K, P)
    seen = ~np.isnan(U1[0]) & ~np.isnan(U2[0])
    assert seen.sum() >= 10
    e1, e2, F_gt = f_epipole(f_reflcamera(n1, 0, H), f_reflcamera(n2, 0, H), K, K)
    F = f_Festim(U1[:, seen], U2[:, seen], 2)
    assert min(np.abs(F - F_gt).max(), np.abs(F + F_gt).max()) < 1e-6
    np.testing.assert_allclose(F_gt @ e1, 0, atol=1e-9)
    np.testing.assert_allclose(e2 @ F_gt, 0, atol=1e-9)


def test_errors_name_the_argument():
    with pytest.raises(GeometryError, match="normal: expected a non-zero 3-vector"):
        f_reflmatrix([0, 0, 0], 1.0)
    with pytest.raises(GeometryError, match="distance"):
        f_reflmatrix([0, 0, 1], "x")
    with pytest.raises(GeometryError, match="H: expected shape"):
        f_reflcamera([0, 0, 1], 0, np.eye(3))
    with pytest.raises(GeometryError, match="Ur: expected as many points as U"):
        f_reflFestim(np.zeros((2, 3)), np.zeros((2, 4)))
    with pytest.raises(GeometryError, match="algorithm"):
        f_reflFestim(np.zeros((2, 3)), np.zeros((2, 3)), 5)
