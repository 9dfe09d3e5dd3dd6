"""The servo demos' image plane as inline SVG: a pure function of one frame's drawing data.

Testability contract (like :mod:`egtviz.viewer.svg`): the root ``<svg>`` carries
``data-egtviz="servo-image"``, ``data-demo`` (``pinhole`` | ``panoramic``),
``data-frame`` (the frame index) and ``data-rev``; drawn elements carry
``data-kind``: ``border``, ``rim``, ``trail`` (``data-index``, one polyline per
feature with at least two finite samples), ``desired`` (``data-index``),
``point`` (``data-index``, the current feature), ``epipolar-line``
(``data-index``), ``epipolar-conic`` (``data-index``; a bi-conic may have several
pieces), ``epipole`` (``data-label``), ``message``, ``caption`` and ``legend``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from html import escape

import numpy as np

from .palette import EPIPOLE_COLOUR, RIM_COLOUR, point_colour
from .svg import _f, _finite_runs, _points_attr, axes_svg

__all__ = ["ServoImage", "servo_image_svg", "trail_indices"]

#: Most vertices per trail (older samples are thinned, the newest is always kept).
TRAIL_VERTICES = 160


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
    conics: list[list[np.ndarray]] = field(default_factory=list)
    epipoles: list[tuple[str, np.ndarray]] = field(default_factory=list)
    rim: np.ndarray | None = None
    caption: str = ""
    message: str = ""
    message_colour: str = "#a00"


def trail_indices(k: int, limit: int = TRAIL_VERTICES) -> np.ndarray:
    """Sample indices ``0..k`` thinned to at most ``limit`` (always containing 0 and ``k``)."""
    if k + 1 <= limit:
        return np.arange(k + 1)
    return np.unique(np.r_[np.linspace(0, k, limit).astype(int), k])


def servo_image_svg(img: ServoImage, *, revision: int | None = None, max_height: str | None = None) -> str:
    """The ``<svg>`` string of one frame (see the module docstring for the ``data-*`` contract)."""
    w, h = float(img.width), float(img.height)
    s = max(w, h)
    font = s / 32.0
    margin = font * 2.6
    bottom = font * 2.4
    r_pt = s / 100.0
    lw = s / 420.0
    rev = "" if revision is None else f' data-rev="{int(revision)}"'
    mh = "" if max_height is None else f";max-height:{escape(max_height)}"
    vb = f"{_f(-margin)} {_f(-margin)} {_f(w + 2 * margin)} {_f(h + margin + bottom)}"
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" data-egtviz="servo-image" data-demo="{escape(img.demo)}" '
        f'data-frame="{int(img.frame)}"{rev} viewBox="{vb}" width="100%" '
        f'style="display:block;font-family:sans-serif;background:#f4f4f4{mh}">',
        f'<rect data-kind="border" x="0" y="0" width="{_f(w)}" height="{_f(h)}" fill="#fff" '
        f'stroke="#333" stroke-width="{_f(lw * 1.5)}"/>',
    ]
    out.append(axes_svg(w, h, font, lw))
    out.append(f'<defs><clipPath id="servo-clip-{escape(img.demo)}"><rect x="0" y="0" width="{_f(w)}" '
               f'height="{_f(h)}"/></clipPath></defs><g clip-path="url(#servo-clip-{escape(img.demo)})">')
    integer = s > 300
    if img.rim is not None and len(img.rim) >= 3:
        R = np.vstack([img.rim, img.rim[:1]])
        out.append(f'<polyline data-kind="rim" points="{_points_attr(R, integer=integer)}" fill="none" '
                   f'stroke="{RIM_COLOUR}" stroke-width="{_f(lw * 1.5)}" stroke-dasharray="{_f(lw * 6)},{_f(lw * 4)}"/>')
    n = len(img.desired)
    # Epipolar lines / bi-conics first (thin), so the features stay on top.
    if img.lines is not None:
        for i, seg in enumerate(np.asarray(img.lines, float)):
            if not np.all(np.isfinite(seg)):
                continue
            out.append(f'<line data-kind="epipolar-line" data-index="{i}" x1="{_f(seg[0, 0])}" y1="{_f(seg[0, 1])}" '
                       f'x2="{_f(seg[1, 0])}" y2="{_f(seg[1, 1])}" stroke="{point_colour(i)}" '
                       f'stroke-width="{_f(lw * 1.2)}" stroke-opacity="0.75"/>')
    for i, arcs in enumerate(img.conics):
        for arc in arcs:
            for run in _finite_runs(arc):
                out.append(f'<polyline data-kind="epipolar-conic" data-index="{i}" '
                           f'points="{_points_attr(run, integer=integer)}" fill="none" stroke="{point_colour(i)}" '
                           f'stroke-width="{_f(lw * 1.2)}" stroke-opacity="0.75"/>')
    # Trails.
    T = np.asarray(img.trails, float)
    for i in range(n):
        for run in _finite_runs(T[:, i, :]) if len(T) else []:
            out.append(f'<polyline data-kind="trail" data-index="{i}" points="{_points_attr(run, integer=False)}" '
                       f'fill="none" stroke="{point_colour(i)}" stroke-width="{_f(lw * 2.2)}" '
                       f'stroke-linejoin="round" stroke-opacity="0.9"/>')
    # Desired features: hollow squares.
    for i, p in enumerate(np.asarray(img.desired, float)):
        if not np.all(np.isfinite(p)):
            continue
        a = r_pt * 1.3
        out.append(f'<rect data-kind="desired" data-index="{i}" x="{_f(p[0] - a)}" y="{_f(p[1] - a)}" '
                   f'width="{_f(2 * a)}" height="{_f(2 * a)}" fill="#fff" fill-opacity="0.6" '
                   f'stroke="{point_colour(i)}" stroke-width="{_f(lw * 2)}"/>')
    # Current features: filled discs with their number.
    for i, p in enumerate(np.asarray(img.current, float)):
        if not np.all(np.isfinite(p)):
            continue
        out.append(f'<circle data-kind="point" data-index="{i}" cx="{_f(p[0])}" cy="{_f(p[1])}" r="{_f(r_pt)}" '
                   f'fill="{point_colour(i)}" stroke="#fff" stroke-width="{_f(lw)}"/>'
                   f'<text x="{_f(p[0] + r_pt * 1.3)}" y="{_f(p[1] - r_pt * 1.1)}" font-size="{_f(font * 0.8)}" '
                   f'fill="{point_colour(i)}" font-weight="bold">{i + 1}</text>')
    for label, e in img.epipoles:
        e = np.asarray(e, float)
        if not np.all(np.isfinite(e)):
            continue
        a = r_pt * 1.6
        out.append(f'<g data-kind="epipole" data-label="{escape(label)}">'
                   f'<line x1="{_f(e[0] - a)}" y1="{_f(e[1] - a)}" x2="{_f(e[0] + a)}" y2="{_f(e[1] + a)}" '
                   f'stroke="{EPIPOLE_COLOUR}" stroke-width="{_f(lw * 2.2)}"/>'
                   f'<line x1="{_f(e[0] - a)}" y1="{_f(e[1] + a)}" x2="{_f(e[0] + a)}" y2="{_f(e[1] - a)}" '
                   f'stroke="{EPIPOLE_COLOUR}" stroke-width="{_f(lw * 2.2)}"/>'
                   f'<text x="{_f(e[0] + a * 1.2)}" y="{_f(e[1] + a * 1.8)}" font-size="{_f(font * 0.85)}" '
                   f'font-style="italic" fill="{EPIPOLE_COLOUR}">{escape(label)}</text></g>')
    out.append("</g>")
    if img.caption:
        out.append(f'<text data-kind="caption" x="{_f(w)}" y="{_f(h - font * 0.5)}" text-anchor="end" '
                   f'font-size="{_f(font * 0.85)}" fill="#333">{escape(img.caption)}</text>')
    if img.message:
        out.append(f'<text data-kind="message" x="{_f(w / 2)}" y="{_f(font * 1.3)}" text-anchor="middle" '
                   f'font-size="{_f(font * 0.85)}" fill="{img.message_colour}" font-weight="bold">'
                   f'{escape(img.message)}</text>')
    # Legend under the image.
    y = h + font * 1.5
    curve = "bi-conic" if img.demo == "panoramic" else "epipolar line"
    a = r_pt
    out.append(
        f'<g data-kind="legend" font-size="{_f(font * 0.8)}" fill="#333">'
        f'<circle cx="{_f(a)}" cy="{_f(y - a * 0.6)}" r="{_f(a)}" fill="#555"/>'
        f'<text x="{_f(3 * a)}" y="{_f(y)}">current</text>'
        f'<rect x="{_f(w * 0.2)}" y="{_f(y - 1.8 * a)}" width="{_f(2 * a)}" height="{_f(2 * a)}" fill="none" '
        f'stroke="#555" stroke-width="{_f(lw * 2)}"/><text x="{_f(w * 0.2 + 3 * a)}" y="{_f(y)}">desired</text>'
        f'<line x1="{_f(w * 0.4)}" y1="{_f(y - a * 0.6)}" x2="{_f(w * 0.4 + 5 * a)}" y2="{_f(y - a * 0.6)}" '
        f'stroke="#555" stroke-width="{_f(lw * 2.2)}"/><text x="{_f(w * 0.4 + 6 * a)}" y="{_f(y)}">trail</text>'
        f'<line x1="{_f(w * 0.58)}" y1="{_f(y - a * 0.6)}" x2="{_f(w * 0.58 + 5 * a)}" y2="{_f(y - a * 0.6)}" '
        f'stroke="#555" stroke-width="{_f(lw * 1.2)}" stroke-opacity="0.75"/>'
        f'<text x="{_f(w * 0.58 + 6 * a)}" y="{_f(y)}">{curve}</text>'
        f'<text x="{_f(w)}" y="{_f(y)}" text-anchor="end" font-style="italic">&#215; epipole</text></g>'
    )
    out.append("</svg>")
    return "".join(out)
