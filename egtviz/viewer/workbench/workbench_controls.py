"""The workbench's controls and scene actions: the drawn pair, points and surfaces, the add-camera buttons, what
the 3D view shows, the servo demos, undo and reset, built-in scenes, and saving and loading scene files.

Scene files travel through the browser (download and upload), never by a server path. Every drop-down value is
checked against the options offered, since a hand-written client can send any string.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable
from html import escape
from typing import TYPE_CHECKING, Literal

from ...geometry.camera_model import CAMERA_MODELS
from ...scene import (
    SCENES,
    Scene,
    SceneError,
    SceneFileError,
    SurfaceSpec,
    limits,
    mesh_names,
    scene_from_bytes,
    scene_to_bytes,
)
from .fields import FieldError, NumberRule, parse_numbers
from .gui_text import plain, set_value
from ..render.panels import CONTROL_PX

if TYPE_CHECKING:
    import viser

    from .tab_context import TabContext

__all__ = ["POINTS_RULE", "SERVO_DEMOS", "SURFACE_KINDS", "WorkbenchControls"]

#: The "how many points" field: what the page offers is what the server accepts.
POINTS_RULE = (NumberRule("how many points", "", 0, limits.MAX_POINTS, integer=True),)
SURFACE_KINDS: tuple[Literal["plane", "sphere"], ...] = ("plane", "sphere")
#: The servo demos' buttons: demo kind -> label.
SERVO_DEMOS = {"pinhole": "Pin-hole camera on a Puma 560", "panoramic": "Panoramic camera on a mobile robot"}
_TOGGLES = (("show_rays", "projection rays"), ("show_planes", "epipolar plane"), ("show_frames", "camera frames"),
            ("show_labels", "labels"), ("show_surfaces", "surfaces"))


def _pair_choices(scene: Scene) -> dict[str, tuple[str, str]]:
    """The "drawn pair" drop-down's options: every pair of the scene's cameras, and the drawn pair whatever it is."""
    pairs = {f"{a} & {b}": (a, b) for a, b in itertools.combinations(scene.camera_names, 2)}
    drawn = scene.drawn_pair
    if drawn is not None and f"{drawn[0]} & {drawn[1]}" not in pairs:
        pairs[f"{drawn[0]} & {drawn[1]}"] = drawn
    return pairs


def _file_name(title: str) -> str:
    """The download's file name: the scene title reduced to letters, digits, ``-`` and ``_``."""
    stem = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "_" for c in title.strip())[:40].strip("_")
    return f"{stem or 'scene'}.json"


