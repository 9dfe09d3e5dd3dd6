"""The servo demos' image plane as inline SVG: a pure function of one frame's drawing data.

Testability contract (like :mod:`egtviz.viewer.render.svg`): the root ``<svg>`` carries
``data-egtviz="servo-image"``, ``data-demo`` (``pinhole`` | ``panoramic``),
``data-frame`` (the frame index) and ``data-rev``; drawn elements carry
``data-kind``: ``border``, ``rim``, ``trail`` (``data-index``, one polyline per
feature with at least two finite samples), ``desired`` (``data-index``),
``point`` (``data-index``, the current feature), ``epipolar-line``
(``data-index``), ``epipolar-conic`` (``data-index``; a bi-conic may have several
pieces), ``epipole`` (``data-label``), ``message``, ``caption`` and ``legend``.

The panel uses the image-plane panels' layout (:func:`egtviz.viewer.render.svg.panel_layout`):
sizes in CSS pixels of a :class:`~egtviz.viewer.render.svg.PanelStyle` at the panel's
width, tick steps from the view, the caption, the message and the legend in
rows under the frame (never over the image), and the feature numbers and
epipole labels placed clear of each other's marks
(:func:`~egtviz.viewer.render.panel_view.place_labels`; each carries ``data-box``); a number
farther from its feature than the panels allow (:func:`~egtviz.viewer.render.svg.number_fates`), or
nearer another, or on a mark, is joined to it by a ``label-leader`` line (``data-index``).
The GUI calls ``servo_image_svg(img, style=PRESENT, panel_px=...)`` in
presentation mode.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from html import escape

import numpy as np

from .palette import EPIPOLE_COLOUR, RIM_COLOUR
from .panel_view import ViewBox, place_labels
from .svg import (
    NORMAL,
    PanelStyle,
    axes_svg,
    finite_runs,
    label_text,
    number_fates,
    panel_layout,
    points_attr,
    svg_number,
    svg_open,
    text_width_px,
)

__all__ = ["ServoImage", "servo_image_svg", "shared_zero_ranges"]

@dataclass(frozen=True)
class ServoImage:
    """Everything one frame of the image panel shows."""

    demo: str
    width: float
    height: float
    frame: int
    current: np.ndarray
    """(N, 2) current feature pixels (NaN: no image)."""
    desired: np.ndarray
    """(N, 2) desired feature pixels."""
    trails: np.ndarray
    """(k, N, 2) feature pixels from the start up to this frame (already thinned)."""
    lines: np.ndarray | None = None
    """(N, 2, 2) clipped epipolar-line segments (NaN rows: off the image)."""
    conics: list[Sequence[np.ndarray]] = field(default_factory=list)
    """Per feature, the (k, 2) polylines of its bi-conic."""
    epipoles: list[tuple[str, np.ndarray]] = field(default_factory=list)
    rim: np.ndarray | None = None
    caption: str = ""
    message: str = ""
    message_colour: str = "#a00"


#: Least fraction of an axis between its zero and either end (:func:`shared_zero_ranges`).
ZERO_FRACTION_MARGIN = 0.02


def shared_zero_ranges(a: tuple[float, float], b: tuple[float, float], pad: float = 0.05
                       ) -> tuple[tuple[float, float], tuple[float, float]]:
    """Ranges for the two y-axes of one plot that put 0 at the same height on both (for the servo plots).

    Each data range ``[lo, hi]`` is first widened to hold 0; with ``p = -lo``,
    ``q = hi``, zero sits at the fraction ``f = p / (p + q)`` of the axis from
    the bottom. One ``f*`` is chosen for both (the larger ``f`` when it is
    below 1, else the smaller when above 0, else 1/2; then kept within
    :data:`ZERO_FRACTION_MARGIN` of either end), and each axis gets the
    span ``s = max(p / f*, q / (1 - f*)) (1 + pad)``, i.e. the range
    ``[-f* s, (1 - f*) s]``, which holds its data.

    Args:
        a, b: ``(min, max)`` of each axis's data (finite).
        pad: extra fraction of the span.

    Returns:
        ``((lo_a, hi_a), (lo_b, hi_b))``.
    """
    pq = []
    for name, (lo, hi) in (("a", a), ("b", b)):
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ValueError(f"{name}: expected finite (min, max) with min <= max, got {(lo, hi)}")
        pq.append((max(-lo, 0.0), max(hi, 0.0)))
    fs = [p / (p + q) if p + q > 0 else 0.5 for p, q in pq]
    f = max(fs) if max(fs) < 1 else (min(fs) if min(fs) > 0 else 0.5)
    # Zero never closer than 2 % to an end: a zero fraction of 1e-300 would need a span of 1e300.
    f = min(max(f, ZERO_FRACTION_MARGIN), 1.0 - ZERO_FRACTION_MARGIN)
    out = []
    for p, q in pq:
        span = max(p / f if p > 0 else 0.0, q / (1 - f) if q > 0 else 0.0)
        if not span > 1e-300:  # no data away from zero (or a subnormal span whose fractions would underflow)
            span = 1.0
        span *= 1.0 + pad
        out.append((-f * span, (1 - f) * span))
    return out[0], out[1]


def _wrap_words(text: str, max_px: float, size_px: float) -> list[str]:
    """``text`` broken at spaces into lines no wider than ``max_px`` (a longer word gets a line of its own)."""
    lines: list[str] = []
    for word in text.split():
        if lines and text_width_px(lines[-1] + " " + word, size_px) <= max_px:
            lines[-1] += " " + word
        else:
            lines.append(word)
    return lines


def _legend_rows(curve: str, max_px: float, size_px: float) -> list[list[tuple[str, str, float]]]:
    """The legend's entries ``(symbol, text, width in CSS px)`` packed into rows no wider than ``max_px``."""
    entries = [("disc", "current"), ("square", "desired"), ("trail", "trail"), ("curve", curve), ("cross", "epipole")]
    rows: list[list[tuple[str, str, float]]] = [[]]
    used = 0.0
    for sym, text in entries:
        width = 2.2 * size_px + text_width_px(text, size_px) + 0.9 * size_px
        if rows[-1] and used + width > max_px:
            rows.append([])
            used = 0.0
        rows[-1].append((sym, text, width))
        used += width
    return rows


