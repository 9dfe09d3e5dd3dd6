"""Homogeneous points and lines in the image plane."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import as_points

#: A homogeneous point whose last coordinate is below this fraction of its norm is at infinity.
AT_INFINITY_TOL = 1e-12


def homogeneous(points: npt.ArrayLike, name: str = "points") -> np.ndarray:
    """(N, 2) pixels -> (N, 3) homogeneous pixels with last coordinate 1."""
    m = as_points(points, name, 2)
    return np.column_stack([m, np.ones(len(m))])


def normalize_homogeneous(v: npt.ArrayLike) -> np.ndarray:
    """Scale homogeneous 3-vectors (3,) or (N, 3): finite -> last coordinate 1, at infinity -> unit norm, w = 0.

    Never divides by zero (see ``docs/conventions.md``).
    """
    a = np.array(v, dtype=np.float64)
    if a.shape == (3,):
        # One vector (epipoles, on every drag): plain floats, the same arithmetic as below.
        x, y, z = a.tolist()
        norm = float(np.linalg.norm(a))
        if abs(z) <= AT_INFINITY_TOL * norm:
            safe = norm if norm > 0 else 1.0
            return np.array([x / safe, y / safe, 0.0])
        return np.array([x / z, y / z, 1.0])
    single = a.ndim == 1
    a = np.atleast_2d(a)
    norm = np.linalg.norm(a, axis=1)
    at_inf = np.abs(a[:, 2]) <= AT_INFINITY_TOL * norm
    out = np.empty_like(a)
    finite = ~at_inf
    out[finite] = a[finite] / a[finite, 2:3]
    safe = np.where(norm[at_inf] > 0, norm[at_inf], 1.0)
    out[at_inf] = a[at_inf] / safe[:, None]
    out[at_inf, 2] = 0.0
    return out[0] if single else out


def is_at_infinity(v: npt.ArrayLike) -> np.ndarray | bool:
    """True where a homogeneous point has (numerically) zero last coordinate."""
    a = np.atleast_2d(np.asarray(v, dtype=np.float64))
    res = np.abs(a[:, 2]) <= AT_INFINITY_TOL * np.linalg.norm(a, axis=1)
    return bool(res[0]) if np.ndim(v) == 1 else res


def normalize_lines(lines: npt.ArrayLike) -> np.ndarray:
    """Scale lines (N, 3) ``(a, b, c)`` to ``a^2 + b^2 = 1`` so that ``l . m`` is a distance in pixels.

    The line at infinity ``(0, 0, c)`` is returned as NaN.
    """
    lines = np.atleast_2d(np.asarray(lines, dtype=np.float64))
    n = np.hypot(lines[:, 0], lines[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        out = lines / n[:, None]
    out[n <= AT_INFINITY_TOL * np.linalg.norm(lines, axis=1)] = np.nan
    return out


def clip_lines_to_rect(lines: npt.ArrayLike, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    r"""Clip infinite lines :math:`a u + b v + c = 0` (N, 3) to the rectangle ``[0, w] x [0, h]``.

    Returns ``(segments (N, 2, 2), hit (N,) bool)``; rows that miss the
    rectangle are NaN. Vectorised: each line is intersected with the four
    border lines and the two extreme points inside the rectangle are kept.
    """
    L = normalize_lines(lines)
    a, b, c = L[:, 0:1], L[:, 1:2], L[:, 2:3]
    eps = 1e-9 * max(width, height, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        xs = np.array([0.0, width])[None, :]
        v_at_x = -(a * xs + c) / b  # crossing u = 0 and u = w
        ys = np.array([0.0, height])[None, :]
        u_at_y = -(b * ys + c) / a  # crossing v = 0 and v = h
    cand_u = np.concatenate([np.broadcast_to(xs, v_at_x.shape), u_at_y], axis=1)
    cand_v = np.concatenate([v_at_x, np.broadcast_to(ys, u_at_y.shape)], axis=1)
    ok = (
        np.isfinite(cand_u) & np.isfinite(cand_v)
        & (cand_u >= -eps) & (cand_u <= width + eps)
        & (cand_v >= -eps) & (cand_v <= height + eps)
    )
    # Parametrise candidates along the line direction (-b, a) and keep the extremes.
    s = np.where(ok, cand_u * -b + cand_v * a, np.nan)
    any_ok = ok.any(axis=1)
    s_fill_lo = np.where(ok, s, np.inf)
    s_fill_hi = np.where(ok, s, -np.inf)
    i_lo = np.argmin(s_fill_lo, axis=1)
    i_hi = np.argmax(s_fill_hi, axis=1)
    rows = np.arange(len(L))
    seg = np.stack(
        [
            np.column_stack([cand_u[rows, i_lo], cand_v[rows, i_lo]]),
            np.column_stack([cand_u[rows, i_hi], cand_v[rows, i_hi]]),
        ],
        axis=1,
    )
    with np.errstate(invalid="ignore"):
        length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
        hit = any_ok & (length > eps)
    seg[~hit] = np.nan
    seg = np.clip(seg, [0.0, 0.0], [width, height])
    return seg, hit
