r"""Planes through the origin and point-plane distances.

A plane is :math:`\{X : n \cdot X = d\}`, unit normal :math:`n`, signed
distance :math:`d` from the origin along :math:`n`. Points are rows.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_array, as_points, as_scalar, as_vector

__all__ = ["plane_normals", "point_plane_distance"]

#: Cross products below this fraction of ``|X1| |X2|`` mean the vectors are parallel.
PARALLEL_TOL = 1e-12


def _euclidean(X: npt.ArrayLike, name: str) -> np.ndarray:
    """(N, 3) rows from Euclidean (N, 3) or homogeneous (N, 4) points (divided by the last coordinate)."""
    arr = as_array(X, name, allow_empty=False, max_abs=None)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] not in (3, 4):
        raise GeometryError(f"{name}: expected shape (N, 3) or homogeneous (N, 4), got {arr.shape}")
    if arr.shape[1] == 4:
        w = arr[:, 3]
        if np.any(np.abs(w) <= 1e-12 * np.abs(arr).max(axis=1)):
            raise GeometryError(f"{name}: a homogeneous point has last coordinate 0 (a point at infinity)")
        arr = arr[:, :3] / w[:, None]
    return as_points(arr, name, 3)


def plane_normals(X1: npt.ArrayLike, X2: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Unit normals of the planes through the origin spanned by ``X1[i]`` and ``X2[i]``.

    .. math:: n = \frac{X_1 \times X_2}{|X_1 \times X_2|}

    Args:
        X1: (N, 3) vectors, or homogeneous (N, 4) points.
        X2: (N, 3) or (N, 4), the same N.

    Returns:
        ``(normals, defined)``: (N, 3) unit normals, zero rows where the two
        vectors are parallel (no plane is defined), and the (N,) bool mask of
        the defined ones.
    """
    a, b = _euclidean(X1, "X1"), _euclidean(X2, "X2")
    if a.shape != b.shape:
        raise GeometryError(f"X2: expected as many points as X1 ({len(a)}), got {len(b)}")
    c = np.cross(a, b)
    norm = np.linalg.norm(c, axis=1)
    defined = norm > PARALLEL_TOL * np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
    n = np.zeros_like(c)
    n[defined] = c[defined] / norm[defined, None]
    return n, defined


def point_plane_distance(normal: npt.ArrayLike, distance: float, X: npt.ArrayLike) -> np.ndarray:
    r"""Unsigned distances of (N, 3) points from the plane :math:`n \cdot X = d`.

    .. math:: \delta = |\hat n \cdot X - d|, \qquad \hat n = n / |n|

    Raises:
        GeometryError: a zero normal, bad shapes.
    """
    n = as_vector(normal, "normal", 3)
    norm = float(np.linalg.norm(n))
    if not norm > 0.0:
        raise GeometryError("normal: expected a non-zero 3-vector")
    d = as_scalar(distance, "distance")
    return np.abs(as_points(X, "X", 3) @ (n / norm) - d)