def servo_image_svg(img: ServoImage, *, revision: int | None = None, max_height: str | None = None,
                    style: PanelStyle = NORMAL, panel_px: float | None = None, fixed_size: bool = False) -> str:
    """The ``<svg>`` string of one frame (see the module docstring for the ``data-*`` contract).

    Args:
        img: the frame's drawing data.
        revision: written as ``data-rev``.
        max_height: a CSS ``max-height`` for the SVG.
        style: ``NORMAL`` or ``PRESENT`` (:mod:`egtviz.viewer.render.svg`).
        panel_px: the panel's width on screen in CSS pixels, if known (default ``style.panel_px``).
        fixed_size: write ``width``/``height`` in pixels (a figure file).
    """
    w, h = float(img.width), float(img.height)
    view = ViewBox(0.0, 0.0, w, h)
    panel_px = float(style.panel_px if panel_px is None else panel_px)
    curve = "bi-conic" if img.demo == "panoramic" else "epipolar line"
    legend = _legend_rows(curve, 0.85 * panel_px, style.status_px)
    caption = _wrap_words(img.caption, 0.8 * panel_px, style.status_px)
    message = _wrap_words(img.message, 0.8 * panel_px, style.status_px * 1.1)  # bold: a little wider
    lay = panel_layout(view, style, panel_px, len(legend) + len(caption) + len(message))
    k = lay.k
    rev = "" if revision is None else f' data-rev="{int(revision)}"'
    attrs = f' data-demo="{escape(img.demo)}" data-frame="{int(img.frame)}"{rev}'
    out = [
        svg_open("servo-image", attrs, lay, style, fixed_size=fixed_size, max_height=max_height),
        f'<rect data-kind="border" x="0" y="0" width="{svg_number(w)}" height="{svg_number(h)}" fill="#fff" '
        f'stroke="{style.ink}" stroke-width="{svg_number(style.frame_px * k)}"/>',
        axes_svg(lay, style),
        f'<defs><clipPath id="servo-clip-{escape(img.demo)}"><rect x="0" y="0" width="{svg_number(w)}" '
        f'height="{svg_number(h)}"/></clipPath></defs><g clip-path="url(#servo-clip-{escape(img.demo)})">',
    ]
    out += _curves_svg(img, style, k)
    out += _features_svg(img, style, k)
    out.append("</g>")
    # Under the frame: the legend rows, then the caption and the message.
    rows = iter(lay.rows_y)
    out += _legend_svg(legend, rows, style, k)
    out += _texts_svg(img, caption, message, rows, style, k)
    out.append("</svg>")
    return "".join(out)


