r"""Epipolar geometry of a pin-hole pair (EGT reference, section 4; Hartley & Zisserman 9.2-9.6).

With :math:`R = R_2^T R_1` and :math:`t = R_2^T (t_1 - t_2)` (camera-1 frame to
camera-2 frame), :math:`E = [t]_\times R`, :math:`F = K_2^{-T} E K_1^{-1}` and
:math:`m_2^T F m_1 = 0`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_calibration, as_matrix, as_points
from .homogeneous import clip_lines_to_rect, homogeneous, normalize_homogeneous
from .pinhole import PinholeCamera
from .poses import Pose, skew

#: Two centres closer than this (relative to the scene scale 1) have no epipolar geometry.
COINCIDENT_CENTRES_TOL = 1e-9


def relative_pose(pose1: Pose, pose2: Pose) -> tuple[np.ndarray, np.ndarray]:
    r"""``(R, t)`` from frame 1 to frame 2: :math:`X_2 = R X_1 + t`, :math:`R = R_2^T R_1`, :math:`t = R_2^T (t_1 - t_2)`."""
    R = pose2.R.T @ pose1.R
    t = pose2.R.T @ (pose1.t - pose2.t)
    return R, t


def check_distinct_centres(c1: np.ndarray, c2: np.ndarray) -> None:
    """Raise :class:`DegenerateConfigurationError` when two centres coincide."""
    scale = max(1.0, float(np.linalg.norm(c1)), float(np.linalg.norm(c2)))
    if np.linalg.norm(np.asarray(c1) - np.asarray(c2)) <= COINCIDENT_CENTRES_TOL * scale:
        raise DegenerateConfigurationError("no epipolar geometry: the centres coincide")


def unit_frobenius(M: np.ndarray) -> np.ndarray:
    """Scale a matrix to unit Frobenius norm with its largest-magnitude entry positive (a canonical sign)."""
    M = M / np.linalg.norm(M)
    k = np.argmax(np.abs(M))
    return M if M.flat[k] >= 0 else -M


def essential_from_poses(pose1: Pose, pose2: Pose) -> np.ndarray:
    r""":math:`E = [t]_\times R` with ``(R, t)`` from :func:`relative_pose`, unit Frobenius norm."""
    check_distinct_centres(pose1.t, pose2.t)
    R, t = relative_pose(pose1, pose2)
    return unit_frobenius(skew(t) @ R)


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
    F = as_matrix(F, "F", (3, 3))
    E = as_calibration(K2, "K2").T @ F @ as_calibration(K1, "K1")
    n = np.linalg.norm(E)
    if n == 0:
        raise GeometryError("F: expected a nonzero matrix")
    return E / n


def fundamental_from_essential(E: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike) -> np.ndarray:
    r"""Fundamental matrix from ``E`` and the calibrations (H&Z 2nd ed., eq. 9.12).

    .. math:: F = K_2^{-T} E K_1^{-1}

    Returned with unit Frobenius norm (positive rescaling only).

    Args:
        E: ``(3, 3)`` essential matrix, ``x2^T E x1 = 0`` in normalised coordinates.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.
    """
    E = as_matrix(E, "E", (3, 3))
    F = _inverse_calibration(K2, "K2").T @ E @ _inverse_calibration(K1, "K1")
    n = np.linalg.norm(F)
    if n == 0:
        raise GeometryError("E: expected a nonzero matrix")
    return F / n


def _inverse_calibration(K: npt.ArrayLike, name: str) -> np.ndarray:
    """``inv(as_calibration(K))``, remembered per matrix (a camera drag keeps both calibrations)."""
    arr = np.ascontiguousarray(K, dtype=np.float64)
    if arr.shape != (3, 3):
        as_calibration(arr, name)  # raises with the shape in the message
    return _inverse_of(arr.tobytes(), name)


@lru_cache(maxsize=64)
def _inverse_of(K_bytes: bytes, name: str) -> np.ndarray:
    inv = np.linalg.inv(as_calibration(np.frombuffer(K_bytes).reshape(3, 3), name))
    inv.setflags(write=False)
    return inv


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

    Raises:
        DegenerateConfigurationError: the two centres coincide.
    """
    check_distinct_centres(cam1.center, cam2.center)
    E = essential_from_poses(cam1.pose, cam2.pose)
    F = unit_frobenius(fundamental_from_essential(E, cam1.K, cam2.K))
    e1, e1_in_front = epipole_of_centre(cam1, cam2.center)
    e2, e2_in_front = epipole_of_centre(cam2, cam1.center)
    return EpipolarPair(
        E=E,
        F=F,
        e1=e1,
        e2=e2,
        e1_at_infinity=bool(e1[2] == 0.0),
        e2_at_infinity=bool(e2[2] == 0.0),
        e1_in_front=e1_in_front,
        e2_in_front=e2_in_front,
    )


