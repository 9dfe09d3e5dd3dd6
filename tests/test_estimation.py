"""Tests of the two-view estimators (``egtviz.geometry.fundamental``, ``.essential``, ``.error_metrics``,
``.sampson_refinement``, ``.robust``; triangulation: ``test_triangulation.py``; EGT 2.0's robust
estimators and LMedS on few points: ``test_robust_estimators.py``).

Every scene comes from ``_twoview.make_two_view`` with an explicit
``np.random.default_rng(seed)``; the true ``F`` is built by the fixture from its
own ``R``, ``t``, ``K`` (``F = K2^-T [t]_x R K1^-1``), not by the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry._validate import DegenerateConfigurationError, GeometryError
from egtviz.geometry.epipolar import essential_from_fundamental, fundamental_from_essential
from egtviz.geometry.error_metrics import reprojection_error, sampson_distance, symmetric_epipolar_distance
from egtviz.geometry.essential import decompose_essential, essential_from_correspondences, pose_from_essential
from egtviz.geometry.fundamental import fundamental_7point, fundamental_8point, fundamental_normalized_8point
from egtviz.geometry.matrices import hartley_normalization
from egtviz.geometry.poses import skew
from egtviz.geometry.robust import RobustEstimate, fundamental_lmeds, fundamental_ransac
from egtviz.geometry.sampson_refinement import fundamental_sampson

try:
    from tests._twoview import f_distance, make_two_view, transfer_error, true_sampson, true_symmetric, unit_sign
except ImportError:  # tests/ run as a plain directory
    from _twoview import f_distance, make_two_view, transfer_error, true_sampson, true_symmetric, unit_sign

LINEAR = [fundamental_8point, fundamental_normalized_8point, fundamental_sampson]
seeds = st.integers(min_value=0, max_value=2**32 - 1)


def assert_canonical_rank2(F: np.ndarray) -> None:
    assert F.shape == (3, 3)
    s = np.linalg.svd(F, compute_uv=False)
    assert s[2] <= 1e-12 * s[0]
    assert s[1] > 1e-9 * s[0]
    assert np.linalg.norm(F) == pytest.approx(1.0, abs=1e-12)
    assert F.flat[np.argmax(np.abs(F))] > 0


def normalized_residual(F: np.ndarray, U1: np.ndarray, U2: np.ndarray) -> np.ndarray:
    """|m2^T F m1| / (|m1| |F| |m2|): the scale-free algebraic error."""
    h1 = np.c_[U1, np.ones(len(U1))]
    h2 = np.c_[U2, np.ones(len(U2))]
    e = np.abs(np.sum(h2 * (h1 @ F.T), axis=1))
    return e / (np.linalg.norm(h1, axis=1) * np.linalg.norm(h2, axis=1) * np.linalg.norm(F))


# --------------------------------------------------------------------------- noise-free properties


@settings(max_examples=25, deadline=None)
@given(seed=seeds, n=st.integers(min_value=8, max_value=60), algo=st.sampled_from(LINEAR))
def test_linear_estimators_exact_on_noise_free_data(seed: int, n: int, algo) -> None:
    scene = make_two_view(np.random.default_rng(seed), n)
    F = algo(scene.U1, scene.U2)
    assert_canonical_rank2(F)
    assert np.max(normalized_residual(F, scene.U1, scene.U2)) < 1e-10
    assert np.max(sampson_distance(F, scene.U1, scene.U2)) < 1e-10
    # Canonical sign and scale: equal to the true F, not just proportional.
    assert np.allclose(F, scene.F, atol=1e-6)


@settings(max_examples=25, deadline=None)
@given(seed=seeds)
def test_7point_has_the_true_solution(seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 7)
    sols = fundamental_7point(scene.U1, scene.U2)
    assert len(sols) in (1, 3)
    for F in sols:
        assert_canonical_rank2(F)
        assert np.max(normalized_residual(F, scene.U1, scene.U2)) < 1e-9
    assert min(f_distance(F, scene.F) for F in sols) < 1e-7


@settings(max_examples=10, deadline=None)
@given(seed=seeds)
def test_robust_estimators_exact_on_noise_free_inliers(seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 120, outlier_ratio=0.25)
    for est in (fundamental_ransac(scene.U1, scene.U2), fundamental_lmeds(scene.U1, scene.U2)):
        assert_canonical_rank2(est.F)
        assert f_distance(est.F, scene.F) < 1e-6
        assert np.array_equal(est.inliers, scene.inliers)


# --------------------------------------------------------------------------- noisy data


def test_normalization_helps_on_average() -> None:
    errs_raw, errs_norm = [], []
    for seed in range(20):
        scene = make_two_view(np.random.default_rng(seed), 40, noise=1.0)
        errs_raw.append(transfer_error(fundamental_8point(scene.U1, scene.U2), scene))
        errs_norm.append(transfer_error(fundamental_normalized_8point(scene.U1, scene.U2), scene))
    assert np.mean(errs_norm) <= np.mean(errs_raw)
    assert np.mean(errs_norm) < 2.0


@pytest.mark.parametrize("seed", range(8))
def test_sampson_refinement_does_not_increase_the_cost(seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 60, noise=1.0)
    F8 = fundamental_normalized_8point(scene.U1, scene.U2)
    Fs = fundamental_sampson(scene.U1, scene.U2)
    assert_canonical_rank2(Fs)
    c8 = true_sampson(F8, scene.U1, scene.U2).sum()
    cs = true_sampson(Fs, scene.U1, scene.U2).sum()
    assert cs <= c8 * (1 + 1e-12)
    # From a poor start (the unnormalised estimate) too.
    Fr = fundamental_8point(scene.U1, scene.U2)
    Fr2 = fundamental_sampson(scene.U1, scene.U2, F0=Fr)
    assert true_sampson(Fr2, scene.U1, scene.U2).sum() <= true_sampson(Fr, scene.U1, scene.U2).sum() * (1 + 1e-12)
    assert_canonical_rank2(Fr2)


def test_sampson_refinement_improves_on_average() -> None:
    gain = []
    for seed in range(10):
        scene = make_two_view(np.random.default_rng(100 + seed), 30, noise=1.0)
        c8 = sampson_distance(fundamental_normalized_8point(scene.U1, scene.U2), scene.U1, scene.U2).sum()
        cs = sampson_distance(fundamental_sampson(scene.U1, scene.U2), scene.U1, scene.U2).sum()
        gain.append(c8 - cs)
    assert np.all(np.array(gain) >= 0) and np.mean(gain) > 0


# --------------------------------------------------------------------------- robust estimation


@pytest.mark.parametrize("method", ["ransac", "lmeds"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_robust_recovers_inliers_with_30_percent_outliers(method: str, seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 400, noise=0.3, outlier_ratio=0.3)
    fn = fundamental_ransac if method == "ransac" else fundamental_lmeds
    est = fn(scene.U1, scene.U2, seed=7)
    assert isinstance(est, RobustEstimate)
    assert est.inliers.shape == (400,) and est.inliers.dtype == bool
    true_in = scene.inliers
    recall = (est.inliers & true_in).sum() / true_in.sum()
    false_in = (est.inliers & ~true_in).sum()
    assert recall >= 0.95
    assert false_in <= 0.02 * (~true_in).sum()
    assert transfer_error(est.F, scene) < 0.3
    assert 0 < est.iterations <= 2000
    # Deterministic for a seed.
    again = fn(scene.U1, scene.U2, seed=7)
    assert np.array_equal(again.F, est.F) and np.array_equal(again.inliers, est.inliers)
    assert again.iterations == est.iterations


def test_ransac_adaptive_bound_stops_early() -> None:
    scene = make_two_view(np.random.default_rng(5), 300, noise=0.3, outlier_ratio=0.1)
    est = fundamental_ransac(scene.U1, scene.U2)
    assert est.iterations < 200  # w ~ 0.9: a few dozen samples suffice
    capped = fundamental_ransac(scene.U1, scene.U2, max_iterations=10)
    assert capped.iterations == 10


def test_robust_result_is_frozen() -> None:
    scene = make_two_view(np.random.default_rng(0), 50)
    est = fundamental_ransac(scene.U1, scene.U2)
    with pytest.raises(AttributeError):
        est.F = np.eye(3)  # type: ignore[misc]


# --------------------------------------------------------------------------- error measures


@settings(max_examples=15, deadline=None)
@given(seed=seeds)
def test_error_measures_match_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    scene = make_two_view(rng, 30, noise=2.0)
    F = scene.F * rng.uniform(0.1, 10.0) * rng.choice([-1.0, 1.0])  # scale-free
    ds = sampson_distance(F, scene.U1, scene.U2)
    dsym = symmetric_epipolar_distance(F, scene.U1, scene.U2)
    assert ds.shape == dsym.shape == (30,)
    assert np.allclose(ds, true_sampson(scene.F, scene.U1, scene.U2), rtol=1e-9)
    assert np.allclose(dsym, true_symmetric(scene.F, scene.U1, scene.U2), rtol=1e-9)
    # (1/a + 1/b)(a + b) >= 4: the symmetric distance bounds four Sampson distances.
    assert np.all(dsym >= 4 * ds * (1 - 1e-12))
    assert np.allclose(sampson_distance(F, scene.U1_true, scene.U2_true), 0.0, atol=1e-16)


def test_reprojection_error() -> None:
    scene = make_two_view(np.random.default_rng(3), 20)
    r = reprojection_error(scene.P1, scene.P2, scene.X, scene.U1, scene.U2)
    assert r.shape == (20,) and np.max(r) < 1e-9
    shifted = scene.U1 + np.array([3.0, 4.0])
    r = reprojection_error(scene.P1, scene.P2, scene.X, shifted, scene.U2)
    assert np.allclose(r, np.sqrt(25.0 / 2.0))


# --------------------------------------------------------------------------- essential matrix


def test_essential_fundamental_round_trip() -> None:
    scene = make_two_view(np.random.default_rng(11), 10)
    E = essential_from_fundamental(scene.F, scene.K1, scene.K2)
    assert f_distance(E, scene.E) < 1e-9
    s = np.linalg.svd(E, compute_uv=False)
    assert s[0] == pytest.approx(s[1], rel=1e-9) and s[2] < 1e-12
    F = fundamental_from_essential(E, scene.K1, scene.K2)
    assert f_distance(F, scene.F) < 1e-12


@settings(max_examples=15, deadline=None)
@given(seed=seeds)
def test_decompose_essential_and_cheirality(seed: int) -> None:
    scene = make_two_view(np.random.default_rng(seed), 30)
    t_unit = scene.t / np.linalg.norm(scene.t)
    sols = decompose_essential(3.7 * scene.E)
    assert len(sols) == 4
    for R, t in sols:
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.linalg.det(R) == pytest.approx(1.0)
        assert np.linalg.norm(t) == pytest.approx(1.0)
        assert f_distance(skew(t) @ R, scene.E) < 1e-9
    matches = [np.allclose(R, scene.R, atol=1e-9) and np.allclose(t, t_unit, atol=1e-9) for R, t in sols]
    assert sum(matches) == 1
    x1n = (np.c_[scene.U1, np.ones(30)] @ np.linalg.inv(scene.K1).T)[:, :2]
    x2n = (np.c_[scene.U2, np.ones(30)] @ np.linalg.inv(scene.K2).T)[:, :2]
    for sign in (1.0, -1.0):  # E and -E describe the same geometry
        R, t, mask = pose_from_essential(sign * scene.E, x1n, x2n)
        assert np.allclose(R, scene.R, atol=1e-9)
        assert np.allclose(t, t_unit, atol=1e-9)
        assert mask.all()


# --------------------------------------------------------------------------- error paths


@pytest.fixture
def pts() -> tuple[np.ndarray, np.ndarray]:
    scene = make_two_view(np.random.default_rng(0), 12)
    return scene.U1, scene.U2


@pytest.mark.parametrize("fn", [fundamental_8point, fundamental_normalized_8point, fundamental_sampson])
def test_errors_linear(fn, pts) -> None:
    U1, U2 = pts
    with pytest.raises(GeometryError, match=r"U1: expected shape \(N, 2\)"):
        fn(np.c_[U1, np.ones(12)], U2)
    bad = U2.copy()
    bad[3, 1] = np.nan
    with pytest.raises(GeometryError, match="U2: contains NaN or inf"):
        fn(U1, bad)
    with pytest.raises(GeometryError, match="U1: needs at least 8 points, got 7"):
        fn(U1[:7], U2[:7])
    with pytest.raises(GeometryError, match="same number of points, got 12 and 11"):
        fn(U1, U2[:11])
    with pytest.raises(DegenerateConfigurationError, match="U1: all points coincide"):
        fn(np.tile([100.0, 200.0], (12, 1)), U2)
    line = np.c_[np.linspace(10, 600, 12), np.linspace(20, 400, 12)]
    with pytest.raises(DegenerateConfigurationError, match="rank < 8"):
        fn(line, U2)


def test_errors_other(pts) -> None:
    U1, U2 = pts
    with pytest.raises(GeometryError, match="exactly 7 points, got 8"):
        fundamental_7point(U1[:8], U2[:8])
    with pytest.raises(DegenerateConfigurationError, match="U2: all points coincide"):
        fundamental_7point(U1[:7], np.zeros((7, 2)))
    with pytest.raises(GeometryError, match="confidence"):
        fundamental_ransac(U1, U2, confidence=1.0)
    with pytest.raises(GeometryError, match="threshold"):
        fundamental_ransac(U1, U2, threshold=0.0)
    with pytest.raises(GeometryError, match="max_iterations"):
        fundamental_lmeds(U1, U2, max_iterations=0)
    with pytest.raises(DegenerateConfigurationError, match="coincide"):
        fundamental_lmeds(np.ones((20, 2)), np.ones((20, 2)))
    with pytest.raises(GeometryError, match=r"F0: expected shape \(3, 3\)"):
        fundamental_sampson(U1, U2, F0=np.eye(2))
    with pytest.raises(GeometryError, match="F0: expected a matrix of rank 2"):
        fundamental_sampson(U1, U2, F0=np.outer([1.0, 2, 3], [1.0, 0, 1]))
    with pytest.raises(GeometryError, match="E: is zero"):
        decompose_essential(np.zeros((3, 3)))
    with pytest.raises(GeometryError, match="E: expected an essential matrix of rank 2"):
        decompose_essential(np.diag([1.0, 0.0, 0.0]))
    with pytest.raises(GeometryError, match=r"E: expected shape \(3, 3\)"):
        decompose_essential(np.eye(4))
    with pytest.raises(GeometryError, match="x1n, x2n: expected the same number"):
        pose_from_essential(skew([1.0, 0, 0]), U1[:5] / 800, U2[:4] / 800)
    with pytest.raises(GeometryError, match="F: contains NaN"):
        sampson_distance(np.full((3, 3), np.nan), U1, U2)
    with pytest.raises(GeometryError, match="K1: calibration matrix"):
        essential_from_fundamental(np.eye(3), np.diag([0.0, 1.0, 1.0]), np.eye(3))


def test_reprojection_error_propagates_nan_points() -> None:
    scene = make_two_view(np.random.default_rng(3), 5)
    X = scene.X.copy()
    X[2] = np.nan
    r = reprojection_error(scene.P1, scene.P2, X, scene.U1, scene.U2)
    assert np.isnan(r[2]) and np.all(r[[0, 1, 3, 4]] < 1e-9)
    with pytest.raises(GeometryError, match=r"X: expected shape \(N, 3\)"):
        reprojection_error(scene.P1, scene.P2, X[:, :2], scene.U1, scene.U2)


@pytest.mark.parametrize("robust", ["ransac", "lmeds"])
def test_all_coplanar_scene_is_refused_by_every_estimator(robust):
    # Points on one plane seen by two cameras are related by a homography: F is not determined.
    from egtviz.geometry import GeometryError, Intrinsics, PinholeCamera
    from egtviz.geometry.poses import look_at

    rng = np.random.default_rng(5)
    X = np.column_stack([rng.uniform(-2, 2, 40), np.zeros(40), rng.uniform(-2, 2, 40)])
    c1 = PinholeCamera(look_at([-1, -6, 1], [0, 0, 0]), Intrinsics())
    c2 = PinholeCamera(look_at([1, -6, 1.5], [0, 0, 0]), Intrinsics())
    u1, u2 = c1.project(X).pixels, c2.project(X).pixels
    estimator = fundamental_ransac if robust == "ransac" else fundamental_lmeds
    with pytest.raises(GeometryError, match="degenerate configuration"):
        estimator(u1, u2)
    with pytest.raises(GeometryError, match="degenerate configuration"):
        fundamental_normalized_8point(u1, u2)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_essential_from_calibrated_correspondences(seed):
    scene = make_two_view(np.random.default_rng(seed), 40)
    E = essential_from_correspondences(scene.U1, scene.U2, scene.K1, scene.K2)
    s = np.linalg.svd(E, compute_uv=False)
    np.testing.assert_allclose(s, [np.sqrt(0.5), np.sqrt(0.5), 0.0], atol=1e-12)  # on the essential manifold
    E_true = scene.E / np.linalg.norm(scene.E)
    assert min(np.linalg.norm(E - E_true), np.linalg.norm(E + E_true)) < 1e-6
    # The four-fold decomposition and cheirality give back the true motion.
    x1 = np.linalg.solve(scene.K1, np.column_stack([scene.U1, np.ones(40)]).T).T[:, :2]
    x2 = np.linalg.solve(scene.K2, np.column_stack([scene.U2, np.ones(40)]).T).T[:, :2]
    R, t, in_front = pose_from_essential(E, x1, x2)
    np.testing.assert_allclose(R, scene.R, atol=1e-6)
    np.testing.assert_allclose(t / np.linalg.norm(t), scene.t / np.linalg.norm(scene.t), atol=1e-6)
    assert in_front.all()


# --------------------------------------------------------------------------- hostile input, inputs up to scale


@pytest.fixture(scope="module")
def two_view():
    return make_two_view(np.random.default_rng(2), 20, noise=0.5)


def _public_calls(scene):
    """(function, valid keyword arguments) for every public function of the two-view estimation modules."""
    U1, U2 = scene.U1, scene.U2
    x1 = (np.c_[U1, np.ones(len(U1))] @ np.linalg.inv(scene.K1).T)[:, :2]
    x2 = (np.c_[U2, np.ones(len(U2))] @ np.linalg.inv(scene.K2).T)[:, :2]
    return [
        (fundamental_8point, {"U1": U1, "U2": U2}),
        (fundamental_normalized_8point, {"U1": U1, "U2": U2}),
        (fundamental_sampson, {"U1": U1, "U2": U2, "F0": scene.F}),
        (fundamental_7point, {"U1": U1[:7], "U2": U2[:7]}),
        (fundamental_ransac, {"U1": U1, "U2": U2}),
        (fundamental_lmeds, {"U1": U1, "U2": U2}),
        (sampson_distance, {"F": scene.F, "U1": U1, "U2": U2}),
        (symmetric_epipolar_distance, {"F": scene.F, "U1": U1, "U2": U2}),
        (reprojection_error, {"P1": scene.P1, "P2": scene.P2, "X": scene.X, "U1": U1, "U2": U2}),
        (decompose_essential, {"E": scene.E}),
        (pose_from_essential, {"E": scene.E, "x1n": x1, "x2n": x2}),
        (essential_from_correspondences, {"U1": U1, "U2": U2, "K1": scene.K1, "K2": scene.K2}),
    ]


def test_every_argument_of_every_estimation_function_refuses_bad_values(two_view) -> None:
    from tests._hostile import all_bad_values, assert_rejects

    for func, kwargs in _public_calls(two_view):
        for arg, valid in kwargs.items():
            for label, bad in all_bad_values(valid):
                if arg == "F0" and bad is None:
                    continue  # the default: start from the normalised 8-point estimate
                if func is reprojection_error and arg == "X" and label == "NaN entry":
                    continue  # documented: a NaN point (at infinity) has a NaN error
                assert_rejects(func, kwargs, arg, bad, label=label)


@pytest.mark.parametrize("k", [1e-200, 1e-9, -4.0, 1e200])
def test_matrices_defined_up_to_scale_give_the_same_result(k: float, two_view) -> None:
    s = two_view
    U1, U2 = s.U1, s.U2
    np.testing.assert_allclose(sampson_distance(k * s.F, U1, U2), sampson_distance(s.F, U1, U2), rtol=1e-9)
    np.testing.assert_allclose(
        symmetric_epipolar_distance(k * s.F, U1, U2), symmetric_epipolar_distance(s.F, U1, U2), rtol=1e-9
    )
    np.testing.assert_allclose(
        reprojection_error(k * s.P1, s.P2 / k, s.X, U1, U2), reprojection_error(s.P1, s.P2, s.X, U1, U2), rtol=1e-10
    )
    for (Ra, ta), (Rb, tb) in zip(decompose_essential(k * s.E), decompose_essential(s.E)):
        np.testing.assert_allclose(Ra, Rb, atol=1e-12)
        assert np.allclose(ta, tb, atol=1e-12) or np.allclose(ta, -tb, atol=1e-12)
    x1 = (np.c_[U1, np.ones(20)] @ np.linalg.inv(s.K1).T)[:, :2]
    x2 = (np.c_[U2, np.ones(20)] @ np.linalg.inv(s.K2).T)[:, :2]
    R, t, mask = pose_from_essential(k * s.E, x1, x2)
    R0, t0, mask0 = pose_from_essential(s.E, x1, x2)
    np.testing.assert_allclose(R, R0, atol=1e-12)
    np.testing.assert_allclose(t, t0, atol=1e-12)
    np.testing.assert_array_equal(mask, mask0)


def test_pixel_magnitudes_that_cannot_be_solved_are_refused(two_view) -> None:
    U1, U2 = two_view.U1, two_view.U2
    with pytest.raises(GeometryError, match="U1: pixel coordinates up to .* unnormalised 8-point"):
        fundamental_8point(U1 * 1e7, U2)
    with pytest.raises(GeometryError, match="U2: pixel coordinates up to .* unnormalised 8-point"):
        fundamental_8point(U1, U2 * 1e-9)
    # The normalised algorithm solves the same pixels (F is covariant with the unit).
    F = fundamental_normalized_8point(U1 * 1e7, U2 * 1e7)
    S = np.diag([1e7, 1e7, 1.0])
    assert f_distance(S @ F @ S, fundamental_normalized_8point(U1, U2)) < 1e-9
    with pytest.raises(GeometryError, match="U1: magnitude .* too large"):
        fundamental_normalized_8point(U1 * 1e120, U2)
    with pytest.raises(GeometryError, match="U2: the points spread over .* F cannot be computed"):
        fundamental_normalized_8point(U1, U2 * 1e-103)


# --------------------------------------------------------------------------- Hartley's normalisation


@settings(max_examples=40, deadline=None)
@given(seed=seeds, n=st.integers(2, 300), spread=st.sampled_from([1e-3, 1.0, 640.0, 1e6]))
def test_hartley_normalization_has_centroid_zero_and_mean_distance_sqrt2(seed: int, n: int, spread: float) -> None:
    # H&Z section 4.4.4 (and OpenCV's and kornia's 8-point): the MEAN distance from the centroid is sqrt 2.
    rng = np.random.default_rng(seed)
    U = rng.uniform(-spread, spread, (n, 2)) + rng.uniform(-10 * spread, 10 * spread, 2)
    Un, T = hartley_normalization(U)
    np.testing.assert_allclose(Un.mean(axis=0), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(Un, axis=1).mean(), np.sqrt(2.0), rtol=1e-12)
    np.testing.assert_allclose((np.c_[U, np.ones(n)] @ T.T)[:, :2], Un, atol=1e-9)
    # The normalised 8-point algorithm uses the same T: its F is T2^T Fn T1 for the F of the normalised points.
    if n >= 8:
        V = rng.uniform(0, 640, (n, 2))
        Vn, T2 = hartley_normalization(V)
        F = fundamental_normalized_8point(U, V)
        np.testing.assert_allclose(
            np.abs(F), np.abs(unit_sign(T2.T @ fundamental_normalized_8point(Un, Vn) @ T)), rtol=1e-6, atol=1e-9
        )


def test_hartley_normalization_by_hand() -> None:
    # Distances 1, 1, 4 and 4 from the centroid (0, 0): mean 2.5, so s = sqrt(2) / 2.5 (the RMS distance,
    # sqrt(8.5), would give s = sqrt(2) / sqrt(8.5)).
    Un, T = hartley_normalization([[1.0, 0.0], [-1.0, 0.0], [0.0, 4.0], [0.0, -4.0]])
    s = np.sqrt(2.0) / 2.5
    np.testing.assert_allclose(T, [[s, 0, 0], [0, s, 0], [0, 0, 1]], atol=1e-15)
    with pytest.raises(DegenerateConfigurationError, match="U: all points coincide"):
        hartley_normalization(np.tile([3.0, 4.0], (5, 1)))


def test_hartley_normalization_of_several_images_is_each_image_on_its_own() -> None:
    rng = np.random.default_rng(11)
    U1, U2 = rng.uniform(0, 640, (30, 2)), rng.uniform(-5, 5, (30, 2))
    (n1, T1), (n2, T2) = hartley_normalization(U1), hartley_normalization(U2)
    for images in ((U1, U2), np.stack([U1, U2]), [U1.T.copy().T, U2]):  # the last: a non-contiguous (N, 2)
        Un, T = hartley_normalization(images, ("U1", "U2"))
        np.testing.assert_array_equal(Un[0], n1)
        np.testing.assert_array_equal(Un[1], n2)
        np.testing.assert_array_equal(T, np.stack([T1, T2]))
    with pytest.raises(DegenerateConfigurationError, match="U2: all points coincide"):
        hartley_normalization((U1, np.ones((30, 2))), ("U1", "U2"))
    with pytest.raises(GeometryError, match="U1: contains NaN"):
        hartley_normalization((np.full((30, 2), np.nan), U2), ("U1", "U2"))
    with pytest.raises(GeometryError, match="U1, U2: expected the same number of points"):
        hartley_normalization((U1, U2[:20]), ("U1", "U2"))


def test_the_checked_helpers_of_the_two_view_modules_name_every_bad_argument(two_view) -> None:
    # The kernels the estimators share (design_matrix, null_vector, ...) take arrays their callers have
    # validated; the helpers that validate (by default) refuse bad values by name, as every estimator does.
    from egtviz.geometry.essential import ray_pairs
    from egtviz.geometry.matrices import nearest_rank2, point_pairs

    try:
        from tests._hostile import all_bad_values, assert_rejects
    except ImportError:  # tests/ run as a plain directory
        from _hostile import all_bad_values, assert_rejects

    rays = np.c_[two_view.U1, np.full(20, 800.0)]
    cases = [
        (point_pairs, {"U1": two_view.U1, "U2": two_view.U2}),
        (hartley_normalization, {"U": two_view.U1}),
        (nearest_rank2, {"M": two_view.F}),
        (lambda d1, d2: ray_pairs(d1, d2, 8), {"d1": rays, "d2": rays + 1.0}),
    ]
    for func, kwargs in cases:
        for arg, valid in kwargs.items():
            for label, bad in all_bad_values(valid):
                assert_rejects(func, kwargs, arg, bad, label=label)


@pytest.mark.parametrize(
    ("where", "value", "match"),
    [
        ("U1", np.nan, "U1: contains NaN or inf"),
        ("U2", -np.inf, "U2: contains NaN or inf"),
        ("U1", 1e120, "U1: magnitude .* too large"),  # one huge point among small ones: the centroid stays small
        ("U2", 1e300, "U2: magnitude .* too large"),
    ],
)
def test_the_normalised_8point_checks_float_arrays_on_the_way(two_view, where, value, match) -> None:
    # Float64 (N, 2) arrays skip the up-front value check; the normalisation must still refuse them by name,
    # before any degeneracy of the other image is reported.
    U = {"U1": two_view.U1.copy(), "U2": two_view.U2.copy()}
    U[where][3, 1] = value
    with pytest.raises(GeometryError, match=match):
        fundamental_normalized_8point(U["U1"], U["U2"])
    other = "U2" if where == "U1" else "U1"
    U[other] = np.tile([5.0, 7.0], (20, 1))  # coincident points: degenerate, but the bad value comes first
    with pytest.raises(GeometryError, match=match):
        fundamental_normalized_8point(U["U1"], U["U2"])
    opposite = two_view.U1.copy()
    opposite[2], opposite[5] = [1e300, 0.0], [-1e300, 0.0]  # the sum cancels; the mean distance does not
    with pytest.raises(GeometryError, match="U1: magnitude .* too large"):
        fundamental_normalized_8point(opposite, two_view.U2)


def test_the_normalised_8point_gives_the_same_f_on_the_fast_and_the_checked_route(two_view) -> None:
    U1, U2 = two_view.U1, two_view.U2
    F_fast = fundamental_normalized_8point(U1, U2)  # float64 arrays: the values checked on the way
    np.testing.assert_array_equal(fundamental_normalized_8point(U1.tolist(), U2.tolist()), F_fast)  # checked first
    U1_32 = U1.astype(np.float32)  # not float64: converted by the up-front check, as a list is
    np.testing.assert_array_equal(
        fundamental_normalized_8point(U1_32, U2), fundamental_normalized_8point(U1_32.tolist(), U2.tolist())
    )
