"""Tests of egtviz.geometry.triangulation.

References are computed here independently of the code under test: the DLT solution by a
per-point ``np.linalg.svd`` of the 4x4 matrix of H&Z section 12.2, written out below; scenes by
``_twoview.make_two_view`` or by the explicit low-parallax rig of ``_low_parallax``.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry._validate import DegenerateConfigurationError, GeometryError
from egtviz.geometry.error_metrics import reprojection_error, sampson_distance
from egtviz.geometry.triangulation import (
    correct_correspondences,
    fundamental_from_projections,
    triangulate_linear,
    triangulate_optimal,
)

try:
    from tests._hostile import all_bad_values, assert_rejects
    from tests._twoview import f_distance, make_two_view
except ImportError:  # tests/ run as a plain directory
    from _hostile import all_bad_values, assert_rejects
    from _twoview import f_distance, make_two_view

seeds = st.integers(min_value=0, max_value=2**32 - 1)
K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def _rotation(w: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(w)
    if th < 1e-15:
        return np.eye(3)
    k = w / th
    S = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(th) * S + (1.0 - np.cos(th)) * S @ S


def _camera(R: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``P = K [R | -R C]`` (world to camera rotation ``R``, centre ``C``)."""
    return K @ np.c_[R, -R @ C]


def _project(P: np.ndarray, X: np.ndarray) -> np.ndarray:
    x = np.c_[X, np.ones(len(X))] @ P.T
    return x[:, :2] / x[:, 2:]


