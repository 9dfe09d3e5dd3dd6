"""The estimation lab: its data, and the estimators compared against the true F."""

from __future__ import annotations

import math

import numpy as np
import pytest

from egtviz.scene import SCENES, PinholeSpec, Scene, SceneError, SceneModel
from egtviz.scene.lab import METHODS, LabSettings, make_correspondences, run_lab


def cube_pair(n=100, seed=5) -> Scene:
    model = SceneModel(SCENES["default"]())
    model.randomize_points(n, seed=seed)
    return model.scene


def large_pixels(n=80, seed=2) -> Scene:
    """A pair with a 4000 x 3000 image and 3000 px focal length: pixel coordinates in the thousands, the
    badly conditioned case of the unnormalised 8-point algorithm (H&Z section 11.2)."""
    big = dict(focal_length=0.03, pixels_per_metre=(1e5, 1e5), principal_point=(2000.0, 1500.0), width=4000,
               height=3000)
    model = SceneModel(Scene(cameras=(PinholeSpec("a", (-2, -8, 1.5), (14, -3, 0), **big),
                                      PinholeSpec("b", (2.5, -7.5, 2.5), (-18, -9, 0), **big))))
    model.randomize_points(n, seed=seed)
    return model.scene


def test_the_data_are_the_true_images_plus_noise_and_the_stated_share_of_outliers():
    scene = cube_pair()
    settings = LabSettings(noise_px=0.5, outlier_percent=20, seed=3)
    data = make_correspondences(scene, settings)
    m = len(data.point_indices)
    planes = SceneModel(scene).derived.image_planes
    both = np.flatnonzero(planes["cam1"].in_image & planes["cam2"].in_image)
    assert m > 90 and np.array_equal(data.point_indices, both)  # the points seen inside both images
    assert np.array_equal(data.true1, planes["cam1"].points[both])
    assert data.outlier.sum() == round(0.2 * m)
    residual = np.concatenate([data.measured1 - data.true1, (data.measured2 - data.true2)[~data.outlier]])
    assert residual.std() == pytest.approx(0.5, rel=0.15)  # the noise is what the slider says
    assert np.all((data.measured2[data.outlier] >= 0) & (data.measured2[data.outlier] <= (640, 480)))
    again = make_correspondences(scene, settings)
    assert np.array_equal(again.measured2, data.measured2)  # deterministic per seed
    other = make_correspondences(scene, LabSettings(noise_px=0.5, outlier_percent=20, seed=4))
    assert not np.array_equal(other.measured1, data.measured1)


def test_without_noise_every_estimator_recovers_the_true_f():
    result = run_lab(cube_pair(), LabSettings(noise_px=0.0))
    assert [f.method for f in result.fits] == list(METHODS)
    for fit in result.fits:
        assert fit.F is not None, fit.message
        assert fit.sampson_true < 1e-6 and fit.symmetric_true < 1e-5, fit.method
        # the same F up to sign: |<F, F_true>| = 1 for unit Frobenius norms
        assert abs(float(np.sum(fit.F * result.F_true))) == pytest.approx(1.0, abs=1e-6)
        e1_err, e2_err = fit.epipole_error_px
        assert e1_err < 1e-3 * np.hypot(*result.e1_true[:2]) and e2_err < 1e-3 * np.hypot(*result.e2_true[:2])
        if fit.method in ("ransac", "lmeds", "mestimator"):
            assert fit.inlier_recall == 1.0 and fit.threshold_px > 0
        else:
            assert fit.inliers is None and math.isnan(fit.inlier_recall) and math.isnan(fit.threshold_px)


def test_normalisation_beats_the_linear_fit_on_badly_conditioned_pixels():
    scene = large_pixels()
    ratios = []
    for seed in range(10):
        result = run_lab(scene, LabSettings(noise_px=0.5, seed=seed), methods=("linear", "normalized"))
        linear, normalized = result.fits
        ratios.append(linear.sampson_true / normalized.sampson_true)
    assert min(ratios) > 1.0, ratios
    assert float(np.median(ratios)) > 5.0, ratios


