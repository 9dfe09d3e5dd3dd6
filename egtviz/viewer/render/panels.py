"""Image-plane panels beside the 3D view: the grid they form, what each one shows, and the first 3D view.

Pure layout in CSS pixels (no viser here; :mod:`egtviz.viewer.workbench.app` applies it):

* :func:`window_from_canvas` estimates the browser window from the canvas
  size the tab reports when it connects;
* :func:`plan_grid` places the panels in columns docked on the right: as
  wide as the window allows, each at least ``MIN_PANEL_PX`` wide when the
  window has room, several cameras as tabs of one panel when it has not;
* :class:`PanelView` is what one panel shows: ``fit`` (all its content,
  followed as it moves), ``image`` (the image rectangle) or a ``custom``
  view left by zoom and pan buttons;
* :func:`framed_camera` starts the 3D view where the whole scene fits the
  part of the window the side panels leave free.

The viser dock takes widths in CSS pixels only, and the width of a docked
region, not of a column (its columns share it equally when they were docked
at the same default width). The layout is planned for the window size
known when the tab connects; the *Fit panels to the window* button plans it
again for the tab's current size.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, TypeVar

import numpy as np
import numpy.typing as npt

from .panel_view import ViewBox, fit_view, fit_with_content, image_view, pan, steady_fit, zoom
from .svg import NORMAL, PanelStyle, panel_layout

if TYPE_CHECKING:
    from ...scene.derived import ImagePlane

__all__ = [
    "CONTROL_PX",
    "DEFAULT_WINDOW",
    "DIVIDER_PX",
    "FLOOR_CANVAS_PX",
    "MIN_PANEL_PX",
    "VIEW_ACTIONS",
    "FramedCamera",
    "PanelGrid",
    "PanelView",
    "WindowSize",
    "dock_plan",
    "framed_camera",
    "initial_view",
    "plan_grid",
    "window_from_canvas",
]

#: Width of the controls docked on the left, in CSS pixels (presentation mode: its larger type needs more).
CONTROL_PX = {"normal": 330.0, "present": 400.0}
#: The narrowest panel worth reading (axis labels and a few ticks per axis).
MIN_PANEL_PX = 300.0
#: A column is at most this fraction of the window wide (one camera does not take the whole screen).
MAX_COLUMN_FRACTION = 0.36
#: The 3D view keeps at least this fraction of the window's width ...
MIN_CANVAS_FRACTION = 0.3
#: ... and at least this many CSS pixels.
MIN_CANVAS_PX = 360.0
#: In a window too small for that, the 3D view gives way down to this width for one panel of MIN_PANEL_PX.
FLOOR_CANVAS_PX = 160.0
#: Height taken in each cell of a column by the panel's handle and tab strip (measured in Chromium: 56-68 px).
CELL_CHROME_PX = 70.0
#: The same by panel style: presentation mode's larger GUI type makes the tab strip taller (measured: 78 px).
CELL_CHROME_BY_STYLE = {"normal": CELL_CHROME_PX, "present": 80.0}
#: Width of the divider between two docked columns, and between a region and the 3D view.
DIVIDER_PX = 5.0
#: Status rows under a panel's frame assumed when planning (the SVG's max-height catches a third).
PLANNED_STATUS_ROWS = 2
#: A camera whose image is smaller than this many pixels on its longer side starts in "fit" (EGT's K = I).
TINY_IMAGE_PX = 32.0
#: Zoom factor of one press of "+" (and 1 / it for "-"); pan step as a fraction of the view.
ZOOM_STEP = 1.25
PAN_STEP = 0.2

ViewMode = Literal["fit", "image", "custom"]
#: The view buttons' labels and what they do (see :meth:`PanelView.after`).
VIEW_ACTIONS = ("fit", "image", "+", "-", "left", "right", "up", "down")


@dataclass(frozen=True)
class WindowSize:
    """The browser window's inner size in CSS pixels."""

    width: float
    height: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.width) and math.isfinite(self.height) and self.width > 0 and self.height > 0):
            raise ValueError(f"WindowSize: width and height must be finite CSS pixels > 0, got "
                             f"{self.width} x {self.height}")