def _curves_svg(img: ServoImage, style: PanelStyle, k: float) -> list[str]:
    """The rim, then the epipolar lines / bi-conics (thin) and the trails, under the features."""
    colours = style.point_colours
    nc = len(colours)
    lw = style.line_px * k
    integer = k >= 1.0
    out = []
    if img.rim is not None and len(img.rim) >= 3:
        R = np.vstack([img.rim, img.rim[:1]])
        out.append(f'<polyline data-kind="rim" points="{points_attr(R, integer=integer)}" fill="none" '
                   f'stroke="{RIM_COLOUR}" stroke-width="{svg_number(lw)}" stroke-dasharray="{svg_number(lw * 5)},{svg_number(lw * 3)}"/>')
    if img.lines is not None:
        for i, seg in enumerate(np.asarray(img.lines, float)):
            if not np.all(np.isfinite(seg)):
                continue
            out.append(f'<line data-kind="epipolar-line" data-index="{i}" x1="{svg_number(seg[0, 0])}" y1="{svg_number(seg[0, 1])}" '
                       f'x2="{svg_number(seg[1, 0])}" y2="{svg_number(seg[1, 1])}" stroke="{colours[i % nc]}" '
                       f'stroke-width="{svg_number(lw * 0.8)}" stroke-opacity="0.75"/>')
    for i, arcs in enumerate(img.conics):
        for arc in arcs:
            for run in finite_runs(arc):
                out.append(f'<polyline data-kind="epipolar-conic" data-index="{i}" '
                           f'points="{points_attr(run, integer=integer)}" fill="none" stroke="{colours[i % nc]}" '
                           f'stroke-width="{svg_number(lw * 0.8)}" stroke-opacity="0.75"/>')
    T = np.asarray(img.trails, float)
    for i in range(len(img.desired)):
        for run in finite_runs(T[:, i, :]) if len(T) else []:
            out.append(f'<polyline data-kind="trail" data-index="{i}" points="{points_attr(run, integer=False)}" '
                       f'fill="none" stroke="{colours[i % nc]}" stroke-width="{svg_number(lw * 1.5)}" '
                       f'stroke-linejoin="round" stroke-opacity="0.9"/>')
    return out


