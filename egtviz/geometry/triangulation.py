r"""Triangulation of corresponding points in two views (Hartley & Zisserman 2nd ed., chapter 12).

* :func:`triangulate_linear`: the homogeneous linear (DLT) method, H&Z 12.2,
  the SVD's solution at any parallax (closed form where its error estimate is far below
  the tests' 1e-10, a batched SVD elsewhere); NaN on the baseline.
* :func:`correct_correspondences`: the optimal correction of H&Z Algorithm 12.1,
  the pair of points nearest to the measurements that satisfies the epipolar
  constraint exactly.
* :func:`triangulate_optimal`: optimal correction, then linear triangulation.
* :func:`fundamental_from_projections`: ``F`` of two camera matrices (H&Z 9.2.2).

Points are rows (``docs/conventions.md``): pixels ``(N, 2)``, world points
``(N, 3)``; camera matrices are ``(3, 4)`` with :math:`m \simeq P X`, and like
``F`` are defined up to scale: any nonzero scale gives the same result.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_up_to_scale
from .matrices import point_pairs

__all__ = [
    "correct_correspondences",
    "fundamental_from_projections",
    "triangulate_linear",
    "triangulate_optimal",
]


def _camera_centre(P: np.ndarray, name: str) -> np.ndarray:
    """Homogeneous centre ``C`` (4,) with ``P C = 0``; raise if ``P`` has rank < 3."""
    _, s, vt = np.linalg.svd(P)
    if s[2] <= 1e-12 * s[0]:
        raise GeometryError(f"{name}: expected a camera matrix of rank 3")
    return vt[3]


def _camera_matrix(P: npt.ArrayLike, name: str) -> np.ndarray:
    """A ``(3, 4)`` camera matrix, defined up to scale, scaled to unit Frobenius norm."""
    P = as_up_to_scale(P, name, (3, 4))
    return P / np.linalg.norm(P)


def _cameras(P1: npt.ArrayLike, P2: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both camera matrices (unit Frobenius norm) and their homogeneous centres; refuse coincident centres."""
    P1 = _camera_matrix(P1, "P1")
    P2 = _camera_matrix(P2, "P2")
    C1 = _camera_centre(P1, "P1")
    C2 = _camera_centre(P2, "P2")
    # Coincident centres: C1 and C2 are the same projective point.
    if np.linalg.norm(np.outer(C1, C2) - np.outer(C2, C1)) <= 1e-10:
        raise DegenerateConfigurationError("P1, P2: the camera centres coincide, there is no baseline")
    return P1, P2, C1, C2


#: The largest ratio of the two camera matrices' scales (largest absolute entries) the linear method takes:
#: the smaller camera's equations then still carry about ``1e-16 * 1e6 = 1e-10`` relative precision, the
#: accuracy promised for exact correspondences; beyond it they sink into the larger one's rounding (at
#: 1e10 the rank test sees a single camera, and the points came out NaN).
MAX_SCALE_RATIO = 1e6


