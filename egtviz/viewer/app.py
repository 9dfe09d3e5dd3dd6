"""The interactive viewer: one ``SceneModel`` and one ``ClientView`` per browser tab.

Data flow (one direction)::

    GUI field / gizmo  ->  SceneModel (validates)  ->  notification
        ->  model.derived (computed once, at commit)  ->  one `client.atomic()` update of the 3D
            scene, every image-plane panel, the F/E read-out and the fields.

Each browser tab has its own model: edits in one tab never reach another.
Every event handler and every render runs under the view's lock, and a render
always draws the model's *current* scene, so an event that arrives late (viser
runs callbacks in a thread pool) cannot overwrite a newer state. GUI fields are
written back under a guard so that the write does not look like a user edit.

Every input is judged on the server. Number fields are text fields whose raw
text is parsed and range-checked in the field's own units
(:mod:`egtviz.viewer.fields`, ranges from :mod:`egtviz.scene.limits`), once the
user stops typing; drop-down values are checked against the options offered,
since a hand-written client can send any string. Every callback is attached
through :func:`~egtviz.viewer.fields.on_event`: whatever it raises reaches the
tab as a notification, and the fields and gizmos go back to the model's values.
Scene files travel through the browser (download and upload), never by a
server path.
"""

from __future__ import annotations

import atexit
import gc
import itertools
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from functools import lru_cache
from html import escape
from typing import Any

import numpy as np
import viser

from ..geometry import GeometryError, PinholeCamera
from ..geometry.camera_model import CAMERA_MODELS
from ..geometry.catadioptric import HYPERBOLIC
from ..geometry.poses import matrix_from_quat_wxyz
from ..scene import (
    SCENES,
    Scene,
    SceneError,
    SceneFileError,
    SceneModel,
    SurfaceSpec,
    compute_derived,
    default_scene,
    limits,
    mesh_names,
    scene_from_bytes,
    scene_to_bytes,
)
from ..scene.derived import shown_value
from ..scene.extent import scene_extent
from ..scene.shown_numbers import format_value, format_vector
from ..scene.specs import OutOfRangeError, model_choices
from .camera_fields import CameraField, camera_fields
from .fields import (
    Debouncer,
    FieldError,
    NumberRule,
    describe_error,
    format_number,
    format_numbers,
    notify_error,
    on_event,
    parse_numbers,
)
from .figure_export import panel_svg_of
from .palette import PRESENT_GUI_CSS
from .panels import (
    CONTROL_PX,
    DEFAULT_WINDOW,
    DIVIDER_PX,
    VIEW_ACTIONS,
    PanelGrid,
    PanelView,
    WindowSize,
    dock_plan,
    framed_camera,
    initial_view,
    plan_grid,
    window_from_canvas,
)
from .models import SHORT_LABELS
from .plot_svg import plot_svg
from .png_worker import PngDownloads
from .svg import NORMAL, PRESENT, empty_svg, image_plane_svg
from .svg import warm_up as svg_warm_up

__all__ = ["EgtvizApp", "ClientView"]

#: The per-panel buttons in each camera's folder: label -> (button text -> view action of :class:`PanelView`).
VIEW_BUTTONS = {
    "panel view": {"fit": "fit", "image": "image", "+": "+", "\u2212": "-"},
    "panel pan": {"\u2190": "left", "\u2192": "right", "\u2191": "up", "\u2193": "down"},
}
DOWNLOAD_FORMATS = ("SVG", "PNG")
#: Changes after which a tab's 3D view is framed on the scene again (what it holds changed, not just a pose).
REFRAME_CHANGES = frozenset({"add_camera", "load"})
#: The width viser's dock gives a new docked column (CSS pixels).
DOCK_DEFAULT_PX = 300.0
#: How much larger the 3D view's labels (point numbers, camera names) are in presentation mode.
PRESENT_LABEL_SCALE = 1.6

def _fmt_matrix(M: np.ndarray) -> str:
    """A matrix's rows; an entry below ``ZERO_FRACTION`` of the matrix's norm is rounding and shown as 0."""
    M = np.asarray(M, float)
    norm = float(np.linalg.norm(M))
    rows = ["  ".join(" 0" if shown_value(v, norm) == 0.0 else format_value(v, " .4e") for v in row)
            for row in M.tolist()]
    return "\n".join(rows)


def _fmt_vec(v: np.ndarray | None) -> str:
    if v is None:
        return "-"
    v = np.asarray(v, float)
    if abs(v[2]) < 1e-12:
        return f"({format_vector(v[:2], '.3g')}, 0) (at infinity)"
    return f"({format_vector(v[:2] / v[2], '.1f')}) px"


def pair_html(derived: Any) -> str:
    """The epipolar read-out of the drawn pair (HTML: cheaper for the browser than re-parsing markdown per drag step).

    Two pin-hole cameras: F (pixels, ``m2^T F m1 = 0``), its rank, E and the epipoles. Any pair with another
    camera: E between the viewing rays (``d2^T E d1 = 0``) and a note that no F relates the pixels.
    """
    p = derived.pair
    style = "font-size:0.82em;line-height:1.35"
    if p.names is None:
        return f'<div style="{style}"><b>Epipolar geometry</b>: add a second camera to see it.</div>'
    law = "<code>m2&#7488; F m1 = 0</code>" if p.F is not None else "<code>d2&#7488; E d1 = 0</code>"
    head = (f'<div style="{style}" data-egtviz="readout"><b>Drawn pair {escape(p.names[0])} &rarr; '
            f"{escape(p.names[1])}</b>&nbsp; {law}<br>")
    if p.message:
        return f'{head}<b style="color:#a00">{escape(p.message)}</b></div>'
    pre = 'style="margin:2px 0;font-size:0.95em;background:#f3f3f3;padding:2px 4px"'
    if p.F is None:
        cams = derived.cameras
        curved = [n for n in p.names if cams[n].projective_calibration is None]
        who = " and ".join(f"{escape(n)} ({escape(SHORT_LABELS[cams[n].kind])})" for n in curved)
        return (f'{head}<span data-relation="essential">No F between pixels: {who} images lines as curves. '
                f"What holds is the epipolar constraint between the viewing rays, <code>d2&#7488; E d1 = 0</code> "
                f"(d1, d2 unit rays in each camera's frame); the epipolar curves are drawn in the panels.</span>"
                f"<br>E = [t]&#8339; R:<pre {pre}>{_fmt_matrix(p.E)}</pre></div>")
    return (
        f'{head}<span data-relation="fundamental">F (unit Frobenius norm), rank {p.rank}:</span>'
        f"<pre {pre}>{_fmt_matrix(p.F)}</pre>"
        f"E = [t]&#8339; R:<pre {pre}>{_fmt_matrix(p.E)}</pre>"
        f"e1 = {escape(_fmt_vec(p.e1))}<br>e2 = {escape(_fmt_vec(p.e2))}</div>"
    )


def _rules(label: str, unit: str, rng: limits.Range, *, scale: float = 1.0,
           axes: Sequence[str] = ("",)) -> tuple[NumberRule, ...]:
    """One field rule per axis from a :mod:`egtviz.scene.limits` range, converted to the field's unit by ``scale``."""
    return tuple(NumberRule(f"{label} {a}".strip(), unit, rng.low * scale, rng.high * scale, integer=rng.integer)
                 for a in axes)