#: The window assumed before a tab has said anything about its size (a common laptop screen).
DEFAULT_WINDOW = WindowSize(1366.0, 768.0)


def window_from_canvas(width_px: float, height_px: float) -> WindowSize:
    """The window's CSS size from the 3D canvas's size in device pixels, reported when the tab connects.

    When a tab connects nothing is docked yet, so the canvas fills the
    window, but viser reports it in device pixels: CSS pixels times the
    screen's pixel ratio, which it does not report. A canvas at least 2400
    wide and 1400 high is taken for a high-density screen (ratio 2: a 13"
    laptop's 2560 x 1600 is a 1280 x 800 window); anything smaller for a
    ratio of 1. A wrong guess only makes the panels narrower or wider than
    the best; text sizes stay right, since the panels are drawn for the
    widths they are given.

    Args:
        width_px, height_px: ``client.camera.image_width`` and ``image_height``.

    Returns:
        The estimated window, or :data:`DEFAULT_WINDOW` for a size that is not a positive number.
    """
    try:
        w, h = float(width_px), float(height_px)
    except (TypeError, ValueError):
        return DEFAULT_WINDOW
    if not (math.isfinite(w) and math.isfinite(h) and w >= 200 and h >= 200):
        return DEFAULT_WINDOW
    ratio = 2.0 if (w >= 2400 and h >= 1400) else 1.0
    return WindowSize(w / ratio, h / ratio)


@dataclass(frozen=True)
class PanelGrid:
    """Where the image-plane panels go: columns docked on the right, cells stacked in each, tabs in a cell.

    ``columns[i][j]`` is the tuple of camera names shown as tabs of the
    panel in row ``j`` of column ``i`` (one name: a plain panel). Columns
    are listed from the 3D view outwards.
    """

    window: WindowSize
    control_px: float
    """Width of the controls docked on the left."""
    column_px: float
    """Width of each column (every column is equally wide)."""
    columns: tuple[tuple[tuple[str, ...], ...], ...]
    chrome_px: float = CELL_CHROME_PX
    """Height of each cell's handle and tab strip (:data:`CELL_CHROME_BY_STYLE`)."""

    @property
    def right_px(self) -> float:
        """Width of the right-hand region: the columns side by side (the dock's dividers not counted)."""
        return self.column_px * len(self.columns)

    @property
    def canvas_px(self) -> float:
        """Width left to the 3D view."""
        return self.window.width - self.control_px - self.right_px - DIVIDER_PX * (len(self.columns) + 1)

    @property
    def cells(self) -> tuple[tuple[str, ...], ...]:
        """Every panel's camera names, column by column."""
        return tuple(cell for col in self.columns for cell in col)

    def _where(self, name: str) -> tuple[int, int]:
        for i, col in enumerate(self.columns):
            for j, cell in enumerate(col):
                if name in cell:
                    return i, j
        raise KeyError(f"no camera {name!r} in the panel grid")

    def rows(self, name: str) -> int:
        """How many panels share the column of camera ``name``."""
        return len(self.columns[self._where(name)[0]])

    def svg_max_height_px(self, name: str) -> float:
        """The tallest an SVG in camera ``name``'s cell can be without making the cell scroll."""
        i, j = self._where(name)
        share = dock_plan(len(self.columns[i]))[1][j]
        return max(self.window.height * share - self.chrome_px, 80.0)