def _common_scale(P1: npt.ArrayLike, P2: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Both camera matrices divided by ONE factor, the largest absolute entry of the two.

    The linear method weighs the two images' equations by the scales of ``P1`` and ``P2``: a common
    factor keeps the DLT answer for the matrices as given (that of OpenCV and kornia) and makes it
    independent of the overall scale; separate factors would reweigh the images under noise.
    """
    _cameras(P1, P2)  # validation, rank and baseline checks
    A1 = np.asarray(P1, dtype=np.float64)
    A2 = np.asarray(P2, dtype=np.float64)
    t1, t2 = float(np.abs(A1).max()), float(np.abs(A2).max())
    top = max(t1, t2)
    if top / min(t1, t2) > MAX_SCALE_RATIO:
        small, large = ("P1", "P2") if t1 < t2 else ("P2", "P1")
        raise GeometryError(
            f"{small}: {large} is {top / min(t1, t2):.1e} times its scale (largest entries); the linear method "
            f"weighs each image's equations by its matrix's scale, so {small}'s would be lost in rounding. "
            f"Give the two camera matrices comparable scales (within {MAX_SCALE_RATIO:.0e}), e.g. each divided "
            "by its largest entry"
        )
    return (A1 / t1) * (t1 / top), (A2 / t2) * (t2 / top)


def fundamental_from_projections(P1: npt.ArrayLike, P2: npt.ArrayLike) -> np.ndarray:
    r"""Fundamental matrix of two cameras (H&Z 2nd ed., section 9.2.2, Result 9.1).

    .. math:: F = [e_2]_\times P_2 P_1^+, \qquad e_2 = P_2 C_1 ,

    where :math:`C_1` is camera 1's centre (:math:`P_1 C_1 = 0`). Then
    :math:`m_2^T F m_1 = 0`. Returned with unit Frobenius norm and its
    largest-magnitude entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, or a camera matrix of rank < 3.
        DegenerateConfigurationError: coincident camera centres.
    """
    P1, P2, C1, _ = _cameras(P1, P2)
    e2 = P2 @ C1
    ex = np.array([[0.0, -e2[2], e2[1]], [e2[2], 0.0, -e2[0]], [-e2[1], e2[0], 0.0]])
    F = ex @ P2 @ np.linalg.pinv(P1)
    F = F / np.linalg.norm(F)
    return F if F.flat[np.argmax(np.abs(F))] > 0 else -F


#: A DLT matrix whose third singular value is below this fraction of its first has rank 2 or less: the
#: two rays coincide (the point lies on the baseline) and the depth along them is undetermined.
_RANK2_TOL = 1e-10


def _adjugate4(A: np.ndarray) -> np.ndarray:
    """Adjugates ``(4, 4, N)`` of 4x4 matrices stacked along the last axis, by Laplace expansion in 2x2 minors."""
    m = [[A[i, j] for j in range(4)] for i in range(4)]
    s0 = m[0][0] * m[1][1] - m[1][0] * m[0][1]
    s1 = m[0][0] * m[1][2] - m[1][0] * m[0][2]
    s2 = m[0][0] * m[1][3] - m[1][0] * m[0][3]
    s3 = m[0][1] * m[1][2] - m[1][1] * m[0][2]
    s4 = m[0][1] * m[1][3] - m[1][1] * m[0][3]
    s5 = m[0][2] * m[1][3] - m[1][2] * m[0][3]
    c5 = m[2][2] * m[3][3] - m[3][2] * m[2][3]
    c4 = m[2][1] * m[3][3] - m[3][1] * m[2][3]
    c3 = m[2][1] * m[3][2] - m[3][1] * m[2][2]
    c2 = m[2][0] * m[3][3] - m[3][0] * m[2][3]
    c1 = m[2][0] * m[3][2] - m[3][0] * m[2][2]
    c0 = m[2][0] * m[3][1] - m[3][0] * m[2][1]
    out = np.empty_like(A)
    out[0, 0] = m[1][1] * c5 - m[1][2] * c4 + m[1][3] * c3
    out[0, 1] = -m[0][1] * c5 + m[0][2] * c4 - m[0][3] * c3
    out[0, 2] = m[3][1] * s5 - m[3][2] * s4 + m[3][3] * s3
    out[0, 3] = -m[2][1] * s5 + m[2][2] * s4 - m[2][3] * s3
    out[1, 0] = -m[1][0] * c5 + m[1][2] * c2 - m[1][3] * c1
    out[1, 1] = m[0][0] * c5 - m[0][2] * c2 + m[0][3] * c1
    out[1, 2] = -m[3][0] * s5 + m[3][2] * s2 - m[3][3] * s1
    out[1, 3] = m[2][0] * s5 - m[2][2] * s2 + m[2][3] * s1
    out[2, 0] = m[1][0] * c4 - m[1][1] * c2 + m[1][3] * c0
    out[2, 1] = -m[0][0] * c4 + m[0][1] * c2 - m[0][3] * c0
    out[2, 2] = m[3][0] * s4 - m[3][1] * s2 + m[3][3] * s0
    out[2, 3] = -m[2][0] * s4 + m[2][1] * s2 - m[2][3] * s0
    out[3, 0] = -m[1][0] * c3 + m[1][1] * c1 - m[1][2] * c0
    out[3, 1] = m[0][0] * c3 - m[0][1] * c1 + m[0][2] * c0
    out[3, 2] = -m[3][0] * s3 + m[3][1] * s1 - m[3][2] * s0
    out[3, 3] = m[2][0] * s3 - m[2][1] * s1 + m[2][2] * s0
    return out


#: Largest estimated relative error of a fast (adjugate) solution before the point is solved by the SVD instead.
_FAST_TOL = 1e-11
#: Inverse-iteration steps of the fast solution.
_FAST_STEPS = 3


def _dlt_fast(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Smallest right singular vectors ``(4, N)`` of the ``A_i`` (stacked ``(4, 4, N)``) and which are trusted.

    :math:`\operatorname{adj} A = \sum_i (\prod_{j \ne i} \sigma_j) v_i u_i^T` is dominated by
    :math:`v_4 u_4^T`; three steps :math:`x \leftarrow \operatorname{adj}(A) \operatorname{adj}(A)^T x`
    (inverse iteration on :math:`A^T A`) each shrink the other components by :math:`(\sigma_4/\sigma_3)^2`.
    Rounding in the 3x3 minors moves :math:`x` by about :math:`\epsilon \sigma_1^2 / (\sigma_2 \sigma_3)
    \le \epsilon \|A\|_F^3 / \|\operatorname{adj} A\|_F`; a point is trusted when that bound (scaled by
    the dehomogenisation's :math:`\|x\| / |x_4|`) and the iteration's remainder are far below rounding of
    the SVD's own answer. The others (low parallax, near the baseline) go to the SVD.
    """
    adj = _adjugate4(A)
    cols = np.einsum("ijn,ijn->jn", adj, adj)
    adj_f = cols.sum(axis=0)
    x = np.take_along_axis(adj, np.argmax(cols, axis=0)[None, None, :], axis=1)[:, 0, :]  # (4, N)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for _ in range(_FAST_STEPS):
            x = x / np.sqrt(np.einsum("in,in->n", x, x))
            x = np.einsum("ijn,jn->in", adj, np.einsum("ijn,in->jn", adj, x))
        x = x / np.sqrt(np.einsum("in,in->n", x, x))
        a_f = np.einsum("ijn,ijn->n", A, A)
        root = np.sqrt(adj_f)
        Ax = np.einsum("ijn,jn->in", A, x)
        s4 = np.sqrt(np.einsum("in,in->n", Ax, Ax))
        # sigma_3 >= |adj A|_F / (sigma_1 sigma_2) >= 2 |adj A|_F / |A|_F^2 (up to adj's other terms, small here)
        ratio = s4 * a_f / (2.0 * root)
        # The start is off by about sigma_4 / sigma_3, each step multiplies that by its square; each
        # coordinate of x[:3] / x[3] then moves by the drift over |x_i| and |x_4| relative to itself.
        drift = np.finfo(float).eps * a_f * np.sqrt(a_f) / root + ratio ** (1 + 2 * _FAST_STEPS)
        err = drift * (1.0 / np.abs(x).min(axis=0) + 1.0 / np.abs(x[3]))
        ok = (ratio < 0.1) & (err < _FAST_TOL)
    return x, ok


def _dlt(P1: np.ndarray, P2: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    r"""Homogeneous DLT solutions ``(N, 4)`` (unit norm): the smallest right singular vectors of the ``A_i``.

    The SVD's answer (H&Z section 12.2), :math:`A_i = U_i \Sigma_i V_i^T`, :math:`\hat X_i = v_{i,4}`,
    each :math:`A_i` first divided by its largest entry, which leaves :math:`v_{i,4}` unchanged and keeps
    the arithmetic in range. A batched SVD costs some microseconds a point, so well-conditioned points
    take the closed form of :func:`_dlt_fast` (the same vector to far below the tests' 1e-10) and only
    the rest the SVD: exact for every conditioning, however small the parallax. A point with
    :math:`\sigma_3 \le 10^{-10} \sigma_1` (rank 2 or less: it lies on the baseline, both rays are the
    baseline) gets NaN.
    """
    uv = np.concatenate([u1, u2], axis=1).T[:, None, :]  # (4, 1, N): u1, v1, u2, v2
    third = np.stack([P1[2], P1[2], P2[2], P2[2]])[:, :, None]
    first = np.stack([P1[0], P1[1], P2[0], P2[1]])[:, :, None]
    A = uv * third - first  # (4, 4, N): rows u p3 - p1, v p3 - p2 of both cameras, points along the last axis
    top = np.abs(A).max(axis=(0, 1))
    A /= np.where(top > 0.0, top, 1.0)
    X, ok = _dlt_fast(A)
    X = X.T
    slow = np.flatnonzero(~ok)
    if slow.size:
        _, s, vt = np.linalg.svd(A[:, :, slow].transpose(2, 0, 1))
        Xs = vt[:, 3, :].copy()
        Xs[~(s[:, 2] > _RANK2_TOL * s[:, 0])] = np.nan
        X[slow] = Xs
    return X


def _dehomogenize(X: np.ndarray) -> np.ndarray:
    w = X[:, 3]
    with np.errstate(invalid="ignore"):
        ok = np.abs(w) > 1e-12 * np.linalg.norm(X[:, :3], axis=1)
    out = X[:, :3] / np.where(ok, w, 1.0)[:, None]
    out[~ok] = np.nan
    return out


def triangulate_linear(
    P1: npt.ArrayLike, P2: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike
) -> np.ndarray:
    r"""Linear (DLT) triangulation (H&Z 2nd ed., section 12.2).

    For each correspondence the four equations :math:`m \times (P X) = 0`
    (two per image) form

    .. math:: A = \begin{bmatrix} u_1 p_1^{3T} - p_1^{1T} \\ v_1 p_1^{3T} - p_1^{2T} \\
              u_2 p_2^{3T} - p_2^{1T} \\ v_2 p_2^{3T} - p_2^{2T} \end{bmatrix}, \qquad
              \hat X = \arg\min_{\|X\| = 1} \|A X\| ,

    :math:`\hat X` is the right singular vector of the smallest singular
    value, computed for all points at once (closed form for well-conditioned
    points, a batched SVD for the others), the SVD's answer for
    every conditioning (low parallax included). ``P1`` and ``P2`` are divided
    by one common factor (the largest absolute entry of the two), so the
    answer for ``(c P1, c P2)`` is the answer for ``(P1, P2)``, and it is the
    DLT of the matrices as given (``cv2.triangulatePoints``, kornia's
    ``triangulate_points``). Scaling one camera alone reweighs its equations
    against the other's: under noise that moves the points (for exact
    correspondences it does not).

    Args:
        P1: ``(3, 4)`` camera matrix of image 1 (any nonzero scale).
        P2: ``(3, 4)`` camera matrix of image 2 (any nonzero scale; within :data:`MAX_SCALE_RATIO` of
            ``P1``'s).
        U1: ``(N, 2)`` pixels in image 1.
        U2: ``(N, 2)`` corresponding pixels in image 2.

    Returns:
        ``(N, 3)`` world points; NaN for a point at infinity (rays parallel)
        or on the baseline (the rays coincide: ``A`` has rank 2 or less and
        the depth is undetermined).

    Raises:
        GeometryError: bad types or shapes, NaN/inf, empty input, mismatched
            ``N``, a zero or rank-deficient ``P``, pixels beyond
            ``MAX_MAGNITUDE``, scales of ``P1`` and ``P2`` more than
            :data:`MAX_SCALE_RATIO` apart (naming the smaller).
        DegenerateConfigurationError: coincident camera centres.
    """
    P1, P2 = _common_scale(P1, P2)
    u1, u2 = point_pairs(U1, U2)
    return _dehomogenize(_dlt(P1, P2, u1, u2))


def _poly_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Products of polynomials given as coefficient rows in increasing powers ``(N, da)``, ``(N, db)``."""
    out = np.zeros((a.shape[0], a.shape[1] + b.shape[1] - 1))
    for i in range(a.shape[1]):
        out[:, i : i + b.shape[1]] += a[:, i : i + 1] * b
    return out


def _poly_roots(c: np.ndarray) -> np.ndarray:
    """Roots of polynomials ``(N, 7)`` (increasing powers), ``(N, 6)`` complex, NaN-padded.

    Points are grouped by their effective degree and each group solved with a
    batched companion-matrix eigenvalue problem.
    """
    n, m = c.shape
    deg_max = m - 1
    scale = np.abs(c).max(axis=1)
    big = np.abs(c) > 1e-12 * scale[:, None]
    deg = np.where(big.any(axis=1), deg_max - np.argmax(big[:, ::-1], axis=1), 0)
    roots = np.full((n, deg_max), np.nan + 0j)
    for d in range(1, deg_max + 1):
        idx = np.nonzero(deg == d)[0]
        if idx.size == 0:
            continue
        cd = c[idx, : d + 1]
        comp = np.zeros((idx.size, d, d))
        comp[:, 0, :] = -cd[:, d - 1 :: -1] / cd[:, d : d + 1]
        comp[:, np.arange(1, d), np.arange(d - 1)] = 1.0
        roots[idx, :d] = np.linalg.eigvals(comp)
    return roots


def correct_correspondences(
    F: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    r"""Optimal correction of correspondences (H&Z 2nd ed., Algorithm 12.1).

    Finds, for each measured pair :math:`(m_1, m_2)`, the pair
    :math:`(\hat m_1, \hat m_2)` minimising the geometric error subject to the
    epipolar constraint:

    .. math:: \min\ d(m_1, \hat m_1)^2 + d(m_2, \hat m_2)^2
              \quad \text{s.t.} \quad \hat m_2^T F \hat m_1 = 0 .

    After moving both points to the origin and rotating the epipoles onto the
    x axis, :math:`e_1 = (1, 0, f)`, :math:`e_2 = (1, 0, f')`, the pencil of
    epipolar lines is parameterised by :math:`t` and the stationary points of
    the cost are the real roots of the sextic (H&Z eq. 12.7)

    .. math:: g(t) = t\bigl((at + b)^2 + f'^2 (ct + d)^2\bigr)^2
              - (ad - bc)(1 + f^2 t^2)^2 (at + b)(ct + d) .

    The cost is evaluated at every root and at :math:`t = \infty`; the corrected
    points are the feet of the perpendiculars from the origin to the chosen
    pair of epipolar lines. ``F`` is first projected to the nearest rank-2
    matrix. The sextics are solved by batched companion-matrix eigenvalues.

    Args:
        F: ``(3, 3)`` fundamental matrix, :math:`m_2^T F m_1 = 0`.
        U1: ``(N, 2)`` measured pixels in image 1.
        U2: ``(N, 2)`` measured pixels in image 2.

    Returns:
        ``(U1c, U2c)``, the corrected ``(N, 2)`` pixels; they satisfy
        :math:`\hat m_2^T F \hat m_1 = 0` to rounding.

    Raises:
        GeometryError: bad shapes, NaN/inf, mismatched ``N``, or ``F`` of rank < 2.
    """
    F = as_up_to_scale(F, "F", (3, 3))
    u1, u2 = point_pairs(U1, U2)
    U, S, Vt = np.linalg.svd(F)
    if S[1] <= 1e-12 * S[0]:
        raise GeometryError("F: expected a fundamental matrix of rank 2")
    # Common isotropic scaling of both images for conditioning (keeps the
    # minimiser, which is invariant to a similarity applied to both images).
    k = 1.0 / max(1.0, float(np.abs(np.concatenate([u1, u2])).mean()))
    S3 = np.array([1.0 / k, 1.0 / k, 1.0])
    Fs = (U[:, :2] * S[:2]) @ Vt[:2]
    Fs = Fs * S3[:, None] * S3[None, :]  # S^-T F S^-1 with S = diag(k, k, 1)
    Fs /= np.linalg.norm(Fs)
    Us, _, Vst = np.linalg.svd(Fs)
    e1 = Vst[2]  # right epipole, F e1 = 0
    e2 = Us[:, 2]  # left epipole, F^T e2 = 0
    x1, x2 = u1 * k, u2 * k
    n = x1.shape[0]

    R1, f1 = _epipole_rotation(e1, x1)
    R2, f2 = _epipole_rotation(e2, x2)
    # (ii), (v): F_i = R2 T2^-T F T1^-1 R1^T.
    G = np.broadcast_to(Fs, (n, 3, 3)).copy()
    G[:, :, 2] += x1[:, 0:1] * Fs[None, :, 0] + x1[:, 1:2] * Fs[None, :, 1]  # F T1^-1
    G[:, 2, :] += x2[:, 0:1] * G[:, 0, :] + x2[:, 1:2] * G[:, 1, :]  # T2^-T (...)
    Fi = R2 @ G @ R1.transpose(0, 2, 1)
    l1, l2 = _optimal_lines(Fi[:, 1, 1], Fi[:, 1, 2], Fi[:, 2, 1], Fi[:, 2, 2], f1, f2)
    # (x): back to the original coordinates, x = T^-1 R^T x_local.
    y1 = np.einsum("nji,nj->ni", R1, _foot(l1))
    y2 = np.einsum("nji,nj->ni", R2, _foot(l2))
    c1 = y1[:, :2] / y1[:, 2:] + x1
    c2 = y2[:, :2] / y2[:, 2:] + x2
    return c1 / k, c2 / k


def _epipole_rotation(e: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Steps (i)-(iii) of H&Z Algorithm 12.1: the rotations ``(N, 3, 3)`` taking the epipole, seen from each
    point moved to the origin, onto the x axis, and the ``f`` of :math:`(1, 0, f)`."""
    n = x.shape[0]
    ex = e[0] - x[:, 0] * e[2]
    ey = e[1] - x[:, 1] * e[2]
    r = np.hypot(ex, ey)
    ok = r > 1e-300
    r = np.where(ok, r, 1.0)
    c = np.where(ok, ex / r, 1.0)
    s = np.where(ok, ey / r, 0.0)
    f = e[2] / r
    R = np.zeros((n, 3, 3))
    R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, s, -s, c, 1.0
    return R, f


def _optimal_lines(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, f1: np.ndarray, f2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Steps (vii)-(ix) of H&Z Algorithm 12.1: the pair of epipolar lines of least cost, ``(N, 3)`` each."""
    n = a.shape[0]
    # (vii): the sextic g(t), coefficients in increasing powers.
    p1 = np.stack([b, a], axis=1)  # a t + b
    p2 = np.stack([d, c], axis=1)  # c t + d
    q = _poly_mul(p1, p1) + (f2**2)[:, None] * _poly_mul(p2, p2)
    term1 = np.zeros((n, 7))
    term1[:, 1:6] = _poly_mul(q, q)
    one_ft = np.zeros((n, 3))
    one_ft[:, 0], one_ft[:, 2] = 1.0, f1**2
    term2 = ((a * d - b * c)[:, None]) * _poly_mul(_poly_mul(one_ft, one_ft), _poly_mul(p1, p2))
    roots = _poly_roots(term1 - term2)
    # (viii): cost at the real parts of all roots (the minimum is at a real
    # root, so extra candidates never win wrongly) and at t = infinity.
    t = np.concatenate([roots.real, np.zeros((n, 1))], axis=1)
    t = np.where(np.isfinite(t), t, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ct = c[:, None] * t + d[:, None]
        at = a[:, None] * t + b[:, None]
        cost = t**2 / (1.0 + (f1**2)[:, None] * t**2) + ct**2 / (at**2 + (f2**2)[:, None] * ct**2)
        cost_inf = 1.0 / f1**2 + c**2 / (a**2 + f2**2 * c**2)
    cost = np.where(np.isfinite(cost), cost, np.inf)
    cost_inf = np.where(np.isfinite(cost_inf), cost_inf, np.inf)
    j = np.argmin(cost, axis=1)
    tb = t[np.arange(n), j]
    use_inf = cost_inf < cost[np.arange(n), j]
    # (ix): the two epipolar lines.
    l1 = np.stack([tb * f1, np.ones(n), -tb], axis=1)
    l2 = np.stack([-f2 * (c * tb + d), a * tb + b, c * tb + d], axis=1)
    l1_inf = np.stack([f1, np.zeros(n), -np.ones(n)], axis=1)
    l2_inf = np.stack([-f2 * c, a, c], axis=1)
    return np.where(use_inf[:, None], l1_inf, l1), np.where(use_inf[:, None], l2_inf, l2)


def _foot(l: np.ndarray) -> np.ndarray:
    """Step (ix): the points of the lines ``l`` closest to the origin, homogeneous ``(N, 3)``."""
    return np.stack([-l[:, 0] * l[:, 2], -l[:, 1] * l[:, 2], l[:, 0] ** 2 + l[:, 1] ** 2], axis=1)


def triangulate_optimal(
    P1: npt.ArrayLike, P2: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike
) -> np.ndarray:
    r"""Optimal (maximum-likelihood under Gaussian noise) triangulation (H&Z 2nd ed., Algorithm 12.1).

    The measurements are corrected with :func:`correct_correspondences`
    using :math:`F` of the two cameras (:func:`fundamental_from_projections`);
    the corrected rays meet exactly and :func:`triangulate_linear` gives
    their intersection. The reprojection error is the minimum possible:

    .. math:: \hat X = \arg\min_X\ d(m_1, P_1 X)^2 + d(m_2, P_2 X)^2 .

    Args:
        P1: ``(3, 4)`` camera matrix of image 1.
        P2: ``(3, 4)`` camera matrix of image 2.
        U1: ``(N, 2)`` pixels in image 1.
        U2: ``(N, 2)`` corresponding pixels in image 2.

    Returns:
        ``(N, 3)`` world points; NaN for a point at infinity or on the baseline.

    Raises:
        GeometryError: bad types or shapes, NaN/inf, empty input, mismatched
            ``N``, a zero or rank-deficient ``P``.
        DegenerateConfigurationError: coincident camera centres.
    """
    P1, P2, _, _ = _cameras(P1, P2)
    u1, u2 = point_pairs(U1, U2)
    c1, c2 = correct_correspondences(fundamental_from_projections(P1, P2), u1, u2)
    return _dehomogenize(_dlt(P1, P2, c1, c2))
