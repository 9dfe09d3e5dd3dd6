r"""Per-frame geometry of a recorded servo run: everything the demos draw that is geometry, for all frames at once.

A :class:`~egtviz.servo.result.ServoResult` records poses, joint angles and features. The demos also draw, at
every frame ``k``, things derived from them; this module derives them, vectorised over the frames (pure numpy
and :mod:`egtviz.geometry`, no viewer):

* **pin-hole** (:func:`pinhole_frames`): the epipolar line in the current image of each desired feature
  :math:`m^*_i`, the image of the epipolar plane through the current centre :math:`c_k`, the target centre
  :math:`c^*` and the desired ray :math:`w_i = R^* K^{-1} m^*_i`:

  .. math:: n_{ki} = (c^* - c_k) \times w_i, \qquad l_{ki} = K^{-T} R_k^T n_{ki},

  the line :math:`l_1 = F^T m^*` of the pair (current, target), clipped to the image; and the epipole
  :math:`e_k \sim K R_k^T (c^* - c_k)` (drawn unless it is at infinity). Once the rotation is compensated
  every current feature lies on its line, and all lines meet in :math:`e_k`.
* **panoramic** (:func:`panoramic_frames`): the bi-conic of each feature pair, the image of the plane
  through the focus spanned by the current and desired rays (mirror frame),
  :math:`n = d \times d^*` (:func:`~egtviz.geometry.panoramic_epipolar.biconic_normals`), sampled into its
  visible arcs by the camera model (``plane_image_arcs``); and the two epipoles of the current image, the
  images of the rays :math:`\pm R_k^T (c^* - c_k)`, drawn where the mirror shows them.
* **both**: the arm's link frames by forward kinematics (:class:`DHChain`), the moving body's pose, its
  path, the viewing rays from the centre to the points seen, and the thinned feature trails.

When the centre reaches the target (:math:`|c^* - c_k| \le` ``COINCIDENT_CENTRES_TOL``
:math:`\max(1, |c_k|, |c^*|)`) there is no epipolar geometry: the frame carries a message instead of lines or
epipoles.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from egtviz.geometry import GeometryError
from egtviz.geometry.camera_model import CameraModel
from egtviz.geometry.epipolar import COINCIDENT_CENTRES_TOL
from egtviz.geometry.homogeneous import clip_lines_to_rect, normalize_homogeneous
from egtviz.geometry.panoramic_epipolar import biconic_normals
from egtviz.geometry.pinhole import Intrinsics
from egtviz.geometry.poses import Pose

from .result import ServoResult

__all__ = [
    "CONIC_SAMPLES",
    "PANORAMIC_GOAL_MESSAGE",
    "PATH_VERTICES",
    "PINHOLE_GOAL_MESSAGE",
    "TRAIL_VERTICES",
    "DHChain",
    "FrameGeometry",
    "ServoFrames",
    "panoramic_frames",
    "pinhole_frames",
    "robot_poses",
    "trail_indices",
]

#: Samples per great circle of a bi-conic (each frame draws one bi-conic per feature).
CONIC_SAMPLES = 96
#: Most vertices per feature trail (older samples are thinned, the newest is always kept).
TRAIL_VERTICES = 160
#: Most vertices of the 3D path.
PATH_VERTICES = 400
#: Samples of the mirror rim's image.
RIM_SAMPLES = 256
#: Frames derived per vectorised block; ``stop()`` is asked between blocks.
BLOCK_FRAMES = 128

PINHOLE_GOAL_MESSAGE = "at the goal: no epipolar geometry (the centres coincide)"
PANORAMIC_GOAL_MESSAGE = "at the goal: no epipoles (the foci coincide)"

Stop = Callable[[], bool]


def trail_indices(k: int, limit: int = TRAIL_VERTICES) -> np.ndarray:
    """Sample indices ``0..k`` thinned to at most ``limit`` (always containing 0 and ``k``), ascending."""
    if k + 1 <= limit:
        return np.arange(k + 1)
    return np.unique(np.r_[np.linspace(0, k, limit).astype(int), k])


# ------------------------------------------------------------------------------------------------ one frame
@dataclass(frozen=True, eq=False)
class FrameGeometry:
    """What the image panel draws at one frame besides the features and their trails."""

    lines: np.ndarray | None
    """(N, 2, 2) clipped epipolar-line segments in the current image (pin-hole); NaN rows miss the image."""
    conics: tuple[tuple[np.ndarray, ...], ...]
    """Per feature, the (k, 2) polylines of its bi-conic (panoramic; empty for the pin-hole)."""
    epipoles: tuple[tuple[str, np.ndarray], ...]
    """``(label, (2,) pixel)`` of each epipole drawn in the current image."""
    message: str
    """Why something is not drawn (the centres coincide at the goal), else ``""``."""


# ------------------------------------------------------------------------------------------------ the run
@dataclass(frozen=True, eq=False)
class ServoFrames:
    """The geometry of every frame of one run (built by :func:`pinhole_frames` or :func:`panoramic_frames`).

    ``T`` is the number of frames (the run's samples), ``N`` the number of features.
    """

    features: np.ndarray
    """(T, N, 2) current feature pixels (NaN: no image)."""
    desired: np.ndarray
    """(N, 2) desired feature pixels."""
    width: int
    height: int
    centres: np.ndarray
    """(T, 3) camera centre (pin-hole) or mirror focus (panoramic) in the world: where the viewing rays start."""
    body_poses: np.ndarray
    """(T, 4, 4) world pose of the moving body drawn in 3D: the camera (pin-hole), the robot base (panoramic)."""
    path: np.ndarray
    """(T, 3) the trajectory drawn in 3D: the camera centre, or the robot on the ground."""
    epipole_labels: tuple[str, ...]
    """Label of each epipole column of :attr:`epipoles`."""
    epipoles: np.ndarray
    """(T, E, 2) epipole pixels of the current image; NaN where one is not drawn."""
    at_goal: np.ndarray
    """(T,) bool: the centre coincides with the target's, there is no epipolar geometry."""
    goal_message: str
    """The message of a frame at the goal."""
    lines: np.ndarray | None = None
    """(T, N, 2, 2) clipped epipolar-line segments (pin-hole), NaN where a line misses the image."""
    conics: tuple[tuple[tuple[np.ndarray, ...], ...], ...] | None = None
    """Per frame, per feature, the visible arcs (k, 2) of its bi-conic (panoramic)."""
    links: np.ndarray | None = None
    """(T, J + 1, 4, 4) the arm's base and link frames (pin-hole), from :meth:`DHChain.link_poses`."""
    rim: np.ndarray | None = None
    """(M, 2) the boundary of the camera's image region (the mirror rim's image; panoramic), an open polyline
    (the drawing closes it)."""

    def __post_init__(self) -> None:
        # Read-only views (the run's own arrays stay as they are): a tab playing the run cannot change it.
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray):
                view = value.view()
                view.setflags(write=False)
                object.__setattr__(self, name, view)

    def __len__(self) -> int:
        return len(self.features)

    def _index(self, k: int) -> int:
        return int(np.clip(int(k), 0, len(self) - 1))

    def at(self, k: int) -> FrameGeometry:
        """Frame ``k`` (clipped to the run) as a :class:`FrameGeometry`."""
        k = self._index(k)
        eps = tuple((label, e) for label, e in zip(self.epipole_labels, self.epipoles[k], strict=True)
                    if np.all(np.isfinite(e)))
        return FrameGeometry(
            lines=None if self.lines is None else self.lines[k],
            conics=() if self.conics is None else self.conics[k],
            epipoles=eps,
            message=self.goal_message if self.at_goal[k] else "",
        )

    def trail(self, k: int, limit: int = TRAIL_VERTICES) -> np.ndarray:
        """(k', N, 2) feature pixels from frame 0 to ``k``, thinned to at most ``limit`` samples."""
        return self.features[trail_indices(self._index(k), limit)]

    def path_segments(self, k: int, limit: int = PATH_VERTICES) -> np.ndarray:
        """(M, 2, 3) segments of the 3D path from frame 0 to ``k`` (thinned); (0, 2, 3) before it moved."""
        P = self.path[trail_indices(self._index(k), limit)]
        return np.stack([P[:-1], P[1:]], axis=1)

    def ray_segments(self, k: int, points: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Viewing rays at frame ``k``: segments (M, 2, 3) from the centre to each point (N, 3) with an image,
        and the indices (M,) of those points."""
        k = self._index(k)
        P = np.asarray(points, dtype=float)
        if P.shape != (self.features.shape[1], 3):
            raise GeometryError(f"points: expected shape ({self.features.shape[1]}, 3), got {P.shape}")
        seen = np.flatnonzero(np.all(np.isfinite(self.features[k]), axis=1))
        segs = np.stack([np.broadcast_to(self.centres[k], (len(seen), 3)), P[seen]], axis=1)
        return segs, seen


# ------------------------------------------------------------------------------------------------ kinematics
@dataclass(frozen=True, eq=False)
class DHChain:
    r"""A serial arm of revolute joints in standard Denavit-Hartenberg form, for forward kinematics.

    Link ``j`` turns about its z axis by :math:`\theta_j = q_j + \mathrm{offset}_j`, then

    .. math:: A_j = R_z(\theta_j)\, T_z(d_j)\, T_x(a_j)\, R_x(\alpha_j) =
        \begin{bmatrix} c_\theta & -s_\theta c_\alpha & s_\theta s_\alpha & a c_\theta \\
        s_\theta & c_\theta c_\alpha & -c_\theta s_\alpha & a s_\theta \\
        0 & s_\alpha & c_\alpha & d \\ 0 & 0 & 0 & 1 \end{bmatrix},
        \qquad T_j = B A_1 \cdots A_j

    with :math:`B` the base pose (Corke, *Robotics, Vision and Control*, section 7.1).
    """

    a: np.ndarray
    """(J,) link lengths, metres."""
    d: np.ndarray
    """(J,) link offsets, metres."""
    alpha: np.ndarray
    """(J,) link twists, radians."""
    offset: np.ndarray
    """(J,) joint angle offsets, radians."""
    base: np.ndarray
    """(4, 4) base pose in the world."""

    def __post_init__(self) -> None:
        shapes = {name: np.shape(getattr(self, name)) for name in ("a", "d", "alpha", "offset")}
        if len(set(shapes.values())) != 1 or len(shapes["a"]) != 1 or shapes["a"][0] < 1:
            raise GeometryError(f"a, d, alpha, offset: expected equal shapes (J,), got {shapes}")
        if np.shape(self.base) != (4, 4):
            raise GeometryError(f"base: expected shape (4, 4), got {np.shape(self.base)}")

    @classmethod
    def of_robot(cls, robot: Any) -> DHChain:
        """The chain of a roboticstoolbox ``DHRobot`` with standard DH revolute joints (e.g. ``Puma560``).

        Raises:
            GeometryError: a modified-DH robot, a prismatic or flipped joint.
        """
        if getattr(robot, "mdh", 0):
            raise GeometryError("robot: expected standard DH parameters, got modified DH")
        links = list(robot.links)
        if any(not link.isrevolute or link.isflip for link in links):
            raise GeometryError("robot: expected revolute, unflipped joints only")
        return cls(
            a=np.array([link.a for link in links], float),
            d=np.array([link.d for link in links], float),
            alpha=np.array([link.alpha for link in links], float),
            offset=np.array([link.offset for link in links], float),
            base=np.array(robot.base.A, float),
        )

    def link_poses(self, q: npt.ArrayLike) -> np.ndarray:
        """World frames of the base and every link, (T, J + 1, 4, 4), for joint angles ``q`` (T, J) or (J,)
        (then T = 1); frame 0 is the base, frame ``j`` is :math:`T_j`."""
        q = np.asarray(q, dtype=float)
        J = len(self.a)
        if q.ndim == 1:
            q = q[None, :]
        if q.ndim != 2 or q.shape[1] != J or not np.all(np.isfinite(q)):
            raise GeometryError(f"q: expected finite joint angles of shape (T, {J}) or ({J},), got {q.shape}")
        theta = q + self.offset
        ct, st = np.cos(theta), np.sin(theta)
        ca, sa = np.cos(self.alpha), np.sin(self.alpha)
        A = np.zeros((len(q), J, 4, 4))
        A[..., 0, 0], A[..., 0, 1], A[..., 0, 2], A[..., 0, 3] = ct, -st * ca, st * sa, self.a * ct
        A[..., 1, 0], A[..., 1, 1], A[..., 1, 2], A[..., 1, 3] = st, ct * ca, -ct * sa, self.a * st
        A[..., 2, 1], A[..., 2, 2], A[..., 2, 3] = sa, ca, self.d
        A[..., 3, 3] = 1.0
        out = np.empty((len(q), J + 1, 4, 4))
        out[:, 0] = self.base
        for j in range(J):  # a chain: each frame needs the previous one (J matrix products over all T)
            out[:, j + 1] = out[:, j] @ A[:, j]
        return out


# ------------------------------------------------------------------------------------------------ builders
def _poses(result: ServoResult) -> tuple[np.ndarray, np.ndarray]:
    H = np.asarray(result.camera_poses, dtype=float)
    return H[:, :3, :3], H[:, :3, 3]


def _at_goal(centres: np.ndarray, target_centre: np.ndarray) -> np.ndarray:
    """(T,) ``|c* - c_k| <= COINCIDENT_CENTRES_TOL max(1, |c_k|, |c*|)``, the core's rule for coincident centres."""
    scale = np.maximum(np.maximum(1.0, np.linalg.norm(centres, axis=1)), np.linalg.norm(target_centre))
    return np.linalg.norm(centres - target_centre, axis=1) <= COINCIDENT_CENTRES_TOL * scale


def _blocks(T: int) -> list[slice]:
    return [slice(s, min(s + BLOCK_FRAMES, T)) for s in range(0, T, BLOCK_FRAMES)]


def _stopped(stop: Stop | None) -> bool:
    return stop is not None and bool(stop())


def pinhole_frames(
    result: ServoResult,
    intrinsics: Intrinsics,
    target_pose: Pose,
    *,
    chain: DHChain | None = None,
    stop: Stop | None = None,
) -> ServoFrames | None:
    r"""Every frame's geometry of a pin-hole run (see the module docstring for the equations).

    Args:
        result: the recorded run (``camera_poses``, ``features``, ``desired_features``, ``joint_angles``).
        intrinsics: the camera's intrinsics (the same at the current and the target pose).
        target_pose: the target camera pose in the world.
        chain: the arm, for the link frames of every frame (from ``result.joint_angles``); None: no arm.
        stop: asked between blocks of frames; when it returns True the work is abandoned.

    Returns:
        The frames, or None if ``stop()`` returned True.
    """
    K = intrinsics.K
    K_inv = np.linalg.inv(K)
    R, c = _poses(result)
    T, N = len(c), len(result.desired_features)
    desired = np.asarray(result.desired_features, dtype=float)
    at_goal = _at_goal(c, target_pose.t)
    # Desired rays in the world, w_i = R* K^-1 m*_i, NaN rows for desired features with no image.
    w = np.column_stack([desired, np.ones(N)]) @ (target_pose.R @ K_inv).T
    lines = np.full((T, N, 2, 2), np.nan)
    epipoles = np.full((T, 1, 2), np.nan)
    for block in _blocks(T):
        if _stopped(stop):
            return None
        b = target_pose.t - c[block]  # (B, 3) towards the target centre
        b_cam = np.einsum("bji,bj->bi", R[block], b)  # R_k^T b
        n_cam = np.einsum("bji,bnj->bni", R[block], np.cross(b[:, None, :], w[None, :, :]))  # R_k^T (b x w)
        ell = n_cam @ K_inv  # l = K^-T n, as rows
        scale = np.linalg.norm(b, axis=1)[:, None] * np.linalg.norm(w, axis=1)[None, :]
        drawable = np.all(np.isfinite(ell), axis=2) & (np.linalg.norm(n_cam, axis=2) > 1e-12 * scale)
        drawable &= ~at_goal[block, None]
        bi, ni = np.nonzero(drawable)
        if len(bi):
            segs, hit = clip_lines_to_rect(ell[bi, ni], intrinsics.width, intrinsics.height)
            lines[block][bi[hit], ni[hit]] = segs[hit]
        moving = np.flatnonzero(~at_goal[block])
        if len(moving):
            e = normalize_homogeneous(b_cam[moving] @ K.T)
            finite = e[:, 2] != 0.0  # an epipole at infinity (baseline parallel to the image) is not drawn
            epipoles[block][moving[finite], 0] = e[finite, :2]
    links = None if chain is None or result.joint_angles is None else chain.link_poses(result.joint_angles)
    return ServoFrames(
        features=np.asarray(result.features, dtype=float),
        desired=desired,
        width=intrinsics.width,
        height=intrinsics.height,
        centres=c,
        body_poses=np.asarray(result.camera_poses, dtype=float),
        path=c,
        epipole_labels=("e",),
        epipoles=epipoles,
        at_goal=at_goal,
        goal_message=PINHOLE_GOAL_MESSAGE,
        lines=lines,
        links=links,
    )


def robot_poses(states: npt.ArrayLike) -> np.ndarray:
    r"""World poses (T, 4, 4) of a ground robot at states :math:`(x, y, \theta)` (T, 3): :math:`R_z(\theta)`, origin
    :math:`(x, y, 0)`."""
    s = np.asarray(states, dtype=float)
    H = np.zeros((len(s), 4, 4))
    ct, st = np.cos(s[:, 2]), np.sin(s[:, 2])
    H[:, 0, 0], H[:, 0, 1], H[:, 1, 0], H[:, 1, 1] = ct, -st, st, ct
    H[:, 2, 2] = H[:, 3, 3] = 1.0
    H[:, 0, 3], H[:, 1, 3] = s[:, 0], s[:, 1]
    return H


#: Height of the drawn ground path above the ground, metres (so that the grid does not hide it).
PATH_LIFT = 0.01


def panoramic_frames(
    result: ServoResult,
    camera: CameraModel,
    target_pose: Pose,
    *,
    stop: Stop | None = None,
    n_samples: int = CONIC_SAMPLES,
) -> ServoFrames | None:
    r"""Every frame's geometry of a panoramic run (see the module docstring for the equations).

    Args:
        result: the recorded run (``camera_poses`` are the mirror frames, ``states`` the robot's).
        camera: the robot's central camera (a catadioptric one in the demo); its pose is ignored: rays are taken
            in the mirror frame.
        target_pose: the target mirror pose in the world.
        stop: asked between blocks of frames; when it returns True the work is abandoned.
        n_samples: samples per great circle of a bi-conic.

    Returns:
        The frames, or None if ``stop()`` returned True.
    """
    model = camera.moved(Pose())  # the mirror frame is the world of this model
    R, c = _poses(result)
    F = np.asarray(result.features, dtype=float)
    T, N = F.shape[:2]
    desired = np.asarray(result.desired_features, dtype=float)
    at_goal = _at_goal(c, target_pose.t)

    def rays(pixels: np.ndarray) -> np.ndarray:
        out = np.full((len(pixels), 3), np.nan)
        seen = np.all(np.isfinite(pixels), axis=1)
        if seen.any():
            out[seen] = model.back_project(pixels[seen])
        return out

    d_star = rays(desired)
    conics: list[tuple[tuple[np.ndarray, ...], ...]] = []
    for block in _blocks(T):
        if _stopped(stop):
            return None
        d = rays(F[block].reshape(-1, 2))
        ds = np.tile(d_star, (block.stop - block.start, 1))
        ok = np.flatnonzero(np.all(np.isfinite(d), axis=1) & np.all(np.isfinite(ds), axis=1))
        per_feature: list[tuple[np.ndarray, ...]] = [() for _ in range(len(d))]
        if len(ok):
            arcs = model.plane_image_arcs(biconic_normals(d[ok], ds[ok]), n_samples)
            for i, a in zip(ok.tolist(), arcs, strict=True):
                per_feature[i] = tuple(a)
        conics.extend(tuple(per_feature[j * N:(j + 1) * N]) for j in range(block.stop - block.start))
    # Epipoles: the images of the rays towards (+) and away from (-) the target focus, in the mirror frame.
    epipoles = np.full((T, 2, 2), np.nan)
    moving = np.flatnonzero(~at_goal)
    if len(moving):
        toward = np.einsum("tji,tj->ti", R[moving], target_pose.t - c[moving])
        proj = model.project(np.concatenate([toward, -toward]))
        px = np.where(proj.visible[:, None], proj.pixels, np.nan).reshape(2, len(moving), 2)
        epipoles[moving] = px.transpose(1, 0, 2)
    states = result.states if result.states is not None else np.column_stack([c[:, :2], np.zeros(T)])
    path = np.column_stack([np.asarray(states, float)[:, :2], np.full(T, PATH_LIFT)])
    return ServoFrames(
        features=F,
        desired=desired,
        width=camera.width,
        height=camera.height,
        centres=c,
        body_poses=robot_poses(states),
        path=path,
        epipole_labels=("e", "e'"),
        epipoles=epipoles,
        at_goal=at_goal,
        goal_message=PANORAMIC_GOAL_MESSAGE,
        conics=tuple(conics),
        rim=model.rim(RIM_SAMPLES)[:-1],
    )
