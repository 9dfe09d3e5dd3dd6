r"""Small matrix utilities of two-view geometry: rank-2 projection, stacking, point normalisation, angles.

Points are rows, ``(N, 2)`` pixels; conventions: ``docs/conventions.md``.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_array, as_count, as_matrix, as_points

__all__ = ["full_angle", "hartley_normalization", "nearest_rank2", "stack_columns", "unstack_columns"]


def nearest_rank2(M: npt.ArrayLike) -> np.ndarray:
    r"""The rank-2 matrix nearest to ``M`` in Frobenius norm (Eckart-Young; H&Z 11.1.1).

    .. math:: M = U \operatorname{diag}(\sigma_1, \sigma_2, \sigma_3) V^T
        \ \mapsto\ U \operatorname{diag}(\sigma_1, \sigma_2, 0) V^T

    Args:
        M: (3, 3) matrix.
    """
    A = as_matrix(M, "M", (3, 3), max_abs=None)
    U, s, Vt = np.linalg.svd(A)
    s[2] = 0.0
    return (U * s) @ Vt


def stack_columns(M: npt.ArrayLike) -> np.ndarray:
    r"""The column-wise stacking :math:`\mathrm{vec}(M)` of an (m, n) matrix: an (m n,) vector, column 1 first."""
    A = as_array(M, "M", allow_empty=False, max_abs=None)
    if A.ndim != 2:
        raise GeometryError(f"M: expected a 2-D matrix, got shape {A.shape}")
    return A.reshape(-1, order="F")


def unstack_columns(v: npt.ArrayLike, columns: int) -> np.ndarray:
    r"""The inverse of :func:`stack_columns`: an (len(v) / columns, columns) matrix filled column by column.

    Raises:
        GeometryError: ``columns`` does not divide the length of ``v``.
    """
    a = as_array(v, "v", allow_empty=False, max_abs=None).reshape(-1)
    k = as_count(columns, "columns", minimum=1)
    if a.size % k:
        raise GeometryError(f"columns: {k} does not divide the vector's length {a.size}")
    return a.reshape(k, -1).T.copy()


def hartley_normalization(U: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Hartley's isotropic normalisation of pixels (H&Z 2nd ed., section 4.4.4).

    .. math:: T = \begin{bmatrix} s & 0 & -s c_u \\ 0 & s & -s c_v \\ 0 & 0 & 1 \end{bmatrix},
        \qquad s = \frac{\sqrt 2}{\sqrt{\tfrac1N \sum_i |u_i - c|^2}}

    with :math:`c` the centroid: the normalised points have centroid 0 and
    root-mean-square distance :math:`\sqrt 2` from it.

    Args:
        U: (N, 2) pixels.

    Returns:
        ``(Un, T)``: (N, 2) normalised pixels and the (3, 3) similarity ``T``.

    Raises:
        DegenerateConfigurationError: all points coincide.
    """
    u = as_points(U, "U", 2)
    c = u.mean(axis=0)
    rms = float(np.sqrt(np.mean(np.sum((u - c) ** 2, axis=1))))
    if not rms > 0.0:
        raise DegenerateConfigurationError("U: all points coincide; no normalisation exists")
    s = np.sqrt(2.0) / rms
    T = np.array([[s, 0.0, -s * c[0]], [0.0, s, -s * c[1]], [0.0, 0.0, 1.0]])
    return s * (u - c), T


def full_angle(y: npt.ArrayLike, x: npt.ArrayLike) -> np.ndarray:
    r"""The angle of :math:`(x, y)` in :math:`[0, 2\pi)`: :math:`\operatorname{atan2}(y, x) \bmod 2\pi`.

    ``y`` and ``x`` broadcast against each other; ``(0, 0)`` gives 0.
    """
    yy = as_array(y, "y", allow_empty=False)
    xx = as_array(x, "x", allow_empty=False)
    try:
        a = np.arctan2(yy, xx)
    except ValueError as exc:
        raise GeometryError(f"y, x: shapes {yy.shape} and {xx.shape} do not broadcast") from exc
    a = np.where(a < 0.0, a + 2.0 * np.pi, a)
    # A tiny negative angle rounds to exactly 2 pi; it is the angle 0.
    return np.where(a >= 2.0 * np.pi, 0.0, a)
