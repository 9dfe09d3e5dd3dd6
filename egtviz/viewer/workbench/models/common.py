"""Node helpers shared by the 3D drawings: point colours and polylines as line segments."""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from ...render.palette import POINT_COLOURS, hex_to_rgb

_POINT_RGB = np.array([hex_to_rgb(c) for c in POINT_COLOURS], dtype=np.uint8)
EMPTY_SEG = np.zeros((1, 2, 3), np.float32)
EMPTY_PTS = np.zeros((1, 3), np.float32)


@lru_cache(maxsize=16)
def colours(n: int) -> np.ndarray:
    """(n, 3) uint8 colours of points 0..n-1 (read-only)."""
    out = _POINT_RGB[np.arange(n) % len(_POINT_RGB)]
    out.setflags(write=False)
    return out


@lru_cache(maxsize=16)
def pair_colours(n: int) -> np.ndarray:
    """(n, 2, 3) uint8: both ends of a segment of point i in its colour (read-only)."""
    out = np.repeat(colours(n)[:, None, :], 2, axis=1)
    out.setflags(write=False)
    return out


def segments(polylines: np.ndarray, rows: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(N, k, 3) polylines (row i: point i) -> float32 (S, 2, 3) segments without NaN and the (S,) point of each.

    ``rows``: only these points (indices); None: all.
    """
    P = np.asarray(polylines)
    if P.ndim != 3 or P.shape[1] < 2 or P.shape[2] != 3:
        return np.zeros((0, 2, 3), np.float32), np.zeros(0, np.intp)
    if rows is not None:
        if not len(rows):
            return np.zeros((0, 2, 3), np.float32), np.zeros(0, np.intp)
        idx = np.asarray(rows, np.intp)
        P = P[idx]
    else:
        idx = np.arange(len(P))
    if P.shape[1] == 2:  # a polyline of two points is one segment
        ok = np.isfinite(P).all(axis=(1, 2))
        return P[ok].astype(np.float32), idx[ok]
    seg = np.stack([P[:, :-1], P[:, 1:]], axis=2)  # (N, k-1, 2, 3)
    ok = np.isfinite(seg).all(axis=(2, 3))  # (N, k-1)
    point = np.broadcast_to(idx[:, None], ok.shape)[ok]
    return seg[ok].astype(np.float32), point
