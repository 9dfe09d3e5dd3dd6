r"""The estimation lab: noisy correspondences from a scene's pin-hole pair, and every estimator of ``F`` on them.

Headless: the viewer plots what :func:`run_lab` returns. The true correspondences are the images
:math:`m_{1i}, m_{2i}` of the scene's points seen inside both images of the drawn pair; the lab adds
Gaussian noise of standard deviation ``noise_px`` to every pixel of both images, then replaces the image-2
pixel of ``outlier_percent`` % of them by a uniform random pixel of the image (gross mismatches). Each
estimator of :mod:`egtviz.geometry.fundamental`, :mod:`egtviz.geometry.robust` and the others is run on the same data
and compared with the true ``F`` by

* the mean squared Sampson distance (H&Z eq. 11.9)

  .. math:: d_i = \frac{(m_{2i}^T F m_{1i})^2}{(F m_{1i})_1^2 + (F m_{1i})_2^2 + (F^T m_{2i})_1^2 + (F^T m_{2i})_2^2}

  over the true inliers, with their noisy pixels (``sampson_noisy``) and with the noise-free ones
  (``sampson_true``: how far ``F`` is from the truth, whatever the noise);
* the mean squared symmetric epipolar distance of the noise-free correspondences (H&Z eq. 11.10);
* the distance of each estimated epipole from the true one, pixels;
* for the robust estimators, the inlier mask, its recall of the true inliers, and the threshold in pixels
  that separated inliers from outliers: RANSAC's own :math:`\tau`; for LMedS and the M-estimator the band
  :math:`2.5\hat\sigma` they use, with :math:`\hat\sigma = 1.4826 (1 + 5 / (N - 7)) \sqrt{\operatorname{med}_i d_i}`
  recomputed from the final ``F``. A correspondence whose Sampson distance is below the threshold is
  consistent with ``F`` to within that many pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

import numpy as np

from ..geometry import GeometryError, PinholeCamera, normalize_homogeneous
from ..geometry.epipolar import epipolar_lines, epipolar_lines_in_first, epipoles_from_fundamental
from ..geometry.error_metrics import sampson_distance, symmetric_epipolar_distance
from ..geometry.fundamental import fundamental_8point, fundamental_normalized_8point
from ..geometry.mestimator import fundamental_mestimator
from ..geometry.robust import fundamental_lmeds, fundamental_ransac
from ..geometry.sampson_refinement import fundamental_sampson
from .derived import Derived, compute_derived
from .limits import LAB_NOISE_PX, LAB_OUTLIER_PERCENT, LAB_SEED, LAB_THRESHOLD_PX, Range
from .scene import Scene
from .specs import SceneError

__all__ = [
    "METHODS",
    "Correspondences",
    "FitResult",
    "LabResult",
    "LabSettings",
    "Method",
    "make_correspondences",
    "run_lab",
]

Method = Literal["linear", "normalized", "sampson", "ransac", "lmeds", "mestimator"]
METHODS: tuple[Method, ...] = ("linear", "normalized", "sampson", "ransac", "lmeds", "mestimator")
"""Every estimator, in the order the lab shows them."""
ROBUST_METHODS = frozenset({"ransac", "lmeds", "mestimator"})
METHOD_TITLES = {
    "linear": "linear 8-point",
    "normalized": "normalised 8-point",
    "sampson": "Sampson",
    "ransac": "RANSAC",
    "lmeds": "LMedS",
    "mestimator": "M-estimator",
}
_MIN_CORRESPONDENCES = 8
_LMEDS_SIGMAS = 2.5


@dataclass(frozen=True)
class LabSettings:
    """The lab's sliders."""

    noise_px: float = 0.5
    """Standard deviation of the Gaussian pixel noise (:data:`LAB_NOISE_PX`)."""
    outlier_percent: float = 0.0
    """Percentage of correspondences replaced by random pixels in image 2 (:data:`LAB_OUTLIER_PERCENT`)."""
    threshold_px: float = 1.0
    """RANSAC's inlier threshold, pixels (:data:`LAB_THRESHOLD_PX`)."""
    seed: int = 0
    """Seed of the noise and the outliers (:data:`LAB_SEED`)."""

    def __post_init__(self) -> None:
        limits = {"noise_px": LAB_NOISE_PX, "outlier_percent": LAB_OUTLIER_PERCENT,
                  "threshold_px": LAB_THRESHOLD_PX, "seed": LAB_SEED}
        for f in fields(self):
            value, limit = getattr(self, f.name), limits[f.name]
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise SceneError(f"{f.name}: expected a number in {limit.describe()}, got {value!r:.40}")
            x = float(value)
            if x not in limit or (limit.integer and not x.is_integer()):
                raise SceneError(f"{f.name}: expected {'a whole number' if limit.integer else 'a number'} in "
                                 f"{limit.describe()}, got {x:g}")
            object.__setattr__(self, f.name, int(x) if limit.integer else x)