def epipole_of_centre(camera: PinholeCamera, other_centre: npt.ArrayLike) -> tuple[np.ndarray, bool]:
    r"""Image of another camera's centre: :math:`e \sim K R^T (c' - t)`, as a homogeneous 3-vector.

    Returns ``(e, in_front)``; ``e`` follows ``normalize_homogeneous`` (at
    infinity when the baseline is parallel to the image plane), ``in_front`` is
    False when the other centre is behind the camera.
    """
    c = as_points(other_centre, "other_centre", 3)[0]
    check_distinct_centres(camera.center, c)
    raw = camera.K @ camera.pose.R.T @ (c - camera.center)
    return normalize_homogeneous(raw), bool(raw[2] > 0)


def lines_of_planes(camera: PinholeCamera, normals_world: npt.ArrayLike) -> np.ndarray:
    r"""Image lines (N, 3) of planes through the camera centre with world normals (N, 3).

    A plane :math:`n \cdot (X - t) = 0` through the centre images to
    :math:`l = K^{-T} R^T n`. For the epipolar plane of a point this is its
    epipolar line (equal to :math:`F m` up to scale), defined whether or not the
    point itself is visible. NaN normals give NaN lines.
    """
    n = np.atleast_2d(np.asarray(normals_world, dtype=np.float64))
    return np.linalg.solve(camera.K.T, camera.pose.R.T @ n.T).T


def fundamental_from_cameras(cam1: PinholeCamera, cam2: PinholeCamera) -> np.ndarray:
    """F of two pin-hole cameras (``m2^T F m1 = 0``)."""
    return epipolar_pair(cam1, cam2).F


def epipoles_from_fundamental(F: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Right and left null vectors of F: ``(e1, e2)`` with :math:`F e_1 = 0`, :math:`F^T e_2 = 0` (H&Z 9.2.4)."""
    F = as_matrix(F, "F", (3, 3))
    U, _, Vt = np.linalg.svd(F)
    return normalize_homogeneous(Vt[2]), normalize_homogeneous(U[:, 2])


def epipolar_lines(F: npt.ArrayLike, m1: npt.ArrayLike) -> np.ndarray:
    r"""Lines in image 2 of points of image 1: :math:`l_2 = F m_1`, (N, 3) from (N, 2) pixels."""
    F = as_matrix(F, "F", (3, 3))
    return homogeneous(m1, "m1") @ F.T


def epipolar_lines_in_first(F: npt.ArrayLike, m2: npt.ArrayLike) -> np.ndarray:
    r"""Lines in image 1 of points of image 2: :math:`l_1 = F^T m_2`, (N, 3) from (N, 2) pixels."""
    F = as_matrix(F, "F", (3, 3))
    return homogeneous(m2, "m2") @ F


def epipolar_constraint(F: npt.ArrayLike, m1: npt.ArrayLike, m2: npt.ArrayLike) -> np.ndarray:
    r"""Algebraic residuals :math:`m_2^T F m_1`, (N,)."""
    F = as_matrix(F, "F", (3, 3))
    h1, h2 = homogeneous(m1, "m1"), homogeneous(m2, "m2")
    if len(h1) != len(h2):
        raise GeometryError(f"m2: expected as many points as m1 ({len(h1)}), got {len(h2)}")
    return np.einsum("ni,ij,nj->n", h2, F, h1)


def epipolar_planes(c1: npt.ArrayLike, c2: npt.ArrayLike, X_world: npt.ArrayLike) -> np.ndarray:
    r"""Planes (N, 4) ``(n, d)`` with :math:`n \cdot X + d = 0` through both centres and each point.

    :math:`n = (c_2 - c_1) \times (X - c_1)`, unit norm. Points on the baseline
    give a NaN row (every plane through the baseline contains them).
    """
    c1 = as_points(c1, "c1", 3)[0]
    c2 = as_points(c2, "c2", 3)[0]
    check_distinct_centres(c1, c2)
    X = as_points(X_world, "X_world", 3)
    n = np.cross(c2 - c1, X - c1)
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    scale = np.linalg.norm(c2 - c1) * np.maximum(np.linalg.norm(X - c1, axis=1, keepdims=True), 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = np.where(norm > 1e-12 * scale, n / norm, np.nan)
    d = -n @ c1
    return np.column_stack([n, d])


def clipped_epipolar_lines(lines: npt.ArrayLike, width: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Clip (N, 3) epipolar lines to an image for drawing: ``(segments (N, 2, 2), hit (N,))``."""
    return clip_lines_to_rect(lines, width, height)
