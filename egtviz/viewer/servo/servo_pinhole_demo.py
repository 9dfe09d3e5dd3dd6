"""The pin-hole servo demo in the browser: a camera on a Puma 560 under Rives' hybrid task (EGT reference, section 7).

In 3D: the arm (rtb-data's link meshes, placed at the link frames of :class:`~egtviz.servo.frames.DHChain`; a stick
figure if the meshes are missing), the camera frustum on the end effector (black), the target frustum (green), the
numbered scene points, the viewing rays and the camera's path. The image plane shows the epipolar line of each
desired feature in the current image and the epipole (:func:`egtviz.servo.frames.pinhole_frames`). Run fields
beside the shared ones (:class:`~egtviz.viewer.servo.servo_player.ServoPlayer`): beta and the F estimator. The model,
its run parameters and its simulation are :class:`~egtviz.controllers.servo_demos.PinholeServoModel`.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, ClassVar, cast

import numpy as np
import viser

from egtviz.controllers.servo_demos import PinholeServoModel, puma_chain
from egtviz.servo.pinhole_arm import TARGET_Q, puma

from .servo_nodes import ServoNodes, pose_node
from .servo_player import ServoPlayer

__all__ = ["PinholeServoDemo", "PumaNodes", "puma_meshes"]


@lru_cache(maxsize=1)
def puma_meshes() -> list[tuple[np.ndarray, np.ndarray]] | None:
    """``(vertices, faces)`` of the Puma 560's 7 link meshes (base, links 1-6) from rtb-data, or ``None``.

    Offline: the STL files ship with the ``rtb-data`` package; nothing is downloaded.
    Mesh ``j`` is drawn at link frame ``j`` of :meth:`DHChain.link_poses` (0 = base).
    """
    try:
        import trimesh

        robot, _ = puma()
        paths = [robot.basemesh] + [link.mesh for link in robot.links]
        if any(p is None for p in paths):
            return None
        out = []
        for p in paths:
            m = cast(trimesh.Trimesh, trimesh.load(str(p), force="mesh"))  # force="mesh": one Trimesh
            out.append((np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)))
        return out
    except Exception:  # noqa: BLE001 - no meshes: the stick figure is drawn instead
        return None


class PumaNodes:
    """The Puma 560 in 3D: its link meshes, or (without them) a stick figure of its link frames.

    Args:
        api: the tab's scene, to add the nodes under ``/servo/arm`` to.
    """

    def __init__(self, api: viser.SceneApi) -> None:
        meshes = puma_meshes()
        #: One mesh per link frame (base, links 1-6); empty if the meshes are missing.
        self.links: list[viser.MeshHandle] = []
        #: The stick figure's links and joints (``None`` when the meshes are drawn).
        self.sticks: viser.LineSegmentsHandle | None = None
        self.joints: viser.PointCloudHandle | None = None
        if meshes is not None:
            tone = [(95, 95, 105)] + [(170, 178, 190)] * 6
            self.links = [api.add_mesh_simple(f"/servo/arm/link{j}", v, f, color=tone[j], flat_shading=False)
                          for j, (v, f) in enumerate(meshes)]
        else:
            self.sticks = api.add_line_segments("/servo/arm/sticks", np.zeros((1, 2, 3), np.float32),
                                                (150, 150, 160), thickness=0.035)
            self.joints = api.add_point_cloud("/servo/arm/joints", np.zeros((1, 3), np.float32), (60, 60, 70),
                                              point_size=0.06, point_shape="circle")

    def pose(self, links: np.ndarray) -> None:
        """Place the link meshes (or the stick figure) at the link frames (J + 1, 4, 4)."""
        if self.links:
            for h, T in zip(self.links, links):
                pose_node(h, T)
        elif self.sticks is not None and self.joints is not None:
            P = links[:, :3, 3].astype(np.float32)
            self.sticks.points = np.stack([P[:-1], P[1:]], axis=1)
            self.joints.points = P


class PinholeServoDemo(ServoPlayer):
    """The pin-hole demo in one tab.

    Args:
        client: the viser client (tab) to draw in.
        beta: weight of the translation task (0: rotation only).
        estimator: F from the ``"true"`` poses or estimated (``"linear"``, ``"normalized"``, ``"sampson"``).
        **options: the shared ones of :class:`~egtviz.viewer.servo.servo_player.ServoPlayer` (seed, noise_px, steps,
            speed, autorun, autoplay, on_back, show_panel, field_delay).
    """

    TITLE: ClassVar[str] = "Visual servoing: pin-hole camera on a Puma 560"
    INTRO: ClassVar[str] = ("Rives' hybrid task: the *rotation* puts every feature on its epipolar line (priority "
                            "task), then the *translation* (weight beta) brings it to its desired position.")
    CONTROL_TITLE: ClassVar[str] = "Camera twist (camera frame): v solid, ω dashed"
    CONTROL_KEY: ClassVar[str] = "camera_twist"
    CONTROL_SERIES: ClassVar[tuple[tuple[str, str, str], ...]] = (
        ("v_x", "#0072B2", "v"), ("v_y", "#D55E00", "v"), ("v_z", "#009E73", "v"),
        ("ω_x", "#0072B2", "w"), ("ω_y", "#D55E00", "w"), ("ω_z", "#009E73", "w"))
    DASHED_RATES: ClassVar[bool] = True

    def __init__(self, client: viser.ClientHandle, *, beta: float = 1.0, estimator: str = "true",
                 **options: Any) -> None:
        #: The camera, the scene and the simulation.
        self.model = PinholeServoModel()
        super().__init__(client, self.model, beta=beta, estimator=estimator, **options)

    def _build_scene(self) -> ServoNodes:
        api = self.client.scene
        api.add_grid("/servo/grid", width=3.0, height=3.0, cell_size=0.1, section_size=0.5, position=(0.5, 0.0, 0.0))
        #: The arm's nodes.
        self.arm = PumaNodes(api)
        model = self.model
        fov, aspect = model.intrinsics.fov_y, model.intrinsics.aspect
        api.add_camera_frustum("/servo/target", fov=fov, aspect=aspect, scale=0.07, color=(0, 158, 115),
                               thickness=0.004, wxyz=model.target_pose.quat_wxyz, position=model.target_pose.t)
        # At the goal the camera sits on the target: their labels grow away from each other, never overlap.
        api.add_label("/servo/target/label", "target", position=(0.0, -0.06, 0.0), font_screen_scale=0.9,
                      anchor="bottom-right")
        camera = api.add_camera_frustum("/servo/camera", fov=fov, aspect=aspect, scale=0.07, color=(20, 20, 20),
                                        thickness=0.005)
        api.add_label("/servo/camera/label", "camera", position=(0.0, -0.06, 0.0), font_screen_scale=0.9,
                      anchor="bottom-left")
        nodes = self._add_common_nodes(camera, point_size=0.022, label_lift=0.02, label_scale=0.7, path_width=0.004,
                                       ray_width=0.0025)
        self.arm.pose(puma_chain().link_poses(TARGET_Q)[0])
        centre = 0.5 * (model.points.mean(axis=0) + model.target_pose.t)
        self._view(centre, centre + np.array([0.9, -1.6, 0.9]))
        return nodes

    def _add_run_fields(self) -> None:
        self.form.add_number_field("beta", "beta",
                                   "Weight of the translation (secondary) task, >= 0; 0 = rotation only.")
        self.form.add_choice_field("estimator", "F estimator",
                                   "F from the true poses, or estimated from the noisy features at every step.")

    def _draw_body(self, k: int) -> None:
        super()._draw_body(k)
        if self.frames is not None and self.frames.links is not None:
            self.arm.pose(self.frames.links[k])
