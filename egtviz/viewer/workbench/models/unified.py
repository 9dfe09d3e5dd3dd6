"""The unified sphere camera in 3D: the sphere, its projection centre, and for the selected point its point on the
sphere and the great circle of its epipolar plane.

The sphere is drawn with radius :data:`SPHERE_RADIUS` (the model is the same at every radius); the projection
centre is then :math:`(0, 0, -\\xi)` times that radius in the model frame (z forward).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...server.viser_adapter import assign, assign_array
from . import CameraDrawing, DrawContext
from .common import EMPTY_SEG
from .shared import SHARED

if TYPE_CHECKING:
    import viser

    from ....geometry.unified import UnifiedCamera
    from ....scene.derived import ImagePlane

#: Radius of the drawn sphere, scene units (metres).
SPHERE_RADIUS = 0.5
#: Samples of the drawn great circle.
CIRCLE_SAMPLES = 96


class UnifiedDrawing(CameraDrawing["UnifiedCamera"]):
    """A translucent sphere about the viewpoint, the projection centre on its axis, the selected point's ray."""

    def __init__(self, api: viser.SceneApi, root: str, k: int, colour: tuple[int, int, int]) -> None:
        super().__init__(api, root, k, colour)
        self.sphere = api.add_icosphere(f"{root}/sphere", radius=SPHERE_RADIUS, color=colour, opacity=0.25,
                                        subdivisions=3, side="double", cast_shadow=False, receive_shadow=False)
        self.centre = api.add_icosphere(f"{root}/projection_centre", radius=0.04, color=(20, 20, 20),
                                        cast_shadow=False, receive_shadow=False)
        self.on_sphere = api.add_icosphere(f"/egt/sphere_point_{k}", radius=0.04, color=(0, 0, 0), visible=False,
                                           cast_shadow=False, receive_shadow=False)
        self.circle = api.add_line_segments(f"/egt/great_circle_{k}", EMPTY_SEG, colour, thickness=0.012,
                                            visible=False)
        self._circle_key: tuple[UnifiedCamera, int, bytes, bytes] | None = None

    def named_nodes(self) -> dict[str, viser.SceneNodeHandle]:
        return {"sphere": self.sphere, "centre": self.centre, "on_sphere": self.on_sphere, "circle": self.circle}

    @property
    def body(self) -> viser.IcosphereHandle:
        return self.sphere

    def update(self, camera: UnifiedCamera, plane: ImagePlane, ctx: DrawContext) -> None:
        # The camera and its derived arrays were checked when the scene was: the core's unchecked calls (every drag).
        # Once per derived camera (SHARED: a classroom's followers draw the instructor's).
        assign(self.centre, "position", SHARED.get("unified.centre", (camera,), None, lambda: _centre(camera)))
        sel, normal = ctx.selected_point, ctx.selected_normal
        show = sel is not None and normal is not None and ctx.in_pair
        if sel is not None and normal is not None and ctx.in_pair:
            key = (camera, sel, normal.tobytes(), ctx.points[sel].tobytes())
            if key != self._circle_key:
                p = camera.sphere_points(ctx.points[sel], SPHERE_RADIUS, check=False)[0]
                assign(self.on_sphere, "position", tuple(p))
                C = camera.great_circle(normal, CIRCLE_SAMPLES, SPHERE_RADIUS, check=False)
                assign_array(self.circle, "points", np.stack([C[:-1], C[1:]], axis=1).astype(np.float32))
                self._circle_key = key
        assign(self.on_sphere, "visible", show)
        assign(self.circle, "visible", show)

    def remove(self) -> None:
        self.on_sphere.remove()
        self.circle.remove()


def _centre(camera: UnifiedCamera) -> tuple[float, ...]:
    """The projection centre of the sphere drawn with radius ``SPHERE_RADIUS``, in the model frame."""
    # The camera and its derived arrays were checked when the scene was: the core's unchecked calls (every drag).
    centre = camera.pose.to_local(camera.projection_centre(SPHERE_RADIUS, check=False), check=False)
    return tuple(centre[0])