@dataclass(frozen=True, eq=False)
class Correspondences:
    """The lab's data: true and measured pixels of the points seen in both images."""

    point_indices: np.ndarray
    """(M,) indices of the scene points used."""
    true1: np.ndarray
    """(M, 2) noise-free pixels in image 1."""
    true2: np.ndarray
    """(M, 2) noise-free pixels in image 2."""
    measured1: np.ndarray
    """(M, 2) noisy pixels in image 1."""
    measured2: np.ndarray
    """(M, 2) noisy pixels in image 2; random pixels where ``outlier``."""
    outlier: np.ndarray
    """(M,) bool: the correspondence is a gross mismatch."""


@dataclass(frozen=True, eq=False)
class FitResult:
    """One estimator's result against the truth; ``F is None`` (and ``message`` set) when it failed."""

    method: Method
    F: np.ndarray | None
    """(3, 3) estimate, rank 2, unit Frobenius norm, ``m2^T F m1 = 0``."""
    e1: np.ndarray | None
    """(3,) epipole in image 1 from ``F`` (``normalize_homogeneous``)."""
    e2: np.ndarray | None
    sampson_noisy: float
    """Mean squared Sampson distance of the true inliers' measured pixels, px^2 (NaN if failed)."""
    sampson_true: float
    """Mean squared Sampson distance of the noise-free correspondences, px^2."""
    symmetric_true: float
    """Mean squared symmetric epipolar distance of the noise-free correspondences, px^2."""
    epipole_error_px: tuple[float, float]
    """Distance of ``e1`` and ``e2`` from the true epipoles, pixels (NaN when either is at infinity)."""
    inliers: np.ndarray | None
    """(M,) the robust estimator's inlier mask (None for the least-squares fits, which use every point)."""
    inlier_recall: float
    """Share of the true inliers marked inliers (NaN for the least-squares fits)."""
    threshold_px: float
    """Inlier threshold in pixels (NaN for the least-squares fits)."""
    message: str | None = None
    lines1: np.ndarray | None = None
    """(M, 3) epipolar lines in image 1 of the measured pixels of image 2, :math:`l_1 = F^T m_2` (what a panel
    drawing this fit shows)."""
    lines2: np.ndarray | None = None
    """(M, 3) epipolar lines in image 2 of the measured pixels of image 1, :math:`l_2 = F m_1`."""

    @property
    def title(self) -> str:
        """The method's name as the lab shows it."""
        return METHOD_TITLES[self.method]


@dataclass(frozen=True, eq=False)
class LabResult:
    """The lab on one scene and one setting: the truth, the data and every fit."""

    settings: LabSettings
    names: tuple[str, str]
    F_true: np.ndarray
    e1_true: np.ndarray
    e2_true: np.ndarray
    data: Correspondences
    fits: tuple[FitResult, ...]

    def fit(self, method: str) -> FitResult:
        """The result of ``method``.

        Raises:
            SceneError: the lab did not run that method.
        """
        for f in self.fits:
            if f.method == method:
                return f
        raise SceneError(f"method: expected one of {', '.join(m.method for m in self.fits)}, got {method!r:.40}")


def _pinhole_pair(scene: Scene, derived: Derived) -> tuple[str, str]:
    names = scene.drawn_pair
    if names is None or not all(isinstance(scene.camera(n).camera(), PinholeCamera) for n in names):
        raise SceneError("the estimation lab needs a drawn pair of two pin-hole cameras")
    if derived.pair.F is None:
        raise SceneError(f"the estimation lab: {derived.pair.message}")
    return names


def make_correspondences(scene: Scene, settings: LabSettings, derived: Derived | None = None) -> Correspondences:
    """The noisy correspondences of ``settings`` for the scene's drawn pin-hole pair (deterministic per seed).

    Raises:
        SceneError: no pin-hole pair, or fewer than 8 points inside both images.
    """
    derived = compute_derived(scene) if derived is None else derived
    names = _pinhole_pair(scene, derived)
    p1, p2 = (derived.image_planes[n] for n in names)
    idx = np.flatnonzero(p1.in_image & p2.in_image)
    if len(idx) < _MIN_CORRESPONDENCES:
        raise SceneError(
            f"the estimation lab needs at least {_MIN_CORRESPONDENCES} points inside both images, got {len(idx)}"
        )
    rng = np.random.default_rng(settings.seed)
    t1, t2 = p1.points[idx], p2.points[idx]
    m1 = t1 + rng.normal(0.0, settings.noise_px, t1.shape)
    m2 = t2 + rng.normal(0.0, settings.noise_px, t2.shape)
    n_out = int(round(settings.outlier_percent / 100.0 * len(idx)))
    outlier = np.zeros(len(idx), dtype=bool)
    outlier[rng.choice(len(idx), size=n_out, replace=False)] = True
    m2[outlier] = rng.uniform((0.0, 0.0), (p2.width, p2.height), size=(n_out, 2))
    for a in (t1, t2, m1, m2, outlier, idx):
        a.setflags(write=False)
    return Correspondences(idx, t1, t2, m1, m2, outlier)


