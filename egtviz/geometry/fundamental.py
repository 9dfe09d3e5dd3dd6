r"""The fundamental matrix from point correspondences: the linear and minimal solvers.

Hartley & Zisserman, *Multiple View Geometry*, 2nd ed. (H&Z), chapter 11, "Computation of the
Fundamental Matrix F":

* :func:`fundamental_8point`: the linear, unnormalised 8-point algorithm (section 11.1, "Basic
  equations").
* :func:`fundamental_normalized_8point`: Hartley's normalised 8-point algorithm (section 11.2,
  Algorithm 11.1, "The normalized 8-point algorithm").
* :func:`fundamental_7point`: the minimal solver (section 11.1.2, "The minimum case - seven point
  correspondences").

The kernels they share with the other estimators are public here: :func:`design_matrix`,
:func:`normalized_design`, :func:`float_pairs`, :func:`null_vector`, :func:`canonical_fundamental` and
:func:`seven_point_candidates` (used by
:mod:`egtviz.geometry.robust`, :mod:`egtviz.geometry.sampson_refinement`,
:mod:`egtviz.geometry.essential`). They take arrays their callers have validated.

Conventions (``docs/conventions.md``): points are rows, pixels ``(N, 2)``;
:math:`m_2^T F m_1 = 0`. Every estimated ``F`` has rank 2, unit Frobenius norm and a deterministic
sign: its largest-magnitude entry is positive.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.linalg import lapack as _lapack

from ._validate import DegenerateConfigurationError, GeometryError
from .matrices import hartley_scales, nearest_rank2, point_pairs

__all__ = [
    "canonical_fundamental",
    "design_matrix",
    "float_pairs",
    "fundamental_7point",
    "fundamental_8point",
    "fundamental_normalized_8point",
    "normalized_design",
    "null_vector",
    "seven_point_candidates",
]

# The second-smallest eigenvalue of A^T A (normalised coordinates) below this
# fraction of the largest means the design matrix has rank < 8.
_RANK_TOL_EIG = 1e-13
# Same test on the singular values of the 7 x 9 design matrix of the 7-point solver.
_RANK_TOL_SV = 1e-10
# Largest pixel coordinate, in absolute value, the unnormalised 8-point algorithm can solve (and
# its inverse the smallest largest one): its design matrix mixes u^2, u and 1, and beyond these
# the rounding of one kind of term swamps the others.
_MAX_RAW_PIXEL = 1e6
# Spreads and magnitudes that hartley_scales accepts by far (its own bounds are 1e-100 and 1e100), so that the
# normalised 8-point algorithm decides them without calling it.
_SURE_SPREAD = 1e-50
_SURE_MAGNITUDE = 1e90
_SQRT2 = math.sqrt(2.0)
# numpy's float64 dtype is a singleton: an identity test is the cheapest dtype check.
_F64 = np.dtype(np.float64)


def design_matrix(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    r"""Transposed design matrix ``(9, N)`` of the epipolar constraint (H&Z 2nd ed., section 11.1, eq. 11.3).

    Column ``n`` is :math:`m_2 \otimes m_1`, so ``f @ At = m2^T F m1`` with ``f = F.ravel()``.
    ``x1``, ``x2`` are checked float arrays: ``(N, 2)`` affine points (third coordinate 1; then rows
    6-8 are :math:`m_1` and rows 2, 5, 8 are :math:`m_2`) or ``(N, 3)`` homogeneous points (rays).
    Kept transposed: every row is contiguous, which makes the products fast.
    """
    n = x1.shape[0]
    At = np.empty((9, n))
    if x1.shape[1] == 2 and x2.shape[1] == 2:
        h1 = At[6:9]
        h1[:2] = x1.T
        h1[2] = 1.0
        np.multiply(x2.T[:, None, :], h1[None, :, :], out=At[0:6].reshape(2, 3, n))  # rows 3a + b, a < 2
        return At
    np.multiply(x2.T[:, None, :], x1.T[None, :, :], out=At.reshape(3, 3, n))
    return At


def float_pairs(U1: npt.ArrayLike, U2: npt.ArrayLike, min_count: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~egtviz.geometry.matrices.point_pairs`, with the value checks left to Hartley's normalisation
    when both are float64 ``(N, 2)`` arrays of one ``N >= min_count`` already: for callers that pass the pair
    to :func:`normalized_design` (or its kernel) before any other use.

    The normalisation checks the values on its centroid and mean distance and raises the same errors
    (:func:`~egtviz.geometry.matrices.hartley_normalization`): the two reductions over each array that a
    full check costs are a fifth of the normalised 8-point algorithm's time at N = 1000.
    """
    if (
        type(U1) is np.ndarray
        and type(U2) is np.ndarray
        and U1.dtype is _F64
        and U2.dtype is _F64
        and U1.ndim == 2 == U2.ndim
        and U1.shape[1] == 2 == U2.shape[1]
        and U1.shape[0] == U2.shape[0] >= min_count
    ):
        return U1, U2
    return point_pairs(U1, U2, min_count)


