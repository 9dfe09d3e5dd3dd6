"""A figure's 2D plot (:class:`egtviz.scene.annotations.Plot`) as an inline SVG panel.

A plot is drawn by the image-plane panel itself (:func:`egtviz.viewer.render.svg.image_plane_svg`): its pixels,
lines and epipoles are handed over as an :class:`~egtviz.scene.ImagePlane` of a camera named after the plot
(``Figure <n>``), so axes, ticks, numbered points, lines, epipole marks and arrows look and are tagged
exactly as in a camera's panel (the ``data-kind`` contract of :mod:`egtviz.viewer.render.svg`). What a plot adds:

* the root also carries ``data-plot="<n>"``;
* circles, as ``<circle data-kind="circle">`` in their MATLAB colour;
* the view is the plot's content (points, lines' points, finite epipoles, circles and the image rectangle
  when the camera's K gives one) plus a margin, at the aspect ratio 4:3, like MATLAB's automatic axes;
* without an image rectangle (a K whose principal point is at the origin, as the tutorial's ``K = I``)
  no border is drawn.

Line ``i`` is drawn in the colour of the point it goes through, as in a camera's panel.
"""

from __future__ import annotations

import math
import re

import numpy as np
import numpy.typing as npt

from ...scene import Epipole, ImagePlane
from ...scene.annotations import Plot
from ...scene.shown_numbers import shown_components
from .panel_view import FIT_MARGIN, FIT_MAX_EXTENT, ViewBox, aspect_box
from .svg import NORMAL, PanelStyle, image_plane_svg, panel_layout

__all__ = ["PLOT_ASPECT", "plot_image_plane", "plot_svg", "plot_view"]

#: Width / height of a plot's view (MATLAB's default axes are 4:3 too).
PLOT_ASPECT = 4.0 / 3.0

_BORDER = re.compile(r'<rect data-kind="border"[^>]*/>')


def _content(plot: Plot) -> np.ndarray:
    parts = [np.asarray(plot.points, float).reshape(-1, 2), np.asarray(plot.line_points, float).reshape(-1, 2)]
    for c in plot.circles:
        cx, cy = c.centre
        parts.append(np.array([[cx - c.radius, cy - c.radius], [cx + c.radius, cy + c.radius]]))
    if plot.image_size is not None:
        parts.append(np.array([[0.0, 0.0], [float(plot.image_size[0]), float(plot.image_size[1])]]))
    P = np.concatenate(parts)
    if len(P):
        # Epipoles far from everything else are shown by an arrow at the frame, not fitted.
        lo, hi = P.min(axis=0), P.max(axis=0)
        reach = FIT_MAX_EXTENT * max(float(np.max(hi - lo)), 1.0)
        for e in plot.epipoles:
            if abs(e[2]) > 0:
                xy = np.array(e[:2]) / e[2]
                if np.all(xy > lo - reach) and np.all(xy < hi + reach):
                    P = np.vstack([P, xy])
    else:
        P = np.array([[e[0] / e[2], e[1] / e[2]] for e in plot.epipoles if abs(e[2]) > 0]).reshape(-1, 2)
    return P


def plot_view(plot: Plot, *, margin: float = FIT_MARGIN) -> ViewBox:
    """The view of a plot: its content's bounding box plus ``margin`` of its span on each side, widened about
    its centre to :data:`PLOT_ASPECT` (an empty plot: the unit square around the origin)."""
    P = _content(plot)
    if not len(P):
        return ViewBox(-PLOT_ASPECT, -1.0, 2.0 * PLOT_ASPECT, 2.0)
    lo, hi = P.min(axis=0), P.max(axis=0)
    span = hi - lo
    pad = np.maximum(margin * span, 1e-3 * max(1.0, float(np.abs(P).max())))  # one point: a small square
    return aspect_box(lo - pad, hi + pad, PLOT_ASPECT)


