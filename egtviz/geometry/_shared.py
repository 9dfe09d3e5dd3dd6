"""Arithmetic several modules of the core share on the per-drag path (public names of a private module).

Each helper is either checked where noted or takes plain, already checked values: they exist so that a module
need not import another module's private names.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from ._validate import as_calibration

__all__ = ["AT_INFINITY_TOL", "inverse_calibration", "normalize_homogeneous3"]

#: A homogeneous point whose last coordinate is below this fraction of its norm is at infinity.
AT_INFINITY_TOL = 1e-12


def normalize_homogeneous3(x: float, y: float, z: float) -> np.ndarray:
    """``normalize_homogeneous`` (:mod:`egtviz.geometry.homogeneous`) of one vector given as three plain finite
    floats (epipoles, on every drag): last coordinate 1, or unit norm with last coordinate 0 at infinity.

    Unchecked, and without the division by the largest entry: the caller passes finite values of moderate
    magnitude; a zero vector gives zeros.
    """
    norm = math.sqrt(x * x + y * y + z * z)
    if abs(z) <= AT_INFINITY_TOL * norm:
        safe = norm if norm > 0 else 1.0
        return np.array([x / safe, y / safe, 0.0])
    return np.array([x / z, y / z, 1.0])


def inverse_calibration(K: npt.ArrayLike, name: str = "K") -> np.ndarray:
    """:math:`K^{-1}` of a calibration matrix (``inv(as_calibration(K))``), read-only, remembered per matrix (a
    camera drag keeps both calibrations).

    A (3, 3) float64 array is looked up by its bytes (checked on its first use only); anything else is checked
    first.

    Raises:
        GeometryError: naming ``name``, for a matrix ``as_calibration`` refuses.
    """
    if not (isinstance(K, np.ndarray) and K.dtype == np.float64 and K.shape == (3, 3)):
        K = as_calibration(K, name)
    return _inverse_of(np.ascontiguousarray(K).tobytes(), name)


@lru_cache(maxsize=64)
def _inverse_of(K_bytes: bytes, name: str) -> np.ndarray:
    inv = np.linalg.inv(as_calibration(np.frombuffer(K_bytes).reshape(3, 3), name))
    inv.setflags(write=False)
    return inv
