r"""Epipolar geometry of a pin-hole pair (EGT reference, section 4; Hartley & Zisserman 9.2-9.6).

With :math:`R = R_2^T R_1` and :math:`t = R_2^T (t_1 - t_2)` (camera-1 frame to
camera-2 frame), :math:`E = [t]_\times R`, :math:`F = K_2^{-T} E K_1^{-1}` and
:math:`m_2^T F m_1 = 0`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ._validate import (
    DegenerateConfigurationError,
    GeometryError,
    as_calibration,
    as_points,
    as_up_to_scale,
    as_up_to_scale_rows,
    as_vector,
)
from ._shared import (
    COINCIDENT_CENTRES_TOL,
    centres_coincide,
    epipolar_normals_columns,
    inverse_calibration,
    normalize_homogeneous3,
    skew3,
)
from .homogeneous import clip_lines_to_rect, homogeneous, normalize_homogeneous
from .pinhole import PinholeCamera
from .poses import Pose

__all__ = [
    "COINCIDENT_CENTRES_TOL",
    "EpipolarPair",
    "check_distinct_centres",
    "clipped_epipolar_lines",
    "epipolar_constraint",
    "epipolar_lines",
    "epipolar_lines_in_first",
    "epipolar_pair",
    "epipolar_planes",
    "epipole_of_centre",
    "epipoles_from_fundamental",
    "essential_from_fundamental",
    "essential_from_poses",
    "fundamental_from_cameras",
    "fundamental_from_essential",
    "lines_of_planes",
    "relative_pose",
    "unit_frobenius",
]

def _check_pose(pose: object, name: str) -> Pose:
    if not isinstance(pose, Pose):
        raise GeometryError(f"{name}: expected a Pose, got {type(pose).__name__}")
    return pose


def _check_pinhole(camera: object, name: str) -> PinholeCamera:
    if not isinstance(camera, PinholeCamera):
        raise GeometryError(f"{name}: expected a PinholeCamera, got {type(camera).__name__}")
    return camera


def relative_pose(pose1: Pose, pose2: Pose) -> tuple[np.ndarray, np.ndarray]:
    r"""``(R, t)`` from frame 1 to frame 2: :math:`X_2 = R X_1 + t`, :math:`R = R_2^T R_1`, :math:`t = R_2^T (t_1 - t_2)`."""
    _check_pose(pose1, "pose1")
    _check_pose(pose2, "pose2")
    R = pose2.R.T @ pose1.R
    t = pose2.R.T @ (pose1.t - pose2.t)
    return R, t


def check_distinct_centres(c1: np.ndarray, c2: np.ndarray) -> None:
    """Raise :class:`DegenerateConfigurationError` when two centres (3-vectors) coincide."""
    if centres_coincide(as_vector(c1, "c1", 3), as_vector(c2, "c2", 3)):
        raise DegenerateConfigurationError("no epipolar geometry: the centres coincide")


def unit_frobenius(M: npt.ArrayLike) -> np.ndarray:
    r"""Scale a 3x3 matrix to unit Frobenius norm with its largest-magnitude entry positive (a canonical sign).

    .. math:: M \mapsto \operatorname{sign}(M_k)\, M / \|M\|_F, \qquad k = \arg\max |M_{ij}|.

    ``M`` (F, E, ...) is defined up to scale: it is divided by its largest absolute entry first, so any
    finite magnitude gives the same result.

    Raises:
        GeometryError: ``M`` is not a finite 3x3 matrix, or is zero.
    """
    return _unit_frobenius(as_up_to_scale(M, "M", (3, 3)))


def _unit_frobenius(M: np.ndarray) -> np.ndarray:
    """:func:`unit_frobenius` of a checked float matrix of moderate scale."""
    M = M / _frobenius(M)
    k = np.argmax(np.abs(M))
    return M if M.flat[k] >= 0 else -M


def _frobenius(M: np.ndarray) -> float:
    """``np.linalg.norm(M)`` (the same arithmetic, ``sqrt(x . x)``) without its wrapper."""
    x = M.ravel()
    return math.sqrt(x.dot(x))


def essential_from_poses(pose1: Pose, pose2: Pose, *, check: bool = True) -> np.ndarray:
    r""":math:`E = [t]_\times R` with ``(R, t)`` from :func:`relative_pose`, unit Frobenius norm.

    Args:
        pose1, pose2: the two frames.
        check: check the arguments (default). ``check=False``: the caller promises two :class:`Pose` objects
            (checked when they were made); coincident centres still raise.

    Raises:
        DegenerateConfigurationError: the two centres coincide.
    """
    if check:
        _check_pose(pose1, "pose1")
        _check_pose(pose2, "pose2")
        check_distinct_centres(pose1.t, pose2.t)
    elif centres_coincide(pose1.t, pose2.t):
        raise DegenerateConfigurationError("no epipolar geometry: the centres coincide")
    return _essential(pose1, pose2)


def _essential(pose1: Pose, pose2: Pose) -> np.ndarray:
    """:func:`essential_from_poses` of poses whose centres are known to be distinct."""
    R, t = relative_pose(pose1, pose2)
    return _unit_frobenius(skew3(*t.tolist()) @ R)


def essential_from_fundamental(F: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike) -> np.ndarray:
    r"""Essential matrix from ``F`` and the calibrations (H&Z 2nd ed., eq. 9.12).

    .. math:: E = K_2^T F K_1

    Returned with unit Frobenius norm (positive rescaling only: the sign of
    ``F`` is kept).

    Args:
        F: ``(3, 3)`` fundamental matrix, ``m2^T F m1 = 0``.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.
    """
    F = as_up_to_scale(F, "F", (3, 3))
    E = as_calibration(K2, "K2").T @ F @ as_calibration(K1, "K1")
    n = np.linalg.norm(E)
    if not n > 0:
        raise GeometryError("F: expected a nonzero matrix")
    return E / n


def fundamental_from_essential(E: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike, *,
                               check: bool = True) -> np.ndarray:
    r"""Fundamental matrix from ``E`` and the calibrations (H&Z 2nd ed., eq. 9.12).

    .. math:: F = K_2^{-T} E K_1^{-1}

    Returned with unit Frobenius norm (positive rescaling only).

    Args:
        E: ``(3, 3)`` essential matrix, ``x2^T E x1 = 0`` in normalised coordinates.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.
        check: check the arguments (default). ``check=False`` (a drag, with the cameras' matrices): the caller
            promises ``E`` a finite, non-zero float64 (3, 3) array and ``K1``, ``K2`` float64 (3, 3) calibration
            matrices (upper triangular, ``K[2, 2] = 1``, invertible); the arithmetic is the checked call's, and
            anything else gives an undefined result.
    """
    E = as_up_to_scale(E, "E", (3, 3)) if check else E / np.abs(E).max()
    F = inverse_calibration(K2, "K2").T @ E @ inverse_calibration(K1, "K1")
    F = F / np.abs(F).max()  # K^-1 may be small (1e-3 per entry): keep the norm's squares in range
    n = _frobenius(F)  # np.linalg.norm(F)'s arithmetic
    if not n > 0:
        raise GeometryError("E: expected a nonzero matrix")
    return F / n


@dataclass(frozen=True, eq=False)
class EpipolarPair:
    """Everything about the epipolar geometry of two pin-hole cameras."""

    E: np.ndarray
    """(3, 3) essential matrix, unit Frobenius norm."""
    F: np.ndarray
    """(3, 3) fundamental matrix, ``m2^T F m1 = 0``, unit Frobenius norm."""
    e1: np.ndarray
    """(3,) epipole in image 1 (image of centre 2), ``F e1 = 0``; see ``normalize_homogeneous``."""
    e2: np.ndarray
    """(3,) epipole in image 2 (image of centre 1), ``F^T e2 = 0``."""
    e1_at_infinity: bool
    e2_at_infinity: bool
    e1_in_front: bool
    """Centre 2 is in front of camera 1 (its image is a real projection, not a back-projection)."""
    e2_in_front: bool


def epipolar_pair(cam1: PinholeCamera, cam2: PinholeCamera) -> EpipolarPair:
    r"""E, F and both epipoles of two pin-hole cameras.

    The epipoles are computed as images of the other centre,
    :math:`e_1 \sim K_1 R_1^T (t_2 - t_1)`, which is exact and handles the
    epipole at infinity (baseline parallel to the image plane) without a division.

    With :math:`b = t_1 - t_2`, so that :math:`t = R_2^T b` and :math:`[R_2^T b]_\times = R_2^T [b]_\times R_2`,

    .. math:: E = [t]_\times R_2^T R_1 = R_2^T [b]_\times R_1, \qquad
        F \sim K_2^{-T} E K_1^{-1} = (R_2 K_2^{-1})^T [b]_\times (R_1 K_1^{-1}),

    both one stacked product of per-camera matrices (this runs on every drag of a
    pin-hole pair), each scaled to unit Frobenius norm with the canonical sign of
    :func:`unit_frobenius`.

    Raises:
        DegenerateConfigurationError: the two centres coincide.
    """
    _check_pinhole(cam1, "cam1")
    _check_pinhole(cam2, "cam2")
    c1, c2 = cam1.center, cam2.center
    if centres_coincide(c1, c2):
        raise DegenerateConfigurationError("no epipolar geometry: the centres coincide")
    b = c1 - c2
    EF = np.matmul(cam2.ray_frames.transpose(0, 2, 1) @ skew3(*b.tolist()), cam1.ray_frames)  # (E, F) unscaled
    flat = EF.reshape(2, 9)
    norm = np.sqrt(np.einsum("ij,ij->i", flat, flat))
    largest = flat[(0, 1), np.abs(flat).argmax(axis=1)]
    flat *= np.copysign(1.0 / norm, largest)[:, None]
    (x1, y1, z1), (x2, y2, z2) = (cam1.K_Rt @ b).tolist(), (cam2.K_Rt @ b).tolist()
    e1, e2 = normalize_homogeneous3(-x1, -y1, -z1), normalize_homogeneous3(x2, y2, z2)  # K R^T (c' - c)
    return EpipolarPair(
        E=EF[0],
        F=EF[1],
        e1=e1,
        e2=e2,
        e1_at_infinity=bool(e1[2] == 0.0),
        e2_at_infinity=bool(e2[2] == 0.0),
        e1_in_front=-z1 > 0,
        e2_in_front=z2 > 0,
    )


def _epipole_of_centre(camera: PinholeCamera, other_centre: np.ndarray) -> tuple[np.ndarray, bool]:
    """:func:`epipole_of_centre` of a checked (3,) centre known to differ from the camera's."""
    x, y, z = (camera.K_Rt @ (other_centre - camera.center)).tolist()
    return normalize_homogeneous3(x, y, z), z > 0


def epipole_of_centre(camera: PinholeCamera, other_centre: npt.ArrayLike) -> tuple[np.ndarray, bool]:
    r"""Image of another camera's centre: :math:`e \sim K R^T (c' - t)`, as a homogeneous 3-vector.

    Returns ``(e, in_front)``; ``e`` follows ``normalize_homogeneous`` (at
    infinity when the baseline is parallel to the image plane), ``in_front`` is
    False when the other centre is behind the camera.
    """
    _check_pinhole(camera, "camera")
    c = as_vector(other_centre, "other_centre", 3)
    check_distinct_centres(camera.center, c)
    return _epipole_of_centre(camera, c)


def lines_of_planes(camera: PinholeCamera, normals_world: npt.ArrayLike) -> np.ndarray:
    r"""Image lines (N, 3) of planes through the camera centre with world normals (N, 3).

    A plane :math:`n \cdot (X - t) = 0` through the centre images to
    :math:`l = K^{-T} R^T n`. For the epipolar plane of a point this is its
    epipolar line (equal to :math:`F m` up to scale), defined whether or not the
    point itself is visible. A normal is defined up to scale (each is first divided by its largest
    entry); the planes of points without one (NaN rows of :func:`epipolar_planes`) must be left out.

    Raises:
        GeometryError: a normal is zero, NaN or inf, or ``normals_world`` is not (N, 3).
    """
    _check_pinhole(camera, "camera")
    n = as_up_to_scale_rows(normals_world, "normals_world", 3)
    return n @ camera.plane_to_line.T


def fundamental_from_cameras(cam1: PinholeCamera, cam2: PinholeCamera) -> np.ndarray:
    """F of two pin-hole cameras (``m2^T F m1 = 0``)."""
    return epipolar_pair(cam1, cam2).F


def epipoles_from_fundamental(F: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Right and left null vectors of F: ``(e1, e2)`` with :math:`F e_1 = 0`, :math:`F^T e_2 = 0` (H&Z 9.2.4)."""
    F = as_up_to_scale(F, "F", (3, 3))
    U, _, Vt = np.linalg.svd(F)
    return normalize_homogeneous(Vt[2]), normalize_homogeneous(U[:, 2])


def epipolar_lines(F: npt.ArrayLike, m1: npt.ArrayLike) -> np.ndarray:
    r"""Lines in image 2 of points of image 1: :math:`l_2 = F m_1`, (N, 3) from (N, 2) pixels.

    ``F`` is defined up to scale: it is divided by its largest absolute entry first (the lines are those of
    that ``F``, whatever the magnitude given).
    """
    F = as_up_to_scale(F, "F", (3, 3))
    return homogeneous(m1, "m1") @ F.T


def epipolar_lines_in_first(F: npt.ArrayLike, m2: npt.ArrayLike) -> np.ndarray:
    r"""Lines in image 1 of points of image 2: :math:`l_1 = F^T m_2`, (N, 3) from (N, 2) pixels.

    ``F`` is divided by its largest absolute entry first, as in :func:`epipolar_lines`.
    """
    F = as_up_to_scale(F, "F", (3, 3))
    return homogeneous(m2, "m2") @ F


def epipolar_constraint(F: npt.ArrayLike, m1: npt.ArrayLike, m2: npt.ArrayLike) -> np.ndarray:
    r"""Algebraic residuals :math:`m_2^T F m_1`, (N,), of ``F`` divided by its largest absolute entry."""
    F = as_up_to_scale(F, "F", (3, 3))
    h1, h2 = homogeneous(m1, "m1"), homogeneous(m2, "m2")
    if len(h1) != len(h2):
        raise GeometryError(f"m2: expected as many points as m1 ({len(h1)}), got {len(h2)}")
    return np.einsum("ni,ij,nj->n", h2, F, h1)


def epipolar_planes(c1: npt.ArrayLike, c2: npt.ArrayLike, X_world: npt.ArrayLike) -> np.ndarray:
    r"""Planes (N, 4) ``(n, d)`` with :math:`n \cdot X + d = 0` through both centres and each point.

    :math:`n = (c_2 - c_1) \times (X - c_1)`, unit norm. Points on the baseline
    give a NaN row (every plane through the baseline contains them).
    """
    c1 = as_vector(c1, "c1", 3)
    c2 = as_vector(c2, "c2", 3)
    check_distinct_centres(c1, c2)
    X = as_points(X_world, "X_world", 3)
    n = epipolar_normals_columns(c1, c2, X.T).T
    return np.column_stack([n, -n @ c1])


def clipped_epipolar_lines(lines: npt.ArrayLike, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Clip (N, 3) epipolar lines to an image for drawing: ``(segments (N, 2, 2), hit (N,))``."""
    return clip_lines_to_rect(lines, width, height)