def dock_plan(rows: int) -> tuple[list[tuple[int, int | None]], list[float]]:
    """How to dock ``rows`` panels in one column so that their heights are as equal as the dock allows.

    viser docks a panel below another by halving the other's cell, in the
    order the commands come. So the column is cut in halves recursively:
    cells ``0 .. k-1`` keep the top half and ``k .. rows-1`` the bottom,
    ``k = ceil(rows / 2)``. Two or four rows get equal heights; three get
    1/4, 1/4, 1/2.

    Returns:
        ``(steps, shares)``: ``steps[i] = (cell, anchor)``, in order, docks
        ``cell`` below ``anchor`` (``None``: the column's first cell, docked
        on the right edge); ``shares[j]`` is cell ``j``'s fraction of the height.
    """
    if rows < 1:
        raise ValueError(f"rows must be >= 1, got {rows}")
    steps: list[tuple[int, int | None]] = [(0, None)]
    shares = [0.0] * rows

    def split(first: int, n: int, share: float) -> None:
        if n == 1:
            shares[first] = share
            return
        k = (n + 1) // 2
        steps.append((first + k, first))
        split(first, k, share / 2)
        split(first + k, n - k, share / 2)

    split(0, rows, 1.0)
    return steps, shares


def _svg_height(width_px: float, image: tuple[float, float], style: PanelStyle) -> float:
    """Height in CSS pixels of a panel ``width_px`` wide showing an image of ``image`` = (width, height) pixels."""
    view = ViewBox(0.0, 0.0, float(image[0]), float(image[1]))
    # The uncached function: planning tries many widths, which must not push the renders' layouts out of the cache.
    return panel_layout.__wrapped__(view, style, float(width_px), PLANNED_STATUS_ROWS).height_px


def _widest_fitting(image: tuple[float, float], max_height: float, style: PanelStyle, hi: float) -> float:
    """The widest panel (at most ``hi``) whose SVG is at most ``max_height`` high (bisection: height grows with width)."""
    if _svg_height(hi, image, style) <= max_height:
        return hi
    lo = 60.0
    if _svg_height(lo, image, style) > max_height:
        return lo
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if _svg_height(mid, image, style) <= max_height:
            lo = mid
        else:
            hi = mid
    return lo


#: An item :func:`_split` deals into runs.
_Item = TypeVar("_Item")


def _split(items: Sequence[_Item], parts: int) -> list[list[_Item]]:
    """``items`` in ``parts`` consecutive runs, the longer runs first (sizes differ by at most one)."""
    q, r = divmod(len(items), parts)
    out, start = [], 0
    for i in range(parts):
        n = q + (1 if i < r else 0)
        out.append(list(items[start:start + n]))
        start += n
    return [p for p in out if p]


def plan_grid(cameras: Sequence[tuple[str, float, float]], window: WindowSize, *,
              style: PanelStyle = NORMAL) -> PanelGrid:
    r"""Place one panel per camera in columns docked on the right of ``window``.

    Every arrangement of ``rows`` panels per column and ``cols`` columns
    that shows each camera in its own panel is tried; its column width is

    .. math::

        w = \min\Big(\frac{W - C - \max(0.3 W, 360)}{cols},\; 0.36 W,\; w_h\Big)

    with ``W`` the window width, ``C`` the controls' width and ``w_h`` the
    widest panel whose SVG fits the smallest cell's height (``H / rows``
    for two or four rows, see :func:`dock_plan`) less the tab strip (the tallest image's, so every panel fits). Among the arrangements whose
    panels are at least ``MIN_PANEL_PX`` wide, the one with the fewest
    columns whose width is within 10 % of the widest is taken (the 3D view
    keeps more room). If none reaches ``MIN_PANEL_PX``, cameras are shown
    as tabs: the fewest tabs per panel for which panels reach it, or, in a
    window too small for that, one panel with every camera as a tab, up to
    ``MIN_PANEL_PX`` wide if the 3D view can keep ``FLOOR_CANVAS_PX``.

    Args:
        cameras: ``(name, image width, image height)`` per camera, in panel order.
        window: the browser window.
        style: the panels' style (its text sizes set the axes' margins).

    Returns:
        The :class:`PanelGrid` (no columns for no cameras).
    """
    control = CONTROL_PX[style.name] if style.name in CONTROL_PX else CONTROL_PX["normal"]
    chrome = CELL_CHROME_BY_STYLE.get(style.name, CELL_CHROME_PX)
    names = [c[0] for c in cameras]
    if not names:
        return PanelGrid(window, control, 0.0, (), chrome)
    # The tallest image sets the heights: every other panel is then at most as high.
    tallest = max(cameras, key=lambda c: float(c[2]) / float(c[1]))
    image = (float(tallest[1]), float(tallest[2]))
    budget = window.width - control - max(MIN_CANVAS_FRACTION * window.width, MIN_CANVAS_PX)
    cap = MAX_COLUMN_FRACTION * window.width

    def width(n_cells: int, rows: int) -> tuple[float, int]:
        cols = math.ceil(n_cells / rows)
        avail_h = window.height * min(dock_plan(rows)[1]) - chrome
        hi = max(min(budget / cols - DIVIDER_PX, cap), 60.0)
        return _widest_fitting(image, avail_h, style, hi), cols

    for tabs in range(1, len(names) + 1):
        n_cells = math.ceil(len(names) / tabs)
        options = [(*width(n_cells, rows), rows) for rows in range(1, n_cells + 1)]
        good = [o for o in options if o[0] >= MIN_PANEL_PX]
        if good or n_cells == 1:
            pool = good or options
            best = max(o[0] for o in pool)
            w, cols, _rows = min((o for o in pool if o[0] >= 0.9 * best), key=lambda o: (o[1], -o[0]))
            if not good:
                # One panel of tabs in a small window: the 3D view shrinks to FLOOR_CANVAS_PX before the panel does.
                room = window.width - control - FLOOR_CANVAS_PX - 2 * DIVIDER_PX
                w = max(w, min(MIN_PANEL_PX, room, _widest_fitting(image, window.height - chrome, style,
                                                                   MIN_PANEL_PX)))
            break
    cells = _split(names, n_cells)
    columns = tuple(tuple(tuple(cell) for cell in col) for col in _split(cells, cols))
    return PanelGrid(window, control, float(math.floor(w)), columns, chrome)


