"""Image-plane panels as inline SVG: a pure function from an ``ImagePlane`` to a string.

The SVG is in pixel units of the image: its ``viewBox`` is the panel's view
(:class:`~egtviz.viewer.render.panel_view.ViewBox`, by default the image rectangle)
plus margins for the axes' tick labels and the status lines under the frame.
Sizes of text, lines and marks are given in CSS pixels by a
:class:`PanelStyle` at a panel width ``panel_px`` and converted to image
pixels through the view box, ``size_user = size_px * viewBox_width / panel_px``:
the panel shown ``W`` CSS pixels wide writes its text at ``size_px * W /
panel_px`` CSS pixels whatever the image's size in pixels (2 px or 4000 px).
It draws only what the scene layer computed (:class:`egtviz.scene.ImagePlane`):
points, epipoles, clipped epipolar lines, epipolar conics, the mirror rim.

How the GUI calls it: ``image_plane_svg(plane, view=view, style=PRESENT,
panel_px=620)``, with ``view`` from :mod:`egtviz.viewer.render.panel_view`
(``fit_view``, ``zoom``, ``pan``; ``None`` = the image rectangle), ``style``
``NORMAL`` or ``PRESENT`` (presentation mode) and ``panel_px`` the width the
panel will have on screen if the app knows it (else the style's own width).
:mod:`egtviz.viewer.render.figure_export` writes the same SVG with a fixed size and
renders it to PNG.

Testability contract (the browser tests rely on it):

* the root ``<svg>`` carries ``data-egtviz="image-plane"``,
  ``data-camera="<camera name>"``, ``data-style`` (``normal`` |
  ``present``) and ``data-view`` (``u0 v0 width height`` of the view);
* drawn elements carry ``data-kind``: ``border`` (the image rectangle),
  ``frame`` (the view's axes box), ``axes``, ``point`` (with ``data-index``,
  0-based, one per point inside the image: a ``<g>`` holding the disc and its
  number, or a bare disc when the point is not numbered), ``point-outside``
  (the same for a visible point outside the image but inside the view: a
  hollow disc), ``epipole`` (with ``data-label``, ``data-where`` = ``inside``
  | ``outside`` | ``infinity`` (relative to the image) and ``data-drawn`` =
  ``mark`` (a cross at the epipole, inside the view) | ``arrow`` (at the
  frame, pointing to it)), ``epipole-arrow``, ``epipole-label``,
  ``epipolar-line`` (with ``data-index``, one per drawn line),
  ``epipolar-conic`` (with ``data-index``; a conic may have several pieces),
  ``rim``, ``horizon`` (a camera's horizon, one polyline per arc), ``message``,
  ``hidden-count``, ``numbering-note``, ``crowded-note`` (with ``data-unnumbered``:
  how many point numbers found no free place and are not drawn), ``label-leader``
  (with ``data-index``: a line from a point number's box to its point);
* every text that labels a mark (point numbers, epipole labels) is placed by
  :func:`~egtviz.viewer.render.panel_view.place_labels` clear of the marks, arrows and
  other labels, and carries ``data-box="x0 y0 x1 y1"``: the box it was placed
  in (image pixels);
* a point number is never free-floating: its box is within ``NUMBER_NEAR`` times
  (its mark's radius plus the gap, ``0.3 * label_px``) of its point, or a
  ``label-leader`` in its point's group ends at the point's centre, or it is not
  drawn and counted in the ``crowded-note``.

Point labels are 1-based, like EGT's ``f_3Dwfenum``; ``data-index`` is 0-based.
Above ``MAX_NUMBERED_POINTS`` points in an image only the selected and
highlighted points are numbered.
"""

from __future__ import annotations

import math
import zlib
from bisect import bisect_left
from dataclasses import dataclass
from functools import lru_cache
from html import escape
from collections.abc import Iterable, Iterator, Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ...scene.shown_numbers import format_value, format_vector
from .palette import EPIPOLE_COLOUR, POINT_COLOURS, PRESENT_POINT_COLOURS, RIM_COLOUR
from .panel_view import PLACEMENT_RINGS, ViewBox, image_view, place_labels, tick_values

if TYPE_CHECKING:
    from ...scene.derived import Epipole, ImagePlane

__all__ = ["NORMAL", "PRESENT", "PanelLayout", "PanelStyle", "axes_svg", "empty_svg", "finite_runs", "image_plane_svg",
           "label_text", "number_fates", "panel_layout", "points_attr", "svg_number", "svg_open", "text_width_px"]

#: Above this many points in an image only the selected and highlighted points are numbered (more are unreadable).
MAX_NUMBERED_POINTS = 40

#: A point number whose box is farther from its point than this many times the mark's radius plus the gap gets a
#: leader line (the nearest candidate boxes lie within sqrt 2 of it, the next ring at twice that).
NUMBER_NEAR = 1.5
#: ... and so does one with another point less than this many times as far from its box as its own point.
NUMBER_CLEAR = 1.25

#: Most conic vertices drawn in one panel (200 conics x 129 samples would be ~260 kB of SVG per update).
CONIC_VERTEX_BUDGET = 10_000

#: Advance of one character in ems, an upper bound over common sans-serif fonts (DejaVu Sans Bold digits: 0.696).
CHAR_EM = 0.7

#: Narrower characters (DejaVu Sans: space, comma, full stop 0.318 em; parentheses 0.39 em; hyphen 0.361 em).
_NARROW_EM = {" ": 0.35, ",": 0.35, ".": 0.35, ":": 0.35, ";": 0.35, "(": 0.42, ")": 0.42, "-": 0.42, "'": 0.35,
              "i": 0.35, "j": 0.35, "l": 0.35, "t": 0.45, "f": 0.45, "r": 0.5, "m": 0.98, "w": 0.84}
#: Other lower-case letters (DejaVu Sans: 0.52-0.64 em).
_LOWER_EM = 0.64


@dataclass(frozen=True)
class PanelStyle:
    """How a panel looks: sizes in CSS pixels when the panel is ``panel_px`` CSS pixels wide, and colours."""

    name: str
    """``normal`` or ``present`` (written as ``data-style``)."""
    panel_px: float
    """The panel width the sizes are meant for, when the caller does not give one."""
    tick_px: float
    """Axis tick labels and the axis names."""
    label_px: float
    """Point numbers and epipole labels."""
    status_px: float
    """Status lines under the frame and messages."""
    line_px: float
    """Epipolar lines and conics (the selected point's are three times as thick)."""
    mark_px: float
    """Radius of a point's disc."""
    frame_px: float
    """The image border and the axes."""
    ink: str
    """Text and axes colour."""
    background: str
    point_colours: tuple[str, ...]


#: The workbench's look (sizes for the 480 px column of a 1600 px window).
NORMAL = PanelStyle("normal", panel_px=480.0, tick_px=11.0, label_px=13.0, status_px=11.5, line_px=1.3,
                    mark_px=4.5, frame_px=1.2, ink="#333333", background="#f4f4f4", point_colours=POINT_COLOURS)
#: Presentation mode: 16 px and larger text on a 620 px panel (a 1920 x 1080 screen), thick lines, high contrast.
PRESENT = PanelStyle("present", panel_px=620.0, tick_px=17.0, label_px=19.0, status_px=17.0, line_px=2.6,
                     mark_px=7.0, frame_px=2.2, ink="#000000", background="#ffffff",
                     point_colours=PRESENT_POINT_COLOURS)


def svg_number(x: float) -> str:
    """Compact coordinate formatting: five significant digits (images may be 2 px or 4000 px wide)."""
    return f"{x:.5g}"


@lru_cache(maxsize=4096)
def text_width_px(text: str, size_px: float) -> float:
    """Upper bound of a one-line text's width in CSS pixels (``CHAR_EM`` per character, less for narrow ones)."""
    return sum(_NARROW_EM.get(ch, _LOWER_EM if ch.islower() else CHAR_EM) for ch in text) * size_px


@dataclass(frozen=True)
class PanelLayout:
    """Where a panel's frame, axes and status lines go; lengths in image pixels (the SVG's user units)."""

    view: ViewBox
    panel_px: float
    """Panel width in CSS pixels the layout is made for."""
    height_px: float
    """Panel height in CSS pixels at that width."""
    k: float
    """Image pixels per CSS pixel (multiply a CSS size by ``k`` to draw it)."""
    viewbox: tuple[float, float, float, float]
    u_ticks: tuple[float, ...]
    v_ticks: tuple[float, ...]
    decimals: int
    """Decimals of the tick labels (the same on both axes: one step)."""
    rows_y: tuple[float, ...]
    """Baselines of the status rows under the frame."""

    def px(self, css: float) -> float:
        """A CSS size in image pixels."""
        return css * self.k