class WorkbenchControls:
    """The tab's control panel (left dock) apart from the camera folders' own fields.

    Args:
        tab: the tab's services (its client, model and event wrappers are used).
        open_demo: ``open_demo(kind)`` replaces the tab by a visual-servoing demo; None: no such folder.
    """

    def __init__(self, tab: TabContext, *, open_demo: Callable[[str], object] | None = None) -> None:
        self.tab = tab
        self.open_demo = open_demo
        self._synced_rest: tuple | None = None
        self._surface_options: dict[str, tuple[Literal["plane", "sphere", "mesh"], str]] = {}
        self._n_points_text = "8"

    def _button(self, label: str, action: Callable[[], object], *, hint: str | None = None) -> viser.GuiButtonHandle:
        """A button whose click runs ``action`` as a user event."""
        tab = self.tab
        button = tab.client.gui.add_button(label, hint=hint)
        tab.on(button.on_click, lambda _: tab.user_event(action))
        return button

    def build(self, *, present: bool) -> None:
        """Build the control panel, top to bottom (``present``: sized for presentation mode)."""
        tab, gui = self.tab, self.tab.client.gui
        gui.configure_theme(dark_mode=False, show_logo=False)
        try:
            gui.main_panel.dock_left()
            gui.main_panel.set_width(CONTROL_PX["present" if present else "normal"])
        except Exception:  # noqa: BLE001 - placement is cosmetic
            pass
        # HTML, not markdown: the title comes from a file and is escaped as text.
        self.title = gui.add_html(self.title_html())
        with gui.add_folder("Epipolar geometry", expand_by_default=True):
            self.pair_dropdown = gui.add_dropdown("drawn pair", ["-"],
                                                  hint="Which two cameras' epipolar geometry is drawn.")
            tab.on(self.pair_dropdown.on_update, lambda _: tab.user_event(self._set_pair))
            self.readout_md = gui.add_html("")
        with gui.add_folder("Points", expand_by_default=True):
            self._build_points()
        with gui.add_folder("Cameras", expand_by_default=True):
            # One button per registered camera model.
            self.add_buttons = {}
            for kind, info in CAMERA_MODELS.items():
                self.add_buttons[kind] = self._button(f"Add {info.label[0].lower()}{info.label[1:]}",
                                                      functools.partial(tab.model.add_camera, kind))
            self.cameras_folder = gui.add_folder("Camera settings", expand_by_default=True)
        with gui.add_folder("Show", expand_by_default=False):
            self.toggles = {}
            for opt, label in _TOGGLES:
                cb = gui.add_checkbox(label, getattr(tab.model.scene.options, opt))

                def toggled(e: viser.GuiEvent[viser.GuiCheckboxHandle], opt: str = opt) -> None:
                    tab.user_event(lambda: self._toggle(opt, e.target.value))

                tab.on(cb.on_update, toggled)
                self.toggles[opt] = cb
        #: The visual-servoing demos' buttons by demo kind (``pinhole``, ``panoramic``); empty: no demos here.
        self.servo_buttons: dict[str, viser.GuiButtonHandle] = {}
        open_demo = self.open_demo
        if open_demo is not None:
            with gui.add_folder("Visual servoing", expand_by_default=False):
                for kind, label in SERVO_DEMOS.items():
                    button = self.servo_buttons[kind] = gui.add_button(label)

                    def clicked(_: viser.GuiEvent[viser.GuiButtonHandle], k: str = kind) -> None:
                        open_demo(k)

                    tab.on(button.on_click, clicked)
        with gui.add_folder("Scene", expand_by_default=False):
            self._build_scene_actions()

    def _build_points(self) -> None:
        tab, gui = self.tab, self.tab.client.gui
        self.point_dropdown = gui.add_dropdown("selected point", ["none"],
                                               hint="The selected point's epipolar plane is drawn in 3D.")
        tab.on(self.point_dropdown.on_update, lambda _: tab.user_event(self._select))
        self.n_points = gui.add_text("how many (randomise)", self._n_points_text,
                                     hint=f"A whole number from 0 to {limits.MAX_POINTS}.")
        tab.on(self.n_points.on_update,
               lambda e: tab.text_event("n_points", self._check_n_points, e.target.value))
        self.btn_random = self._button("Randomise points", self._randomise)
        self.btn_add_point = self._button("Add point", lambda: tab.model.add_point((0.0, 0.0, 1.0)))
        self.btn_remove_point = self._button("Remove selected (or last) point", self._remove_point)
        self._surface_options = {k: (k, "") for k in SURFACE_KINDS}
        self._surface_options.update({f"mesh: {m}": ("mesh", m) for m in mesh_names()})
        self.surface_kind = gui.add_dropdown("surface", tuple(self._surface_options), initial_value="sphere")
        self.btn_surface = self._button("Add surface", self._add_surface)

    def _build_scene_actions(self) -> None:
        tab, gui = self.tab, self.tab.client.gui
        self.btn_undo = self._button("Undo", self._undo)
        self.btn_reset = self._button("Reset", tab.model.reset)
        self.builtin = gui.add_dropdown("built-in scene", tuple(SCENES), initial_value=next(iter(SCENES)),
                                        hint="A ready-made scene; Open replaces this tab's scene (undoable).")
        self.btn_open = self._button("Open built-in scene", self._open_builtin)
        self.btn_save = self._button("Save (download)", self._save, hint="Download this tab's scene as a JSON file.")
        self.btn_load = gui.add_upload_button(
            "Load (upload)", mime_type="application/json",
            hint=f"Open a scene file from this computer (at most {limits.MAX_SCENE_FILE_BYTES // 1000} kB).")
        tab.on(self.btn_load.on_upload, lambda _: tab.user_event(self._load))

    def title_html(self) -> str:
        """The scene's title and a figure's messages (what its drawing calls could not draw), escaped."""
        scene = self.tab.model.scene
        title = escape(plain(scene.title or "egtviz", limits.MAX_TITLE_LENGTH))
        notes = "".join(f'<br><span data-egtviz="figure-message" style="color:#a00">{escape(plain(m, 200))}</span>'
                        for m in scene.annotations.messages)
        return (f'<div style="font-size:0.9em;padding:0 0.6em"><b>{title}</b><br>Drag the gizmos or edit the fields; '
                f"the image planes are in the panels on the right. Point numbers match in 3D and in the images.{notes}"
                "</div>")

    # -- actions ---------------------------------------------------------------------------------------

    def _undo(self) -> None:
        """Undo one change; at an undo barrier (a lesson step's start) say why nothing happened."""
        model = self.tab.model
        if not model.undo() and model.undo_barrier_note is not None:
            self.tab.client.add_notification("Nothing to undo", model.undo_barrier_note, color="yellow",
                                              auto_close_seconds=8.0)

    def _check_n_points(self, text: str) -> None:
        parse_numbers(text, POINTS_RULE)
        self._n_points_text = text  # the last valid count: a refused one reverts to it

    def _set_pair(self) -> None:
        value = self.pair_dropdown.value
        # The options as last written: the model's scene, since every change is written back under the lock.
        pair = _pair_choices(self.tab.model.scene).get(value)
        if pair is None:
            raise FieldError(f"drawn pair: no pair {plain(repr(value), 40)}")
        if pair != self.tab.model.scene.drawn_pair:
            self.tab.model.set_pair(*pair)

    def _select(self) -> None:
        v = self.point_dropdown.value
        n = len(self.tab.model.scene.points)
        options = {"none": None} | {f"point {i + 1}": i for i in range(n)}
        if v not in options:
            raise FieldError(f"selected point: no {plain(repr(v), 40)} (have {n} points)")
        idx = options[v]
        if idx != self.tab.model.scene.selected_point:
            self.tab.model.select_point(idx)

    def _toggle(self, opt: str, value: object) -> None:
        if not isinstance(value, bool):
            raise FieldError(f"{opt}: expected true or false, got {plain(repr(value), 40)}")
        if getattr(self.tab.model.scene.options, opt) != value:
            self.tab.model.set_option(opt, value)

    def _centre(self) -> tuple[float, float, float]:
        X = self.tab.model.scene.points_array()
        return tuple(X.mean(axis=0)) if len(X) else (0.0, 0.0, 1.0)

    def _randomise(self) -> None:
        (n,) = parse_numbers(self.n_points.value, POINTS_RULE)
        self.tab.model.randomize_points(int(n), center=self._centre(), extent=2.0)

    def _remove_point(self) -> None:
        scene = self.tab.model.scene
        if not scene.points:
            raise SceneError("no points to remove")
        self.tab.model.remove_point(scene.selected_point if scene.selected_point is not None
                                     else len(scene.points) - 1)

    def _add_surface(self) -> None:
        choice = self._surface_options.get(self.surface_kind.value)
        if choice is None:  # a raw client can send any string: only the listed surfaces exist
            raise FieldError(f"surface: no surface {plain(repr(self.surface_kind.value), 40)}")
        kind, mesh = choice
        centre = self._centre()
        if kind == "mesh":
            # A mesh of the package's own, standing on the ground under the points.
            self.tab.model.add_surface(
                SurfaceSpec(kind="mesh", center=(centre[0], centre[1], 0.0), size=2.0, samples=300, path=mesh)
            )
            return
        size = 1.0 if kind == "sphere" else 3.0
        self.tab.model.add_surface(SurfaceSpec(kind=kind, center=centre, size=size, samples=200))

    def _open_builtin(self) -> None:
        name = self.builtin.value
        if name not in SCENES:  # a raw client can send any string
            raise FieldError(f"built-in scene: no scene {plain(repr(name), 40)}; "
                             f"the built-in scenes are {', '.join(SCENES)}")
        self.tab.model.load_scene(SCENES[name]())

    def _save(self) -> None:
        scene = self.tab.model.scene
        self.tab.client.send_file_download(_file_name(scene.title or "scene"), scene_to_bytes(scene),
                                            save_immediately=True)

    def _load(self) -> None:
        upload = self.btn_load.value
        name = plain(getattr(upload, "name", "") or "the upload", 60)
        content = getattr(upload, "content", None)
        if not isinstance(content, bytes):
            raise SceneFileError(f"{name}: the upload holds no file")
        if len(content) > limits.MAX_SCENE_FILE_BYTES:  # before parsing: a big file is refused unread
            raise SceneFileError(f"{name}: the file has {len(content)} bytes; a scene file has at most "
                                 f"{limits.MAX_SCENE_FILE_BYTES} bytes")
        self.tab.model.load_scene(scene_from_bytes(content, source=name))

    # -- write-back --------------------------------------------------------------------------------------

    def sync(self, scene: Scene, *, force: bool) -> None:
        """Write the model's pair, points, options, undo state and title into the controls.

        ``force=False`` (a render): skipped when nothing they show changed (a drag moves one camera's pose only).
        """
        model = self.tab.model
        title = self.title_html()
        rest_key = (scene.camera_names, scene.drawn_pair, len(scene.points), scene.selected_point, scene.options,
                    model.can_undo, model.undo_barrier_note, title)
        if not force and rest_key == self._synced_rest:
            return
        self._synced_rest = rest_key
        drawn = scene.drawn_pair
        options = tuple(_pair_choices(scene)) or ("-",)
        if tuple(self.pair_dropdown.options) != options:
            self.pair_dropdown.options = options
        set_value(self.pair_dropdown, f"{drawn[0]} & {drawn[1]}" if drawn else "-")
        if len(self.point_dropdown.options) != len(scene.points) + 1:  # "none", then one per point
            self.point_dropdown.options = ("none",) + tuple(f"point {i + 1}" for i in range(len(scene.points)))
        sel = scene.selected_point
        set_value(self.point_dropdown, "none" if sel is None else f"point {sel + 1}")
        for opt, cb in self.toggles.items():
            set_value(cb, getattr(scene.options, opt))
        set_value(self.n_points, self._n_points_text)
        undo_off = not model.can_undo and model.undo_barrier_note is None  # a barrier explains itself
        if self.btn_undo.disabled != undo_off:
            self.btn_undo.disabled = undo_off
        if self.title.content != title:
            self.title.content = title
