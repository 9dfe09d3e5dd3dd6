"""EGT's scene helpers: planes, point-plane distances, random points, sampled surfaces."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import numpy.typing as npt

from ..geometry._validate import GeometryError, as_count
from ..geometry.planes import plane_normals, point_plane_distance
from ..geometry.shapes import SURFACE_KINDS, SurfaceKind, random_points_in_ball, sample_surface_grid
from ._convert import draw as _draw
from ._convert import flag, world_columns

#: EGT 2.0's ``f_3Dsurface`` object numbers that exist here (its code's numbering: 1 sphere, 2 torus, 6 "cone").
SURFACE_NUMBERS = {1: "sphere", 2: "torus", 6: "cone"}


def f_normplane(X1: npt.ArrayLike, X2: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Unit normal :math:`n = X_1 \times X_2 / |X_1 \times X_2|` of the plane through the origin and ``X1``, ``X2``.

    Args:
        X1, X2: (3, N) vectors, or homogeneous (4, N) points.

    Returns:
        ``(plane, flag)``: (3, N) unit normals (zero columns where the vectors
        are parallel) and (N,) flags, 1 where the plane is defined, else 0.
    """
    n, defined = plane_normals(world_columns(X1, "X1"), world_columns(X2, "X2"))
    return n.T, defined.astype(int)


def f_3Dpointplanedistance(normal: npt.ArrayLike, distance: float, points: npt.ArrayLike) -> np.ndarray:
    r"""Distances :math:`|\hat n \cdot X - d|` of ``points`` (3, N) from the plane :math:`n \cdot X = d`: (N,)."""
    return point_plane_distance(normal, distance, world_columns(points, "points"))


def f_3Drandpoint(
    n: int, center: npt.ArrayLike, radius: float, *, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    """``n`` points (3, n) uniformly distributed inside the ball of ``radius`` around ``center``.

    ``rng``: a ``numpy.random.Generator`` or a seed for reproducible points.
    """
    return random_points_in_ball(n, center, radius, rng).T


def f_3Dsurface(
    ogg: int | str = "sphere",
    R: npt.ArrayLike | None = None,
    t: npt.ArrayLike | None = None,
    param: npt.ArrayLike | None = None,
    n: int = 20,
    *plot: Any,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""Points and unit outward normals of a plane, sphere, cylinder, cone or torus on an ``n x n`` grid.

    Args:
        ogg: ``"plane"``, ``"sphere"``, ``"cylinder"``, ``"cone"``, ``"torus"``, or EGT's
            numbers 1 (sphere), 2 (torus), 6 (cone).
        R, t: rotation and translation placing the surface (identity, origin by default).
        param: the kind's parameters (:data:`~egtviz.geometry.shapes.SURFACE_KINDS`): plane
            ``(width, height)``, sphere ``radius``, cylinder and cone ``(radius, height)``,
            torus ``(major, minor)``; default 1 for each.
        n: grid size.
        *plot: EGT's ``disegna``: a true value draws the surface.

    Returns:
        ``(x, y, z, nx, ny, nz)``, each (n, n), like MATLAB's ``surf`` input and ``surfnorm`` output.
    """
    if isinstance(ogg, str):
        kind = ogg
    else:
        number = as_count(ogg, "ogg", minimum=1, maximum=6)
        if number not in SURFACE_NUMBERS:
            raise GeometryError(
                f"ogg: EGT's object {number} is not available; use one of {sorted(SURFACE_NUMBERS)} "
                f"or a name {sorted(SURFACE_KINDS)}"
            )
        kind = SURFACE_NUMBERS[number]
    if kind not in SURFACE_KINDS:
        raise GeometryError(f"ogg: expected one of {sorted(SURFACE_KINDS)} or {sorted(SURFACE_NUMBERS)}, got {ogg!r}")
    if param is None:
        values: npt.ArrayLike = np.ones(len(SURFACE_KINDS[kind]))
        if kind == "torus":
            values = np.array([1.0, 0.3])
    else:
        values = param
    s = sample_surface_grid(cast(SurfaceKind, kind), values, n, R, t)  # a member of SURFACE_KINDS, checked above
    out = (*np.moveaxis(s.points, -1, 0), *np.moveaxis(s.normals, -1, 0))
    if plot and flag(plot[0]):
        _draw("surface", **dict(zip(("x", "y", "z", "nx", "ny", "nz"), out)))
    return out
