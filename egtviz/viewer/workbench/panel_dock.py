"""The image-plane panels of a workbench tab: their grid and dock, each panel's view, downloads, presentation mode.

The grid follows the tab's window (:func:`~egtviz.viewer.render.panels.plan_grid`); each panel keeps its own view (zoom,
pan, fit: :class:`~egtviz.viewer.render.panels.PanelView`), and an SVG whose inputs did not change is not drawn again.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from ...controllers.workbench_fields import FieldError, plain
from ...scene import CameraSpec, Scene, SceneError
from ...scene.annotations import Plot
from ...scene.extent import scene_extent
from ..render.figure_export import panel_svg_of
from ..render.palette import PRESENT_GUI_CSS
from ..render.panels import (
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
from ..render.plot_svg import plot_svg
from ..render.png_worker import PngDownloads
from ..render.panel_view import ViewBox
from ..render.svg import NORMAL, PRESENT, PanelStyle, empty_svg, image_plane_svg

if TYPE_CHECKING:
    import viser

    from ...scene.derived import ImagePlane
    from .camera_settings import FieldHandle
    from .scene3d import Scene3D
    from .tab_context import TabContext

__all__ = ["DOWNLOAD_FORMATS", "PLOT_KEY", "PanelDock", "VIEW_BUTTONS", "plot_key"]

#: The per-panel buttons in each camera's folder: label -> (button text -> view action of :class:`PanelView`).
VIEW_BUTTONS = {
    "panel view": {"fit": "fit", "image": "image", "+": "+", "\u2212": "-"},
    "panel pan": {"\u2190": "left", "\u2192": "right", "\u2191": "up", "\u2193": "down"},
}
DOWNLOAD_FORMATS = ("SVG", "PNG")
#: The width viser's dock gives a new docked column (CSS pixels).
DOCK_DEFAULT_PX = 300.0
#: How much larger the 3D view's labels (point numbers, camera names) are in presentation mode.
PRESENT_LABEL_SCALE = 1.6
#: Panel keys of a figure's plots start with a control character, which no camera name has.
PLOT_KEY = "\x1fplot "


def plot_key(number: int) -> str:
    """The panel key of a figure's plot ``Figure <number>``."""
    return f"{PLOT_KEY}{number}"