def _label_boxes(C: np.ndarray, D: np.ndarray, eps: list[tuple[str, np.ndarray]], cur: list[int],
                 style: PanelStyle, k: float, bounds: tuple[float, float, float, float]
                 ) -> tuple[np.ndarray, list[bool], list[bool]]:
    """The boxes of the epipole labels and then the current features' numbers, clear of every disc, square and
    cross, and which numbers are free and which need a leader line (:func:`~egtviz.viewer.render.svg.number_fates`)."""
    r_pt = style.mark_px * k
    lw = style.line_px * k
    a_sq = r_pt * 1.3
    a_ep = r_pt * 1.6
    size = style.label_px * k
    halo = 0.25 * style.label_px * k
    obstacles = [(p[0] - r_pt - lw, p[1] - r_pt - lw, p[0] + r_pt + lw, p[1] + r_pt + lw) for p in C[cur]]
    obstacles += [(p[0] - a_sq - lw, p[1] - a_sq - lw, p[0] + a_sq + lw, p[1] + a_sq + lw)
                  for p in D if np.all(np.isfinite(p))]
    obstacles += [(e[0] - a_ep, e[1] - a_ep, e[0] + a_ep, e[1] + a_ep) for _, e in eps]
    anchors = [tuple(e) for _, e in eps] + [tuple(C[i]) for i in cur]
    radii = [a_ep] * len(eps) + [r_pt] * len(cur)
    sizes = [(text_width_px(lab, style.label_px) * k + halo, 0.95 * size + halo) for lab, _ in eps]
    sizes += [(text_width_px(str(i + 1), style.label_px) * k + halo, 0.95 * size + halo) for i in cur]
    boxes = place_labels(anchors, radii, sizes, obstacles, bounds, gap=0.3 * size) if anchors else np.zeros((0, 4))
    keep, far = number_fates(boxes, len(eps), np.asarray(anchors, float).reshape(-1, 2),
                             np.asarray(radii, float) + 0.3 * size, np.asarray(obstacles, float).reshape(-1, 4),
                             C[cur].reshape(-1, 2))
    return boxes, keep, far


def _features_svg(img: ServoImage, style: PanelStyle, k: float) -> list[str]:
    """The desired squares, the current features with their numbers, and the epipoles with their labels."""
    colours = style.point_colours
    nc = len(colours)
    r_pt = style.mark_px * k
    lw = style.line_px * k
    a_sq = r_pt * 1.3
    a_ep = r_pt * 1.6
    size = style.label_px * k
    D = np.asarray(img.desired, float).reshape(-1, 2)
    C = np.asarray(img.current, float).reshape(-1, 2)
    out = [f'<rect data-kind="desired" data-index="{i}" x="{svg_number(p[0] - a_sq)}" y="{svg_number(p[1] - a_sq)}" '
           f'width="{svg_number(2 * a_sq)}" height="{svg_number(2 * a_sq)}" fill="#fff" fill-opacity="0.6" '
           f'stroke="{colours[i % nc]}" stroke-width="{svg_number(lw * 1.5)}"/>'
           for i, p in enumerate(D) if np.all(np.isfinite(p))]
    eps = [(str(lab), np.asarray(e, float)) for lab, e in img.epipoles]
    eps = [(lab, e) for lab, e in eps if np.all(np.isfinite(e))]
    cur = [i for i in range(len(C)) if np.all(np.isfinite(C[i]))]
    boxes, keep, far = _label_boxes(C, D, eps, cur, style, k, (0.0, 0.0, float(img.width), float(img.height)))
    halo_attr = f' stroke="#fff" stroke-width="{svg_number(0.25 * style.label_px * k)}" paint-order="stroke"'
    # As in the panels, a number is next to its feature or joined to it by a leader line; one that found no free
    # place is drawn too, with its line (a dozen features: the frame has no row to count hidden ones in).
    for i, box, free, near_miss in zip(cur, boxes[len(eps):], keep, far):
        p = C[i]
        line = ""
        if near_miss or not free:
            lx, ly = min(max(p[0], box[0]), box[2]), min(max(p[1], box[1]), box[3])
            line = (f'<line data-kind="label-leader" data-index="{i}" x1="{svg_number(lx)}" y1="{svg_number(ly)}" x2="{svg_number(p[0])}" '
                    f'y2="{svg_number(p[1])}" stroke="{style.ink}" stroke-width="{svg_number(lw * 0.6)}"/>')
        text = label_text(box, size, str(i + 1),
                           f' font-size="{svg_number(size)}" fill="{style.ink}" font-weight="bold"{halo_attr}', p[0])
        out.append(f'{line}<circle data-kind="point" data-index="{i}" cx="{svg_number(p[0])}" cy="{svg_number(p[1])}" '
                   f'r="{svg_number(r_pt)}" fill="{colours[i % nc]}" stroke="#fff" stroke-width="{svg_number(lw * 0.6)}"/>' + text)
    for (lab, e), box in zip(eps, boxes[: len(eps)]):
        out.append(f'<g data-kind="epipole" data-label="{escape(lab)}">'
                   f'<path d="M{svg_number(e[0] - a_ep)} {svg_number(e[1] - a_ep)}L{svg_number(e[0] + a_ep)} {svg_number(e[1] + a_ep)}'
                   f'M{svg_number(e[0] - a_ep)} {svg_number(e[1] + a_ep)}L{svg_number(e[0] + a_ep)} {svg_number(e[1] - a_ep)}" '
                   f'stroke="{EPIPOLE_COLOUR}" stroke-width="{svg_number(lw * 1.6)}"/>'
                   + label_text(box, size, escape(lab),
                                 f' font-size="{svg_number(size)}" font-style="italic" fill="{EPIPOLE_COLOUR}"{halo_attr}',
                                 e[0])
                   + "</g>")
    return out