def normalized_design(u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(At, T1, T2)``: :func:`design_matrix` of the Hartley-normalised points of two checked ``(N, 2)`` arrays.

    ``T1``, ``T2`` are the similarities of :func:`~egtviz.geometry.matrices.hartley_normalization`
    (H&Z Algorithm 11.1, step (i)); their scales are ``T[0, 0]``. The values are checked as there.
    """
    At, (s1, p1, q1, s2, p2, q2) = _normalized_design_floats(u1, u2)
    return At, np.array([[s1, 0.0, p1], [0.0, s1, q1], [0.0, 0.0, 1.0]]), np.array(
        [[s2, 0.0, p2], [0.0, s2, q2], [0.0, 0.0, 1.0]]
    )


def _normalized_design_floats(u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, tuple[float, ...]]:
    """:func:`normalized_design`, the similarities ``T = [s, 0, p; 0, s, q]`` as floats ``(s1, p1, q1, s2, p2, q2)``.

    The normalisation of :func:`~egtviz.geometry.matrices.hartley_normalization` (the same centroids,
    distances and scales, bit for bit, and the same checks), with the scaling done as the points are
    written into the design matrix: numpy's per-call cost, not the arithmetic, dominates here.
    """
    n = u1.shape[0]
    images, names = (u1, u2), ("U1", "U2")
    # Each row (x, y) read as one complex number x + iy, both images stacked: one call per pass.
    Z = np.empty((2, n), np.complex128)
    np.concatenate(images, out=Z.view(np.float64).reshape(2 * n, 2))
    c = np.add.reduce(Z, axis=1)
    parts = c.view(np.float64)
    parts /= n  # each part divided by n (as Python divides a complex by an int), not multiplied by 1 / n
    centres = c.tolist()
    c1, c2 = centres
    if not math.isfinite(abs(c1) + abs(c2)):
        hartley_scales(centres, None, n, images, names)  # names a NaN or inf
    Z -= c[:, None]
    m1, m2 = [d / n for d in np.add.reduce(np.abs(Z), axis=1).tolist()]
    r1, r2 = abs(c1), abs(c2)  # each at least the larger of its parts
    if (
        _SURE_SPREAD < m1 > 1e-9 * r1
        and _SURE_SPREAD < m2 > 1e-9 * r2
        and r1 + n * m1 <= _SURE_MAGNITUDE
        and r2 + n * m2 <= _SURE_MAGNITUDE
    ):
        # Every check of hartley_scales passes by a wide margin (the usual case): its scales, without its loops.
        s1, s2 = _SQRT2 / m1, _SQRT2 / m2
    else:
        s1, s2 = hartley_scales(centres, [m1, m2], n, images, names)
    X = Z.view(np.float64).reshape(2, n, 2)
    At = np.empty((9, n))
    h1 = At[6:9]
    np.multiply(X[0].T, s1, out=h1[:2])
    h1[2] = 1.0
    x2 = np.multiply(X[1].T, s2)
    np.multiply(x2[:, None, :], h1[None, :, :], out=At[0:6].reshape(2, 3, n))  # rows 3a + b, a < 2 (eq. 11.3)
    return At, (s1, -s1 * c1.real, -s1 * c1.imag, s2, -s2 * c2.real, -s2 * c2.imag)


def null_vector(At: np.ndarray, names: str = "U1, U2") -> np.ndarray:
    r"""Unit ``f`` minimising :math:`\|A f\|` (H&Z 2nd ed., section 11.1): the smallest eigenvector of :math:`A^T A`.

    The 9x9 normal matrix is what OpenCV's 8-point solver decomposes too; for Hartley-normalised
    coordinates it is well conditioned (H&Z section 11.2).

    Raises:
        DegenerateConfigurationError: ``rank A < 8`` (the message starts with ``names``).
    """
    M = At @ At.T
    # LAPACK directly: numpy.linalg's wrapper costs more than a 9x9 eigenproblem.
    w, v, info = _lapack.dsyevd(M)
    if info != 0:  # pragma: no cover - LAPACK failure
        w, v = np.linalg.eigh(M)
    w1, w9 = w[1:9:7].tolist()
    if w1 <= _RANK_TOL_EIG * w9:
        raise DegenerateConfigurationError(
            f"{names}: degenerate configuration, the design matrix has rank < 8 "
            "(repeated, collinear or coplanar points?)"
        )
    return v[:, 0]


def canonical_fundamental(F: np.ndarray) -> np.ndarray:
    """``F`` (a checked, non-zero float 3x3 array) at unit Frobenius norm with its largest-magnitude entry positive."""
    # Dividing by the signed largest entry first: the sum of squares in the norm cannot overflow.
    G = F / max(F.ravel().tolist(), key=abs)
    g = G.ravel()
    return G / math.sqrt(g.dot(g))


def _rank2_denormalize_canonical(f: np.ndarray, t: tuple[float, ...]) -> np.ndarray:
    r""":func:`canonical_fundamental` of :math:`F = T_2^T \hat F T_1`, :math:`\hat F` the rank-2 matrix nearest ``f``.

    H&Z Algorithm 11.1, steps (ii) and (iii): ``f`` (9,) is the linear solution in normalised
    coordinates, :math:`\hat F = U \operatorname{diag}(\sigma_1, \sigma_2, 0) V^T` (as
    :func:`~egtviz.geometry.matrices.nearest_rank2`). For the similarities
    :math:`T = [s, 0, p;\ 0, s, q;\ 0, 0, 1]` of Hartley's normalisation the products are written out
    on Python floats: numpy's per-call cost dominates on nine numbers. ``t`` is ``(s1, p1, q1, s2, p2, q2)``.
    """
    # LAPACK directly: numpy.linalg's wrapper costs more than a 3x3 SVD.
    U, sv, Vt, info = _lapack.dgesvd(f.reshape(3, 3))
    if info != 0:  # pragma: no cover - LAPACK failure
        U, sv, Vt = np.linalg.svd(f.reshape(3, 3))
    # F = (T2^T U_2 S_2)(V_2^T T1): the two rank-1 terms, each side denormalised before the product.
    (u00, u01, _), (u10, u11, _), (u20, u21, _) = U.tolist()
    d0, d1, _ = sv.tolist()
    (v00, v01, v02), (v10, v11, v12), _ = Vt.tolist()
    s1, p1, q1, s2, p2, q2 = t
    a0, a1, a2 = u00 * d0, u10 * d0, u20 * d0
    b0, b1, b2 = u01 * d1, u11 * d1, u21 * d1
    l0, m0, l1, m1 = s2 * a0, s2 * b0, s2 * a1, s2 * b1
    l2, m2 = p2 * a0 + q2 * a1 + a2, p2 * b0 + q2 * b1 + b2
    x0, x1, x2 = s1 * v00, s1 * v01, p1 * v00 + q1 * v01 + v02
    y0, y1, y2 = s1 * v10, s1 * v11, p1 * v10 + q1 * v11 + v12
    f9 = [l0 * x0 + m0 * y0, l0 * x1 + m0 * y1, l0 * x2 + m0 * y2,
          l1 * x0 + m1 * y0, l1 * x1 + m1 * y1, l1 * x2 + m1 * y2,
          l2 * x0 + m2 * y0, l2 * x1 + m2 * y1, l2 * x2 + m2 * y2]
    # The largest-magnitude entry (the first of them, as max(f9, key=abs), on a tie of +v and -v).
    hi, lo = max(f9), min(f9)
    top = hi if hi > -lo else lo if -lo > hi else max(f9, key=abs)
    g = [v / top for v in f9]
    F = np.array(g)
    F /= math.hypot(*g)
    return F.reshape(3, 3)


def _det3_rows(M: np.ndarray) -> np.ndarray:
    """Determinants of 3x3 matrices given as the rows of ``M`` ``(9, K)`` (entry ``3 i + j`` in row ``3 i + j``),
    written out on contiguous rows."""
    a, b, c, d, e, f, g, h, i = M
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


_THIRDS_OF_TURN = np.arange(3) * (2.0 * np.pi / 3.0)


def _real_cubic_roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Real roots of the monic cubics :math:`x^3 + a x^2 + b x + c` (arrays ``(K,)``).

    Cardano's formula for one real root, the trigonometric form for three,
    each polished by two Newton steps. Returns roots ``(K, 3)`` and a ``(K, 3)``
    mask of the valid ones (one or three per cubic).
    """
    p = b - a * a / 3.0
    q = 2.0 * a**3 / 27.0 - a * b / 3.0 + c
    h = -q / 2.0
    disc = h * h + (p / 3.0) ** 3  # h * h is (q / 2)^2, bit for bit
    one = disc > 0.0
    sq = np.sqrt(np.where(one, disc, 0.0))
    y1 = np.cbrt(h + sq) + np.cbrt(h - sq)
    flat = p >= 0.0
    pn = np.where(one | flat, -1.0, p)  # p < 0 whenever there are three real roots
    m = 2.0 * np.sqrt(-pn / 3.0)
    arg = np.minimum(np.maximum(3.0 * q / (pn * m), -1.0), 1.0)  # np.clip's own wrapper costs more
    phi = np.arccos(arg) / 3.0
    y3 = m[:, None] * np.cos(phi[:, None] - _THIRDS_OF_TURN)
    y3 = np.where(flat[:, None], 0.0, y3)  # triple root
    y = np.where(one[:, None], y1[:, None], y3)
    A, B, C = a[:, None], b[:, None], c[:, None]
    x = y - (a / 3.0)[:, None]
    A2 = 2.0 * A
    for _ in range(2):
        # Horner's rule, each operation in place on one buffer (numpy's per-call cost dominates on K x 3).
        f = x + A
        f *= x
        f += B
        f *= x
        f += C
        df = 3.0 * x
        df += A2
        df *= x
        df += B
        nonzero = df != 0.0
        step = np.divide(f, df, out=np.zeros_like(f), where=nonzero)
        np.subtract(x, step, out=x, where=np.isfinite(step))
    valid = np.ones(x.shape, bool)
    valid[:, 1:] = ~one[:, None]
    return x, valid


def _cubic_solutions(F1: np.ndarray, F2: np.ndarray) -> np.ndarray:
    r"""Real rank-2 members of the pencils :math:`a F_1 + b F_2` (stacks ``(K, 3, 3)``; H&Z section 11.1.2).

    :math:`\det(a F_1 + b F_2)` is a homogeneous cubic
    :math:`k_3 a^3 + k_2 a^2 b + k_1 a b^2 + k_0 b^3`; it is solved for
    :math:`a/b` or :math:`b/a`, whichever end coefficient is larger, so the
    solver never divides by a vanishing leading coefficient.

    Returns the members ``(M, 3, 3)`` of the real, finite roots (one or three per pencil), pencil by pencil
    and in the order of the roots: :math:`r F_1 + F_2` or :math:`F_1 + r F_2`, written as
    :math:`\alpha F_1 + \beta F_2` with the other coefficient 1 (the same numbers), only for those roots.
    """
    K = F1.shape[0]
    # The four stacks' entries as contiguous rows: one pass over all of them per product.
    entries = np.ascontiguousarray(np.stack((F1, F2, F1 + F2, F1 - F2)).reshape(4 * K, 9).T)
    k3, k0, pp, pm = _det3_rows(entries).reshape(4, K)
    k2 = 0.5 * (pp - pm) - k0
    k1 = 0.5 * (pp + pm) - k3
    first = np.abs(k3) >= np.abs(k0)  # solve for r = a / b
    lead = np.where(first, k3, k0)
    lead = np.where(lead == 0.0, 1e-300, lead)
    with np.errstate(over="ignore", invalid="ignore"):
        roots, real = _real_cubic_roots(
            np.where(first, k2, k1) / lead, np.where(first, k1, k2) / lead, np.where(first, k0, k3) / lead
        )
    k, j = np.nonzero(real & np.isfinite(roots))
    r = roots[k, j][:, None]
    on_first = first[k][:, None]
    # Rows of 9 (not (3, 3) blocks): numpy's loops are far slower over small inner dimensions.
    members = np.where(on_first, r, 1.0) * F1.reshape(K, 9)[k] + np.where(on_first, 1.0, r) * F2.reshape(K, 9)[k]
    return members.reshape(-1, 3, 3)


def seven_point_candidates(A7: np.ndarray) -> np.ndarray:
    """Real 7-point solutions (H&Z section 11.1.2), unit norm, for a batch of 7x9 design matrices ``(K, 7, 9)``.

    The null space of each is spanned by two vectors found by one batched solve (an SVD where the
    first 7x7 block is singular); the rank-2 members of each pencil are returned stacked, ``(M, 3, 3)``.
    """
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
    cand = _cubic_solutions(N1.reshape(K, 3, 3), N2.reshape(K, 3, 3)).reshape(-1, 9)
    cand = cand[np.logical_and.reduce(np.isfinite(cand), axis=1)]
    norms = np.sqrt(np.add.reduce(cand * cand, axis=1))  # np.linalg.norm(cand, axis=1), without its wrapper
    norms[norms == 0.0] = 1.0
    cand /= norms[:, None]
    return cand.reshape(-1, 3, 3)


def fundamental_8point(U1: npt.ArrayLike, U2: npt.ArrayLike) -> np.ndarray:
    r"""Linear (unnormalised) 8-point algorithm (H&Z 2nd ed., section 11.1, "Basic equations").

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
    u1, u2 = point_pairs(U1, U2, 8)
    for u, name in ((u1, "U1"), (u2, "U2")):
        top = float(np.abs(u).max())
        if not 1.0 / _MAX_RAW_PIXEL <= top <= _MAX_RAW_PIXEL:
            raise GeometryError(
                f"{name}: pixel coordinates up to {top:.3g} in absolute value cannot be solved by the "
                f"unnormalised 8-point algorithm (the largest must be within [{1.0 / _MAX_RAW_PIXEL:.0e}, "
                f"{_MAX_RAW_PIXEL:.0e}]); fundamental_normalized_8point solves them"
            )
    # The rank test is done in normalised coordinates, where it is meaningful.
    null_vector(normalized_design(u1, u2)[0])
    A = design_matrix(u1, u2).T
    f = np.linalg.svd(A, full_matrices=A.shape[0] < 9)[2][-1]  # (9, 9) V^T when N = 8
    return canonical_fundamental(nearest_rank2(f.reshape(3, 3), check=False))


def fundamental_normalized_8point(U1: npt.ArrayLike, U2: npt.ArrayLike) -> np.ndarray:
    r"""Hartley's normalised 8-point algorithm (H&Z 2nd ed., section 11.2, Algorithm 11.1).

    Points are normalised by similarities :math:`\hat m_1 = T_1 m_1`,
    :math:`\hat m_2 = T_2 m_2` (centroid at the origin, mean distance
    :math:`\sqrt 2`: :func:`~egtviz.geometry.matrices.hartley_normalization`); the linear solution
    :math:`\hat F` (smallest eigenvector of the 9x9 matrix :math:`A^T A`) is projected to rank 2
    and denormalised:

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
    u1, u2 = float_pairs(U1, U2, 8)
    At, t = _normalized_design_floats(u1, u2)
    return _rank2_denormalize_canonical(null_vector(At), t)


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
    u1, u2 = point_pairs(U1, U2, 7)
    if u1.shape[0] != 7:
        raise GeometryError(f"U1: the 7-point algorithm needs exactly 7 points, got {u1.shape[0]}")
    At, T1, T2 = normalized_design(u1, u2)
    _, s, vt = np.linalg.svd(At.T)
    if s[6] <= _RANK_TOL_SV * s[0]:
        raise DegenerateConfigurationError(
            "U1, U2: degenerate configuration, the 7x9 design matrix has rank < 7"
        )
    members = _cubic_solutions(vt[7].reshape(1, 3, 3), vt[8].reshape(1, 3, 3))
    return [canonical_fundamental(nearest_rank2(T2.T @ Fn @ T1, check=False)) for Fn in members]
