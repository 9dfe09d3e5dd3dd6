r"""EGT 2.0's M-estimator of the fundamental matrix (``f_Festim`` algorithm 4).

Torr and Murray's iteratively reweighted least squares on Sampson residuals (Hartley & Zisserman,
*Multiple View Geometry*, 2nd ed. (H&Z), appendix A6.8, "Robust cost functions", with the Sampson
distance of section 11.4.3), the scale from the median absolute deviation, then a reweighted
minimisation of the Sampson distance (:func:`~egtviz.geometry.sampson_refinement.refine_sampson`).
The sampling estimators are in :mod:`egtviz.geometry.robust`; this one returns the same
:class:`~egtviz.geometry.robust.RobustEstimate` record.

Conventions (``docs/conventions.md``): pixels as rows ``(N, 2)``; :math:`m_2^T F m_1 = 0`.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_count, as_up_to_scale, short_repr
from .fundamental import canonical_fundamental, normalized_design, null_vector
from .matrices import nearest_rank2, point_pairs
from .robust import RobustEstimate, fundamental_lmeds
from .sampson_refinement import refine_sampson

__all__ = ["fundamental_mestimator"]

# Consistency factor of the MAD for Gaussian residuals: sigma = 1.4826 median |r|.
_MAD_TO_SIGMA = 1.4826
# Tukey's biweight cut-off, in sigmas (95% efficiency under Gaussian noise).
_TUKEY_C = 4.685
# Inliers of the M-estimator: |r| <= 2.5 sigma, the band LMedS uses.
_INLIER_SIGMAS = 2.5
# The M-estimator's smallest scale, relative to the point spread (as LMedS's floor).
_SIGMA_FLOOR = 1e-9


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
    over rank-2 ``F`` by MINPACK's Levenberg-Marquardt (the same minimal
    parameterisation as :func:`~egtviz.geometry.sampson_refinement.fundamental_sampson`),
    the weights recomputed after each such step.

    The start is ``F0`` if given, else the least-median-of-squares estimate
    (:func:`~egtviz.geometry.robust.fundamental_lmeds`): started from the
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
        :class:`~egtviz.geometry.robust.RobustEstimate`: ``F`` (rank 2,
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
    u1, u2 = point_pairs(U1, U2, 8)
    At, T1, T2 = normalized_design(u1, u2)
    null_vector(At)
    Fn = _start(u1, u2, F0, T1, T2)
    s1, s2 = T1[0, 0], T2[0, 0]
    floor = _SIGMA_FLOOR / min(s1, s2)
    # Rousseeuw and Leroy's small-sample correction (as in LMedS): with N close to the 7 degrees of
    # freedom of F the fit absorbs most of the noise and the raw MAD underestimates sigma.
    mad_to_sigma = _MAD_TO_SIGMA * (1.0 + 5.0 / (u1.shape[0] - 7))

    def reweight(Fn: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        e, den = _residual_parts(Fn, At, s1, s2)
        r = e / np.sqrt(den)
        sigma = max(mad_to_sigma * float(np.median(np.abs(r))), floor)
        return _weights(r, sigma, weight), den, sigma

    Fn, done = _irls(Fn, At, reweight, iters)
    Fn, sigma = _refine(Fn, At, s1, s2, reweight)
    e, den = _residual_parts(Fn, At, s1, s2)
    inliers = np.abs(e) / np.sqrt(den) <= _INLIER_SIGMAS * sigma
    return RobustEstimate(F=canonical_fundamental(T2.T @ Fn @ T1), inliers=inliers, iterations=done)


def _start(
    u1: np.ndarray, u2: np.ndarray, F0: npt.ArrayLike | None, T1: np.ndarray, T2: np.ndarray
) -> np.ndarray:
    """The start in normalised coordinates (unit norm, rank 2): ``F0``, or the LMedS estimate."""
    if F0 is None:
        start = fundamental_lmeds(u1, u2).F
    else:
        start = as_up_to_scale(F0, "F0", (3, 3))
        sv = np.linalg.svd(start, compute_uv=False)
        if sv[1] <= 1e-12 * sv[0]:
            raise GeometryError("F0: expected a matrix of rank 2, got rank < 2")
    Fn = nearest_rank2(np.linalg.inv(T2).T @ start @ np.linalg.inv(T1), check=False)
    Fn /= np.linalg.norm(Fn)
    return Fn


def _irls(Fn: np.ndarray, At: np.ndarray, reweight, iters: int) -> tuple[np.ndarray, int]:
    """Iteratively reweighted linear fits (Sampson denominators frozen at the previous ``F``): ``(Fn, iterations)``."""
    done = 0
    w, den, _ = reweight(Fn)
    while done < iters:
        done += 1
        keep = w > 0.0
        if keep.sum() < 8:
            break
        try:
            Fnew = nearest_rank2(null_vector(At[:, keep] * np.sqrt(w[keep] / den[keep])).reshape(3, 3), check=False)
        except DegenerateConfigurationError:
            break
        Fnew /= np.linalg.norm(Fnew)
        if Fnew.ravel() @ Fn.ravel() < 0:
            Fnew = -Fnew
        step = float(np.abs(Fnew - Fn).max())
        Fn = Fnew
        w, den, _ = reweight(Fn)
        if step < 1e-10:
            break
    return Fn, done


def _refine(Fn: np.ndarray, At: np.ndarray, s1: float, s2: float, reweight) -> tuple[np.ndarray, float]:
    """The nonlinear step: weighted Sampson minimisation, the weights refreshed between passes: ``(Fn, sigma)``."""
    w, _, sigma = reweight(Fn)
    for _ in range(3):
        keep = w > 0.0
        if keep.sum() < 8:
            break  # too few weighted points to refine over: F stays the reweighted linear estimate
        Fn = refine_sampson(Fn, At[:, keep], s1, s2, w[keep], tol=1e-8)
        w, _, sigma = reweight(Fn)
    return Fn, sigma
