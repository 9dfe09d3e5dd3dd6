r"""Estimating the fundamental matrix from point correspondences.

EGT's ``f_Festim`` (reference, section 6) offers three estimators; this module
has them and the robust estimators and error measures a lesson needs:

* :func:`fundamental_8point`: the linear, unnormalised 8-point algorithm
  (Hartley & Zisserman 2nd ed., section 11.1).
* :func:`fundamental_normalized_8point`: Hartley's normalised 8-point algorithm
  (H&Z Algorithm 11.1).
* :func:`fundamental_sampson`: iterative minimisation of the Sampson distance
  (H&Z section 11.4.3), started from the normalised 8-point estimate.
* :func:`fundamental_7point`: the minimal 7-point solver (H&Z section 11.1.2).
* :func:`fundamental_ransac`, :func:`fundamental_lmeds`: robust estimation
  from 7-point samples (H&Z section 11.6, Algorithm 4.6).

Essential matrices (H&Z section 9.6): :func:`essential_from_fundamental`,
:func:`fundamental_from_essential`, :func:`decompose_essential`,
:func:`pose_from_essential`.

Conventions (``docs/conventions.md``): points are rows, pixels ``(N, 2)``;
:math:`m_2^T F m_1 = 0`; the pose between the cameras maps camera-1
coordinates to camera-2 coordinates, :math:`X_{c2} = R X_{c1} + t` and
:math:`E = [t]_\times R`. Every estimated ``F`` has rank 2, unit Frobenius norm
and a deterministic sign: its largest-magnitude entry is positive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares

from ._validate import (
    DegenerateConfigurationError,
    GeometryError,
    as_calibration,
    as_matrix,
    as_points,
)

__all__ = [
    "RobustEstimate",
    "decompose_essential",
    "essential_from_fundamental",
    "fundamental_7point",
    "fundamental_8point",
    "fundamental_from_essential",
    "fundamental_lmeds",
    "fundamental_normalized_8point",
    "fundamental_ransac",
    "fundamental_sampson",
    "pose_from_essential",
    "reprojection_error",
    "sampson_distance",
    "symmetric_epipolar_distance",
]

# The second-smallest eigenvalue of A^T A (normalised coordinates) below this
# fraction of the largest means the design matrix has rank < 8.
_RANK_TOL_EIG = 1e-13
# Same test on the singular values of the 7 x 9 design matrix of the 7-point solver.
_RANK_TOL_SV = 1e-10
# Inliers needed before a robust estimate can be refitted with the 8-point algorithm.
_MIN_REFIT = 8
# Hypotheses drawn per batch by the robust estimators.
_BATCH = 48


@dataclass(frozen=True, eq=False)
class RobustEstimate:
    """Result of :func:`fundamental_ransac` or :func:`fundamental_lmeds`."""

    F: np.ndarray
    """(3, 3) fundamental matrix, rank 2, unit Frobenius norm, ``m2^T F m1 = 0``."""
    inliers: np.ndarray
    """(N,) bool mask of the correspondences consistent with ``F``."""
    iterations: int
    """Number of 7-point samples drawn before the adaptive bound stopped the search."""


# --------------------------------------------------------------------------- helpers


def _pair(U1: npt.ArrayLike, U2: npt.ArrayLike, min_count: int) -> tuple[np.ndarray, np.ndarray]:
    """Validate two ``(N, 2)`` pixel arrays with the same ``N >= min_count``."""
    u1 = as_points(U1, "U1", 2, min_count=min_count)
    u2 = as_points(U2, "U2", 2, min_count=min_count)
    if u1.shape[0] != u2.shape[0]:
        raise GeometryError(
            f"U1, U2: expected the same number of points, got {u1.shape[0]} and {u2.shape[0]}"
        )
    return u1, u2


def _hartley(u: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray, float]:
    r"""Hartley's isotropic normalisation (H&Z section 4.4.4).

    Returns ``T`` (3, 3), the normalised homogeneous points ``(N, 3)`` and the
    scale ``s``: the centroid moves to the origin and the mean distance from it
    becomes :math:`\sqrt 2`.
    """
    c = u.mean(axis=0)
    d = u - c
    mean_dist = float(np.sqrt(np.einsum("ij,ij->i", d, d)).mean())
    if not mean_dist > 1e-9 * max(1.0, float(np.abs(c).max())):
        raise DegenerateConfigurationError(f"{name}: all points coincide, F is undefined")
    s = math.sqrt(2.0) / mean_dist
    T = np.array([[s, 0.0, -s * c[0]], [0.0, s, -s * c[1]], [0.0, 0.0, 1.0]])
    h = np.empty((u.shape[0], 3))
    h[:, :2] = d * s
    h[:, 2] = 1.0
    return T, h, s


def _homogeneous(u: np.ndarray) -> np.ndarray:
    h = np.empty((u.shape[0], 3))
    h[:, :2] = u
    h[:, 2] = 1.0
    return h


def _design(h1: np.ndarray, h2: np.ndarray) -> np.ndarray:
    r"""Design matrix ``(N, 9)``: row :math:`m_2^T \otimes m_1^T`, so ``A f = m2^T F m1`` with ``f = F.ravel()``."""
    return (h2[:, :, None] * h1[:, None, :]).reshape(h1.shape[0], 9)


def _null_vector_normal(A: np.ndarray) -> np.ndarray:
    """Unit ``f`` minimising ``|A f|`` from the 9x9 normal matrix; raise if ``rank A < 8``."""
    w, v = np.linalg.eigh(A.T @ A)
    if w[1] <= _RANK_TOL_EIG * w[-1]:
        raise DegenerateConfigurationError(
            "U1, U2: degenerate configuration, the design matrix has rank < 8 "
            "(repeated, collinear or coplanar points?)"
        )
    return v[:, 0]


def _rank2(F: np.ndarray) -> np.ndarray:
    """Closest rank-2 matrix in Frobenius norm (H&Z section 11.1.1)."""
    U, S, Vt = np.linalg.svd(F)
    return (U[:, :2] * S[:2]) @ Vt[:2]


def _canonical(F: np.ndarray) -> np.ndarray:
    """Unit Frobenius norm, largest-magnitude entry positive."""
    F = F / np.linalg.norm(F)
    if F.flat[np.argmax(np.abs(F))] < 0:
        F = -F
    return F


def _finalize(F: np.ndarray) -> np.ndarray:
    return _canonical(_rank2(F))


def _denormalize(Fn: np.ndarray, T1: np.ndarray, T2: np.ndarray) -> np.ndarray:
    return T2.T @ Fn @ T1


def _sampson_normalized(
    Fs: np.ndarray, h1: np.ndarray, h2: np.ndarray, s1: float, s2: float
) -> np.ndarray:
    r"""Pixel Sampson distances ``(M, N)`` of ``M`` candidates ``Fs`` given in normalised coordinates.

    With :math:`F = T_2^T F_n T_1` the algebraic error is unchanged and the
    first two coordinates of the epipolar lines scale by :math:`s_2` (image 2)
    and :math:`s_1` (image 1), so no candidate needs denormalising.
    """
    M, N = Fs.shape[0], h1.shape[0]
    e = Fs.reshape(M, 9) @ _design(h1, h2).T
    l2 = (Fs[:, :2, :].reshape(2 * M, 3) @ h1.T).reshape(M, 2, N)
    l1 = (Fs.transpose(0, 2, 1)[:, :2, :].reshape(2 * M, 3) @ h2.T).reshape(M, 2, N)
    den = (s2 * s2) * np.einsum("mkn,mkn->mn", l2, l2) + (s1 * s1) * np.einsum("mkn,mkn->mn", l1, l1)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = e * e / den
    return np.where(np.isfinite(d), d, np.inf)


def _det3(M: np.ndarray) -> np.ndarray:
    """Determinants of a stack of 3x3 matrices ``(..., 3, 3)``, written out."""
    return (
        M[..., 0, 0] * (M[..., 1, 1] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 1])
        - M[..., 0, 1] * (M[..., 1, 0] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 0])
        + M[..., 0, 2] * (M[..., 1, 0] * M[..., 2, 1] - M[..., 1, 1] * M[..., 2, 0])
    )


def _cubic_solutions(F1: np.ndarray, F2: np.ndarray, imag_tol: float = 1e-7) -> tuple[np.ndarray, np.ndarray]:
    r"""Rank-2 members of the pencils :math:`a F_1 + b F_2` (stacks ``(K, 3, 3)``).

    :math:`\det(a F_1 + b F_2)` is a homogeneous cubic
    :math:`k_3 a^3 + k_2 a^2 b + k_1 a b^2 + k_0 b^3`; it is solved for
    :math:`a/b` or :math:`b/a`, whichever end coefficient is larger, so the
    companion matrix never divides by a vanishing leading coefficient.

    Returns candidates ``(K, 3, 3, 3)`` and a ``(K, 3)`` mask of the real roots
    (at least one per pencil).
    """
    k3 = _det3(F1)
    k0 = _det3(F2)
    pp = _det3(F1 + F2)
    pm = _det3(F1 - F2)
    k2 = 0.5 * (pp - pm) - k0
    k1 = 0.5 * (pp + pm) - k3
    first = np.abs(k3) >= np.abs(k0)  # solve for r = a / b
    lead = np.where(first, k3, k0)
    c2 = np.where(first, k2, k1)
    c1 = np.where(first, k1, k2)
    c0 = np.where(first, k0, k3)
    lead = np.where(lead == 0.0, 1e-300, lead)
    K = F1.shape[0]
    comp = np.zeros((K, 3, 3))
    comp[:, 0, 0] = -c2 / lead
    comp[:, 0, 1] = -c1 / lead
    comp[:, 0, 2] = -c0 / lead
    comp[:, 1, 0] = 1.0
    comp[:, 2, 1] = 1.0
    comp = np.where(np.isfinite(comp), comp, 0.0)
    roots = np.linalg.eigvals(comp)
    re = roots.real
    im = np.abs(roots.imag)
    real = im <= imag_tol * (1.0 + np.abs(re))
    real[np.arange(K), np.argmin(im, axis=1)] = True
    r = re[:, :, None, None]
    cand = np.where(
        first[:, None, None, None], r * F1[:, None] + F2[:, None], F1[:, None] + r * F2[:, None]
    )
    return cand, real


# --------------------------------------------------------------------------- linear solvers


def fundamental_8point(U1: npt.ArrayLike, U2: npt.ArrayLike) -> np.ndarray:
    r"""Linear (unnormalised) 8-point algorithm (H&Z 2nd ed., section 11.1).

    Each correspondence gives one linear equation in the entries
    :math:`f = \mathrm{vec}(F)`:

    .. math:: m_2^T F m_1 = (m_2^T \otimes m_1^T) f = 0, \qquad
              \hat f = \arg\min_{\|f\| = 1} \|A f\|,

    solved by the SVD of the ``(N, 9)`` design matrix ``A`` in raw pixel
    coordinates; rank 2 is then enforced by zeroing the smallest singular value
    (H&Z section 11.1.1). Without normalisation ``A`` is badly conditioned
    (H&Z section 11.2): compare :func:`fundamental_normalized_8point`.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.

    Returns:
        ``(3, 3)`` ``F`` with :math:`m_2^T F m_1 = 0`, rank 2, unit Frobenius
        norm, largest-magnitude entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8`` or mismatched ``N``.
        DegenerateConfigurationError: coincident points or a design matrix of
            rank below 8 (e.g. collinear or coplanar scene points).
    """
    u1, u2 = _pair(U1, U2, 8)
    # The rank test is done in normalised coordinates, where it is meaningful.
    _, n1, _ = _hartley(u1, "U1")
    _, n2, _ = _hartley(u2, "U2")
    _null_vector_normal(_design(n1, n2))
    A = _design(_homogeneous(u1), _homogeneous(u2))
    f = np.linalg.svd(A, full_matrices=False)[2][-1]
    return _finalize(f.reshape(3, 3))


def fundamental_normalized_8point(U1: npt.ArrayLike, U2: npt.ArrayLike) -> np.ndarray:
    r"""Hartley's normalised 8-point algorithm (H&Z 2nd ed., Algorithm 11.1).

    Points are normalised by similarities :math:`\hat m_1 = T_1 m_1`,
    :math:`\hat m_2 = T_2 m_2` (centroid at the origin, mean distance
    :math:`\sqrt 2`); the linear solution :math:`\hat F` (smallest eigenvector of
    the 9x9 matrix :math:`A^T A`) is projected to rank 2 and denormalised:

    .. math:: F = T_2^T \hat F T_1 .

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.

    Returns:
        ``(3, 3)`` ``F``, rank 2, unit Frobenius norm, largest entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8`` or mismatched ``N``.
        DegenerateConfigurationError: coincident points or rank-deficient data.
    """
    u1, u2 = _pair(U1, U2, 8)
    T1, n1, _ = _hartley(u1, "U1")
    T2, n2, _ = _hartley(u2, "U2")
    Fn = _rank2(_null_vector_normal(_design(n1, n2)).reshape(3, 3))
    return _canonical(_denormalize(Fn, T1, T2))


def fundamental_7point(U1: npt.ArrayLike, U2: npt.ArrayLike) -> list[np.ndarray]:
    r"""Minimal 7-point solver (H&Z 2nd ed., section 11.1.2).

    Seven correspondences leave a two-dimensional null space
    :math:`\alpha F_1 + \beta F_2` of the 7x9 design matrix; the singularity
    constraint

    .. math:: \det(\alpha F_1 + \beta F_2) = 0

    is a cubic with one or three real roots, each giving a solution. The
    computation runs in Hartley-normalised coordinates.

    Args:
        U1: exactly seven pixels ``(7, 2)`` in image 1.
        U2: the seven corresponding pixels in image 2.

    Returns:
        A list of one or three ``(3, 3)`` matrices, each rank 2, unit
        Frobenius norm, largest entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, or not exactly seven points.
        DegenerateConfigurationError: the null space has dimension above 2.
    """
    u1, u2 = _pair(U1, U2, 7)
    if u1.shape[0] != 7:
        raise GeometryError(f"U1: the 7-point algorithm needs exactly 7 points, got {u1.shape[0]}")
    T1, n1, _ = _hartley(u1, "U1")
    T2, n2, _ = _hartley(u2, "U2")
    _, s, vt = np.linalg.svd(_design(n1, n2))
    if s[6] <= _RANK_TOL_SV * s[0]:
        raise DegenerateConfigurationError(
            "U1, U2: degenerate configuration, the 7x9 design matrix has rank < 7"
        )
    cand, real = _cubic_solutions(vt[7].reshape(1, 3, 3), vt[8].reshape(1, 3, 3))
    out = []
    for Fn in cand[0][real[0]]:
        out.append(_finalize(_denormalize(Fn, T1, T2)))
    return out


# --------------------------------------------------------------------------- Sampson refinement


def _rodrigues(w: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(K, 3, 3)`` from rotation vectors ``(K, 3)``."""
    th = np.linalg.norm(w, axis=1)
    small = th < 1e-12
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th**2 / 6.0, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th**2 / 24.0, (1.0 - np.cos(ths)) / ths**2)
    W = np.zeros((w.shape[0], 3, 3))
    W[:, 0, 1], W[:, 0, 2], W[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    W[:, 1, 0], W[:, 2, 0], W[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    return np.eye(3) + a[:, None, None] * W + b[:, None, None] * (W @ W)


def _refine_sampson(Fn0: np.ndarray, h1: np.ndarray, h2: np.ndarray, s1: float, s2: float) -> np.ndarray:
    r"""Minimise the pixel Sampson distance over rank-2 ``F`` in normalised coordinates.

    Parameterisation (7 parameters, exactly rank 2):
    :math:`F = U_0 R(\omega_1)\,\mathrm{diag}(1, \sigma, 0)\,R(\omega_2)^T V_0^T`.
    """
    U0, S, V0t = np.linalg.svd(Fn0)
    p0 = np.zeros(7)
    p0[6] = S[1] / S[0]
    V0 = V0t.T
    e2 = s2 * s2
    e1 = s1 * s1
    kron = _design(h1, h2)
    mask2 = np.array([1.0, 1.0, 0.0])

    def f_of(P: np.ndarray) -> np.ndarray:
        R1 = _rodrigues(P[:, :3])
        R2 = _rodrigues(P[:, 3:6])
        D = np.zeros((P.shape[0], 3, 3))
        D[:, 0, 0] = 1.0
        D[:, 1, 1] = P[:, 6]
        return U0 @ R1 @ D @ R2.transpose(0, 2, 1) @ V0.T

    def parts(p: np.ndarray):
        F = f_of(p[None])[0]
        l2 = h1 @ F.T  # F m1, lines in image 2 (normalised)
        l1 = h2 @ F  # F^T m2, lines in image 1
        e = kron @ F.ravel()
        den = e2 * (l2[:, 0] ** 2 + l2[:, 1] ** 2) + e1 * (l1[:, 0] ** 2 + l1[:, 1] ** 2)
        den = np.maximum(den, 1e-300)
        return F, l1, l2, e, den

    def fun(p: np.ndarray) -> np.ndarray:
        _, _, _, e, den = parts(p)
        return e / np.sqrt(den)

    def jac(p: np.ndarray) -> np.ndarray:
        _, l1, l2, e, den = parts(p)
        rs = 1.0 / np.sqrt(den)
        a = (e2 * mask2) * l2  # d den / dF_ij = 2 (a_i m1_j + m2_i b_j)
        b = (e1 * mask2) * l1
        g = e * rs / den
        JF = kron * rs[:, None] - g[:, None] * (
            (a[:, :, None] * h1[:, None, :]).reshape(-1, 9) + (h2[:, :, None] * b[:, None, :]).reshape(-1, 9)
        )
        h = 1e-6
        P = np.repeat(p[None], 14, axis=0)
        idx = np.arange(7)
        P[idx, idx] += h
        P[7 + idx, idx] -= h
        Fs = f_of(P).reshape(14, 9)
        dF = (Fs[:7] - Fs[7:]).T / (2.0 * h)  # (9, 7)
        return JF @ dF

    r0 = fun(p0)
    cost0 = float(r0 @ r0)
    res = least_squares(fun, p0, jac=jac, method="lm", xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=60)
    F = f_of(res.x[None])[0]
    if not (np.all(np.isfinite(F)) and 2.0 * res.cost <= cost0):
        return Fn0
    return F


def fundamental_sampson(
    U1: npt.ArrayLike, U2: npt.ArrayLike, F0: npt.ArrayLike | None = None
) -> np.ndarray:
    r"""Iterative minimisation of the Sampson distance (H&Z 2nd ed., section 11.4.3).

    Minimises the first-order geometric error (H&Z eq. 11.9)

    .. math:: \sum_i \frac{(m_{2i}^T F m_{1i})^2}
              {(F m_{1i})_1^2 + (F m_{1i})_2^2 + (F^T m_{2i})_1^2 + (F^T m_{2i})_2^2}

    with ``scipy.optimize.least_squares`` (Levenberg-Marquardt, analytic
    Jacobian) over a minimal rank-2 parameterisation: in Hartley-normalised
    coordinates :math:`F = U R(\omega_1)\,\mathrm{diag}(1, \sigma, 0)\,R(\omega_2)^T V^T`
    (7 parameters, H&Z section 11.4.2). The result is exactly rank 2 and its
    Sampson cost never exceeds that of the start.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        F0: optional ``(3, 3)`` starting estimate (projected to rank 2);
            default :func:`fundamental_normalized_8point`.

    Returns:
        ``(3, 3)`` ``F``, rank 2, unit Frobenius norm, largest entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8``, mismatched ``N``, or a
            rank < 2 ``F0``.
        DegenerateConfigurationError: coincident points or rank-deficient data.
    """
    u1, u2 = _pair(U1, U2, 8)
    T1, n1, s1 = _hartley(u1, "U1")
    T2, n2, s2 = _hartley(u2, "U2")
    if F0 is None:
        Fn0 = _rank2(_null_vector_normal(_design(n1, n2)).reshape(3, 3))
    else:
        F0 = as_matrix(F0, "F0", (3, 3))
        Fn0 = np.linalg.inv(T2).T @ F0 @ np.linalg.inv(T1)
        sv = np.linalg.svd(Fn0, compute_uv=False)
        if sv[1] <= 1e-12 * sv[0]:
            raise GeometryError("F0: expected a matrix of rank 2, got rank < 2")
        Fn0 = _rank2(Fn0)
    Fn0 = Fn0 / np.linalg.norm(Fn0)
    return _canonical(_denormalize(_refine_sampson(Fn0, n1, n2, s1, s2), T1, T2))


# --------------------------------------------------------------------------- robust estimation


def _check_robust_args(confidence: float, max_iterations: int) -> None:
    if not (0.0 < float(confidence) < 1.0):
        raise GeometryError(f"confidence: expected a number in (0, 1), got {confidence!r}")
    if int(max_iterations) != max_iterations or max_iterations < 1:
        raise GeometryError(f"max_iterations: expected a positive integer, got {max_iterations!r}")


def _iteration_bound(inlier_ratio: float, confidence: float) -> float:
    r"""Adaptive number of samples (H&Z Algorithm 4.5): :math:`\log(1-p) / \log(1 - w^7)`."""
    p = min(max(inlier_ratio, 0.0), 1.0) ** 7
    if p >= 1.0 - 1e-15:
        return 1.0
    if p <= 1e-300:
        return math.inf
    return math.ceil(math.log(1.0 - confidence) / math.log1p(-p))


def _sample(rng: np.random.Generator, n: int, k: int) -> np.ndarray:
    """``k`` samples of 7 distinct indices in ``range(n)``, ``(k, 7)``."""
    if n < 64:
        return np.argpartition(rng.random((k, n)), 7, axis=1)[:, :7]
    out = []
    got = 0
    while got < k:
        draw = rng.integers(0, n, size=(k + 8, 7))
        srt = np.sort(draw, axis=1)
        ok = np.all(srt[:, 1:] != srt[:, :-1], axis=1)
        out.append(draw[ok])
        got += int(ok.sum())
    return np.concatenate(out)[:k]


def _seven_point_batch(A7: np.ndarray) -> np.ndarray:
    """Real 7-point candidates (normalised coordinates) for a batch of 7x9 design matrices."""
    K = A7.shape[0]
    try:
        X = np.linalg.solve(A7[:, :, :7], -A7[:, :, 7:])  # (K, 7, 2)
        N1 = np.zeros((K, 9))
        N2 = np.zeros((K, 9))
        N1[:, :7], N1[:, 7] = X[:, :, 0], 1.0
        N2[:, :7], N2[:, 8] = X[:, :, 1], 1.0
    except np.linalg.LinAlgError:
        vt = np.linalg.svd(A7)[2]
        N1, N2 = vt[:, 7], vt[:, 8]
    cand, real = _cubic_solutions(N1.reshape(K, 3, 3), N2.reshape(K, 3, 3))
    cand = cand[real]
    ok = np.all(np.isfinite(cand.reshape(-1, 9)), axis=1)
    cand = cand[ok]
    norms = np.linalg.norm(cand.reshape(-1, 9), axis=1)
    return cand / np.where(norms > 0, norms, 1.0)[:, None, None]


def _refit(
    inl: np.ndarray, n1: np.ndarray, n2: np.ndarray, s1: float, s2: float, Fn_best: np.ndarray
) -> np.ndarray:
    """Normalised 8-point then Sampson refinement on the inliers (normalised coordinates)."""
    if inl.sum() < _MIN_REFIT:
        return Fn_best
    h1, h2 = n1[inl], n2[inl]
    try:
        Fn = _rank2(_null_vector_normal(_design(h1, h2)).reshape(3, 3))
    except DegenerateConfigurationError:
        Fn = _rank2(Fn_best)
    Fn = Fn / np.linalg.norm(Fn)
    return _refine_sampson(Fn, h1, h2, s1, s2)


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
    u1, u2 = _pair(U1, U2, _MIN_REFIT)
    _check_robust_args(confidence, max_iterations)
    N = u1.shape[0]
    T1, n1, s1 = _hartley(u1, "U1")
    T2, n2, s2 = _hartley(u2, "U2")
    A = _design(n1, n2)
    rng = np.random.default_rng(seed)
    th2 = threshold * threshold
    kth = N // 2
    lmeds_scale = (1.4826 * (1.0 + 5.0 / (N - 7))) ** 2 * 2.5**2
    best_cost = math.inf
    best_F: np.ndarray | None = None
    bound = math.inf
    done = 0
    while done < min(bound, max_iterations):
        k = int(min(_BATCH, max_iterations - done))
        cand = _seven_point_batch(A[_sample(rng, N, k)])
        done += k
        if cand.shape[0] == 0:
            continue
        d = _sampson_normalized(cand, n1, n2, s1, s2)
        if mode == "ransac":
            cost = np.minimum(d, th2).sum(axis=1)
        else:
            cost = np.partition(d, kth, axis=1)[:, kth]
        j = int(np.argmin(cost))
        if cost[j] < best_cost:
            best_cost = float(cost[j])
            best_F = cand[j]
            if mode == "ransac":
                w = float((d[j] < th2).mean())
            else:
                w = float((d[j] <= lmeds_scale * max(best_cost, 1e-24)).mean())
            bound = _iteration_bound(w, confidence)
    if best_F is None:
        raise DegenerateConfigurationError("U1, U2: no 7-point sample gave a fundamental matrix")

    def classify(Fn: np.ndarray) -> np.ndarray:
        d = _sampson_normalized(Fn[None], n1, n2, s1, s2)[0]
        if mode == "ransac":
            return d < th2
        return d <= lmeds_scale * max(float(np.median(d)), 1e-24)

    inl = classify(best_F)
    if inl.sum() < _MIN_REFIT:
        raise DegenerateConfigurationError(
            f"U1, U2: the best model has only {int(inl.sum())} inliers, at least {_MIN_REFIT} are needed"
        )
    Fn = best_F
    for _ in range(3):
        Fn = _refit(inl, n1, n2, s1, s2, Fn)
        new = classify(Fn)
        if np.array_equal(new, inl) or new.sum() < _MIN_REFIT:
            break
        inl = new
    inl = classify(Fn)
    F = _canonical(_denormalize(Fn, T1, T2))
    return RobustEstimate(F=F, inliers=inl, iterations=int(done))


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
    best hypothesis so far and the confidence :math:`p`. The best hypothesis's
    inliers (:math:`d_i < \tau^2`) are refitted with the normalised 8-point
    algorithm and a Sampson refinement; the inlier set is updated and refitted
    until it is stable (at most three times).

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
    thr = float(threshold)
    if not (math.isfinite(thr) and thr > 0):
        raise GeometryError(f"threshold: expected a positive number of pixels, got {threshold!r}")
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
    The inliers are refitted with the normalised 8-point algorithm and a Sampson
    refinement. LMedS breaks down with more than 50% outliers.

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


# --------------------------------------------------------------------------- error measures


def _lines_and_error(F: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike):
    Fm = as_matrix(F, "F", (3, 3))
    u1, u2 = _pair(U1, U2, 1)
    h1 = _homogeneous(u1)
    h2 = _homogeneous(u2)
    l2 = h1 @ Fm.T  # F m1
    l1 = h2 @ Fm  # F^T m2
    e = np.einsum("ij,ij->i", h2, l2)
    return l1, l2, e


def sampson_distance(F: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike) -> np.ndarray:
    r"""Squared Sampson distance of each correspondence (H&Z 2nd ed., eq. 11.9).

    .. math:: d_i = \frac{(m_{2i}^T F m_{1i})^2}
              {(F m_{1i})_1^2 + (F m_{1i})_2^2 + (F^T m_{2i})_1^2 + (F^T m_{2i})_2^2}

    The first-order approximation of the squared distance (pixels squared) to
    the nearest correspondence that satisfies the epipolar constraint. It does
    not depend on the scale of ``F``. ``inf`` where the denominator vanishes.

    Args:
        F: ``(3, 3)`` fundamental matrix, ``m2^T F m1 = 0``.
        U1: ``(N, 2)`` pixels in image 1.
        U2: ``(N, 2)`` pixels in image 2.

    Returns:
        ``(N,)`` squared distances in pixels squared.
    """
    l1, l2, e = _lines_and_error(F, U1, U2)
    den = l2[:, 0] ** 2 + l2[:, 1] ** 2 + l1[:, 0] ** 2 + l1[:, 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        d = e * e / den
    return np.where(den > 0, d, np.inf)


def symmetric_epipolar_distance(F: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike) -> np.ndarray:
    r"""Squared symmetric epipolar distance of each correspondence (H&Z 2nd ed., eq. 11.10).

    The sum of the squared distances from each point to the epipolar line of
    its partner:

    .. math:: d_i = (m_{2i}^T F m_{1i})^2 \left(
              \frac{1}{(F m_{1i})_1^2 + (F m_{1i})_2^2} +
              \frac{1}{(F^T m_{2i})_1^2 + (F^T m_{2i})_2^2} \right)

    Args:
        F: ``(3, 3)`` fundamental matrix.
        U1: ``(N, 2)`` pixels in image 1.
        U2: ``(N, 2)`` pixels in image 2.

    Returns:
        ``(N,)`` squared distances in pixels squared (``inf`` for a line at infinity).
    """
    l1, l2, e = _lines_and_error(F, U1, U2)
    a = l2[:, 0] ** 2 + l2[:, 1] ** 2
    b = l1[:, 0] ** 2 + l1[:, 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        d = e * e * (1.0 / a + 1.0 / b)
    return np.where((a > 0) & (b > 0), d, np.inf)


def reprojection_error(
    P1: npt.ArrayLike, P2: npt.ArrayLike, X: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike
) -> np.ndarray:
    r"""Per-point RMS reprojection error in the two images (H&Z 2nd ed., eq. 12.1).

    .. math:: r_i = \sqrt{\tfrac12 \left( \|\pi(P_1 X_i) - u_{1i}\|^2 +
              \|\pi(P_2 X_i) - u_{2i}\|^2 \right)}

    where :math:`\pi` divides by the third coordinate.

    Args:
        P1: ``(3, 4)`` projection matrix of camera 1.
        P2: ``(3, 4)`` projection matrix of camera 2.
        X: ``(N, 3)`` world points.
        U1: ``(N, 2)`` measured pixels in image 1.
        U2: ``(N, 2)`` measured pixels in image 2.

    Returns:
        ``(N,)`` errors in pixels; NaN for a point on a camera's principal
        plane (no image).
    """
    P1 = as_matrix(P1, "P1", (3, 4))
    P2 = as_matrix(P2, "P2", (3, 4))
    Xw = as_points(X, "X", 3, min_count=1)
    u1, u2 = _pair(U1, U2, 1)
    if Xw.shape[0] != u1.shape[0]:
        raise GeometryError(f"X, U1: expected the same number of points, got {Xw.shape[0]} and {u1.shape[0]}")
    Xh = _homogeneous(Xw)
    total = np.zeros(Xw.shape[0])
    for P, u in ((P1, u1), (P2, u2)):
        x = Xh @ P.T
        w = x[:, 2]
        ok = np.abs(w) > 1e-12 * np.linalg.norm(x, axis=1)
        wsafe = np.where(ok, w, 1.0)
        px = x[:, :2] / wsafe[:, None]
        total += np.where(ok, np.sum((px - u) ** 2, axis=1), np.nan)
    return np.sqrt(0.5 * total)


# --------------------------------------------------------------------------- essential matrix


def essential_from_fundamental(F: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike) -> np.ndarray:
    r"""Essential matrix from ``F`` and the calibrations (H&Z 2nd ed., eq. 9.12).

    .. math:: E = K_2^T F K_1

    Returned with unit Frobenius norm (positive rescaling only: the sign of
    ``F`` is kept).

    Args:
        F: ``(3, 3)`` fundamental matrix, ``m2^T F m1 = 0``.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.
    """
    F = as_matrix(F, "F", (3, 3))
    E = as_calibration(K2, "K2").T @ F @ as_calibration(K1, "K1")
    n = np.linalg.norm(E)
    if n == 0:
        raise GeometryError("F: expected a nonzero matrix")
    return E / n


def fundamental_from_essential(E: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike) -> np.ndarray:
    r"""Fundamental matrix from ``E`` and the calibrations (H&Z 2nd ed., eq. 9.12).

    .. math:: F = K_2^{-T} E K_1^{-1}

    Returned with unit Frobenius norm (positive rescaling only).

    Args:
        E: ``(3, 3)`` essential matrix, ``x2^T E x1 = 0`` in normalised coordinates.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.
    """
    E = as_matrix(E, "E", (3, 3))
    F = np.linalg.inv(as_calibration(K2, "K2")).T @ E @ np.linalg.inv(as_calibration(K1, "K1"))
    n = np.linalg.norm(F)
    if n == 0:
        raise GeometryError("E: expected a nonzero matrix")
    return F / n


def decompose_essential(E: npt.ArrayLike) -> list[tuple[np.ndarray, np.ndarray]]:
    r"""The four poses compatible with an essential matrix (H&Z 2nd ed., Result 9.19, section 9.6.2).

    With :math:`E = U\,\mathrm{diag}(1, 1, 0)\,V^T` (:math:`\det U = \det V = 1`)
    and :math:`W = \begin{bmatrix}0&-1&0\\1&0&0\\0&0&1\end{bmatrix}`:

    .. math:: R \in \{U W V^T,\ U W^T V^T\}, \qquad t = \pm u_3 ,

    where :math:`u_3` is the last column of :math:`U` (unit norm). Each pair
    satisfies :math:`E \simeq [t]_\times R` with :math:`X_{c2} = R X_{c1} + t`.

    Args:
        E: ``(3, 3)`` essential matrix (any nonzero scale; noise is tolerated,
            the closest essential matrix is used).

    Returns:
        ``[(R1, t), (R1, -t), (R2, t), (R2, -t)]``, rotations ``(3, 3)``, unit ``t`` ``(3,)``.

    Raises:
        GeometryError: bad shape, NaN/inf, or ``E`` of rank below 2.
    """
    E = as_matrix(E, "E", (3, 3))
    U, S, Vt = np.linalg.svd(E)
    if S[0] == 0 or S[1] <= 1e-9 * S[0]:
        raise GeometryError("E: expected an essential matrix of rank 2")
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    Ra = U @ W @ Vt
    Rb = U @ W.T @ Vt
    t = U[:, 2].copy()
    return [(Ra, t), (Ra, -t), (Rb, t.copy()), (Rb, -t)]


def _depths(R: np.ndarray, t: np.ndarray, h1: np.ndarray, h2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Depths :math:`z_1, z_2` minimising :math:`\|z_1 R x_1 + t - z_2 x_2\|` per point (NaN if parallel)."""
    a = h1 @ R.T
    b = h2
    aa = np.einsum("ij,ij->i", a, a)
    bb = np.einsum("ij,ij->i", b, b)
    ab = np.einsum("ij,ij->i", a, b)
    at = a @ t
    bt = b @ t
    det = aa * bb - ab * ab
    ok = det > 1e-14 * aa * bb
    dets = np.where(ok, det, 1.0)
    # Normal equations: [aa, -ab; ab, -bb] [z1; z2] = [-at; -bt]
    z1 = (-at * bb + ab * bt) / dets
    z2 = (aa * bt - ab * at) / dets
    return np.where(ok, z1, np.nan), np.where(ok, z2, np.nan)


def pose_from_essential(
    E: npt.ArrayLike, x1n: npt.ArrayLike, x2n: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Relative pose from ``E`` by the cheirality test (H&Z 2nd ed., section 9.6.3).

    Of the four poses of :func:`decompose_essential` the one that puts the most
    triangulated points in front of both cameras is chosen. Depths solve, per
    point, the two-ray least-squares problem

    .. math:: \min_{z_1, z_2} \| z_1 R x_1 + t - z_2 x_2 \| ,

    and a point is in front if :math:`z_1 > 0` and :math:`z_2 > 0`.
    ``cv2.recoverPose`` uses the same convention (:math:`X_{c2} = R X_{c1} + t`).

    Args:
        E: ``(3, 3)`` essential matrix, :math:`x_2^T E x_1 = 0`.
        x1n: ``(N, 2)`` normalised (calibrated) coordinates :math:`K_1^{-1} m_1` in image 1.
        x2n: ``(N, 2)`` normalised coordinates in image 2.

    Returns:
        ``(R, t, in_front)``: rotation ``(3, 3)``, unit translation ``(3,)``
        (the baseline's scale is unobservable) and the ``(N,)`` bool mask of
        points in front of both cameras.
    """
    sols = decompose_essential(E)
    a1 = as_points(x1n, "x1n", 2, min_count=1)
    a2 = as_points(x2n, "x2n", 2, min_count=1)
    if a1.shape[0] != a2.shape[0]:
        raise GeometryError(
            f"x1n, x2n: expected the same number of points, got {a1.shape[0]} and {a2.shape[0]}"
        )
    h1 = _homogeneous(a1)
    h2 = _homogeneous(a2)
    best = None
    for R, t in sols:
        z1, z2 = _depths(R, t, h1, h2)
        mask = (z1 > 0) & (z2 > 0)
        if best is None or mask.sum() > best[2].sum():
            best = (R, t, mask)
    assert best is not None
    return best