def _dlt_reference(P1: np.ndarray, P2: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """H&Z 12.2 point by point: the right singular vector of the smallest singular value, the P's as given."""
    out = []
    for a, b in zip(u1, u2):
        A = np.array([a[0] * P1[2] - P1[0], a[1] * P1[2] - P1[1], b[0] * P2[2] - P2[0], b[1] * P2[2] - P2[1]])
        v = np.linalg.svd(A)[2][-1]
        out.append(v[:3] / v[3])
    return np.array(out)


def _low_parallax(rng: np.random.Generator, n: int, noise: float, origin: float = 20.0):
    """Two cameras 0.2 m apart looking along +z at points about 20 m away (parallax about 0.6 degrees).

    The rig stands at ``(origin, origin, 0)`` in the world: the homogeneous world points are then
    poorly scaled, and the two smallest singular values of the DLT matrices close, as in any scene
    whose world frame is not at a camera.
    """
    O = np.array([origin, origin, 0.0])
    P1 = _camera(np.eye(3), O)
    P2 = _camera(_rotation(np.array([0.0, -0.01, 0.0])), O + np.array([0.2, 0.0, 0.0]))
    X = O + np.c_[rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(19.0, 21.0, n)]
    u1 = _project(P1, X) + rng.normal(0.0, noise, (n, 2))
    u2 = _project(P2, X) + rng.normal(0.0, noise, (n, 2))
    return P1, P2, X, u1, u2


# --------------------------------------------------------------------------- the DLT solution


@pytest.mark.parametrize("origin", [0.0, 5.0, 20.0])
@pytest.mark.parametrize(("seed", "noise"), [(0, 0.5), (1, 2.0), (2, 1.0)])
def test_linear_triangulation_is_the_svd_solution_at_low_parallax(seed: int, noise: float, origin: float) -> None:
    P1, P2, X, u1, u2 = _low_parallax(np.random.default_rng(seed), 300, noise=noise, origin=origin)
    Xl = triangulate_linear(P1, P2, u1, u2)
    ref = _dlt_reference(P1, P2, u1, u2)
    np.testing.assert_allclose(Xl, ref, rtol=1e-9, atol=0.0)
    # It is the minimiser: |A X| / |X| equals the smallest singular value.
    top = max(np.abs(P1).max(), np.abs(P2).max())
    P1n, P2n = P1 / top, P2 / top
    A = np.stack(
        [
            u1[:, 0:1] * P1n[2] - P1n[0],
            u1[:, 1:2] * P1n[2] - P1n[1],
            u2[:, 0:1] * P2n[2] - P2n[0],
            u2[:, 1:2] * P2n[2] - P2n[1],
        ],
        axis=1,
    )
    Xh = np.c_[Xl, np.ones(len(Xl))]
    resid = np.linalg.norm(np.einsum("nij,nj->ni", A, Xh), axis=1) / np.linalg.norm(Xh, axis=1)
    smallest = np.linalg.svd(A, compute_uv=False)[:, 3]
    np.testing.assert_allclose(resid, smallest, rtol=1e-7)
    # The reprojection error of the DLT point is that of the reference point, to rounding.
    np.testing.assert_allclose(
        reprojection_error(P1, P2, Xl, u1, u2), reprojection_error(P1, P2, ref, u1, u2), rtol=1e-9, atol=1e-12
    )


def test_linear_triangulation_equals_batched_svd() -> None:
    scene = make_two_view(np.random.default_rng(4), 200, noise=2.0)
    X_ref = _dlt_reference(scene.P1, scene.P2, scene.U1, scene.U2)
    np.testing.assert_allclose(triangulate_linear(scene.P1, scene.P2, scene.U1, scene.U2), X_ref, rtol=1e-10)


# OpenCV's answer for a fixed input, kept here so that the comparison holds without OpenCV. Produced by
#
#     import cv2, numpy as np
#     Xh = cv2.triangulatePoints(_PEER_P1, _PEER_P2, _PEER_U1.T.copy(), _PEER_U2.T.copy())
#     print(repr((Xh[:3] / Xh[3]).T))
#
# with opencv-python-headless 5.0 (the inputs: a make_two_view scene of seed 2024, 0.8 px of noise,
# rounded to three decimals, P2 multiplied by 40). Splitting the scale per camera moved these points by
# up to 9e-4 of their size.
_PEER_P1 = np.array([[814.067, 0.0, 316.189, 0.0], [0.0, 823.818, 240.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
_PEER_P2 = np.array(
    [
        [29331.711, 1478.577, 16359.512, 29544.799],
        [-1818.33, 31547.019, 8230.504, 6956.353],
        [-4.769, 2.053, 39.662, 3.01],
    ]
)
_PEER_U1 = np.array(
    [[66.385, 270.995], [3.301, 225.056], [132.43, 212.461], [177.27, 420.293], [134.42, 131.598], [171.296, 33.608]]
)
_PEER_U2 = np.array(
    [[345.473, 275.545], [249.155, 227.777], [356.28, 211.486], [393.174, 397.749], [316.646, 128.728],
     [355.434, 37.116]]
)
_PEER_X_OPENCV = np.array(
    [
        [-1.2832243988086225, 0.14631408366728435, 4.190553093753196],
        [-2.102270430119843, -0.10968331193433141, 5.476215051856359],
        [-1.339495218678166, -0.20789714105900187, 5.944408107168046],
        [-1.0969392657109438, 1.3974690747769791, 6.443661946459427],
        [-1.9990528974932353, -1.1816493066359708, 8.95668842897023],
        [-1.469845456505611, -2.0671595508335723, 8.256092650825448],
    ]
)


def test_linear_triangulation_equals_opencv_recorded() -> None:
    X = triangulate_linear(_PEER_P1, _PEER_P2, _PEER_U1, _PEER_U2)
    np.testing.assert_allclose(X, _PEER_X_OPENCV, rtol=1e-10, atol=0.0)
    # The written-out DLT of the matrices as given agrees as well.
    np.testing.assert_allclose(_dlt_reference(_PEER_P1, _PEER_P2, _PEER_U1, _PEER_U2), _PEER_X_OPENCV, rtol=1e-10)


@settings(max_examples=30, deadline=None)
@given(seed=seeds, power=st.integers(-250, 250), sign=st.sampled_from([1.0, -1.0]), noise=st.floats(0.3, 1.0))
def test_linear_triangulation_is_invariant_to_a_common_scale_only(
    seed: int, power: int, sign: float, noise: float
) -> None:
    rng = np.random.default_rng(seed)
    scene = make_two_view(rng, 40, noise=noise)
    P2 = scene.P2 * rng.uniform(0.05, 20.0)  # the two matrices of different norms, as a caller may pass them
    c = sign * 10.0**power
    base = triangulate_linear(scene.P1, P2, scene.U1, scene.U2)
    np.testing.assert_allclose(triangulate_linear(c * scene.P1, c * P2, scene.U1, scene.U2), base, rtol=1e-10)
    np.testing.assert_allclose(base, _dlt_reference(scene.P1, P2, scene.U1, scene.U2), rtol=1e-9)


@settings(max_examples=15, deadline=None)
@given(seed=seeds)
def test_triangulation_exact_on_noise_free_data(seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 40)
    for tri in (triangulate_linear, triangulate_optimal):
        X = tri(scene.P1, scene.P2, scene.U1, scene.U2)
        assert X.shape == (40, 3)
        np.testing.assert_allclose(X, scene.X, rtol=1e-9, atol=1e-9)
    c1, c2 = correct_correspondences(scene.F, scene.U1, scene.U2)
    np.testing.assert_allclose(c1, scene.U1, atol=1e-8)
    np.testing.assert_allclose(c2, scene.U2, atol=1e-8)


@settings(max_examples=15, deadline=None)
@given(seed=seeds, k1=st.sampled_from([1e-200, 1e-7, -3.0, 1e9, 1e200]), k2=st.sampled_from([1e-200, 0.5, -1.0, 1e200]))
def test_triangulation_does_not_depend_on_the_scale_of_P(seed: int, k1: float, k2: float) -> None:
    # The linear method depends on the two cameras' relative scale (it weighs their equations), not on a
    # common one; the optimal method and the correction depend on neither.
    scene = make_two_view(np.random.default_rng(seed), 30, noise=1.0)
    base = triangulate_linear(scene.P1, scene.P2, scene.U1, scene.U2)
    np.testing.assert_allclose(triangulate_linear(k1 * scene.P1, k1 * scene.P2, scene.U1, scene.U2), base, rtol=1e-10)
    opt = triangulate_optimal(scene.P1, scene.P2, scene.U1, scene.U2)
    np.testing.assert_allclose(triangulate_optimal(k1 * scene.P1, k2 * scene.P2, scene.U1, scene.U2), opt, rtol=1e-9)
    c_base = correct_correspondences(scene.F, scene.U1, scene.U2)
    c_scaled = correct_correspondences(k1 * scene.F, scene.U1, scene.U2)
    np.testing.assert_allclose(c_scaled[0], c_base[0], rtol=1e-10)
    np.testing.assert_allclose(c_scaled[1], c_base[1], rtol=1e-10)


# --------------------------------------------------------------------------- points on the baseline


@settings(max_examples=40, deadline=None)
@given(seed=seeds, where=st.sampled_from(["beyond camera 2", "between", "behind camera 1"]))
def test_a_point_on_the_baseline_is_nan(seed: int, where: str) -> None:
    rng = np.random.default_rng(seed)
    C2 = rng.normal(size=3)
    C2[2] = abs(C2[2]) + 0.3  # a forward component: the baseline points have finite images
    P1 = _camera(np.eye(3), np.zeros(3))
    P2 = _camera(_rotation(rng.normal(0.0, 0.1, 3)), C2)
    low, high = {"beyond camera 2": (1.5, 20.0), "between": (0.1, 0.9), "behind camera 1": (-5.0, -0.1)}[where]
    lam = rng.uniform(low, high)
    X = np.vstack([lam * C2, [0.3, -0.2, 6.0]])  # the second point is off the baseline
    u1, u2 = _project(P1, X), _project(P2, X)
    for tri in (triangulate_linear, triangulate_optimal):
        out = tri(P1, P2, u1, u2)
        assert np.isnan(out[0]).all(), (tri.__name__, out[0])
        np.testing.assert_allclose(out[1], X[1], rtol=1e-9)


def test_a_point_near_the_baseline_is_still_triangulated() -> None:
    P1 = _camera(np.eye(3), np.zeros(3))
    C2 = np.array([0.5, 0.1, 1.0])
    P2 = _camera(np.eye(3), C2)
    X = 8.0 * C2 + np.array([1e-3, 0.0, 0.0])  # 1 mm off the baseline, 8 m away
    u1, u2 = _project(P1, X[None]), _project(P2, X[None])
    np.testing.assert_allclose(triangulate_linear(P1, P2, u1, u2)[0], X, rtol=1e-6)


# --------------------------------------------------------------------------- optimal correction


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_optimal_correction(seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 150, noise=1.5)
    F = fundamental_from_projections(scene.P1, scene.P2)
    assert f_distance(F, scene.F) < 1e-12
    c1, c2 = correct_correspondences(F, scene.U1, scene.U2)
    # Exactly on corresponding epipolar lines: distance of c2 to F c1 in pixels.
    l2 = np.c_[c1, np.ones(150)] @ F.T
    dist = np.abs(np.sum(np.c_[c2, np.ones(150)] * l2, axis=1)) / np.hypot(l2[:, 0], l2[:, 1])
    assert np.max(dist) < 1e-9 * 640
    # The correction is as small as the first-order (Sampson) estimate says.
    moved = np.sum((c1 - scene.U1) ** 2 + (c2 - scene.U2) ** 2, axis=1)
    np.testing.assert_allclose(moved, sampson_distance(F, scene.U1, scene.U2), rtol=1e-3, atol=1e-9)
    X_lin = triangulate_linear(scene.P1, scene.P2, scene.U1, scene.U2)
    X_opt = triangulate_optimal(scene.P1, scene.P2, scene.U1, scene.U2)
    e_lin = reprojection_error(scene.P1, scene.P2, X_lin, scene.U1, scene.U2)
    e_opt = reprojection_error(scene.P1, scene.P2, X_opt, scene.U1, scene.U2)
    assert np.all(e_opt <= e_lin + 1e-9)
    np.testing.assert_allclose(2 * e_opt**2, moved, rtol=1e-6)


def test_optimal_triangulation_beats_linear_at_low_parallax() -> None:
    P1, P2, X, u1, u2 = _low_parallax(np.random.default_rng(9), 200, noise=0.5)
    e_lin = reprojection_error(P1, P2, triangulate_linear(P1, P2, u1, u2), u1, u2)
    e_opt = reprojection_error(P1, P2, triangulate_optimal(P1, P2, u1, u2), u1, u2)
    assert np.all(e_opt <= e_lin + 1e-9)
    assert e_opt.mean() < e_lin.mean()


# --------------------------------------------------------------------------- bad input


@pytest.fixture(scope="module")
def valid() -> dict[str, np.ndarray]:
    scene = make_two_view(np.random.default_rng(0), 12, noise=0.5)
    return {"P1": scene.P1, "P2": scene.P2, "U1": scene.U1, "U2": scene.U2, "F": scene.F}


@pytest.mark.parametrize(
    ("func", "args"),
    [
        (triangulate_linear, ("P1", "P2", "U1", "U2")),
        (triangulate_optimal, ("P1", "P2", "U1", "U2")),
        (correct_correspondences, ("F", "U1", "U2")),
        (fundamental_from_projections, ("P1", "P2")),
    ],
)
def test_every_argument_refuses_bad_values(func, args, valid) -> None:
    kwargs = {a: valid[a] for a in args}
    for arg in args:
        for label, bad in all_bad_values(valid[arg]):
            assert_rejects(func, kwargs, arg, bad, label=label)


def test_errors_triangulation(valid) -> None:
    U1, U2 = valid["U1"], valid["U2"]
    P = np.hstack([np.eye(3), np.zeros((3, 1))])
    with pytest.raises(DegenerateConfigurationError, match="camera centres coincide"):
        triangulate_linear(P, 2.0 * P, U1, U2)
    with pytest.raises(GeometryError, match=r"P2: expected shape \(3, 4\)"):
        triangulate_optimal(P, np.eye(3), U1, U2)
    with pytest.raises(GeometryError, match="P1: is zero"):
        triangulate_linear(np.zeros((3, 4)), P, U1, U2)
    with pytest.raises(GeometryError, match="P1: expected a camera matrix of rank 3"):
        triangulate_linear(np.c_[np.ones((3, 3)), np.zeros(3)], P, U1, U2)
    with pytest.raises(GeometryError, match="same number of points"):
        triangulate_linear(P, P + np.c_[np.zeros((3, 3)), [1.0, 0, 0]], U1, U2[:3])
    with pytest.raises(GeometryError, match="F: expected a fundamental matrix of rank 2"):
        correct_correspondences(np.diag([1.0, 0, 0]), U1, U2)
    # Pixels that can be represented but not computed with.
    with pytest.raises(GeometryError, match="U2: magnitude .* too large"):
        triangulate_linear(valid["P1"], valid["P2"], U1, U2 * 1e150)
