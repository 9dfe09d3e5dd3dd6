"""Checks at the public boundary of the numeric core.

Every public function of :mod:`egtviz.geometry` converts its array arguments
with these helpers, so that bad input fails early with a message naming the
argument and the expected shape, never with a numpy traceback from deep inside.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


class GeometryError(ValueError):
    """Bad input to, or a degenerate configuration for, a geometric computation."""


class DegenerateConfigurationError(GeometryError):
    """The configuration has no answer (coincident centres, coplanar data, ...)."""


def as_array(value: npt.ArrayLike, name: str) -> np.ndarray:
    """Convert ``value`` to a finite float64 array, or raise naming ``name``."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{name}: expected a numeric array, got {type(value).__name__}") from exc
    if not np.all(np.isfinite(arr)):
        raise GeometryError(f"{name}: contains NaN or inf")
    return arr


def as_points(value: npt.ArrayLike, name: str, dim: int, *, min_count: int = 0) -> np.ndarray:
    """Points as rows: accept ``(N, dim)`` or a single ``(dim,)`` point; return ``(N, dim)``."""
    arr = as_array(value, name)
    if arr.ndim == 1 and arr.shape[0] == dim:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise GeometryError(f"{name}: expected shape (N, {dim}), got {arr.shape}")
    if arr.shape[0] < min_count:
        raise GeometryError(f"{name}: needs at least {min_count} points, got {arr.shape[0]}")
    return arr


def as_matrix(value: npt.ArrayLike, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """A finite array of exactly ``shape``."""
    arr = as_array(value, name)
    if arr.shape != shape:
        raise GeometryError(f"{name}: expected shape {shape}, got {arr.shape}")
    return arr


def as_vector(value: npt.ArrayLike, name: str, size: int) -> np.ndarray:
    """A finite vector of ``size`` entries; a column ``(size, 1)`` is accepted too."""
    arr = as_array(value, name)
    if arr.shape in ((size,), (size, 1), (1, size)):
        return arr.reshape(size)
    raise GeometryError(f"{name}: expected a {size}-vector, got shape {arr.shape}")


def as_positive(value: float, name: str) -> float:
    """A finite, strictly positive scalar."""
    try:
        x = float(value)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{name}: expected a positive number, got {value!r}") from exc
    if not np.isfinite(x) or x <= 0:
        raise GeometryError(f"{name}: expected a positive finite number, got {value!r}")
    return x


def as_rotation(value: npt.ArrayLike, name: str, *, tol: float = 1e-6) -> np.ndarray:
    """A 3x3 proper rotation (orthonormal, determinant +1) within ``tol``."""
    R = as_matrix(value, name, (3, 3))
    if np.abs(R.T @ R - np.eye(3)).max() > tol or np.linalg.det(R) <= 0:
        raise GeometryError(f"{name}: expected a 3x3 rotation matrix (R^T R = I, det R = +1)")
    return R


def as_calibration(value: npt.ArrayLike, name: str) -> np.ndarray:
    """An invertible upper-triangular-style calibration matrix ``K`` (3x3, ``K[2] = [0, 0, 1]`` up to scale)."""
    K = as_matrix(value, name, (3, 3))
    if abs(K[2, 2]) < 1e-12 or not np.allclose(K[2, :2], 0.0):
        raise GeometryError(f"{name}: expected a calibration matrix with last row [0, 0, k33 != 0]")
    K = K / K[2, 2]
    if abs(K[0, 0] * K[1, 1]) < 1e-12 or np.linalg.cond(K) > 1e12:
        raise GeometryError(f"{name}: calibration matrix is not invertible")
    return K
