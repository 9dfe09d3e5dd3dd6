"""Checks at the public boundary of the numeric core.

Every public function of :mod:`egtviz.geometry` converts its arguments with
these helpers, so that bad input fails early with a :class:`GeometryError`
whose message names the argument and what was expected, never with a numpy
traceback from deep inside. The rules, in one place:

- ``None``, strings, booleans, complex numbers, object arrays, ragged nested
  lists and integers too large for a float are refused (a boolean is not a
  number here, even though numpy would read it as 0 or 1);
- NaN and inf are refused;
- empty input is refused where it makes no sense (a matrix, a vector, too
  few points for an estimator); an ``(0, dim)`` set of points is valid;
- magnitudes are bounded by :data:`MAX_MAGNITUDE` (world coordinates, pixels,
  calibration entries): beyond it, squares and products of coordinates
  overflow and no result could be trusted;
- quantities defined up to scale (F, E, P, H, quaternions, lines, homogeneous
  points) are divided by their largest absolute entry before any linear
  algebra (:func:`as_up_to_scale`), so that ``1e-200 F`` and ``1e200 F`` give
  the result of ``F``; the all-zero value is refused;
- a calibration matrix is upper triangular with last row (0, 0, 1) after
  division by ``K[2,2]`` (:func:`as_calibration`, the one check every camera
  model uses), and invertible;
- counts and image sizes are whole numbers in a stated range
  (:func:`as_count`): 2.5 samples or 640.5 pixels are refused, not rounded.

A bad value is quoted by at most a short prefix (:func:`short_repr`).
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt


class GeometryError(ValueError):
    """Bad input to, or a degenerate configuration for, a geometric computation."""


class DegenerateConfigurationError(GeometryError):
    """The configuration has no answer (coincident centres, coplanar data, ...)."""


#: Largest absolute coordinate, pixel or matrix entry the core accepts (outside quantities defined up to
#: scale). Its square, 1e200, and products of a few such terms stay far below the float64 limit (1.8e308).
MAX_MAGNITUDE = 1e100

#: Smallest length the core accepts where it is squared or inverted (mirror parameters): its square, 1e-200,
#: stays a normal float.
MIN_MAGNITUDE = 1e-100

#: Largest image side, in pixels, the core accepts.
MAX_IMAGE_SIZE = 10_000_000

#: Characters of a bad value quoted in an error message.
_QUOTE_LIMIT = 60


def short_repr(value: object) -> str:
    """A representation of ``value`` of at most a few dozen characters, for error messages.

    Integers too long to print (Python refuses ``repr`` beyond 4300 digits) are described by their size.
    """
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 200:
        return f"an integer of about {int(value.bit_length() * 0.30103)} digits"
    if isinstance(value, np.ndarray):
        text = np.array2string(value, threshold=6, edgeitems=2, max_line_width=_QUOTE_LIMIT)
        text = f"array({text}, shape={value.shape}, dtype={value.dtype})"
    else:
        try:
            text = repr(value)
        except Exception:  # a ragged list holding a huge integer, a broken __repr__, ...
            text = f"<{type(value).__name__}>"
    text = " ".join(text.split())
    return text if len(text) <= _QUOTE_LIMIT else text[: _QUOTE_LIMIT - 3] + "..."


def _describe(kind: str) -> str:
    return {
        "b": "booleans",
        "c": "complex numbers",
        "U": "strings",
        "S": "bytes",
        "O": "non-numeric objects",
        "M": "dates",
        "m": "time deltas",
        "V": "raw records",
    }.get(kind, f"values of kind {kind!r}")


def _scan_sequence(value: object, name: str, depth: int = 0) -> None:
    """Refuse booleans, None, strings and complex numbers hidden in nested lists (numpy would convert them)."""
    if depth > 32:
        raise GeometryError(f"{name}: nested more than 32 levels deep")
    if isinstance(value, bool | np.bool_):
        raise GeometryError(f"{name}: expected numbers, got a boolean ({value!r})")
    if value is None:
        raise GeometryError(f"{name}: expected numbers, got None inside a list")
    if isinstance(value, str | bytes):
        raise GeometryError(f"{name}: expected numbers, got a string ({short_repr(value)})")
    if isinstance(value, complex | np.complexfloating):
        raise GeometryError(f"{name}: expected real numbers, got a complex number ({short_repr(value)})")
    if isinstance(value, list | tuple):
        for item in value:
            if type(item) is not float and type(item) is not int:  # the common case, a flat list of numbers
                _scan_sequence(item, name, depth + 1)


def to_float64(value: object, name: str) -> np.ndarray:
    """``value`` as a float64 array (any shape), refusing every non-real-number type."""
    if value is None:
        raise GeometryError(f"{name}: expected a number or an array of numbers, got None")
    if isinstance(value, str | bytes):
        raise GeometryError(f"{name}: expected numbers, got a string ({short_repr(value)})")
    if isinstance(value, np.ndarray):
        arr = value
    else:
        if isinstance(value, list | tuple):
            _scan_sequence(value, name)
        elif isinstance(value, bool | np.bool_):
            raise GeometryError(f"{name}: expected a number, got a boolean ({value!r})")
        elif isinstance(value, complex | np.complexfloating):
            raise GeometryError(f"{name}: expected a real number, got a complex number ({short_repr(value)})")
        elif not isinstance(value, numbers.Real | np.generic | Sequence) and not hasattr(value, "__array__"):
            raise GeometryError(f"{name}: expected a number or an array of numbers, got {type(value).__name__}")
        try:
            arr = np.asarray(value)
        except (TypeError, ValueError, OverflowError) as exc:
            raise GeometryError(
                f"{name}: expected a rectangular array of numbers (nested lists of equal lengths), "
                f"got {short_repr(value)}"
            ) from exc
    kind = arr.dtype.kind
    if kind == "f" and arr.dtype == np.float64:
        return arr
    if kind in "iuf":
        try:
            return arr.astype(np.float64)
        except OverflowError as exc:  # pragma: no cover - float128 beyond float64
            raise GeometryError(f"{name}: values too large for a float ({short_repr(value)})") from exc
    if kind == "O":
        # Object arrays are refused outright, even of numbers: they come from mixed or oversized entries
        # (an integer beyond 64 bits, None, a Fraction); name the first such entry.
        for item in arr.reshape(-1):
            if isinstance(item, int) and not isinstance(item, bool) and abs(item) >= 2**63:
                if item.bit_length() > 1023:
                    raise GeometryError(f"{name}: {short_repr(item)} is too large for a float")
                raise GeometryError(f"{name}: {short_repr(item)} is an integer beyond 64 bits; pass it as a float")
            if not isinstance(item, numbers.Real) or isinstance(item, bool):
                break
        raise GeometryError(f"{name}: expected an array of real numbers, got an object array ({short_repr(value)})")
    raise GeometryError(f"{name}: expected real numbers, got {_describe(kind)} ({short_repr(value)})")


def _refuse_non_finite_or_huge(arr: np.ndarray, name: str, max_abs: float | None) -> None:
    """Refuse NaN, inf and entries above ``max_abs``: one or two reductions on the accepting path, the diagnosis
    only when it fails (NaN fails every comparison)."""
    if arr.size == 0:
        return
    limit = _FLOAT_MAX if max_abs is None else max_abs
    if arr.size > 64:
        # Two reductions without a temporary beat abs() on large arrays (a projection of 1e5 points).
        if -limit <= arr.min() and arr.max() <= limit:
            return
    elif np.abs(arr).max() <= limit:
        return
    if not np.all(np.isfinite(arr)):
        raise GeometryError(f"{name}: contains NaN or inf ({short_repr(arr)})")
    raise GeometryError(
        f"{name}: magnitude {np.abs(arr).max():.3g} is too large to compute with (at most {limit:.3g} in "
        "absolute value)"
    )


_FLOAT_MAX = float(np.finfo(np.float64).max)

__all__ = [
    "CALIBRATION_ZERO_TOL",
    "MAX_IMAGE_SIZE",
    "MAX_MAGNITUDE",
    "MIN_MAGNITUDE",
    "DegenerateConfigurationError",
    "GeometryError",
    "as_array",
    "as_calibration",
    "as_count",
    "as_matrix",
    "as_points",
    "as_positive",
    "as_rotation",
    "as_scalar",
    "as_up_to_scale",
    "as_up_to_scale_rows",
    "as_vector",
    "row_scales",
    "short_repr",
    "to_float64",
]


def as_array(
    value: object, name: str, *, allow_empty: bool = True, max_abs: float | None = MAX_MAGNITUDE
) -> np.ndarray:
    """Convert ``value`` to a finite float64 array of moderate magnitude, or raise naming ``name``.

    Args:
        value: a number or (nested) sequence or array of real numbers.
        name: the argument's name, quoted in the error.
        allow_empty: whether an array with no entries is accepted.
        max_abs: the largest accepted absolute entry (``None``: any finite value).

    Raises:
        GeometryError: ``None``, strings, booleans, complex numbers, objects, ragged lists, NaN, inf,
            an entry above ``max_abs``, or an empty array when ``allow_empty`` is False.
    """
    arr = to_float64(value, name)
    if not allow_empty and arr.size == 0:
        raise GeometryError(f"{name}: expected a non-empty array, got shape {arr.shape}")
    _refuse_non_finite_or_huge(arr, name, max_abs)
    return arr


def as_scalar(value: object, name: str, *, max_abs: float | None = MAX_MAGNITUDE) -> float:
    """A finite real number (a 1-element array is accepted); booleans, ``None``, strings are refused."""
    arr = as_array(value, name, max_abs=max_abs)
    if arr.size != 1:
        raise GeometryError(f"{name}: expected a single number, got shape {arr.shape}")
    return float(arr.reshape(()))


def as_points(
    value: npt.ArrayLike, name: str, dim: int, *, min_count: int = 0, max_abs: float | None = MAX_MAGNITUDE
) -> np.ndarray:
    """Points as rows: accept ``(N, dim)`` or a single ``(dim,)`` point; return ``(N, dim)``.

    At least ``min_count`` points are required. No points, ``(0, dim)``, is a valid set by default (a
    scene with no points has no images); an estimator that needs data passes its minimum. A flat empty
    array ``(0,)`` is a wrong shape.
    """
    arr = as_array(value, name, max_abs=max_abs)
    if arr.ndim == 1 and arr.shape[0] == dim:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise GeometryError(f"{name}: expected shape (N, {dim}) or ({dim},), got {arr.shape}")
    if arr.shape[0] < min_count:
        raise GeometryError(f"{name}: needs at least {min_count} points, got {arr.shape[0]}")
    return arr


def as_matrix(
    value: npt.ArrayLike, name: str, shape: tuple[int, ...], *, max_abs: float | None = MAX_MAGNITUDE
) -> np.ndarray:
    """A finite array of exactly ``shape``."""
    arr = as_array(value, name, max_abs=max_abs)
    if arr.shape != shape:
        raise GeometryError(f"{name}: expected shape {shape}, got {arr.shape}")
    return arr


def as_vector(value: npt.ArrayLike, name: str, size: int, *, max_abs: float | None = MAX_MAGNITUDE) -> np.ndarray:
    """A finite vector of ``size`` entries; a column ``(size, 1)`` or row ``(1, size)`` is accepted too."""
    arr = as_array(value, name, max_abs=max_abs)
    if arr.shape in ((size,), (size, 1), (1, size)):
        return arr.reshape(size)
    raise GeometryError(f"{name}: expected a {size}-vector, got shape {arr.shape}")


def as_up_to_scale(value: npt.ArrayLike, name: str, shape: tuple[int, ...]) -> np.ndarray:
    r"""A quantity defined up to scale, divided by its largest absolute entry: :math:`A / \max_{ij} |A_{ij}|`.

    Any finite magnitude is accepted (1e-300 to 1e300): after the division every entry is in ``[-1, 1]``
    and the largest is exactly 1 in absolute value, so the linear algebra that follows sees the same
    numbers whatever the scale. The all-zero value defines nothing and is refused.

    Args:
        value: F, E, P, H, a quaternion, a line, a homogeneous point, ...
        name: the argument's name, quoted in the error.
        shape: the required shape.

    Raises:
        GeometryError: a bad type, NaN, inf, a wrong shape, or all entries zero.
    """
    arr = as_matrix(value, name, shape, max_abs=None)
    top = np.abs(arr).max() if arr.size else 0.0
    if not top > 0.0:
        raise GeometryError(f"{name}: is zero; a quantity defined up to scale must have a non-zero entry")
    return arr / top


def as_up_to_scale_rows(
    value: npt.ArrayLike, name: str, dim: int, *, min_count: int = 0, allow_zero: bool = False
) -> np.ndarray:
    r"""Rows ``(N, dim)`` each defined up to scale (homogeneous points, lines, directions, plane normals), each
    divided by its largest absolute entry.

    A single ``(dim,)`` row is accepted as ``N = 1``. Any finite magnitude is accepted. A row of zeros is
    refused, naming its index, unless ``allow_zero`` (where the caller documents what a zero row means,
    e.g. a direction that is no ray): it is then returned as zeros.
    """
    arr, top = _rows_and_scales(value, name, dim, min_count=min_count, allow_zero=allow_zero)
    return arr / top[:, None]


def _rows_and_scales(
    value: npt.ArrayLike, name: str, dim: int, *, min_count: int = 0, allow_zero: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """The checked rows ``(N, dim)`` and each row's largest absolute entry (1 for a zero row)."""
    arr = as_points(value, name, dim, min_count=min_count, max_abs=None)
    top = np.abs(arr).max(axis=1) if arr.size else np.ones(len(arr))
    zero = ~(top > 0.0)
    if zero.any():
        if not allow_zero:
            raise GeometryError(
                f"{name}: row {int(np.flatnonzero(zero)[0])} is zero; a quantity defined up to scale needs a "
                "non-zero entry"
            )
        top[zero] = 1.0
    return arr, top


