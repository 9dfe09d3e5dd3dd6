"""EGT's pin-hole functions: placement, projection, epipoles, epipolar lines, images of 3D lines."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt

from ..geometry._validate import GeometryError, as_array, as_up_to_scale, as_vector
from ..geometry.epipolar import epipolar_lines, epipolar_lines_in_first, epipolar_pair, unit_frobenius
from ..geometry.homogeneous import normalize_homogeneous
from ..geometry.lines3d import image_of_line, image_of_plucker_line
from ..geometry.pinhole import PinholeCamera
from ..geometry.poses import Pose
from ._convert import draw as _draw
from ._convert import columns, flag, pinhole, pixels, style, world_columns


def f_Rt2H(R: npt.ArrayLike, t: npt.ArrayLike) -> np.ndarray:
    r"""EGT's pose of a pin-hole camera: :math:`H = [R_x(-\pi/2) R\ t;\ 0\ 1]` (4x4).

    ``R`` turns the camera about its own axes (identity: looking along world +y),
    ``t`` is its centre in world coordinates (3-vector or 3x1).
    """
    return Pose.from_egt(R, t).matrix


def project_pixels(Xw: np.ndarray, H: npt.ArrayLike, K: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
    """(N, 2) pixels of (N, 3) world points (float64 rows, ``world_columns``); a reflected camera's pixels are
    mirrored back. ``H`` and ``K`` are checked; the points too unless ``check=False`` (the caller checked them)."""
    camera, flip = pinhole(H, K)
    px = camera.project(Xw, check=check).pixels
    if flip is not None:
        px = px @ flip[:2, :2].T + flip[:2, 2]
    return px


@lru_cache(maxsize=16)
def _checked_pinhole(h: bytes, k: bytes) -> tuple[PinholeCamera, np.ndarray | None]:
    """:func:`pinhole` of a float64 ``H`` (4x4) and ``K`` (3x3) given by their bytes: the same bytes pass the
    same checks and give the same camera, so a script projecting with one camera again and again (EGT's
    loops, the exercises) checks and builds it once. Refusals are raised, never cached."""
    return pinhole(np.frombuffer(h).reshape(4, 4), np.frombuffer(k).reshape(3, 3))


def _pinhole_of(H: npt.ArrayLike, K: npt.ArrayLike) -> tuple[PinholeCamera, np.ndarray | None]:
    """:func:`pinhole`, through :func:`_checked_pinhole` for float64 arrays of the right shapes."""
    if (type(H) is np.ndarray and type(K) is np.ndarray and H.dtype == np.float64 and K.dtype == np.float64
            and H.shape == (4, 4) and K.shape == (3, 3)):
        return _checked_pinhole(H.tobytes(), K.tobytes())
    return pinhole(H, K)


def f_perspproj(Xw: npt.ArrayLike, H: npt.ArrayLike, K: npt.ArrayLike, *plot: Any) -> np.ndarray:
    r"""Pin-hole projection :math:`m \sim K [R^T | -R^T t] X_w` of world points ``Xw`` (3, N).

    ``H`` may be a reflected (virtual) camera from :func:`f_reflcamera`: its
    pixels are the real camera's pixels of the reflected points.

    Args:
        Xw: (3, N) world points (homogeneous (4, N) accepted).
        H: 4x4 camera pose (:func:`f_Rt2H`).
        K: 3x3 calibration.
        *plot: EGT's ``adjplot``: 1 draws the pixels in the camera's image, 2
            also the rays from the camera centre to the points; further
            arguments are accepted and passed on as the style.

    Returns:
        (2, N) pixels, NaN for a point behind the camera. It unpacks as
        ``u, v = f_perspproj(...)``.
    """
    X = world_columns(Xw, "Xw")
    camera, flip = _pinhole_of(H, K)
    px = camera.project(X, check=False).pixels  # X checked once, by world_columns
    if flip is not None:
        px = px @ flip[:2, :2].T + flip[:2, 2]
    U = px.T
    level = flag(plot[0]) if plot else 0
    if level >= 1:
        _draw("image_points", pixels=U, H=np.asarray(H, dtype=float), K=np.asarray(K, dtype=float), figure=None,
              style=style(plot[1:]))
    if level >= 2:
        _draw("projection_rays", points=X.T, centre=np.asarray(H, float)[:3, 3])
    return U


def f_epipole(
    H1: npt.ArrayLike, H2: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Epipoles and fundamental matrix of two pin-hole cameras.

    Reflected (virtual) cameras are accepted: with the image reflections
    :math:`M_i` of :func:`f_perspproj`, :math:`F = M_2^{-T} F' M_1^{-1}` and
    :math:`e_i = M_i e'_i` for the rigid cameras' :math:`F', e'_i`.

    Returns:
        ``(e1, e2, F)``: ``e1`` the epipole in image 1 (``F e1 = 0``), ``e2``
        in image 2, homogeneous 3-vectors (last coordinate 1, or 0 at
        infinity), and ``F`` with :math:`m_2^T F m_1 = 0`, unit Frobenius norm.
    """
    cam1, M1 = pinhole(H1, K1, "K1", "H1")
    cam2, M2 = pinhole(H2, K2, "K2", "H2")
    pair = epipolar_pair(cam1, cam2)
    if M1 is None and M2 is None:
        return pair.e1, pair.e2, pair.F
    M1 = np.eye(3) if M1 is None else M1
    M2 = np.eye(3) if M2 is None else M2
    # Each M is an involution: M^-1 = M.
    F = unit_frobenius(M2.T @ pair.F @ M1)
    return normalize_homogeneous(M1 @ pair.e1), normalize_homogeneous(M2 @ pair.e2), F


