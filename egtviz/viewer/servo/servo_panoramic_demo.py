"""The panoramic servo demo in the browser: a catadioptric camera on a holonomic robot, bi-conics (EGT reference,
section 7).

In 3D: the robot (a disc with an orange heading arrow and a mast carrying the mirror, drawn
:data:`MIRROR_DRAW_SCALE` times enlarged so that it can be seen), the target robot (translucent green), the points,
the rays from the mirror focus and the trajectory on the ground. The image plane shows the mirror rim, the
bi-conic of each feature pair and the true epipoles ``e``, ``e'`` (:func:`egtviz.servo.frames.panoramic_frames`);
the caption says which step runs. Only the shared run fields (:class:`~egtviz.viewer.servo.servo_player.ServoPlayer`).
The model, its run parameters and its simulation are :class:`~egtviz.controllers.servo_demos.PanoramicServoModel`.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, cast

import numpy as np
import viser

from egtviz.controllers.servo_demos import PanoramicServoModel
from egtviz.servo.panoramic_robot import CAMERA_HEIGHT

from .servo_nodes import ServoNodes
from .servo_player import ServoPlayer

__all__ = ["MIRROR_DRAW_SCALE", "PanoramicServoDemo"]

#: The panoramic mirror (2 cm rim) is drawn this much larger in 3D, so that it can be seen.
MIRROR_DRAW_SCALE = 4.0


class PanoramicServoDemo(ServoPlayer):
    """The panoramic demo in one tab; options as :class:`~egtviz.viewer.servo.servo_player.ServoPlayer`."""

    TITLE: ClassVar[str] = "Visual servoing: panoramic camera on a mobile robot"
    INTRO: ClassVar[str] = ("Step 1 turns the robot until all bi-conics meet in the two epipoles (same "
                            "orientation); step 2 translates along the baseline until s(t), the feature distance, "
                            "is zero.")
    CONTROL_TITLE: ClassVar[str] = "Robot velocity (robot frame)"
    CONTROL_KEY: ClassVar[str] = "robot_velocity"
    CONTROL_SERIES: ClassVar[tuple[tuple[str, str, str], ...]] = (
        ("v_x", "#0072B2", "v"), ("v_y", "#D55E00", "v"), ("ω (right axis)", "#009E73", "w"))
    FEATURE_ERROR_LABEL: ClassVar[str] = "s(t)"

    def __init__(self, client: viser.ClientHandle, **options: Any) -> None:
        #: The camera, the scene and the simulation.
        self.model = PanoramicServoModel()
        super().__init__(client, self.model, **options)

    def _build_scene(self) -> ServoNodes:
        import trimesh

        api = self.client.scene
        api.add_grid("/servo/grid", width=14.0, height=14.0, cell_size=0.5, section_size=1.0)
        body = trimesh.creation.cylinder(radius=0.28, height=0.22, sections=40)
        body.apply_translation((0, 0, 0.16))
        mast = trimesh.creation.cylinder(radius=0.015, height=CAMERA_HEIGHT - 0.27, sections=12)
        mast.apply_translation((0, 0, 0.27 + (CAMERA_HEIGHT - 0.27) / 2 - 0.06))
        arrow = trimesh.creation.cone(radius=0.07, height=0.16, sections=20)
        arrow.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, (0, 1, 0)))
        arrow.apply_translation((0.3, 0, 0.16))
        shaft = trimesh.creation.box(extents=(0.22, 0.04, 0.04))
        shaft.apply_translation((0.2, 0, 0.16))
        heading = cast(trimesh.Trimesh, trimesh.util.concatenate([arrow, shaft]))  # of two meshes: one mesh
        mv, mf = self.model.camera.mirror.surface(n_radial=12, n_angular=48)
        mv = mv * MIRROR_DRAW_SCALE + np.array([0.0, 0.0, CAMERA_HEIGHT])

        def robot(root: str, colour: tuple[int, int, int], opacity: float | None) -> viser.FrameHandle:
            node = api.add_frame(root, show_axes=False)
            api.add_mesh_simple(f"{root}/body", body.vertices, body.faces, color=colour, opacity=opacity)
            api.add_mesh_simple(f"{root}/heading", heading.vertices, heading.faces, color=(213, 94, 0),
                                opacity=opacity)
            api.add_mesh_simple(f"{root}/mast", mast.vertices, mast.faces, color=(90, 90, 90), opacity=opacity)
            api.add_mesh_simple(f"{root}/mirror", mv, mf, color=(200, 215, 230), opacity=opacity, side="double")
            return node

        robot("/servo/target", (0, 158, 115), 0.35)
        # At the goal the robot stands on the target: their labels grow away from each other, never overlap.
        api.add_label("/servo/target/label", "target", position=(0.0, 0.0, 0.75), font_screen_scale=0.9,
                      anchor="bottom-right")
        moving = robot("/servo/robot", (86, 110, 140), None)
        api.add_label("/servo/robot/label", "robot", position=(0.0, 0.0, 0.75), font_screen_scale=0.9,
                      anchor="bottom-left")
        nodes = self._add_common_nodes(moving, point_size=0.09, label_lift=0.12, label_scale=0.8, path_width=0.025,
                                       ray_width=0.008)
        self._view(np.array([0.0, 0.0, 0.3]), np.array([2.0, -8.0, 6.0]))
        return nodes
