r"""Planar mirrors: reflections of points and cameras, and the epipolar geometry they create.

A plane mirror is :math:`\{X : n \cdot X = d\}` with a unit normal :math:`n`
and signed distance :math:`d` of the plane from the world origin (positive
along :math:`n`). The reflection of a point is

.. math:: X' = X - 2 (n \cdot X - d)\, n = (I - 2 n n^T) X + 2 d n,

the homogeneous :math:`D = [I - 2 n n^T,\ 2 d n;\ 0\ 1]`, an involution
(:math:`D^2 = I`) whose linear part has determinant -1.

A camera :math:`H = [R\ t;\ 0\ 1]` looking at the mirror sees the reflected
scene. Equivalently, the *virtual camera* :math:`D H` (a left-handed frame,
:math:`\det(R_v) = -1`) sees the real scene: for every point
:math:`R_v^T (X - t_v) = R^T (D X - t)`, so both give the same pixel with the
same ``K``. The image of a point and the image of its reflection are one
correspondence of a two-view geometry whose epipole is the vanishing point of
the mirror normal, :math:`e = K R^T n`: the segment from :math:`X` to
:math:`X'` is parallel to :math:`n`, so every pair :math:`(m, m')` is
collinear with :math:`e`, and

.. math:: m'^T [e]_\times m = 0 ,

a *skew-symmetric* fundamental matrix (two degrees of freedom). Conventions:
``docs/conventions.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_matrix, as_points, as_scalar, as_vector
from .epipolar import unit_frobenius
from .matrices import hartley_normalization
from .pinhole import PinholeCamera
from .poses import Pose, skew

__all__ = [
    "PlaneMirror",
    "fundamental_from_reflections",
    "mirror_fundamental",
    "reflection_matrix",
    "split_virtual_pose",
]

#: Relative size below which a direction counts as parallel to the mirror.
_PARALLEL_TOL = 1e-12


@dataclass(frozen=True)
class PlaneMirror:
    r"""A plane mirror :math:`n \cdot X = d`."""

    normal: np.ndarray
    """(3,) unit normal (the constructor normalises any non-zero vector)."""
    distance: float = 0.0
    """Signed distance of the plane from the world origin, along ``normal``."""

    if TYPE_CHECKING:
        # The constructor takes any array-like normal; the field holds the checked array.
        def __init__(self, normal: npt.ArrayLike, distance: float = 0.0) -> None: ...

    def __post_init__(self) -> None:
        n = as_vector(self.normal, "normal", 3)
        norm = float(np.linalg.norm(n))
        if not norm > 0.0:
            raise GeometryError("normal: expected a non-zero 3-vector (the mirror's normal)")
        n = n / norm
        n.setflags(write=False)
        object.__setattr__(self, "normal", n)
        object.__setattr__(self, "distance", as_scalar(self.distance, "distance"))

    @property
    def matrix(self) -> np.ndarray:
        r"""The 4x4 reflection :math:`D = [I - 2 n n^T,\ 2 d n;\ 0\ 1]`."""
        D = np.eye(4)
        D[:3, :3] -= 2.0 * np.outer(self.normal, self.normal)
        D[:3, 3] = 2.0 * self.distance * self.normal
        return D

    def reflect_points(self, X: npt.ArrayLike) -> np.ndarray:
        r"""Mirror images :math:`X' = (I - 2 n n^T) X + 2 d n` of (N, 3) points (rows)."""
        P = as_points(X, "X", 3)
        return P - 2.0 * (P @ self.normal - self.distance)[:, None] * self.normal

    def reflect_pose(self, H: npt.ArrayLike) -> np.ndarray:
        r"""The virtual camera :math:`H_v = D H` of a camera pose ``H`` (4x4); its rotation has determinant -1.

        Returned as a matrix, not a :class:`~egtviz.geometry.poses.Pose`: a reflected frame is
        left-handed, which a rigid pose cannot be.
        """
        H = as_matrix(H, "H", (4, 4))
        if not np.allclose(H[3], [0.0, 0.0, 0.0, 1.0]):
            raise GeometryError("H: expected a 4x4 pose [R t; 0 1] with last row (0, 0, 0, 1)")
        return self.matrix @ H

    def mirror_points(self, centre: npt.ArrayLike, X: npt.ArrayLike) -> np.ndarray:
        r"""Where the light from ``X`` to a camera at ``centre`` meets the mirror (N, 3).

        The point lies on the segment from the virtual centre :math:`C_v = D C`
        to :math:`X`: :math:`M = C_v + s (X - C_v)` with
        :math:`s = (d - n \cdot C_v) / (n \cdot (X - C_v))`. NaN where that
        segment is parallel to the mirror.
        """
        C = as_vector(centre, "centre", 3)
        P = as_points(X, "X", 3)
        Cv = self.reflect_points(C)[0]
        v = P - Cv
        den = v @ self.normal
        scale = np.maximum(np.linalg.norm(v, axis=1), 1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(np.abs(den) > _PARALLEL_TOL * scale, (self.distance - Cv @ self.normal) / den, np.nan)
        return Cv + s[:, None] * v


def reflection_matrix(normal: npt.ArrayLike, distance: float = 0.0) -> np.ndarray:
    r"""The 4x4 reflection in the plane :math:`n \cdot X = d`: :math:`D = [I - 2 n n^T,\ 2 d n;\ 0\ 1]`.

    Args:
        normal: (3,) mirror normal; normalised here, so ``d`` is a distance along the unit normal.
        distance: signed distance of the plane from the origin.

    Raises:
        GeometryError: a zero or malformed normal, a non-finite distance.
    """
    return PlaneMirror(normal, distance).matrix


def mirror_fundamental(camera: PinholeCamera, mirror: PlaneMirror) -> np.ndarray:
    r"""The fundamental matrix between a camera's direct and reflected images of the same points.

    .. math:: F = [e]_\times, \qquad e = K R^T n

    (the vanishing point of the mirror normal), so that :math:`m'^T F m = 0`
    for the image :math:`m` of a point and the image :math:`m'` of its
    reflection. Unit Frobenius norm; skew-symmetric.

    Raises:
        GeometryError: ``camera`` is not a :class:`PinholeCamera`.
    """
    if not isinstance(camera, PinholeCamera):
        raise GeometryError(f"camera: expected a PinholeCamera, got {type(camera).__name__}")
    if not isinstance(mirror, PlaneMirror):
        raise GeometryError(f"mirror: expected a PlaneMirror, got {type(mirror).__name__}")
    e = camera.K @ (camera.pose.R.T @ mirror.normal)
    return unit_frobenius(skew(e))


def fundamental_from_reflections(U: npt.ArrayLike, Ur: npt.ArrayLike, *, normalize: bool = True) -> np.ndarray:
    r"""Estimate the skew-symmetric F of a planar mirror from direct and reflected pixels.

    Each pair gives the line :math:`l_i = m_i \times m'_i` through the epipole;
    the epipole is their least-squares intersection, the right singular vector
    of the smallest singular value of :math:`L = [l_1; \dots; l_N]`, and
    :math:`F = [e]_\times` (:math:`m'^T F m = \det(m', e, m) = 0`). With
    ``normalize`` the pixels are first moved to zero mean and mean distance
    :math:`\sqrt 2` (Hartley's normalisation, H&Z Algorithm 11.1; one similarity :math:`T` for both images, since they are
    the same image) and :math:`F = T^T [\hat e]_\times T`.

    Args:
        U: (N, 2) pixels of the points, ``N >= 2``.
        Ur: (N, 2) pixels of their reflections, in the same camera.
        normalize: apply the similarity normalisation first.

    Returns:
        (3, 3) skew-symmetric ``F``, unit Frobenius norm.

    Raises:
        GeometryError: bad shapes, fewer than two pairs, different counts.
        DegenerateConfigurationError: all pairs coincide (no line through the epipole).
    """
    u = as_points(U, "U", 2, min_count=2)
    ur = as_points(Ur, "Ur", 2, min_count=2)
    if len(u) != len(ur):
        raise GeometryError(f"Ur: expected as many points as U ({len(u)}), got {len(ur)}")
    T = np.eye(3)
    if normalize:
        try:
            T = hartley_normalization(np.vstack([u, ur]))[1]
        except DegenerateConfigurationError:
            raise DegenerateConfigurationError("U, Ur: all points coincide") from None
    h = np.column_stack([u, np.ones(len(u))]) @ T.T
    hr = np.column_stack([ur, np.ones(len(ur))]) @ T.T
    L = np.cross(h, hr)
    sv = np.linalg.svd(L, compute_uv=False)
    if sv[1] <= 1e-12 * max(sv[0], 1e-300):
        raise DegenerateConfigurationError("U, Ur: the pairs do not define two distinct lines through an epipole")
    e = np.linalg.svd(L)[2][-1]
    F = T.T @ skew(e) @ T
    # T^T S T is skew for skew S; rounding is not: keep the exact structure.
    return unit_frobenius(0.5 * (F - F.T))


#: Most a 4x4 pose's rotation block may differ from orthonormal.
_ORTHONORMAL_TOL = 1e-6


def split_virtual_pose(H: npt.ArrayLike, name: str = "H") -> tuple[Pose, bool]:
    r"""A camera pose ``H`` as a rigid :class:`Pose` and whether it is a reflected (virtual) camera.

    A virtual camera :math:`H_v = D H` has an orthonormal rotation block with
    :math:`\det R_v = -1`. It equals the rigid pose :math:`R = R_v S`,
    :math:`S = \mathrm{diag}(-1, 1, 1)` (its x axis reversed), followed by the
    pixel reflection :math:`K S K^{-1}`, because :math:`R_v^T = S R^T`.

    Returns:
        ``(pose, flipped)``: the rigid pose (``H`` itself when ``det R = +1``)
        and True when the x axis was reversed.

    Raises:
        GeometryError: ``H`` is not a 4x4 ``[R t; 0 0 0 1]`` with orthonormal ``R``.
    """
    M = as_matrix(H, name, (4, 4))
    if not np.allclose(M[3], [0.0, 0.0, 0.0, 1.0]):
        raise GeometryError(f"{name}: expected a 4x4 pose [R t; 0 1] with last row (0, 0, 0, 1)")
    R = M[:3, :3]
    if np.abs(R.T @ R - np.eye(3)).max() > _ORTHONORMAL_TOL:
        raise GeometryError(f"{name}: expected an orthonormal rotation block (R^T R = I)")
    if np.linalg.det(R) > 0:
        return Pose(R, M[:3, 3]), False
    return Pose(R @ np.diag([-1.0, 1.0, 1.0]), M[:3, 3]), True
