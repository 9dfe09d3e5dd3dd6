"""The 3D nodes every servo demo shares: the moving body, the numbered scene points, its path and the viewing rays.

Pure drawing helpers for :class:`~egtviz.viewer.servo.servo_player.ServoPlayer`: they add nodes under ``/servo`` and
pose them from the run's :class:`~egtviz.servo.frames.ServoFrames`; they compute no geometry.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import viser

from egtviz.geometry.poses import quat_wxyz_from_matrix
from egtviz.servo.frames import ServoFrames

from ..render.palette import hex_to_rgb, point_colour

__all__ = ["ServoNodes", "add_common_nodes", "look_from", "pose_node"]


def _no_segments() -> np.ndarray:
    """A placeholder of one zero-length segment (viser draws no empty set of segments)."""
    return np.zeros((1, 2, 3), np.float32)


def _colours(indices: Iterable[int]) -> np.ndarray:
    return np.array([hex_to_rgb(point_colour(i)) for i in indices], np.uint8)


@dataclass(frozen=True)
class ServoNodes:
    """The 3D nodes the player poses at every frame (a demo poses its own, an arm say, in ``_draw_body``).

    Attributes:
        body: the moving body (camera or robot), posed at ``frames.body_poses[k]``.
        points: the numbered scene points.
        path: the body's path up to the frame.
        rays: the viewing rays to the points seen at the frame.
    """

    body: viser.SceneNodeHandle
    points: viser.PointCloudHandle
    path: viser.LineSegmentsHandle
    rays: viser.LineSegmentsHandle

    def draw_path_and_rays(self, frames: ServoFrames, k: int, points: np.ndarray) -> None:
        """The path up to frame ``k`` and the rays to the ``points`` seen at ``k`` (in the points' colours)."""
        path = frames.path_segments(k)
        self.path.points = path.astype(np.float32) if len(path) else _no_segments()
        segs, seen = frames.ray_segments(k, points)
        if len(seen):
            self.rays.points = segs.astype(np.float32)
            self.rays.colors = np.repeat(_colours(seen)[:, None, :], 2, axis=1)
        else:
            self.rays.points = _no_segments()


def add_common_nodes(api: viser.SceneApi, points: np.ndarray, body: viser.SceneNodeHandle, *, point_size: float,
                     label_lift: float, label_scale: float, path_width: float, ray_width: float) -> ServoNodes:
    """Add the numbered scene points (N, 3), the path and the viewing rays to scene ``api``; with the demo's
    ``body`` (added before), the nodes the player poses."""
    cloud = api.add_point_cloud("/servo/points", points.astype(np.float32), _colours(range(len(points))),
                                point_size=point_size, point_shape="circle")
    for i, X in enumerate(points):
        api.add_label(f"/servo/point_labels/{i}", str(i + 1), position=tuple(X + [0, 0, label_lift]),
                      font_screen_scale=label_scale)
    path = api.add_line_segments("/servo/path", _no_segments(), (20, 20, 20), thickness=path_width)
    rays = api.add_line_segments("/servo/rays", _no_segments(), (120, 120, 120), thickness=ray_width)
    return ServoNodes(body=body, points=cloud, path=path, rays=rays)


def pose_node(node: viser.SceneNodeHandle, H: np.ndarray) -> None:
    """Place ``node`` at the rigid transform ``H`` (4, 4)."""
    node.position = H[:3, 3]
    node.wxyz = quat_wxyz_from_matrix(H[:3, :3])


def _xyz(v: np.ndarray) -> tuple[float, float, float]:
    """A 3-vector as the float triple viser's camera setters take."""
    x, y, z = (float(c) for c in v)
    return x, y, z


def look_from(client: viser.ClientHandle, look_at: np.ndarray, position: np.ndarray) -> None:
    """Point the tab's 3D view (z up) from ``position`` at ``look_at``; a tab that refuses keeps its view."""
    try:
        cam = client.camera
        cam.up_direction = (0.0, 0.0, 1.0)
        cam.position = _xyz(position)
        cam.look_at = _xyz(look_at)
    except Exception:  # noqa: BLE001 - camera placement is cosmetic
        pass
