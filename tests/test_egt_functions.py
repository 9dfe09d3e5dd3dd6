"""Golden and property tests of the EGT facade's functions beyond the tutorial's examples.

Each golden value is derived independently of egtviz's code path: by hand
(the derivation is in the comment), from Hartley & Zisserman, or from a peer
library at equal conventions (OpenCV's ``decomposeEssentialMat``, scipy's
``Rotation.align_vectors``); the property tests check identities that any
correct implementation satisfies.
"""

from __future__ import annotations

import sys
import types

import cv2
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from egtviz.egt import (
    DEFAULT_PANORAMIC_K,
    GeometryError,
    f_3Dpointplanedistance,
    f_3Drandpoint,
    f_3Dsurface,
    f_atan,
    f_backcatmod,
    f_catmod,
    f_daqaXhmir,
    f_E2Motion,
    f_epipline,
    f_epipole,
    f_Festim,
    f_findepipoles,
    f_forcerank2,
    f_lambda,
    f_normalize,
    f_normplane,
    f_panE,
    f_panEestim,
    f_panparconic,
    f_panproj,
    f_perspline,
    f_perspproj,
    f_panepipoles,
    f_epipconics,
    f_Procrustes,
    f_projectmir,
    f_reflcamera,
    f_reflFestim,
    f_reflmatrix,
    f_reflpersproj,
    f_reflpoint,
    f_Rt2H,
    f_skew,
    f_stack,
    f_unstacked,
    rotox,
    rotoy,
    rotoz,
)
from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror

K_PAN = DEFAULT_PANORAMIC_K
finite = st.floats(-10, 10, allow_nan=False)


def pose(R, t):
    H = np.eye(4)
    H[:3, :3] = R
    H[:3, 3] = t
    return H


# ------------------------------------------------------------------ algebra
def test_skew_by_hand_and_cross_product():
    np.testing.assert_array_equal(f_skew([1, 2, 3]), [[0, -3, 2], [3, 0, -1], [-2, 1, 0]])
    v, w = np.array([0.3, -1.2, 2.0]), np.array([4.0, 0.5, -0.7])
    np.testing.assert_allclose(f_skew(v) @ w, np.cross(v, w), atol=1e-15)


def test_E2Motion_contains_the_true_motion_and_agrees_with_opencv():
    R = Rotation.from_rotvec([0.1, -0.3, 0.2]).as_matrix()
    t = np.array([0.4, -1.0, 2.0])
    E = f_skew(t) @ R
    sol = f_E2Motion(E)
    assert sol.shape == (3, 4, 4)
    # One of the four is (R, t) itself, at the true scale |t| (E's singular values are |t|, |t|, 0).
    errors = [np.abs(sol[:, :3, k] - R).max() + np.abs(sol[:, 3, k] - t).max() for k in range(4)]
    assert min(errors) < 1e-12
    # Every solution reproduces E up to sign.
    for k in range(4):
        Ek = f_skew(sol[:, 3, k]) @ sol[:, :3, k]
        assert min(np.abs(Ek - E).max(), np.abs(Ek + E).max()) < 1e-12
    # Peer: OpenCV's decomposition gives the same two rotations and the same baseline direction.
    R1, R2, tc = cv2.decomposeEssentialMat(E)
    ours = {tuple(np.round(sol[:, :3, k], 9).ravel()) for k in range(4)}
    assert {tuple(np.round(R1, 9).ravel()), tuple(np.round(R2, 9).ravel())} == ours
    assert abs(abs(tc.ravel() @ sol[:, 3, 0]) / np.linalg.norm(t) - 1) < 1e-12