def _tick_labels(values: Iterable[float], decimals: int) -> list[str]:
    """Tick labels by the one rule of :mod:`egtviz.scene.shown_numbers` (``-0`` is written ``0``)."""
    return [format_value(v, f".{decimals}f") for v in values]


@lru_cache(maxsize=64)
def panel_layout(view: ViewBox, style: PanelStyle, panel_px: float, n_rows: int) -> PanelLayout:
    """The layout of a panel ``panel_px`` CSS pixels wide showing ``view``, with ``n_rows`` status rows.

    The axes frame is the view; the left margin holds the v tick labels, the
    top margin the u tick labels, the right margin the axis name ``u``, the
    bottom the name ``v`` and the status rows. The scale is
    ``s = (panel_px - left - right) / view.width`` CSS pixels per image pixel,
    the same along v (square pixels), and the tick step is the smallest 1-2-5
    step whose labels do not touch (:func:`~egtviz.viewer.render.panel_view.tick_values`).
    """
    t = style.tick_px
    tick_len, gap = 0.45 * t, 0.35 * t
    left, right = 5 * CHAR_EM * t + tick_len + gap, 3.0 * t
    decimals = 0
    for _ in range(3):  # margins depend on the labels, labels on the scale: settles in two rounds
        plot_w = max(panel_px - left - right, 0.35 * panel_px)
        s = plot_w / view.width
        ends = _tick_labels(np.array([view.u0, view.u1, view.v0, view.v1]), decimals)
        u_gap = max(text_width_px(e, t) for e in ends) + 1.2 * t
        u_ticks, du = tick_values(view.u0, view.u1, s, u_gap)
        v_ticks, dv = tick_values(view.v0, view.v1, s, 2.0 * t)
        decimals = max(du, dv)
        v_labels = _tick_labels(v_ticks, decimals) or ["0"]
        u_labels = _tick_labels(u_ticks, decimals) or ["0"]
        left = max(text_width_px(x, t) for x in v_labels) + tick_len + gap + 0.3 * t
        last_right = (u_ticks[-1] - view.u1) * s + text_width_px(u_labels[-1], t) / 2 if len(u_ticks) else 0.0
        right = max(last_right, 0.0) + gap + 1.4 * t
    plot_w = max(panel_px - left - right, 0.35 * panel_px)
    s = plot_w / view.width
    k = 1.0 / s
    top = tick_len + gap + 1.1 * t
    row = 1.3 * style.status_px
    first = max(1.45 * t, 0.35 * t + row)
    bottom = first + (max(n_rows, 1) - 1) * row + 0.45 * style.status_px
    plot_h = view.height * s
    height = top + plot_h + bottom
    rows = tuple(view.v1 + (first + i * row) * k for i in range(max(n_rows, 1)))
    vb = (view.u0 - left * k, view.v0 - top * k, panel_px * k, height * k)
    return PanelLayout(view, float(panel_px), float(height), k, vb, tuple(u_ticks.tolist()), tuple(v_ticks.tolist()),
                       decimals, rows)


@lru_cache(maxsize=64)
def axes_svg(lay: PanelLayout, style: PanelStyle) -> str:
    """The view's frame with ticks: u along the top edge, v along the left edge (v grows downwards)."""
    v, k, t = lay.view, lay.k, style.tick_px
    tick, gap, lw = 0.45 * t * k, 0.35 * t * k, style.frame_px * k
    parts = [f'<rect data-kind="frame" x="{svg_number(v.u0)}" y="{svg_number(v.v0)}" width="{svg_number(v.width)}" height="{svg_number(v.height)}" '
             f'fill="none" stroke="{style.ink}" stroke-width="{svg_number(lw)}"/>']
    path = []
    texts = []
    for val, lab in zip(lay.u_ticks, _tick_labels(lay.u_ticks, lay.decimals)):
        path.append(f"M{svg_number(val)} {svg_number(v.v0)}v{svg_number(-tick)}")
        texts.append(f'<text x="{svg_number(val)}" y="{svg_number(v.v0 - tick - gap)}" text-anchor="middle">{lab}</text>')
    for val, lab in zip(lay.v_ticks, _tick_labels(lay.v_ticks, lay.decimals)):
        path.append(f"M{svg_number(v.u0)} {svg_number(val)}h{svg_number(-tick)}")
        texts.append(f'<text x="{svg_number(v.u0 - tick - gap)}" y="{svg_number(val + 0.35 * t * k)}" text-anchor="end">{lab}</text>')
    last = _tick_labels(lay.u_ticks[-1:], lay.decimals)
    u_x = max(v.u1, (lay.u_ticks[-1] + text_width_px(last[0], t) * k / 2) if last else v.u1) + gap
    parts.append(f'<path d="{"".join(path)}" stroke="{style.ink}" stroke-width="{svg_number(lw)}"/>')
    parts.append(
        f'<g font-size="{svg_number(t * k)}" fill="{style.ink}">{"".join(texts)}'
        f'<text x="{svg_number(u_x)}" y="{svg_number(v.v0 - tick - gap)}" font-style="italic">u</text>'
        f'<text x="{svg_number(v.u0 - tick - gap)}" y="{svg_number(lay.rows_y[0])}" font-style="italic" text-anchor="end">v</text></g>'
    )
    return f'<g data-kind="axes">{"".join(parts)}</g>'


def svg_open(kind: str, attrs: str, lay: PanelLayout, style: PanelStyle, *, fixed_size: bool,
             max_height: str | None) -> str:
    """The root ``<svg>`` tag and a background covering the whole view box."""
    x, y, w, h = lay.viewbox
    mh = "" if max_height is None else f";max-height:{escape(max_height)}"
    size = (f'width="{svg_number(lay.panel_px)}" height="{svg_number(lay.height_px)}"' if fixed_size else 'width="100%"')
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" data-egtviz="{kind}"{attrs} data-style="{style.name}" '
        f'viewBox="{svg_number(x)} {svg_number(y)} {svg_number(w)} {svg_number(h)}" {size} '
        f'style="display:block;font-family:sans-serif;background:{style.background}{mh}">'
        f'<rect x="{svg_number(x)}" y="{svg_number(y)}" width="{svg_number(w)}" height="{svg_number(h)}" fill="{style.background}"/>'
    )


