"""A student's tab while it follows the instructor: the room's scene, shown as the instructor's tab drew it.

Nothing is computed here per follower: a :class:`RoomFrame` carries the instructor's scene, its derived
geometry (computed once, when the instructor's model committed it) and the very SVG strings of the instructor's
panels and read-out; every follower is given the same objects. A panel whose SVG is the object already shown is
not sent again. The 3D view draws the same scene and derived arrays, and its nodes are handed the arrays the
instructor's tab prepared from them (``egtviz.viewer.workbench.models.shared``): a follower only assigns them.

A follower cannot change the room's scene: there is no field to edit, and a gizmo moved in the browser is
refused (the tab is told why) and put back.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import viser

from ...scene import Derived, Scene, SceneError
from ...scene.extent import scene_extent
from ..render.palette import PRESENT_GUI_CSS
from ..render.panels import DEFAULT_WINDOW, WindowSize, dock_plan, framed_camera, plan_grid, window_from_canvas
from ..render.svg import NORMAL, PRESENT
from ..workbench.fields import notify_error

__all__ = ["FOLLOW_REFUSAL", "FollowView", "RoomFrame"]

#: What a follower is told when it tries to move something in the room's scene.
FOLLOW_REFUSAL = "You are following the instructor: the scene is theirs. Leave follow to work on your own scene."


@dataclass(frozen=True)
class RoomFrame:
    """What every follower shows: one drawn update of the instructor's tab.

    Attributes:
        number: grows with every frame the room is sent.
        version: the classroom's shared version the scene belongs to.
        scene: the instructor's scene.
        derived: its derived geometry (:attr:`egtviz.scene.SceneModel.derived`).
        panels: ``(key, tab title, svg)`` of each panel, in the instructor's order.
        readout: the F/E read-out's HTML.
        present: drawn in presentation mode.
        caption: the lesson step the instructor is on (its title and text, HTML), ``""`` outside a lesson.
    """

    number: int
    version: int
    scene: Scene
    derived: Derived
    panels: tuple[tuple[str, str, str], ...]
    readout: str
    present: bool
    caption: str = ""


class FollowView:
    """One following student's tab. Call :meth:`show` with each new frame, :meth:`close` when it stops following.

    Args:
        client: the tab's viser client.
        frame: the room's frame at the start (None: the instructor has shown nothing yet).
        present: start in presentation mode (large type); a frame drawn in presentation mode turns it on too.
        window: the tab's window and device pixel ratio as a workbench it showed before measured them (None:
            from the canvas it reports now, before this view docks its controls).
    """

    def __init__(self, client: viser.ClientHandle, frame: RoomFrame | None, *, present: bool = False,
                 window: tuple[WindowSize, float] | None = None) -> None:
        from ..workbench.scene3d import Scene3D

        self.client = client
        self.lock = threading.RLock()
        self.closed = False
        self.frame: RoomFrame | None = None
        self._html: dict[str, viser.GuiHtmlHandle] = {}
        self._shown: dict[str, str] = {}
        self._panels: list[viser.PanelHandle] = []
        self._layout_key: tuple | None = None
        self.present = False
        # Measured once, before the controls dock and narrow the canvas (as the workbench's panel dock does).
        #: The tab's window (CSS pixels) and its device pixels per CSS pixel.
        measured: tuple[WindowSize, float] = window if window is not None else self._canvas_window()
        self.window, self.pixel_ratio = measured
        with self.lock, client.atomic():
            try:  # docked on the left, as in the workbench: the scene in the middle, the panels on the right
                client.gui.main_panel.dock_left()
            except Exception:  # noqa: BLE001 - placement is cosmetic
                pass
            self.style = client.gui.add_html("")
            self.note = client.gui.add_markdown("The instructor has not shown a scene yet." if frame is None else "")
            self.caption = client.gui.add_html("")
            self.readout = client.gui.add_html("")
            self.scene3d = Scene3D(client.scene, self.camera_event, self.point_event, report=self.report)
            self._set_present(present)
        if frame is not None:
            self.show(frame)

    # -- a follower may look, not touch ---------------------------------------------------------------

    def camera_event(self, name: str, event: object) -> None:
        """A camera's gizmo moved in the browser: refused (:meth:`report` puts it back)."""
        raise SceneError(FOLLOW_REFUSAL)

    def point_event(self, index: int, event: object) -> None:
        """A point's gizmo moved in the browser: refused."""
        raise SceneError(FOLLOW_REFUSAL)

    def report(self, exc: BaseException) -> None:
        """Tell the tab why, and put every gizmo back where the room's scene has it."""
        with self.lock:
            if self.closed:
                return
            notify_error(self.client, exc, title="Following the instructor")
            frame = self.frame
            if frame is not None:
                with self.client.atomic():
                    self.scene3d.draw(frame.scene, frame.derived, force=True)
                self.client.flush()

    # -- showing a frame ------------------------------------------------------------------------------

    def show(self, frame: RoomFrame) -> None:
        """Show ``frame`` (an older one than shown is ignored); only what changed is sent."""
        with self.lock:
            if self.closed or (self.frame is not None and frame.number <= self.frame.number):
                return
            first = self.frame is None
            with self.client.atomic():
                self._set_present(self.present or frame.present)
                self._layout(frame)
                for key, _title, svg in frame.panels:
                    handle = self._html.get(key)
                    if handle is not None and self._shown.get(key) is not svg:
                        handle.content = svg
                        self._shown[key] = svg
                if first:
                    self.note.content = ""
                if self.frame is None or self.frame.readout is not frame.readout:
                    self.readout.content = frame.readout
                if self.frame is None or self.frame.caption != frame.caption:
                    self.caption.content = frame.caption
                self.scene3d.draw(frame.scene, frame.derived)
                if first:
                    self._frame_camera(frame)
            self.frame = frame
        self.client.flush()

    def _set_present(self, present: bool) -> None:
        if present == self.present:
            return
        from ..workbench.panel_dock import PRESENT_LABEL_SCALE

        self.present = present
        self.style.content = PRESENT_GUI_CSS if present else ""
        self.scene3d.set_label_scale(PRESENT_LABEL_SCALE if present else 1.0)

    def _canvas_window(self) -> tuple[WindowSize, float]:
        try:
            width = self.client.camera.image_width
            window = window_from_canvas(width, self.client.camera.image_height)
        except (AssertionError, AttributeError):
            return DEFAULT_WINDOW, 1.0
        return window, (float(width) / window.width if window is not DEFAULT_WINDOW else 1.0)

    def _layout(self, frame: RoomFrame) -> None:
        """Dock one panel per image plane, as the grid for this tab's window places them (again only when the
        set of panels changes)."""
        key = tuple((k, t) for k, t, _ in frame.panels) + (frame.present,)
        if key == self._layout_key:
            return
        for panel in self._panels:
            panel.remove()
        self._panels, self._html, self._shown = [], {}, {}
        sizes = {c.name: (float(c.width), float(c.height)) for c in frame.scene.cameras}
        cells = [(k, *sizes.get(k, (640.0, 480.0))) for k, _t, _s in frame.panels]
        titles = {k: t for k, t, _ in frame.panels}
        if cells:
            grid = plan_grid(cells, self.window, style=PRESENT if frame.present else NORMAL)
            gui = self.client.gui
            for column in grid.columns:
                steps, _ = dock_plan(len(column))
                handles: dict[int, viser.PanelHandle] = {}
                for cell, anchor in steps:
                    panel = gui.add_panel()
                    for name in column[cell]:
                        with panel.add_tab(titles[name]):
                            self._html[name] = gui.add_html("")
                    if anchor is None:
                        panel.dock_right()
                    else:
                        panel.dock_below(handles[anchor])
                    handles[cell] = panel
                    self._panels.append(panel)
            try:
                self._panels[-1 if len(grid.columns) > 1 else 0].set_width(grid.right_px)
                gui.main_panel.set_width(grid.control_px)
            except Exception:  # noqa: BLE001 - placement is cosmetic
                pass
        self._layout_key = key

    def _frame_camera(self, frame: RoomFrame) -> None:
        extent = scene_extent(frame.scene, frame.derived)
        self.scene3d.set_glyph(extent.glyph)
        window = self.window
        framed = framed_camera(extent.points, max(window.width * 0.5, 120.0) / window.height, pad=extent.glyph,
                               min_radius=3.0 * extent.glyph)
        try:
            cam = self.client.camera
            cam.up_direction = (0.0, 0.0, 1.0)
            cam.position = framed.position
            cam.look_at = framed.look_at
        except (AssertionError, ValueError):
            pass

    def set_camera(self, position: tuple[float, float, float], look_at: tuple[float, float, float],
                   up: tuple[float, float, float]) -> None:
        """Put this tab's view camera where the instructor's is (cameras locked)."""
        with self.lock:
            if self.closed:
                return
            try:
                cam = self.client.camera
                cam.up_direction = up
                cam.position = position
                cam.look_at = look_at
            except (AssertionError, ValueError):
                pass

    def close(self) -> None:
        """Stop showing frames (the tab's GUI and scene are cleared by whoever shows something else)."""
        with self.lock:
            self.closed = True