def row_scales(value: npt.ArrayLike, name: str, dim: int, *, allow_zero: bool = False) -> tuple[np.ndarray, np.ndarray]:
    r""":func:`as_up_to_scale_rows` that also returns each row's scale ``(N,)``, for results that must be scaled
    back (a ray parameter :math:`\lambda` of :math:`X = \lambda d`)."""
    arr, top = _rows_and_scales(value, name, dim, allow_zero=allow_zero)
    return arr / top[:, None], top


def as_positive(
    value: object, name: str, *, max_abs: float | None = MAX_MAGNITUDE, min_value: float = 0.0
) -> float:
    """A finite, strictly positive scalar, at least ``min_value`` (e.g. :data:`MIN_MAGNITUDE` for a length that
    is squared) and at most ``max_abs``."""
    x = as_scalar(value, name, max_abs=max_abs)
    if x <= 0:
        raise GeometryError(f"{name}: expected a positive number, got {short_repr(value)}")
    if x < min_value:
        raise GeometryError(f"{name}: {x:.3g} is too small to compute with (at least {min_value:.3g})")
    return x


def as_count(value: object, name: str, *, minimum: int = 1, maximum: int | None = None) -> int:
    """A whole number in ``[minimum, maximum]`` (a float with an integral value is accepted; 2.5 is not)."""
    x = as_scalar(value, name)
    if x != int(x):
        raise GeometryError(f"{name}: expected a whole number, got {short_repr(value)}")
    n = int(x)
    if n < minimum or (maximum is not None and n > maximum):
        upper = "" if maximum is None else f" and at most {maximum}"
        raise GeometryError(f"{name}: expected a whole number at least {minimum}{upper}, got {short_repr(n)}")
    return n