def _border_exit(view: ViewBox, target: Sequence[float],
                 inset: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """Where the ray from the view's centre towards ``target`` leaves the view (``inset`` inside it), and its direction.

    Used only to place an arrow marker (layout, not geometry): the epipole
    itself comes from the scene layer. Plain floats: two coordinates do not pay numpy's fixed cost per call.
    """
    cu, cv = view.centre
    du, dv = float(target[0]) - cu, float(target[1]) - cv
    n = float(np.hypot(du, dv))
    if n == 0.0 or not math.isfinite(n):
        return (cu, cv), (1.0, 0.0)
    du, dv = du / n, dv / n
    ts = []
    if abs(du) > 1e-12:
        ts.append((view.width / 2.0 - inset) / abs(du))
    if abs(dv) > 1e-12:
        ts.append((view.height / 2.0 - inset) / abs(dv))
    t = min(ts) if ts else 0.0
    return (cu + t * du, cv + t * dv), (du, dv)


def _arrow(tip: tuple[float, float], d: tuple[float, float], length: float, colour: str, width: float
           ) -> tuple[str, tuple[float, float, float, float]]:
    """An arrow whose head is at ``tip`` pointing along ``d``, and its bounding box ``(x0, y0, x1, y1)``."""
    (tx, ty), (dx, dy) = tip, d
    ax, ay = tx - dx * length, ty - dy * length
    head = length * 0.38
    nx, ny = -dy, dx
    p1x, p1y = tx - dx * head + nx * head * 0.5, ty - dy * head + ny * head * 0.5
    p2x, p2y = tx - dx * head - nx * head * 0.5, ty - dy * head - ny * head * 0.5
    box = (min(ax, tx, p1x, p2x) - width, min(ay, ty, p1y, p2y) - width,
           max(ax, tx, p1x, p2x) + width, max(ay, ty, p1y, p2y) + width)
    svg = (
        f'<line x1="{svg_number(ax)}" y1="{svg_number(ay)}" x2="{svg_number(tx)}" y2="{svg_number(ty)}" '
        f'stroke="{colour}" stroke-width="{svg_number(width)}"/>'
        f'<polygon points="{svg_number(tx)},{svg_number(ty)} {svg_number(p1x)},{svg_number(p1y)} {svg_number(p2x)},{svg_number(p2y)}" '
        f'fill="{colour}"/>'
    )
    return svg, box

def points_attr(P: np.ndarray, *, integer: bool) -> str:
    """A polyline's ``points`` attribute in one %-format (a 200-conic panel has ~25 000 vertices).

    Whole pixels when the image is large (a panel shows it at well under 1 screen pixel per image pixel).
    """
    if integer:
        Q = np.rint(P).astype(np.int64)
        return (("%d,%d " * len(Q)) % tuple(Q.ravel().tolist()))[:-1]
    return (("%.5g,%.5g " * len(P)) % tuple(np.asarray(P, float).ravel().tolist()))[:-1]


#: Whole numbers in ``[_INT_LO, _INT_HI)`` are written from lookup tables (a panel's pixels nearly always are).
_INT_LO, _INT_HI = -8192, 16384
_INT_TABLES: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None


def _int_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Object arrays of ``"v,"``, ``"v "`` and ``"v"`` for every whole number v in the table range."""
    global _INT_TABLES
    if _INT_TABLES is None:
        nums = [str(v) for v in range(_INT_LO, _INT_HI)]
        tabs = []
        for sep in (",", " ", ""):
            t = np.empty(len(nums), dtype=object)
            t[:] = [x + sep for x in nums]
            tabs.append(t)
        _INT_TABLES = (tabs[0], tabs[1], tabs[2])
    return _INT_TABLES


#: ``rint(x * 10**dp)`` in ``[_FIX_LO, _FIX_HI)`` is written from a lookup table (``"%.{dp}f"``).
_FIX_LO, _FIX_HI = -32768, 65536
_FIX_TABLES: dict[int, np.ndarray] = {}
#: Up to this many numbers are formatted one by one (the same text, without the table's dozen numpy calls).
_FIX_SMALL = 48


def _fixed_strs(X: npt.ArrayLike, dp: int) -> np.ndarray:
    """``"%.{dp}f" % x`` for every entry of ``X``, as an object array of the same shape.

    The decimal rounding is done once in numpy: where ``x * 10**dp`` is not
    within 1e-6 of a tie (so its correct rounding is certainly ``rint``) the
    string comes from a table; the few others (ties, ``-0.0``, out of the table
    range, non-finite) are formatted by ``%`` itself, so the text is identical.
    """
    X = np.asarray(X, float)
    if X.size <= _FIX_SMALL:  # a few numbers: numpy's fixed cost per call exceeds the formatting itself
        out = np.empty(X.shape, dtype=object)
        fmt = f"%.{dp}f"
        out.ravel()[:] = [fmt % v for v in X.ravel().tolist()]
        return out
    table = _FIX_TABLES.get(dp)
    if table is None:
        sc = 10**dp
        strs = []
        for n in range(_FIX_LO, _FIX_HI):
            a = abs(n)
            t = f"{a // sc}.{a % sc:0{dp}d}" if dp else str(a)
            strs.append("-" + t if n < 0 else t)
        table = np.empty(len(strs), dtype=object)
        table[:] = strs
        _FIX_TABLES[dp] = table
    with np.errstate(invalid="ignore", over="ignore"):
        y = X * float(10**dp)
        r = np.rint(y)
        ok = np.isfinite(y) & (r >= _FIX_LO) & (r < _FIX_HI) & (np.abs(np.abs(y - r) - 0.5) > 1e-6)
        ok &= ~(np.signbit(X) & (r == 0))
    out = np.empty(X.shape, dtype=object)
    out[ok] = table[(r[ok] - _FIX_LO).astype(np.int64)]
    if not ok.all():
        fmt = f"%.{dp}f"
        out[~ok] = [fmt % v for v in X[~ok].tolist()]
    return out


def warm_up() -> None:
    """Build the number tables of images 100 px and larger now, not in the first drag step that needs them."""
    _int_tables()
    _fixed_strs(np.zeros(1), 0)
    _fixed_strs(np.zeros(1), 1)


def finite_runs(P: np.ndarray) -> list[np.ndarray]:
    """Split a polyline at NaN rows into runs of at least two points."""
    P = np.asarray(P, float)
    if P.ndim != 2 or len(P) == 0:
        return []
    ok = np.all(np.isfinite(P), axis=1)
    if ok.all():
        return [P] if len(P) >= 2 else []
    edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(np.int8), 0]))
    return [P[a:b] for a, b in zip(edges[::2], edges[1::2]) if b - a >= 2]


def _conics_svg(conics: Sequence[Sequence[np.ndarray]], selected_point: int | None, lw: float, integer: bool,
                colours: tuple[str, ...]) -> str:
    """The ``epipolar-conic`` polylines of a panel, in index order, formatted in bulk.

    An arc with NaN vertices is split into its finite runs. Past
    ``CONIC_VERTEX_BUDGET`` vertices only every k-th sample is kept (and each
    run's last). On a large image (whole pixels) all runs are rounded in one
    numpy pass and written as one stream of table strings (``integer``).
    """
    runs = [piece for arcs in conics for piece in arcs]
    idx = [i for i, arcs in enumerate(conics) for _ in arcs]
    counts = [len(piece) for piece in runs]
    if counts and min(counts) < 2:  # rare: a piece of one sample is not drawn
        keep = [j for j, n in enumerate(counts) if n >= 2]
        runs, idx, counts = [runs[j] for j in keep], [idx[j] for j in keep], [counts[j] for j in keep]
    if not runs:
        return ""
    V = np.concatenate(runs).astype(float, copy=False)
    if not np.isfinite(V).all():  # rare: split the arcs with NaN vertices into their finite runs
        pairs = [(i, run) for i, piece in zip(idx, runs) for run in finite_runs(piece)]
        if not pairs:
            return ""
        idx, runs = [i for i, _ in pairs], [r for _, r in pairs]
        counts = [len(r) for r in runs]
        V = np.concatenate(runs)
    lengths = np.array(counts)
    stride = max(1, math.ceil(int(lengths.sum()) / CONIC_VERTEX_BUDGET))
    if stride > 1:
        # Keep every stride-th sample of each run, and its last.
        ends = np.cumsum(lengths)
        local = np.arange(len(V)) - np.repeat(ends - lengths, lengths)
        keep = (local % stride == 0) | (local == np.repeat(lengths - 1, lengths))
        V = V[keep]
        lengths = np.add.reduceat(keep, ends - lengths)
    prefixes, suffixes = _conic_tags(tuple(idx), selected_point, f' stroke-width="{svg_number(lw * 3.0)}"', colours)
    Q = np.rint(V).astype(np.int64) if integer else None
    if Q is None or Q.min() < _INT_LO or Q.max() >= _INT_HI:
        ends = np.cumsum(lengths)
        return "".join(p + points_attr(V[e - k:e], integer=Q is not None) + q
                       for p, q, e, k in zip(prefixes, suffixes, ends.tolist(), lengths.tolist()))
    # One token stream: per run [prefix, "x,", "y ", ..., "x,", "y", suffix].
    comma, space, bare = _int_tables()
    n, T = len(lengths), len(Q)
    first = 2 * (np.cumsum(lengths) - lengths) + 2 * np.arange(n)  # where each run's prefix goes
    vertex = np.repeat(first + 1, lengths) + 2 * (np.arange(T) - np.repeat(np.cumsum(lengths) - lengths, lengths))
    last = np.cumsum(lengths) - 1
    Q -= _INT_LO
    tokens = np.empty(2 * T + 2 * n, dtype=object)
    tokens[first] = prefixes
    tokens[first + 2 * lengths + 1] = suffixes
    tokens[vertex] = comma[Q[:, 0]]
    tokens[vertex + 1] = space[Q[:, 1]]
    tokens[vertex[last] + 1] = bare[Q[last, 1]]
    return "".join(tokens.tolist())


@lru_cache(maxsize=16)
def _conic_tags(idx: tuple[int, ...], selected_point: int | None, thick: str,
                colours: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The text before and after the vertices of each ``epipolar-conic`` run, as read-only object arrays (the same
    from one drag step to the next)."""
    prefixes = np.empty(len(idx), dtype=object)
    prefixes[:] = [f'<polyline data-kind="epipolar-conic" data-index="{i}" points="' for i in idx]
    suffixes = np.empty(len(idx), dtype=object)
    suffixes[:] = [f'" stroke="{colours[i % len(colours)]}"{thick if i == selected_point else ""}/>' for i in idx]
    prefixes.setflags(write=False)
    suffixes.setflags(write=False)
    return prefixes, suffixes


@lru_cache(maxsize=16)
def _line_tags(idx_bytes: bytes, selected_point: int | None, thick: str, colours: tuple[str, ...]) -> np.ndarray:
    """The text around the four coordinates of each ``epipolar-line`` (the same from one drag step to the next)."""
    idx = np.frombuffer(idx_bytes, dtype=np.intp).tolist()
    tags = np.empty((len(idx), 5), dtype=object)
    tags[:, 0] = [f'<line data-kind="epipolar-line" data-index="{i}" x1="' for i in idx]
    tags[:, 1] = '" y1="'
    tags[:, 2] = '" x2="'
    tags[:, 3] = '" y2="'
    tags[:, 4] = [f'" stroke="{colours[i % len(colours)]}"{thick if i == selected_point else ""}/>' for i in idx]
    tags.setflags(write=False)
    return tags


def numbered_points(n_in_image: int, show_labels: bool | str) -> bool:
    """Whether every point in the image gets its number (else only the selected and highlighted ones, as always
    when ``show_labels`` is ``"marked"``: a lesson step's ``labels = "selected"``)."""
    return bool(show_labels) and show_labels != "marked" and n_in_image <= MAX_NUMBERED_POINTS


#: A placed label's text in one %-format: ``"%.5g"`` writes a float as :func:`svg_number` does, for every float.
_LABEL_TEXT = '<text x="%.5g" y="%.5g" text-anchor="%s" data-box="%.5g %.5g %.5g %.5g"%s>%s</text>'


def label_text(box: Iterable[float], size: float, text: str, attrs: str, mark_x: float) -> str:
    """A text written in its placed box, on the side towards its mark (``mark_x``), baseline near the bottom.

    Left of the mark it ends at the box's right edge, right of it it starts at
    the left edge, above or below it is centred: the box's slack (its width is
    an upper bound) goes away from the mark.
    """
    x0, y0, x1, y1 = (float(b) for b in box)
    if x1 <= mark_x:
        x, anchor = x1, "end"
    elif x0 >= mark_x:
        x, anchor = x0, "start"
    else:
        x, anchor = (x0 + x1) / 2, "middle"
    return _LABEL_TEXT % (x, y1 - 0.17 * size, anchor, x0, y0, x1, y1, attrs, text)


def number_fates(boxes: np.ndarray, n_first: int, anchors: np.ndarray, reach: np.ndarray,
                  obstacles: np.ndarray, shown: np.ndarray) -> tuple[list[bool], list[bool]]:
    """Which placed point numbers are drawn, and which of those need a leader line to their point.

    A number whose box still overlaps a mark, an arrow or an earlier drawn label (the placement found no free
    box: a crowd) is not drawn; the panel says how many. A drawn number farther from its point than
    ``NUMBER_NEAR`` times the mark's reach (radius + gap; the first ring of candidates is within sqrt 2 of it),
    or with another point less than ``NUMBER_CLEAR`` times as far from it as its own, gets a leader line.

    Args:
        boxes: (n, 4) the placed boxes: first ``n_first`` epipole labels (always drawn), then the numbers.
        n_first: how many leading boxes are epipole labels.
        anchors: (n, 2) the marks' centres.
        reach: (n,) each mark's radius plus the placement gap.
        obstacles: (m, 4) the marks' and arrows' boxes.
        shown: (k, 2) every drawn point.
    """
    keep: list[bool] = []
    far: list[bool] = []
    B = boxes[n_first:]
    if len(B) == 0:
        return keep, far
    tiny = 1e-6 * (B[:, 2] - B[:, 0]) * (B[:, 3] - B[:, 1])  # rounding, not an overlap
    # Each number's overlap with every mark and arrow, then with every label (itself and those after it included:
    # only the labels drawn before it are read), in one pass.
    others = np.concatenate([obstacles.reshape(-1, 4), boxes])
    ow = np.minimum(B[:, None, 2], others[None, :, 2]) - np.maximum(B[:, None, 0], others[None, :, 0])
    oh = np.minimum(B[:, None, 3], others[None, :, 3]) - np.maximum(B[:, None, 1], others[None, :, 1])
    hits = (ow > 0) & (oh > 0) & (ow * oh > tiny[:, None])
    m = len(others) - len(boxes)
    blocked = hits[:, :m].any(axis=1).tolist()
    overlaps = hits[:, m:].tolist()
    drawn = list(range(n_first))
    for j, (row, hit) in enumerate(zip(overlaps, blocked)):
        hit = hit or any(row[i] for i in drawn)
        keep.append(not hit)
        if not hit:
            drawn.append(n_first + j)
    # A number's distance to every drawn point does not depend on the others' fates: all at once.
    A = anchors[n_first:]
    S = shown[None, :, :]
    D = np.maximum(np.maximum(B[:, None, :2] - S, S - B[:, None, 2:]), 0.0)
    mine = (S == A[:, None, :]).all(axis=2)  # the number's own point (and any drawn on it)
    nearest = np.where(mine, np.inf, np.hypot(D[..., 0], D[..., 1])).min(axis=1, initial=np.inf).tolist()
    for (x0, y0, x1, y1), (ax, ay), r, ok, d in zip(B.tolist(), A.tolist(), reach[n_first:].tolist(), keep, nearest):
        if not ok:
            far.append(False)
            continue
        own = math.hypot(max(x0 - ax, 0.0, ax - x1), max(y0 - ay, 0.0, ay - y1))
        far.append(own > NUMBER_NEAR * float(r) or d < NUMBER_CLEAR * own)
    return keep, far


@dataclass(frozen=True)
class _EpipoleLabel:
    """An epipole's label to place: its anchor (the cross, or the arrow's tail) and what to keep clear."""

    text: str
    anchor: tuple[float, float]
    radius: float
    obstacle: tuple[float, float, float, float]


def _marked_points(P: np.ndarray, drawn: np.ndarray, selected_point: int | None, highlighted: frozenset) -> set[int]:
    """The selected and highlighted points that are drawn (each gets a ring)."""
    candidates = set(highlighted) | ({selected_point} if selected_point is not None else set())
    return {int(i) for i in candidates if isinstance(i, (int, np.integer)) and 0 <= i < len(P) and drawn[i]}


@dataclass(frozen=True)
class _NumberPlan:
    """The point numbers of a panel to place, and the marks they keep clear of (the same while the points stay put).

    Attributes:
        numbered: the numbered points, in placement order (the selected, the highlighted, the others by index).
        marked: the points with a ring.
        obstacles: (m, 4) the discs' and rings' boxes.
        anchors, radii, sizes: each number's mark centre, mark radius and box size (``place_labels``'s arguments).
        reach: (n, 4) the box within which each number's candidate boxes lie (what can sway its placement).
        shown: (k, 2) every drawn point.
    """

    numbered: tuple[int, ...]
    marked: frozenset[int]
    obstacles: np.ndarray
    anchors: np.ndarray
    radii: np.ndarray
    sizes: np.ndarray
    reach: np.ndarray
    shown: np.ndarray


@lru_cache(maxsize=16)
def _number_plan(P_bytes: bytes, in_image_bytes: bytes, in_view_bytes: bytes, selected_point: int | None,
                 highlighted: frozenset, show_labels: bool | str, style: PanelStyle, k: float,
                 ringed: frozenset = frozenset()) -> _NumberPlan:
    """What :func:`_place_numbers` places (cached: a panel whose points stay put keeps it while its epipoles move).
    ``ringed`` points get a ring but a number only when every point is numbered."""
    P = np.frombuffer(P_bytes).reshape(-1, 2)
    in_image = np.frombuffer(in_image_bytes, dtype=bool)
    in_view = np.frombuffer(in_view_bytes, dtype=bool)
    marked = _marked_points(P, in_image | in_view, selected_point, highlighted | ringed)
    ring_only = marked - _marked_points(P, in_image | in_view, selected_point, highlighted) if ringed else set()
    r_pt = style.mark_px * k
    ring_r = r_pt * 2.0
    lw = style.line_px * k
    idx, outside = np.flatnonzero(in_image).tolist(), np.flatnonzero(in_view & ~in_image).tolist()
    number_all = numbered_points(len(idx), show_labels)
    # Points outside the view (zoomed in) keep their disc for the contract, clipped, but get no number. Only the
    # marked ones are numbered above MAX_NUMBERED_POINTS (the sort below fixes the order).
    numbered = [i for i in (idx + outside if number_all else marked) if show_labels and in_view[i]
                and (number_all or (i in marked and i not in ring_only))]
    # Placement order: epipole labels, then the selected, the highlighted, the others by index.
    numbered.sort(key=lambda i: (i != selected_point, i not in marked, i))
    size = style.label_px * k
    halo = 0.25 * style.label_px * k
    shown = P[in_view]
    obstacles = [np.column_stack([shown - r_pt - lw, shown + r_pt + lw])] if len(shown) else []
    if marked:
        M = P[sorted(marked)]
        obstacles.append(np.column_stack([M - ring_r - lw, M + ring_r + lw]))
    O = np.concatenate(obstacles) if obstacles else np.zeros((0, 4))
    anchors = np.array([P[i] for i in numbered], float).reshape(-1, 2)
    radii = np.array([ring_r if i in marked else r_pt for i in numbered], float)
    sizes = np.array([(text_width_px(str(i + 1), style.label_px) * k + halo, 0.95 * size + halo) for i in numbered],
                     float).reshape(-1, 2)
    # As place_labels bounds a label's candidates (the last ring's distance plus the box's size).
    far = (radii + 0.3 * size) * PLACEMENT_RINGS[-1]
    rx, ry = far + sizes[:, 0], far + sizes[:, 1]
    reach = np.column_stack([anchors[:, 0] - rx, anchors[:, 1] - ry, anchors[:, 0] + rx, anchors[:, 1] + ry])
    for a in (O, anchors, radii, sizes, reach, shown):
        a.setflags(write=False)
    return _NumberPlan(tuple(numbered), frozenset(marked), O, anchors, radii, sizes, reach, shown)


def _epipole_obstacles(plan: _NumberPlan, epipoles: tuple[_EpipoleLabel, ...]) -> np.ndarray:
    """The marks' boxes, then the epipoles' (the order :func:`place_labels` adds up their overlaps in)."""
    if not epipoles:
        return plan.obstacles
    return np.concatenate([plan.obstacles, np.array([e.obstacle for e in epipoles], float).reshape(-1, 4)])


def _epipole_boxes(plan: _NumberPlan, epipoles: tuple[_EpipoleLabel, ...], style: PanelStyle, k: float,
                   bounds: tuple[float, float, float, float]) -> np.ndarray:
    """The epipole labels' boxes: placed first, so the point numbers never move them."""
    if not epipoles:
        return np.zeros((0, 4))
    size = style.label_px * k
    halo = 0.25 * style.label_px * k
    sizes = [(text_width_px(e.text, style.label_px) * k + halo, 0.95 * size + halo) for e in epipoles]
    return place_labels([e.anchor for e in epipoles], [e.radius for e in epipoles], sizes,
                        _epipole_obstacles(plan, epipoles), bounds, gap=0.3 * size)


def _clear_of_numbers(plan: _NumberPlan, boxes: np.ndarray) -> bool:
    """Whether ``boxes`` (the epipoles' marks and labels) lie outside every number's reach, with a margin.

    Then they cannot sway a number's placement nor its fate: :func:`place_labels` adds up only the boxes within
    a label's reach, and a number's box lies inside its reach. The margin (far above rounding) keeps this true
    whatever the last bit of a reach's sum.
    """
    R = plan.reach
    if not len(R) or not len(boxes):
        return True
    if not np.isfinite(boxes).all():
        return False
    margin = 1e-9 * (1.0 + max(np.abs(R).max(), np.abs(boxes).max()))
    lo, hi = R[:, :2] - margin, R[:, 2:] + margin
    B = boxes[:, None, :]
    return bool(((B[..., :2] > hi) | (B[..., 2:] < lo)).any(axis=2).all())


def _place_numbers(plan: _NumberPlan, style: PanelStyle, k: float, bounds: tuple[float, float, float, float],
                   epipoles: tuple[_EpipoleLabel, ...], ep_boxes: tuple
                   ) -> tuple[dict[int, tuple[float, ...]], dict[int, tuple[float, ...]], int]:
    """Where the point numbers go, clear of the marks, of the epipole labels (placed first, in ``ep_boxes``) and of
    each other.

    Returns:
        ``(label_of, leader_of, n_unnumbered)``: the box of each drawn number by point, the boxes of the numbers
        that need a leader line, and how many numbers found no free box.
    """
    if not plan.numbered:
        return {}, {}, 0
    gap = 0.3 * style.label_px * k
    O = _epipole_obstacles(plan, epipoles)
    first = np.array(ep_boxes, float).reshape(-1, 4)
    placed = place_labels(plan.anchors, plan.radii, plan.sizes, O, bounds, gap=gap, placed=first)
    boxes = np.concatenate([first, placed.reshape(-1, 4)])
    anchors = np.concatenate([np.array([e.anchor for e in epipoles], float).reshape(-1, 2), plan.anchors])
    radii = np.concatenate([np.array([e.radius for e in epipoles], float), plan.radii])
    keep, far = number_fates(boxes, len(epipoles), anchors, radii + gap, O, plan.shown)
    numbered = plan.numbered
    placed = placed.tolist()
    label_of = {i: tuple(b) for i, b, ok in zip(numbered, placed, keep) if ok}
    leader_of = {i: tuple(b) for i, b, ok, f in zip(numbered, placed, keep, far) if ok and f}
    return label_of, leader_of, len(numbered) - len(label_of)


@lru_cache(maxsize=64)
def _group_constants(style: PanelStyle, k: float) -> tuple[str, str, str, str, str, float, str]:
    """The sizes a point's group writes, as text: disc radius, outline width, ring radius, ring width, leader width,
    the number's size, and its halo's attributes."""
    r_pt, lw = style.mark_px * k, style.line_px * k
    halo = 0.25 * style.label_px * k
    return (svg_number(r_pt), svg_number(lw * 1.6), svg_number(r_pt * 2.0), svg_number(lw * 1.5),
            svg_number(lw * 0.6), style.label_px * k, f' stroke="#fff" stroke-width="{svg_number(halo)}"')


@lru_cache(maxsize=256)
def _point_group(i: int, kind: str, xy: tuple[float, float], *, ring: bool, selected: bool,
                 label_box: tuple[float, ...] | None, leader_box: tuple[float, ...] | None, style: PanelStyle,
                 k: float, dp: int) -> str:
    """Point ``i``'s ``<g>``: its disc with (if any) its ring, its number and the number's leader line.

    Cached: the panel of the camera that does not move draws the same groups from one drag step to the next.
    """
    c = f"%.{dp}f"
    r_text, outline, ring_r, ring_w, leader_w, size, halo = _group_constants(style, k)
    x, y = xy
    cx, cy = c % x, c % y
    col = style.point_colours[i % len(style.point_colours)]
    hollow = kind == "point-outside"
    fill = "#fff" if hollow else col
    stroke = f' stroke="{col}" stroke-width="{outline}"' if hollow else ""
    ring_svg = label = leader = ""
    if ring:
        ring_svg = (f'<circle cx="{cx}" cy="{cy}" r="{ring_r}" fill="none" stroke="{style.ink}" '
                    f'stroke-width="{ring_w}" data-selected="{"true" if selected else "false"}"/>')
    if label_box is not None:
        label = label_text(label_box, size, str(i + 1), halo, x)
    if leader_box is not None:
        # From the box's nearest point to the disc's centre, under the disc: it ends at the point.
        x0, y0, x1, y1 = leader_box
        lx, ly = min(max(x, x0), x1), min(max(y, y0), y1)
        leader = (f'<line data-kind="label-leader" data-index="{i}" x1="{svg_number(lx)}" y1="{svg_number(ly)}" x2="{cx}" '
                  f'y2="{cy}" stroke="{style.ink}" stroke-width="{leader_w}"/>')
    return (f'<g data-kind="{kind}" data-index="{i}">{leader}{ring_svg}<circle cx="{cx}" cy="{cy}" '
            f'r="{r_text}" fill="{fill}"{stroke}/>{label}</g>')


def _marks(P_bytes: bytes, in_image_bytes: bytes, in_view_bytes: bytes, selected_point: int | None,
           highlighted: frozenset, show_labels: bool | str, style: PanelStyle, k: float, dp: int,
           bounds: tuple[float, float, float, float], epipoles: tuple[_EpipoleLabel, ...],
           ringed: frozenset = frozenset()) -> tuple[str, tuple, int]:
    """The points (``point`` and ``point-outside``) with their numbers, and the epipole label boxes.

    During a drag the panel of the camera that does not move keeps its pixels while its epipoles move: when the
    epipoles' marks and labels stay out of every number's reach (:func:`_clear_of_numbers`), the numbers are where
    they would be without them, and the points' text drawn for that case is reused.
    """
    plan = _number_plan(P_bytes, in_image_bytes, in_view_bytes, selected_point, highlighted, show_labels, style, k,
                        ringed)
    ep_boxes = _epipole_boxes(plan, epipoles, style, k, bounds)
    boxes = tuple(tuple(b) for b in ep_boxes.tolist())
    near = epipoles if plan.numbered else ()
    if near and _clear_of_numbers(plan, np.concatenate([ep_boxes, [e.obstacle for e in epipoles]])):
        near = ()
    body, n_unnumbered = _point_marks(P_bytes, in_image_bytes, in_view_bytes, selected_point, highlighted, show_labels,
                                      style, k, dp, bounds, near, boxes if near else (), ringed)
    return body, boxes, n_unnumbered


@lru_cache(maxsize=16)
def _point_marks(P_bytes: bytes, in_image_bytes: bytes, in_view_bytes: bytes, selected_point: int | None,
                 highlighted: frozenset, show_labels: bool | str, style: PanelStyle, k: float, dp: int,
                 bounds: tuple[float, float, float, float], epipoles: tuple[_EpipoleLabel, ...],
                 ep_boxes: tuple, ringed: frozenset = frozenset()) -> tuple[str, int]:
    """The points' text with their numbers placed clear of ``epipoles`` and their labels (``ep_boxes``) too, and how
    many numbers found no room."""
    P = np.frombuffer(P_bytes).reshape(-1, 2)
    in_image = np.frombuffer(in_image_bytes, dtype=bool)
    in_view = np.frombuffer(in_view_bytes, dtype=bool)
    idx, outside = np.flatnonzero(in_image).tolist(), np.flatnonzero(in_view & ~in_image).tolist()
    plan = _number_plan(P_bytes, in_image_bytes, in_view_bytes, selected_point, highlighted, show_labels, style, k,
                        ringed)
    marked = plan.marked
    label_of, leader_of, n_unnumbered = _place_numbers(plan, style, k, bounds, epipoles, ep_boxes)
    special = sorted(set(label_of) | marked)
    xy = [tuple(p) for p in P.tolist()] if special else []

    def group(i: int, kind: str) -> str:
        return _point_group(i, kind, xy[i], ring=i in marked, selected=i == selected_point,
                            label_box=label_of.get(i), leader_box=leader_of.get(i), style=style, k=k, dp=dp)

    if len(special) == len(idx) + len(outside):  # every disc has a number or a ring (a few points): groups only
        text = "".join([group(i, "point") for i in idx] + [group(i, "point-outside") for i in outside])
    else:
        rows = _plain_point_rows(P_bytes, in_image_bytes, in_view_bytes, style, k, dp)
        if special:
            rows = rows.copy()
        for i in special:  # a ring or a number: the disc's row becomes its group
            if in_image[i]:
                rows[bisect_left(idx, i)] = (group(i, "point"), "", "", "", "", "", "")
            else:
                rows[len(idx) + bisect_left(outside, i)] = (group(i, "point-outside"), "", "", "", "", "", "")
        text = "".join(rows.ravel().tolist())
    body = (f'<g stroke="{style.ink}" stroke-width="{svg_number(style.line_px * k * 0.5)}" '
            f'font-size="{svg_number(style.label_px * k)}" font-weight="bold" fill="{style.ink}" paint-order="stroke">'
            f'{text}</g>')
    return body, n_unnumbered


@lru_cache(maxsize=16)
def _plain_point_rows(P_bytes: bytes, in_image_bytes: bytes, in_view_bytes: bytes, style: PanelStyle, k: float,
                      dp: int) -> np.ndarray:
    """Every drawn point as a bare disc (no ring, no number), in :func:`_marks`'s order: the points in the image,
    then those in the view outside it. One row of strings per disc, whose concatenation is its ``<circle>``
    (read-only object array, (M, 7)). Cached apart from the labels: a panel whose points stay put (the camera that
    does not move during a drag) keeps these rows while its epipoles, and so its labels, move."""
    P = np.frombuffer(P_bytes).reshape(-1, 2)
    in_image = np.frombuffer(in_image_bytes, dtype=bool)
    in_view = np.frombuffer(in_view_bytes, dtype=bool)
    inside = np.flatnonzero(in_image)
    outside = np.flatnonzero(in_view & ~in_image)
    members = np.concatenate([inside, outside])
    rows = np.empty((len(members), 7), dtype=object)
    if not len(members):
        return rows
    xy = _fixed_strs(P[members], dp)  # the exact "%.{dp}f" text
    (head_in, fill_in), (head_out, fill_out) = _disc_tags(len(P), style.point_colours)
    n_in = len(inside)
    rows[:n_in, 0], rows[:n_in, 5], rows[:n_in, 6] = head_in[inside], fill_in[inside], ""
    rows[n_in:, 0], rows[n_in:, 5] = head_out[outside], fill_out[outside]
    rows[n_in:, 6] = f' stroke-width="{svg_number(style.line_px * k * 1.6)}"/>'
    rows[:, 1] = xy[:, 0]
    rows[:, 2] = '" cy="'
    rows[:, 3] = xy[:, 1]
    rows[:, 4] = f'" r="{svg_number(style.mark_px * k)}" fill="'
    rows.setflags(write=False)
    return rows


@lru_cache(maxsize=16)
def _disc_tags(n: int, colours: tuple[str, ...]) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """Per index, the text before ``cx`` and the fill after ``r`` of each point's bare disc: ``(heads, fills)`` of the
    ``point`` variant and of the ``point-outside`` one (the same from one drag step to the next)."""
    h_in, f_in, h_out, f_out = (np.empty(n, dtype=object) for _ in range(4))
    h_in[:] = [f'<circle data-kind="point" data-index="{i}" cx="' for i in range(n)]
    h_out[:] = [f'<circle data-kind="point-outside" data-index="{i}" cx="' for i in range(n)]
    f_in[:] = [f'{colours[i % len(colours)]}"/>' for i in range(n)]
    f_out[:] = [f'#fff" stroke="{colours[i % len(colours)]}"' for i in range(n)]
    for a in (h_in, f_in, h_out, f_out):
        a.setflags(write=False)
    return (h_in, f_in), (h_out, f_out)


def empty_svg(camera: str, width: int = 640, height: int = 480, message: str = "") -> str:
    """A blank image plane with a border and a message (before the first update)."""
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" data-egtviz="image-plane" data-camera="{escape(camera)}" '
        f'viewBox="0 0 {width} {height}" width="100%">'
        f'<rect data-kind="border" x="0" y="0" width="{width}" height="{height}" fill="#fff" stroke="#333"/>'
        f'<text data-kind="message" x="{width / 2}" y="{height / 2}" text-anchor="middle">{escape(message)}</text>'
        "</svg>"
    )


def _wrap(clauses: list[str], max_px: float, size_px: float) -> list[str]:
    """Join clauses with ``"; "`` into lines no wider than ``max_px`` (a clause longer than that gets a line)."""
    lines: list[str] = []
    for cl in clauses:
        if lines and text_width_px(lines[-1] + "; " + cl, size_px) <= max_px:
            lines[-1] += "; " + cl
        else:
            lines.append(cl)
    return lines


def _segments_of_lines(L: np.ndarray, coefficients: np.ndarray | None, view: ViewBox) -> np.ndarray:
    """The segments ``L`` (N, 4), with a segment of its line ``(a, b, c)`` where the scene layer had none because the
    line misses the image: the foot of the perpendicular from the view's centre ``p0`` and ``p0 + (-b, a)``."""
    if coefficients is None:
        return L
    coefficients = np.asarray(coefficients, float)
    with np.errstate(invalid="ignore"):
        drawable = np.all(np.isfinite(coefficients), axis=1) & (np.abs(coefficients[:, :2]).sum(axis=1) > 0)
    missing = ~np.all(np.isfinite(L), axis=1) & drawable
    if not missing.any():
        return L
    a, b, c = coefficients[missing].T
    n2 = a * a + b * b
    cu, cv = view.centre
    dist = (a * cu + b * cv + c) / n2
    u0, v0 = cu - a * dist, cv - b * dist
    L = L.copy()
    L[missing] = np.column_stack([u0, v0, u0 - b, v0 + a])
    return L


def _extend_segments(L: np.ndarray, view: ViewBox) -> np.ndarray:
    """Each segment (x1, y1, x2, y2) extended along its own line to the view's edges (rows that miss it: NaN).

    The scene layer clips epipolar lines to the image; a view larger than the
    image shows the same straight lines over its whole box (Liang-Barsky
    clipping of ``p = a + t (b - a)`` to the box).
    """
    a, d = L[:, 0:2], L[:, 2:4] - L[:, 0:2]
    mn, mx = np.array([view.u0, view.v0]), np.array([view.u1, view.v1])
    with np.errstate(divide="ignore", invalid="ignore"):
        # Both axes at once: the same operations per coordinate as one axis after the other.
        t1, t2 = (mn - a) / d, (mx - a) / d
        flat = d == 0
        inside = (a >= mn) & (a <= mx)
        t_lo = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
        t_hi = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
        lo, hi = np.maximum(t_lo[:, 0], t_lo[:, 1]), np.minimum(t_hi[:, 0], t_hi[:, 1])
    ok = (hi > lo) & np.isfinite(lo) & np.isfinite(hi)
    out = np.full_like(L, np.nan)
    out[ok] = np.column_stack([a[ok] + lo[ok, None] * d[ok], a[ok] + hi[ok, None] * d[ok]])
    return out


def image_plane_svg(
    plane: ImagePlane,
    *,
    selected_point: int | None = None,
    highlighted: frozenset[int] | set[int] = frozenset(),
    show_labels: bool | str = True,
    revision: int | None = None,
    max_height: str | None = None,
    view: ViewBox | None = None,
    style: PanelStyle = NORMAL,
    panel_px: float | None = None,
    fixed_size: bool = False,
    ringed: frozenset[int] = frozenset(),
) -> str:
    """Inline SVG of one camera's image plane, in pixel units.

    Args:
        plane: an :class:`egtviz.scene.ImagePlane` (read: ``camera``, ``width``, ``height``, ``points``,
            ``visible``, ``in_image``, ``n_hidden``, ``no_image``, ``epipoles``, ``lines``, ``conics``, ``rim``,
            ``horizon``, ``message``).
        selected_point: 0-based index of the selected scene point: drawn with a ring, its epipolar line/conic thicker.
        highlighted: 0-based indices of highlighted points (a ring too).
        show_labels: write the point numbers (1-based) next to the points (``"marked"``: the marked ones).
        revision: written as ``data-rev`` on the root (a browser test or the benchmark recognises an update by it).
        max_height: a CSS ``max-height`` for the SVG (it keeps its aspect ratio).
        view: the part of the image plane shown (:mod:`egtviz.viewer.render.panel_view`);
            ``None``: the image rectangle.
        style: ``NORMAL`` or ``PRESENT``.
        panel_px: the panel's width on screen in CSS pixels, if known: the style's sizes are met at that width
            (default ``style.panel_px``).
        fixed_size: write ``width``/``height`` in pixels (a figure file) instead of ``width="100%"`` (a panel that
            follows its column).
        ringed: 0-based indices of points an instrument rings (e.g. the estimation lab's rejects): a ring, and a
            number only when every point is numbered (a step that numbers the selected point only keeps it so).

    Returns:
        The ``<svg>`` element as a string (see the module docstring for the
        ``data-*`` attributes).
    """
    image = image_view(plane)
    view = image if view is None else view
    panel_px = float(style.panel_px if panel_px is None else panel_px)
    if not (math.isfinite(panel_px) and panel_px > 0):
        raise ValueError(f"panel_px must be a finite number of CSS pixels > 0, got {panel_px}")
    P = np.ascontiguousarray(np.asarray(plane.points, float).reshape(-1, 2))
    in_image = np.ascontiguousarray(np.asarray(plane.in_image, bool).reshape(-1))
    epipoles = tuple(plane.epipoles or ())
    status_lines, numbering_note = _status_lines(plane, len(P), int(in_image.sum()), show_labels, style, panel_px)
    at_inf = [ep for ep in epipoles if ep.at_infinity or ep.xy is None]
    lay = panel_layout(view, style, panel_px, len(at_inf) + len(status_lines) + int(numbering_note))
    k = lay.k
    rev = "" if revision is None else f' data-rev="{int(revision)}"'
    attrs = (f' data-camera="{escape(str(plane.camera))}"{rev} '
             f'data-view="{svg_number(view.u0)} {svg_number(view.v0)} {svg_number(view.width)} {svg_number(view.height)}"')
    out = [svg_open("image-plane", attrs, lay, style, fixed_size=fixed_size, max_height=max_height),
           *_frame_svg(plane, view, lay, style)]
    # Decimals: a quarter of a CSS pixel; whole image pixels once one is at most a CSS pixel wide.
    dp = int(min(6, max(0, math.ceil(math.log10(4.0 / k)))))
    if plane.lines is not None:
        out.append(_lines_svg(plane, view, image, selected_point, style, k, dp))
    if plane.conics is not None:
        lw = style.line_px * k
        out.append(f'<g fill="none" stroke-width="{svg_number(lw)}">'
                   f'{_conics_svg(plane.conics, selected_point, lw, k >= 1.0, style.point_colours)}</g>')
    row = iter(lay.rows_y)  # the epipoles at infinity take the first status rows
    ep_marks, ep_labels = _epipole_marks(epipoles, view, style, k, row)
    in_view = np.ascontiguousarray(view.contains(P))
    points_svg, ep_boxes, n_unnumbered = _marks(P.tobytes(), in_image.tobytes(), in_view.tobytes(), selected_point,
                                                frozenset(highlighted), show_labels, style, k, dp,
                                                (view.u0, view.v0, view.u1, view.v1), tuple(ep_labels),
                                                frozenset(ringed))
    if n_unnumbered:  # one more status row (the scale, and so every size drawn so far, does not depend on the rows)
        lay = panel_layout(view, style, panel_px, len(lay.rows_y) + 1)
        out[0] = svg_open("image-plane", attrs, lay, style, fixed_size=fixed_size, max_height=max_height)
    out += [points_svg, "</g>"]  # the points end the clipped group
    out.extend(_epipole_groups(ep_marks, ep_labels, ep_boxes, style, k))
    out.extend(_notes_svg(plane, view, style, k, row, status_lines, numbering_note, n_unnumbered,
                          lay.rows_y[-1] if n_unnumbered else 0.0))
    out.append("</svg>")
    return "".join(out)


def _status_lines(plane: ImagePlane, n_points: int, n_in: int, show_labels: bool | str, style: PanelStyle,
                  panel_px: float) -> tuple[list[str], bool]:
    """The status rows under the frame (the point counts, wrapped to the panel's width) and whether the numbering
    note takes one more."""
    n_hidden = int(plane.n_hidden)
    n_outside = int(n_points - n_hidden - n_in)
    clauses = [f"{n_in} of {n_points} points in the image"]
    if n_hidden:
        clauses.append(f"{n_hidden} hidden ({plane.no_image})")
    if n_outside > 0:
        clauses.append(f"{n_outside} outside the image")
    return _wrap(clauses, 0.8 * panel_px, style.status_px), bool(show_labels) and not numbered_points(n_in, True)


def _frame_svg(plane: ImagePlane, view: ViewBox, lay: PanelLayout, style: PanelStyle) -> list[str]:
    """The image's border and the axes, then the group clipped to the view opened with the rim and the horizon.

    Cached by what it draws: a drag step changes none of it (a mirror's rim and horizon are some hundred vertices).
    """
    rim = None if plane.rim is None else np.ascontiguousarray(plane.rim, float)
    arcs = tuple(np.ascontiguousarray(arc, float) for arc in plane.horizon)
    return list(_frame_parts(str(plane.camera), float(plane.width), float(plane.height), view, lay, style,
                             None if rim is None else (rim.tobytes(), rim.shape),
                             tuple((a.tobytes(), a.shape) for a in arcs)))


@lru_cache(maxsize=32)
def _frame_parts(camera: str, w: float, h: float, view: ViewBox, lay: PanelLayout, style: PanelStyle,
                 rim: tuple[bytes, tuple[int, ...]] | None, horizon: tuple[tuple[bytes, tuple[int, ...]], ...]
                 ) -> tuple[str, ...]:
    """:func:`_frame_svg`'s text; ``rim`` and each horizon arc as their float64 bytes and shape."""
    k = lay.k
    lw = style.line_px * k
    out = [
        f'<rect data-kind="border" x="0" y="0" width="{svg_number(w)}" height="{svg_number(h)}" fill="#ffffff" '
        f'stroke="{style.ink}" stroke-width="{svg_number(style.frame_px * k)}"/>',
        axes_svg(lay, style),
    ]
    # Clip everything drawn on the image plane to the view.
    clip_id = "clip-" + "".join(ch if ch.isalnum() else "_" for ch in camera)
    clip_id += f"-{zlib.crc32(camera.encode()):08x}"  # "a b" and "a_b" stay distinct
    out.append(f'<defs><clipPath id="{clip_id}"><rect x="{svg_number(view.u0)}" y="{svg_number(view.v0)}" width="{svg_number(view.width)}" '
               f'height="{svg_number(view.height)}"/></clipPath></defs><g clip-path="url(#{clip_id})">')
    if rim is not None:
        for run in finite_runs(np.frombuffer(rim[0]).reshape(rim[1])):
            out.append(
                f'<polygon data-kind="rim" points="{points_attr(run, integer=False)}" fill="none" '
                f'stroke="{RIM_COLOUR}" '
                f'stroke-width="{svg_number(lw)}" stroke-dasharray="{svg_number(lw * 5)} {svg_number(lw * 3)}"/>'
            )
    for data, shape in horizon:
        out.append(
            f'<polyline data-kind="horizon" points="{points_attr(np.frombuffer(data).reshape(shape), integer=False)}" '
            f'fill="none" stroke="{RIM_COLOUR}" stroke-width="{svg_number(lw)}" stroke-dasharray="{svg_number(lw)} {svg_number(lw * 3)}"/>'
        )
    return tuple(out)


def _lines_svg(plane: ImagePlane, view: ViewBox, image: ViewBox, selected_point: int | None, style: PanelStyle,
               k: float, dp: int) -> str:
    """The epipolar lines: clipped to the image, or across the whole view when it is not the image rectangle."""
    lw = style.line_px * k
    thick = f' stroke-width="{svg_number(lw * 2.5)}"'
    L = np.asarray(plane.lines, float).reshape(-1, 4)
    if view != image:
        L = _extend_segments(_segments_of_lines(L, plane.line_coefficients, view), view)
    ok = np.all(np.isfinite(L), axis=1)
    idx = np.flatnonzero(ok)
    table = np.empty((len(idx), 9), dtype=object)
    if len(idx):
        table[:, 0::2] = _line_tags(idx.tobytes(), selected_point, thick, style.point_colours)
        table[:, 1:9:2] = _fixed_strs(L[ok], max(dp, 1))
    return f'<g stroke-width="{svg_number(lw)}">{"".join(table.ravel().tolist())}</g>'


def _epipole_marks(epipoles: tuple[Epipole, ...], view: ViewBox, style: PanelStyle, k: float, row: Iterator[float]
                   ) -> tuple[list[tuple[Epipole, str, str, str]], list[_EpipoleLabel]]:
    """Each epipole's mark: in the view a cross, elsewhere an arrow at the frame pointing to it; one at infinity
    also gets a status row (from ``row``) saying its direction.

    Returns:
        ``(marks, labels)``: per epipole ``(epipole, where, drawn, svg of the mark and its text)``, and the labels
        still to place (the epipoles not at infinity, in order).
    """
    lw = style.line_px * k
    size = style.label_px * k
    a = style.mark_px * 1.8 * k
    arrow_len = 2.6 * style.label_px * k
    st = style.status_px * k
    ep_marks: list[tuple[Epipole, str, str, str]] = []
    ep_labels: list[_EpipoleLabel] = []
    for ep in epipoles:
        label = str(ep.label)
        where = "inside" if ep.inside else "outside"
        if ep.at_infinity or ep.xy is None:
            d = np.asarray(ep.direction, float) if ep.direction is not None else np.array([1.0, 0.0])
            tip, dd = _border_exit(view, (np.array(view.centre) + d * 1e6 * max(view.width, view.height)).tolist(),
                                   0.3 * a)
            svg, _ = _arrow(tip, dd, arrow_len, EPIPOLE_COLOUR, lw * 1.8)
            text = (f'<text x="{svg_number(view.u0)}" y="{svg_number(next(row))}" font-size="{svg_number(st)}" fill="{EPIPOLE_COLOUR}">'
                    f"{escape(label)} at infinity, direction ({format_vector(d[:2], '.2f')})</text>")
            ep_marks.append((ep, "infinity", "arrow", f'<g data-kind="epipole-arrow">{svg}</g>{text}'))
            continue
        x, y = (float(v) for v in ep.xy)
        if view.u0 <= x <= view.u1 and view.v0 <= y <= view.v1:  # as ViewBox.contains (NaN: outside)
            svg = (f'<path d="M{svg_number(x - a)} {svg_number(y - a)}L{svg_number(x + a)} {svg_number(y + a)}M{svg_number(x - a)} {svg_number(y + a)}'
                   f'L{svg_number(x + a)} {svg_number(y - a)}" stroke="{EPIPOLE_COLOUR}" stroke-width="{svg_number(lw * 1.8)}"/>')
            text = label if ep.inside else f"{label} ({format_vector((x, y))})"
            ep_labels.append(_EpipoleLabel(text, (x, y), a, (x - a, y - a, x + a, y + a)))
            ep_marks.append((ep, where, "mark", svg))
        else:
            tip, dd = _border_exit(view, (x, y), 0.3 * a)
            svg, box = _arrow(tip, dd, arrow_len, EPIPOLE_COLOUR, lw * 1.8)
            tail = (tip[0] - dd[0] * arrow_len, tip[1] - dd[1] * arrow_len)
            ep_labels.append(_EpipoleLabel(f"{label} ({format_vector((x, y))})", tail, 0.2 * size, box))
            ep_marks.append((ep, where, "arrow", f'<g data-kind="epipole-arrow">{svg}</g>'))
    return ep_marks, ep_labels


def _epipole_groups(ep_marks: list[tuple[Epipole, str, str, str]], ep_labels: list[_EpipoleLabel], ep_boxes: tuple,
                    style: PanelStyle, k: float) -> list[str]:
    """Each epipole's ``<g>``: its mark and (not at infinity) its label in the box placed for it."""
    size = style.label_px * k
    halo = 0.25 * style.label_px * k
    placed = iter(zip(ep_labels, ep_boxes))
    out = []
    for ep, where, drawn, mark in ep_marks:
        label = escape(str(ep.label))
        text = ""
        if where != "infinity":
            lab, box = next(placed)
            text = label_text(box, size, escape(lab.text),
                               f' data-kind="epipole-label" font-size="{svg_number(size)}" fill="{EPIPOLE_COLOUR}" '
                               f'font-style="italic" paint-order="stroke" stroke="#fff" stroke-width="{svg_number(halo)}"',
                               lab.anchor[0])
        xy = "" if ep.xy is None else f' data-x="{float(ep.xy[0]):.5g}" data-y="{float(ep.xy[1]):.5g}"'
        out.append(f'<g data-kind="epipole" data-label="{label}" data-where="{where}" data-drawn="{drawn}"{xy}>'
                   f"{mark}{text}</g>")
    return out


def _notes_svg(plane: ImagePlane, view: ViewBox, style: PanelStyle, k: float, row: Iterator[float],
               status_lines: list[str], numbering_note: bool, n_unnumbered: int, crowded_y: float) -> list[str]:
    """The status rows under the frame (from ``row``): the counts, the numbering note and the crowded note (at
    ``crowded_y``, the row added for it), then the plane's message over its centre."""
    st = style.status_px * k
    halo = 0.25 * style.label_px * k
    ys = [next(row) for _ in status_lines]
    spans = (escape(status_lines[0]) if len(status_lines) == 1 else
             "".join(f'<tspan x="{svg_number(view.u1)}" y="{svg_number(y)}">{escape(s)}</tspan>' for s, y in zip(status_lines, ys)))
    out = [f'<text data-kind="hidden-count" data-hidden="{int(plane.n_hidden)}" x="{svg_number(view.u1)}" y="{svg_number(ys[0])}" '
           f'text-anchor="end" font-size="{svg_number(st)}" fill="{style.ink}">{spans}</text>']
    if numbering_note:
        out.append(
            f'<text data-kind="numbering-note" x="{svg_number(view.u1)}" y="{svg_number(next(row))}" text-anchor="end" '
            f'font-size="{svg_number(st)}" fill="{style.ink}">numbers: selected point only '
            f"(over {MAX_NUMBERED_POINTS} points)</text>"
        )
    if n_unnumbered:
        what = "number" if n_unnumbered == 1 else "numbers"
        out.append(
            f'<text data-kind="crowded-note" data-unnumbered="{n_unnumbered}" x="{svg_number(view.u1)}" '
            f'y="{svg_number(crowded_y)}" text-anchor="end" font-size="{svg_number(st)}" fill="{style.ink}">'
            f"{n_unnumbered} point {what} not shown (no room beside their points)</text>"
        )
    if plane.message:
        cu, cv = view.centre
        out.append(
            f'<text data-kind="message" x="{svg_number(cu)}" y="{svg_number(cv)}" text-anchor="middle" font-size="{svg_number(st)}" '
            f'fill="#a00" paint-order="stroke" stroke="#fff" stroke-width="{svg_number(halo)}">'
            f"{escape(str(plane.message))}</text>"
        )
    return out
