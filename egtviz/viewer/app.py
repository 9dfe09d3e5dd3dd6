"""The interactive viewer: one ``SceneModel`` and one ``ClientView`` per browser tab.

Data flow (one direction)::

    GUI field / gizmo  ->  SceneModel (validates)  ->  notification
        ->  compute_derived(scene)  ->  one `client.atomic()` update of the 3D
            scene, every image-plane panel, the F/E read-out and the fields.

Each browser tab has its own model: edits in one tab never reach another.
Every event handler and every render runs under the view's lock, and a render
always draws the model's *current* scene, so an event that arrives late (viser
runs callbacks in a thread pool) cannot overwrite a newer state. GUI fields are
written back under a guard so that the write does not look like a user edit.
"""

from __future__ import annotations

import atexit
import gc
import itertools
import threading
import time
from collections import deque
from html import escape
from typing import Any

import numpy as np
import viser

from ..geometry.poses import matrix_from_quat_wxyz
from ..scene import (
    Scene,
    SceneError,
    SceneFileError,
    SceneModel,
    SurfaceSpec,
    compute_derived,
    default_scene,
)
from .svg import empty_svg, image_plane_svg
from .svg import warm_up as svg_warm_up

__all__ = ["EgtvizApp", "ClientView"]

PANEL_WIDTH = 430
CONTROL_WIDTH = 330

EGT_PINHOLE_HINT = (
    "EGT convention (f_Rt2H): yaw, pitch, roll turn the camera about its own axes "
    "(x right, y down, z = optical axis): R = roty(yaw) rotx(pitch) rotz(roll), then H = [rotx(-90) R, t]. "
    "All zero: looking along world +y."
)
EGT_PANORAMIC_HINT = (
    "Mirror frame: z = mirror axis. R = rotz(yaw) roty(pitch) rotx(roll); all zero: an upright mirror."
)


def _fmt_matrix(M: np.ndarray) -> str:
    rows = ["  ".join(f"{v: .4e}" for v in row) for row in np.asarray(M)]
    return "\n".join(rows)


def _fmt_vec(v: np.ndarray | None) -> str:
    if v is None:
        return "-"
    v = np.asarray(v, float)
    if abs(v[2]) < 1e-12:
        return f"({v[0]:.3g}, {v[1]:.3g}, 0) (at infinity)"
    return f"({v[0] / v[2]:.1f}, {v[1] / v[2]:.1f}) px"


def pair_html(derived: Any) -> str:
    """The F / E read-out of the drawn pair (HTML: cheaper for the browser than re-parsing markdown per drag step)."""
    p = derived.pair
    style = "font-size:0.82em;line-height:1.35"
    if p.names is None:
        return f'<div style="{style}"><b>Epipolar geometry</b>: add a second camera to see it.</div>'
    law = "<code>m2&#7488; F m1 = 0</code>" if p.F is not None else ""
    head = (f'<div style="{style}" data-egtviz="readout"><b>Drawn pair {escape(p.names[0])} &rarr; '
            f"{escape(p.names[1])}</b>&nbsp; {law}<br>")
    if p.message:
        return f'{head}<b style="color:#a00">{escape(p.message)}</b></div>'
    if p.F is None:
        return (f"{head}Panoramic pair (no F between pixels): <code>X_h2&#7488; E X_h1 = 0</code> holds between "
                "the viewing rays (mirror points); the epipolar conics are drawn in the panels.</div>")
    pre = 'style="margin:2px 0;font-size:0.95em;background:#f3f3f3;padding:2px 4px"'
    return (
        f"{head}F (unit Frobenius norm), rank {p.rank}:<pre {pre}>{_fmt_matrix(p.F)}</pre>"
        f"E = [t]&#8339; R:<pre {pre}>{_fmt_matrix(p.E)}</pre>"
        f"e1 = {escape(_fmt_vec(p.e1))}<br>e2 = {escape(_fmt_vec(p.e2))}</div>"
    )