#: What each camera field accepts, in the units the field shows (the scene's limits, converted).
FIELD_RULES: dict[str, tuple[NumberRule, ...]] = {
    "position": _rules("position", "m", limits.COORDINATE, axes="xyz"),
    "ypr": _rules("angle", "deg", limits.ANGLE_DEG, axes=("yaw", "pitch", "roll")),
}
"""The pose fields every camera has; a model's own fields take their rules from its parameters
(:mod:`egtviz.viewer.camera_fields`)."""
#: The "how many points" field: what the page offers is what the server accepts.
POINTS_RULE = (NumberRule("how many points", "", 0, limits.MAX_POINTS, integer=True),)
#: Seconds a text field must stay unchanged before its value is judged (see :class:`Debouncer`).
FIELD_DELAY = 0.6
SURFACE_KINDS = ("plane", "sphere")


#: Spec fields (as :class:`OutOfRangeError` names them) in the words and units of the GUI: label, unit, scale.
_SPEC_TERMS = {
    "focal_length": ("focal length", "mm", 1e3),
    "focal_length * pixels_per_metre": ("focal length in pixels (focal length / pixel size)", "px", 1.0),
    "b/a": ("b / a", "", 1.0),
    "focal_pixels": ("focal length", "px", 1.0),
}


def _restated(exc: OutOfRangeError, name: str) -> FieldError:
    """The model's range refusal restated for the user: the camera, the field's words and units."""
    label, unit, scale = _SPEC_TERMS.get(exc.field, (exc.field.replace("_", " "), exc.limit.unit, 1.0))
    rule = NumberRule(label, unit, exc.limit.low * scale, exc.limit.high * scale, integer=exc.limit.integer)
    try:
        rule.check(float(exc.value) * scale, owner=name)
    except FieldError as restated:
        return restated
    except (TypeError, ValueError):  # a value that is no number: keep the model's own words
        pass
    return FieldError(f"{name}: {exc}")


@lru_cache(maxsize=16)
def _model_fields(model_kind: str) -> tuple[dict[str, CameraField], dict[str, Any]]:
    """A model's GUI fields by key, and its parameter specs by name (from the registry)."""
    params = CAMERA_MODELS[model_kind].parameters
    return {f.key: f for f in camera_fields(params)}, {p.name: p for p in params}


def _spec_values(spec: Any) -> dict[str, tuple[float, ...]]:
    """A camera spec's values as its fields show them (model parameters -> the fields' units)."""
    values: dict[str, tuple[float, ...]] = {"position": tuple(spec.position), "ypr": tuple(spec.ypr_deg)}
    params = spec.model_values()
    for key, field in _model_fields(spec.model_kind)[0].items():
        values[key] = field.shown(params)
    return values


def _field_rules(spec: Any, key: str) -> tuple[NumberRule, ...]:
    """What field ``key`` of this camera accepts (its parameters' ranges in the field's units)."""
    if key in FIELD_RULES:
        return FIELD_RULES[key]
    fields, specs = _model_fields(spec.model_kind)
    if key not in fields:
        raise FieldError(f"{spec.name}: no field {key!r} on a {spec.model.label.lower()}")
    return fields[key].rules(specs)


def _spec_fields(spec: Any, key: str, v: tuple[float, ...]) -> dict[str, Any]:
    """Parsed field values as spec fields (the fields' units -> model parameters -> spec fields)."""
    if key == "position":
        return {"position": v}
    if key == "ypr":
        return {"ypr_deg": v}
    field = _model_fields(spec.model_kind)[0].get(key)
    if field is None:
        raise FieldError(f"unknown field {key!r}")
    return spec.fields_for_parameters(**field.parameters_of(v))


def _plain(text: str, limit: int = 80) -> str:
    """Text from a file or a browser, safe to show: printable characters only, at most ``limit`` of them."""
    clean = "".join(c if c.isprintable() else "?" for c in str(text))
    return clean if len(clean) <= limit else clean[:limit] + "..."


def _file_name(title: str) -> str:
    """The download's file name: the scene title reduced to letters, digits, ``-`` and ``_``."""
    stem = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "_" for c in title.strip())[:40].strip("_")
    return f"{stem or 'scene'}.json"


