r"""Rotations and rigid poses.

A pose is :math:`H = [R\ t;\ 0\ 1]`: ``t`` is the frame's origin (camera centre,
mirror focus) in world coordinates and the columns of ``R`` are the frame's axes
in world coordinates, so a world point maps into the frame as
:math:`X_c = R^T (X_w - t)` (EGT reference, section 1).
"""

from __future__ import annotations

import math
from dataclasses import InitVar, dataclass, field
from typing import TYPE_CHECKING, cast

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from ._shared import cached_value
from ._validate import GeometryError, as_matrix, as_points, as_rotation, as_scalar, as_vector

__all__ = [
    "EGT_CAMERA_BASE",
    "Pose",
    "egt_rotation_from_ypr",
    "look_at",
    "matrix_from_quat_wxyz",
    "quat_wxyz_from_matrix",
    "rotx",
    "roty",
    "rotz",
    "skew",
    "ypr_from_egt_rotation",
]


def rotx(angle: float) -> np.ndarray:
    r"""Right-handed rotation about x by ``angle`` radians (EGT ``rotox``).

    .. math:: R_x(a) = \begin{bmatrix}1&0&0\\0&\cos a&-\sin a\\0&\sin a&\cos a\end{bmatrix}
    """
    c, s = _cos_sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def roty(angle: float) -> np.ndarray:
    r"""Right-handed rotation about y by ``angle`` radians (EGT ``rotoy``).

    .. math:: R_y(a) = \begin{bmatrix}\cos a&0&\sin a\\0&1&0\\-\sin a&0&\cos a\end{bmatrix}
    """
    c, s = _cos_sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rotz(angle: float) -> np.ndarray:
    r"""Right-handed rotation about z by ``angle`` radians (EGT ``rotoz``).

    .. math:: R_z(a) = \begin{bmatrix}\cos a&-\sin a&0\\\sin a&\cos a&0\\0&0&1\end{bmatrix}
    """
    c, s = _cos_sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _cos_sin(angle: float) -> tuple[float, float]:
    """``(cos a, sin a)`` of a checked angle (radians, a finite real number)."""
    a = as_scalar(angle, "angle")
    return math.cos(a), math.sin(a)


#: The rotation EGT's ``f_Rt2H`` folds in: a pin-hole camera "with no rotation"
#: looks along world +y with its image v axis pointing to world -z.
EGT_CAMERA_BASE = rotx(-np.pi / 2)


def skew(v: npt.ArrayLike) -> np.ndarray:
    r"""The cross-product matrix :math:`[v]_\times`, with :math:`[v]_\times w = v \times w`."""
    x, y, z = as_vector(v, "v", 3)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