def _legend_svg(legend: list[list[tuple[str, str, float]]], rows: Iterator[float], style: PanelStyle, k: float
                ) -> list[str]:
    """The legend, one ``<g>`` per row (its baselines from ``rows``): each symbol drawn as in the image, and its
    name."""
    st = style.status_px * k
    lw = style.line_px * k
    grey = "#555"
    out = []
    for entries in legend:
        y = next(rows)
        x = 0.0
        items = []
        for sym, text, width in entries:
            cy = y - 0.35 * st
            if sym == "disc":
                items.append(f'<circle cx="{svg_number(x + 0.5 * st)}" cy="{svg_number(cy)}" r="{svg_number(0.4 * st)}" fill="{grey}"/>')
            elif sym == "square":
                items.append(f'<rect x="{svg_number(x + 0.1 * st)}" y="{svg_number(cy - 0.4 * st)}" width="{svg_number(0.8 * st)}" '
                             f'height="{svg_number(0.8 * st)}" fill="none" stroke="{grey}" stroke-width="{svg_number(lw * 1.5)}"/>')
            elif sym == "cross":
                items.append(f'<path d="M{svg_number(x + 0.1 * st)} {svg_number(cy - 0.4 * st)}l{svg_number(0.8 * st)} {svg_number(0.8 * st)}'
                             f'm0 {svg_number(-0.8 * st)}l{svg_number(-0.8 * st)} {svg_number(0.8 * st)}" stroke="{EPIPOLE_COLOUR}" '
                             f'stroke-width="{svg_number(lw * 1.6)}"/>')
            else:
                op = ' stroke-opacity="0.75"' if sym == "curve" else ""
                wd = lw * (0.8 if sym == "curve" else 1.5)
                items.append(f'<line x1="{svg_number(x)}" y1="{svg_number(cy)}" x2="{svg_number(x + 1.6 * st)}" y2="{svg_number(cy)}" '
                             f'stroke="{grey}" stroke-width="{svg_number(wd)}"{op}/>')
            items.append(f'<text x="{svg_number(x + 2.2 * st)}" y="{svg_number(y)}">{text}</text>')
            x += width * k
        out.append(f'<g data-kind="legend" font-size="{svg_number(st)}" fill="{style.ink}">{"".join(items)}</g>')
    return out


def _texts_svg(img: ServoImage, caption: list[str], message: list[str], rows: Iterator[float], style: PanelStyle,
               k: float) -> list[str]:
    """The caption and the message, each a ``<text>`` of one or more lines (their baselines from ``rows``)."""
    st = style.status_px * k
    out = []
    for kind, lines, attrs in (("caption", caption, f'fill="{style.ink}"'),
                               ("message", message, f'fill="{img.message_colour}" font-weight="bold"')):
        if lines:
            ys = [next(rows) for _ in lines]
            body = (escape(lines[0]) if len(lines) == 1 else
                    "".join(f'<tspan x="0" y="{svg_number(y)}">{escape(t)}</tspan>' for t, y in zip(lines, ys)))
            out.append(f'<text data-kind="{kind}" x="0" y="{svg_number(ys[0])}" font-size="{svg_number(st)}" {attrs}>{body}</text>')
    return out