def initial_view(plane: ImagePlane) -> ViewMode:
    """How a new panel starts: ``fit`` for a tiny image (EGT's ``K = I``) or a visible point outside it, else ``image``.

    Args:
        plane: an :class:`egtviz.scene.ImagePlane`.
    """
    if max(float(plane.width), float(plane.height)) < TINY_IMAGE_PX:
        return "fit"
    visible = np.asarray(plane.visible, bool).reshape(-1)
    in_image = np.asarray(plane.in_image, bool).reshape(-1)
    return "fit" if bool(np.any(visible & ~in_image)) else "image"


@dataclass(frozen=True)
class PanelView:
    """What one panel shows: ``fit`` (all content, refitted at every update; during a drag held still while it
    still shows everything), ``image``, or a fixed ``box``."""

    mode: ViewMode = "image"
    box: ViewBox | None = None
    """The view of a ``custom`` panel (None otherwise)."""

    def __post_init__(self) -> None:
        if self.mode not in ("fit", "image", "custom"):
            raise ValueError(f"PanelView.mode: expected 'fit', 'image' or 'custom', got {self.mode!r}")
        if (self.mode == "custom") != (self.box is not None):
            raise ValueError("PanelView: a box is given exactly when mode is 'custom'")

    def resolve(self, plane: ImagePlane, *, kept: ViewBox | None = None) -> ViewBox | None:
        """The view box to draw ``plane`` with (None: the image rectangle).

        ``kept``: during a drag, the view of its previous step; a ``fit`` panel keeps it while it still shows all
        the content (:func:`~egtviz.viewer.render.panel_view.steady_fit`).
        """
        if self.mode != "fit":
            return self.box
        if kept is None:
            return fit_view(plane)
        fitted, content = fit_with_content(plane)
        return steady_fit(fitted, kept, content=content)

    def after(self, action: str, plane: ImagePlane) -> PanelView:
        """The view after a button press (one of :data:`VIEW_ACTIONS`), starting from what ``plane`` shows now.

        ``+``/``-`` zoom by ``ZOOM_STEP`` about the view's centre; the arrows
        move the view by ``PAN_STEP`` of its size (``left`` shows what lies
        to the left, ...).

        Raises:
            ValueError: ``action`` is not one of :data:`VIEW_ACTIONS`.
        """
        if action == "fit":
            return PanelView("fit")
        if action == "image":
            return PanelView("image")
        current = self.resolve(plane) or image_view(plane)
        moves = {"+": lambda v: zoom(v, ZOOM_STEP), "-": lambda v: zoom(v, 1.0 / ZOOM_STEP),
                 "left": lambda v: pan(v, -PAN_STEP, 0.0), "right": lambda v: pan(v, PAN_STEP, 0.0),
                 "up": lambda v: pan(v, 0.0, -PAN_STEP), "down": lambda v: pan(v, 0.0, PAN_STEP)}
        if action not in moves:
            raise ValueError(f"view action: expected one of {', '.join(VIEW_ACTIONS)}, got {action!r}")
        return PanelView("custom", moves[action](current))


