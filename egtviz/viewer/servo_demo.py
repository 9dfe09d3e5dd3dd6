"""The visual-servoing demos in the browser: one reusable unit per tab (EGT reference, section 7).

:class:`ServoDemo` owns everything it shows in one viser client (browser tab):

* 3D nodes under ``/servo/...``: the Puma 560 (rtb-data's link meshes, placed by
  forward kinematics; a stick figure if the meshes are missing) with its camera
  frustum and the target frustum, or the holonomic robot with its mirror and its
  ground trajectory; the scene points and the viewing rays;
* GUI: a *Run* folder (seed, beta, noise, F estimator, max steps, Run), a
  *Playback* folder (Play/Pause, step back/forward, speed, time scrubber) and a
  status line that shows a failed or non-converged run in words;
* a panel on the right: the image plane (SVG: current and desired features,
  feature trails, epipolar lines or bi-conics, epipoles, the mirror rim) and two
  uPlot charts (controls; errors on a log scale) revealed up to the current time.

The simulation (:mod:`egtviz.servo`) runs in a background thread when *Run* is
pressed, and the per-frame drawing data is derived there too
(:mod:`egtviz.viewer.servo_frames`): playback only formats and sends. A playback
thread advances the frame at the chosen speed and redraws inside
``client.atomic()``. :meth:`ServoDemo.close` stops both threads and removes
the demo's nodes and GUI.

Lessons load the unit and drive it::

    demo = ServoDemo(client, "pinhole", beta=0.0, autoplay=False)
    demo.on_result(lambda r: check(r))      # called after every finished run
    demo.set_params(beta=0.5); demo.run(wait=True); demo.seek_time(3.0); demo.play()
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from functools import lru_cache
from html import escape
from typing import Any, Literal

import numpy as np
import viser

from egtviz.geometry.poses import Pose, quat_wxyz_from_matrix
from egtviz.servo import ServoResult, simulate_panoramic, simulate_pinhole

from .fields import Debouncer, FieldError, NumberRule, describe_error, format_number, on_event, parse_numbers
from .palette import hex_to_rgb, point_colour
from .servo_frames import ServoFrames
from .servo_svg import ServoImage, servo_image_svg, trail_indices

__all__ = ["ServoDemo", "DemoKind", "ESTIMATOR_CHOICES", "SPEEDS"]

DemoKind = Literal["pinhole", "panoramic"]
ESTIMATOR_CHOICES = {"true": None, "linear": 1, "normalized": 2, "sampson": 3}
SPEEDS = ("0.25x", "0.5x", "1x", "2x", "4x")
PANEL_WIDTH = 470
FPS = 15.0
#: Most samples per uPlot series sent per frame (the series are thinned, the newest sample kept).
PLOT_SAMPLES = 300
#: The panoramic mirror (2 cm rim) is drawn this much larger in 3D, so that it can be seen.
MIRROR_DRAW_SCALE = 4.0
#: Most simulation steps a run may take (the demos converge in a few hundred).
MAX_STEPS = 10_000
#: What each run field accepts; a refused value gets a notification and the field shows the last valid one.
RUN_RULES = {
    "seed": NumberRule("seed", "", 0, 2**32 - 1, integer=True),
    "beta": NumberRule("beta", "", 0.0, 100.0),
    "noise_px": NumberRule("noise", "px", 0.0, 50.0),
    "steps": NumberRule("max steps", "", 1, MAX_STEPS, integer=True),
}
#: Seconds a run field must stay unchanged before it is judged (see ``fields.Debouncer``).
FIELD_DELAY = 0.6

_TITLES = {
    "pinhole": ("Visual servoing: pin-hole camera on a Puma 560",
                "Rives' hybrid task: the *rotation* puts every feature on its epipolar line (priority task), "
                "then the *translation* (weight beta) brings it to its desired position."),
    "panoramic": ("Visual servoing: panoramic camera on a mobile robot",
                  "Step 1 turns the robot until all bi-conics meet in the two epipoles (same orientation); "
                  "step 2 translates along the baseline until s(t), the feature distance, is zero."),
}


def _rgb(colour: str) -> tuple[int, int, int]:
    return hex_to_rgb(colour)


@lru_cache(maxsize=1)
def puma_meshes() -> list[tuple[np.ndarray, np.ndarray]] | None:
    """``(vertices, faces)`` of the Puma 560's 7 link meshes (base, links 1-6) from rtb-data, or ``None``.

    Offline: the STL files ship with the ``rtb-data`` package; nothing is downloaded.
    Mesh ``j`` is drawn at ``robot.fkine_all(q)[j]`` (0 = base).
    """
    try:
        import trimesh

        from egtviz.servo.pinhole_arm import puma

        robot, _ = puma()
        paths = [robot.basemesh] + [link.mesh for link in robot.links]
        if any(p is None for p in paths):
            return None
        out = []
        for p in paths:
            m = trimesh.load(str(p), force="mesh")
            out.append((np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)))
        return out
    except Exception:  # noqa: BLE001 - no meshes: the stick figure is drawn instead
        return None


def _checked_number(key: str, value: Any) -> float | int:
    """A run parameter given in code (a number or a field's text), checked by its rule in :data:`RUN_RULES`."""
    rule = RUN_RULES[key]
    if isinstance(value, str):
        (number,) = parse_numbers(value, (rule,))
    elif isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise FieldError(f"{rule.label}: expected a number, got {type(value).__name__}")
    else:
        number = rule.check(float(value))
    return int(number) if rule.integer else float(number)


def _thin(k: int, limit: int = PLOT_SAMPLES) -> np.ndarray:
    return trail_indices(k, limit)


class ServoDemo:
    """One servo demo in one browser tab: its scene, its controls and its playback.

    Args:
        client: the viser client (tab) to draw in.
        kind: ``"pinhole"`` (Puma 560, Rives' hybrid task) or ``"panoramic"`` (holonomic robot, bi-conics).
        seed: start pose / noise seed.
        beta: weight of the translation task (pin-hole).
        noise_px: image noise, pixels.
        estimator: F from the ``"true"`` poses or estimated (``"linear"``, ``"normalized"``, ``"sampson"``; pin-hole).
        steps: maximum number of simulation steps (``None``: the simulation's default).
        speed: playback speed, one of :data:`SPEEDS`.
        autorun: start a run at once (in the background).
        autoplay: play each run as soon as it is ready.
        on_back: if given, a "Back" button calls it (the app uses it to return to the workbench).
        show_panel: add the right-hand panel (image plane and plots).
        field_delay: seconds a run field must stay unchanged before it is judged (0: at once).

    Raises:
        ValueError: a parameter outside :data:`RUN_RULES`, an unknown estimator or speed.
    """

    def __init__(
        self,
        client: viser.ClientHandle,
        kind: DemoKind,
        *,
        seed: int = 0,
        beta: float = 1.0,
        noise_px: float = 0.0,
        estimator: str = "true",
        steps: int | None = None,
        speed: str = "1x",
        autorun: bool = True,
        autoplay: bool = True,
        on_back: Callable[[], None] | None = None,
        show_panel: bool = True,
        field_delay: float = FIELD_DELAY,
    ) -> None:
        if kind not in ("pinhole", "panoramic"):
            raise ValueError(f"kind: expected 'pinhole' or 'panoramic', got {kind!r}")
        if estimator not in ESTIMATOR_CHOICES:
            raise ValueError(f"estimator: expected one of {list(ESTIMATOR_CHOICES)}, got {estimator!r}")
        if speed not in SPEEDS:
            raise ValueError(f"speed: expected one of {list(SPEEDS)}, got {speed!r}")
        if steps is None:
            steps = 1000 if kind == "pinhole" else 1500
        #: The last valid value of each run field (what Run uses), in the fields' units.
        self._values: dict[str, Any] = {"estimator": estimator, "speed": speed}
        for key, value in (("seed", seed), ("beta", beta), ("noise_px", noise_px), ("steps", steps)):
            self._values[key] = _checked_number(key, value)
        self._typing = Debouncer(field_delay)
        self.client = client
        self.kind: DemoKind = kind
        self.autoplay = autoplay
        self.lock = threading.RLock()
        self._closed = threading.Event()
        self._syncing = False
        self._sim_gen = 0
        self._play_gen = 0
        self._sim_thread: threading.Thread | None = None
        self._play_thread: threading.Thread | None = None
        self._listeners: list[Callable[[ServoResult], None]] = []
        self._on_back = on_back
        #: The last finished run (``None`` before the first one or after a failed one).
        self.result: ServoResult | None = None
        self.frames: ServoFrames | None = None
        self._links: np.ndarray | None = None
        #: The frame shown (index into ``result.time``).
        self.frame = 0
        self.playing = False
        self.running = False
        #: The last error message of a run that raised (bad parameters), else "".
        self.error = ""
        #: The SVG of the image panel as last sent.
        self.svg = ""
        self.revision = 0
        self._setup_model()
        with self.lock, client.atomic():
            self._build_scene()
            self._build_gui()
            if show_panel:
                self._build_panel()
            else:
                self.panel = None
                self.image_html = None
                self.plot_controls = None
                self.plot_errors = None
            self._draw_idle("press Run to simulate")
        if autorun:
            self.run()

    # -- model of the demo (camera, target, scene) ------------------------------------

    def _setup_model(self) -> None:
        if self.kind == "pinhole":
            from egtviz.servo.pinhole_arm import TARGET_Q, camera_pose_from_q, default_intrinsics, default_scene

            self.intrinsics = default_intrinsics()
            self.camera_model = None
            self.target_pose = camera_pose_from_q(TARGET_Q)
            self.points = default_scene(self.target_pose)
            self.width, self.height = self.intrinsics.width, self.intrinsics.height
        else:
            from egtviz.servo.panoramic_robot import default_camera, default_scene, mirror_pose

            self.intrinsics = None
            self.camera_model = default_camera()
            self.target_state = np.zeros(3)
            self.target_pose = mirror_pose(self.target_state)
            self.points = default_scene()
            self.width, self.height = self.camera_model.width, self.camera_model.height

    # -- 3D scene ---------------------------------------------------------------------

    def _build_scene(self) -> None:
        api = self.client.scene
        cols = np.array([_rgb(point_colour(i)) for i in range(len(self.points))], np.uint8)
        self.nodes: dict[str, Any] = {}
        n = self.nodes
        if self.kind == "pinhole":
            api.add_grid("/servo/grid", width=3.0, height=3.0, cell_size=0.1, section_size=0.5,
                         position=(0.5, 0.0, 0.0))
            meshes = puma_meshes()
            self._has_meshes = meshes is not None
            if meshes is not None:
                tone = [(95, 95, 105)] + [(170, 178, 190)] * 6
                n["links"] = [api.add_mesh_simple(f"/servo/arm/link{j}", v, f, color=tone[j], flat_shading=False)
                              for j, (v, f) in enumerate(meshes)]
            else:
                n["sticks"] = api.add_line_segments("/servo/arm/sticks", np.zeros((1, 2, 3), np.float32),
                                                    (150, 150, 160), thickness=0.035)
                n["joints"] = api.add_point_cloud("/servo/arm/joints", np.zeros((1, 3), np.float32),
                                                  (60, 60, 70), point_size=0.06, point_shape="circle")
            fov = self.intrinsics.fov_y
            aspect = self.intrinsics.aspect
            n["target"] = api.add_camera_frustum("/servo/target", fov=fov, aspect=aspect, scale=0.07,
                                                 color=(0, 158, 115), thickness=0.004,
                                                 wxyz=self.target_pose.quat_wxyz, position=self.target_pose.t)
            api.add_label("/servo/target/label", "target", position=(0.0, -0.06, 0.0), font_screen_scale=0.9)
            n["camera"] = api.add_camera_frustum("/servo/camera", fov=fov, aspect=aspect, scale=0.07,
                                                 color=(20, 20, 20), thickness=0.005)
            api.add_label("/servo/camera/label", "camera", position=(0.0, -0.06, 0.0), font_screen_scale=0.9)
            n["points"] = api.add_point_cloud("/servo/points", self.points.astype(np.float32), cols,
                                              point_size=0.022, point_shape="circle")
            for i, X in enumerate(self.points):
                api.add_label(f"/servo/point_labels/{i}", str(i + 1), position=tuple(X + [0, 0, 0.02]),
                              font_screen_scale=0.7)
            n["path"] = api.add_line_segments("/servo/path", np.zeros((1, 2, 3), np.float32), (20, 20, 20),
                                              thickness=0.004)
            n["rays"] = api.add_line_segments("/servo/rays", np.zeros((1, 2, 3), np.float32), (120, 120, 120),
                                              thickness=0.0025)
            self._set_arm(None)
            centre = 0.5 * (self.points.mean(axis=0) + self.target_pose.t)
            self._view(centre, centre + np.array([0.9, -1.6, 0.9]))
        else:
            from egtviz.servo.panoramic_robot import CAMERA_HEIGHT

            import trimesh

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
            heading = trimesh.util.concatenate([arrow, shaft])
            mv, mf = self.camera_model.mirror.surface(n_radial=12, n_angular=48)
            mv = mv * MIRROR_DRAW_SCALE + np.array([0.0, 0.0, CAMERA_HEIGHT])

            def robot(root: str, colour, opacity):
                node = api.add_frame(root, show_axes=False)
                api.add_mesh_simple(f"{root}/body", body.vertices, body.faces, color=colour, opacity=opacity)
                api.add_mesh_simple(f"{root}/heading", heading.vertices, heading.faces, color=(213, 94, 0),
                                    opacity=opacity)
                api.add_mesh_simple(f"{root}/mast", mast.vertices, mast.faces, color=(90, 90, 90), opacity=opacity)
                api.add_mesh_simple(f"{root}/mirror", mv, mf, color=(200, 215, 230), opacity=opacity, side="double")
                return node

            n["target"] = robot("/servo/target", (0, 158, 115), 0.35)
            api.add_label("/servo/target/label", "target", position=(0.0, 0.0, 0.75), font_screen_scale=0.9)
            n["robot"] = robot("/servo/robot", (86, 110, 140), None)
            api.add_label("/servo/robot/label", "robot", position=(0.0, 0.0, 0.75), font_screen_scale=0.9)
            n["points"] = api.add_point_cloud("/servo/points", self.points.astype(np.float32), cols,
                                              point_size=0.09, point_shape="circle")
            for i, X in enumerate(self.points):
                api.add_label(f"/servo/point_labels/{i}", str(i + 1), position=tuple(X + [0, 0, 0.12]),
                              font_screen_scale=0.8)
            n["path"] = api.add_line_segments("/servo/path", np.zeros((1, 2, 3), np.float32), (20, 20, 20),
                                              thickness=0.025)
            n["rays"] = api.add_line_segments("/servo/rays", np.zeros((1, 2, 3), np.float32), (120, 120, 120),
                                              thickness=0.008)
            self._view(np.array([0.0, 0.0, 0.3]), np.array([2.0, -8.0, 6.0]))

    def _view(self, look_at: np.ndarray, position: np.ndarray) -> None:
        try:
            cam = self.client.camera
            cam.up_direction = (0.0, 0.0, 1.0)
            cam.position = tuple(float(x) for x in position)
            cam.look_at = tuple(float(x) for x in look_at)
        except Exception:  # noqa: BLE001 - camera placement is cosmetic
            pass

    def _set_arm(self, k: int | None) -> None:
        """Pose the arm at frame ``k`` (``None``: the target configuration)."""
        if self.kind != "pinhole":
            return
        if k is None or self._links is None:
            from egtviz.servo.pinhole_arm import TARGET_Q, puma

            links = np.asarray(puma()[0].fkine_all(TARGET_Q).A)
        else:
            links = self._links[k]
        if "links" in self.nodes:
            for j, h in enumerate(self.nodes["links"]):
                h.position = links[j][:3, 3]
                h.wxyz = quat_wxyz_from_matrix(links[j][:3, :3])
        else:
            P = np.array([T[:3, 3] for T in links], np.float32)
            self.nodes["sticks"].points = np.stack([P[:-1], P[1:]], axis=1)
            self.nodes["joints"].points = P

    # -- GUI ----------------------------------------------------------------------------

    def _on(self, register: Any, callback: Any) -> None:
        """Attach ``callback`` to a handle's event: whatever it raises reaches this tab (``fields.on_event``)."""
        on_event(register, callback, self.report)

    def _build_gui(self) -> None:
        gui = self.client.gui
        v = self._values
        gui.configure_theme(dark_mode=False, show_logo=False)
        try:
            gui.main_panel.dock_left()
            gui.main_panel.set_width(330)
        except Exception:  # noqa: BLE001 - placement is cosmetic
            pass
        title, text = _TITLES[self.kind]
        self.title_md = gui.add_markdown(f"**{title}**  \n{text}")
        if self._on_back is not None:
            self.btn_back = gui.add_button("Back to the epipolar workbench", icon=viser.Icon.ARROW_LEFT)
            self._on(self.btn_back.on_click, lambda _: self._back())
        else:
            self.btn_back = None
        self.folder_run = gui.add_folder("Run", expand_by_default=True)
        with self.folder_run:
            self.f_seed = gui.add_text("seed", format_number(v["seed"]),
                                       hint="Draws the start pose and the image noise: a whole number >= 0.")
            if self.kind == "pinhole":
                self.f_beta = gui.add_text("beta", format_number(v["beta"]),
                                           hint="Weight of the translation (secondary) task, >= 0; 0 = rotation only.")
                self.f_estimator = gui.add_dropdown("F estimator", tuple(ESTIMATOR_CHOICES), initial_value=v["estimator"],
                                                    hint="F from the true poses, or estimated from the noisy "
                                                         "features at every step.")
                self._on(self.f_estimator.on_update, lambda e: self._choice_event("estimator", e.target.value))
            else:
                self.f_beta = None
                self.f_estimator = None
            self.f_noise = gui.add_text("noise (px)", format_number(v["noise_px"]),
                                        hint="Standard deviation of the Gaussian pixel noise, >= 0.")
            self.f_steps = gui.add_text("max steps", format_number(v["steps"]),
                                        hint=f"1 to {MAX_STEPS}; the run stops earlier once the features reach "
                                             "their goal.")
            for key, handle in self._number_fields().items():
                self._on(handle.on_update, lambda e, key=key: self._text_event(key, e.target.value))
            self.btn_run = gui.add_button("Run", icon=viser.Icon.PLAYER_PLAY)
            self._on(self.btn_run.on_click, lambda _: self.run())
            self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        self.status = gui.add_html("")
        self.folder_play = gui.add_folder("Playback", expand_by_default=True)
        with self.folder_play:
            self.btn_play = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY)
            self._on(self.btn_play.on_click, lambda _: self.toggle_play())
            self.btn_step_back = gui.add_button("Step back", icon=viser.Icon.PLAYER_TRACK_PREV)
            self._on(self.btn_step_back.on_click, lambda _: self.step(-1))
            self.btn_step = gui.add_button("Step", icon=viser.Icon.PLAYER_TRACK_NEXT)
            self._on(self.btn_step.on_click, lambda _: self.step(1))
            self.f_speed = gui.add_dropdown("speed", SPEEDS, initial_value=v["speed"],
                                            hint="Simulated seconds per real second.")
            self._on(self.f_speed.on_update, lambda e: self._choice_event("speed", e.target.value))
            self.slider = gui.add_slider("time (s)", min=0.0, max=1.0, step=0.05, initial_value=0.0,
                                         hint="Drag to any time of the run.")
            self._on(self.slider.on_update, self._slider_event)
        self.readout = gui.add_html("")

    def _number_fields(self) -> dict[str, Any]:
        fields = {"seed": self.f_seed, "beta": self.f_beta, "noise_px": self.f_noise, "steps": self.f_steps}
        return {k: h for k, h in fields.items() if h is not None}

    # -- field events ----------------------------------------------------------------------

    def _text_event(self, key: str, text: Any) -> None:
        """A run field changed: judge its text once the user stopped typing (latest text wins)."""
        if self._syncing or self._closed.is_set():
            return

        def judge() -> None:
            try:
                with self.lock:
                    if self._syncing or self._closed.is_set():
                        return
                    (value,) = parse_numbers(text, (RUN_RULES[key],))
                    self._values[key] = int(value) if RUN_RULES[key].integer else value
            except Exception as exc:  # noqa: BLE001 - from a timer thread: no callback wrapper above us
                self.report(exc)

        self._typing.submit(key, judge)

    def _choice_event(self, key: str, value: Any) -> None:
        choices = ESTIMATOR_CHOICES if key == "estimator" else SPEEDS
        with self.lock:
            if self._syncing or self._closed.is_set():
                return
            if value not in choices:  # a raw client can send any string
                label = "F estimator" if key == "estimator" else "speed"
                shown = "".join(c if c.isprintable() else "?" for c in repr(value))[:40]
                raise FieldError(f"{label}: expected one of {', '.join(choices)}, got {shown}")
            self._values[key] = value

    def report(self, exc: BaseException) -> None:
        """Tell this tab what went wrong and show the last valid value in every run field."""
        title, body = describe_error(exc)
        with self.lock:
            if self._closed.is_set():
                return
            try:
                self.client.add_notification(title, body, color="red", auto_close_seconds=8.0)
            except Exception:  # noqa: BLE001 - the client may be gone
                pass
            self._sync_fields()

    def _sync_fields(self) -> None:
        """Write the last valid run parameters into the fields (not user edits)."""
        self._syncing = True
        try:
            for key, handle in self._number_fields().items():
                text = format_number(self._values[key])
                if handle.value != text:
                    handle.value = text
            for key, handle in (("estimator", self.f_estimator), ("speed", self.f_speed)):
                if handle is not None and handle.value != self._values[key]:
                    handle.value = self._values[key]
            shown = float(min(self.time, self.slider.max))
            if self.slider.value != shown:
                self.slider.value = shown
        finally:
            self._syncing = False

    def _build_panel(self) -> None:
        gui = self.client.gui
        self.panel = gui.add_panel()
        with self.panel.add_tab("Image plane and plots"):
            self.image_html = gui.add_html("")
            if self.kind == "pinhole":
                series = [("v_x", "#0072B2", "v"), ("v_y", "#D55E00", "v"), ("v_z", "#009E73", "v"),
                          ("ω_x", "#0072B2", "w"), ("ω_y", "#D55E00", "w"), ("ω_z", "#009E73", "w")]
                ctitle = "Camera twist (camera frame): v solid, ω dashed"
            else:
                series = [("v_x", "#0072B2", "v"), ("v_y", "#D55E00", "v"), ("ω (right axis)", "#009E73", "w")]
                ctitle = "Robot velocity (robot frame)"
            self._control_series = series
            self.plot_controls = self._uplot(ctitle, series, dual=True)
            ename = "s(t)" if self.kind == "panoramic" else "features"
            eseries = [("rotation", "#D55E00", "e"), ("translation", "#0072B2", "e"), (ename, "#CC79A7", "e")]
            self._error_series = eseries
            self.plot_errors = self._uplot("Errors, % of their start value", eseries, dual=False)
        self.panel.dock_right()
        self.panel.set_width(PANEL_WIDTH)

    def _uplot(self, title: str, series: list[tuple[str, str, str]], *, dual: bool, t_end: float = 1.0):
        from viser import uplot

        ser = [uplot.Series(label="t (s)")]
        for label, colour, scale in series:
            s = uplot.Series(label=label, stroke=colour, width=1.6, scale=scale)
            if scale == "w" and self.kind == "pinhole":
                s["dash"] = [6, 4]
            ser.append(s)
        if dual:
            scales = {"x": uplot.Scale(time=False, auto=False, range=(0.0, t_end)), "v": uplot.Scale(auto=True),
                      "w": uplot.Scale(auto=True)}
            vlab = "v (m/s)"
            axes = (uplot.Axis(label="t (s)"), uplot.Axis(scale="v", label=vlab),
                    uplot.Axis(scale="w", side=1, label="ω (rad/s)", grid={"show": False}))
        else:
            scales = {"x": uplot.Scale(time=False, auto=False, range=(0.0, t_end)),
                      "e": uplot.Scale(auto=False, range=(0.0, 105.0))}
            axes = (uplot.Axis(label="t (s)"), uplot.Axis(scale="e", label="%"))
        data = tuple([np.zeros(1)] + [np.full(1, np.nan) for _ in series])
        return self.client.gui.add_uplot(data, tuple(ser), title=title, scales=scales, axes=axes, height=140,
                                         legend=uplot.Legend(show=True), aspect=2.0)

    # -- public control ------------------------------------------------------------------

    def on_result(self, callback: Callable[[ServoResult], None]) -> None:
        """Call ``callback(result)`` after every finished run (lessons check their tasks here)."""
        self._listeners.append(callback)

    def set_params(self, **params: Any) -> None:
        """Set run parameters (and their fields): ``seed``, ``beta``, ``noise_px``, ``estimator``, ``steps``, ``speed``.

        Raises:
            ValueError: an unknown parameter or one the demo does not use, or a value outside :data:`RUN_RULES`;
                nothing is changed then.
        """
        known = {"seed", "noise_px", "steps", "speed"} | ({"beta", "estimator"} if self.kind == "pinhole" else set())
        new = dict(self._values)
        for key, value in params.items():
            if key not in known:
                raise ValueError(f"{key}: not a parameter of the {self.kind} demo")
            if key == "estimator" and value not in ESTIMATOR_CHOICES:
                raise ValueError(f"estimator: expected one of {list(ESTIMATOR_CHOICES)}, got {value!r}")
            if key == "speed" and value not in SPEEDS:
                raise ValueError(f"speed: expected one of {list(SPEEDS)}, got {value!r}")
            new[key] = value if key in ("estimator", "speed") else _checked_number(key, value)
        with self.lock:
            self._values = new
            self._sync_fields()

    def params(self) -> dict[str, Any]:
        """The run parameters the next run uses (the keyword arguments of the simulation)."""
        v = self._values
        kw: dict[str, Any] = {"seed": int(v["seed"]), "noise_px": float(v["noise_px"]), "steps": int(v["steps"])}
        if self.kind == "pinhole":
            kw["beta"] = float(v["beta"])
            kw["f_algorithm"] = ESTIMATOR_CHOICES[v["estimator"]]
        return kw

    @property
    def n_frames(self) -> int:
        return 0 if self.result is None else self.result.n_samples

    @property
    def time(self) -> float:
        """Simulated time of the frame shown."""
        return 0.0 if self.result is None else float(self.result.time[self.frame])

    def run(self, *, wait: bool = False, timeout: float = 60.0) -> bool:
        """Start a simulation with the GUI's parameters in a background thread; ``False`` if one is running.

        With ``wait`` the call blocks until the run is drawn (or failed).
        """
        with self.lock:
            if self._closed.is_set() or self.running:
                return False
            self.pause()
            self.running = True
            self._sim_gen += 1
            gen = self._sim_gen
            kw = self.params()
            self.btn_run.disabled = True
            self.progress.value = 0.0
            self.progress.visible = True
            self.status.content = self._status_html("running", "Simulating ...")
        self._sim_thread = threading.Thread(target=self._simulate, args=(gen, kw), daemon=True,
                                            name=f"servo-sim-{self.kind}")
        self._sim_thread.start()
        if wait:
            return self.wait(timeout)
        return True

    def wait(self, timeout: float = 60.0) -> bool:
        """Block until no run is in progress; ``True`` if it finished in time."""
        t = self._sim_thread
        if t is not None:
            t.join(timeout)
            return not t.is_alive()
        return True

    def play(self) -> None:
        """Play from the current frame (from the start if at the end)."""
        with self.lock:
            if self._closed.is_set() or self.result is None or self.playing:
                return
            if self.frame >= self.n_frames - 1:
                self._show(0)
            self.playing = True
            self._play_gen += 1
            gen = self._play_gen
            self.btn_play.label = "Pause"
            self.btn_play.icon = viser.Icon.PLAYER_PAUSE
        self._play_thread = threading.Thread(target=self._loop, args=(gen,), daemon=True,
                                             name=f"servo-play-{self.kind}")
        self._play_thread.start()

    def pause(self) -> None:
        with self.lock:
            self._play_gen += 1
            if self.playing:
                self.playing = False
                if not self._closed.is_set():
                    self.btn_play.label = "Play"
                    self.btn_play.icon = viser.Icon.PLAYER_PLAY

    def toggle_play(self) -> None:
        with self.lock:
            if self.playing:
                self.pause()
            else:
                self.play()

    def step(self, n: int = 1) -> None:
        """Pause and move ``n`` frames (negative: back)."""
        with self.lock:
            self.pause()
            if self.result is not None:
                self._show(int(np.clip(self.frame + n, 0, self.n_frames - 1)))

    def seek(self, frame: int) -> None:
        """Show frame ``frame`` (clipped to the run)."""
        with self.lock:
            if self.result is not None:
                self._show(int(np.clip(frame, 0, self.n_frames - 1)))

    def seek_time(self, t: float) -> None:
        """Show the frame at simulated time ``t`` (the nearest sample)."""
        with self.lock:
            if self.result is not None:
                self._show(int(np.argmin(np.abs(self.result.time - float(t)))))

    def close(self, *, client_gone: bool = False) -> None:
        """Stop the threads and remove the demo's 3D nodes and GUI (not when the tab is gone). Idempotent."""
        with self.lock:
            if self._closed.is_set():
                return
            self._closed.set()
            self._typing.close()
            self._play_gen += 1
            self._sim_gen += 1
            self.playing = False
        for t in (self._play_thread, self._sim_thread):
            if t is not None and t is not threading.current_thread():
                t.join(2.0)
        if client_gone:
            return  # nothing to remove in a page that no longer exists
        try:
            with self.client.atomic():
                self.client.scene.remove_by_name("/servo")
                for h in (self.title_md, self.btn_back, self.folder_run, self.status, self.folder_play,
                          self.readout, self.panel):
                    if h is not None:
                        h.remove()
        except Exception:  # noqa: BLE001 - the client may be gone already
            pass

    @property
    def closed(self) -> bool:
        return self._closed.is_set()

    # -- background work ---------------------------------------------------------------

    def _simulate(self, gen: int, kw: dict[str, Any]) -> None:
        stale = lambda: self._closed.is_set() or gen != self._sim_gen  # noqa: E731

        def progress(step: int, steps: int) -> None:
            if not stale():
                self.progress.value = float(min(100.0, 100.0 * step / max(steps, 1)))

        result = frames = links = None
        error = ""
        try:
            if self.kind == "pinhole":
                result = simulate_pinhole(**kw, progress=progress)
            else:
                result = simulate_panoramic(**kw, camera=self.camera_model, progress=progress)
            frames = ServoFrames(result, target_pose=self._target_pose_of(result),
                                 pinhole_intrinsics=self.intrinsics, camera=self.camera_model)
            frames.precompute(stop=stale)
            if self.kind == "pinhole" and result.joint_angles is not None:
                from egtviz.servo.pinhole_arm import puma

                robot = puma()[0]
                links = np.stack([np.asarray(robot.fkine_all(q).A) for q in result.joint_angles])
        except (ValueError, TypeError) as exc:
            error = f"Bad parameters: {exc}"
        except Exception as exc:  # noqa: BLE001 - shown in the UI, never a traceback
            error = f"The simulation failed: {type(exc).__name__}: {exc}"
        with self.lock:
            if stale():
                return
            self.running = False
            with self.client.atomic():
                self.btn_run.disabled = False
                self.progress.visible = False
                if error:
                    self.error = error
                    self.result = None
                    self.frames = None
                    self.status.content = self._status_html("error", error)
                    self._draw_idle(error, colour="#a00")
                else:
                    self.error = ""
                    self.result, self.frames, self._links = result, frames, links
                    self._install_result()
            if error:
                try:
                    self.client.add_notification("Servo run failed", error, color="red", auto_close_seconds=8.0)
                except Exception:  # noqa: BLE001
                    pass
                return
        for cb in list(self._listeners):
            try:
                cb(result)
            except Exception as exc:  # noqa: BLE001 - a lesson's callback must not kill the demo
                self.status.content = self._status_html("error", f"lesson check failed: {exc}")
        if self.autoplay:
            self.play()

    def _target_pose_of(self, result: ServoResult) -> Pose:
        if self.kind == "pinhole" and "target_pose" in result.extras:
            return Pose.from_matrix(result.extras["target_pose"])
        return self.target_pose

    def _install_result(self) -> None:
        r = self.result
        assert r is not None
        t_end = float(r.time[-1]) if r.n_samples > 1 else 1.0
        self._syncing = True
        try:
            self.slider.max = max(t_end, float(r.params.get("dt", 0.05)))
            self.slider.step = float(r.params.get("dt", 0.05))
            self.slider.value = 0.0
        finally:
            self._syncing = False
        if self.plot_errors is not None:
            e = r.errors
            starts = (f"{math.degrees(e['rotation_error_rad'][0]):.3g}°", f"{100 * e['translation_error'][0]:.3g} cm",
                      f"{e['feature_error_px'][0]:.3g} px")
            ser = list(self.plot_errors.series)
            for j, ((label, _, _), s0) in enumerate(zip(self._error_series, starts)):
                ser[j + 1] = {**ser[j + 1], "label": f"{label} (100% = {s0})"}
            self.plot_errors.series = tuple(ser)
        for plot in (self.plot_controls, self.plot_errors):
            if plot is not None:
                scales = dict(plot.scales)
                scales["x"] = {"time": False, "auto": False, "range": (0.0, t_end)}
                plot.scales = scales
        if r.converged:
            msg = (f"Converged in {r.sim_time_s:.2f} s ({r.steps} steps): rotation error "
                   f"{math.degrees(r.final_rotation_error_rad):.3g} deg, translation error "
                   f"{100 * r.final_translation_error:.3g} cm.")
            self.status.content = self._status_html("ok", msg)
        else:
            self.status.content = self._status_html("warn", f"Did not converge: {r.reason}")
        self._show(0)

    def _loop(self, gen: int) -> None:
        t_last = time.perf_counter()
        with self.lock:
            pos = float(self.frame)
        while not self._closed.wait(1.0 / FPS):
            with self.lock:
                if gen != self._play_gen or not self.playing or self.result is None:
                    return
                now = time.perf_counter()
                dt = float(self.result.params.get("dt", 0.05))
                speed = float(self._values["speed"].rstrip("x"))
                pos += (now - t_last) * speed / dt
                t_last = now
                last = self.n_frames - 1
                k = min(int(pos), last)
                if k != self.frame:
                    self._show(k)
                if k >= last:
                    self.playing = False
                    self.btn_play.label = "Play"
                    self.btn_play.icon = viser.Icon.PLAYER_PLAY
                    return

    def _slider_event(self, event: Any) -> None:
        with self.lock:
            if self._syncing or self._closed.is_set() or self.result is None:
                return
            t = self.slider.value
            if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
                raise FieldError(f"time: expected a number of seconds, got {repr(t)[:40]}")
            self.pause()
            k = int(np.argmin(np.abs(self.result.time - float(t))))
            if k != self.frame:
                self._show(k)

    def _back(self) -> None:
        cb = self._on_back
        if cb is not None:
            cb()

    # -- drawing ------------------------------------------------------------------------

    @staticmethod
    def _status_html(level: str, text: str) -> str:
        colour = {"ok": "#1a7f37", "warn": "#b35900", "error": "#b00020", "running": "#555"}[level]
        return (f'<div data-egtviz="servo-status" data-level="{level}" style="font-size:0.85em;color:{colour};'
                f'padding:2px 0"><b>{escape(text)}</b></div>')

    def _draw_idle(self, message: str, colour: str = "#555") -> None:
        n = len(self.points)
        img = ServoImage(demo=self.kind, width=self.width, height=self.height, frame=0,
                         current=np.full((n, 2), np.nan), desired=np.full((n, 2), np.nan),
                         trails=np.zeros((0, n, 2)), rim=self._rim(), message=message, message_colour=colour)
        self._send_svg(img)

    def _rim(self) -> np.ndarray | None:
        return None if self.camera_model is None else self.camera_model.rim_image()

    def _send_svg(self, img: ServoImage) -> None:
        self.revision += 1
        self.svg = servo_image_svg(img, revision=self.revision, max_height="calc(100vh - 500px)")
        if self.image_html is not None:
            self.image_html.content = self.svg

    def _show(self, k: int) -> None:
        """Draw frame ``k`` everywhere, in one atomic update (call with the lock held)."""
        r, frames = self.result, self.frames
        if r is None or frames is None or self._closed.is_set():
            return
        self.frame = k
        g = frames.at(k)
        idx = trail_indices(k)
        phase = ""
        if self.kind == "panoramic" and "phase" in r.extras and k < len(r.extras["phase"]):
            ph = r.extras["phase"][k]
            if np.isfinite(ph):
                phase = "  step 1: rotation" if int(ph) == 1 else "  step 2: translation"
        caption = f"t = {r.time[k]:.2f} s{phase}"
        message = g.message
        if k == r.n_samples - 1 and not r.converged:
            message = "did not converge (see the status on the left)"
        img = ServoImage(demo=self.kind, width=self.width, height=self.height, frame=k, current=r.features[k],
                         desired=r.desired_features, trails=r.features[idx], lines=g.lines, conics=g.conics,
                         epipoles=g.epipoles, rim=frames.rim, caption=caption, message=message)
        with self.client.atomic():
            self._send_svg(img)
            self._draw_3d(k)
            self._draw_plots(k)
            self._syncing = True
            try:
                self.slider.value = float(min(r.time[k], self.slider.max))
            finally:
                self._syncing = False
            e = r.errors
            self.readout.content = (
                f'<div style="font-size:0.82em" data-egtviz="servo-readout">frame {k + 1} / {r.n_samples}, '
                f"t = {r.time[k]:.2f} s<br>rotation error {math.degrees(e['rotation_error_rad'][k]):.3g} deg, "
                f"translation error {100 * e['translation_error'][k]:.3g} cm, "
                f"feature error {e['feature_error_px'][k]:.3g} px</div>")

    def _draw_3d(self, k: int) -> None:
        r = self.result
        n = self.nodes
        H = r.camera_poses[: k + 1]
        if self.kind == "pinhole":
            self._set_arm(k)
            Hk = r.camera_poses[k]
            n["camera"].position = Hk[:3, 3]
            n["camera"].wxyz = quat_wxyz_from_matrix(Hk[:3, :3])
            C = H[:, :3, 3]
        else:
            x, y, th = r.states[k]
            n["robot"].position = (float(x), float(y), 0.0)
            n["robot"].wxyz = quat_wxyz_from_matrix(np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0],
                                              [0, 0, 1.0]]))
            C = np.column_stack([r.states[: k + 1, :2], np.full(k + 1, 0.01)])
        idx = trail_indices(k, 400)
        C = C[idx]
        if len(C) >= 2:
            n["path"].points = np.stack([C[:-1], C[1:]], axis=1).astype(np.float32)
        else:
            n["path"].points = np.zeros((1, 2, 3), np.float32)
        c = r.camera_poses[k][:3, 3]
        seen = np.all(np.isfinite(r.features[k]), axis=1)
        P = self.points[seen]
        if len(P):
            segs = np.stack([np.broadcast_to(c, P.shape), P], axis=1).astype(np.float32)
            cols = np.array([_rgb(point_colour(i)) for i in np.flatnonzero(seen)], np.uint8)
            n["rays"].points = segs
            n["rays"].colors = np.repeat(cols[:, None, :], 2, axis=1)
        else:
            n["rays"].points = np.zeros((1, 2, 3), np.float32)

    def _draw_plots(self, k: int) -> None:
        if self.plot_controls is None:
            return
        r = self.result
        idx = _thin(k)
        t = r.time[idx]
        if self.kind == "pinhole":
            u = r.controls["camera_twist"][idx]
        else:
            u = r.controls["robot_velocity"][idx]
        self.plot_controls.data = (t, *[u[:, j] for j in range(u.shape[1])])
        e = r.errors

        def pct(x: np.ndarray) -> np.ndarray:
            x0 = float(x[0]) if np.isfinite(x[0]) and x[0] > 0 else 1.0
            return 100.0 * x[idx] / x0

        self.plot_errors.data = (t, pct(e["rotation_error_rad"]), pct(e["translation_error"]),
                                 pct(e["feature_error_px"]))
