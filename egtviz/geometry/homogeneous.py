"""Homogeneous points and lines in the image plane."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import numpy.typing as npt

from ._shared import AT_INFINITY_TOL, normalize_homogeneous3
from ._validate import as_array, as_points, as_positive, as_up_to_scale_rows

__all__ = [
    "AT_INFINITY_TOL",
    "clip_lines_to_rect",
    "homogeneous",
    "is_at_infinity",
    "normalize_homogeneous",
    "normalize_lines",
]


def homogeneous(points: npt.ArrayLike, name: str = "points") -> np.ndarray:
    """(N, 2) pixels -> (N, 3) homogeneous pixels with last coordinate 1."""
    m = as_points(points, name, 2)
    return np.column_stack([m, np.ones(len(m))])


def normalize_homogeneous(v: npt.ArrayLike) -> np.ndarray:
    r"""Scale homogeneous 3-vectors (3,) or (N, 3): finite -> last coordinate 1, at infinity -> unit norm, w = 0.

    .. math:: v \mapsto v / v_3 \quad (|v_3| > \epsilon |v|), \qquad v \mapsto (v_1, v_2, 0) / |v| \quad
        \text{otherwise},

    with :math:`\epsilon` = ``AT_INFINITY_TOL``. Each vector is defined up to scale and first divided by its
    largest absolute entry, so any finite magnitude gives the same result; never divides by zero (see
    ``docs/conventions.md``).

    Raises:
        GeometryError: ``v`` is not (3,) or (N, 3) finite numbers, or a vector is zero.
    """
    single = _is_single(v, "v")
    a = as_up_to_scale_rows(v, "v", 3)
    if single:
        return normalize_homogeneous3(*a[0].tolist())
    norm = np.linalg.norm(a, axis=1)
    at_inf = np.abs(a[:, 2]) <= AT_INFINITY_TOL * norm
    out = np.empty_like(a)
    finite = ~at_inf
    out[finite] = a[finite] / a[finite, 2:3]
    out[at_inf] = a[at_inf] / norm[at_inf, None]  # norm >= 1: the largest entry is +-1
    out[at_inf, 2] = 0.0
    return out


def _is_single(v: npt.ArrayLike, name: str) -> bool:
    """Whether ``v`` is one flat vector (then results are returned flat); bad input raises naming ``name``."""
    return as_array(v, name, max_abs=None).ndim == 1


def is_at_infinity(v: npt.ArrayLike) -> np.ndarray | bool:
    r"""True where a homogeneous point (3,) or (N, 3) has (numerically) zero last coordinate,
    :math:`|v_3| \le \epsilon |v|` with :math:`\epsilon` = ``AT_INFINITY_TOL`` (a bool for a single vector)."""
    single = _is_single(v, "v")
    a = as_up_to_scale_rows(v, "v", 3)
    res = np.abs(a[:, 2]) <= AT_INFINITY_TOL * np.linalg.norm(a, axis=1)
    return bool(res[0]) if single else res


def normalize_lines(lines: npt.ArrayLike) -> np.ndarray:
    r"""Scale lines (N, 3) ``(a, b, c)`` to :math:`a^2 + b^2 = 1` so that ``l . m`` is a distance in pixels.

    Each line is defined up to scale (first divided by its largest absolute entry, so any finite magnitude
    gives the same result). The line at infinity ``(0, 0, c)``, :math:`|(a, b)| \le \epsilon |(a, b, c)|`, is
    returned as NaN.

    Raises:
        GeometryError: ``lines`` is not (3,) or (N, 3) finite numbers, or a line is zero.
    """
    return _normalized_lines(as_up_to_scale_rows(lines, "lines", 3))


def _normalized_lines(lines: np.ndarray) -> np.ndarray:
    """:func:`normalize_lines` of float64 (N, 3) rows already divided by their largest absolute entry; unchecked."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return _normalized_lines_quiet(lines)


def _normalized_lines_quiet(lines: np.ndarray) -> np.ndarray:
    """:func:`_normalized_lines` under the caller's ``np.errstate`` (division and invalid ignored): one
    context fewer per drag, each a few microseconds."""
    n = np.hypot(lines[:, 0], lines[:, 1])
    out = lines / n[:, None]
    # |l| as np.linalg.norm(lines, axis=1) computes it (the squares summed in order), without its wrapper.
    norm = lines[:, 0] * lines[:, 0]
    norm += lines[:, 1] * lines[:, 1]
    norm += lines[:, 2] * lines[:, 2]
    out[n <= AT_INFINITY_TOL * np.sqrt(norm)] = np.nan
    return out