@dataclass(frozen=True)
class FramedCamera:
    """A start for the browser's 3D view: where it looks from and at (world coordinates), z up."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    fov: float
    """Vertical field of view in radians."""


#: Direction from the scene's centre to the viewer (a view from the front right, above): unit vector.
VIEW_DIRECTION = np.array([0.3, -1.45, 0.9]) / np.linalg.norm([0.3, -1.45, 0.9])


def framed_camera(points: npt.ArrayLike, canvas_aspect: float, *, fov: float = math.radians(60.0),
                  margin: float = 1.25, pad: float = 1.0, min_radius: float = 3.0) -> FramedCamera:
    r"""The closest 3D view that shows every point of ``points`` in a canvas of aspect ``canvas_aspect``.

    The side panels are docked, so the canvas is the free part of the window
    between them; a narrow canvas sees less sideways. The view looks at the
    centre ``c`` of the points' bounding box from :data:`VIEW_DIRECTION`
    ``d``, with z up. In the view's frame (``right``, ``up`` and ``d``), a
    point ``p`` lies ``x_i`` to the right, ``y_i`` up and ``s_i = (p - c) . d``
    towards the viewer; at distance ``D`` it is seen at depth ``D - s_i``.
    It is inside the canvas, grown by ``pad`` (a camera's frustum and gizmo
    reach about a metre from its centre) and then by the factor ``m``, when

    .. math::

        m (|x_i| + pad) \le (D - s_i) \tan a_h, \qquad
        m (|y_i| + pad) \le (D - s_i) \tan a_v,

    with the half-angles ``a_v = fov / 2`` and ``a_h = atan(tan(fov / 2) aspect)``.
    ``D`` is the least distance meeting both for every point, and at least
    ``m min_radius / tan min(a_v, a_h)`` (a lone point is not seen from up close).

    Args:
        points: (N, 3) what must be seen (camera centres, scene points); N = 0: the origin.
        canvas_aspect: the canvas's width / height (> 0).
        fov: the vertical field of view (radians).
        margin: ``m`` (>= 1).
        pad: metres added around each point.
        min_radius: the smallest half-extent framed, in metres.
    """
    if not (math.isfinite(canvas_aspect) and canvas_aspect > 0):
        raise ValueError(f"canvas_aspect must be a finite number > 0, got {canvas_aspect}")
    P = np.asarray(points, float).reshape(-1, 3)
    P = P[np.all(np.isfinite(P), axis=1)]
    if len(P) == 0:
        P = np.zeros((1, 3))
    centre = 0.5 * (P.min(axis=0) + P.max(axis=0))
    tan_v = math.tan(fov / 2.0)
    tan_h = tan_v * canvas_aspect
    right = np.cross(-VIEW_DIRECTION, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -VIEW_DIRECTION)
    Q = P - centre
    x, y, s = np.abs(Q @ right), np.abs(Q @ up), Q @ VIEW_DIRECTION
    need = np.maximum(margin * (x + pad) / tan_h, margin * (y + pad) / tan_v) + s
    distance = max(float(need.max()), margin * min_radius / min(tan_v, tan_h))
    position = centre + VIEW_DIRECTION * distance
    return FramedCamera((float(position[0]), float(position[1]), float(position[2])),
                        (float(centre[0]), float(centre[1]), float(centre[2])), float(fov))