def _estimate(method: Method, u1: np.ndarray, u2: np.ndarray, settings: LabSettings
              ) -> tuple[np.ndarray, np.ndarray | None]:
    if method == "linear":
        return fundamental_8point(u1, u2), None
    if method == "normalized":
        return fundamental_normalized_8point(u1, u2), None
    if method == "sampson":
        return fundamental_sampson(u1, u2), None
    if method == "ransac":
        est = fundamental_ransac(u1, u2, threshold=settings.threshold_px, seed=settings.seed)
    elif method == "lmeds":
        est = fundamental_lmeds(u1, u2, seed=settings.seed)
    else:
        est = fundamental_mestimator(u1, u2)
    return est.F, est.inliers


def _epipole_distance(e: np.ndarray, e_true: np.ndarray) -> float:
    if e[2] == 0.0 or e_true[2] == 0.0:
        return math.nan
    return float(np.hypot(e[0] - e_true[0], e[1] - e_true[1]))


def _fit(method: Method, data: Correspondences, settings: LabSettings, e_true: tuple[np.ndarray, np.ndarray]
         ) -> FitResult:
    nan = math.nan
    try:
        F, inliers = _estimate(method, data.measured1, data.measured2, settings)
    except (GeometryError, np.linalg.LinAlgError) as exc:  # degenerate data: reported, the other fits still run
        return FitResult(method, None, None, None, nan, nan, nan, (nan, nan), None, nan, nan, str(exc))
    good = ~data.outlier
    e1, e2 = epipoles_from_fundamental(F)
    e1, e2 = normalize_homogeneous(e1), normalize_homogeneous(e2)
    noisy = float(np.mean(sampson_distance(F, data.measured1[good], data.measured2[good])))
    true = float(np.mean(sampson_distance(F, data.true1, data.true2)))
    sym = float(np.mean(symmetric_epipolar_distance(F, data.true1, data.true2)))
    recall = threshold = nan
    if inliers is not None:
        recall = float(np.count_nonzero(inliers & good) / max(int(np.count_nonzero(good)), 1))
        if method == "ransac":
            threshold = settings.threshold_px
        else:
            d = sampson_distance(F, data.measured1, data.measured2)
            n = len(d)
            sigma = 1.4826 * (1.0 + 5.0 / max(n - 7, 1)) * math.sqrt(float(np.median(d)))
            threshold = _LMEDS_SIGMAS * sigma
        inliers = inliers.copy()
        inliers.setflags(write=False)
    return FitResult(
        method, F, e1, e2, noisy, true, sym,
        (_epipole_distance(e1, e_true[0]), _epipole_distance(e2, e_true[1])), inliers, recall, threshold,
        lines1=epipolar_lines_in_first(F, data.measured2), lines2=epipolar_lines(F, data.measured1),
    )


def run_lab(scene: Scene, settings: LabSettings = LabSettings(), methods: tuple[Method, ...] = METHODS,
            derived: Derived | None = None) -> LabResult:
    """Every estimator in ``methods`` on the noisy correspondences of ``settings`` (module docstring).

    An estimator that fails (e.g. too few inliers for the robust ones) gives a :class:`FitResult` with
    ``F = None`` and its ``message``; the others are unaffected.

    Raises:
        SceneError: bad ``settings`` or ``methods``, no pin-hole pair, or fewer than 8 points inside both images.
    """
    if not isinstance(settings, LabSettings):
        raise SceneError(f"settings: expected LabSettings, got {type(settings).__name__}")
    for m in methods:
        if m not in METHODS:
            raise SceneError(f"methods: expected names from {', '.join(METHODS)}, got {m!r:.40}")
    derived = compute_derived(scene) if derived is None else derived
    names = _pinhole_pair(scene, derived)
    data = make_correspondences(scene, settings, derived)
    F_true = np.asarray(derived.pair.F)
    e1_true, e2_true = derived.pair.e1, derived.pair.e2
    if e1_true is None or e2_true is None:  # set whenever F is, which _pinhole_pair checked
        raise SceneError(f"the estimation lab: {derived.pair.message}")
    e_true = (normalize_homogeneous(e1_true), normalize_homogeneous(e2_true))
    fits = tuple(_fit(m, data, settings, e_true) for m in methods)
    return LabResult(settings, names, F_true, e_true[0], e_true[1], data, fits)
