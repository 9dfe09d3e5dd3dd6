r"""Estimating the fundamental matrix from point correspondences.

EGT's ``f_Festim`` offers the first three estimators below and EGT 2.0 adds
robust ones; this module has the linear and iterative estimators, RANSAC and
LMedS, and the error measures a lesson needs (EGT 2.0's M-estimator and
MAPSAC, and the robust essential matrix from rays, are in
:mod:`egtviz.geometry.robust`):

* :func:`fundamental_8point`: the linear, unnormalised 8-point algorithm
  (Hartley & Zisserman 2nd ed., section 11.1).
* :func:`fundamental_normalized_8point`: Hartley's normalised 8-point algorithm
  (H&Z Algorithm 11.1).
* :func:`fundamental_sampson`: iterative minimisation of the Sampson distance
  (H&Z section 11.4.3), started from the normalised 8-point estimate.
* :func:`fundamental_7point`: the minimal 7-point solver (H&Z section 11.1.2).
* :func:`fundamental_ransac`, :func:`fundamental_lmeds`: robust estimation
  from 7-point samples (H&Z section 11.6, Algorithm 11.4; adaptive
  sampling, Algorithm 4.5). LMedS works from 8 points on.

Essential matrices (H&Z section 9.6; the E <-> F conversions live in
:mod:`egtviz.geometry.epipolar`): :func:`decompose_essential`,
:func:`pose_from_essential`; :func:`essential_from_correspondences`
estimates E from calibrated correspondences, :func:`essential_from_rays` from
corresponding rays (bearing vectors, mirror points).

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
from scipy.linalg import lapack as _lapack
from scipy.optimize import least_squares

from ._validate import (
    DegenerateConfigurationError,
    GeometryError,
    as_calibration,
    as_count,
    as_positive,
    as_points,
    as_scalar,
    as_up_to_scale,
    as_up_to_scale_rows,
    short_repr,
)

__all__ = [
    "RobustEstimate",
    "decompose_essential",
    "essential_from_correspondences",
    "essential_from_rays",
    "fundamental_7point",
    "fundamental_8point",
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
# Samples per batch of the robust estimators: the first batch, then what the
# adaptive bound still asks for, within [_BATCH_MIN, _BATCH_MAX]. Batches
# amortise numpy's per-call overhead.
_BATCH_FIRST = 100
_BATCH_MIN = 16
_BATCH_MAX = 256
# Smallest mean distance of the points from their centroid that F can be computed for.
_MIN_SPREAD = 1e-100
# Largest pixel coordinate, in absolute value, the unnormalised 8-point algorithm can solve (and
# its inverse the smallest largest one): its design matrix mixes u^2, u and 1, and beyond these
# the rounding of one kind of term swamps the others.
_MAX_RAW_PIXEL = 1e6
# LMedS's smallest scale estimate, relative to the spread of the points.
_SIGMA_FLOOR = 1e-9
# Pre-emptive scoring: subset size, and hypotheses per batch scored on all points.
_SUBSET = 100
_KEEP = 4


@dataclass(frozen=True, eq=False)
class RobustEstimate:
    """Result of every robust estimator: :func:`fundamental_ransac`, :func:`fundamental_lmeds` and those of
    :mod:`egtviz.geometry.robust` (M-estimator, MAPSAC, the essential matrix from rays)."""

    F: np.ndarray
    """(3, 3) fundamental matrix, rank 2, unit Frobenius norm, ``m2^T F m1 = 0`` (for the estimator from
    rays, the essential matrix, ``d2^T E d1 = 0``)."""
    inliers: np.ndarray
    """(N,) bool mask of the correspondences consistent with ``F``."""
    iterations: int
    """Number of minimal samples drawn before the adaptive bound stopped the search (for the M-estimator,
    the number of reweighting iterations)."""


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


def _hartley(u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray, np.ndarray, float]:
    r"""Hartley's isotropic normalisation of both images (H&Z section 4.4.4).

    For each image returns ``T`` (3, 3), the normalised homogeneous points as
    rows ``(3, N)`` (x, y, 1) and the scale ``s``: the centroid moves to the
    origin and the mean distance from it becomes :math:`\sqrt 2`,
    :math:`\hat m = T m`. Written with few, contiguous numpy operations: it
    is a large part of the cost of the normalised 8-point algorithm.
    """
    n = u1.shape[0]
    H = np.empty((2, 3, n))
    H[0, :2] = u1.T
    H[1, :2] = u2.T
    H[:, 2] = 1.0
    P = H[:, :2]  # (2 images, xy, N)
    c = (np.add.reduce(P, axis=2) / n).ravel()  # cx1, cy1, cx2, cy2
    P -= c.reshape(2, 2, 1)
    sq = P * P
    mean_dist = np.add.reduce(np.sqrt(sq[:, 0] + sq[:, 1]), axis=1) / n
    for k, name in enumerate(("U1", "U2")):
        if not mean_dist[k] > 1e-9 * max(abs(c[2 * k]), abs(c[2 * k + 1])) or mean_dist[k] == 0.0:
            raise DegenerateConfigurationError(f"{name}: all points coincide, F is undefined")
        if mean_dist[k] < _MIN_SPREAD:
            # F's entries scale as 1 / spread^2 against F[2, 2]: beyond this it is not representable.
            raise GeometryError(
                f"{name}: the points spread over {mean_dist[k]:.3g} only; F cannot be computed "
                f"below a spread of {_MIN_SPREAD:.0e} (rescale the coordinates)"
            )
    s1, s2 = math.sqrt(2.0) / mean_dist
    P[0] *= s1
    P[1] *= s2
    T1 = np.array([[s1, 0.0, -s1 * c[0]], [0.0, s1, -s1 * c[1]], [0.0, 0.0, 1.0]])
    T2 = np.array([[s2, 0.0, -s2 * c[2]], [0.0, s2, -s2 * c[3]], [0.0, 0.0, 1.0]])
    return T1, H[0], float(s1), T2, H[1], float(s2)


def _homogeneous(u: np.ndarray) -> np.ndarray:
    h = np.empty((u.shape[0], 3))
    h[:, :2] = u
    h[:, 2] = 1.0
    return h


def _design(h1: np.ndarray, h2: np.ndarray) -> np.ndarray:
    r"""Transposed design matrix ``(9, N)`` from homogeneous points as rows ``(3, N)``.

    Column ``n`` is :math:`m_2 \otimes m_1`, so ``f @ At = m2^T F m1`` with
    ``f = F.ravel()``. Rows 6-8 are :math:`m_1` and rows 2, 5, 8 are :math:`m_2`.
    (Kept transposed: every row is contiguous, which makes the products fast.)
    """
    return (h2[:, None, :] * h1[None, :, :]).reshape(9, h1.shape[1])


def _null_vector_normal(At: np.ndarray, names: str = "U1, U2") -> np.ndarray:
    """Unit ``f`` minimising ``|A f|`` from the 9x9 normal matrix; raise naming ``names`` if ``rank A < 8``."""
    M = At @ At.T
    # LAPACK directly: numpy.linalg's wrapper costs more than a 9x9 eigenproblem.
    w, v, info = _lapack.dsyevd(M)
    if info != 0:  # pragma: no cover - LAPACK failure
        w, v = np.linalg.eigh(M)
    if w[1] <= _RANK_TOL_EIG * w[-1]:
        raise DegenerateConfigurationError(
            f"{names}: degenerate configuration, the design matrix has rank < 8 "
            "(repeated, collinear or coplanar points?)"
        )
    return v[:, 0]


def _rank2(F: np.ndarray) -> np.ndarray:
    """Closest rank-2 matrix in Frobenius norm (H&Z section 11.1.1)."""
    U, S, Vt, info = _lapack.dgesvd(F)
    if info != 0:  # pragma: no cover - LAPACK failure
        U, S, Vt = np.linalg.svd(F)
    return (U[:, :2] * S[:2]) @ Vt[:2]


def _canonical(F: np.ndarray) -> np.ndarray:
    """Unit Frobenius norm, largest-magnitude entry positive."""
    F = F / np.abs(F).max()  # first: the sum of squares in the norm must not overflow
    F = F / np.linalg.norm(F)
    if F.flat[np.argmax(np.abs(F))] < 0:
        F = -F
    return F


def _finalize(F: np.ndarray) -> np.ndarray:
    return _canonical(_rank2(F))


def _denormalize(Fn: np.ndarray, T1: np.ndarray, T2: np.ndarray) -> np.ndarray:
    return T2.T @ Fn @ T1


# OpenBLAS runs a GEMM multithreaded above m*n*k = 4 * 65536; on a busy
# machine that is far slower than one thread, so the scorer stays below it.
_GEMM_CHUNK = 4 * 65536


def _linear_forms(Fs: np.ndarray) -> np.ndarray:
    """``(M, 5, 9)``: rows giving, from a design row, ``m2^T F m1``, ``(F m1)_1,2`` and ``(F^T m2)_1,2``."""
    M = Fs.shape[0]
    G = np.zeros((M, 5, 9))
    G[:, 0] = Fs.reshape(M, 9)
    G[:, 1, 6:9] = Fs[:, 0, :]
    G[:, 2, 6:9] = Fs[:, 1, :]
    G[:, 3, 2::3] = Fs[:, :, 0]
    G[:, 4, 2::3] = Fs[:, :, 1]
    return G


def _sampson_normalized(Fs: np.ndarray, At: np.ndarray, s1: float, s2: float) -> np.ndarray:
    r"""Pixel Sampson distances ``(M, N)`` of ``M`` candidates ``Fs`` given in normalised coordinates.

    With :math:`F = T_2^T F_n T_1` the algebraic error is unchanged and the
    first two coordinates of the epipolar lines scale by :math:`s_2` (image 2)
    and :math:`s_1` (image 1), so no candidate needs denormalising. All the
    quantities are linear in the design row, hence one (chunked) GEMM.
    """
    M, N = Fs.shape[0], At.shape[1]
    G = _linear_forms(Fs).reshape(5 * M, 9)
    V = np.empty((5 * M, N))
    step = max(1, _GEMM_CHUNK // (9 * N))
    for i in range(0, 5 * M, step):
        np.matmul(G[i : i + step], At, out=V[i : i + step])
    Q = V.reshape(M, 5, N)
    np.multiply(Q, Q, out=Q)
    den = np.einsum("mkn,k->mn", Q[:, 1:], np.array([s2 * s2, s2 * s2, s1 * s1, s1 * s1]))
    np.maximum(den, 1e-300, out=den)
    d = np.divide(Q[:, 0], den, out=den)
    return d


def _det3(M: np.ndarray) -> np.ndarray:
    """Determinants of a stack of 3x3 matrices ``(..., 3, 3)``, written out."""
    return (
        M[..., 0, 0] * (M[..., 1, 1] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 1])
        - M[..., 0, 1] * (M[..., 1, 0] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 0])
        + M[..., 0, 2] * (M[..., 1, 0] * M[..., 2, 1] - M[..., 1, 1] * M[..., 2, 0])
    )


def _real_cubic_roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Real roots of the monic cubics :math:`x^3 + a x^2 + b x + c` (arrays ``(K,)``).

    Cardano's formula for one real root, the trigonometric form for three,
    each polished by two Newton steps. Returns roots ``(K, 3)`` and a ``(K, 3)``
    mask of the valid ones (one or three per cubic).
    """
    p = b - a * a / 3.0
    q = 2.0 * a**3 / 27.0 - a * b / 3.0 + c
    disc = (q / 2.0) ** 2 + (p / 3.0) ** 3
    one = disc > 0.0
    sq = np.sqrt(np.where(one, disc, 0.0))
    y1 = np.cbrt(-q / 2.0 + sq) + np.cbrt(-q / 2.0 - sq)
    pn = np.where(one | (p >= 0.0), -1.0, p)  # p < 0 whenever there are three real roots
    m = 2.0 * np.sqrt(-pn / 3.0)
    arg = np.clip(3.0 * q / (pn * m), -1.0, 1.0)
    phi = np.arccos(arg) / 3.0
    k = np.arange(3) * (2.0 * np.pi / 3.0)
    y3 = m[:, None] * np.cos(phi[:, None] - k)
    y3 = np.where((p >= 0.0)[:, None], 0.0, y3)  # triple root
    y = np.where(one[:, None], y1[:, None], y3)
    x = y - (a / 3.0)[:, None]
    for _ in range(2):
        f = ((x + a[:, None]) * x + b[:, None]) * x + c[:, None]
        df = (3.0 * x + 2.0 * a[:, None]) * x + b[:, None]
        step = np.where(df != 0.0, f / np.where(df != 0.0, df, 1.0), 0.0)
        x = np.where(np.isfinite(step), x - step, x)
    valid = np.ones(x.shape, bool)
    valid[:, 1:] = ~one[:, None]
    return x, valid