@dataclass(frozen=True, eq=False)
class Pose:
    r"""A rigid pose :math:`H = [R\ t;\ 0\ 1]` of a frame in the world."""

    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    """(3, 3) rotation; columns are the frame's axes in world coordinates."""
    t: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """(3,) origin of the frame in world coordinates."""

    check: InitVar[bool] = True
    """``False``: ``R`` and ``t`` are trusted to be a rotation (orthonormal to rounding) and a finite 3-vector
    already, e.g. a rotation the caller built from angles; they are only copied, not checked and not
    re-orthonormalised (the per-drag fast path)."""

    if TYPE_CHECKING:
        # The constructor takes any array-like R and t; the fields hold the checked, read-only arrays.
        def __init__(self, R: npt.ArrayLike = ..., t: npt.ArrayLike = ..., check: bool = True) -> None: ...

    def __post_init__(self, check: bool) -> None:
        if check:
            R = as_rotation(self.R, "R")
            # Re-orthonormalise so repeated composition does not drift.
            u, _, vt = np.linalg.svd(R)
            R = u @ vt
            t = as_vector(self.t, "t", 3).copy()
        else:
            R = np.array(self.R, dtype=np.float64).reshape(3, 3)
            t = np.array(self.t, dtype=np.float64).reshape(3)
        R.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "t", t)

    @classmethod
    def from_matrix(cls, H: npt.ArrayLike) -> Pose:
        """Pose from a 4x4 homogeneous matrix ``[R t; 0 1]``."""
        H = as_matrix(H, "H", (4, 4))
        if not np.allclose(H[3], [0.0, 0.0, 0.0, 1.0]):
            raise GeometryError("H: expected last row [0, 0, 0, 1]")
        return cls(H[:3, :3], H[:3, 3])

    @classmethod
    def from_egt(cls, R: npt.ArrayLike, t: npt.ArrayLike) -> Pose:
        r"""EGT's ``f_Rt2H`` convention: :math:`H = [R_x(-\pi/2) R\ t;\ 0\ 1]`.

        ``R`` turns the camera about its own axes, ``t`` is in world coordinates.
        """
        return cls(EGT_CAMERA_BASE @ as_rotation(R, "R"), t)

    @property
    def matrix(self) -> np.ndarray:
        """The 4x4 homogeneous matrix ``H``."""
        H = np.eye(4)
        H[:3, :3] = self.R
        H[:3, 3] = self.t
        return H

    @property
    def egt_rotation(self) -> np.ndarray:
        r"""The ``R`` that ``f_Rt2H`` would need: :math:`R_x(-\pi/2)^T R`."""
        return EGT_CAMERA_BASE.T @ self.R

    def to_local(self, X_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        r"""World points (N, 3) into this frame: :math:`X = R^T (X_w - t)`.

        ``check=False``: the caller promises a float64 (N, 3) (or (3,)) array of finite values; nothing is checked.
        """
        X = as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world).reshape(-1, 3)
        return (X - self.t) @ self.R

    def to_world(self, X_local: npt.ArrayLike) -> np.ndarray:
        r"""Local points (N, 3) into the world: :math:`X_w = R X + t`."""
        X = as_points(X_local, "X_local", 3)
        return X @ self.R.T + self.t

    def direction_to_world(self, d_local: npt.ArrayLike) -> np.ndarray:
        """Local directions (N, 3) into world directions (rotation only)."""
        return as_points(d_local, "d_local", 3) @ self.R.T

    def compose(self, other: Pose) -> Pose:
        """``self @ other``: ``other`` expressed in this frame, returned in the world."""
        if not isinstance(other, Pose):
            raise GeometryError(f"other: expected a Pose, got {type(other).__name__}")
        return Pose(self.R @ other.R, self.R @ other.t + self.t)

    def inverse(self) -> Pose:
        """The inverse pose ``H^-1``."""
        return Pose(self.R.T, -self.R.T @ self.t)

    def with_position(self, t: npt.ArrayLike) -> Pose:
        """The same orientation at a new position."""
        return Pose(self.R, t)

    def with_rotation(self, R: npt.ArrayLike) -> Pose:
        """The same position with a new orientation."""
        return Pose(R, self.t)

    @cached_value
    def quat_wxyz(self) -> np.ndarray:
        """Orientation as a unit quaternion ``(w, x, y, z)`` (viser's order)."""
        return _quat_wxyz(self.R)  # R is a rotation already

    def __repr__(self) -> str:
        return f"Pose(R={np.round(self.R, 6).tolist()}, t={np.round(self.t, 6).tolist()})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Pose):
            return NotImplemented
        return bool(np.array_equal(self.R, other.R) and np.array_equal(self.t, other.t))

    def __hash__(self) -> int:
        # Hashed by value as floats (``-0.0`` and ``0.0`` hash alike, as ``__eq__`` finds them equal), so
        # specs that differ only in their pose do not all share one hash; R and t are read-only.
        h = self.__dict__.get("_hash")
        if h is None:
            h = self.__dict__["_hash"] = hash((*self.R.ravel().tolist(), *self.t.tolist()))
        return h


