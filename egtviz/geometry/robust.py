r"""Robust estimation of the epipolar geometry by random sampling: RANSAC, LMedS, MAPSAC.

Hartley & Zisserman, *Multiple View Geometry*, 2nd ed. (H&Z), section 11.6 ("Automatic computation
of F", Algorithm 11.4) with the adaptive number of samples of section 4.7.1 (Algorithm 4.5,
"Adaptive algorithm for determining the number of RANSAC samples"):

* :func:`fundamental_ransac`: RANSAC over 7-point samples, scored by the truncated (MSAC) cost.
* :func:`fundamental_lmeds`: least median of squares (Rousseeuw and Leroy), no threshold.
* :func:`fundamental_mapsac`: MAPSAC (Torr 2002), EGT 2.0's ``f_Festim`` algorithm 6.
* :func:`essential_from_rays_ransac`: a robust essential matrix from corresponding rays (mirror
  points of two central catadioptric cameras, or any bearing vectors), RANSAC over 8-ray samples
  (EGT's ``f_panEestim``).

EGT 2.0's M-estimator is :func:`~egtviz.geometry.mestimator.fundamental_mestimator`; every robust
estimator returns the same :class:`RobustEstimate` record.

Conventions (``docs/conventions.md``): pixels as rows ``(N, 2)``, rays as rows ``(N, 3)``;
:math:`m_2^T F m_1 = 0`, :math:`d_2^T E d_1 = 0`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_count, as_positive, as_scalar, short_repr
from .error_metrics import sampson_distances_normalized
from .essential import essential_linear, essential_projection, ray_pairs, ray_sampson
from .fundamental import canonical_fundamental, design_matrix, float_pairs, normalized_design, null_vector
from .fundamental import seven_point_candidates
from .matrices import nearest_rank2
from .sampson_refinement import polish_sampson, refine_sampson

__all__ = [
    "RobustEstimate",
    "essential_from_rays_ransac",
    "fundamental_lmeds",
    "fundamental_mapsac",
    "fundamental_ransac",
]

# Integers up to this are exact as floats: the checked route (through a float) returns them unchanged.
_EXACT_INT = 2**53
# Inliers needed before a robust estimate can be refitted with the 8-point algorithm.
_MIN_REFIT = 8
# Samples per batch of the robust estimators: the first batch, then what the
# adaptive bound still asks for, within [_BATCH_MIN, _BATCH_MAX]. Batches
# amortise numpy's per-call overhead; the first is large enough for the bound
# at 0.999 and an inlier ratio of 0.66 (124 samples), so that a typical search
# is one batch rather than a full one and a second of 16 (the fixed cost of a
# batch is about that of 100 samples).
_BATCH_FIRST = 128
_BATCH_MIN = 16
_BATCH_MAX = 256
# Relative tolerance (cost and step) of the final Sampson refinement of the robust estimators.
_REFINE_TOL = 1e-3
# LMedS's smallest scale estimate, relative to the spread of the points.
_SIGMA_FLOOR = 1e-9
# Pre-emptive scoring: subset size, and hypotheses per batch scored on all points.
_SUBSET = 100
_KEEP = 2
# ... in two stages: all hypotheses on the subset's first points, the best of them on the whole subset.
_SUBSET_FIRST = 25
_PREEMPT_KEEP = 64
# 8-ray samples per batch of the robust essential estimator.
_RAYS_BATCH = 128
# chi-square 95% quantile with one degree of freedom: F is a manifold of codimension 1 in the
# 4-D space of correspondences, so a squared distance of an inlier over sigma^2 follows chi^2_1.
_CHI2_1_95 = 3.84


@dataclass(frozen=True, eq=False)
class RobustEstimate:
    """Result of every robust estimator: those of this module and
    :func:`~egtviz.geometry.mestimator.fundamental_mestimator`."""

    F: np.ndarray
    """(3, 3) fundamental matrix, rank 2, unit Frobenius norm, ``m2^T F m1 = 0`` (for the estimator from
    rays, the essential matrix, ``d2^T E d1 = 0``)."""
    inliers: np.ndarray
    """(N,) bool mask of the correspondences consistent with ``F``."""
    iterations: int
    """Number of minimal samples drawn before the adaptive bound stopped the search (for the M-estimator,
    the number of reweighting iterations)."""


def _check_robust_args(confidence: object, max_iterations: object, seed: object) -> tuple[float, int, int | None]:
    """The options shared by the sampling estimators, validated: ``(confidence, max_iterations, seed)``."""
    if (
        type(confidence) is float
        and 0.0 < confidence < 1.0
        and type(max_iterations) is int
        and 1 <= max_iterations <= _EXACT_INT
        and (seed is None or (type(seed) is int and seed >= 0))
    ):
        return confidence, max_iterations, seed  # what the checks below return for these plain values
    conf = as_scalar(confidence, "confidence")
    if not 0.0 < conf < 1.0:
        raise GeometryError(f"confidence: expected a number in (0, 1), got {short_repr(confidence)}")
    iters = as_count(max_iterations, "max_iterations")
    if seed is not None and (isinstance(seed, bool | np.bool_) or not isinstance(seed, int | np.integer) or seed < 0):
        raise GeometryError(f"seed: expected None or a non-negative integer, got {short_repr(seed)}")
    return conf, iters, None if seed is None else int(seed)


def _iteration_bound(inlier_ratio: float, confidence: float, size: int = 7) -> float:
    r"""Adaptive number of samples (H&Z Algorithm 4.5): :math:`\log(1-p) / \log(1 - w^s)`, sample size ``s``."""
    p = min(max(inlier_ratio, 0.0), 1.0) ** size
    if p >= 1.0 - 1e-15:
        return 1.0
    if p <= 1e-300:
        return math.inf
    return math.ceil(math.log(1.0 - confidence) / math.log1p(-p))


def _sample(rng: np.random.Generator, n: int, k: int, size: int = 7) -> np.ndarray:
    """``k`` samples of ``size`` distinct indices in ``range(n)``, ``(k, size)``."""
    if n < 64:
        return np.argpartition(rng.random((k, n)), min(size, n - 1), axis=1)[:, :size]
    out = []
    got = 0
    while got < k:
        draw = rng.integers(0, n, size=(k + 8, size))
        srt = np.sort(draw, axis=1)
        ok = np.logical_and.reduce(srt[:, 1:] != srt[:, :-1], axis=1)  # np.all without its wrapper
        out.append(draw[ok])
        got += int(np.count_nonzero(ok))
    return (out[0] if len(out) == 1 else np.concatenate(out))[:k]


class _Scorer:
    """Cost and inlier rule: truncated quadratic (RANSAC's MSAC cost, MAPSAC) or LMedS's order statistic."""

    def __init__(self, mode: str, th2: float, n: int, floor2: float) -> None:
        self.mode = mode
        self.th2 = th2
        # LMedS: inlier if d <= (2.5 sigma)^2, sigma = 1.4826 (1 + 5 / (N - 7)) sqrt(d_(h)).
        self.lmeds_scale = (2.5 * 1.4826 * (1.0 + 5.0 / max(n - 7, 1))) ** 2
        # Rounding makes the residuals of exact data about 1e-15 of the point spread, never exactly zero;
        # the floor keeps sigma above that, and far below any real noise.
        self.floor2 = floor2

    def cost(self, d: np.ndarray) -> np.ndarray:
        if self.mode != "lmeds":
            return np.add.reduce(np.minimum(d, self.th2), axis=-1)  # ndarray.sum's own wrapper costs more
        # The order statistic h = floor(n / 2) + 4 of n residuals (Rousseeuw and Leroy's
        # floor(n / 2) + floor((p + 1) / 2), p = 7 parameters), 0-based below: the 7 sample points fit
        # exactly, so a plain median would fall among them for n < 14 and read a zero scale; d_(h) is
        # the median of the other n - 7.
        n = d.shape[-1]
        h = min(n - 1, n // 2 + 3)
        return np.partition(d, h, axis=-1)[..., h]

    def inliers(self, d: np.ndarray, cost: float) -> np.ndarray:
        if self.mode != "lmeds":
            return d < self.th2
        return d <= self.lmeds_scale * max(cost, self.floor2)


def _prepare(U1: npt.ArrayLike, U2: npt.ArrayLike, mode: str, threshold: float, options: tuple) -> tuple:
    """Validated data of a sampling estimator: ``(At, T1, T2, scorer, (confidence, max_iterations, seed))``."""
    u1, u2 = float_pairs(U1, U2, _MIN_REFIT)
    At, T1, T2 = normalized_design(u1, u2)  # checks the values, with point_pairs' errors, before the options
    options = _check_robust_args(*options)
    null_vector(At)  # all the data degenerate (e.g. a coplanar scene seen twice): no F to find
    # Scale floor of LMedS: 1e-9 of the larger point spread (mean distance to the centroid, 1 / s).
    floor2 = (_SIGMA_FLOOR / min(T1[0, 0], T2[0, 0])) ** 2
    return At, T1, T2, _Scorer(mode, threshold * threshold, u1.shape[0], floor2), options


def _local_refits(
    At: np.ndarray, s1: float, s2: float, scorer: _Scorer, best: tuple[float, np.ndarray, np.ndarray], widen: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """LO-RANSAC: linear refits on the (widened) support of a new best ``(cost, F, d)`` while the cost falls."""
    best_cost, best_F, best_d = best
    fitted_on = None  # the support the best F was refitted on
    for _ in range(4):
        inl = scorer.inliers(best_d / widen**2, best_cost)
        if np.count_nonzero(inl) < _MIN_REFIT:
            break
        if fitted_on is not None and np.array_equal(inl, fitted_on):
            break  # the refit would be the best F again, bit for bit, and the loop would stop on its cost
        try:
            F_lo = nearest_rank2(null_vector(np.compress(inl, At, axis=1)).reshape(3, 3), check=False)
        except DegenerateConfigurationError:
            break
        f = F_lo.ravel()
        F_lo /= math.sqrt(f.dot(f))  # np.linalg.norm's arithmetic without its wrapper
        d_lo = sampson_distances_normalized(F_lo[None], At, s1, s2)[0]
        c_lo = float(scorer.cost(d_lo))
        if c_lo >= best_cost:
            break
        best_cost, best_F, best_d, fitted_on = c_lo, F_lo, d_lo, inl
    return best_cost, best_F, best_d


def _preempt(cand: np.ndarray, At_sub: np.ndarray, s1: float, s2: float, scorer: _Scorer) -> np.ndarray:
    """The ``_KEEP`` best hypotheses of a batch on the subset ``At_sub``, scored in two stages.

    Every hypothesis is scored on the first ``_SUBSET_FIRST`` points of the subset (a random draw, as the
    subset's points are in random order); only the best ``_PREEMPT_KEEP`` of them on the whole subset.
    """
    if cand.shape[0] > _PREEMPT_KEEP:
        c_first = scorer.cost(sampson_distances_normalized(cand, At_sub[:, :_SUBSET_FIRST], s1, s2))
        cand = cand[np.sort(np.argsort(c_first, kind="stable")[:_PREEMPT_KEEP])]
    c_sub = scorer.cost(sampson_distances_normalized(cand, At_sub, s1, s2))
    return cand[np.argsort(c_sub, kind="stable")[:_KEEP]]


def _search(
    At: np.ndarray, s1: float, s2: float, scorer: _Scorer, widen: float, confidence: float, max_iterations: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, int]:
    """The sampling loop: the best hypothesis in normalised coordinates, its squared Sampson distances and
    the number of samples drawn."""
    N = At.shape[1]
    A = At.T  # rows of the design matrix, for gathering samples
    # Pre-emptive scoring: every hypothesis is scored on a fixed random subset,
    # only the best few of each batch on all the points.
    # In the order drawn (not sorted): its first _SUBSET_FIRST points are a random subset too.
    sub = rng.choice(N, _SUBSET, replace=False) if N > 2 * _SUBSET else None
    At_sub = At[:, sub] if sub is not None else At
    best: tuple[float, np.ndarray, np.ndarray] | None = None
    bound = math.inf
    done = 0
    while done < min(bound, max_iterations):
        want = _BATCH_FIRST if done == 0 else min(max(bound - done, _BATCH_MIN), _BATCH_MAX)
        k = int(min(want, max_iterations - done))
        cand = seven_point_candidates(A[_sample(rng, N, k)])
        done += k
        if cand.shape[0] == 0:
            continue
        if sub is not None:
            cand = _preempt(cand, At_sub, s1, s2, scorer)
        d = sampson_distances_normalized(cand, At, s1, s2)
        cost = scorer.cost(d)
        j = int(np.argmin(cost))
        if best is not None and cost[j] >= best[0]:
            continue
        best = _local_refits(At, s1, s2, scorer, (float(cost[j]), cand[j], d[j]), widen)
        bound = _iteration_bound(float(scorer.inliers(best[2], best[0]).mean()), confidence)
    if best is None:
        raise DegenerateConfigurationError("U1, U2: no 7-point sample gave a fundamental matrix")
    return best[1], best[2], done


def _final_fit(
    Fn: np.ndarray, d: np.ndarray, At: np.ndarray, s1: float, s2: float, scorer: _Scorer, mode: str,
    threshold: float, widen: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The final model and its inliers ``(Fn, inliers)``; ``d`` are ``Fn``'s squared Sampson distances.

    RANSAC: one Gauss-Newton step on the Sampson cost over rank-2 F (its band). LMedS and MAPSAC: linear refits
    on the support, then the Levenberg-Marquardt Sampson refinement."""

    def support(Fn: np.ndarray, widen: float) -> tuple[np.ndarray, np.ndarray]:
        d = sampson_distances_normalized(Fn[None], At, s1, s2)[0]
        return scorer.inliers(d / widen**2, float(scorer.cost(d))), d

    if mode == "ransac":
        # The maximum-likelihood step (H&Z 11.4.3): the Sampson cost over rank-2 F, on the band the refits use.
        # Minimised on the rank-2 manifold, not by linear refits made rank 2 afterwards: over 48 fresh bench
        # scenes that is 11 % more accurate (mean symmetric epipolar distance to the true F). From the locally
        # refitted model one Gauss-Newton step is enough: more steps (or Levenberg-Marquardt to 1e-10) changed
        # the mean error on those scenes by under 0.1 %.
        band = d < widen**2 * scorer.th2
        if np.count_nonzero(band) >= _MIN_REFIT:
            Fn = polish_sampson(Fn, np.compress(band, At, axis=1), s1, s2, max_steps=1)
            d = sampson_distances_normalized(Fn[None], At, s1, s2)[0]
        return Fn, scorer.inliers(d, float(scorer.cost(d)))
    sel = scorer.inliers(d / widen**2, float(scorer.cost(d)))
    for _ in range(3):  # linear refits until the support is stable
        if sel.sum() < _MIN_REFIT:
            break
        try:
            F_lin = nearest_rank2(null_vector(np.compress(sel, At, axis=1)).reshape(3, 3), check=False)
        except DegenerateConfigurationError:
            break
        Fn = F_lin / np.linalg.norm(F_lin)
        new, d = support(Fn, widen)
        if np.array_equal(new, sel):
            break
        sel = new
    if sel.sum() < _MIN_REFIT:
        raise DegenerateConfigurationError(
            f"U1, U2: the best model has only {int(sel.sum())} inliers, at least {_MIN_REFIT} are needed"
        )
    # Sampson refinement. LMedS makes it robust by two reweighting passes with
    # Cauchy weights 1 / (1 + d / c^2), c = 2 sigma; tighter weights tie the fit
    # to the starting F (the same bias as truncation).
    # MAPSAC refines the plain Sampson cost of its inliers (Torr's maximum
    # likelihood step), twice, the inliers recomputed in between.
    if mode == "lmeds":
        c2 = 4.0 * scorer.lmeds_scale / 2.5**2 * max(float(scorer.cost(d)), scorer.floor2)
    else:
        c2 = 4.0 * threshold**2
    for _ in range(2):
        weights = None if mode == "mapsac" else 1.0 / (1.0 + d[sel] / max(c2, 1e-300))
        # The Sampson cost of n inliers is a sum of n noisy squares whose own spread is about sqrt(2 / n) of
        # it (5 % at n = 700): a relative change of _REFINE_TOL is far below that noise. Tighter (1e-6) moved F
        # by 1e-7 on the bench scenes, with the same inliers and accuracy, for 12-16 % more time.
        Fn = refine_sampson(Fn, np.compress(sel, At, axis=1), s1, s2, weights, tol=_REFINE_TOL)
        new, d = support(Fn, widen)
        if new.sum() < _MIN_REFIT:
            break
        sel = new
    return Fn, scorer.inliers(d, float(scorer.cost(d)))  # d is the last Fn's


def _robust(
    U1: npt.ArrayLike,
    U2: npt.ArrayLike,
    *,
    mode: str,
    threshold: float,
    confidence: float,
    max_iterations: int,
    seed: int | None,
) -> RobustEstimate:
    At, T1, T2, scorer, options = _prepare(U1, U2, mode, threshold, (confidence, max_iterations, seed))
    confidence, max_iterations, seed = options
    s1, s2 = T1[0, 0], T2[0, 0]
    # Refits use the correspondences within 1.5 times the RANSAC threshold
    # (LMedS's 2.5 sigma band is wide already): refitting only on d < threshold^2
    # would favour the hypothesis that chose them (truncation bias).
    widen = 1.5 if mode == "ransac" else 1.0
    rng = np.random.default_rng(seed)
    Fn, d, done = _search(At, s1, s2, scorer, widen, confidence, max_iterations, rng)
    Fn, inl = _final_fit(Fn, d, At, s1, s2, scorer, mode, threshold, widen)
    return RobustEstimate(F=canonical_fundamental(T2.T @ Fn @ T1), inliers=inl, iterations=int(done))


def fundamental_ransac(
    U1: npt.ArrayLike,
    U2: npt.ArrayLike,
    *,
    threshold: float = 1.0,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    seed: int | None = 0,
) -> RobustEstimate:
    r"""Robust ``F`` by RANSAC over 7-point samples (H&Z 2nd ed., section 11.6, Algorithm 4.5).

    Hypotheses from minimal 7-point samples (up to three each) are scored in
    batches by the truncated (MSAC) cost of the squared Sampson distance
    :math:`d_i` (H&Z eq. 11.9):

    .. math:: C(F) = \sum_i \min(d_i, \tau^2), \qquad
              N_{\text{iter}} = \frac{\log(1 - p)}{\log(1 - w^7)},

    with the number of samples adapted to the inlier ratio :math:`w` of the
    best hypothesis so far and the confidence :math:`p`. Samples are drawn in
    batches, the first of 128 (so at least 128 samples unless
    ``max_iterations`` is smaller; the search stops once the bound is met).
    Each batch is pre-scored on a fixed random subset of 100 correspondences,
    in two stages (every hypothesis on 25 of them, the best 64 on all 100), and
    its best two hypotheses on all the correspondences. A new best hypothesis
    is improved at once by linear refits on its support (LO-RANSAC). The final
    model minimises the Sampson cost :math:`\sum_i d_i` over rank-2 matrices
    (the maximum-likelihood step of H&Z 11.4.3; one Gauss-Newton step of
    :func:`~egtviz.geometry.sampson_refinement.polish_sampson` from the
    best model) on the correspondences with :math:`d_i < (1.5\tau)^2` (a
    wider band than the inlier test, against the truncation bias). Inliers are
    :math:`d_i < \tau^2` under the final ``F``.

    Until 2026-12-02 the final model was two linear 8-point refits weighted by
    the inverse Sampson denominators, each made rank 2 afterwards: its answers
    differ from today's by the estimation noise (about 0.01 px on the bench
    scenes). Minimising on the rank-2 manifold is 11 % more accurate over 48
    fresh bench scenes (mean symmetric epipolar distance to the true ``F`` on
    the true inliers, ``docs/conventions.md``) at about the same time.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        threshold: inlier threshold :math:`\tau` in pixels on the Sampson
            distance (square root of :func:`sampson_distance`).
        confidence: probability :math:`p` of drawing one all-inlier sample.
        max_iterations: upper bound on the number of samples.
        seed: seed of ``np.random.default_rng``; the result is deterministic.

    Returns:
        :class:`RobustEstimate` with ``F``, the inlier mask and the number of samples.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8``, mismatched ``N`` or bad options.
        DegenerateConfigurationError: coincident points, or fewer than 8 inliers.
    """
    thr = as_positive(threshold, "threshold")
    return _robust(
        U1, U2, mode="ransac", threshold=thr, confidence=confidence, max_iterations=max_iterations, seed=seed
    )


def fundamental_lmeds(
    U1: npt.ArrayLike,
    U2: npt.ArrayLike,
    *,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    seed: int | None = 0,
) -> RobustEstimate:
    r"""Robust ``F`` by least median of squares over 7-point samples (H&Z 2nd ed., section 11.6).

    Each hypothesis is scored by the median of the squared Sampson distances
    :math:`d_i`; no threshold is needed. From the best median the robust
    standard deviation (Rousseeuw and Leroy)

    .. math:: \hat\sigma = 1.4826\,\Bigl(1 + \frac{5}{N - 7}\Bigr)\sqrt{\operatorname{med}_i d_i}

    classifies inliers as :math:`d_i \le (2.5 \hat\sigma)^2`; their fraction
    :math:`w` sets the adaptive number of samples as in :func:`fundamental_ransac`.
    The inliers are refitted with the normalised 8-point algorithm and two
    passes of Sampson refinement with Cauchy weights
    :math:`1 / (1 + d_i / (2\hat\sigma)^2)`. LMedS breaks down with more than
    50% outliers.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        confidence: probability of drawing one all-inlier sample.
        max_iterations: upper bound on the number of samples.
        seed: seed of ``np.random.default_rng``; the result is deterministic.

    Returns:
        :class:`RobustEstimate` with ``F``, the inlier mask and the number of samples.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8``, mismatched ``N`` or bad options.
        DegenerateConfigurationError: coincident points, or fewer than 8 inliers.
    """
    return _robust(
        U1, U2, mode="lmeds", threshold=1.0, confidence=confidence, max_iterations=max_iterations, seed=seed
    )


def fundamental_mapsac(
    U1: npt.ArrayLike,
    U2: npt.ArrayLike,
    *,
    sigma: float = 0.5,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    seed: int | None = 0,
) -> RobustEstimate:
    r"""Robust ``F`` by MAPSAC (Torr 2002; Torr and Zisserman's MLESAC, 2000) over 7-point samples.

    Every hypothesis of the minimal 7-point solver is scored by the
    truncated cost of the squared Sampson distances :math:`d_i` (H&Z eq. 11.9),

    .. math:: C(F) = \sum_i \min(d_i, T), \qquad T = 3.84\,\sigma^2 ,

    the negative log-posterior of a Gaussian inlier / uniform outlier mixture
    up to constants; :math:`T` is the 95% quantile of :math:`\chi^2_1` (an
    inlier's squared distance to the codimension-1 manifold of ``F``). The
    search, its adaptive number of samples (H&Z Algorithm 4.5) and the local
    refits are those of :func:`~fundamental_ransac`,
    whose MSAC cost is the same function; MAPSAC then minimises the plain
    Sampson cost of its inliers :math:`d_i < T` (the maximum-likelihood
    step), twice, the inliers recomputed in between.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        sigma: standard deviation of the inliers' image noise, pixels.
        confidence: probability of drawing one all-inlier sample.
        max_iterations: upper bound on the number of samples.
        seed: seed of ``np.random.default_rng``; the result is deterministic.

    Returns:
        :class:`RobustEstimate` with ``F``, the
        inlier mask (:math:`d_i < T`) and the number of samples.

    Raises:
        GeometryError: bad types or shapes, NaN/inf, ``N < 8``, mismatched ``N`` or bad options.
        DegenerateConfigurationError: coincident points, rank-deficient data, or fewer than 8 inliers.
    """
    s = as_positive(sigma, "sigma")
    return _robust(
        U1,
        U2,
        mode="mapsac",
        threshold=math.sqrt(_CHI2_1_95) * s,
        confidence=confidence,
        max_iterations=max_iterations,
        seed=seed,
    )


def essential_from_rays_ransac(
    d1: npt.ArrayLike,
    d2: npt.ArrayLike,
    *,
    threshold_rad: float = 1e-3,
    confidence: float = 0.999,
    max_iterations: int = 2000,
    seed: int | None = 0,
) -> RobustEstimate:
    r"""Robust essential matrix from corresponding rays by RANSAC over 8-ray samples (EGT's ``f_panEestim``).

    Each sample of 8 correspondences gives one hypothesis by the linear
    method of :func:`~egtviz.geometry.essential.essential_from_rays`
    (projected onto the essential matrices). Hypotheses are scored by the
    truncated cost of the squared angular Sampson distances :math:`\delta_i`
    (radians squared; the first-order angle by which the two unit rays must
    turn to satisfy the constraint),

    .. math:: C(E) = \sum_i \min(\delta_i, \tau^2), \qquad
              N_{\text{iter}} = \frac{\log(1 - p)}{\log(1 - w^8)} ,

    with the adaptive number of samples of H&Z Algorithm 4.5. The best
    hypothesis is refitted on its inliers :math:`\delta_i < \tau^2` by the
    linear method with Sampson weights :math:`1 / (|g_1|^2 + |g_2|^2)` (the
    gradient norms at the previous ``E``) until the inliers no longer change.

    Args:
        d1: ``(N, 3)`` rays in frame 1 (any nonzero lengths), ``N >= 8``.
        d2: ``(N, 3)`` corresponding rays in frame 2.
        threshold_rad: inlier threshold :math:`\tau` on the angular Sampson
            distance, radians.
        confidence: probability :math:`p` of drawing one all-inlier sample.
        max_iterations: upper bound on the number of samples.
        seed: seed of ``np.random.default_rng``; the result is deterministic.

    Returns:
        :class:`RobustEstimate` whose ``F`` field
        holds ``E`` (:math:`d_2^T E d_1 = 0`, singular values
        :math:`(1/\sqrt 2, 1/\sqrt 2, 0)`, largest entry positive), the inlier
        mask and the number of samples.

    Raises:
        GeometryError: bad types or shapes, NaN/inf, a zero ray, ``N < 8``,
            mismatched ``N`` or bad options.
        DegenerateConfigurationError: rank-deficient data, or fewer than 8 inliers.
    """
    tau = as_positive(threshold_rad, "threshold_rad")
    if tau >= 1.0:
        raise GeometryError(f"threshold_rad: expected an angle below 1 radian, got {short_repr(threshold_rad)}")
    conf, iters, seed = _check_robust_args(confidence, max_iterations, seed)
    r1, r2 = ray_pairs(d1, d2, 8)
    At = design_matrix(r1, r2)
    null_vector(At, "d1, d2")
    th2 = tau * tau
    E, done = _rays_search(At.T, r1, r2, th2, conf, iters, np.random.default_rng(seed))
    E, inl = _rays_refit(E, r1, r2, th2)
    return RobustEstimate(F=canonical_fundamental(E), inliers=inl, iterations=int(done))


def _rays_search(
    A: np.ndarray, r1: np.ndarray, r2: np.ndarray, th2: float, conf: float, iters: int, rng: np.random.Generator
) -> tuple[np.ndarray, int]:
    """The sampling loop of :func:`essential_from_rays_ransac`: the best ``E`` and the number of samples."""
    n = r1.shape[0]
    best_cost, best_E = math.inf, None
    bound, done = math.inf, 0
    while done < min(bound, iters):
        k = int(min(_RAYS_BATCH, iters - done))
        samples = A[_sample(rng, n, k, 8)]  # (k, 8, 9)
        done += k
        vt = np.linalg.svd(samples, full_matrices=True)[2]
        Es = essential_projection(vt[:, 8].reshape(k, 3, 3))
        cost = np.minimum(ray_sampson(Es, r1, r2), th2).sum(axis=1)
        j = int(np.argmin(cost))
        if cost[j] < best_cost:
            best_cost, best_E = float(cost[j]), Es[j]
            w = float((ray_sampson(best_E[None], r1, r2)[0] < th2).mean())
            bound = _iteration_bound(w, conf, 8)
    assert best_E is not None
    return best_E, done


def _rays_refit(E: np.ndarray, r1: np.ndarray, r2: np.ndarray, th2: float) -> tuple[np.ndarray, np.ndarray]:
    """Sampson-weighted linear refits of ``E`` on its inliers until they no longer change: ``(E, inliers)``."""
    inl = ray_sampson(E[None], r1, r2)[0] < th2
    for _ in range(10):
        if inl.sum() < 8:
            raise DegenerateConfigurationError(
                f"d1, d2: the best model has only {int(inl.sum())} inliers, at least 8 are needed"
            )
        a, b = r1[inl], r2[inl]
        Ed1, Etd2 = a @ E.T, b @ E
        e = np.einsum("ni,ni->n", Ed1, b)
        grad2 = np.einsum("ni,ni->n", Ed1, Ed1) + np.einsum("ni,ni->n", Etd2, Etd2) - 2.0 * e * e
        # A ray pair at the epipoles has no gradient: cap its weight at 1e12 times the smallest.
        weights = 1.0 / np.maximum(grad2, 1e-12 * grad2.max())
        try:
            E = essential_linear(a, b, weights / weights.max())
        except DegenerateConfigurationError:
            break
        new = ray_sampson(E[None], r1, r2)[0] < th2
        if np.array_equal(new, inl):
            break
        inl = new
    return E, inl