def clip_lines_to_rect(lines: npt.ArrayLike, width: float, height: float, *,
                       check: bool = True) -> tuple[np.ndarray, np.ndarray]:
    r"""Clip infinite lines :math:`a u + b v + c = 0` (N, 3) to the rectangle ``[0, w] x [0, h]``.

    Returns ``(segments (N, 2, 2), hit (N,) bool)``; rows that miss the
    rectangle are NaN. Vectorised: each line, divided by its largest absolute entry (defined up to scale), is
    intersected with the four border lines,

    .. math:: v = -\frac{a u + c}{b} \ (u \in \{0, w\}), \qquad u = -\frac{b v + c}{a} \ (v \in \{0, h\}),

    and of the candidates inside the rectangle (up to ``eps``) the two extreme
    ones along the line direction :math:`(-b, a)` are kept. The line at infinity
    (:func:`normalize_lines`' NaN) meets no rectangle.

    Args:
        lines: (N, 3) line coefficients.
        width, height: the rectangle's size (> 0).
        check: validate the arguments (default). ``check=False`` is the fast path for lines that are already a
            float64 (N, 3) array and a positive finite ``width`` and ``height`` (e.g. computed by the core from
            validated cameras): nothing is checked, and a row that is not finite or is zero
            (which the checked call refuses) gives a NaN segment and ``hit = False``. Valid rows give exactly the
            checked call's segments.

    Raises:
        GeometryError: (``check=True``) ``lines`` is not (N, 3) finite numbers or a line is zero; ``width`` or
            ``height`` is not a positive number.
    """
    if not check:
        # The checked call's arithmetic without its checks: each row divided by its largest entry (a row that is
        # not finite or is zero becomes NaN on the way).
        lines = np.asarray(lines)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # one context for both steps
            L = lines / np.maximum.reduce(np.abs(lines), axis=1, initial=0.0)[:, None]
            return _clip_line_rows_quiet(L, float(width), float(height))
    L = as_up_to_scale_rows(lines, "lines", 3)
    width, height = as_positive(width, "width"), as_positive(height, "height")
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return _clip_line_rows_quiet(L, width, height)


def _clip_lines(lines_T: np.ndarray, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`clip_lines_to_rect` of float64 lines given coordinate-major, ``(a, b, c)`` rows (3, N); unchecked.

    The lines need not be normalised: the candidates, and their order along the line, do not depend on the
    scale of ``(a, b, c)`` (but it should be moderate, as for image lines of unit plane normals).
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return _clip_line_rows_quiet(lines_T.T, width, height)


@lru_cache(maxsize=32)
def _border_columns(width: float, height: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For the borders ``u = 0``, ``u = w``, ``v = 0``, ``v = h`` (in this order): a stack (4, 3, 4) of matrices
    whose products with lines ``(a, b, c)`` give, per border, the numerator and the denominator of the
    candidate's free coordinate (``-(a u + c)`` over ``b``, ``-(b v + c)`` over ``a``), and the coefficient and
    the constant of its position :math:`s = -b u + a v` along the line's direction; the fixed coordinates (4,);
    the free coordinates' upper limits (4,), widened by the clip's ``eps``. Read-only."""
    M = np.zeros((4, 3, 4))
    M[0, 2] = -1.0  # numerators: -c, -(a w + c), -c, -(b h + c)
    M[0, 0, 1] = -width
    M[0, 1, 3] = -height
    M[1, 1, 0:2] = 1.0  # denominators: b, b, a, a
    M[1, 0, 2:4] = 1.0
    M[2, 0, 0:2] = 1.0  # coefficients of the free coordinate in s: a, a, -b, -b
    M[2, 1, 2:4] = -1.0
    M[3, 1, 1] = -width  # constants: 0, -b w, 0, a h
    M[3, 0, 3] = height
    eps = 1e-9 * max(width, height, 1.0)
    out = (M, np.array([0.0, width, 0.0, height]), np.array([height, height, width, width]) + eps)
    for a in out:
        a.setflags(write=False)
    return out


def _clip_line_rows_quiet(L: np.ndarray, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`clip_lines_to_rect` of float64 (N, 3) lines of moderate scale, under the caller's ``np.errstate``
    (division, invalid and overflow ignored); unchecked (both images of a pin-hole pair, on every drag).

    One stacked product gives every border's candidate and its position along the line (4 contiguous (N, 4)
    blocks); then a fixed, small number of numpy calls over the (N, 4) candidates.
    """
    n = len(L)
    eps = 1e-9 * max(width, height, 1.0)
    if max(width, height) > 1e9:
        # normalize_lines makes the line at infinity, |(a, b)| <= AT_INFINITY_TOL |(a, b, c)|, NaN. It lies
        # 1 / AT_INFINITY_TOL or more from the origin: only so large a rectangle needs that done here.
        L = _normalized_lines_quiet(L)
    M, fixed, upper = _border_columns(width, height)
    num, den, coef, const = np.matmul(L, M)
    free = num / den
    # A candidate counts when its computed coordinate is inside (up to eps; NaN and inf are not).
    ok = free >= -eps
    ok &= free <= upper
    s = free * coef
    s += const
    # Keep the extremes along the line (the first on ties).
    ends = np.empty((n, 2), dtype=np.intp)
    np.where(ok, s, np.inf).argmin(axis=1, out=ends[:, 0])
    np.where(ok, s, -np.inf).argmax(axis=1, out=ends[:, 1])
    cand = np.empty((n, 4, 2))
    cand[:, 0:2, 0] = fixed[0:2]
    cand[:, 0:2, 1] = free[:, 0:2]
    cand[:, 2:4, 0] = free[:, 2:4]
    cand[:, 2:4, 1] = fixed[2:4]
    seg = cand[np.arange(n)[:, None], ends]  # (line, end, coordinate)
    # A line that meets the rectangle in one corner only, or not at all (both ends are then the same
    # candidate, maybe NaN), has no segment: length <= eps, compared squared.
    d = seg[:, 1] - seg[:, 0]
    d *= d
    hit = d[:, 0] + d[:, 1] > eps * eps
    seg[~hit] = np.nan
    np.maximum(seg, 0.0, out=seg)
    np.minimum(seg, fixed[1::2], out=seg)  # (w, h): each coordinate at most its side
    return seg, hit