def _cubic_solutions(F1: np.ndarray, F2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Rank-2 members of the pencils :math:`a F_1 + b F_2` (stacks ``(K, 3, 3)``).

    :math:`\det(a F_1 + b F_2)` is a homogeneous cubic
    :math:`k_3 a^3 + k_2 a^2 b + k_1 a b^2 + k_0 b^3`; it is solved for
    :math:`a/b` or :math:`b/a`, whichever end coefficient is larger, so the
    solver never divides by a vanishing leading coefficient.

    Returns candidates ``(K, 3, 3, 3)`` and a ``(K, 3)`` mask of the real roots
    (one or three per pencil).
    """
    k3 = _det3(F1)
    k0 = _det3(F2)
    pp = _det3(F1 + F2)
    pm = _det3(F1 - F2)
    k2 = 0.5 * (pp - pm) - k0
    k1 = 0.5 * (pp + pm) - k3
    first = np.abs(k3) >= np.abs(k0)  # solve for r = a / b
    lead = np.where(first, k3, k0)
    lead = np.where(lead == 0.0, 1e-300, lead)
    with np.errstate(over="ignore", invalid="ignore"):
        roots, real = _real_cubic_roots(
            np.where(first, k2, k1) / lead, np.where(first, k1, k2) / lead, np.where(first, k0, k3) / lead
        )
    r = roots[:, :, None, None]
    cand = np.where(
        first[:, None, None, None], r * F1[:, None] + F2[:, None], F1[:, None] + r * F2[:, None]
    )
    return cand, real & np.isfinite(roots)


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
        GeometryError: bad types or shapes, NaN/inf, ``N < 8``, mismatched
            ``N``, or a largest pixel coordinate outside ``[1e-6, 1e6]`` in
            absolute value (the unnormalised system cannot be solved there).
        DegenerateConfigurationError: coincident points or a design matrix of
            rank below 8 (e.g. collinear or coplanar scene points).
    """
    u1, u2 = _pair(U1, U2, 8)
    for u, name in ((u1, "U1"), (u2, "U2")):
        top = float(np.abs(u).max())
        if not 1.0 / _MAX_RAW_PIXEL <= top <= _MAX_RAW_PIXEL:
            raise GeometryError(
                f"{name}: pixel coordinates up to {top:.3g} in absolute value cannot be solved by the "
                f"unnormalised 8-point algorithm (the largest must be within [{1.0 / _MAX_RAW_PIXEL:.0e}, "
                f"{_MAX_RAW_PIXEL:.0e}]); fundamental_normalized_8point solves them"
            )
    # The rank test is done in normalised coordinates, where it is meaningful.
    _, n1, _, _, n2, _ = _hartley(u1, u2)
    _null_vector_normal(_design(n1, n2))
    A = _design(_homogeneous(u1).T, _homogeneous(u2).T).T
    f = np.linalg.svd(A, full_matrices=A.shape[0] < 9)[2][-1]  # (9, 9) V^T when N = 8
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
    T1, n1, _, T2, n2, _ = _hartley(u1, u2)
    Fn = _rank2(_null_vector_normal(_design(n1, n2)).reshape(3, 3))
    return _canonical(_denormalize(Fn, T1, T2))


def essential_from_correspondences(
    U1: npt.ArrayLike, U2: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike
) -> np.ndarray:
    r"""Essential matrix from calibrated correspondences (H&Z 2nd ed., sections 9.6 and 11.1).

    The pixels are normalised, :math:`\hat x = K^{-1} m`, the normalised
    8-point algorithm gives :math:`E_0` with :math:`\hat x_2^T E_0 \hat x_1 = 0`,
    and :math:`E_0 = U \Sigma V^T` is projected onto the essential matrices
    (two equal singular values, one zero, H&Z Result 9.17):

    .. math:: E = U \operatorname{diag}(1, 1, 0) V^T / \sqrt 2 .

    Decompose it with :func:`decompose_essential` / :func:`pose_from_essential`.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.

    Returns:
        ``(3, 3)`` ``E``, unit Frobenius norm, largest entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8``, mismatched ``N`` or a
            non-invertible calibration.
        DegenerateConfigurationError: coincident points or rank-deficient data.
    """
    u1, u2 = _pair(U1, U2, 8)
    x1 = np.linalg.solve(as_calibration(K1, "K1"), _homogeneous(u1).T).T
    x2 = np.linalg.solve(as_calibration(K2, "K2"), _homogeneous(u2).T).T
    E0 = fundamental_normalized_8point(x1[:, :2] / x1[:, 2:], x2[:, :2] / x2[:, 2:])
    U, _, Vt = np.linalg.svd(E0)
    return _canonical(U @ np.diag([1.0, 1.0, 0.0]) @ Vt)


def _rays_pair(d1: npt.ArrayLike, d2: npt.ArrayLike, min_count: int) -> tuple[np.ndarray, np.ndarray]:
    """Two ``(N, 3)`` ray arrays (any nonzero length each) with the same ``N``, scaled to unit rows."""
    r1 = as_up_to_scale_rows(d1, "d1", 3, min_count=min_count)
    r2 = as_up_to_scale_rows(d2, "d2", 3, min_count=min_count)
    if r1.shape[0] != r2.shape[0]:
        raise GeometryError(f"d1, d2: expected the same number of rays, got {r1.shape[0]} and {r2.shape[0]}")
    return (
        r1 / np.linalg.norm(r1, axis=1, keepdims=True),
        r2 / np.linalg.norm(r2, axis=1, keepdims=True),
    )


def _essential_projection(M: np.ndarray) -> np.ndarray:
    r"""Nearest essential matrices :math:`U \operatorname{diag}(1, 1, 0) V^T / \sqrt 2` of a stack ``(..., 3, 3)``."""
    U, _, Vt = np.linalg.svd(M)
    return (U[..., :, :2] @ Vt[..., :2, :]) / math.sqrt(2.0)


def _ray_sampson(Es: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    r"""Squared angular Sampson distances ``(M, N)`` (radians squared) of unit rays under ``M`` matrices ``Es``.

    The first-order distance to the constraint :math:`d_2^T E d_1 = 0` when each unit ray moves on its
    sphere: the gradients are projected on the tangent planes,
    :math:`g_1 = (I - d_1 d_1^T) E^T d_2`, :math:`g_2 = (I - d_2 d_2^T) E d_1`, and
    :math:`\delta = (d_2^T E d_1)^2 / (|g_1|^2 + |g_2|^2)`.
    """
    Ed1 = np.einsum("mij,nj->mni", Es, r1)  # (M, N, 3)
    Etd2 = np.einsum("mji,nj->mni", Es, r2)
    e = np.einsum("mni,ni->mn", Ed1, r2)
    e1 = np.einsum("mni,ni->mn", Etd2, r1)  # equal to e; used to project Etd2
    g1 = np.einsum("mni,mni->mn", Etd2, Etd2) - e1 * e1
    g2 = np.einsum("mni,mni->mn", Ed1, Ed1) - e * e
    return e * e / np.maximum(g1 + g2, 1e-300)


def _essential_linear(r1: np.ndarray, r2: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Linear E of unit rays (rows), optionally with row weights; unit Frobenius norm, canonical sign."""
    At = _design(r1.T, r2.T)
    if weights is not None:
        At = At * np.sqrt(weights)
    E0 = _null_vector_normal(At, "d1, d2").reshape(3, 3)
    return _canonical(_essential_projection(E0))


def essential_from_rays(d1: npt.ArrayLike, d2: npt.ArrayLike) -> np.ndarray:
    r"""Essential matrix from corresponding rays (H&Z 2nd ed., sections 9.6 and 11.1; EGT's ``f_panEestim``).

    A ray is any direction from a camera's centre (a bearing vector, a point
    on a mirror seen from its focus, :math:`K^{-1} m` for a pin-hole camera);
    each row is scaled to unit length, which conditions the linear system as
    Hartley's normalisation does for pixels. Each correspondence gives one
    equation in :math:`e = \mathrm{vec}(E)`,

    .. math:: d_2^T E d_1 = (d_2^T \otimes d_1^T)\, e = 0, \qquad
              \hat e = \arg\min_{\|e\| = 1} \|A e\| ,

    and :math:`\hat E = U \Sigma V^T` is projected onto the essential
    matrices (H&Z Result 9.17): :math:`E = U \operatorname{diag}(1, 1, 0) V^T / \sqrt 2`.
    With :math:`X_2 = R X_1 + t` between the two frames, :math:`E \simeq [t]_\times R`.

    Args:
        d1: ``(N, 3)`` rays in frame 1 (any nonzero lengths), ``N >= 8``.
        d2: ``(N, 3)`` corresponding rays in frame 2.

    Returns:
        ``(3, 3)`` ``E`` with :math:`d_2^T E d_1 = 0`, singular values
        :math:`(1/\sqrt 2, 1/\sqrt 2, 0)` (unit Frobenius norm), largest-magnitude
        entry positive.

    Raises:
        GeometryError: bad types or shapes, NaN/inf, a zero ray, ``N < 8`` or mismatched ``N``.
        DegenerateConfigurationError: a design matrix of rank below 8 (e.g. the
            scene points and both centres on one plane, or repeated rays).
    """
    r1, r2 = _rays_pair(d1, d2, 8)
    return _essential_linear(r1, r2)


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
    T1, n1, _, T2, n2, _ = _hartley(u1, u2)
    _, s, vt = np.linalg.svd(_design(n1, n2).T)
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


def _skew_stack(c: np.ndarray) -> np.ndarray:
    """Cross-product matrices ``(K, 3, 3)`` of vectors ``(K, 3)``."""
    W = np.zeros((c.shape[0], 3, 3))
    W[:, 0, 1], W[:, 0, 2], W[:, 1, 2] = -c[:, 2], c[:, 1], -c[:, 0]
    W[:, 1, 0], W[:, 2, 0], W[:, 2, 1] = c[:, 2], -c[:, 1], c[:, 0]
    return W


def _rodrigues_jr(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Rotation :math:`R(\omega)` and right Jacobian :math:`J_r(\omega)`.

    :math:`R(\omega + \delta) \approx R(\omega) \exp([J_r(\omega) \delta]_\times)`.
    """
    th = float(np.linalg.norm(w))
    W = _skew_stack(w[None])[0]
    W2 = W @ W
    if th < 1e-8:
        return np.eye(3) + W + 0.5 * W2, np.eye(3) - 0.5 * W + W2 / 6.0
    a = math.sin(th) / th
    b = (1.0 - math.cos(th)) / th**2
    c = (th - math.sin(th)) / th**3
    return np.eye(3) + a * W + b * W2, np.eye(3) - b * W + c * W2


class _SampsonProblem:
    r"""Sampson residuals over the rank-2 parameterisation used by :func:`fundamental_sampson`.

    :math:`F = U_0 R(\omega_1)\,\mathrm{diag}(1, \sigma, 0)\,R(\omega_2)^T V_0^T`, ``p = (w1, w2, sigma)``,
    in Hartley-normalised coordinates; the residuals are pixel Sampson distances
    (see :func:`_sampson_normalized`), optionally weighted.
    """

    def __init__(
        self, Fn0: np.ndarray, At: np.ndarray, s1: float, s2: float, weights: np.ndarray | None = None
    ) -> None:
        U0, S, V0t = np.linalg.svd(Fn0)
        self.sw = None if weights is None else np.sqrt(weights)
        self.U0, self.V0t = U0, V0t
        self.p0 = np.zeros(7)
        self.p0[6] = S[1] / S[0]
        self.At = At
        self.h1 = At[6:9]  # m1 as rows (3, N)
        self.h2 = np.ascontiguousarray(At[2::3])  # m2 as rows (3, N)
        self.q1, self.q2 = s1 * s1, s2 * s2
        self._key: bytes | None = None

    def F(self, p: np.ndarray) -> np.ndarray:
        return self._eval(p)[0]

    def _eval(self, p: np.ndarray):
        key = p.tobytes()
        if key != self._key:
            R1, J1 = _rodrigues_jr(p[:3])
            R2, J2 = _rodrigues_jr(p[3:6])
            L = self.U0 @ R1
            Rt = R2.T @ self.V0t
            F = (L[:, :2] * np.array([1.0, p[6]])) @ Rt[:2]
            l2 = F[:2] @ self.h1  # (F m1)_{1,2}: lines in image 2, (2, N)
            l1 = F[:, :2].T @ self.h2  # (F^T m2)_{1,2}: lines in image 1
            e = F.ravel() @ self.At
            den = self.q2 * (l2[0] ** 2 + l2[1] ** 2) + self.q1 * (l1[0] ** 2 + l1[1] ** 2)
            np.maximum(den, 1e-300, out=den)
            self._cache = (F, l1, l2, e, den, L, Rt, J1, J2)
            self._key = key
        return self._cache

    def residuals(self, p: np.ndarray) -> np.ndarray:
        e, den = self._eval(p)[3:5]
        r = e / np.sqrt(den)
        return r if self.sw is None else r * self.sw

    def jacobian(self, p: np.ndarray) -> np.ndarray:
        _, l1, l2, e, den, L, Rt, J1, J2 = self._eval(p)
        dF = np.empty((7, 3, 3))
        D = np.diag([1.0, p[6], 0.0])
        dF[0:3] = L @ _skew_stack(J1.T) @ (D @ Rt)
        dF[3:6] = -((L @ D) @ _skew_stack(J2.T) @ Rt)
        dF[6] = np.outer(L[:, 1], Rt[1])
        # r = e / sqrt(den): dr = de / sqrt(den) - e / (2 den^1.5) d(den), with
        # de = m2^T dF m1, d(den) = 2 q2 (F m1)_i (dF m1)_i + 2 q1 (F^T m2)_j (dF^T m2)_j (i, j < 2).
        N = e.shape[0]
        de = dF.reshape(7, 9) @ self.At
        P = (dF[:, :2, :].reshape(14, 3) @ self.h1).reshape(7, 2, N)
        Q = (dF[:, :, :2].transpose(0, 2, 1).reshape(14, 3) @ self.h2).reshape(7, 2, N)
        dden = self.q2 * (P[:, 0] * l2[0] + P[:, 1] * l2[1]) + self.q1 * (Q[:, 0] * l1[0] + Q[:, 1] * l1[1])
        rs = 1.0 / np.sqrt(den)
        g = e * rs / den
        J = de * rs - dden * g
        if self.sw is not None:
            J *= self.sw
        return J.T


def _refine_sampson(
    Fn0: np.ndarray,
    At: np.ndarray,
    s1: float,
    s2: float,
    weights: np.ndarray | None = None,
    tol: float = 1e-10,
) -> np.ndarray:
    """Minimise the (weighted) pixel Sampson distance over rank-2 ``F`` in normalised coordinates."""
    prob = _SampsonProblem(Fn0, At, s1, s2, weights)
    r0 = prob.residuals(prob.p0)
    cost0 = float(r0 @ r0)
    res = least_squares(
        prob.residuals, prob.p0, jac=prob.jacobian, method="lm", xtol=tol, ftol=tol, gtol=1e-12, max_nfev=50
    )
    F = prob.F(res.x)
    if not (np.all(np.isfinite(F)) and 2.0 * res.cost <= cost0):
        return Fn0
    return F / np.linalg.norm(F)


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
    T1, n1, s1, T2, n2, s2 = _hartley(u1, u2)
    At = _design(n1, n2)
    if F0 is None:
        Fn0 = _rank2(_null_vector_normal(At).reshape(3, 3))
    else:
        F0 = as_up_to_scale(F0, "F0", (3, 3))
        Fn0 = np.linalg.inv(T2).T @ F0 @ np.linalg.inv(T1)
        sv = np.linalg.svd(Fn0, compute_uv=False)
        if sv[1] <= 1e-12 * sv[0]:
            raise GeometryError("F0: expected a matrix of rank 2, got rank < 2")
        Fn0 = _rank2(Fn0)
    Fn0 = Fn0 / np.linalg.norm(Fn0)
    return _canonical(_denormalize(_refine_sampson(Fn0, At, s1, s2), T1, T2))


# --------------------------------------------------------------------------- robust estimation


def _check_robust_args(confidence: object, max_iterations: object, seed: object) -> tuple[float, int, int | None]:
    """The options shared by the sampling estimators, validated: ``(confidence, max_iterations, seed)``."""
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
            return np.minimum(d, self.th2).sum(axis=-1)
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
    confidence, max_iterations, seed = _check_robust_args(confidence, max_iterations, seed)
    N = u1.shape[0]
    T1, n1, s1, T2, n2, s2 = _hartley(u1, u2)
    At = _design(n1, n2)
    _null_vector_normal(At)  # all the data degenerate (e.g. a coplanar scene seen twice): no F to find
    A = At.T  # rows of the design matrix, for gathering samples
    rng = np.random.default_rng(seed)
    # Scale floor of LMedS: 1e-9 of the larger point spread (mean distance to the centroid, 1 / s).
    scorer = _Scorer(mode, threshold * threshold, N, (_SIGMA_FLOOR / min(s1, s2)) ** 2)
    # Pre-emptive scoring: every hypothesis is scored on a fixed random subset,
    # only the best few of each batch on all the points.
    sub = np.sort(rng.choice(N, _SUBSET, replace=False)) if N > 2 * _SUBSET else None
    At_sub = At[:, sub] if sub is not None else At
    # Refits use the correspondences within 1.5 times the RANSAC threshold
    # (LMedS's 2.5 sigma band is wide already): refitting only on d < threshold^2
    # would favour the hypothesis that chose them (truncation bias).
    widen = 1.5 if mode == "ransac" else 1.0
    best_cost = math.inf
    best_F: np.ndarray | None = None
    bound = math.inf
    done = 0
    while done < min(bound, max_iterations):
        want = _BATCH_FIRST if done == 0 else min(max(bound - done, _BATCH_MIN), _BATCH_MAX)
        k = int(min(want, max_iterations - done))
        cand = _seven_point_batch(A[_sample(rng, N, k)])
        done += k
        if cand.shape[0] == 0:
            continue
        if sub is not None:
            c_sub = scorer.cost(_sampson_normalized(cand, At_sub, s1, s2))
            cand = cand[np.argsort(c_sub, kind="stable")[:_KEEP]]
        d = _sampson_normalized(cand, At, s1, s2)
        cost = scorer.cost(d)
        j = int(np.argmin(cost))
        if cost[j] >= best_cost:
            continue
        best_cost, best_F, best_d = float(cost[j]), cand[j], d[j]
        # Local optimisation (LO-RANSAC): linear refits on the (widened) support of a new best.
        for _ in range(4):
            inl = scorer.inliers(best_d / widen**2, best_cost)
            if inl.sum() < _MIN_REFIT:
                break
            try:
                F_lo = _rank2(_null_vector_normal(At[:, inl]).reshape(3, 3))
            except DegenerateConfigurationError:
                break
            F_lo /= np.linalg.norm(F_lo)
            d_lo = _sampson_normalized(F_lo[None], At, s1, s2)[0]
            c_lo = float(scorer.cost(d_lo))
            if c_lo >= best_cost:
                break
            best_cost, best_F, best_d = c_lo, F_lo, d_lo
        bound = _iteration_bound(float(scorer.inliers(best_d, best_cost).mean()), confidence)
    if best_F is None:
        raise DegenerateConfigurationError("U1, U2: no 7-point sample gave a fundamental matrix")

    def support(Fn: np.ndarray, widen: float) -> tuple[np.ndarray, np.ndarray]:
        d = _sampson_normalized(Fn[None], At, s1, s2)[0]
        return scorer.inliers(d / widen**2, float(scorer.cost(d))), d

    Fn = best_F
    sel, d = support(Fn, widen)
    for _ in range(3):  # linear refits until the support is stable
        if sel.sum() < _MIN_REFIT:
            break
        try:
            F_lin = _rank2(_null_vector_normal(At[:, sel]).reshape(3, 3))
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
    # Sampson refinement. RANSAC and LMedS make it robust by reweighting passes
    # (one for RANSAC, two for LMedS, whose band is looser) with Cauchy weights
    # 1 / (1 + d / c^2), c = 2 threshold (RANSAC) or 2 sigma (LMedS); tighter
    # weights tie the fit to the starting F (the same bias as truncation).
    # MAPSAC refines the plain Sampson cost of its inliers (Torr's maximum
    # likelihood step), twice, the inliers recomputed in between.
    if mode == "lmeds":
        c2 = 4.0 * scorer.lmeds_scale / 2.5**2 * max(float(scorer.cost(d)), scorer.floor2)
    else:
        c2 = 4.0 * threshold**2
    for _ in range(1 if mode == "ransac" else 2):
        weights = None if mode == "mapsac" else 1.0 / (1.0 + d[sel] / max(c2, 1e-300))
        # A relative cost change of 1e-6 is far below the noise a robust fit works with.
        Fn = _refine_sampson(Fn, At[:, sel], s1, s2, weights, tol=1e-6)
        new, d = support(Fn, widen)
        if new.sum() < _MIN_REFIT:
            break
        sel = new
    inl = support(Fn, 1.0)[0]
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
    best hypothesis so far and the confidence :math:`p`. Samples are drawn in
    batches; each batch is scored on a fixed random subset of 100
    correspondences and its best few hypotheses on all of them. A new best
    hypothesis is improved at once by linear refits on its support (LO-RANSAC).
    The final model is refitted on the correspondences with
    :math:`d_i < (1.5\tau)^2` (a wider band than the inlier test, against the
    truncation bias) by the normalised 8-point algorithm and a Sampson
    refinement with Cauchy weights :math:`1 / (1 + d_i / (2\tau)^2)`. Inliers
    are :math:`d_i < \tau^2` under the final ``F``.

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


# --------------------------------------------------------------------------- error measures


def _lines_and_error(F: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike):
    Fm = as_up_to_scale(F, "F", (3, 3))
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
        plane (no image) and for a NaN row of ``X`` (a point at infinity from
        :func:`~egtviz.geometry.triangulation.triangulate_linear`).
    """
    P1 = as_up_to_scale(P1, "P1", (3, 4))
    P2 = as_up_to_scale(P2, "P2", (3, 4))
    # NaN rows of X (points at infinity from triangulation) are allowed and propagate.
    nan_rows = None
    if isinstance(X, np.ndarray) and X.dtype.kind == "f" and np.isnan(X).any():
        nan_rows = np.isnan(X).any(axis=-1).reshape(-1)
        X = np.where(np.isnan(X), 0.0, X)
    Xw = as_points(X, "X", 3)
    if nan_rows is not None:
        Xw[nan_rows] = np.nan
    u1, u2 = _pair(U1, U2, 1)
    if Xw.shape[0] != u1.shape[0]:
        raise GeometryError(f"X, U1: expected the same number of points, got {Xw.shape[0]} and {u1.shape[0]}")
    Xh = np.empty((Xw.shape[0], 4))
    Xh[:, :3] = Xw
    Xh[:, 3] = 1.0
    total = np.zeros(Xw.shape[0])
    for P, u in ((P1, u1), (P2, u2)):
        x = Xh @ P.T
        w = x[:, 2]
        with np.errstate(invalid="ignore"):
            ok = np.abs(w) > 1e-12 * np.linalg.norm(x, axis=1)
        wsafe = np.where(ok, w, 1.0)
        px = x[:, :2] / wsafe[:, None]
        total += np.where(ok, np.sum((px - u) ** 2, axis=1), np.nan)
    return np.sqrt(0.5 * total)


# --------------------------------------------------------------------------- essential matrix


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
    E = as_up_to_scale(E, "E", (3, 3))
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