class ClientView:
    """One browser tab: its model, its 3D nodes, its panels and fields.

    Every callback is attached through :func:`egtviz.viewer.fields.on_event`:
    whatever it raises reaches this tab as a notification, and the fields and
    gizmos go back to the model's values.

    Args:
        client: a :class:`viser.ClientHandle` (its ``scene``, ``gui``, ``atomic()``
            and ``add_notification`` are used).
        model: the tab's own :class:`SceneModel`.
        open_demo: ``open_demo(kind)`` opens a visual-servoing demo in this tab; None: no such folder.
        field_delay: seconds a text field must stay unchanged before it is judged (0: at once).
        present: start in presentation mode (large type, thick lines: see :data:`egtviz.viewer.svg.PRESENT`).
    """

    def __init__(self, client: viser.ClientHandle, model: SceneModel, *, open_demo: Any = None,
                 field_delay: float = FIELD_DELAY, present: bool = False,
                 window: tuple[WindowSize, float] | None = None) -> None:
        from .scene3d import Scene3D

        self.client = client
        self.model = model
        #: ``open_demo(kind, **run_fields)`` replaces this tab by a servo demo (the app passes it); None: no demos.
        self.open_demo = open_demo
        self.lock = threading.RLock()
        self.closed = False
        self.revision = 0
        self._syncing = False
        self._moving: str | None = None
        #: Whether the update being drawn is a step of a gizmo drag (fitted panels then keep a steady view).
        self._drag_step = False
        #: Each panel's view as last drawn (a fitted panel's steady view during a drag).
        self._shown_views: dict[str, Any] = {}
        self._gizmo_stamp: dict[str, float] = {}
        self._drag_seq: dict[str, int] = {}
        self._typing = Debouncer(field_delay)
        #: Seconds from a user event (field, button, gizmo) to the end of its atomic update (benchmark).
        self.timings: deque[float] = deque(maxlen=5000)
        self._t_event: float | None = None
        #: Seconds spent in each part of the last update.
        self.breakdown: dict[str, float] = {}
        self.last_update_wall: float = 0.0
        self.svgs: dict[str, str] = {}
        #: Per panel, the image plane and the other inputs its SVG was last drawn from, and that SVG.
        self._drawn_panels: dict[str, tuple[Any, tuple, str]] = {}
        self.readout = ""
        self._cam_fields: dict[str, dict[str, Any]] = {}
        self._cam_folders: dict[str, Any] = {}
        self._html: dict[str, Any] = {}
        self._panel_sig: tuple = ()
        self._pair_options: dict[str, tuple[str, str]] = {}
        #: Presentation mode (larger type and lines in the panels and the GUI).
        self.present = bool(present)
        # A tab coming back from a servo demo reports the demo's narrowed canvas: the app passes the window
        # its previous workbench had measured instead.
        self._window, self._pixel_ratio = window if window is not None else self._client_window()
        #: Where the panels are (see :func:`egtviz.viewer.panels.plan_grid`); None before the first layout.
        self.grid: PanelGrid | None = None
        self._grid_key: tuple | None = None
        self._width_pending: PanelGrid | None = None
        self._panel_handles: list[Any] = []
        #: What each panel shows, with the image size it was chosen for: ``name -> ((width, height), PanelView)``.
        self._views: dict[str, tuple[tuple[int, int], PanelView]] = {}
        #: Each camera's panel buttons (button groups by label: ``panel view``, ``panel pan``, ``download panel``).
        self.panel_buttons: dict[str, dict[str, Any]] = {}
        #: The panels' PNG downloads: rendered in a worker process, one waiting per tab, refused above the limits.
        self.png = PngDownloads(client)
        self._synced_specs: dict[str, Any] = {}
        self._synced_fields: dict[str, Any] = {}
        self._point_options_n = -1
        self._synced_rest: tuple | None = None
        self._surface_options: dict[str, tuple[str, str]] = {}
        self._n_points_text = "8"
        #: What the image-plane panels draw instead of the model's derived quantities (a lesson's convention lens
        #: or estimation lab): ``panel_filter(scene, derived) -> (derived for the panels, point indices to ring)``.
        #: None: the model's. The 3D view and the read-out always show the model's.
        self.panel_filter: Callable[[Scene, Any], tuple[Any, frozenset[int]]] | None = None
        #: A lesson's narrower ranges for camera fields: ``field_guard(camera, spec_fields) -> refusal or None``
        #: is asked before a field's new value is committed; a refusal reverts the field with that message.
        self.field_guard: Callable[[str, dict[str, Any]], str | None] | None = None
        #: A lesson's narrower ranges for a camera's pose under a gizmo drag:
        #: ``pose_guard(camera, position, R_world) -> (position, R_world)`` turns the pose the gizmo sent into the
        #: pose to apply (one inside the ranges); the gizmo shows the applied pose when the drag ends.
        self.pose_guard: Callable[[str, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None

        with self.lock, client.atomic():
            self.scene3d = Scene3D(client.scene, self._camera_gizmo_event, self._point_gizmo_event,
                                   report=self.report)
            self.scene3d.set_label_scale(PRESENT_LABEL_SCALE if self.present else 1.0)
            self._build_controls()
            self._build_panel_controls()
            self._render(self.model.scene, None)
            self._frame_camera()
        self._on(client.camera.on_update, self._on_canvas)
        self._unsubscribe = model.subscribe(self._on_change)

    # -- GUI construction -------------------------------------------------------

    def _on(self, register: Any, callback: Any) -> None:
        """Attach ``callback`` to a handle's event (``handle.on_update`` ...): errors reach this tab."""
        on_event(register, callback, self.report)

    def _build_controls(self) -> None:
        gui = self.client.gui
        gui.configure_theme(dark_mode=False, show_logo=False)
        try:
            gui.main_panel.dock_left()
            gui.main_panel.set_width(CONTROL_PX["present" if self.present else "normal"])
        except Exception:  # noqa: BLE001 - placement is cosmetic
            pass
        # HTML, not markdown: the title comes from a file and is escaped as text.
        self.title = gui.add_html(self._title_html())
        with gui.add_folder("Epipolar geometry", expand_by_default=True):
            self.pair_dropdown = gui.add_dropdown("drawn pair", ["-"], hint="Which two cameras' epipolar geometry is drawn.")
            self._on(self.pair_dropdown.on_update, lambda _: self._user_event(self._set_pair))
            self.readout_md = gui.add_html("")
        with gui.add_folder("Points", expand_by_default=True):
            self.point_dropdown = gui.add_dropdown("selected point", ["none"],
                                                   hint="The selected point's epipolar plane is drawn in 3D.")
            self._on(self.point_dropdown.on_update, lambda _: self._user_event(self._select))
            self.n_points = gui.add_text("how many (randomise)", self._n_points_text,
                                         hint=f"A whole number from 0 to {limits.MAX_POINTS}.")
            self._on(self.n_points.on_update,
                     lambda e: self._text_event("n_points", self._check_n_points, e.target.value))
            self.btn_random = gui.add_button("Randomise points")
            self._on(self.btn_random.on_click, lambda _: self._user_event(self._randomise))
            self.btn_add_point = gui.add_button("Add point")
            self._on(self.btn_add_point.on_click,
                     lambda _: self._user_event(lambda: self.model.add_point((0.0, 0.0, 1.0))))
            self.btn_remove_point = gui.add_button("Remove selected (or last) point")
            self._on(self.btn_remove_point.on_click, lambda _: self._user_event(self._remove_point))
            self._surface_options = {k: (k, "") for k in SURFACE_KINDS}
            self._surface_options.update({f"mesh: {m}": ("mesh", m) for m in mesh_names()})
            self.surface_kind = gui.add_dropdown("surface", tuple(self._surface_options), initial_value="sphere")
            self.btn_surface = gui.add_button("Add surface")
            self._on(self.btn_surface.on_click, lambda _: self._user_event(self._add_surface))
        with gui.add_folder("Cameras", expand_by_default=True):
            # One button per registered camera model.
            self.add_buttons = {}
            for kind, info in CAMERA_MODELS.items():
                button = gui.add_button(f"Add {info.label[0].lower()}{info.label[1:]}")
                self._on(button.on_click, lambda _, k=kind: self._user_event(lambda: self.model.add_camera(k)))
                self.add_buttons[kind] = button
            self.btn_add_pinhole = self.add_buttons[PinholeCamera.kind]
            self.btn_add_pano = self.add_buttons[HYPERBOLIC.kind]
            self.cameras_folder = gui.add_folder("Camera settings", expand_by_default=True)
        with gui.add_folder("Show", expand_by_default=False):
            self.toggles = {}
            for opt, label in (("show_rays", "projection rays"), ("show_planes", "epipolar plane"),
                               ("show_frames", "camera frames"), ("show_labels", "labels"),
                               ("show_surfaces", "surfaces")):
                cb = gui.add_checkbox(label, getattr(self.model.scene.options, opt))
                self._on(cb.on_update, lambda e, opt=opt: self._user_event(lambda: self._toggle(opt, e.target.value)))
                self.toggles[opt] = cb
        if self.open_demo is not None:
            with gui.add_folder("Visual servoing", expand_by_default=False):
                self.btn_servo_pinhole = gui.add_button("Pin-hole camera on a Puma 560")
                self._on(self.btn_servo_pinhole.on_click, lambda _: self.open_demo("pinhole"))
                self.btn_servo_panoramic = gui.add_button("Panoramic camera on a mobile robot")
                self._on(self.btn_servo_panoramic.on_click, lambda _: self.open_demo("panoramic"))
        with gui.add_folder("Scene", expand_by_default=False):
            self.btn_undo = gui.add_button("Undo")
            self._on(self.btn_undo.on_click, lambda _: self._user_event(self._undo))
            self.btn_reset = gui.add_button("Reset")
            self._on(self.btn_reset.on_click, lambda _: self._user_event(self.model.reset))
            self.builtin = gui.add_dropdown("built-in scene", tuple(SCENES), initial_value=next(iter(SCENES)),
                                            hint="A ready-made scene; Open replaces this tab's scene (undoable).")
            self.btn_open = gui.add_button("Open built-in scene")
            self._on(self.btn_open.on_click, lambda _: self._user_event(self._open_builtin))
            self.btn_save = gui.add_button("Save (download)", hint="Download this tab's scene as a JSON file.")
            self._on(self.btn_save.on_click, lambda _: self._user_event(self._save))
            self.btn_load = gui.add_upload_button(
                "Load (upload)", mime_type="application/json",
                hint=f"Open a scene file from this computer (at most {limits.MAX_SCENE_FILE_BYTES // 1000} kB).")
            self._on(self.btn_load.on_upload, lambda _: self._user_event(self._load))

    def _title_html(self) -> str:
        title = escape(_plain(self.model.scene.title or "egtviz", limits.MAX_TITLE_LENGTH))
        # A figure's messages: what its drawing calls could not draw.
        notes = "".join(f'<br><span data-egtviz="figure-message" style="color:#a00">{escape(_plain(m, 200))}</span>'
                        for m in self.model.scene.annotations.messages)
        return (f'<div style="font-size:0.9em;padding:0 0.6em"><b>{title}</b><br>Drag the gizmos or edit the fields; '
                f"the image planes are in the panels on the right. Point numbers match in 3D and in the images.{notes}"
                "</div>")

    def _build_camera_fields(self, spec: Any) -> None:
        """A camera's folder: its pose, the choice among the models its spec builds, and one field per model
        parameter (or pair), built from the model's parameter specs, with the units in the labels."""
        gui = self.client.gui
        name = spec.name
        with self.cameras_folder:
            # The first two cameras (the drawn pair, usually) start open: their fields are what a lesson edits.
            folder = gui.add_folder(f"{name} ({SHORT_LABELS[spec.model_kind]})",
                                    expand_by_default=len(self._cam_folders) < 2)
        values = _spec_values(spec)
        fields, _ = _model_fields(spec.model_kind)
        f: dict[str, Any] = {}
        with folder:
            f["position"] = gui.add_text("position x, y, z (m)", format_numbers(values["position"]),
                                         hint="Camera centre (single viewpoint) in world coordinates: x, y, z.")
            hint = spec.ANGLE_CONVENTION
            f["ypr"] = gui.add_text("yaw, pitch, roll (deg)", format_numbers(values["ypr"]), hint=hint)
            gui.add_markdown(f"<small>{hint}</small>")
            for key, options in model_choices(type(spec)).items():
                f[key] = gui.add_dropdown(key, options, initial_value=getattr(spec, key))
            for key, field in fields.items():
                if field.slider:
                    (p,) = field.rules(_model_fields(spec.model_kind)[1])
                    f[key] = gui.add_slider(field.title, min=p.lo, max=p.hi, step=0.01, initial_value=values[key][0],
                                            hint=field.hint or None)
                else:
                    f[key] = gui.add_text(field.title, format_numbers(values[key]), hint=field.hint or None)
            remove = gui.add_button(f"Remove {name}", color="red")
            self._on(remove.on_click, lambda _, n=name: self._user_event(lambda: self.model.remove_camera(n)))
        choices = model_choices(type(spec))
        for key, handle in f.items():
            if key in choices:
                self._on(handle.on_update, lambda e, n=name, k=key: self._user_event(
                    lambda: self._set_choice(n, k, e.target.value)))
            elif key in fields and fields[key].slider:
                # A slider acts at once (the image morphs as it moves); one slide is one undo step.
                self._on(handle.on_update, lambda e, n=name, k=key: self._user_event(
                    lambda: self._apply_slider(n, k, e.target.value)))
            else:
                self._on(handle.on_update, lambda e, n=name, k=key: self._text_event(
                    (n, k), lambda text, n=n, k=k: self._apply_field(n, k, text), e.target.value))
        self._cam_fields[name] = f
        self._cam_folders[name] = folder

    # -- user events ----------------------------------------------------------------

    def _user_event(self, action: Any) -> None:
        """Run a user's action under the lock (ignored while fields are written back or after the tab left).

        Errors propagate to :meth:`report` through the callback wrapper.
        """
        t0 = time.perf_counter()
        with self.lock:
            if self.closed or self._syncing:
                return
            self._t_event = t0
            action()

    def _undo(self) -> None:
        """Undo one change; at an undo barrier (a lesson step's start) say why nothing happened."""
        if not self.model.undo() and self.model.undo_barrier_note is not None:
            self.client.add_notification("Nothing to undo", self.model.undo_barrier_note, color="yellow",
                                         auto_close_seconds=8.0)

    def _text_event(self, key: Any, apply: Any, text: Any = None) -> None:
        """A text field changed: judge its text once the user stopped typing (latest text wins)."""
        with self.lock:
            if self.closed or self._syncing:
                return  # our own write-back, or the tab is gone

        def judge() -> None:
            try:
                self._user_event(lambda: apply(text))
            except Exception as exc:  # noqa: BLE001 - from a timer thread: no callback wrapper above us
                self.report(exc)

        self._typing.submit(key, judge)

    def report(self, exc: BaseException) -> None:
        """Tell this tab what went wrong and put every field and gizmo back to the model's values."""
        with self.lock:
            if self.closed:
                return
            notify_error(self.client, exc)
            self._resync()

    def _resync(self) -> None:
        """Rewrite every field and put every gizmo back to the model's scene (after a refusal or a failure).

        The panels are left alone: the scene they show has not changed.
        """
        scene = self.model.scene
        try:
            with self.client.atomic():
                self._sync_fields(scene, force=True)
                self.scene3d.draw(scene, self.model.derived, force=True)
        except Exception:  # noqa: BLE001 - a half-built tab: draw it all again, or show why not
            self._render(scene, None, force_fields=True)

    def _apply_field(self, name: str, key: str, text: Any) -> None:
        if name not in self.model.scene.camera_names:
            return  # the camera was removed while the user typed
        spec = self.model.scene.camera(name)
        values = parse_numbers(text, _field_rules(spec, key), owner=name)
        current = _spec_values(spec).get(key)
        if current is None:
            raise FieldError(f"{name}: no field {key!r} on a {spec.model.label.lower()}")
        # A number the user left as shown keeps the model's full precision (the field shows six digits).
        values = tuple(c if format_number(v) == format_number(c) else v for v, c in zip(values, current))
        if values == current:
            return  # nothing edited (e.g. our own write-back, or the same text again)
        self._update_camera(spec, _spec_fields(spec, key, values))

    def _apply_slider(self, name: str, key: str, value: Any) -> None:
        if name not in self.model.scene.camera_names:
            return
        spec = self.model.scene.camera(name)
        (rule,) = _field_rules(spec, key)
        if isinstance(value, bool) or not isinstance(value, (int, float)):  # a raw client can send anything
            raise FieldError(f"{name}: {rule.label} must be a number, got {_plain(repr(value), 40)}")
        x = (rule.check(float(value), owner=name),)
        if x == _spec_values(spec).get(key):
            return
        self._update_camera(spec, _spec_fields(spec, key, x), merge_key=("slider", name, key))

    def _update_camera(self, spec: Any, fields: dict[str, Any], merge_key: Any = None) -> None:
        name = spec.name
        if all(getattr(spec, k) == v for k, v in fields.items()):
            return
        refusal = self.field_guard(name, fields) if self.field_guard is not None else None
        if refusal is not None:
            raise FieldError(refusal)
        try:
            self.model.update_camera(name, merge_key=merge_key, **fields)
        except OutOfRangeError as exc:  # a limit across fields (e.g. focal length in pixels): say it in UI terms
            raise _restated(exc, name) from exc
        except SceneError as exc:
            if str(exc).startswith(f"{name}:"):
                raise
            raise SceneError(f"{name}: {exc}") from exc

    def _set_choice(self, name: str, key: str, value: Any) -> None:
        """Switch a camera among the models its spec builds (a mirror's shape); the spec adapts its parameters."""
        if name not in self.model.scene.camera_names:
            return
        spec = self.model.scene.camera(name)
        options = model_choices(type(spec)).get(key, ())
        if value not in options:  # a raw client can send any string
            raise FieldError(f"{name}: {key} must be one of {', '.join(options)}, got {_plain(repr(value), 40)}")
        if getattr(spec, key) != value:
            self.model.update_camera(name, **{key: value})

    def _check_n_points(self, text: Any) -> None:
        parse_numbers(text, POINTS_RULE)
        self._n_points_text = text  # the last valid count: a refused one reverts to it

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
            self._moving = name if phase == "update" else None
            self._drag_step = phase == "update"
            try:
                if name not in self.model.scene.camera_names:
                    return
                if name in self.model.scene.locked:  # a lesson's lock: the drag is undone when it ends
                    if phase == "end":
                        raise SceneError(f"{name} is locked: its gizmo cannot move it now")
                    return
                try:
                    R = matrix_from_quat_wxyz(target.wxyz)
                except GeometryError as exc:
                    raise SceneError(f"{name}: the gizmo sent an orientation that is not a rotation ({exc})") from exc
                position = np.asarray(target.position, float)
                if position.shape != (3,) or not np.isfinite(position).all():
                    raise SceneError(f"{name}: the gizmo sent a position that is not 3 finite numbers")
                if self.pose_guard is not None:  # whatever the browser sent: the pose the lesson allows
                    position, R = self.pose_guard(name, position, R)
                pose = self.model.scene.camera(name).camera().pose  # the spec's cached camera: no new Pose
                if _allclose(pose.t, position, 1e-9) and _allclose(pose.R, R, 1e-9):
                    if phase == "end":  # nothing moved since the last update: just resync the fields
                        self._render(self.model.scene, None)
                    return
                self.model.set_camera_pose(name, tuple(position), R, drag_id=self._drag_seq.get(name))
            finally:
                self._moving = None
                self._drag_step = False

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
            if getattr(event, "phase", "update") == "start":
                self._drag_seq[key] = self._drag_seq.get(key, 0) + 1  # one drag = one undo step
                if scene.selected_point != index and index < len(scene.points):
                    self.model.select_point(index)
                return
            if index < len(scene.points):
                position = np.asarray(target.position, float)
                if position.shape != (3,) or not np.isfinite(position).all():
                    raise SceneError(f"point {index + 1}: the gizmo sent a position that is not 3 finite numbers")
                self._drag_step = getattr(event, "phase", "update") == "update"
                try:
                    self.model.set_point(index, tuple(position), drag_id=self._drag_seq.get(key))
                finally:
                    self._drag_step = False

    def _set_pair(self) -> None:
        value = self.pair_dropdown.value
        pair = self._pair_options.get(value)
        if pair is None:
            raise FieldError(f"drawn pair: no pair {_plain(repr(value), 40)}")
        if pair != self.model.scene.drawn_pair:
            self.model.set_pair(*pair)

    def _select(self) -> None:
        v = self.point_dropdown.value
        n = len(self.model.scene.points)
        options = {"none": None} | {f"point {i + 1}": i for i in range(n)}
        if v not in options:
            raise FieldError(f"selected point: no {_plain(repr(v), 40)} (have {n} points)")
        idx = options[v]
        if idx != self.model.scene.selected_point:
            self.model.select_point(idx)

    def _toggle(self, opt: str, value: Any) -> None:
        if not isinstance(value, bool):
            raise FieldError(f"{opt}: expected true or false, got {_plain(repr(value), 40)}")
        if getattr(self.model.scene.options, opt) != value:
            self.model.set_option(opt, value)

    def _randomise(self) -> None:
        (n,) = parse_numbers(self.n_points.value, POINTS_RULE)
        X = self.model.scene.points_array()
        centre = tuple(X.mean(axis=0)) if len(X) else (0.0, 0.0, 1.0)
        self.model.randomize_points(int(n), center=centre, extent=2.0)

    def _remove_point(self) -> None:
        scene = self.model.scene
        if not scene.points:
            raise SceneError("no points to remove")
        self.model.remove_point(scene.selected_point if scene.selected_point is not None else len(scene.points) - 1)

    def _add_surface(self) -> None:
        choice = self._surface_options.get(self.surface_kind.value)
        if choice is None:  # a raw client can send any string: only the listed surfaces exist
            raise FieldError(f"surface: no surface {_plain(repr(self.surface_kind.value), 40)}")
        kind, mesh = choice
        X = self.model.scene.points_array()
        centre = tuple(X.mean(axis=0)) if len(X) else (0.0, 0.0, 1.0)
        if kind == "mesh":
            # A mesh of the package's own, standing on the ground under the points.
            self.model.add_surface(
                SurfaceSpec(kind="mesh", center=(centre[0], centre[1], 0.0), size=2.0, samples=300, path=mesh)
            )
            return
        size = 1.0 if kind == "sphere" else 3.0
        self.model.add_surface(SurfaceSpec(kind=kind, center=centre, size=size, samples=200))

    def _open_builtin(self) -> None:
        name = self.builtin.value
        if name not in SCENES:  # a raw client can send any string
            raise FieldError(f"built-in scene: no scene {_plain(repr(name), 40)}; "
                             f"the built-in scenes are {', '.join(SCENES)}")
        self.model.load_scene(SCENES[name]())

    def _save(self) -> None:
        scene = self.model.scene
        self.client.send_file_download(_file_name(scene.title or "scene"), scene_to_bytes(scene),
                                       save_immediately=True)

    def _load(self) -> None:
        upload = self.btn_load.value
        name = _plain(getattr(upload, "name", "") or "the upload", 60)
        content = getattr(upload, "content", None)
        if not isinstance(content, bytes):
            raise SceneFileError(f"{name}: the upload holds no file")
        if len(content) > limits.MAX_SCENE_FILE_BYTES:  # before parsing: a big file is refused unread
            raise SceneFileError(f"{name}: the file has {len(content)} bytes; a scene file has at most "
                                 f"{limits.MAX_SCENE_FILE_BYTES} bytes")
        self.model.load_scene(scene_from_bytes(content, source=name))

    # -- rendering ----------------------------------------------------------------

    def _on_change(self, scene: Scene, change: Any) -> None:
        with self.lock:
            if self.closed:
                return
            # Draw the model's current scene, not the notified one: a late notification never wins.
            self._render(self.model.scene, change)
            if getattr(change, "kind", None) in REFRAME_CHANGES:
                with self.client.atomic():
                    self._frame_camera()  # a new camera or scene: in view, beside the panels it docked

    def _render(self, scene: Scene, change: Any, *, force_fields: bool = False) -> None:
        """Draw ``scene`` (the model's current one) with the model's derived quantities, in one atomic update."""
        t0 = time.perf_counter()
        try:
            # The model computed (and checked) these when it committed the scene: never computed twice.
            derived = self.model.derived
            if scene is not self.model.scene:
                raise RuntimeError("render: the scene is not the model's current scene")
        except Exception as exc:  # noqa: BLE001 - a bug below must not take the tab down
            self._render_failure(scene, exc)
            return
        t1 = time.perf_counter()
        self.revision += 1
        with self.client.atomic():
            self._sync_panels(scene)
            # Panels first: within the atomic batch the browser then updates the SVGs before the 3D view.
            highlighted = {int(h.split(":")[1]) for h in scene.highlighted if h.startswith("point:")}
            panel_derived, ringed = self._filtered(scene, derived)
            highlighted |= ringed
            for spec in scene.cameras:
                plane = panel_derived.image_planes.get(spec.name)
                if plane is None:
                    continue
                svg = self._panel_svg(spec.name, plane, scene, highlighted)
                self.svgs[spec.name] = svg
                self._html[spec.name].content = svg
            for plot in scene.annotations.plots:  # a figure's 2D plots
                key = _plot_key(plot.number)
                svg = self._plot_panel_svg(key, plot)
                self.svgs[key] = svg
                self._html[key].content = svg
            t2 = time.perf_counter()
            self.readout = pair_html(derived)
            self.readout_md.content = self.readout
            self._sync_fields(scene, force=force_fields)
            t3 = time.perf_counter()
            self.scene3d.draw(scene, derived, moving=self._moving, force=force_fields)
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

    def _plot_panel_svg(self, key: str, plot: Any) -> str:
        """A figure's plot panel (:func:`egtviz.viewer.plot_svg.plot_svg`), drawn again only when the plot, the
        style or the panel's size changed (a drag leaves a plot alone)."""
        grid = self.grid
        panel_px = grid.column_px if grid is not None and grid.columns else None
        max_height = f"{grid.svg_max_height_px(key):.0f}px" if panel_px is not None else None
        inputs = (self._style, panel_px, max_height)
        kept = self._drawn_panels.get(key)
        if kept is not None and kept[0] is plot and kept[1] == inputs:
            return kept[2]
        svg = plot_svg(plot, revision=self.revision, max_height=max_height, style=self._style, panel_px=panel_px)
        self._drawn_panels[key] = (plot, inputs, svg)
        return svg

    def _filtered(self, scene: Scene, derived: Any) -> tuple[Any, frozenset[int]]:
        """What the panels draw: ``derived``, or what :attr:`panel_filter` makes of it (its failure is reported)."""
        if self.panel_filter is None:
            return derived, frozenset()
        try:
            return self.panel_filter(scene, derived)
        except Exception as exc:  # noqa: BLE001 - the panels then show the model's geometry, and the tab says why
            import traceback

            traceback.print_exception(exc)
            notify_error(self.client, exc)
            return derived, frozenset()

    def redraw(self) -> None:
        """Draw the model's scene again (after something the panels depend on changed outside the model)."""
        with self.lock:
            if not self.closed:
                self._render(self.model.scene, None)

    def _render_failure(self, scene: Scene, exc: BaseException) -> None:
        """Show what failed in every panel and as a notification; fields still follow the model."""
        import traceback

        traceback.print_exception(exc)
        self.revision += 1
        msg = f"cannot draw this scene: {describe_error(exc)[1]}"
        with self.client.atomic():
            self._sync_panels(scene)
            for spec in scene.cameras:
                svg = empty_svg(spec.name, spec.width, spec.height, msg)
                self.svgs[spec.name] = svg
                self._html[spec.name].content = svg
            self.readout = f"<b>{escape(msg)}</b>"
            self.readout_md.content = self.readout
            self._sync_fields(scene)
        notify_error(self.client, exc)

    def _sync_panels(self, scene: Scene) -> None:
        """(Re)build the camera folders when the set of cameras changes, and the panels when their grid does."""
        sig = tuple((c.name, c.model_kind) for c in scene.cameras)
        if sig != self._panel_sig:
            for name in list(self._cam_folders):
                self._cam_folders.pop(name).remove()
                self._cam_fields.pop(name, None)
                self.panel_buttons.pop(name, None)
            for spec in scene.cameras:
                self._build_camera_fields(spec)
                self._build_view_buttons(spec.name)
            self._panel_sig = sig
        cameras = tuple((c.name, float(c.width), float(c.height)) for c in scene.cameras)
        plots = {_plot_key(p.number): p for p in scene.annotations.plots}  # a figure's 2D plots: 4:3 panels
        cameras += tuple((key, 640.0, 480.0) for key in plots)
        key = (cameras, self._window, self.present)
        if key == self._grid_key:
            return  # a drag: nothing the layout depends on has changed
        grid = plan_grid(cameras, self._window, style=self._style)
        if grid != self.grid:
            self._apply_grid(grid, {c.name: c for c in scene.cameras} | plots)
        self._grid_key = key

    @property
    def _style(self) -> Any:
        return PRESENT if self.present else NORMAL

    def _apply_grid(self, grid: PanelGrid, specs: dict[str, Any]) -> None:
        """Dock the panels as ``grid`` says: rebuilt if its cells changed, else only resized."""
        gui = self.client.gui
        if self.grid is None or grid.columns != self.grid.columns or set(self._html) != set(specs):
            for panel in self._panel_handles:
                panel.remove()
            self._panel_handles = []
            self._html = {}
            # viser puts each new right-hand column outside the ones docked before: the first is nearest the 3D view.
            for col in grid.columns:
                steps, _ = dock_plan(len(col))
                handles: dict[int, Any] = {}
                for cell, anchor in steps:
                    panel = gui.add_panel()
                    for name in col[cell]:
                        spec = specs[name]
                        if name.startswith(PLOT_KEY):
                            with panel.add_tab(spec.title):
                                self._html[name] = gui.add_html(empty_svg(spec.title))
                            continue
                        with panel.add_tab(f"{name}: image plane"):
                            self._html[name] = gui.add_html(empty_svg(name, spec.width, spec.height))
                    if anchor is None:
                        panel.dock_right()
                    else:
                        panel.dock_below(handles[anchor])
                    handles[cell] = panel
                    self._panel_handles.append(panel)
        self.grid = grid
        self._set_widths(grid)
        # viser applies a new column's dock and a width sent with it in one step, which gives the new column
        # its default width: the widths are sent again once the tab reports its canvas shrunk by the docks.
        self._width_pending = grid if len(grid.columns) > 1 else None

    def _set_widths(self, grid: PanelGrid) -> None:
        """Send the controls' and the panels' widths (a docked panel's width is its region's: the columns,
        docked at one default width, share it equally)."""
        try:
            if self._panel_handles:
                # One column: to its top panel, docked in the first pass. More: to the panel docked last, which
                # waits for its anchor when it is docked below one, so it comes after every column is in place.
                target = self._panel_handles[0] if len(grid.columns) == 1 else self._panel_handles[-1]
                target.set_width(grid.right_px)
            self.client.gui.main_panel.set_width(grid.control_px)
        except Exception:  # noqa: BLE001 - placement is cosmetic
            pass

    def _on_canvas(self, camera: Any) -> None:
        """The tab reported its camera and canvas: once the docks took their room, send the panel widths again."""
        with self.lock:
            grid = self._width_pending
            if self.closed or grid is None or grid is not self.grid:
                return
            try:
                width = float(camera.image_width)
            except (AssertionError, AttributeError, TypeError, ValueError):
                return
            # New columns come at the dock's default width (300 px): wait until the canvas gave up at least most
            # of that room beside the controls, i.e. the docks are in place.
            docked = grid.control_px + 0.9 * DOCK_DEFAULT_PX * len(grid.columns)
            if width > (self._window.width - docked) * self._pixel_ratio:
                return
            self._width_pending = None
            self._set_widths(grid)

    def _panel_view(self, name: str, plane: Any) -> PanelView:
        """What panel ``name`` shows; a new panel, or a new image size, starts from :func:`initial_view`."""
        size = (int(plane.width), int(plane.height))
        kept = self._views.get(name)
        if kept is None or kept[0] != size:
            kept = (size, PanelView(initial_view(plane)))
            self._views[name] = kept
        return kept[1]

    def _panel_svg(self, name: str, plane: Any, scene: Scene, highlighted: set[int]) -> str:
        """Panel ``name``'s SVG: its view, the tab's style, drawn for the width its column has on screen.

        A panel whose image plane is the very object drawn last time (a camera that neither moved nor is in the
        drawn pair: ``compute_derived`` reuses its plane) and whose other inputs are equal keeps its SVG, revision
        included: the same text assigned again is not sent.
        """
        grid = self.grid
        panel_px = grid.column_px if grid is not None and grid.columns else None
        max_height = f"{grid.svg_max_height_px(name):.0f}px" if panel_px is not None else None
        # During a drag a fitted panel holds its view while everything stays in it: still axes, a layout made once.
        kept = self._shown_views.get(name) if self._drag_step else None
        view = self._panel_view(name, plane).resolve(plane, kept=kept)
        self._shown_views[name] = view
        inputs = (scene.selected_point, frozenset(highlighted), scene.options.show_labels, view, self._style, panel_px,
                  max_height)
        kept = self._drawn_panels.get(name)
        if kept is not None and kept[0] is plane and kept[1] == inputs:
            return kept[2]
        svg = image_plane_svg(
            plane,
            selected_point=scene.selected_point,
            highlighted=highlighted,
            show_labels=scene.options.show_labels,
            revision=self.revision,
            view=view,
            style=self._style,
            panel_px=panel_px,
            # The grid leaves room for the SVG in its cell; the cap only keeps a longer status text from scrolling.
            max_height=max_height,
        )
        self._drawn_panels[name] = (plane, inputs, svg)
        return svg

    # -- panel view, downloads, presentation mode ------------------------------------------

    def _build_panel_controls(self) -> None:
        """The "Panels" folder (presentation mode, re-layout) and the style that scales the GUI's type."""
        gui = self.client.gui
        # At the top level: a style inside a closed folder would not be in the page.
        self._gui_style = gui.add_html(PRESENT_GUI_CSS if self.present else "")
        with gui.add_folder("Panels", expand_by_default=False):
            self.present_checkbox = gui.add_checkbox(
                "presentation mode", self.present,
                hint="Large type, thick lines, high contrast: for a projector.")
            self._on(self.present_checkbox.on_update,
                     lambda e: self._user_event(lambda: self._set_present(e.target.value)))
            self.btn_relayout = gui.add_button(
                "Fit panels to the window", hint="Lay the panels out again for this window's present size.")
            self._on(self.btn_relayout.on_click, lambda _: self._user_event(self._relayout))

    def _build_view_buttons(self, name: str) -> None:
        """Zoom, pan, fit and download buttons for camera ``name``'s panel, in the camera's folder."""
        gui = self.client.gui
        groups: dict[str, Any] = {}
        # After the camera's last field, before its Remove button (viser's default orders are whole numbers).
        last = max((float(h.order) for h in self._cam_fields.get(name, {}).values()), default=None)
        order = (lambda k: None) if last is None else (lambda k: last + 0.1 * (k + 1))
        with self._cam_folders[name]:
            for k, (label, actions) in enumerate(VIEW_BUTTONS.items()):
                groups[label] = gui.add_button_group(label, tuple(actions), order=order(k))
                self._on(groups[label].on_click, lambda e, n=name, a=actions: self._user_event(
                    lambda: self._view_action(n, a.get(e.target.value, e.target.value))))
            groups["download panel"] = gui.add_button_group("download panel", DOWNLOAD_FORMATS,
                                                            order=order(len(VIEW_BUTTONS)))
            self._on(groups["download panel"].on_click,
                     lambda e, n=name: self._user_event(lambda: self._download(n, e.target.value)))
        self.panel_buttons[name] = groups

    def _view_action(self, name: str, action: Any) -> None:
        """Apply a view button (one of :data:`~egtviz.viewer.panels.VIEW_ACTIONS`) to panel ``name`` and redraw it."""
        if action not in VIEW_ACTIONS:  # a raw client can send any string
            raise FieldError(f"{name}: no view button {_plain(repr(action), 40)}")
        plane = self.model.derived.image_planes.get(name)
        if plane is None:
            return  # the camera was removed meanwhile
        view = self._panel_view(name, plane).after(action, plane)
        self._views[name] = ((int(plane.width), int(plane.height)), view)
        self._render(self.model.scene, None)

    def _download(self, name: str, fmt: Any) -> None:
        """Send panel ``name`` as it is shown (its view, the tab's style) as an SVG or PNG file."""
        if fmt not in DOWNLOAD_FORMATS:
            raise FieldError(f"{name}: no download format {_plain(repr(fmt), 40)}")
        scene = self.model.scene
        plane = self.model.derived.image_planes.get(name)
        if plane is None:
            raise SceneError(f"{name}: no such camera")
        svg = panel_svg_of(plane, present=self.present, view=self._panel_view(name, plane).resolve(plane),
                           selected_point=scene.selected_point, show_labels=scene.options.show_labels)
        stem = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "_" for c in name)[:40] or "camera"
        if fmt == "PNG":  # rendered in a worker process: this tab gets the file when it is done, others carry on
            self.png.request(f"{stem}-image-plane.png", svg)
            return
        self.client.send_file_download(f"{stem}-image-plane.svg", svg.encode("utf-8"), save_immediately=True)

    def _set_present(self, value: Any) -> None:
        """Presentation mode on or off: the panels' style, the GUI's type and the layout follow."""
        if not isinstance(value, bool):
            raise FieldError(f"presentation mode: expected true or false, got {_plain(repr(value), 40)}")
        if value == self.present:
            return
        self.present = value
        self._gui_style.content = PRESENT_GUI_CSS if value else ""
        self.scene3d.set_label_scale(PRESENT_LABEL_SCALE if value else 1.0)
        self._render(self.model.scene, None)

    @property
    def window(self) -> tuple[WindowSize, float]:
        """The tab's window in CSS pixels and its device pixels per CSS pixel, as this view estimated them."""
        return self._window, self._pixel_ratio

    def _client_window(self) -> tuple[WindowSize, float]:
        """The tab's window in CSS pixels and the device pixels per CSS pixel, from the canvas size it reported."""
        try:
            w, h = self.client.camera.image_width, self.client.camera.image_height
        except (AssertionError, AttributeError):  # no camera message yet (viser asserts one arrived)
            return DEFAULT_WINDOW, 1.0
        window = window_from_canvas(w, h)
        ratio = float(w) / window.width if window is not DEFAULT_WINDOW else 1.0
        return window, ratio

    def _relayout(self) -> None:
        """Plan the panels again for the window as it is now (the canvas plus what is docked beside it)."""
        grid = self.grid
        try:
            w, h = self.client.camera.image_width, self.client.camera.image_height
        except (AssertionError, AttributeError):
            return
        if grid is None or not (w > 0 and h > 0):
            return
        docked = grid.control_px + grid.right_px + DIVIDER_PX * (len(grid.columns) + 1)
        self._window = WindowSize(w / self._pixel_ratio + docked, h / self._pixel_ratio)
        self._render(self.model.scene, None)

    def _frame_camera(self) -> None:
        """Start this tab's 3D view on the whole scene, inside the canvas the docked panels leave free."""
        grid = self.grid
        if grid is None:
            return
        # What the scene holds (mirrors and their CCDs too) and its size: the glyphs are drawn at that size.
        extent = scene_extent(self.model.scene, self.model.derived)
        self.scene3d.set_glyph(extent.glyph)
        aspect = max(grid.canvas_px, 120.0) / grid.window.height
        framed = framed_camera(extent.points, aspect, pad=extent.glyph, min_radius=3.0 * extent.glyph)
        cam = self.client.camera
        try:
            cam.up_direction = (0.0, 0.0, 1.0)
            cam.position = framed.position  # viser moves look_at with the position: set it after
            cam.look_at = framed.look_at
        except (AssertionError, ValueError):  # no camera reported yet: the server's initial camera stays
            pass

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
                sliders = {k for k, fld in _model_fields(spec.model_kind)[0].items() if fld.slider}
                for key, values in _spec_values(spec).items():
                    _set(f[key], values[0] if key in sliders else format_numbers(values))
                for key in model_choices(type(spec)):
                    _set(f[key], getattr(spec, key))
            title = self._title_html()
            # A drag changes one camera's pose and nothing below: skip the rest when its inputs are unchanged.
            rest_key = (scene.camera_names, scene.drawn_pair, len(scene.points), scene.selected_point, scene.options,
                        self.model.can_undo, self.model.undo_barrier_note, title)
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
            _set(self.n_points, self._n_points_text)
            undo_off = not self.model.can_undo and self.model.undo_barrier_note is None  # a barrier explains itself
            if self.btn_undo.disabled != undo_off:
                self.btn_undo.disabled = undo_off
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
            self._typing.close()
            self.png.close()
            self._unsubscribe()


#: Panel keys of a figure's plots start with a control character, which no camera name has.
PLOT_KEY = "\x1fplot "


def _plot_key(number: int) -> str:
    """The panel key of a figure's plot ``Figure <number>``."""
    return f"{PLOT_KEY}{number}"


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
        demo: open this servo demo (``"pinhole"`` or ``"panoramic"``) in every new tab instead of the workbench.
        field_delay: seconds a text field must stay unchanged before it is judged (tests use 0: at once).
        present: every new tab starts in presentation mode (``egtviz --present``).
        course: every new tab starts on the course's start page (:mod:`egtviz.viewer.start_page`): the lessons,
            the learner's name, and the workbench one click away.
        lesson: every new tab opens this lesson (``egtviz lesson NAME``), with the course one click away.
        progress: where learners' progress is kept (a :class:`~egtviz.lessons.ProgressStore`; default: the
            user's data folder).

    A tab whose workbench cannot be built on ``scene`` (it cannot be drawn) gets
    the default scene and a notification saying why; a tab is never left half-built.
    """

    def __init__(self, server: viser.ViserServer, scene: Scene | None = None, *, demo: str | None = None,
                 field_delay: float = FIELD_DELAY, present: bool = False, course: bool = False,
                 lesson: str | None = None, progress: Any = None) -> None:
        if demo not in (None, "pinhole", "panoramic"):
            raise ValueError(f"demo: expected None, 'pinhole' or 'panoramic', got {demo!r}")
        Debouncer(field_delay)  # checks the value now rather than in every tab
        self.field_delay = field_delay
        self.server = server
        self.initial_scene = scene if scene is not None else default_scene()
        #: Open this servo demo in every new tab instead of the workbench.
        self.demo = demo
        #: New tabs start in presentation mode.
        self.present = bool(present)
        self.views: dict[int, ClientView] = {}
        #: The servo demo shown in a tab (``egtviz.viewer.servo_demo.ServoDemo``), by client id.
        self.demos: dict[int, Any] = {}
        self._models: dict[int, SceneModel] = {}
        #: Each tab's window as its last workbench estimated it (a servo demo narrows the canvas it reports).
        self._windows: dict[int, tuple[WindowSize, float]] = {}
        self._lock = threading.Lock()
        self._gone: set[int] = set()
        #: The course (start page, lessons) that new tabs open in; None: the workbench or ``demo``.
        self.course: Any = None
        if course or lesson is not None:
            from .start_page import Course

            self.course = Course(self, lesson=lesson, progress=progress)  # LessonError: no such lesson
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
        """Start the browser's view camera on every camera and point, in the canvas a common window leaves free.

        Each tab then frames its own view for its window (:meth:`ClientView._frame_camera`).
        """
        extent = scene_extent(scene, compute_derived(scene))
        grid = plan_grid([(c.name, float(c.width), float(c.height)) for c in scene.cameras], DEFAULT_WINDOW,
                         style=PRESENT if self.present else NORMAL)
        framed = framed_camera(extent.points, max(grid.canvas_px, 120.0) / DEFAULT_WINDOW.height, pad=extent.glyph,
                               min_radius=3.0 * extent.glyph)
        cam = self.server.initial_camera
        cam.look_at = framed.look_at
        cam.position = framed.position
        cam.up = (0.0, 0.0, 1.0)
        cam.fov = framed.fov

    def show_scene(self, scene: Scene) -> None:
        """Show ``scene`` in every open workbench tab and start new tabs on it (the EGT figure front-end).

        Each tab loads it as a new scene (undoable); new tabs' view camera is framed on it.
        """
        if not isinstance(scene, Scene):
            raise SceneError(f"scene: expected a Scene, got {type(scene).__name__}")
        self.initial_scene = scene
        self._frame_view(scene)
        with self._lock:
            views = list(self.views.values())
        for view in views:
            view.model.load_scene(scene)

    def _connect(self, client: viser.ClientHandle) -> None:
        if self.course is not None:
            self.course.open(client)
            return
        if self.demo is not None:
            self.open_demo(client, self.demo)
            return
        view = self._build_view(client, None)
        with self._lock:
            if client.client_id in self._gone:  # it left while we were building its view
                self._gone.discard(client.client_id)
                view.close()
                return
            self.views[client.client_id] = view

    def _build_view(self, client: viser.ClientHandle, model: SceneModel | None) -> ClientView:
        """The tab's workbench on ``model`` (None: a new model of the initial scene).

        If that fails (a scene that cannot be drawn), the tab is cleared and
        gets the default scene, with a notification giving the reason.
        """
        open_demo = lambda kind, c=client, **options: self.open_demo(c, kind, **options)  # noqa: E731
        window = self._windows.get(client.client_id)
        try:
            return ClientView(client, model or SceneModel(self.initial_scene), open_demo=open_demo,
                              field_delay=self.field_delay, present=self.present, window=window)
        except Exception as exc:  # noqa: BLE001 - the tab must come up whatever the scene holds
            title, body = describe_error(exc)
            if title == "Something went wrong":
                import traceback

                traceback.print_exception(exc)
            client.gui.reset()
            client.scene.reset()
            view = ClientView(client, SceneModel(default_scene()), open_demo=open_demo, field_delay=self.field_delay,
                              present=self.present, window=window)
            client.add_notification("Showing the default scene instead",
                                    f"The scene could not be drawn: {body}", color="red", auto_close_seconds=None)
            return view

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            view = self.views.pop(client.client_id, None)
            demo = self.demos.pop(client.client_id, None)
            self._models.pop(client.client_id, None)
            self._windows.pop(client.client_id, None)
            if view is None and demo is None:
                self._gone.add(client.client_id)
        if view is not None:
            view.close()
        if demo is not None:
            demo.close(client_gone=True)
        if self.course is not None:
            self.course.forget(client.client_id)

    # -- visual-servoing demos (egtviz.viewer.servo_demo) ---------------------------------

    def open_demo(self, client: viser.ClientHandle, kind: str, **options: Any) -> Any:
        """Replace the tab's workbench by a servo demo (its scene is kept for the way back); ``options``: the
        demo's run fields (``seed``, ``beta``, ...: ``make_servo_demo``)."""
        from .servo_demo import make_servo_demo

        cid = client.client_id
        with self._lock:
            view = self.views.pop(cid, None)
            old = self.demos.pop(cid, None)
        if view is not None:
            view.close()
            self._models[cid] = view.model
            self._windows[cid] = view.window
        if old is not None:
            old.close()
        client.gui.reset()
        client.scene.reset()
        present = view.present if view is not None else self.present  # the tab's own choice, if it made one
        try:
            demo = make_servo_demo(client, kind, on_back=lambda: self.close_demo(client),
                                   field_delay=self.field_delay, present=present, **options)
        except Exception as exc:  # noqa: BLE001 - back to a working workbench, with the reason
            import traceback

            traceback.print_exception(exc)
            self.close_demo(client)
            notify_error(client, exc, title="Could not open the demo")
            return None
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
        view = self._build_view(client, model)
        with self._lock:
            if cid in self._gone:
                self._gone.discard(cid)
                view.close()
                return None
            self.views[cid] = view
        if self.course is not None:  # the lesson (or the way back to the course) the tab had before the demo
            self.course.restore(client, view)
        return view

    def show_workbench(self, client: viser.ClientHandle, model: SceneModel | None = None) -> ClientView | None:
        """Replace what the tab shows by a workbench on ``model`` (None: a new model of the initial scene).

        Returns the tab's view, or None if the tab left meanwhile.
        """
        self.clear_tab(client)
        view = self._build_view(client, model)
        with self._lock:
            if client.client_id in self._gone:
                self._gone.discard(client.client_id)
                view.close()
                return None
            self.views[client.client_id] = view
        return view

    def clear_tab(self, client: viser.ClientHandle) -> None:
        """Close the tab's workbench or servo demo and empty its GUI and 3D scene."""
        cid = client.client_id
        with self._lock:
            view = self.views.pop(cid, None)
            demo = self.demos.pop(cid, None)
        if view is not None:
            view.close()
        if demo is not None:
            demo.close()
        client.gui.reset()
        client.scene.reset()

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
