"""OpenCV as an independent oracle for estimation and triangulation.

OpenCV (``opencv-python-headless``) is a test-only dependency. Its conventions
match ours: ``findFundamentalMat`` returns ``F`` with ``x2^T F x1 = 0``,
``recoverPose`` returns ``(R, t)`` with ``X_c2 = R X_c1 + t``, and
``triangulatePoints`` is the homogeneous DLT of the camera matrices as given
(``triangulate_linear`` divides both by one common factor, which leaves that
answer unchanged). Accuracy is compared on the
true inliers as the mean symmetric epipolar distance (pixels) to the
noise-free correspondences of the synthetic scene.
"""

from __future__ import annotations

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

from egtviz.geometry.epipolar import essential_from_fundamental  # noqa: E402
from egtviz.geometry.essential import pose_from_essential  # noqa: E402
from egtviz.geometry.fundamental import fundamental_normalized_8point  # noqa: E402
from egtviz.geometry.mestimator import fundamental_mestimator  # noqa: E402
from egtviz.geometry.robust import fundamental_lmeds, fundamental_mapsac, fundamental_ransac  # noqa: E402
from egtviz.geometry.triangulation import correct_correspondences, triangulate_linear  # noqa: E402

try:
    from tests._twoview import f_distance, make_two_view, transfer_error, true_sampson
except ImportError:  # tests/ run as a plain directory
    from _twoview import f_distance, make_two_view, transfer_error, true_sampson


def test_8point_agrees_with_opencv() -> None:
    scene = make_two_view(np.random.default_rng(21), 200, noise=0.8)
    F_cv, _ = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.FM_8POINT)
    F = fundamental_normalized_8point(scene.U1, scene.U2)
    # Same algorithm (Hartley normalisation, SVD rank-2 projection), same points.
    assert f_distance(F, F_cv) < 1e-6
    assert transfer_error(F, scene) == pytest.approx(transfer_error(F_cv, scene), rel=1e-4)


def test_robust_estimators_match_or_beat_opencv() -> None:
    # Single scenes are noisy comparisons (the estimators trade places), so the
    # accuracy is compared on the mean over six scenes; per scene only a loose bound.
    errs = []
    for seed in range(31, 37):
        scene = make_two_view(np.random.default_rng(seed), 600, noise=0.5, outlier_ratio=0.3)
        ours_r = fundamental_ransac(scene.U1, scene.U2, threshold=1.0)
        ours_l = fundamental_lmeds(scene.U1, scene.U2)
        F_ransac, m_ransac = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.FM_RANSAC, 1.0, 0.999, 2000)
        F_lmeds, _ = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.FM_LMEDS, 1.0, 0.999, 2000)
        F_magsac, _ = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.USAC_MAGSAC, 1.0, 0.999, 2000)
        e = [transfer_error(F, scene) for F in (ours_r.F, ours_l.F, F_magsac, F_ransac, F_lmeds)]
        assert e[0] <= 2.0 * e[2] + 0.05 and e[1] <= 2.0 * e[2] + 0.05
        errs.append(e)
        # OpenCV's FM_RANSAC tests max(d1, d2) < threshold on the two point-line
        # distances, ours the Sampson distance: ours keeps at least as many true
        # inliers, and neither accepts many outliers.
        cv_mask = m_ransac.ravel().astype(bool)
        assert ours_r.inliers[scene.inliers].mean() >= cv_mask[scene.inliers].mean() - 0.02
        assert ours_r.inliers[~scene.inliers].mean() <= 0.02
    ransac, lmeds, magsac, cv_ransac, cv_lmeds = np.mean(errs, axis=0)
    assert ransac <= magsac and lmeds <= magsac
    assert ransac <= cv_ransac and lmeds <= cv_lmeds


def test_recover_pose_agrees_with_opencv() -> None:
    scene = make_two_view(np.random.default_rng(41), 100, noise=0.3)
    K = scene.K1
    # recoverPose takes one camera matrix: use K1 for both images here.
    U2 = (np.c_[scene.U2, np.ones(100)] @ np.linalg.inv(scene.K2).T @ K.T)[:, :2]
    F = fundamental_normalized_8point(scene.U1, U2)
    E = essential_from_fundamental(F, K, K)
    x1n = (np.c_[scene.U1, np.ones(100)] @ np.linalg.inv(K).T)[:, :2]
    x2n = (np.c_[U2, np.ones(100)] @ np.linalg.inv(K).T)[:, :2]
    R, t, mask = pose_from_essential(E, x1n, x2n)
    _, R_cv, t_cv, _ = cv2.recoverPose(E, scene.U1, U2, K)
    assert np.allclose(R, R_cv, atol=1e-9)
    assert np.allclose(t, t_cv.ravel(), atol=1e-9)
    assert mask.mean() > 0.95
    t_true = scene.t / np.linalg.norm(scene.t)
    assert np.linalg.norm(t - t_true) < 0.05
    assert np.linalg.norm(R - scene.R) < 0.01