def quat_wxyz_from_matrix(R: npt.ArrayLike) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` of a rotation matrix, with ``w >= 0``."""
    return _quat_wxyz(as_rotation(R, "R"))


def _quat_wxyz(R: np.ndarray) -> np.ndarray:
    """:func:`quat_wxyz_from_matrix` of a checked rotation."""
    # Shepperd's method as scipy's ``Rotation.from_matrix`` does it, in plain floats (no per-call
    # numpy overhead: this runs on every camera drag).
    m = R.tolist()
    tr = m[0][0] + m[1][1] + m[2][2]
    decision = (m[0][0], m[1][1], m[2][2], tr)
    choice = max(range(4), key=decision.__getitem__)
    xyzw = [0.0, 0.0, 0.0, 0.0]
    if choice != 3:
        i = choice
        j = (i + 1) % 3
        k = (j + 1) % 3
        xyzw[i] = 1.0 - tr + 2.0 * m[i][i]
        xyzw[j] = m[j][i] + m[i][j]
        xyzw[k] = m[k][i] + m[i][k]
        xyzw[3] = m[k][j] - m[j][k]
    else:
        xyzw[0] = m[2][1] - m[1][2]
        xyzw[1] = m[0][2] - m[2][0]
        xyzw[2] = m[1][0] - m[0][1]
        xyzw[3] = 1.0 + tr
    n = math.sqrt(sum(c * c for c in xyzw))
    q = np.array([xyzw[3] / n, xyzw[0] / n, xyzw[1] / n, xyzw[2] / n])
    return q if q[0] >= 0 else -q


def matrix_from_quat_wxyz(q: npt.ArrayLike) -> np.ndarray:
    r"""Rotation matrix of a quaternion :math:`q = (w, x, y, z)`; it need not be unit-norm.

    ``q`` is defined up to scale: it is first divided by its largest absolute entry (any finite magnitude
    gives the same rotation), then with :math:`s = 2 / |q|^2`

    .. math:: R = \begin{bmatrix} 1 - s(y^2 + z^2) & s(xy - wz) & s(xz + wy) \\
        s(xy + wz) & 1 - s(x^2 + z^2) & s(yz - wx) \\ s(xz - wy) & s(yz + wx) & 1 - s(x^2 + y^2) \end{bmatrix}.

    Raises:
        GeometryError: ``q`` is not 4 finite numbers, or is zero.
    """
    q = as_vector(q, "q", 4, max_abs=None)
    top = max(abs(c) for c in q.tolist())
    if top == 0.0:
        raise GeometryError("q: a zero quaternion is not a rotation")
    w, x, y, z = (c / top for c in q.tolist())
    n2 = w * w + x * x + y * y + z * z  # >= 1: the largest entry is +-1
    # The textbook formula in plain floats (scipy's Rotation costs ~50 us a call; this runs on every gizmo event).
    s = 2.0 / n2
    return np.array([
        [1.0 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)],
        [s * (x * y + w * z), 1.0 - s * (x * x + z * z), s * (y * z - w * x)],
        [s * (x * z - w * y), s * (y * z + w * x), 1.0 - s * (x * x + y * y)],
    ])


def egt_rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
    r"""EGT user rotation from yaw, pitch, roll (radians) about the camera's own axes.

    In EGT's camera frame (x right, y down, z along the optical axis):
    yaw turns about the camera's y axis (pan), pitch about its x axis (tilt),
    roll about its z axis (the optical axis), applied in that order as
    intrinsic rotations:

    .. math:: R = R_y(\text{yaw})\, R_x(\text{pitch})\, R_z(\text{roll})

    Feed the result to :meth:`Pose.from_egt` (``f_Rt2H``); ``rotoy(pi/4)`` is a
    yaw of 45 degrees.
    """
    yaw, pitch, roll = as_scalar(yaw, "yaw"), as_scalar(pitch, "pitch"), as_scalar(roll, "roll")
    return roty(yaw) @ rotx(pitch) @ rotz(roll)


def ypr_from_egt_rotation(R: npt.ArrayLike) -> tuple[float, float, float]:
    """Inverse of :func:`egt_rotation_from_ypr`: ``(yaw, pitch, roll)`` in radians.

    Pitch is in ``[-pi/2, pi/2]``; at the gimbal lock (pitch = +-pi/2) roll is 0.
    """
    R = as_rotation(R, "R")
    # Intrinsic Y-X-Z Euler angles: R[1, 2] = -sin(pitch), R[0, 2] / R[2, 2] = tan(yaw), R[1, 0] / R[1, 1] = tan(roll).
    m = R.tolist()
    if abs(m[1][2]) < 0.999:  # well away from the gimbal lock: closed form (no scipy overhead on every drag)
        yaw = math.atan2(m[0][2], m[2][2])
        pitch = math.atan2(-m[1][2], math.hypot(m[0][2], m[2][2]))
        roll = math.atan2(m[1][0], m[1][1])
        return yaw, pitch, roll
    yaw, pitch, roll = Rotation.from_matrix(R).as_euler("YXZ")
    return float(yaw), float(pitch), float(roll)


def look_at(eye: npt.ArrayLike, target: npt.ArrayLike, up: npt.ArrayLike = (0.0, 0.0, 1.0)) -> Pose:
    """Camera pose at ``eye`` whose optical axis (+z) points at ``target``, image v (+y) towards -``up``."""
    eye = as_vector(eye, "eye", 3)
    z = as_vector(target, "target", 3) - eye
    if np.linalg.norm(z) < 1e-12:
        raise GeometryError("target: coincides with eye, the viewing direction is undefined")
    z = z / np.linalg.norm(z)
    up = as_vector(up, "up", 3)
    x = np.cross(z, up)
    if np.linalg.norm(x) < 1e-9:
        x = np.cross(z, [1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.cross(z, [0.0, 1.0, 0.0])
    x = x / np.linalg.norm(x)
    y = np.cross(z, x)
    return Pose(np.column_stack([x, y, z]), eye)