def test_ransac_keeps_the_true_inliers_with_twenty_percent_outliers():
    scene = cube_pair()
    for seed in range(5):
        result = run_lab(scene, LabSettings(noise_px=0.5, outlier_percent=20, threshold_px=1.5, seed=seed),
                         methods=("ransac", "normalized"))
        ransac, normalized = result.fits
        assert ransac.inlier_recall >= 0.9, seed
        assert ransac.threshold_px == 1.5
        outliers = result.data.outlier
        assert np.count_nonzero(ransac.inliers & outliers) <= 2  # gross mismatches are rejected
        assert ransac.sampson_true < 0.1 < normalized.sampson_true  # least squares is ruined, RANSAC is not


def test_lmeds_and_the_m_estimator_report_their_threshold_in_pixels():
    settings = LabSettings(noise_px=1.0, outlier_percent=30)
    result = run_lab(cube_pair(), settings, methods=("lmeds", "mestimator"))
    for fit in result.fits:
        # 2.5 sigma with sigma estimated from the median Sampson distance: about 2.5 to 4 px at 1 px of noise
        assert 1.5 < fit.threshold_px < 6.0, (fit.method, fit.threshold_px)
        assert fit.inlier_recall > 0.9


def test_degenerate_data_give_failed_fits_with_a_message_not_an_exception():
    model = SceneModel(SCENES["default"]())
    model.set_points([(x, y, 0.0) for x in (-1.5, -0.5, 0.5, 1.5) for y in (-1.5, -0.5, 0.5, 1.5)])
    result = run_lab(model.scene, LabSettings(noise_px=0.0))  # coplanar points: F is not determined
    for fit in result.fits:
        assert fit.F is None and "degenerate" in fit.message and math.isnan(fit.sampson_true)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"noise_px": -1}, "noise_px: expected a number in 0..20 px"),
        ({"outlier_percent": 61}, "outlier_percent: expected a number in 0..60 %"),
        ({"threshold_px": 0}, "threshold_px: expected a number in 0.05..100 px"),
        ({"seed": 1.5}, "seed: expected a whole number"),
        ({"noise_px": True}, "noise_px: expected a number"),
    ],
)
def test_settings_outside_their_ranges_are_refused(kwargs, words):
    with pytest.raises(SceneError, match=words):
        LabSettings(**kwargs)


def test_the_lab_needs_a_pinhole_pair_and_eight_points():
    with pytest.raises(SceneError, match="pin-hole"):
        run_lab(SCENES["panoramic"]())
    with pytest.raises(SceneError, match="at least 8 points"):
        run_lab(SCENES["example3"]())
    with pytest.raises(SceneError, match="methods"):
        run_lab(cube_pair(), methods=("magic",))


def test_each_fit_carries_the_epipolar_lines_of_the_measured_pixels():
    """``l2 = F m1`` and ``l1 = F^T m2`` of the measured pixels: each measured pixel of the other image lies on its
    line when the data are exact (no noise, no outliers)."""
    result = run_lab(cube_pair(40), LabSettings(noise_px=0.0, outlier_percent=0.0))
    h = np.ones((len(result.data.measured1), 1))
    for fit in result.fits:
        assert fit.F is not None, fit.message
        m1 = np.hstack([result.data.measured1, h])
        m2 = np.hstack([result.data.measured2, h])
        d2 = np.abs(np.sum(fit.lines2 * m2, axis=1)) / np.hypot(fit.lines2[:, 0], fit.lines2[:, 1])
        d1 = np.abs(np.sum(fit.lines1 * m1, axis=1)) / np.hypot(fit.lines1[:, 0], fit.lines1[:, 1])
        assert d1.max() < 1e-6 and d2.max() < 1e-6, fit.method