def f_epipline(
    m1: npt.ArrayLike, m2: npt.ArrayLike, F: npt.ArrayLike, *plot: Any
) -> tuple[np.ndarray, np.ndarray]:
    r"""Epipolar lines ``(l1, l2)``, each (3, N): :math:`l_1 = F^T m_2` in image 1, :math:`l_2 = F m_1` in image 2.

    Args:
        m1, m2: (2, N) or homogeneous (3, N) corresponding pixels.
        F: 3x3 fundamental matrix, :math:`m_2^T F m_1 = 0` (any scale).
        *plot: EGT's ``flag, figa, figd, car``: a true ``flag`` draws the lines
            from each point to its image's epipole, in figures ``figa`` and
            ``figd``, with the MATLAB style ``car`` (e.g. ``'b:'``).

    Returns:
        ``(l1, l2)`` in the scale of the ``F`` given, as EGT returns them (``F`` is divided by its
        largest entry for the arithmetic and the lines multiplied back).
    """
    Fn = as_up_to_scale(F, "F", (3, 3))
    top = float(np.abs(np.asarray(F, dtype=np.float64)).max())  # finite and non-zero: checked above
    p1, p2 = pixels(m1, "m1"), pixels(m2, "m2")
    if len(p1) != len(p2):
        raise GeometryError(f"m2: expected as many points as m1 ({len(p1)}), got {len(p2)}")
    with np.errstate(over="ignore"):  # beyond the float range EGT's product overflows to inf too
        l1, l2 = epipolar_lines_in_first(Fn, p2).T * top, epipolar_lines(Fn, p1).T * top
    if plot and flag(plot[0]):
        figs = [p if isinstance(p, (int, np.integer)) and not isinstance(p, bool) else None for p in plot[1:3]]
        figs += [None] * (2 - len(figs))
        line_style = style(plot[1:])
        U, S, Vt = np.linalg.svd(Fn)
        e1, e2 = normalize_homogeneous(Vt[-1]), normalize_homogeneous(U[:, -1])
        _draw("epipolar_lines", lines=l1, points=p1.T, epipole=e1, figure=figs[0], style=line_style)
        _draw("epipolar_lines", lines=l2, points=p2.T, epipole=e2, figure=figs[1], style=line_style)
    return l1, l2


def f_perspline(U: npt.ArrayLike, H: npt.ArrayLike, K: npt.ArrayLike, *plot: Any) -> np.ndarray:
    r"""Image of a 3D line: :math:`l \sim K^{-T} R^T \big((X_1 - C) \times (X_2 - C)\big)`, a 3-vector.

    Args:
        U: (3, 2) two world points of the line, or a 6-vector of Plücker
            coordinates ``(d, m)`` in the camera frame (:math:`l \sim K^{-T} m`).
        H, K: the camera (:func:`f_Rt2H`), calibration.
        *plot: EGT's ``adjplot, fig``: a true ``adjplot`` draws the 3D segment.

    Returns:
        The line ``(a, b, c)``, :math:`a u + b v + c = 0`, scaled to
        :math:`a^2 + b^2 = 1`. (EGT returned ``[ell, Xh1m, Xh2m]``, the line and
        two plotting points; the plotting points are not returned.)
    """
    camera, flip = pinhole(H, K)
    arr = as_array(U, "U", allow_empty=False)
    if arr.size == 6 and arr.shape in ((6,), (6, 1)):
        line = image_of_plucker_line(camera, arr.reshape(6))
    else:
        P = columns(arr, "U", 3)
        if len(P) != 2:
            raise GeometryError(f"U: expected two points, shape (3, 2), or a Plücker 6-vector, got {arr.shape}")
        line = image_of_line(camera, as_vector(P[0], "U", 3), as_vector(P[1], "U", 3))
        if plot and flag(plot[0]):
            _draw("line3d", points=P.T, style=style(plot[1:]))
    if flip is not None:
        line = flip.T @ line  # a line maps by M^-T, and M^-1 = M
        line = line / np.hypot(line[0], line[1])
    return line