class ClientView:
    """One browser tab: its model, its 3D nodes, its panels and fields.

    Args:
        client: a :class:`viser.ClientHandle` (its ``scene``, ``gui``, ``atomic()``
            and ``add_notification`` are used).
        model: the tab's own :class:`SceneModel`.
    """

    def __init__(self, client: viser.ClientHandle, model: SceneModel, *, open_demo: Any = None) -> None:
        from .scene3d import Scene3D

        self.client = client
        self.model = model
        #: ``open_demo(kind)`` opens a visual-servoing demo in this tab (the app passes it); None: no folder.
        self._open_demo = open_demo
        self.lock = threading.RLock()
        self.closed = False
        self.revision = 0
        self._syncing = False
        self._moving: str | None = None
        self._gizmo_stamp: dict[str, float] = {}
        self._drag_seq: dict[str, int] = {}
        #: Seconds from a user event (field, button, gizmo) to the end of its atomic update (benchmark).
        self.timings: deque[float] = deque(maxlen=5000)
        self._t_event: float | None = None
        #: Seconds spent in each part of the last update.
        self.breakdown: dict[str, float] = {}
        self.last_update_wall: float = 0.0
        self.svgs: dict[str, str] = {}
        self.readout = ""
        self._cam_fields: dict[str, dict[str, Any]] = {}
        self._cam_folders: dict[str, Any] = {}
        self._panels: dict[str, Any] = {}
        self._html: dict[str, Any] = {}
        self._panel_sig: tuple = ()
        self._pair_options: dict[str, tuple[str, str]] = {}
        self._panel_share: dict[str, float] = {}
        self._synced_specs: dict[str, Any] = {}
        self._synced_fields: dict[str, Any] = {}
        self._point_options_n = -1
        self._synced_rest: tuple | None = None

        with self.lock, client.atomic():
            self.scene3d = Scene3D(client.scene, self._camera_gizmo_event, self._point_gizmo_event)
            self._build_controls()
            self._render(self.model.scene, None)
        self._unsubscribe = model.subscribe(self._on_change)

    # -- GUI construction -------------------------------------------------------

    def _build_controls(self) -> None:
        gui = self.client.gui
        gui.configure_theme(dark_mode=False, show_logo=False)
        try:
            gui.main_panel.dock_left()
            gui.main_panel.set_width(CONTROL_WIDTH)
        except Exception:  # noqa: BLE001 - placement is cosmetic
            pass
        self.title = gui.add_markdown(self._title_md())
        with gui.add_folder("Epipolar geometry", expand_by_default=True):
            self.pair_dropdown = gui.add_dropdown("drawn pair", ["-"], hint="Which two cameras' epipolar geometry is drawn.")
            self.pair_dropdown.on_update(self._pair_event)
            self.readout_md = gui.add_html("")
        with gui.add_folder("Points", expand_by_default=True):
            self.point_dropdown = gui.add_dropdown("selected point", ["none"],
                                                   hint="The selected point's epipolar plane is drawn in 3D.")
            self.point_dropdown.on_update(self._select_event)
            self.n_points = gui.add_number("how many (randomise)", 8, min=0, max=2000, step=1)
            self.btn_random = gui.add_button("Randomise points")
            self.btn_random.on_click(lambda _: self._guarded(self._randomise))
            self.btn_add_point = gui.add_button("Add point")
            self.btn_add_point.on_click(lambda _: self._guarded(lambda: self.model.add_point((0.0, 0.0, 1.0))))
            self.btn_remove_point = gui.add_button("Remove selected (or last) point")
            self.btn_remove_point.on_click(lambda _: self._guarded(self._remove_point))
            self.surface_kind = gui.add_dropdown("surface", ["plane", "sphere", "mesh: house.obj"], initial_value="sphere")
            self.btn_surface = gui.add_button("Add surface")
            self.btn_surface.on_click(lambda _: self._guarded(self._add_surface))
        with gui.add_folder("Cameras", expand_by_default=True):
            self.btn_add_pinhole = gui.add_button("Add pin-hole camera")
            self.btn_add_pinhole.on_click(lambda _: self._guarded(lambda: self.model.add_camera("pinhole")))
            self.btn_add_pano = gui.add_button("Add panoramic camera")
            self.btn_add_pano.on_click(lambda _: self._guarded(lambda: self.model.add_camera("panoramic")))
            self.cameras_folder = gui.add_folder("Camera settings", expand_by_default=True)
        with gui.add_folder("Show", expand_by_default=False):
            self.toggles = {}
            for opt, label in (("show_rays", "projection rays"), ("show_planes", "epipolar plane"),
                               ("show_frames", "camera frames"), ("show_labels", "labels"),
                               ("show_surfaces", "surfaces")):
                cb = gui.add_checkbox(label, getattr(self.model.scene.options, opt))
                cb.on_update(lambda e, opt=opt: self._guarded(lambda: self._toggle(opt, e.target.value)))
                self.toggles[opt] = cb
        if self._open_demo is not None:
            with gui.add_folder("Visual servoing", expand_by_default=False):
                self.btn_servo_pinhole = gui.add_button("Pin-hole camera on a Puma 560")
                self.btn_servo_pinhole.on_click(lambda _: self._open_demo("pinhole"))
                self.btn_servo_panoramic = gui.add_button("Panoramic camera on a mobile robot")
                self.btn_servo_panoramic.on_click(lambda _: self._open_demo("panoramic"))
        with gui.add_folder("Scene file", expand_by_default=False):
            self.btn_undo = gui.add_button("Undo")
            self.btn_undo.on_click(lambda _: self._guarded(self.model.undo))
            self.btn_reset = gui.add_button("Reset")
            self.btn_reset.on_click(lambda _: self._guarded(self.model.reset))
            self.path_field = gui.add_text("file", "scene.json", hint="Path on the server, relative to where egtviz runs.")
            self.btn_save = gui.add_button("Save")
            self.btn_save.on_click(lambda _: self._guarded(self._save))
            self.btn_load = gui.add_button("Load")
            self.btn_load.on_click(lambda _: self._guarded(self._load))

    def _title_md(self) -> str:
        title = self.model.scene.title or "egtviz"
        return (f"**{title}**  \nDrag the gizmos or edit the fields; "
                "the image planes are in the panels on the right. Point numbers match in 3D and in the images.")

    def _build_camera_fields(self, spec: Any) -> None:
        gui = self.client.gui
        name = spec.name
        with self.cameras_folder:
            folder = gui.add_folder(f"{name} ({'pin-hole' if spec.kind == 'pinhole' else 'panoramic'})",
                                    expand_by_default=False)
        f: dict[str, Any] = {}
        with folder:
            f["position"] = gui.add_vector3("position (m)", spec.position, step=0.1,
                                            hint="Camera centre (mirror focus) in world coordinates.")
            hint = EGT_PINHOLE_HINT if spec.kind == "pinhole" else EGT_PANORAMIC_HINT
            f["ypr"] = gui.add_vector3("yaw, pitch, roll (deg)", spec.ypr_deg, step=1.0, hint=hint)
            gui.add_markdown(f"<small>{hint}</small>")
            if spec.kind == "pinhole":
                f["focal"] = gui.add_number("focal length (mm)", spec.focal_length * 1e3, step=0.1)
                f["pixel"] = gui.add_vector2("pixel size (µm)", tuple(1e6 / k for k in spec.pixels_per_metre), step=0.1)
                f["pp"] = gui.add_vector2("principal point (px)", spec.principal_point, step=1.0)
                f["size"] = gui.add_vector2("image size (px)", (spec.width, spec.height), step=1.0)
            else:
                f["mirror"] = gui.add_dropdown("mirror", ["hyperbolic", "parabolic"], initial_value=spec.mirror)
                f["a"] = gui.add_number("a (h if parabolic)", spec.a, step=0.1)
                f["b"] = gui.add_number("b", spec.b, step=0.1)
                f["focal_px"] = gui.add_number("focal length (px)", spec.focal_pixels, step=10.0)
                f["pp"] = gui.add_vector2("principal point (px)", spec.principal_point, step=1.0)
                f["size"] = gui.add_vector2("image size (px)", (spec.width, spec.height), step=1.0)
            remove = gui.add_button(f"Remove {name}", color="red")
            remove.on_click(lambda _, n=name: self._guarded(lambda: self.model.remove_camera(n)))
        for key, handle in f.items():
            handle.on_update(lambda e, n=name, k=key: self._field_event(n, k, e.target))
        self._cam_fields[name] = f
        self._cam_folders[name] = folder

    # -- user events ----------------------------------------------------------------

    def _guarded(self, action: Any) -> None:
        """Run a model action under the lock; show a notification (and leave the scene) on error."""
        t0 = time.perf_counter()
        with self.lock:
            if self.closed or self._syncing:
                return
            self._t_event = t0
            try:
                action()
            except (SceneError, ValueError, OSError) as exc:
                self._notify_error(exc)
                self._sync_fields(self.model.scene)

    def _notify_error(self, exc: BaseException) -> None:
        title = "Could not load the scene" if isinstance(exc, SceneFileError) else "Value refused"
        try:
            self.client.add_notification(title, str(exc), color="red", auto_close_seconds=8.0)
        except Exception:  # noqa: BLE001 - the client may be gone
            pass

    def _field_values(self, name: str, key: str, value: Any) -> dict[str, Any]:
        """A GUI field's value as spec fields (UI units -> spec units)."""
        v = value
        arr = np.asarray(v, dtype=float) if not isinstance(v, str) else None
        if arr is not None and not np.all(np.isfinite(arr)):
            raise SceneError(f"{key}: expected finite numbers, got {v!r}")
        if key == "position":
            return {"position": tuple(v)}
        if key == "ypr":
            return {"ypr_deg": tuple(v)}
        if key == "focal":
            return {"focal_length": float(v) * 1e-3}
        if key == "pixel":
            if np.any(arr <= 0):
                raise SceneError(f"pixel size: expected positive sizes, got {tuple(v)}")
            return {"pixels_per_metre": tuple(1e6 / x for x in arr)}
        if key == "pp":
            return {"principal_point": tuple(v)}
        if key == "size":
            w, h = arr
            if w != round(w) or h != round(h):
                raise SceneError(f"image size: expected whole numbers of pixels, got {tuple(v)}")
            return {"width": int(round(w)), "height": int(round(h))}
        if key == "mirror":
            return {"mirror": v}
        if key in ("a", "b"):
            return {key: float(v)}
        if key == "focal_px":
            return {"focal_pixels": float(v)}
        raise SceneError(f"unknown field {key!r}")

    def _field_event(self, name: str, key: str, handle: Any) -> None:
        def apply() -> None:
            if name not in self.model.scene.camera_names:
                return
            fields = self._field_values(name, key, handle.value)
            spec = self.model.scene.camera(name)
            if all(getattr(spec, k) == v for k, v in fields.items()):
                return  # the field already shows the model's value (e.g. our own write-back)
            self.model.update_camera(name, **fields)

        self._guarded(apply)

    def _camera_gizmo_event(self, name: str, event: Any) -> None:
        t0 = time.perf_counter()
        with self.lock:
            if self.closed:
                return
            target = event.target
            stamp = float(getattr(target, "update_timestamp", 0.0))
            if stamp < self._gizmo_stamp.get(name, -1.0):
                return  # an older event delivered late: the newer pose is already applied
            self._gizmo_stamp[name] = stamp
            phase = getattr(event, "phase", "update")
            if phase == "start":
                self._drag_seq[name] = self._drag_seq.get(name, 0) + 1  # one drag = one undo step
                return
            self._t_event = t0
            R = matrix_from_quat_wxyz(target.wxyz)
            position = np.asarray(target.position, float)
            self._moving = name if phase == "update" else None
            try:
                if name not in self.model.scene.camera_names:
                    return
                pose = self.model.scene.camera(name).camera().pose  # the spec's cached camera: no new Pose
                if _allclose(pose.t, position, 1e-9) and _allclose(pose.R, R, 1e-9):
                    if phase == "end":  # nothing moved since the last update: just resync the fields
                        self._render(self.model.scene, None)
                    return
                self.model.set_camera_pose(name, tuple(position), R, drag_id=self._drag_seq.get(name))
            except SceneError as exc:
                self._notify_error(exc)
            finally:
                self._moving = None

    def _point_gizmo_event(self, index: int, event: Any) -> None:
        t0 = time.perf_counter()
        with self.lock:
            if self.closed:
                return
            key = f"point:{index}"
            target = event.target
            stamp = float(getattr(target, "update_timestamp", 0.0))
            if stamp < self._gizmo_stamp.get(key, -1.0):
                return
            self._gizmo_stamp[key] = stamp
            self._t_event = t0
            scene = self.model.scene
            try:
                if getattr(event, "phase", "update") == "start":
                    self._drag_seq[key] = self._drag_seq.get(key, 0) + 1  # one drag = one undo step
                    if scene.selected_point != index and index < len(scene.points):
                        self.model.select_point(index)
                    return
                if index < len(scene.points):
                    self.model.set_point(index, tuple(np.asarray(target.position, float)), drag_id=self._drag_seq.get(key))
            except SceneError as exc:
                self._notify_error(exc)

    def _pair_event(self, event: Any) -> None:
        def apply() -> None:
            pair = self._pair_options.get(self.pair_dropdown.value)
            if pair is not None and pair != self.model.scene.drawn_pair:
                self.model.set_pair(*pair)

        self._guarded(apply)

    def _select_event(self, event: Any) -> None:
        def apply() -> None:
            v = self.point_dropdown.value
            idx = None if v == "none" else int(v.split()[-1]) - 1
            if idx != self.model.scene.selected_point:
                self.model.select_point(idx)

        self._guarded(apply)

    def _toggle(self, opt: str, value: bool) -> None:
        if getattr(self.model.scene.options, opt) != bool(value):
            self.model.set_option(opt, bool(value))

    def _randomise(self) -> None:
        n = self.n_points.value
        if not np.isfinite(n) or n < 0 or n != int(n):
            raise SceneError(f"how many: expected a whole number >= 0, got {n!r}")
        X = self.model.scene.points_array()
        centre = tuple(X.mean(axis=0)) if len(X) else (0.0, 0.0, 1.0)
        self.model.randomize_points(int(n), center=centre, extent=2.0)

    def _remove_point(self) -> None:
        scene = self.model.scene
        if not scene.points:
            raise SceneError("no points to remove")
        self.model.remove_point(scene.selected_point if scene.selected_point is not None else len(scene.points) - 1)

    def _add_surface(self) -> None:
        kind = self.surface_kind.value
        X = self.model.scene.points_array()
        centre = tuple(X.mean(axis=0)) if len(X) else (0.0, 0.0, 1.0)
        if kind.startswith("mesh: "):
            # A mesh from assets/, standing on the ground under the points.
            self.model.add_surface(
                SurfaceSpec(kind="mesh", center=(centre[0], centre[1], 0.0), size=2.0, samples=300, path=kind[6:])
            )
            return
        size = 1.0 if kind == "sphere" else 3.0
        self.model.add_surface(SurfaceSpec(kind=kind, center=centre, size=size, samples=200))

    def _save(self) -> None:
        path = self.path_field.value
        self.model.save(path)
        self.client.add_notification("Saved", f"scene written to {path}", auto_close_seconds=4.0)

    def _load(self) -> None:
        self.model.load(self.path_field.value)

    # -- rendering ----------------------------------------------------------------

    def _on_change(self, scene: Scene, change: Any) -> None:
        with self.lock:
            if self.closed:
                return
            # Draw the model's current scene, not the notified one: a late notification never wins.
            self._render(self.model.scene, change)

    def _render(self, scene: Scene, change: Any) -> None:
        t0 = time.perf_counter()
        try:
            derived = compute_derived(scene)
        except Exception as exc:  # noqa: BLE001 - a bug below must not take the tab down
            self._render_failure(scene, exc)
            return
        t1 = time.perf_counter()
        self.revision += 1
        with self.client.atomic():
            self._sync_panels(scene)
            # Panels first: within the atomic batch the browser then updates the SVGs before the 3D view.
            highlighted = {int(h.split(":")[1]) for h in scene.highlighted if h.startswith("point:")}
            for spec in scene.cameras:
                plane = derived.image_planes.get(spec.name)
                if plane is None:
                    continue
                svg = image_plane_svg(
                    plane,
                    selected_point=scene.selected_point,
                    highlighted=highlighted,
                    show_labels=scene.options.show_labels,
                    revision=self.revision,
                    # Each SVG shrinks to its panel's share of the window height: no scrolling.
                    max_height=f"calc({100.0 * self._panel_share.get(spec.name, 1.0):.3f}vh - 75px)",
                )
                self.svgs[spec.name] = svg
                self._html[spec.name].content = svg
            t2 = time.perf_counter()
            self.readout = pair_html(derived)
            self.readout_md.content = self.readout
            self._sync_fields(scene, force=False)
            t3 = time.perf_counter()
            self.scene3d.draw(scene, derived, moving=self._moving)
            t4 = time.perf_counter()
        # Send now: viser otherwise holds a finished atomic batch for up to one 1/60 s window.
        self.client.flush()
        t5 = time.perf_counter()
        self.last_update_wall = time.time()
        self.breakdown = {"model": t0 - self._t_event if self._t_event is not None else 0.0, "derived": t1 - t0, "svg": t2 - t1, "fields": t3 - t2, "scene3d": t4 - t3, "flush": t5 - t4}
        t_event = self._t_event
        if t_event is not None:
            self.timings.append(t5 - t_event)
            self._t_event = None

    def _render_failure(self, scene: Scene, exc: BaseException) -> None:
        """Show what failed in every panel and as a notification; fields still follow the model."""
        import traceback

        traceback.print_exception(exc)
        self.revision += 1
        msg = f"cannot draw this scene: {type(exc).__name__}: {exc}"
        with self.client.atomic():
            self._sync_panels(scene)
            for spec in scene.cameras:
                svg = empty_svg(spec.name, spec.width, spec.height, msg)
                self.svgs[spec.name] = svg
                self._html[spec.name].content = svg
            self.readout = f"<b>{escape(msg)}</b>"
            self.readout_md.content = self.readout
            self._sync_fields(scene)
        self._notify_error(exc)

    def _sync_panels(self, scene: Scene) -> None:
        """(Re)build camera folders and image panels when the set of cameras changes."""
        sig = tuple((c.name, c.kind) for c in scene.cameras)
        if sig == self._panel_sig:
            return
        gui = self.client.gui
        for name in list(self._panels):
            self._panels.pop(name).remove()
            self._html.pop(name, None)
        for name in list(self._cam_folders):
            self._cam_folders.pop(name).remove()
            self._cam_fields.pop(name, None)
        # One column docked on the right, panels stacked top to bottom: none hides another or the 3D view.
        # viser splits a docked slot into two halves and applies the dock commands in the order the panels
        # were created, so plan a balanced docking order first (equal heights for 2, 4, 8 ... cameras).
        specs = {c.name: c for c in scene.cameras}
        plan: list[tuple[str, str | None]] = []
        self._panel_share = {}
        names = list(specs)
        if names:
            plan.append((names[0], None))
            self._plan_split(names, 1.0, plan)
        for name, anchor in plan:
            spec = specs[name]
            panel = gui.add_panel()
            with panel.add_tab(f"{spec.name}: image plane"):
                self._html[spec.name] = gui.add_html(empty_svg(spec.name, spec.width, spec.height))
            if anchor is None:
                panel.dock_right()
                panel.set_width(PANEL_WIDTH)
            else:
                panel.dock_below(self._panels[anchor])
            self._panels[name] = panel
        for spec in scene.cameras:
            self._build_camera_fields(spec)
        self._panel_sig = sig

    def _plan_split(self, names: list[str], share: float, plan: list) -> None:
        """``names[0]`` holds a slot of height ``share``: stack all ``names`` in it by halving it recursively."""
        if len(names) == 1:
            self._panel_share[names[0]] = share
            return
        k = (len(names) + 1) // 2
        plan.append((names[k], names[0]))
        self._plan_split(names[:k], share / 2, plan)
        self._plan_split(names[k:], share / 2, plan)

    def _sync_fields(self, scene: Scene, *, force: bool = True) -> None:
        """Write the model's values into the GUI (guarded: these writes are not user edits).

        ``force=False`` (a render): a camera whose spec is the very object last written is skipped.
        """
        self._syncing = True
        try:
            for spec in scene.cameras:
                f = self._cam_fields.get(spec.name)
                if f is None:
                    continue
                if not force and self._synced_specs.get(spec.name) is spec and f is self._synced_fields.get(spec.name):
                    continue
                self._synced_specs[spec.name] = spec
                self._synced_fields[spec.name] = f
                _set(f["position"], tuple(spec.position))
                _set(f["ypr"], tuple(round(a, 6) for a in spec.ypr_deg))
                _set(f["pp"], tuple(spec.principal_point))
                _set(f["size"], (float(spec.width), float(spec.height)))
                if spec.kind == "pinhole":
                    _set(f["focal"], spec.focal_length * 1e3)
                    _set(f["pixel"], tuple(1e6 / k for k in spec.pixels_per_metre))
                else:
                    _set(f["mirror"], spec.mirror)
                    _set(f["a"], float(spec.a))
                    _set(f["b"], float(spec.b))
                    _set(f["focal_px"], float(spec.focal_pixels))
            title = self._title_md()
            # A drag changes one camera's pose and nothing below: skip the rest when its inputs are unchanged.
            rest_key = (scene.camera_names, scene.drawn_pair, len(scene.points), scene.selected_point, scene.options,
                        self.model.can_undo, title)
            if not force and rest_key == self._synced_rest:
                return
            self._synced_rest = rest_key
            names = scene.camera_names
            pairs = {f"{a} & {b}": (a, b) for a, b in itertools.combinations(names, 2)}
            drawn = scene.drawn_pair
            if drawn is not None and f"{drawn[0]} & {drawn[1]}" not in pairs:
                pairs[f"{drawn[0]} & {drawn[1]}"] = drawn
            self._pair_options = pairs
            options = tuple(pairs) or ("-",)
            if tuple(self.pair_dropdown.options) != options:
                self.pair_dropdown.options = options
            _set(self.pair_dropdown, f"{drawn[0]} & {drawn[1]}" if drawn else "-")
            if self._point_options_n != len(scene.points):
                popts = ("none",) + tuple(f"point {i + 1}" for i in range(len(scene.points)))
                if tuple(self.point_dropdown.options) != popts:
                    self.point_dropdown.options = popts
                self._point_options_n = len(scene.points)
            sel = scene.selected_point
            _set(self.point_dropdown, "none" if sel is None else f"point {sel + 1}")
            for opt, cb in self.toggles.items():
                _set(cb, getattr(scene.options, opt))
            if self.btn_undo.disabled != (not self.model.can_undo):
                self.btn_undo.disabled = not self.model.can_undo
            if self.title.content != title:
                self.title.content = title
        finally:
            self._syncing = False

    # -- teardown -------------------------------------------------------------------

    def close(self) -> None:
        """Stop listening; later events for this tab are ignored. The model is dropped."""
        with self.lock:
            if self.closed:
                return
            self.closed = True
            self._unsubscribe()