def test_normalize_by_hand_and_properties():
    # Square of side 2 centred at (1, 1): every point is sqrt(2) from the centroid, so s = 1.
    Un, T = f_normalize([[0, 2, 0, 2], [0, 0, 2, 2]])
    np.testing.assert_allclose(T, [[1, 0, -1], [0, 1, -1], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(Un, [[-1, 1, -1, 1], [-1, -1, 1, 1]], atol=1e-15)
    rng = np.random.default_rng(3)
    U = rng.uniform(0, 640, (2, 30))
    Un, T = f_normalize(U)
    np.testing.assert_allclose(Un.mean(axis=1), 0, atol=1e-12)
    # H&Z's (and OpenCV's, kornia's) normalisation: MEAN distance sqrt(2) from the centroid, not RMS.
    np.testing.assert_allclose(np.mean(np.linalg.norm(Un, axis=0)), np.sqrt(2), rtol=1e-12)
    np.testing.assert_allclose((T @ np.vstack([U, np.ones(30)]))[:2], Un, atol=1e-12)


def test_forcerank2_by_hand_and_eckart_young():
    Q1, Q2 = Rotation.from_rotvec([0.3, 0.2, 0.1]).as_matrix(), Rotation.from_rotvec([-1, 0.5, 0.2]).as_matrix()
    M = Q1 @ np.diag([3.0, 2.0, 1.0]) @ Q2
    np.testing.assert_allclose(f_forcerank2(M), Q1 @ np.diag([3.0, 2.0, 0.0]) @ Q2, atol=1e-12)
    assert np.linalg.matrix_rank(f_forcerank2(M)) == 2
    # Distance to M is sigma_3 = 1 (Eckart-Young).
    assert abs(np.linalg.norm(f_forcerank2(M) - M) - 1.0) < 1e-12


def test_stack_is_matlab_colon_and_unstacked_inverts_it():
    np.testing.assert_array_equal(f_stack([[1, 2], [3, 4]]).ravel(), [1, 3, 2, 4])  # MATLAB M(:)
    assert f_stack([[1, 2], [3, 4]]).shape == (4, 1)
    M = np.arange(9.0).reshape(3, 3)
    np.testing.assert_array_equal(f_unstacked(f_stack(M), 3), M)
    np.testing.assert_array_equal(f_unstacked([1, 2, 3, 4, 5, 6], 2), [[1, 4], [2, 5], [3, 6]])
    with pytest.raises(GeometryError, match="columns: 4 does not divide"):
        f_unstacked([1, 2, 3, 4, 5, 6], 4)


def test_atan_full_circle_by_hand():
    a = f_atan([0, 1, 0, -1, 1, -1e-300], [1, 0, -1, 0, -1, 1])
    np.testing.assert_allclose(a, [0, np.pi / 2, np.pi, 3 * np.pi / 2, 3 * np.pi / 4, 0], atol=1e-15)


@given(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3))
def test_atan_range_and_consistency(y, x):
    a = float(f_atan(y, x))
    assert 0.0 <= a < 2 * np.pi
    r = np.hypot(x, y)
    if r > 1e-6:
        np.testing.assert_allclose([r * np.cos(a), r * np.sin(a)], [x, y], atol=1e-9 * max(r, 1))


def test_procrustes_matches_scipy_align_vectors():
    rng = np.random.default_rng(5)
    R = Rotation.from_rotvec([0.7, -0.2, 1.1]).as_matrix()
    Y = rng.normal(size=(3, 20))
    X = R @ Y + 0.01 * rng.normal(size=(3, 20))
    Rhat = f_Procrustes(X, Y)
    peer, _ = Rotation.align_vectors(X.T, Y.T)  # minimises sum |x_i - R y_i|^2
    np.testing.assert_allclose(Rhat, peer.as_matrix(), atol=1e-10)
    assert abs(np.linalg.det(Rhat) - 1) < 1e-12
    # A reflected cloud: the unconstrained orthogonal optimum has det -1; a rotation is returned.
    Rr = f_Procrustes(np.diag([1.0, 1.0, -1.0]) @ Y, Y)
    assert abs(np.linalg.det(Rr) - 1) < 1e-12


# ------------------------------------------------------------------ planes, points, surfaces
def test_normplane_by_hand():
    n, flag = f_normplane(np.array([[1, 0], [0, 1], [0, 0]]), np.array([[0, 2], [3, 0], [0, 0]]))
    np.testing.assert_allclose(n, [[0, 0], [0, 0], [1, -1]])
    np.testing.assert_array_equal(flag, [1, 1])
    n, flag = f_normplane([1, 2, 3], [2, 4, 6])  # parallel: no plane
    np.testing.assert_array_equal(n.ravel(), 0)
    assert flag[0] == 0
    # Homogeneous input (4, N) is dehomogenised: (2, 0, 0, 2) is the point (1, 0, 0).
    n, _ = f_normplane([2, 0, 0, 2], [0, 1, 0, 1])
    np.testing.assert_allclose(n.ravel(), [0, 0, 1])


def test_point_plane_distance_egt_example():
    # EGT's documented example: N = (1, 1, 0), ds = 5, P = (10, 12, 1): |22 / sqrt 2 - 5|.
    np.testing.assert_allclose(f_3Dpointplanedistance([1, 1, 0], 5, [10, 12, 1]), [22 / np.sqrt(2) - 5])
    np.testing.assert_allclose(f_3Dpointplanedistance([0, 0, 2], 1, [[0, 0], [0, 0], [3, -1]]), [2, 2])


def test_randpoint_inside_ball_uniform_and_reproducible():
    P = f_3Drandpoint(20000, [1, 2, 3], 2.0, rng=7)
    assert P.shape == (3, 20000)
    r = np.linalg.norm(P - np.array([[1], [2], [3]]), axis=0)
    assert r.max() <= 2.0
    # Uniform in the ball: P(r < R/2) = 1/8; 20000 draws give a standard error of 0.0023.
    assert abs(np.mean(r < 1.0) - 0.125) < 0.01
    np.testing.assert_array_equal(P, f_3Drandpoint(20000, [1, 2, 3], 2.0, rng=7))


@pytest.mark.parametrize(
    "kind, param, implicit",
    [
        ("plane", (4.0, 2.0), lambda x, y, z: z),
        ("sphere", (2.0,), lambda x, y, z: x * x + y * y + z * z - 4.0),
        ("cylinder", (1.5, 3.0), lambda x, y, z: x * x + y * y - 2.25),
        ("cone", (1.0, 2.0), lambda x, y, z: np.hypot(x, y) - (1 - z / 2.0)),
        ("torus", (3.0, 1.0), lambda x, y, z: (np.hypot(x, y) - 3.0) ** 2 + z * z - 1.0),
    ],
)
def test_surface_points_lie_on_the_surface_with_gradient_normals(kind, param, implicit):
    R = Rotation.from_rotvec([0.2, 0.4, -0.3]).as_matrix()
    t = np.array([10.0, -2.0, 1.0])
    x, y, z, nx, ny, nz = f_3Dsurface(kind, R, t, param, 15)
    assert x.shape == (15, 15)
    P = np.stack([x, y, z], -1).reshape(-1, 3)
    N = np.stack([nx, ny, nz], -1).reshape(-1, 3)
    L = (P - t) @ R  # back to the surface's frame
    np.testing.assert_allclose(implicit(*L.T), 0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1, atol=1e-12)
    # The normal is parallel to the implicit function's gradient (central differences), away from the cone apex.
    h = 1e-6
    grad = np.column_stack([(implicit(*(L + h * e).T) - implicit(*(L - h * e).T)) / (2 * h) for e in np.eye(3)])
    keep = (np.linalg.norm(grad, axis=1) > 1e-3) & (np.hypot(L[:, 0], L[:, 1]) > 1e-3)
    g = grad[keep] / np.linalg.norm(grad[keep], axis=1, keepdims=True)
    np.testing.assert_allclose(np.abs(np.sum(g * (N[keep] @ R), axis=1)), 1, atol=1e-6)


def test_surface_egt_numbers_and_errors():
    x, *_ = f_3Dsurface(1, np.eye(3), [0, 0, 0], 2.0, 5)  # EGT's code: 1 is the sphere
    assert abs(np.max(x) - 2.0) < 1e-12
    with pytest.raises(GeometryError, match="ogg: EGT's object 3 is not available"):
        f_3Dsurface(3)
    with pytest.raises(GeometryError, match=r"params \(radius\): expected a positive"):
        f_3Dsurface("sphere", None, None, -1.0)


# ------------------------------------------------------------------ pin-hole lines
def test_perspline_by_hand_plucker_and_points_on_it():
    H = f_Rt2H(np.eye(3), [0, 0, 0])  # looks along +y, image v along -z
    # Points (0, 10, 0) -> pixel (0, 0); (1, 10, 1) -> (0.1, -0.1): the line u + v = 0.
    l = f_perspline(np.array([[0, 10, 0], [1, 10, 1]], float).T, H, np.eye(3))
    np.testing.assert_allclose(l, [np.sqrt(0.5), np.sqrt(0.5), 0], atol=1e-15)
    K = np.array([[800, 0, 320], [0, 780, 240], [0, 0, 1.0]])
    H = f_Rt2H(rotoy(0.3) @ rotox(-0.2), [1, -2, 0.5])
    A, B = np.array([2.0, 8.0, 1.0]), np.array([-3.0, 12.0, -1.0])
    l = f_perspline(np.column_stack([A, B]), H, K)
    for s in np.linspace(-1, 2, 7):
        u, v = f_perspproj(A + s * (B - A), H, K)
        assert abs(l @ [u[0], v[0], 1]) < 1e-9
    # Plücker coordinates (d, m = X x d) in the camera frame give the same line.
    Rc, tc = H[:3, :3], H[:3, 3]
    Ac, Bc = Rc.T @ (A - tc), Rc.T @ (B - tc)
    d = Bc - Ac
    lp = f_perspline(np.concatenate([d, np.cross(Ac, d)]), H, K)
    assert min(np.abs(lp - l).max(), np.abs(lp + l).max()) < 1e-12


# ------------------------------------------------------------------ catadioptric
def test_lambda_by_hand():
    # Hyperbola a=3, b=1 along the axis: lambda = -e +- a (den = b^2 v_z^2 = 1).
    l1, l2 = f_lambda(3, 1, 1, [0, 0, 1])
    np.testing.assert_allclose([l1[0], l2[0]], [3 - np.sqrt(10), -3 - np.sqrt(10)], atol=1e-14)
    # Parabola h=2 along x: (x^2 - 4)/4 = 0 at x = +-2.
    l1, l2 = f_lambda(2, 0, 2, [1, 0, 0])
    np.testing.assert_allclose([l1[0], l2[0]], [2, -2], atol=1e-14)


@given(st.tuples(finite, finite, finite).filter(lambda v: np.linalg.norm(v) > 1e-3))
def test_lambda_roots_lie_on_the_quadric(v):
    a, b, e = 3.0, 1.0, np.sqrt(10.0)
    for lam in f_lambda(a, b, 1, np.array(v)):
        X = lam[0] * np.array(v)
        if np.isfinite(X).all() and np.abs(X).max() < 1e6:
            lhs = (X[2] + e) ** 2 / a**2 - (X[0] ** 2 + X[1] ** 2) / b**2
            assert abs(lhs - 1) < 1e-7 * max(1, np.abs(X).max() ** 2)


def test_projectmir_root_by_hand_including_points_above_the_focus():
    a, b, e = 3.0, 1.0, np.sqrt(10.0)
    for X in ([1.0, 0.5, -2.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.3]):
        d = np.array(X)
        # The ray's hit on the sheet z = -e + a sqrt(1 + r^2/b^2), lambda > 0, by bracketing.
        f = lambda lam: lam * d[2] + e - a * np.sqrt(1 + (lam * np.hypot(d[0], d[1]) / b) ** 2)  # noqa: E731
        lam = brentq(f, 1e-9, 0.5)
        np.testing.assert_allclose(f_projectmir(a, b, 1, d)[:, 0], lam * d, atol=1e-12)
    # Steeper than the asymptote (blind cone): no image.
    assert np.isnan(f_projectmir(a, b, 1, [0.0, 0.0, 5.0])).all()


def test_catmod_by_hand():
    # ell = m = 0.5, K = I, point on the equator: x_s = (1,0,0), lambda = 0.5, xt = (2, 0, -1).
    x, xt, p = f_catmod([1, 0, 0], np.eye(3), [0, 0, 0], 0.5, 0.5, np.eye(3))
    np.testing.assert_allclose(x[:, 0], [1, 0, 0])
    np.testing.assert_allclose(xt[:, 0], [2, 0, -1])
    np.testing.assert_allclose(p[:, 0], [2, 0, 1])


@pytest.mark.parametrize("mirror", [HyperbolicMirror(3.0, 1.0), HyperbolicMirror(0.04, 0.02), ParabolicMirror(0.5)])
def test_catmod_equals_mirror_projection(mirror):
    """Two independent routes: the sphere model (xi, gamma) and the ray-mirror intersection."""
    H = pose(rotoz(0.6) @ rotox(0.2), [1.0, -2.0, 0.5])
    rng = np.random.default_rng(11)
    P = H[:3, 3][:, None] + rng.uniform(-5, 5, (3, 40))
    is_parabola = isinstance(mirror, ParabolicMirror)
    a, b, quadric = (mirror.h, 1.0, 2) if is_parabola else (mirror.a, mirror.b, 1)
    m, _ = f_panproj(P, H, K_PAN, a, b, quadric)
    _, _, p = f_catmod(P, H[:3, :3], H[:3, 3], mirror.xi, mirror.gamma - mirror.xi, K_PAN)
    seen = ~np.isnan(m[0])
    assert seen.sum() > 10
    np.testing.assert_allclose(p[:, seen], m[:, seen], atol=1e-8)


@given(
    st.tuples(finite, finite, finite).filter(lambda v: np.linalg.norm(v) > 1e-2),
    st.floats(0.0, 1.0),
    st.floats(0.1, 3.0),
)
def test_backcatmod_inverts_catmod(X, ell, m):
    x, _, p = f_catmod(np.array(X), np.eye(3), [0, 0, 0], ell, m, K_PAN)
    if x[2, 0] < ell - 1e-3:  # points at the projection centre have no image
        np.testing.assert_allclose(f_backcatmod(p, m, ell, K_PAN), x, atol=1e-8)


def test_daqaXhmir_inverts_panproj():
    rng = np.random.default_rng(2)
    P = rng.uniform(-5, 5, (3, 30))
    for a, b, quadric in ((3.0, 1.0, 1), (0.5, 1.0, 2)):
        m, Xh = f_panproj(P, np.eye(4), K_PAN, a, b, quadric)
        seen = ~np.isnan(m[0])
        assert seen.sum() > 10
        np.testing.assert_allclose(f_daqaXhmir(m[:, seen], K_PAN, a, b, quadric), Xh[:, seen], atol=1e-9)
    # A pixel far outside the rim's image has no mirror point.
    assert np.isnan(f_daqaXhmir([5000.0, 5000.0], K_PAN)).all()


def test_findepipoles_by_hand():
    # Other focus along +x: the horizontal ray meets z = 0 = -e + a sqrt(1 + r^2/b^2) at r = b^2/a = 1/3;
    # the CCD is 2e below: u = 320 + 1000 (1/3) / (2 sqrt 10).
    qe1, qe2, e1, e2 = f_findepipoles([10, 0, 0], 3, 1, K_PAN)
    np.testing.assert_allclose(e1, [1 / 3, 0, 0], atol=1e-12)
    np.testing.assert_allclose(e2, [-1 / 3, 0, 0], atol=1e-12)
    du = 1000 / 3 / (2 * np.sqrt(10))
    np.testing.assert_allclose(qe1, [320 + du, 240, 1], atol=1e-9)
    np.testing.assert_allclose(qe2, [320 - du, 240, 1], atol=1e-9)


def test_panparconic_circle_by_hand_and_through_the_images():
    h, K = 0.5, np.array([[800, 0, 320], [0, 800, 240], [0, 0, 1.0]])
    H = pose(rotoz(0.4), [0.2, 0.1, 0.0])
    P = np.array([[1.0, 0.3, -1.0], [0.2, 1.5, -2.0]]).T
    cx, cy, r, n, _ = f_panparconic(P, H, K, h, 1.0, 2)
    # Stereographic image of a great circle with normal n: centre -h (nx, ny)/nz, radius h/|nz| (then K).
    Pl = (P.T - H[:3, 3]) @ H[:3, :3]
    n_hand = np.cross(Pl[1], Pl[0])
    n_hand /= np.linalg.norm(n_hand)
    np.testing.assert_allclose(np.abs(n @ n_hand), 1, atol=1e-12)
    np.testing.assert_allclose([cx, cy], [320 - 800 * h * n_hand[0] / n_hand[2], 240 - 800 * h * n_hand[1] / n_hand[2]])
    np.testing.assert_allclose(r, 800 * h / abs(n_hand[2]))
    m, _ = f_panproj(P, H, K, h, 1.0, 2)
    np.testing.assert_allclose(np.hypot(m[0] - cx, m[1] - cy), r, rtol=1e-10)
    with pytest.raises(GeometryError, match="quadric: f_panparconic is for a parabolic mirror"):
        f_panparconic(P, H, K, 3.0, 1.0, 1)


def test_panE_by_hand_and_constraint():
    # Mirror 2 one metre along +x of mirror 1, same orientation: R = I, t = R2^T (t1 - t2) = (-1, 0, 0).
    E = f_panE(np.eye(4), pose(np.eye(3), [1, 0, 0]))
    np.testing.assert_allclose(E, [[0, 0, 0], [0, 0, 1], [0, -1, 0]], atol=1e-15)
    H1, H2 = pose(rotoz(0.5), [-1, 0.5, 0.2]), pose(rotoz(-0.3) @ rotox(0.1), [1.0, 1.0, 0.0])
    E = f_panE(H1, H2)
    P = np.random.default_rng(4).uniform(-4, 4, (3, 20))
    _, X1 = f_panproj(P, H1)
    _, X2 = f_panproj(P, H2)
    seen = ~np.isnan(X1[0]) & ~np.isnan(X2[0])
    assert seen.sum() > 5
    res = np.einsum("in,ij,jn->n", X2[:, seen], E, X1[:, seen])
    np.testing.assert_allclose(res, 0, atol=1e-12)
    # One argument: the relative pose of mirror 2 in mirror 1's frame.
    H12 = np.linalg.inv(H1) @ H2
    np.testing.assert_allclose(f_panE(H12), f_panE(H1, H2) @ H1[:3, :3].T @ H1[:3, :3], atol=1e-12)


def test_panEestim_recovers_E_with_outliers():
    H1, H2 = pose(rotoz(0.5), [-1, 0.5, 0.2]), pose(rotoz(-0.3), [1.0, 1.0, 0.1])
    rng = np.random.default_rng(8)
    P = rng.uniform(-4, 4, (3, 200))
    _, X1 = f_panproj(P, H1)
    _, X2 = f_panproj(P, H2)
    seen = ~np.isnan(X1[0]) & ~np.isnan(X2[0])
    X1, X2 = X1[:, seen], X2[:, seen]
    n = X1.shape[1]
    bad = rng.choice(n, n // 5, replace=False)
    X2[:, bad] = rng.uniform(-1, 1, (3, len(bad)))
    E, flags = f_panEestim(np.vstack([X1, X2]))
    E_true = f_panE(H1, H2)
    E_true /= np.linalg.norm(E_true)
    assert min(np.abs(E - E_true).max(), np.abs(E + E_true).max()) < 1e-6
    assert flags[bad].sum() <= 1 and flags.sum() >= n - len(bad) - 1


def test_festim_robust_numbers_with_outliers():
    H1, H2 = f_Rt2H(rotoz(np.pi / 4), [-10, -10, 0]), f_Rt2H(np.eye(3), [0, 0, 0])
    K = np.array([[800, 0, 320], [0, 800, 240], [0, 0, 1.0]])
    _, _, F = f_epipole(H1, H2, K, K)
    rng = np.random.default_rng(1)
    Xw = np.vstack([rng.uniform(-5, 5, 80), rng.uniform(8, 16, 80), rng.uniform(-3, 3, 80)])
    U1, U2 = f_perspproj(Xw, H1, K), f_perspproj(Xw, H2, K)
    U2[:, :16] += rng.uniform(-80, 80, (2, 16))  # 20% gross outliers
    for algorithm in (4, 5, 6, 7, "ransac", "mapsac"):
        Fe = f_Festim(U1, U2, algorithm)
        assert min(np.linalg.norm(Fe - F), np.linalg.norm(Fe + F)) < 1e-5, algorithm


# ------------------------------------------------------------------ EGT's signatures and drawing
def test_perspproj_returns_one_array_that_unpacks():
    H = f_Rt2H(np.eye(3), [0, 0, 0])
    U = f_perspproj(np.array([[1.0, 5.0, 0.0], [0.0, 10.0, -2.0]]).T, H, np.eye(3))
    assert isinstance(U, np.ndarray) and U.shape == (2, 2)
    u, v = U
    np.testing.assert_allclose(u, [0.2, 0.0])
    np.testing.assert_allclose(v, [0.0, 0.2])


def test_plot_arguments_are_accepted_and_reach_the_figure(monkeypatch):
    calls = []
    fake = types.ModuleType("egtviz.egt_figure")
    fake.draw = lambda kind, **data: calls.append((kind, data))
    monkeypatch.setitem(sys.modules, "egtviz.egt_figure", fake)
    H1, H2 = f_Rt2H(rotoz(np.pi / 4), [-10, -10, 0]), f_Rt2H(np.eye(3), [0, 0, 0])
    P = np.array([[0, 10, 10], [-10, 5, 5]], float).T
    U1 = f_perspproj(P, H1, np.eye(3), 1)
    U2 = f_perspproj(P, H2, np.eye(3), 2)
    _, _, F = f_epipole(H1, H2, np.eye(3), np.eye(3))
    f_epipline(U1, U2, F, 1, 2, 3, "b:")
    f_panproj(P, pose(np.eye(3), [0, 0, 0]), K_PAN, 3, 1, 1, "g")
    kinds = [k for k, _ in calls]
    assert kinds == ["image_points", "image_points", "projection_rays", "epipolar_lines", "epipolar_lines",
                     "panoramic_points"]
    lines = [d for k, d in calls if k == "epipolar_lines"]
    assert [d["figure"] for d in lines] == [2, 3] and {d["style"] for d in lines} == {"b:"}
    np.testing.assert_allclose(calls[0][1]["pixels"], U1)


def test_plot_arguments_without_a_figure_module_do_nothing(monkeypatch):
    monkeypatch.setitem(sys.modules, "egtviz.egt_figure", None)  # import raises ModuleNotFoundError
    H = f_Rt2H(np.eye(3), [0, 0, 0])
    U = f_perspproj([0.0, 5.0, 0.0], H, np.eye(3), 1, "r*")
    np.testing.assert_allclose(U.ravel(), [0, 0])
    f_epipline(U, U, np.eye(3), 1, 2, 3, "b:")


@pytest.mark.parametrize("extra", [(1,), (2, "r*"), ("b:",), (None,), (1, 2, 3, "b:", [1, 2]), (np.nan, {})])
def test_odd_plot_arguments_never_raise(extra, monkeypatch):
    monkeypatch.setitem(sys.modules, "egtviz.egt_figure", None)
    H1, H2 = f_Rt2H(rotoz(np.pi / 4), [-10, -10, 0]), f_Rt2H(np.eye(3), [0, 0, 0])
    P = np.array([[0, 10, 10], [-10, 5, 5]], float).T
    U1, U2 = f_perspproj(P, H1, np.eye(3), *extra), f_perspproj(P, H2, np.eye(3), *extra)
    np.testing.assert_array_equal(U1, f_perspproj(P, H1, np.eye(3)))
    _, _, F = f_epipole(H1, H2, np.eye(3), np.eye(3))
    f_epipline(U1, U2, F, *extra)
    f_panproj(P, np.eye(4), None, 3, 1, 1, *extra)
    f_reflpoint([0, 1, 0], 0, P, *extra)
    f_reflcamera([0, 1, 0], 0, H1, *extra)
    f_3Dsurface("sphere", None, None, None, 5, *extra)
    f_catmod(P, np.eye(3), [0, 0, 0], 0.5, 0.5, np.eye(3), *extra)
    f_perspline(P, H2, np.eye(3), *extra)


def test_panproj_quadric_positional_and_keyword():
    P = np.array([[1.0, 0.5, -1.0]]).T
    m_pos, _ = f_panproj(P, np.eye(4), K_PAN, 0.5, 1.0, 2)
    m_kw, _ = f_panproj(P, np.eye(4), K_PAN, a=0.5, quadric=2)
    np.testing.assert_array_equal(m_pos, m_kw)
    # Parabola by hand: lambda = h (z + |X|) / (x^2 + y^2), m = K (lambda x, lambda y, 1).
    X = P[:, 0]
    lam = 0.5 * (X[2] + np.linalg.norm(X)) / (X[0] ** 2 + X[1] ** 2)
    np.testing.assert_allclose(m_pos[:, 0], K_PAN @ [lam * X[0], lam * X[1], 1])


BAD = [None, "abc", np.nan, [[1, 2], [3]], True, 1j, []]


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda x: f_perspproj(x, np.eye(4), np.eye(3)), "Xw"),
        (lambda x: f_perspproj([0, 1, 0], x, np.eye(3)), "H"),
        (lambda x: f_perspproj([0, 1, 0], np.eye(4), x), "K"),
        (lambda x: f_panproj(x, np.eye(4)), "Xw"),
        (lambda x: f_epipline(x, [1, 1], np.eye(3)), "m1"),
        (lambda x: f_epipline([1, 1], [1, 1], x), "F"),
        (lambda x: f_Festim(x, np.zeros((2, 8))), "U1"),
        (lambda x: f_skew(x), "v"),
        (lambda x: f_E2Motion(x), "E"),
        (lambda x: f_normalize(x), "U"),
        (lambda x: f_forcerank2(x), "M"),
        (lambda x: f_stack(x), "M"),
        (lambda x: f_atan(x, 1.0), "y"),
        (lambda x: f_panE(x), "H1"),
        (lambda x: f_panEestim(x), "M"),
        (lambda x: f_catmod(x, np.eye(3), [0, 0, 0], 0.5, 0.5, np.eye(3)), "P"),
        (lambda x: f_backcatmod(x, 0.5, 0.5, np.eye(3)), "p"),
        (lambda x: f_lambda(3, 1, 1, x), "v"),
        (lambda x: f_projectmir(x, 1, 1, [1, 0, 0]), "a"),
        (lambda x: f_daqaXhmir(x), "Q"),
        (lambda x: f_findepipoles(x), "F"),
        (lambda x: f_panparconic(x, np.eye(4), None, 0.5, 1, 2), "P"),
        (lambda x: f_perspline(x, np.eye(4), np.eye(3)), "U"),
        (lambda x: f_normplane(x, [1, 0, 0]), "X1"),
        (lambda x: f_3Dpointplanedistance(x, 1.0, [1, 0, 0]), "normal"),
        (lambda x: f_Procrustes(x, np.eye(3)), "X"),
        (lambda x: f_3Drandpoint(x, [0, 0, 0], 1), "n"),
        (lambda x: f_3Dsurface("sphere", None, None, [x]), "params"),
        (lambda x: f_3Dsurface("sphere", [x]), "R"),
        (lambda x: f_Rt2H(x, [0, 0, 0]), "R"),
        (lambda x: f_Rt2H(np.eye(3), x), "t"),
        (lambda x: f_epipole(x, np.eye(4), np.eye(3), np.eye(3)), "H1"),
        (lambda x: f_epipole(np.eye(4), np.eye(4), np.eye(3), x), "K2"),
        (lambda x: f_panepipoles(x, np.eye(4)), "H1"),
        (lambda x: f_epipconics(x, np.eye(4), np.eye(4)), "Xw"),
        (lambda x: f_panproj([0, 0, 1], np.eye(4), None, 3, 1, x), "quadric"),
        (lambda x: f_reflmatrix(x, 0.0), "normal"),
        (lambda x: f_reflmatrix([0, 0, 1], x), "distance"),
        (lambda x: f_reflpoint([0, 0, 1], 0.0, x), "points"),
        (lambda x: f_reflcamera([0, 0, 1], 0.0, x), "H"),
        (lambda x: f_reflpersproj([0, 0, 1], 0.0, np.eye(4), np.eye(3), x), "points"),
        (lambda x: f_reflFestim(x, np.zeros((2, 3))), "U"),
    ],
)
@pytest.mark.parametrize("bad", BAD, ids=["None", "str", "nan", "ragged", "bool", "complex", "empty"])
def test_every_function_names_the_bad_argument(call, name, bad):
    with pytest.raises(GeometryError, match=rf"^{name}\b"):
        call(bad)