@pytest.mark.parametrize("seed", range(51, 56))
def test_triangulation_agrees_with_opencv(seed: int) -> None:
    # Both get the camera matrices as given, of different norms (the scale of each weighs its image's
    # equations under noise): the same DLT, so the same points to rounding.
    rng = np.random.default_rng(seed)
    scene = make_two_view(rng, 45, noise=rng.uniform(0.3, 1.0))
    P1, P2 = scene.P1 * rng.uniform(0.01, 1.0), scene.P2 * rng.uniform(1.0, 100.0)
    X = triangulate_linear(P1, P2, scene.U1, scene.U2)
    Xh = cv2.triangulatePoints(P1, P2, scene.U1.T.copy(), scene.U2.T.copy())
    X_cv = (Xh[:3] / Xh[3]).T
    np.testing.assert_allclose(X, X_cv, rtol=1e-10, atol=0.0)


@pytest.mark.parametrize("origin", [0.0, 20.0])
def test_low_parallax_triangulation_agrees_with_opencv(origin: float) -> None:
    # Two cameras 0.2 m apart, points about 20 m away, the rig at (origin, origin, 0).
    rng = np.random.default_rng(52)
    K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
    O = np.array([origin, origin, 0.0])
    P1 = K @ np.c_[np.eye(3), -O]
    P2 = K @ np.c_[np.eye(3), -(O + [0.2, 0.0, 0.0])]
    X = O + np.c_[rng.uniform(-3, 3, 200), rng.uniform(-2, 2, 200), rng.uniform(19, 21, 200)]
    h1 = np.c_[X, np.ones(200)] @ P1.T
    h2 = np.c_[X, np.ones(200)] @ P2.T
    u1 = h1[:, :2] / h1[:, 2:] + rng.normal(0.0, 1.0, (200, 2))
    u2 = h2[:, :2] / h2[:, 2:] + rng.normal(0.0, 1.0, (200, 2))
    Xh = cv2.triangulatePoints(P1, P2, u1.T.copy(), u2.T.copy())
    X_cv = (Xh[:3] / Xh[3]).T
    np.testing.assert_allclose(triangulate_linear(P1, P2, u1, u2), X_cv, rtol=1e-8)


def test_optimal_correction_agrees_with_opencv() -> None:
    scene = make_two_view(np.random.default_rng(61), 200, noise=1.0)
    c1, c2 = correct_correspondences(scene.F, scene.U1, scene.U2)
    c1_cv, c2_cv = cv2.correctMatches(scene.F, scene.U1[None], scene.U2[None])
    assert np.allclose(c1, c1_cv[0], atol=1e-6)
    assert np.allclose(c2, c2_cv[0], atol=1e-6)


def test_epipolar_lines_agree_with_opencv() -> None:
    from egtviz.geometry.epipolar import epipolar_lines

    scene = make_two_view(np.random.default_rng(71), 50, noise=0.5)
    lines = epipolar_lines(scene.F, scene.U1)
    lines = lines / np.hypot(lines[:, 0], lines[:, 1])[:, None]
    lines_cv = cv2.computeCorrespondEpilines(scene.U1.reshape(-1, 1, 2), 1, scene.F).reshape(-1, 3)
    sign = np.sign(np.sum(lines * lines_cv, axis=1))[:, None]
    assert np.allclose(lines, sign * lines_cv, atol=1e-6)


@pytest.mark.parametrize("n", range(8, 14))
def test_lmeds_on_8_to_13_points_is_at_least_as_good_as_opencv(n: int) -> None:
    # Accuracy: RMS Sampson distance of the estimate on the noise-free correspondences (pixels),
    # averaged over 20 scenes with 0.5 px noise. Single scenes trade places (the estimators draw
    # different samples), so the margin is on the mean: ours must not exceed OpenCV's FM_LMEDS.
    ours, theirs = [], []
    for seed in range(20):
        scene = make_two_view(np.random.default_rng(1000 * n + seed), n, noise=0.5)
        est = fundamental_lmeds(scene.U1, scene.U2)
        F_cv, _ = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.FM_LMEDS, 1.0, 0.999)
        assert F_cv is not None and F_cv.shape == (3, 3)
        ours.append(np.sqrt(true_sampson(est.F, scene.U1_true, scene.U2_true).mean()))
        theirs.append(np.sqrt(true_sampson(F_cv, scene.U1_true, scene.U2_true).mean()))
        assert est.inliers.sum() >= 8
    assert np.mean(ours) <= np.mean(theirs)
    assert np.median(ours) <= np.median(theirs)


def test_mestimator_and_mapsac_match_opencv_on_outliers() -> None:
    # Mean over six scenes, as for RANSAC and LMedS above; the robust estimators of EGT 2.0 must be
    # at least as accurate as OpenCV's FM_LMEDS and FM_RANSAC (1 px) on 30% outliers.
    errs = []
    for seed in range(81, 87):
        scene = make_two_view(np.random.default_rng(seed), 400, noise=0.5, outlier_ratio=0.3)
        F_ransac, _ = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.FM_RANSAC, 1.0, 0.999, 2000)
        F_lmeds, _ = cv2.findFundamentalMat(scene.U1, scene.U2, cv2.FM_LMEDS, 1.0, 0.999, 2000)
        errs.append(
            [
                transfer_error(fundamental_mestimator(scene.U1, scene.U2).F, scene),
                transfer_error(fundamental_mapsac(scene.U1, scene.U2).F, scene),
                transfer_error(F_ransac, scene),
                transfer_error(F_lmeds, scene),
            ]
        )
    mest, mapsac, cv_ransac, cv_lmeds = np.mean(errs, axis=0)
    assert mest <= min(cv_ransac, cv_lmeds)
    assert mapsac <= min(cv_ransac, cv_lmeds)
