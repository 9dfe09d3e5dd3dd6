r"""EGT 2.0's robust estimators of the epipolar geometry, beside RANSAC and LMedS.

* :func:`fundamental_mestimator`: an M-estimator of ``F`` (Torr and Murray's
  iteratively reweighted least squares on Sampson residuals, scale from the
  median absolute deviation, then a reweighted Sampson minimisation).
* :func:`fundamental_mapsac`: MAPSAC, the truncated cost :math:`\sum_i \min(d_i, T)`
  over 7-point samples, then the Sampson minimisation on its inliers.
* :func:`essential_from_rays_ransac`: a robust essential matrix from
  corresponding rays (mirror points of two central catadioptric cameras,
  or any bearing vectors), RANSAC over 8-ray samples.

:func:`~egtviz.geometry.estimation.fundamental_ransac` and
:func:`~egtviz.geometry.estimation.fundamental_lmeds` live in
:mod:`egtviz.geometry.estimation`; every robust estimator returns the same
:class:`~egtviz.geometry.estimation.RobustEstimate` record.

Conventions (``docs/conventions.md``): pixels as rows ``(N, 2)``, rays as rows
``(N, 3)``; :math:`m_2^T F m_1 = 0`, :math:`d_2^T E d_1 = 0`.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
import numpy.typing as npt

from ._validate import (
    DegenerateConfigurationError,
    GeometryError,
    as_count,
    as_positive,
    as_up_to_scale,
    short_repr,
)
from .estimation import (
    RobustEstimate,
    _canonical,
    _check_robust_args,
    _denormalize,
    _design,
    _hartley,
    _null_vector_normal,
    _pair,
    _rank2,
    _refine_sampson,
    _essential_linear,
    _essential_projection,
    _iteration_bound,
    _ray_sampson,
    _rays_pair,
    _robust,
    _sample,
)

__all__ = [
    "essential_from_rays_ransac",
    "fundamental_mapsac",
    "fundamental_mestimator",
]

# Consistency factor of the MAD for Gaussian residuals: sigma = 1.4826 median |r|.
_MAD_TO_SIGMA = 1.4826
# Tukey's biweight cut-off, in sigmas (95% efficiency under Gaussian noise).
_TUKEY_C = 4.685
# Inliers of the M-estimator: |r| <= 2.5 sigma, the band LMedS uses.
_INLIER_SIGMAS = 2.5
# The M-estimator's smallest scale, relative to the point spread (as LMedS's floor).
_SIGMA_FLOOR = 1e-9
# 8-ray samples per batch of the robust essential estimator.
_RAYS_BATCH = 128
# chi-square 95% quantile with one degree of freedom: F is a manifold of codimension 1 in the
# 4-D space of correspondences, so a squared distance of an inlier over sigma^2 follows chi^2_1.
_CHI2_1_95 = 3.84


def _residual_parts(Fn: np.ndarray, At: np.ndarray, s1: float, s2: float) -> tuple[np.ndarray, np.ndarray]:
    """Algebraic errors ``e`` (normalised coordinates) and Sampson denominators ``den`` (pixel units)."""
    e = Fn.ravel() @ At
    l2 = Fn[:2] @ At[6:9]  # (F m1)_{1,2}
    l1 = Fn[:, :2].T @ At[2::3]  # (F^T m2)_{1,2}
    den = s2 * s2 * (l2[0] ** 2 + l2[1] ** 2) + s1 * s1 * (l1[0] ** 2 + l1[1] ** 2)
    return e, np.maximum(den, 1e-300)


def _weights(r: np.ndarray, sigma: float, kind: str) -> np.ndarray:
    """IRLS weights of the residuals ``r`` at scale ``sigma`` (formulas in :func:`fundamental_mestimator`)."""
    a = np.abs(r)
    if kind == "torr":
        return np.where(a < 3.0 * sigma, np.minimum(1.0, sigma / np.maximum(a, 1e-300)), 0.0)
    u = a / (_TUKEY_C * sigma)
    return np.where(u < 1.0, (1.0 - u * u) ** 2, 0.0)


def fundamental_mestimator(
    U1: npt.ArrayLike,
    U2: npt.ArrayLike,
    *,
    weight: Literal["tukey", "torr"] = "tukey",
    max_iterations: int = 50,
    F0: npt.ArrayLike | None = None,
) -> RobustEstimate:
    r"""Robust ``F`` by an M-estimator on Sampson residuals (Torr and Murray 1997; H&Z 2nd ed., A6.8).

    Minimises :math:`\sum_i \rho(r_i / \sigma)` over rank-2 ``F``, where
    :math:`r_i = \sqrt{d_i}` is the Sampson distance (H&Z eq. 11.9) in pixels,
    by iteratively reweighted least squares:

    .. math:: \sigma = 1.4826\,\Bigl(1 + \frac{5}{N - 7}\Bigr) \operatorname{med}_i |r_i|, \qquad
              w_i = \frac{\rho'(r_i/\sigma)}{r_i/\sigma}, \qquad
              F \leftarrow \arg\min_{\|f\| = 1} \sum_i w_i \frac{(m_{2i}^T F m_{1i})^2}{g_i^2}

    with the gradient norms :math:`g_i^2` (the Sampson denominators) frozen at
    the previous ``F``, then projected to rank 2 (in Hartley-normalised
    coordinates). Weights, with :math:`u = r / \sigma`: Tukey's biweight
    :math:`w = (1 - (u / 4.685)^2)^2` for :math:`|u| < 4.685`, else 0; or
    Torr's (EGT 2.0's) Huber weights cut off at three sigma,
    :math:`w = \min(1, 1 / |u|)` for :math:`|u| < 3`, else 0. (Plain Huber
    weights, never zero, are not offered: with a third of gross outliers
    their summed pull breaks the estimate down.)
    When the weights have settled, the weighted Sampson cost is minimised
    over rank-2 ``F`` by ``scipy.optimize.least_squares`` (the same minimal
    parameterisation as :func:`~egtviz.geometry.estimation.fundamental_sampson`),
    the weights recomputed after each such step.

    The start is ``F0`` if given, else the least-median-of-squares estimate
    (:func:`~egtviz.geometry.estimation.fundamental_lmeds`): started from the
    plain least-squares ``F``, as in EGT 2.0, an M-estimator is not robust to
    gross outliers, whose leverage moves the start too far. Inliers are
    :math:`|r_i| \le 2.5\sigma` with the final scale.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        weight: ``"tukey"`` or ``"torr"``; both give gross outliers weight 0.
        max_iterations: upper bound on the reweighting iterations.
        F0: optional ``(3, 3)`` start of rank 2 (any nonzero scale).

    Returns:
        :class:`~egtviz.geometry.estimation.RobustEstimate`: ``F`` (rank 2,
        unit Frobenius norm, largest entry positive), the inlier mask and the
        number of reweighting iterations.

    Raises:
        GeometryError: bad types or shapes, NaN/inf, ``N < 8``, mismatched
            ``N``, an unknown ``weight``, a bad ``max_iterations`` or a rank < 2 ``F0``.
        DegenerateConfigurationError: coincident points or rank-deficient data.
    """
    if not isinstance(weight, str) or weight not in ("tukey", "torr"):
        raise GeometryError(f"weight: expected 'tukey' or 'torr', got {short_repr(weight)}")
    iters = as_count(max_iterations, "max_iterations")
    u1, u2 = _pair(U1, U2, 8)
    T1, n1, s1, T2, n2, s2 = _hartley(u1, u2)
    At = _design(n1, n2)
    _null_vector_normal(At)
    if F0 is None:
        start = _robust(u1, u2, mode="lmeds", threshold=1.0, confidence=0.999, max_iterations=2000, seed=0).F
    else:
        start = as_up_to_scale(F0, "F0", (3, 3))
        sv = np.linalg.svd(start, compute_uv=False)
        if sv[1] <= 1e-12 * sv[0]:
            raise GeometryError("F0: expected a matrix of rank 2, got rank < 2")
    Fn = _rank2(np.linalg.inv(T2).T @ start @ np.linalg.inv(T1))
    Fn /= np.linalg.norm(Fn)
    floor = _SIGMA_FLOOR / min(s1, s2)
    # Rousseeuw and Leroy's small-sample correction (as in LMedS): with N close to the 7 degrees of
    # freedom of F the fit absorbs most of the noise and the raw MAD underestimates sigma.
    mad_to_sigma = _MAD_TO_SIGMA * (1.0 + 5.0 / (u1.shape[0] - 7))

    def reweight(Fn: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        e, den = _residual_parts(Fn, At, s1, s2)
        r = e / np.sqrt(den)
        sigma = max(mad_to_sigma * float(np.median(np.abs(r))), floor)
        return _weights(r, sigma, weight), den, sigma

    done = 0
    w, den, sigma = reweight(Fn)
    while done < iters:
        done += 1
        keep = w > 0.0
        if keep.sum() < 8:
            break
        try:
            Fnew = _rank2(_null_vector_normal(At[:, keep] * np.sqrt(w[keep] / den[keep])).reshape(3, 3))
        except DegenerateConfigurationError:
            break
        Fnew /= np.linalg.norm(Fnew)
        if Fnew.ravel() @ Fn.ravel() < 0:
            Fnew = -Fnew
        step = float(np.abs(Fnew - Fn).max())
        Fn = Fnew
        w, den, sigma = reweight(Fn)
        if step < 1e-10:
            break
    # The nonlinear step: weighted Sampson minimisation, weights refreshed between passes.
    for _ in range(3):
        keep = w > 0.0
        if keep.sum() < 8:
            break  # too few weighted points to refine over: F stays the reweighted linear estimate
        Fn = _refine_sampson(Fn, At[:, keep], s1, s2, w[keep], tol=1e-8)
        w, den, sigma = reweight(Fn)
    e, den = _residual_parts(Fn, At, s1, s2)
    inliers = np.abs(e) / np.sqrt(den) <= _INLIER_SIGMAS * sigma
    return RobustEstimate(F=_canonical(_denormalize(Fn, T1, T2)), inliers=inliers, iterations=done)


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
    refits are those of :func:`~egtviz.geometry.estimation.fundamental_ransac`,
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
        :class:`~egtviz.geometry.estimation.RobustEstimate` with ``F``, the
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
    method of :func:`~egtviz.geometry.estimation.essential_from_rays`
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
        :class:`~egtviz.geometry.estimation.RobustEstimate` whose ``F`` field
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
    r1, r2 = _rays_pair(d1, d2, 8)
    n = r1.shape[0]
    At = _design(r1.T, r2.T)
    _null_vector_normal(At, "d1, d2")
    A = At.T
    th2 = tau * tau
    rng = np.random.default_rng(seed)
    best_cost, best_E = math.inf, None
    bound, done = math.inf, 0
    while done < min(bound, iters):
        k = int(min(_RAYS_BATCH, iters - done))
        samples = A[_sample(rng, n, k, 8)]  # (k, 8, 9)
        done += k
        vt = np.linalg.svd(samples, full_matrices=True)[2]
        Es = _essential_projection(vt[:, 8].reshape(k, 3, 3))
        cost = np.minimum(_ray_sampson(Es, r1, r2), th2).sum(axis=1)
        j = int(np.argmin(cost))
        if cost[j] < best_cost:
            best_cost, best_E = float(cost[j]), Es[j]
            w = float((_ray_sampson(best_E[None], r1, r2)[0] < th2).mean())
            bound = _iteration_bound(w, conf, 8)
    assert best_E is not None
    E = best_E
    inl = _ray_sampson(E[None], r1, r2)[0] < th2
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
            E = _essential_linear(a, b, weights / weights.max())
        except DegenerateConfigurationError:
            break
        new = _ray_sampson(E[None], r1, r2)[0] < th2
        if np.array_equal(new, inl):
            break
        inl = new
    return RobustEstimate(F=_canonical(E), inliers=inl, iterations=int(done))
