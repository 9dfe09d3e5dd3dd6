"""The 3D nodes every servo demo shares: the numbered scene points, the moving body's path and the viewing rays.

Pure drawing helpers for :class:`~egtviz.viewer.servo.servo_player.ServoPlayer`: they add nodes under ``/servo`` and
pose them from the run's :class:`~egtviz.servo.frames.ServoFrames`; they compute no geometry.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from egtviz.geometry.poses import quat_wxyz_from_matrix
from egtviz.servo.frames import ServoFrames

from ..render.palette import hex_to_rgb, point_colour

__all__ = ["add_common_nodes", "draw_path_and_rays", "look_from", "pose_node"]


def _no_segments() -> np.ndarray:
    """A placeholder of one zero-length segment (viser draws no empty set of segments)."""
    return np.zeros((1, 2, 3), np.float32)


def _colours(indices: Any) -> np.ndarray:
    return np.array([hex_to_rgb(point_colour(i)) for i in indices], np.uint8)


def add_common_nodes(api: Any, points: np.ndarray, *, point_size: float, label_lift: float, label_scale: float,
                     path_width: float, ray_width: float) -> dict[str, Any]:
    """Add the numbered scene points (N, 3), the path and the viewing rays to scene ``api``; their handles by name
    (``points``, ``path``, ``rays``)."""
    nodes = {"points": api.add_point_cloud("/servo/points", points.astype(np.float32), _colours(range(len(points))),
                                           point_size=point_size, point_shape="circle")}
    for i, X in enumerate(points):
        api.add_label(f"/servo/point_labels/{i}", str(i + 1), position=tuple(X + [0, 0, label_lift]),
                      font_screen_scale=label_scale)
    nodes["path"] = api.add_line_segments("/servo/path", _no_segments(), (20, 20, 20), thickness=path_width)
    nodes["rays"] = api.add_line_segments("/servo/rays", _no_segments(), (120, 120, 120), thickness=ray_width)
    return nodes


def pose_node(node: Any, H: np.ndarray) -> None:
    """Place ``node`` at the rigid transform ``H`` (4, 4)."""
    node.position = H[:3, 3]
    node.wxyz = quat_wxyz_from_matrix(H[:3, :3])


def draw_path_and_rays(nodes: dict[str, Any], frames: ServoFrames, k: int, points: np.ndarray) -> None:
    """The path up to frame ``k`` and the rays to the points seen at ``k`` (in the points' colours)."""
    path = frames.path_segments(k)
    nodes["path"].points = path.astype(np.float32) if len(path) else _no_segments()
    segs, seen = frames.ray_segments(k, points)
    if len(seen):
        nodes["rays"].points = segs.astype(np.float32)
        nodes["rays"].colors = np.repeat(_colours(seen)[:, None, :], 2, axis=1)
    else:
        nodes["rays"].points = _no_segments()


def look_from(client: Any, look_at: np.ndarray, position: np.ndarray) -> None:
    """Point the tab's 3D view (z up) from ``position`` at ``look_at``; a tab that refuses keeps its view."""
    try:
        cam = client.camera
        cam.up_direction = (0.0, 0.0, 1.0)
        cam.position = tuple(float(x) for x in position)
        cam.look_at = tuple(float(x) for x in look_at)
    except Exception:  # noqa: BLE001 - camera placement is cosmetic
        pass