class PanelDock:
    """The tab's panels: where they are, what each shows, and the "Panels" folder.

    Args:
        tab: the tab's services (its client, controller, event wrappers, lesson policy and render are used).
        scene3d: the tab's 3D view (its labels follow presentation mode; its glyphs, the scene's size).
        present: start in presentation mode.
        window: the tab's window and device pixel ratio if known (a tab back from a servo demo), else None.
    """

    def __init__(self, tab: TabContext, scene3d: Scene3D, *, present: bool,
                 window: tuple[WindowSize, float] | None) -> None:
        self.tab = tab
        self.scene3d = scene3d
        self.client = tab.client
        #: Presentation mode (larger type and lines in the panels and the GUI).
        self.present = bool(present)
        # A tab coming back from a servo demo reports the demo's narrowed canvas: the app passes the window
        # its previous workbench had measured instead.
        self.window, self.pixel_ratio = window if window is not None else self._client_window()
        #: Where the panels are (see :func:`egtviz.viewer.render.panels.plan_grid`); None before the first layout.
        self.grid: PanelGrid | None = None
        self._grid_key: tuple | None = None
        self._width_pending: PanelGrid | None = None
        self._panel_handles: list[viser.PanelHandle] = []
        #: Each panel's HTML element, by camera name or plot key.
        self.html: dict[str, viser.GuiHtmlHandle] = {}
        #: What each panel shows, with the image size it was chosen for: ``name -> ((width, height), PanelView)``.
        self._views: dict[str, tuple[tuple[int, int], PanelView]] = {}
        #: Per panel, the lesson step's view last applied (a step applies its view once: the buttons then move it).
        self._step_views: dict[str, tuple[int, PanelView]] = {}
        #: Each panel's view as last drawn (a fitted panel's steady view during a drag).
        self._shown_views: dict[str, ViewBox | None] = {}
        #: Per panel, the image plane and the other inputs its SVG was last drawn from, and that SVG.
        self._drawn: dict[str, tuple[ImagePlane | Plot, tuple, str]] = {}
        #: Each camera's panel buttons (button groups by label: ``panel view``, ``panel pan``, ``download panel``).
        self.buttons: dict[str, dict[str, viser.GuiButtonGroupHandle]] = {}
        #: The panels' PNG downloads: rendered in a worker process, one waiting per tab, refused above the limits.
        self.png = PngDownloads(tab.client)

    @property
    def style(self) -> PanelStyle:
        """The panels' style (:data:`~egtviz.viewer.render.svg.PRESENT` in presentation mode)."""
        return PRESENT if self.present else NORMAL

    # -- the "Panels" folder and each camera's panel buttons ------------------------------------------

    def build_controls(self) -> None:
        """The "Panels" folder (presentation mode, re-layout) and the style that scales the GUI's type."""
        tab, gui = self.tab, self.client.gui
        # At the top level: a style inside a closed folder would not be in the page.
        self.gui_style = gui.add_html(PRESENT_GUI_CSS if self.present else "")
        with gui.add_folder("Panels", expand_by_default=False):
            self.present_checkbox = gui.add_checkbox(
                "presentation mode", self.present,
                hint="Large type, thick lines, high contrast: for a projector.")
            tab.on(self.present_checkbox.on_update,
                   lambda e: tab.user_event(lambda: self.set_present(e.target.value)))
            self.btn_relayout = gui.add_button(
                "Fit panels to the window", hint="Lay the panels out again for this window's present size.")
            tab.on(self.btn_relayout.on_click, lambda _: tab.user_event(self.relayout))

    def build_buttons(self, name: str, folder: viser.GuiFolderHandle, fields: Mapping[str, FieldHandle]) -> None:
        """Zoom, pan, fit and download buttons for camera ``name``'s panel, in the camera's ``folder``."""
        tab, gui = self.tab, self.client.gui
        groups: dict[str, viser.GuiButtonGroupHandle] = {}
        # After the camera's last field, before its Remove button (viser's default orders are whole numbers).
        last = max((float(h.order) for h in fields.values()), default=None)
        order = (lambda k: None) if last is None else (lambda k: last + 0.1 * (k + 1))
        with folder:
            for k, (label, actions) in enumerate(VIEW_BUTTONS.items()):
                groups[label] = gui.add_button_group(label, tuple(actions), order=order(k))

                def clicked(e: viser.GuiEvent[viser.GuiButtonGroupHandle], a: dict[str, str] = actions) -> None:
                    tab.user_event(lambda: self.view_action(name, a.get(e.target.value, e.target.value)))

                tab.on(groups[label].on_click, clicked)
            groups["download panel"] = gui.add_button_group("download panel", DOWNLOAD_FORMATS,
                                                            order=order(len(VIEW_BUTTONS)))
            tab.on(groups["download panel"].on_click,
                   lambda e: tab.user_event(lambda: self.download(name, e.target.value)))
        self.buttons[name] = groups

    def view_action(self, name: str, action: str) -> None:
        """Apply a view button (one of :data:`~egtviz.viewer.render.panels.VIEW_ACTIONS`) to panel ``name`` and redraw it."""
        if action not in VIEW_ACTIONS:  # a raw client can send any string
            raise FieldError(f"{name}: no view button {plain(repr(action), 40)}")
        plane = self.tab.controller.derived.image_planes.get(name)
        if plane is None:
            return  # the camera was removed meanwhile
        view = self.panel_view(name, plane).after(action, plane)
        self._views[name] = ((int(plane.width), int(plane.height)), view)
        self.tab.redraw_now()

    def download(self, name: str, fmt: str) -> None:
        """Send panel ``name`` as it is shown (its view, the tab's style) as an SVG or PNG file."""
        if fmt not in DOWNLOAD_FORMATS:
            raise FieldError(f"{name}: no download format {plain(repr(fmt), 40)}")
        controller = self.tab.controller
        scene = controller.scene
        plane = controller.derived.image_planes.get(name)
        if plane is None:
            raise SceneError(f"{name}: no such camera")
        svg = panel_svg_of(plane, present=self.present, view=self.panel_view(name, plane).resolve(plane),
                           selected_point=scene.selected_point, show_labels=scene.options.show_labels)
        stem = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "_" for c in name)[:40] or "camera"
        if fmt == "PNG":  # rendered in a worker process: this tab gets the file when it is done, others carry on
            self.png.request(f"{stem}-image-plane.png", svg)
            return
        self.client.send_file_download(f"{stem}-image-plane.svg", svg.encode("utf-8"), save_immediately=True)

    def set_present(self, value: object) -> None:
        """Presentation mode on or off: the panels' style, the GUI's type and the layout follow."""
        if not isinstance(value, bool):
            raise FieldError(f"presentation mode: expected true or false, got {plain(repr(value), 40)}")
        if value == self.present:
            return
        self.present = value
        self.gui_style.content = PRESENT_GUI_CSS if value else ""
        self.scene3d.set_label_scale(PRESENT_LABEL_SCALE if value else 1.0)
        self.tab.redraw_now()

    # -- the grid ----------------------------------------------------------------------------------------

    def layout(self, scene: Scene) -> None:
        """Plan the grid for the scene's cameras and plots in this window; dock the panels when it changed."""
        cameras = tuple((c.name, float(c.width), float(c.height)) for c in scene.cameras)
        plots = {plot_key(p.number): p for p in scene.annotations.plots}  # a figure's 2D plots: 4:3 panels
        cameras += tuple((key, 640.0, 480.0) for key in plots)
        key = (cameras, self.window, self.present)
        if key == self._grid_key:
            return  # a drag: nothing the layout depends on has changed
        grid = plan_grid(cameras, self.window, style=self.style)
        if grid != self.grid:
            self._apply_grid(grid, {c.name: c for c in scene.cameras}, plots)
        self._grid_key = key

    def _apply_grid(self, grid: PanelGrid, cameras: Mapping[str, CameraSpec], plots: Mapping[str, Plot]) -> None:
        """Dock the panels as ``grid`` says: rebuilt if its cells changed, else only resized."""
        if self.grid is None or grid.columns != self.grid.columns or set(self.html) != set(cameras) | set(plots):
            for panel in self._panel_handles:
                panel.remove()
            self._panel_handles = []
            self.html = {}
            # viser puts each new right-hand column outside the ones docked before: the first is nearest the 3D view.
            for col in grid.columns:
                self._dock_column(col, cameras, plots)
        self.grid = grid
        self._set_widths(grid)
        # viser applies a new column's dock and a width sent with it in one step, which gives the new column
        # its default width: the widths are sent again once the tab reports its canvas shrunk by the docks.
        self._width_pending = grid if len(grid.columns) > 1 else None

    def _dock_column(self, col: tuple[tuple[str, ...], ...], cameras: Mapping[str, CameraSpec],
                     plots: Mapping[str, Plot]) -> None:
        gui = self.client.gui
        steps, _ = dock_plan(len(col))
        handles: dict[int, viser.PanelHandle] = {}
        for cell, anchor in steps:
            panel = gui.add_panel()
            for name in col[cell]:
                if name.startswith(PLOT_KEY):
                    plot = plots[name]
                    with panel.add_tab(plot.title):
                        self.html[name] = gui.add_html(empty_svg(plot.title))
                    continue
                spec = cameras[name]
                with panel.add_tab(f"{name}: image plane"):
                    self.html[name] = gui.add_html(empty_svg(name, spec.width, spec.height))
            if anchor is None:
                panel.dock_right()
            else:
                panel.dock_below(handles[anchor])
            handles[cell] = panel
            self._panel_handles.append(panel)

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

    def on_canvas(self, camera: viser.CameraHandle) -> None:
        """The tab reported its camera and canvas: once the docks took their room, send the panel widths again."""
        grid = self._width_pending
        if grid is None or grid is not self.grid:
            return
        try:
            width = float(camera.image_width)
        except (AssertionError, AttributeError, TypeError, ValueError):
            return
        # New columns come at the dock's default width (300 px): wait until the canvas gave up at least most
        # of that room beside the controls, i.e. the docks are in place.
        docked = grid.control_px + 0.9 * DOCK_DEFAULT_PX * len(grid.columns)
        if width > (self.window.width - docked) * self.pixel_ratio:
            return
        self._width_pending = None
        self._set_widths(grid)

    def _client_window(self) -> tuple[WindowSize, float]:
        """The tab's window in CSS pixels and the device pixels per CSS pixel, from the canvas size it reported."""
        try:
            w, h = self.client.camera.image_width, self.client.camera.image_height
        except (AssertionError, AttributeError):  # no camera message yet (viser asserts one arrived)
            return DEFAULT_WINDOW, 1.0
        window = window_from_canvas(w, h)
        ratio = float(w) / window.width if window is not DEFAULT_WINDOW else 1.0
        return window, ratio

    def relayout(self) -> None:
        """Plan the panels again for the window as it is now (the canvas plus what is docked beside it)."""
        grid = self.grid
        try:
            w, h = self.client.camera.image_width, self.client.camera.image_height
        except (AssertionError, AttributeError):
            return
        if grid is None or not (w > 0 and h > 0):
            return
        docked = grid.control_px + grid.right_px + DIVIDER_PX * (len(grid.columns) + 1)
        self.window = WindowSize(w / self.pixel_ratio + docked, h / self.pixel_ratio)
        self.tab.redraw_now()

    def frame_camera(self) -> None:
        """Start this tab's 3D view on the whole scene, inside the canvas the docked panels leave free."""
        grid = self.grid
        if grid is None:
            return
        # What the scene holds (mirrors and their CCDs too) and its size: the glyphs are drawn at that size.
        extent = scene_extent(self.tab.controller.scene, self.tab.controller.derived)
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

    # -- what each panel shows --------------------------------------------------------------------------

    def panel_view(self, name: str, plane: ImagePlane) -> PanelView:
        """What panel ``name`` shows; a new panel, or a new image size, starts from :func:`initial_view`."""
        size = (int(plane.width), int(plane.height))
        kept = self._views.get(name)
        step_view = self.tab.policy().step_view(name)
        if step_view is None:
            self._step_views.pop(name, None)  # the next step that sets a view applies it again
        elif self._step_views.get(name) != step_view:
            self._step_views[name] = step_view
            kept = (size, step_view[1])
            self._views[name] = kept
        if kept is None or kept[0] != size:
            kept = (size, PanelView(initial_view(plane)))
            self._views[name] = kept
        return kept[1]

    def _sizes(self, name: str) -> tuple[float | None, str | None]:
        grid = self.grid
        panel_px = grid.column_px if grid is not None and grid.columns else None
        max_height = f"{grid.svg_max_height_px(name):.0f}px" if grid is not None and panel_px is not None else None
        return panel_px, max_height

    def panel_svg(self, name: str, plane: ImagePlane, scene: Scene, highlighted: set[int], *, revision: int,
                  drag_step: bool, ringed: frozenset[int] = frozenset()) -> str:
        """Panel ``name``'s SVG: its view, the tab's style, drawn for the width its column has on screen.

        A panel whose image plane is the very object drawn last time (a camera that neither moved nor is in the
        drawn pair: ``compute_derived`` reuses its plane) and whose other inputs are equal keeps its SVG, revision
        included: the same text assigned again is not sent.
        """
        panel_px, max_height = self._sizes(name)
        # During a drag a fitted panel holds its view while everything stays in it: still axes, a layout made once.
        kept = self._shown_views.get(name) if drag_step else None
        view = self.panel_view(name, plane).resolve(plane, kept=kept)
        self._shown_views[name] = view
        inputs = (scene.selected_point, frozenset(highlighted), scene.options.show_labels,
                  self.tab.policy().shown().labels, view, self.style, panel_px, max_height, ringed)
        drawn = self._drawn.get(name)
        if drawn is not None and drawn[0] is plane and drawn[1] == inputs:
            return drawn[2]
        svg = image_plane_svg(
            plane,
            selected_point=scene.selected_point,
            highlighted=highlighted,
            show_labels=self._labels(scene),
            revision=revision,
            view=view,
            style=self.style,
            panel_px=panel_px,
            # The grid leaves room for the SVG in its cell; the cap only keeps a longer status text from scrolling.
            max_height=max_height,
            ringed=ringed,
        )
        self._drawn[name] = (plane, inputs, svg)
        return svg

    def _labels(self, scene: Scene) -> bool | str:
        """The panels' ``show_labels``: the scene's option, narrowed by the lesson step's ``labels``."""
        labels = self.tab.policy().shown().labels
        if not scene.options.show_labels or labels == "none":
            return False
        return "marked" if labels == "selected" else True

    def plot_panel_svg(self, key: str, plot: Plot, *, revision: int) -> str:
        """A figure's plot panel (:func:`egtviz.viewer.render.plot_svg.plot_svg`), drawn again only when the plot, the
        style or the panel's size changed (a drag leaves a plot alone)."""
        panel_px, max_height = self._sizes(key)
        inputs = (self.style, panel_px, max_height)
        drawn = self._drawn.get(key)
        if drawn is not None and drawn[0] is plot and drawn[1] == inputs:
            return drawn[2]
        svg = plot_svg(plot, revision=revision, max_height=max_height, style=self.style, panel_px=panel_px)
        self._drawn[key] = (plot, inputs, svg)
        return svg

    def close(self) -> None:
        """Stop the tab's PNG downloads."""
        self.png.close()