@pytest.mark.parametrize("scale", [1e-200, 1e200])
def test_quantities_up_to_scale_give_the_same_result_at_any_scale(scale):
    H1, H2 = f_Rt2H(rotoz(np.pi / 4), [-10, -10, 0]), f_Rt2H(np.eye(3), [0, 0, 0])
    _, _, F = f_epipole(H1, H2, np.eye(3), np.eye(3))
    m = np.array([[0.1, -0.3], [0.2, 0.5]])
    for a, b in zip(f_epipline(m, m, F), f_epipline(m, m, scale * F)):
        # The lines come in F's scale (EGT's): the same lines, scale times longer.
        np.testing.assert_allclose(b / scale, a, rtol=1e-12, atol=1e-14)
    E = f_panE(np.eye(4), pose(rotoz(0.3), [1.0, 2.0, 0.5]))
    sol, sol_scaled = f_E2Motion(E), f_E2Motion(scale * E)
    np.testing.assert_allclose(sol_scaled[:, :3], sol[:, :3], atol=1e-12)
    np.testing.assert_allclose(sol_scaled[:, 3] / scale, sol[:, 3], rtol=1e-12)


def test_epipline_returns_egts_lines_in_the_scale_of_the_given_f():
    # EGT's f_epipline: lp = F * [U; 1] and l = F' * [Up; 1], with F as given (no rescaling).
    F = np.array([[0.0, -2.5, 40.0], [3.0, 0.5, -75.0], [-30.0, 60.0, 7.5]])  # |F| is about 106, max 75
    m1 = np.array([[10.0, 250.0, -4.0], [20.0, 3.5, 100.0]])
    m2 = np.array([[12.0, 240.0, 0.0], [18.0, 7.0, 90.0]])
    l, lp = f_epipline(m1, m2, F)
    l_egt = F.T @ np.vstack([m2, np.ones(3)])
    lp_egt = F @ np.vstack([m1, np.ones(3)])
    np.testing.assert_allclose(l, l_egt, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(lp, lp_egt, rtol=1e-14, atol=1e-12)
    # A written-out entry: lp[:, 0] = F (10, 20, 1) = (-50 + 40, 30 + 10 - 75, -300 + 1200 + 7.5).
    np.testing.assert_allclose(lp[:, 0], [-10.0, -35.0, 907.5], rtol=1e-15)
