r"""Error measures of two-view geometry: the Sampson distance, the symmetric epipolar distance, the reprojection error.

Hartley & Zisserman, *Multiple View Geometry*, 2nd ed. (H&Z):

* :func:`sampson_distance`: the first-order geometric error of a correspondence (section 11.4.3,
  "The Sampson distance", eq. 11.9).
* :func:`symmetric_epipolar_distance`: the distances of each point from its partner's epipolar line
  (section 11.4.3, eq. 11.10).
* :func:`reprojection_error`: the reprojection error of triangulated points (chapter 12,
  "Structure Computation", eq. 12.1).
* :func:`sampson_distances_normalized`: the Sampson distance of many candidate ``F`` at once, in
  Hartley-normalised coordinates (the robust estimators' scoring kernel).

Conventions (``docs/conventions.md``): points are rows, pixels ``(N, 2)``; :math:`m_2^T F m_1 = 0`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_points, as_up_to_scale
from .matrices import point_pairs

__all__ = [
    "reprojection_error",
    "sampson_distance",
    "sampson_distances_normalized",
    "symmetric_epipolar_distance",
]

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


def sampson_distances_normalized(Fs: np.ndarray, At: np.ndarray, s1: float, s2: float) -> np.ndarray:
    r"""Pixel Sampson distances ``(M, N)`` of ``M`` candidates ``Fs`` given in normalised coordinates (H&Z eq. 11.9).

    ``At`` is the transposed design matrix of the Hartley-normalised points
    (:func:`~egtviz.geometry.fundamental.design_matrix`), ``s1``, ``s2`` the normalisations' scales.

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
    den = np.array([s2 * s2, s2 * s2, s1 * s1, s1 * s1]) @ Q[:, 1:]  # (M, N): a batched product, not einsum
    np.maximum(den, 1e-300, out=den)
    d = np.divide(Q[:, 0], den, out=den)
    return d


def _lines_and_error(F: npt.ArrayLike, U1: npt.ArrayLike, U2: npt.ArrayLike):
    Fm = as_up_to_scale(F, "F", (3, 3))
    u1, u2 = point_pairs(U1, U2)
    h1 = np.column_stack([u1, np.ones(len(u1))])
    h2 = np.column_stack([u2, np.ones(len(u2))])
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
    u1, u2 = point_pairs(U1, U2)
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
