"""The equidistant fisheye camera in 3D: its lens, a translucent dome over the viewpoint facing the optical axis.

The dome is the half of a sphere of radius :data:`LENS_RADIUS` in front of the lens (model frame: z forward): the
rays a 180-degree fisheye images. The light paths (point -> centre) are the scene's rays, drawn with every camera's.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from . import CameraDrawing, DrawContext

if TYPE_CHECKING:
    from ....geometry.fisheye import FisheyeCamera
    from ....scene.derived import ImagePlane

#: Radius of the drawn lens, scene units (metres).
LENS_RADIUS = 0.25
#: Rings and segments of the drawn cap.
_RINGS, _SEGMENTS = 8, 32


def cap_mesh(half_angle: float, radius: float = LENS_RADIUS) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (T, 3) of the spherical cap ``theta <= half_angle`` about +z."""
    theta = np.linspace(0.0, half_angle, _RINGS + 1)[1:]
    phi = 2.0 * np.pi * np.arange(_SEGMENTS) / _SEGMENTS
    ring = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.sin(theta)[:, None] * np.sin(phi),
                     np.broadcast_to(np.cos(theta)[:, None], (_RINGS, _SEGMENTS))], axis=-1)
    vertices = radius * np.vstack([[0.0, 0.0, 1.0], ring.reshape(-1, 3)])
    faces = [(0, 1 + j, 1 + (j + 1) % _SEGMENTS) for j in range(_SEGMENTS)]
    for i in range(_RINGS - 1):
        a, b = 1 + i * _SEGMENTS, 1 + (i + 1) * _SEGMENTS
        for j in range(_SEGMENTS):
            k = (j + 1) % _SEGMENTS
            faces += [(a + j, b + j, b + k), (a + j, b + k, a + k)]
    return vertices.astype(np.float32), np.asarray(faces, np.uint32)


class FisheyeDrawing(CameraDrawing["FisheyeCamera"]):
    """A translucent dome over the viewpoint, facing the optical axis."""

    def __init__(self, api: Any, root: str, k: int, colour: tuple[int, int, int]) -> None:
        super().__init__(api, root, k, colour)
        vertices, faces = cap_mesh(math.pi / 2)
        self.lens = api.add_mesh_simple(f"{root}/lens", vertices, faces, color=colour, opacity=0.35, side="double",
                                        cast_shadow=False, receive_shadow=False)

    def named_nodes(self) -> dict[str, Any]:
        return {"lens": self.lens}

    @property
    def body(self) -> Any:
        return self.lens

    def update(self, camera: FisheyeCamera, plane: ImagePlane, ctx: DrawContext) -> None:
        """Nothing moves but the gizmo (the lens is a child of it)."""