def as_rotation(value: npt.ArrayLike, name: str, *, tol: float = 1e-6) -> np.ndarray:
    """A 3x3 proper rotation (orthonormal, determinant +1) within ``tol``."""
    R = as_matrix(value, name, (3, 3))
    if np.abs(R.T @ R - np.eye(3)).max() > tol or np.linalg.det(R) <= 0:
        raise GeometryError(f"{name}: expected a 3x3 rotation matrix (R^T R = I, det R = +1)")
    return R


#: Relative tolerance on the entries of a calibration matrix that must be zero.
CALIBRATION_ZERO_TOL = 1e-12


def as_calibration(value: npt.ArrayLike, name: str) -> np.ndarray:
    r"""A calibration matrix, scaled to :math:`K_{33} = 1`, upper triangular and invertible.

    .. math:: K = \begin{bmatrix} k_u f & \gamma & u_0 \\ 0 & k_v f & v_0 \\ 0 & 0 & 1 \end{bmatrix}

    ``K`` is accepted up to scale (it is divided by :math:`K_{33}`); the entries below the diagonal must
    then be zero within ``CALIBRATION_ZERO_TOL`` times the largest entry (and are set to exactly zero), so
    every camera model reads the same matrix. Anything else is refused, not silently altered.

    Raises:
        GeometryError: a bad type or shape, :math:`K_{33} = 0`, a non-zero entry below the diagonal, a
            singular or ill-conditioned matrix (condition number above 1e12).
    """
    K = as_up_to_scale(value, name, (3, 3))
    if K[2, 2] == 0.0:
        raise GeometryError(f"{name}: expected a calibration matrix with last row (0, 0, k) and k != 0")
    if abs(K[2, 2]) < 1e-12:
        raise GeometryError(
            f"{name}: entries up to {1.0 / abs(K[2, 2]):.3g} times K[2,2]; a calibration matrix needs them within "
            "1e12 times K[2,2] (pixels and focal lengths in pixels of a plausible camera)"
        )
    K = K / K[2, 2]
    tol = CALIBRATION_ZERO_TOL * np.abs(K).max()
    below = K[(1, 2, 2), (0, 0, 1)]
    if np.abs(below).max() > tol:
        raise GeometryError(
            f"{name}: expected an upper-triangular calibration matrix with last row (0, 0, 1); "
            f"got K[1,0] = {below[0]:.6g}, K[2,0] = {below[1]:.6g}, K[2,1] = {below[2]:.6g} "
            f"(after dividing by K[2,2])"
        )
    K[(1, 2, 2), (0, 0, 1)] = 0.0
    if abs(K[0, 0] * K[1, 1]) < 1e-12 or np.linalg.cond(K) > 1e12:
        raise GeometryError(f"{name}: calibration matrix is not invertible (singular, or condition number above 1e12)")
    return K
