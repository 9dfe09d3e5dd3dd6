"""The workbench's controls: the drawn pair, points and surfaces, the add-camera buttons, what the 3D view shows,
the servo demos, undo and reset, built-in scenes, and saving and loading scene files.

Each widget maps to one intent of the tab's controller (:class:`~egtviz.controllers.workbench.WorkbenchController`),
which checks every drop-down value against the options offered (a hand-written client can send any string) and
every count in its units. Scene files travel through the browser (download and upload), never by a server path.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from html import escape
from typing import TYPE_CHECKING

from ...controllers.workbench_fields import plain
from ...geometry.camera_model import CAMERA_MODELS
from ...scene import Scene, limits
from .gui_text import set_value
from ..render.panels import CONTROL_PX

if TYPE_CHECKING:
    import viser

    from .tab_context import TabContext

__all__ = ["SERVO_DEMOS", "WorkbenchControls"]

#: The servo demos' buttons: demo kind -> label.
SERVO_DEMOS = {"pinhole": "Pin-hole camera on a Puma 560", "panoramic": "Panoramic camera on a mobile robot"}
_TOGGLES = (("show_rays", "projection rays"), ("show_planes", "epipolar plane"), ("show_frames", "camera frames"),
            ("show_labels", "labels"), ("show_surfaces", "surfaces"))


class WorkbenchControls:
    """The tab's control panel (left dock) apart from the camera folders' own fields.

    Args:
        tab: the tab's services (its client, controller and event wrappers are used).
        open_demo: ``open_demo(kind)`` replaces the tab by a visual-servoing demo; None: no such folder.
    """

    def __init__(self, tab: TabContext, *, open_demo: Callable[[str], object] | None = None) -> None:
        self.tab = tab
        self.open_demo = open_demo
        self._synced_rest: tuple | None = None

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
            tab.on(self.pair_dropdown.on_update,
                   lambda _: tab.user_event(lambda: tab.controller.set_pair(self.pair_dropdown.value)))
            self.readout_md = gui.add_html("")
        with gui.add_folder("Points", expand_by_default=True):
            self._build_points()
        with gui.add_folder("Cameras", expand_by_default=True):
            # One button per registered camera model.
            self.add_buttons = {}
            for kind, info in CAMERA_MODELS.items():
                self.add_buttons[kind] = self._button(f"Add {info.label[0].lower()}{info.label[1:]}",
                                                      functools.partial(tab.controller.add_camera, kind))
            self.cameras_folder = gui.add_folder("Camera settings", expand_by_default=True)
        with gui.add_folder("Show", expand_by_default=False):
            self.toggles = {}
            for opt, label in _TOGGLES:
                cb = gui.add_checkbox(label, getattr(tab.controller.scene.options, opt))

                def toggled(e: viser.GuiEvent[viser.GuiCheckboxHandle], opt: str = opt) -> None:
                    tab.user_event(lambda: tab.controller.set_option(opt, e.target.value))

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
        controller = tab.controller
        tab.on(self.point_dropdown.on_update,
               lambda _: tab.user_event(lambda: controller.select_point(self.point_dropdown.value)))
        self.n_points = gui.add_text("how many (randomise)", controller.point_count_text,
                                     hint=f"A whole number from 0 to {limits.MAX_POINTS}.")
        tab.on(self.n_points.on_update,
               lambda e: tab.text_event("n_points", controller.set_point_count, e.target.value))
        self.btn_random = self._button("Randomise points", lambda: controller.randomise_points(self.n_points.value))
        self.btn_add_point = self._button("Add point", controller.add_point)
        self.btn_remove_point = self._button("Remove selected (or last) point", controller.remove_point)
        self.surface_kind = gui.add_dropdown("surface", tuple(controller.surfaces), initial_value="sphere")
        self.btn_surface = self._button("Add surface", lambda: controller.add_surface(self.surface_kind.value))

    def _build_scene_actions(self) -> None:
        tab, gui, controller = self.tab, self.tab.client.gui, self.tab.controller
        self.btn_undo = self._button("Undo", self._undo)
        self.btn_reset = self._button("Reset", controller.reset)
        self.builtin = gui.add_dropdown("built-in scene", controller.builtin_scenes,
                                        initial_value=controller.builtin_scenes[0],
                                        hint="A ready-made scene; Open replaces this tab's scene (undoable).")
        self.btn_open = self._button("Open built-in scene", lambda: controller.open_builtin(self.builtin.value))
        self.btn_save = self._button("Save (download)", self._save, hint="Download this tab's scene as a JSON file.")
        self.btn_load = gui.add_upload_button(
            "Load (upload)", mime_type="application/json",
            hint=f"Open a scene file from this computer (at most {limits.MAX_SCENE_FILE_BYTES // 1000} kB).")
        tab.on(self.btn_load.on_upload, lambda _: tab.user_event(self._load))

    def title_html(self) -> str:
        """The scene's title and a figure's messages (what its drawing calls could not draw), escaped."""
        scene = self.tab.controller.scene
        title = escape(plain(scene.title or "egtviz", limits.MAX_TITLE_LENGTH))
        notes = "".join(f'<br><span data-egtviz="figure-message" style="color:#a00">{escape(plain(m, 200))}</span>'
                        for m in scene.annotations.messages)
        return (f'<div style="font-size:0.9em;padding:0 0.6em"><b>{title}</b><br>Drag the gizmos or edit the fields; '
                f"the image planes are in the panels on the right. Point numbers match in 3D and in the images.{notes}"
                "</div>")

    # -- actions ---------------------------------------------------------------------------------------

    def _undo(self) -> None:
        """Undo one change; at an undo barrier (a lesson step's start) say why nothing happened."""
        note = self.tab.controller.undo()
        if note is not None:
            self.tab.client.add_notification("Nothing to undo", note, color="yellow", auto_close_seconds=8.0)

    def _save(self) -> None:
        saved = self.tab.controller.save()
        self.tab.client.send_file_download(saved.name, saved.content, save_immediately=True)

    def _load(self) -> None:
        upload = self.btn_load.value
        self.tab.controller.load(getattr(upload, "name", "") or "", getattr(upload, "content", None))

    # -- write-back --------------------------------------------------------------------------------------

    def sync(self, scene: Scene, *, force: bool) -> None:
        """Write the model's pair, points, options, undo state and title into the controls.

        ``force=False`` (a render): skipped when nothing they show changed (a drag moves one camera's pose only).
        """
        controller = self.tab.controller
        title = self.title_html()
        rest_key = (scene.camera_names, scene.drawn_pair, len(scene.points), scene.selected_point, scene.options,
                    controller.undo_enabled, title)
        if not force and rest_key == self._synced_rest:
            return
        self._synced_rest = rest_key
        drawn = scene.drawn_pair
        options = tuple(controller.pair_choices()) or ("-",)
        if tuple(self.pair_dropdown.options) != options:
            self.pair_dropdown.options = options
        set_value(self.pair_dropdown, f"{drawn[0]} & {drawn[1]}" if drawn else "-")
        if len(self.point_dropdown.options) != len(scene.points) + 1:  # "none", then one per point
            self.point_dropdown.options = tuple(controller.point_choices())
        sel = scene.selected_point
        set_value(self.point_dropdown, "none" if sel is None else f"point {sel + 1}")
        for opt, cb in self.toggles.items():
            set_value(cb, getattr(scene.options, opt))
        set_value(self.n_points, controller.point_count_text)
        undo_off = not controller.undo_enabled  # a barrier explains itself
        if self.btn_undo.disabled != undo_off:
            self.btn_undo.disabled = undo_off
        if self.title.content != title:
            self.title.content = title
