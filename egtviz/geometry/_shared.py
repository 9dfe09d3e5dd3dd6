"""Arithmetic several modules of the core share on the per-drag path (public names of a private module).

Each helper is either checked where noted or takes plain, already checked values: they exist so that a module
need not import another module's private names.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Generic, TypeVar, overload

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, as_calibration

__all__ = [
    "AT_INFINITY_TOL",
    "COINCIDENT_CENTRES_TOL",
    "cached_value",
    "centres_coincide",
    "epipolar_normals_columns",
    "inverse_calibration",
    "matrix_rank3",
    "normalize_homogeneous3",
    "skew3",
]

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
    elif not K.flags.writeable and K.base is None:
        # A camera's own read-only K that owns its data (the same array on every drag): found by identity, no bytes
        # to hash. The entry holds K itself, so its id is not reused while the entry lives.
        hit = _BY_IDENTITY.get(id(K))
        if hit is not None and hit[0] is K and hit[2] == name:
            return hit[1]
        inv = _inverse_of(np.ascontiguousarray(K).tobytes(), name)
        if len(_BY_IDENTITY) >= 64:
            _BY_IDENTITY.clear()
        _BY_IDENTITY[id(K)] = (K, inv, name)
        return inv
    return _inverse_of(np.ascontiguousarray(K).tobytes(), name)


_BY_IDENTITY: dict[int, tuple[np.ndarray, np.ndarray, str]] = {}
"""Read-only calibration matrices seen last, by ``id``: ``(K, K^-1, name)``."""


@lru_cache(maxsize=64)
def _inverse_of(K_bytes: bytes, name: str) -> np.ndarray:
    inv = np.linalg.inv(as_calibration(np.frombuffer(K_bytes).reshape(3, 3), name))
    inv.setflags(write=False)
    return inv


#: Two centres closer than this (relative to the scene scale 1) have no epipolar geometry.
COINCIDENT_CENTRES_TOL = 1e-9


def centres_coincide(c1: np.ndarray, c2: np.ndarray) -> bool:
    """``|c1 - c2| <= COINCIDENT_CENTRES_TOL * max(1, |c1|, |c2|)``; plain floats for two 3-vectors (every drag)."""
    if c1.shape == c2.shape == (3,):
        a, b = c1.tolist(), c2.tolist()
        scale = max(1.0, math.hypot(*a), math.hypot(*b))
        return math.dist(a, b) <= COINCIDENT_CENTRES_TOL * scale
    scale = max(1.0, float(np.linalg.norm(c1)), float(np.linalg.norm(c2)))
    return bool(np.linalg.norm(c1 - c2) <= COINCIDENT_CENTRES_TOL * scale)


def skew3(x: float, y: float, z: float) -> np.ndarray:
    """:func:`~egtviz.geometry.poses.skew` of an already checked vector."""
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def matrix_rank3(M: np.ndarray, tol: float) -> int:
    r"""``np.linalg.matrix_rank(M, tol)`` of a 3x3 matrix, decided from its invariants when that is conclusive.

    The singular values :math:`\sigma_1 \ge \sigma_2 \ge \sigma_3` satisfy
    :math:`\|M\|_F / \sqrt 3 \le \sigma_1 \le \|M\|_F`,
    :math:`\|\mathrm{adj}\,M\|_F / \sqrt 3 \le \sigma_1 \sigma_2 \le \|\mathrm{adj}\,M\|_F` (the singular
    values of the adjugate are :math:`\sigma_1\sigma_2, \sigma_1\sigma_3, \sigma_2\sigma_3`) and
    :math:`\sigma_1\sigma_2\sigma_3 = |\det M|`, which bound each :math:`\sigma_k`. When every bound,
    widened by generous rounding allowances, is on one side of ``tol`` by a factor 2, the rank follows
    without an SVD (a fundamental matrix on every drag: rank 2 with :math:`\sigma_3` at rounding level);
    otherwise the SVD decides.
    """
    (a, b, c), (d, e, f), (g, h, i) = M.tolist()
    # Adjugate entries (cofactors, p - q) and the determinant along the first row, with the sizes |p| + |q|
    # of their terms for the rounding allowances (over ten times the worst case of these formulas).
    pairs = ((e * i, f * h), (f * g, d * i), (d * h, e * g),
             (c * h, b * i), (a * i, c * g), (b * g, a * h),
             (b * f, c * e), (c * d, a * f), (a * e, b * d))
    cof = [p - q for p, q in pairs]
    size = [abs(p) + abs(q) for p, q in pairs]
    norm = math.sqrt(a * a + b * b + c * c + d * d + e * e + f * f + g * g + h * h + i * i)
    adj = math.sqrt(sum(x * x for x in cof))
    det = abs(a * cof[0] + b * cof[1] + c * cof[2])
    err_adj = 1e-14 * sum(size)
    err_det = 1e-14 * (abs(a) * size[0] + abs(b) * size[1] + abs(c) * size[2])
    r3 = math.sqrt(3.0)
    bounds = [(norm / r3, norm)]  # sigma_1
    if adj > err_adj:
        bounds.append(((adj - err_adj) / (r3 * norm), r3 * (adj + err_adj) / norm))  # sigma_1 sigma_2 / sigma_1
        bounds.append(((det - err_det) / (adj + err_adj), r3 * (det + err_det) / (adj - err_adj)))  # det / (s1 s2)
    # The SVD's own singular values are off by up to a few ulps of |M|: decide only beyond that as well.
    above, below = 2.0 * tol + 1e-13 * norm, 0.5 * tol - 1e-13 * norm
    rank = 0
    for lo, hi in bounds:  # sigma_1, sigma_2, sigma_3 in turn
        if lo > above:
            rank += 1
        elif hi < below:
            return rank  # this and every smaller singular value are below tol
        else:
            break  # too close to tol to tell
    else:
        if len(bounds) == 3:
            return rank
    # Inconclusive (or adj M at rounding level: sigma_2 not bounded away from 0): the SVD decides.
    return int(np.linalg.matrix_rank(M, tol=tol))


def epipolar_normals_columns(c1: np.ndarray, c2: np.ndarray, XT: np.ndarray) -> np.ndarray:
    r"""The unit normals of :func:`~egtviz.geometry.epipolar.epipolar_planes`, coordinate-major: (3, N) from checked ``c1``, ``c2`` (3,)
    and the points as ``XT`` (3, N) (best contiguous).

    :math:`n = [b]_\times v` with :math:`b = c_2 - c_1`, :math:`v = X - c_1` (one matrix product for all
    points). NaN columns for points on the baseline, :math:`|n| \le 10^{-12} |b|\,|v|`.

    Raises:
        DegenerateConfigurationError: the centres coincide.
    """
    if centres_coincide(c1, c2):
        raise DegenerateConfigurationError("no epipolar geometry: the centres coincide")
    bx, by, bz = (c2 - c1).tolist()
    v = XT - c1[:, None]
    n = skew3(bx, by, bz) @ v
    norm2 = np.add.reduce(n * n, axis=0)
    # Points on the baseline: |n| <= 1e-12 |b| |v|, compared squared.
    on_baseline = norm2 <= np.add.reduce(v * v, axis=0) * (1e-24 * (bx * bx + by * by + bz * bz))
    if np.logical_or.reduce(on_baseline):
        with np.errstate(divide="ignore", invalid="ignore"):
            n /= np.sqrt(norm2)
        n[:, on_baseline] = np.nan
    else:
        # Every norm is positive (a zero one is on the baseline): no error context needed (every drag).
        n /= np.sqrt(norm2)
    return n


_T = TypeVar("_T")


class _CachedValue(Generic[_T]):
    """``functools.cached_property`` without its lock: the value, computed on first read, is stored in the
    instance's ``__dict__`` (later reads never reach the descriptor).

    Python 3.11's ``cached_property`` takes a lock shared by every instance on each first read; the values here
    (matrices of an immutable camera or pose) are deterministic, so two threads that compute one at once store
    equal values, and a new camera per drag step reads several of them.
    """

    def __init__(self, func: Callable[[Any], _T]) -> None:
        self.func = func
        self.name = func.__name__
        self.__doc__ = func.__doc__

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, instance: None, owner: type | None = None) -> _CachedValue[_T]: ...

    @overload
    def __get__(self, instance: object, owner: type | None = None) -> _T: ...

    def __get__(self, instance: object, owner: type | None = None) -> _T | _CachedValue[_T]:
        if instance is None:
            return self
        value = instance.__dict__[self.name] = self.func(instance)
        return value



if TYPE_CHECKING:
    # A type checker knows cached_property as a read-only member (it matches a Protocol's property); at run time
    # the lock-free class above stands in for it with the same reads.
    from functools import cached_property as cached_value
else:
    cached_value = _CachedValue