def _epipole(label: str, e: npt.ArrayLike, size: tuple[int, int] | None) -> Epipole:
    e = np.asarray(e, float)
    if abs(e[2]) <= 1e-12 * float(np.linalg.norm(e)):
        d = e[:2] / float(np.hypot(e[0], e[1]))
        return Epipole(label, None, d, True, False)
    xy = e[:2] / e[2]
    xy = np.array(shown_components(xy))  # rounding dust is 0, not -6e-17: the one rule of every shown number
    inside = size is not None and 0.0 <= xy[0] <= size[0] and 0.0 <= xy[1] <= size[1]
    return Epipole(label, xy, None, False, bool(inside))


def plot_image_plane(plot: Plot, view: ViewBox) -> ImagePlane:
    """The plot as the content of an image-plane panel named ``Figure <n>`` (see the module docstring)."""
    P = np.asarray(plot.points, float).reshape(-1, 2)
    n = len(P)
    size = plot.image_size
    if size is None:
        in_image = np.ones(n, bool)
        width = height = 1
    else:
        width, height = size
        with np.errstate(invalid="ignore"):
            in_image = (P[:, 0] >= 0) & (P[:, 0] <= width) & (P[:, 1] >= 0) & (P[:, 1] <= height)
    # One row per point (line i in the colour of point i), then rows for lines through no listed point.
    rows: list[np.ndarray] = [np.full((2, 2), np.nan) for _ in range(n)]
    reach = 4.0 * math.hypot(view.width, view.height)
    for (a, b, _c), p in zip(plot.lines, plot.line_points):
        d = np.array([-b, a]) / math.hypot(a, b)
        seg = np.array([np.asarray(p) - reach * d, np.asarray(p) + reach * d])
        match: np.ndarray | list[int]
        match = np.flatnonzero(np.all(np.abs(P - np.asarray(p)) <= 1e-9 * (1.0 + np.abs(P)), axis=1)) if n else []
        free = [j for j in match if np.isnan(rows[j]).all()]
        if free:
            rows[free[0]] = seg
        else:
            rows.append(seg)
    lines = np.array(rows).reshape(-1, 2, 2) if plot.lines else None
    labels = [f"e{plot.number}" + "'" * k for k in range(len(plot.epipoles))]
    epipoles = tuple(_epipole(lab, e, size) for lab, e in zip(labels, plot.epipoles))
    return ImagePlane(camera=plot.title, width=int(width), height=int(height), points=P,
                      visible=np.ones(n, bool), in_image=in_image, n_hidden=0, epipoles=epipoles, lines=lines)


def plot_svg(plot: Plot, *, revision: int | None = None, max_height: str | None = None, style: PanelStyle = NORMAL,
             panel_px: float | None = None, fixed_size: bool = False) -> str:
    """Inline SVG of a figure's 2D plot (arguments as :func:`egtviz.viewer.render.svg.image_plane_svg`)."""
    view = plot_view(plot)
    plane = plot_image_plane(plot, view)
    svg = image_plane_svg(plane, revision=revision, max_height=max_height, view=view, style=style,
                          panel_px=panel_px, fixed_size=fixed_size)
    svg = svg.replace('data-egtviz="image-plane"', f'data-egtviz="image-plane" data-plot="{int(plot.number)}"', 1)
    if plot.image_size is None:
        svg = _BORDER.sub("", svg, count=1)
    if plot.circles:
        px = float(style.panel_px if panel_px is None else panel_px)
        k = panel_layout(view, style, px, 1).k
        circles = "".join(
            f'<circle data-kind="circle" cx="{c.centre[0]:.6g}" cy="{c.centre[1]:.6g}" r="{c.radius:.6g}" '
            f'fill="none" stroke="{c.colour}" stroke-width="{style.line_px * k:.5g}"/>'
            for c in plot.circles
        )
        svg = svg[: -len("</svg>")] + circles + "</svg>"
    return svg