def _allclose(a: np.ndarray, b: np.ndarray, atol: float) -> bool:
    """``np.allclose(a, b, atol=atol)`` (rtol 1e-5) without its per-call overhead (runs on every drag event)."""
    return bool((np.abs(a - b) <= atol + 1e-5 * np.abs(b)).all())


def _set(handle: Any, value: Any) -> None:
    """Assign a GUI value only if it differs (viser also fires callbacks on assignment)."""
    current = handle.value
    if isinstance(value, tuple) and isinstance(current, tuple):
        if len(value) == len(current) and all(
            (isinstance(a, str) and a == b) or (not isinstance(a, str) and abs(float(a) - float(b)) <= 1e-9)
            for a, b in zip(value, current)
        ):
            return
    elif current == value:
        return
    handle.value = value


class EgtvizApp:
    """The egtviz viewer on a viser server: each connecting browser tab gets its own scene.

    Args:
        server: the viser server to serve on.
        scene: the scene every new tab starts from (default: :func:`default_scene`).
    """

    def __init__(self, server: viser.ViserServer, scene: Scene | None = None, *, demo: str | None = None) -> None:
        if demo not in (None, "pinhole", "panoramic"):
            raise ValueError(f"demo: expected None, 'pinhole' or 'panoramic', got {demo!r}")
        self.server = server
        self.initial_scene = scene if scene is not None else default_scene()
        #: Open this servo demo in every new tab instead of the workbench.
        self.demo = demo
        self.views: dict[int, ClientView] = {}
        #: The servo demo shown in a tab (``egtviz.viewer.servo_demo.ServoDemo``), by client id.
        self.demos: dict[int, Any] = {}
        self._models: dict[int, SceneModel] = {}
        self._lock = threading.Lock()
        self._gone: set[int] = set()
        self._frame_view(self.initial_scene)
        svg_warm_up()
        # The long-lived objects (numpy, scipy, trimesh, viser, the scene) are never garbage: a full
        # collection walking them all would stall a drag update for tens of milliseconds.
        gc.collect()
        gc.freeze()
        atexit.register(gc.unfreeze)  # let the interpreter's last collection reach them at exit
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)

    def _frame_view(self, scene: Scene) -> None:
        """Start the browser's view camera where it sees every camera and point (view layout only)."""
        pts = [np.asarray(c.position, float) for c in scene.cameras]
        if scene.points:
            pts.append(scene.points_array().mean(axis=0))
        centre = np.mean(pts, axis=0) if pts else np.zeros(3)
        extent = max(6.0, max((float(np.linalg.norm(p - centre)) for p in pts), default=6.0))
        cam = self.server.initial_camera
        cam.look_at = tuple(centre)
        cam.position = tuple(centre + extent * np.array([0.3, -1.45, 0.9]))
        cam.up = (0.0, 0.0, 1.0)
        cam.fov = float(np.radians(60.0))

    def _connect(self, client: viser.ClientHandle) -> None:
        if self.demo is not None:
            self.open_demo(client, self.demo)
            return
        model = SceneModel(self.initial_scene)
        view = ClientView(client, model, open_demo=lambda kind, c=client: self.open_demo(c, kind))
        with self._lock:
            if client.client_id in self._gone:  # it left while we were building its view
                self._gone.discard(client.client_id)
                view.close()
                return
            self.views[client.client_id] = view

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            view = self.views.pop(client.client_id, None)
            demo = self.demos.pop(client.client_id, None)
            self._models.pop(client.client_id, None)
            if view is None and demo is None:
                self._gone.add(client.client_id)
        if view is not None:
            view.close()
        if demo is not None:
            demo.close(client_gone=True)

    # -- visual-servoing demos (egtviz.viewer.servo_demo) ---------------------------------

    def open_demo(self, client: viser.ClientHandle, kind: str) -> Any:
        """Replace the tab's workbench by a servo demo (its scene is kept for the way back)."""
        from .servo_demo import ServoDemo

        cid = client.client_id
        with self._lock:
            view = self.views.pop(cid, None)
            old = self.demos.pop(cid, None)
        if view is not None:
            view.close()
            self._models[cid] = view.model
        if old is not None:
            old.close()
        client.gui.reset()
        client.scene.reset()
        demo = ServoDemo(client, kind, on_back=lambda: self.close_demo(client))  # type: ignore[arg-type]
        with self._lock:
            if cid in self._gone:
                self._gone.discard(cid)
                demo.close()
                return None
            self.demos[cid] = demo
        return demo

    def close_demo(self, client: viser.ClientHandle) -> ClientView | None:
        """Close the tab's servo demo and bring its workbench back."""
        cid = client.client_id
        with self._lock:
            demo = self.demos.pop(cid, None)
            model = self._models.pop(cid, None)
        if demo is not None:
            demo.close()
        client.gui.reset()
        client.scene.reset()
        view = ClientView(client, model or SceneModel(self.initial_scene),
                          open_demo=lambda kind, c=client: self.open_demo(c, kind))
        with self._lock:
            if cid in self._gone:
                self._gone.discard(cid)
                view.close()
                return None
            self.views[cid] = view
        return view

    def wait_for_view(self, timeout: float = 10.0, count: int = 1) -> list[ClientView]:
        """Block until at least ``count`` tabs are connected (tests, benchmark)."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self._lock:
                if len(self.views) >= count:
                    return list(self.views.values())
            time.sleep(0.02)
        raise TimeoutError(f"fewer than {count} viewer tabs connected after {timeout} s")

    def wait_for_demo(self, timeout: float = 10.0, count: int = 1) -> list[Any]:
        """Block until at least ``count`` tabs show a servo demo (tests)."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self._lock:
                if len(self.demos) >= count:
                    return list(self.demos.values())
            time.sleep(0.02)
        raise TimeoutError(f"fewer than {count} servo demos open after {timeout} s")
