"""EGT 2.0's planar-mirror functions: reflections of points and cameras, their images, their F."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ..geometry._validate import GeometryError, as_count, as_scalar, as_vector
from ..geometry.planar_mirror import PlaneMirror, fundamental_from_reflections
from ._convert import draw as _draw
from ._convert import flag, pixels, style, world_columns
from ._pinhole import project_pixels


def f_reflmatrix(normal: npt.ArrayLike, distance: float) -> np.ndarray:
    r"""The 4x4 reflection in the plane :math:`n \cdot X = d`: :math:`D = [I - 2 n n^T,\ 2 d n;\ 0\ 1]`.

    ``normal`` is normalised first, so ``distance`` is the plane's signed
    distance from the origin along the unit normal.
    """
    return PlaneMirror(normal, distance).matrix


def f_reflpoint(normal: npt.ArrayLike, distance: float, points: npt.ArrayLike, *plot: Any) -> np.ndarray:
    r"""Mirror images :math:`X' = (I - 2 n n^T) X + 2 d n` of the points ``points`` (3, N): (3, N).

    ``*plot``: EGT's ``plot_flag, color``; a true flag draws the reflected points.
    """
    out = PlaneMirror(normal, distance).reflect_points(world_columns(points, "points")).T
    if plot and flag(plot[0]):
        _draw("scene_points", points=out, style=style(plot[1:]) or "r*")
    return out


def f_reflcamera(normal: npt.ArrayLike, distance: float, H: npt.ArrayLike, *plot: Any) -> np.ndarray:
    r"""The virtual camera :math:`H_v = D H` of the camera ``H`` in the mirror (4x4; :math:`\det R_v = -1`).

    :func:`f_perspproj` and :func:`f_epipole` accept it: it images the real
    scene as the real camera images the reflected scene.

    ``*plot``: EGT's ``plot, color, length, scale, title``; a true ``plot`` draws the camera.
    """
    Hv = PlaneMirror(normal, distance).reflect_pose(H)
    if plot and flag(plot[0]):
        _colour, length, scale, title = (list(plot[1:5]) + [None] * 4)[:4]
        _draw(
            "camera", H=Hv, style=style(plot[1:2]), frame_length=_number(length), scale=_number(scale),
            title=title if isinstance(title, str) else None,
        )
    return Hv


def _number(value: Any) -> float | None:
    """A finite plotting number, or None for anything else."""
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) and np.isfinite(value):
        return float(value)
    return None


def _inside(values: np.ndarray, margin: npt.ArrayLike | None, precision: float, name: str) -> np.ndarray:
    if margin is None:
        return np.ones(len(values), dtype=bool)
    lo, hi = as_vector(margin, name, 2)
    return (values >= lo - precision) & (values < hi + precision)


def f_reflpersproj(
    normal: npt.ArrayLike,
    distance: float,
    H: npt.ArrayLike,
    K: npt.ArrayLike,
    points: npt.ArrayLike,
    precision: float = 1e-4,
    marginX: npt.ArrayLike | None = None,
    marginY: npt.ArrayLike | None = None,
    marginZ: npt.ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""What a camera sees of ``points`` (3, N) in a plane mirror: pixels and mirror points.

    The pixel is the real camera's image of the reflected point,
    :math:`m \sim K R^T (D X - t)`; the mirror point is where the ray from the
    virtual centre :math:`D C` to :math:`X` crosses the plane. Column ``i``
    belongs to point ``i`` (EGT's label structs are not needed).

    Args:
        normal, distance: the mirror plane :math:`n \cdot X = d`.
        H, K: the real camera (:func:`f_Rt2H`) and its calibration.
        points: (3, N) world points.
        precision: tolerance on the margins.
        marginX, marginY, marginZ: optional ``(min, max)`` extents of the
            mirror in world coordinates; points reflected outside them are not seen.

    Returns:
        ``(pixels, mirror_points)``: (2, N) and (3, N); NaN columns for points
        that are not seen: on the other side of the mirror from the camera,
        reflected outside the margins, or whose reflection is behind the camera.
    """
    mirror = PlaneMirror(normal, distance)
    X = world_columns(points, "points")
    tol = as_scalar(precision, "precision")
    U = project_pixels(mirror.reflect_points(X), H, K)  # checks H and K
    centre = np.asarray(H, dtype=np.float64)[:3, 3]
    M = mirror.mirror_points(centre, X)
    same_side = (X @ mirror.normal - mirror.distance) * (centre @ mirror.normal - mirror.distance) > 0.0
    seen = same_side & ~np.isnan(M[:, 0]) & ~np.isnan(U[:, 0])
    for axis, (margin, name) in enumerate(((marginX, "marginX"), (marginY, "marginY"), (marginZ, "marginZ"))):
        seen &= _inside(np.nan_to_num(M[:, axis]), margin, tol, name)
    U[~seen] = np.nan
    M[~seen] = np.nan
    return U.T, M.T


def f_reflFestim(U: npt.ArrayLike, Ur: npt.ArrayLike, algorithm: int = 2, *unused: Any) -> np.ndarray:
    r"""F of a planar mirror from pixels ``U`` (2, N) and the pixels ``Ur`` (2, N) of the reflections.

    The skew-symmetric :math:`F = [e]_\times`, :math:`e` the vanishing point
    of the mirror normal, :math:`u_r^T F u = 0`; two or more pairs.
    ``algorithm``: 1 on raw pixels, 2 (default) after Hartley's normalisation.
    Further EGT arguments are accepted and have no effect.
    """
    kind = as_count(algorithm, "algorithm", minimum=1, maximum=2)
    p, pr = pixels(U, "U"), pixels(Ur, "Ur")
    if len(p) != len(pr):
        raise GeometryError(f"Ur: expected as many points as U ({len(p)}), got {len(pr)}")
    return fundamental_from_reflections(p, pr, normalize=kind == 2)
