"""Image-plane panels as inline SVG: a pure function from an ``ImagePlane`` to a string.

The SVG is in pixel units (``viewBox`` = the image, plus a margin for the axes'
tick labels and for the arrows that point to epipoles outside the image). It
draws only what the scene layer computed (:class:`egtviz.scene.ImagePlane`):
points, epipoles, clipped epipolar lines, epipolar conics, the mirror rim.

Testability contract (the browser tests rely on it):

* the root ``<svg>`` carries ``data-egtviz="image-plane"`` and
  ``data-camera="<camera name>"``;
* drawn elements carry ``data-kind``: ``border``, ``point`` (with
  ``data-index``, 0-based, one per point inside the image: a ``<g>`` holding
  the disc and its number, or a bare disc when the point is not numbered),
  ``epipole`` (with
  ``data-label`` and ``data-where`` = ``inside`` | ``outside`` | ``infinity``),
  ``epipolar-line`` (with ``data-index``, one per drawn line),
  ``epipolar-conic`` (with ``data-index``; a conic may have several pieces),
  ``rim``, ``message``, ``hidden-count``, ``numbering-note``.

Point labels are 1-based, like EGT's ``f_3Dwfenum``; ``data-index`` is 0-based.
Above ``MAX_NUMBERED_POINTS`` points in an image only the selected and
highlighted points are numbered.
"""

from __future__ import annotations

import math
import zlib
from functools import lru_cache
from html import escape
from typing import Any

import numpy as np

from .palette import EPIPOLE_COLOUR, POINT_COLOURS, RIM_COLOUR, point_colour

_COLOURS = tuple(POINT_COLOURS)
_N_COLOURS = len(_COLOURS)

__all__ = ["image_plane_svg", "empty_svg"]

#: Above this many points in an image only the selected and highlighted points are numbered (more are unreadable).
MAX_NUMBERED_POINTS = 40

#: Most conic vertices drawn in one panel (200 conics x 129 samples would be ~260 kB of SVG per update).
CONIC_VERTEX_BUDGET = 10_000


def _f(x: float) -> str:
    """Compact coordinate formatting: five significant digits (images may be 2 px or 4000 px wide)."""
    return f"{x:.5g}"


def _nice_step(span: float) -> float:
    """A 1-2-5 tick step giving about 5-8 ticks over ``span``."""
    raw = span / 6.0
    mag = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if raw <= m * mag:
            return m * mag
    return 10.0 * mag


def _border_exit(w: float, h: float, target: np.ndarray, inset: float) -> tuple[np.ndarray, np.ndarray]:
    """Where the segment from the image centre towards ``target`` leaves the image, and its unit direction.

    Used only to place an arrow marker (layout, not geometry): the epipole itself
    comes from the scene layer.
    """
    c = np.array([w / 2.0, h / 2.0])
    d = np.asarray(target, float) - c
    n = float(np.hypot(*d))
    if n == 0.0 or not np.isfinite(n):
        return c, np.array([1.0, 0.0])
    d = d / n
    ts = []
    if abs(d[0]) > 1e-12:
        ts.append(((w / 2.0 - inset) / abs(d[0])))
    if abs(d[1]) > 1e-12:
        ts.append(((h / 2.0 - inset) / abs(d[1])))
    t = min(ts) if ts else 0.0
    return c + t * d, d


def _arrow(tip: np.ndarray, d: np.ndarray, length: float, colour: str, width: float) -> str:
    """An arrow whose head is at ``tip`` pointing along ``d``."""
    tail = tip - d * length
    head = length * 0.35
    nrm = np.array([-d[1], d[0]])
    p1 = tip - d * head + nrm * head * 0.5
    p2 = tip - d * head - nrm * head * 0.5
    return (
        f'<line x1="{_f(tail[0])}" y1="{_f(tail[1])}" x2="{_f(tip[0])}" y2="{_f(tip[1])}" '
        f'stroke="{colour}" stroke-width="{_f(width)}"/>'
        f'<polygon points="{_f(tip[0])},{_f(tip[1])} {_f(p1[0])},{_f(p1[1])} {_f(p2[0])},{_f(p2[1])}" '
        f'fill="{colour}"/>'
    )


def _points_attr(P: np.ndarray, *, integer: bool) -> str:
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


def _int_rows_joined(V: np.ndarray, prefixes: list[str], suffixes: list[str]) -> str:
    """``prefix + "x,y x,y ..." + suffix`` for each row of whole numbers ``V`` (n, 2k), concatenated.

    Exactly what ``"%d,%d "`` would write, but the numbers come from lookup
    tables and the whole block is one ``join`` (a 200-conic panel has 10 000
    numbers: one ``%d`` each costs several times more).
    """
    n, m = V.shape
    if n == 0:
        return ""
    if m == 0 or V.min() < _INT_LO or V.max() >= _INT_HI:
        tpl = ("%d,%d " * (m // 2))[:-1]
        return "".join(p + tpl % tuple(r) + q for p, r, q in zip(prefixes, V.tolist(), suffixes))
    comma, space, bare = _int_tables()
    J = V - _INT_LO
    out = np.empty((n, m + 2), dtype=object)
    out[:, 0] = prefixes
    out[:, 1:m:2] = comma[J[:, 0::2]]
    out[:, 2:m:2] = space[J[:, 1:-1:2]]
    out[:, m] = bare[J[:, -1]]
    out[:, m + 1] = suffixes
    return "".join(out.ravel().tolist())


#: ``rint(x * 10**dp)`` in ``[_FIX_LO, _FIX_HI)`` is written from a lookup table (``"%.{dp}f"``).
_FIX_LO, _FIX_HI = -32768, 65536
_FIX_TABLES: dict[int, np.ndarray] = {}


def _fixed_strs(X: Any, dp: int) -> np.ndarray:
    """``"%.{dp}f" % x`` for every entry of ``X``, as an object array of the same shape.

    The decimal rounding is done once in numpy: where ``x * 10**dp`` is not
    within 1e-6 of a tie (so its correct rounding is certainly ``rint``) the
    string comes from a table; the few others (ties, ``-0.0``, out of the table
    range, non-finite) are formatted by ``%`` itself, so the text is identical.
    """
    X = np.asarray(X, float)
    table = _FIX_TABLES.get(dp)
    if table is None:
        sc = 10**dp
        strs = []
        for r in range(_FIX_LO, _FIX_HI):
            a = abs(r)
            t = f"{a // sc}.{a % sc:0{dp}d}"
            strs.append("-" + t if r < 0 else t)
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
    _fixed_strs(np.zeros(1), 1)


def _finite_runs(P: np.ndarray) -> list[np.ndarray]:
    """Split a polyline at NaN rows into runs of at least two points."""
    P = np.asarray(P, float)
    if P.ndim != 2 or len(P) == 0:
        return []
    ok = np.all(np.isfinite(P), axis=1)
    if ok.all():
        return [P] if len(P) >= 2 else []
    edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(np.int8), 0]))
    return [P[a:b] for a, b in zip(edges[::2], edges[1::2]) if b - a >= 2]


def _conics_svg(conics: Any, selected_point: int | None, lw: float, s: float) -> str:
    """The ``epipolar-conic`` polylines of a panel, in index order, formatted in bulk.

    An arc with NaN vertices is split into its finite runs. Past
    ``CONIC_VERTEX_BUDGET`` vertices only every k-th sample is kept (and each
    run's last). On a large image (whole pixels) all runs are rounded in one
    numpy pass and written as one stream of table strings.
    """
    idx = [i for i, arcs in enumerate(conics) for piece in arcs if len(piece) >= 2]
    runs = [piece for arcs in conics for piece in arcs if len(piece) >= 2]
    if not runs:
        return ""
    V = np.concatenate(runs).astype(float, copy=False)
    if not np.isfinite(V).all():  # rare: split the arcs with NaN vertices into their finite runs
        pairs = [(i, run) for i, piece in zip(idx, runs) for run in _finite_runs(piece)]
        if not pairs:
            return ""
        idx, runs = [i for i, _ in pairs], [r for _, r in pairs]
        V = np.concatenate(runs)
    lengths = np.array([len(r) for r in runs])
    stride = max(1, math.ceil(int(lengths.sum()) / CONIC_VERTEX_BUDGET))
    if stride > 1:
        # Keep every stride-th sample of each run, and its last.
        ends = np.cumsum(lengths)
        local = np.arange(len(V)) - np.repeat(ends - lengths, lengths)
        keep = (local % stride == 0) | (local == np.repeat(lengths - 1, lengths))
        V = V[keep]
        lengths = np.add.reduceat(keep, ends - lengths)
    thick = f' stroke-width="{_f(lw * 3.0)}"'
    prefixes = [f'<polyline data-kind="epipolar-conic" data-index="{i}" points="' for i in idx]
    suffixes = [f'" stroke="{_COLOURS[i % _N_COLOURS]}"{thick if i == selected_point else ""}/>' for i in idx]
    Q = np.rint(V).astype(np.int64) if s >= 200 else None
    if Q is None or Q.min() < _INT_LO or Q.max() >= _INT_HI:
        ends = np.cumsum(lengths)
        return "".join(p + _points_attr(V[e - k:e], integer=Q is not None) + q
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
def _line_tags(idx_bytes: bytes, selected_point: int | None, thick: str) -> np.ndarray:
    """The text around the four coordinates of each ``epipolar-line`` (the same from one drag step to the next)."""
    idx = np.frombuffer(idx_bytes, dtype=np.intp).tolist()
    tags = np.empty((len(idx), 5), dtype=object)
    tags[:, 0] = [f'<line data-kind="epipolar-line" data-index="{i}" x1="' for i in idx]
    tags[:, 1] = '" y1="'
    tags[:, 2] = '" x2="'
    tags[:, 3] = '" y2="'
    tags[:, 4] = [f'" stroke="{_COLOURS[i % _N_COLOURS]}"{thick if i == selected_point else ""}/>' for i in idx]
    tags.setflags(write=False)
    return tags


@lru_cache(maxsize=64)
def axes_svg(w: float, h: float, font: float, lw: float) -> str:
    """Pixel axes with ticks and labels: u along the top edge, v along the left edge (origin top-left)."""
    step = _nice_step(max(w, h))
    tick = font * 0.5
    ticks: list[str] = []
    u = 0.0
    while u <= w + 1e-9:
        ticks.append(f'<line x1="{_f(u)}" y1="0" x2="{_f(u)}" y2="{_f(-tick)}" stroke="#333" stroke-width="{_f(lw)}"/>')
        ticks.append(
            f'<text x="{_f(u)}" y="{_f(-tick * 1.4)}" font-size="{_f(font * 0.8)}" text-anchor="middle" '
            f'fill="#333">{u:g}</text>'
        )
        u += step
    v = 0.0
    while v <= h + 1e-9:
        ticks.append(f'<line x1="0" y1="{_f(v)}" x2="{_f(-tick)}" y2="{_f(v)}" stroke="#333" stroke-width="{_f(lw)}"/>')
        ticks.append(
            f'<text x="{_f(-tick * 1.4)}" y="{_f(v + font * 0.3)}" font-size="{_f(font * 0.8)}" text-anchor="end" '
            f'fill="#333">{v:g}</text>'
        )
        v += step
    return (
        f'<g data-kind="axes">{"".join(ticks)}'
        f'<text x="{_f(w + tick)}" y="{_f(-tick * 1.4)}" font-size="{_f(font)}" font-style="italic">u</text>'
        f'<text x="{_f(-tick * 1.4)}" y="{_f(h + font * 1.2)}" font-size="{_f(font)}" font-style="italic" '
        f'text-anchor="end">v</text></g>'
    )


def _points_group(P: np.ndarray, in_image: np.ndarray, selected_point: int | None, highlighted: frozenset,
                  show_labels: bool, c: str, r_pt: float, lw: float, font: float) -> str:
    """The ``point`` group of a panel; reused while its pixels and marks are unchanged (the other camera's
    panel during a camera drag)."""
    P = np.ascontiguousarray(P, dtype=np.float64)
    in_image = np.ascontiguousarray(in_image, dtype=bool)
    return _points_group_of(P.tobytes(), in_image.tobytes(), selected_point, frozenset(highlighted), show_labels,
                            c, r_pt, lw, font)


def numbered_points(n_in_image: int, show_labels: bool) -> bool:
    """Whether every point in the image gets its number (else only the selected and highlighted ones)."""
    return show_labels and n_in_image <= MAX_NUMBERED_POINTS


@lru_cache(maxsize=16)
def _points_group_of(P_bytes: bytes, in_image_bytes: bytes, selected_point: int | None, highlighted: frozenset,
                     show_labels: bool, c: str, r_pt: float, lw: float, font: float) -> str:
    """Numbered points are ``<g data-kind="point">`` (a disc and its number); the others a bare disc.

    A bare ``<circle>`` per point keeps a 200-point panel at a third of the DOM
    elements: the browser parses and lays out every panel on every update.
    """
    P = np.frombuffer(P_bytes).reshape(-1, 2)
    in_image = np.frombuffer(in_image_bytes, dtype=bool)
    idx = np.flatnonzero(in_image).tolist()
    Q = P[in_image]
    dp = int(c[2:-1])
    disc = f'" r="{_f(r_pt)}" fill="'
    body = ""
    if idx:
        # Bare discs for all, in one table: index, cx, cy, colour.
        table = np.empty((len(idx), 7), dtype=object)
        table[:, 0] = [f'<circle data-kind="point" data-index="{i}" cx="' for i in idx]
        table[:, 1:4:2] = _fixed_strs(Q, dp)
        table[:, 2] = '" cy="'
        table[:, 4] = disc
        table[:, 5] = [_COLOURS[i % _N_COLOURS] for i in idx]
        table[:, 6] = '"/>'
        rows = table.sum(axis=1).tolist()
        number_all = numbered_points(len(idx), show_labels)
        marked = {i for i in idx if i == selected_point or i in highlighted}
        dl = r_pt * 1.4
        sw = _f(lw * 3)
        for k, (i, (x, y)) in enumerate(zip(idx, Q.tolist())):
            if not (number_all or i in marked):
                continue
            col = _COLOURS[i % _N_COLOURS]
            ring = ""
            if i in marked:
                ring = (f'<circle cx="{c % x}" cy="{c % y}" r="{_f(r_pt * 2.2)}" fill="none" stroke="#000" '
                        f'stroke-width="{_f(lw * 2)}" data-selected="{"true" if i == selected_point else "false"}"/>')
            label = ""
            if show_labels:
                label = (f'<text x="{c % (x + dl)}" y="{c % (y - dl)}" fill="{col}" stroke="#fff" '
                         f'stroke-width="{sw}">{i + 1}</text>')
            rows[k] = (f'<g data-kind="point" data-index="{i}">{ring}<circle cx="{c % x}" cy="{c % y}{disc}{col}"/>'
                       f"{label}</g>")
        body = "".join(rows)
    return (
        f'<g stroke="#000" stroke-width="{_f(lw * 0.6)}" font-size="{_f(font)}" font-weight="bold" '
        f'paint-order="stroke">{body}</g>'
    )


def empty_svg(camera: str, width: int = 640, height: int = 480, message: str = "") -> str:
    """A blank image plane with a border and a message (before the first update)."""
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" data-egtviz="image-plane" data-camera="{escape(camera)}" '
        f'viewBox="0 0 {width} {height}" width="100%">'
        f'<rect data-kind="border" x="0" y="0" width="{width}" height="{height}" fill="#fff" stroke="#333"/>'
        f'<text data-kind="message" x="{width / 2}" y="{height / 2}" text-anchor="middle">{escape(message)}</text>'
        "</svg>"
    )


def image_plane_svg(
    plane: Any,
    *,
    selected_point: int | None = None,
    highlighted: frozenset[int] | set[int] = frozenset(),
    show_labels: bool = True,
    revision: int | None = None,
    max_height: str | None = None,
) -> str:
    """Inline SVG of one camera's image plane, in pixel units.

    Args:
        plane: an :class:`egtviz.scene.ImagePlane` (read: ``camera``, ``kind``,
            ``width``, ``height``, ``points``, ``in_image``, ``n_hidden``,
            ``epipoles``, ``lines``, ``conics``, ``rim``, ``message``).
        selected_point: 0-based index of the selected scene point: drawn with a
            ring, its epipolar line/conic thicker.
        highlighted: 0-based indices of highlighted points (a ring too).
        show_labels: write the point numbers (1-based) next to the points.
        max_height: a CSS ``max-height`` for the SVG (it keeps its aspect ratio).
        revision: written as ``data-rev`` on the root (lets a browser test or
            the benchmark recognise a given update).

    Returns:
        The ``<svg>`` element as a string (see the module docstring for the
        ``data-*`` attributes).
    """
    w, h = float(plane.width), float(plane.height)
    s = max(w, h)
    font = s / 32.0
    margin = font * 3.2
    r_pt = s / 110.0
    lw = s / 400.0
    n_inf_total = sum(1 for ep in (plane.epipoles or ()) if ep.at_infinity or ep.xy is None)
    in_image = np.asarray(plane.in_image, bool).reshape(-1)
    numbering_note = show_labels and not numbered_points(int(in_image.sum()), True)
    bottom = margin * (0.45 + 0.55 * (n_inf_total + 1 + numbering_note))
    vb = f"{_f(-margin)} {_f(-margin)} {_f(w + 2 * margin)} {_f(h + margin + bottom)}"
    rev = "" if revision is None else f' data-rev="{int(revision)}"'
    mh = "" if max_height is None else f";max-height:{escape(max_height)}"
    out: list[str] = [
        f'<svg xmlns="http://www.w3.org/2000/svg" data-egtviz="image-plane" data-camera="{escape(str(plane.camera))}" '
        f'data-camera-kind="{escape(str(plane.kind))}"{rev} viewBox="{vb}" width="100%" '
        f'style="display:block;font-family:sans-serif;background:#f4f4f4{mh}">',
        f'<rect data-kind="border" x="0" y="0" width="{_f(w)}" height="{_f(h)}" fill="#ffffff" '
        f'stroke="#333" stroke-width="{_f(lw * 1.5)}"/>',
    ]

    out.append(axes_svg(w, h, font, lw))

    # Clip everything drawn inside the image to the image rectangle.
    clip_id = "clip-" + "".join(ch if ch.isalnum() else "_" for ch in str(plane.camera))
    clip_id += f"-{zlib.crc32(str(plane.camera).encode()):08x}"  # "a b" and "a_b" stay distinct
    out.append(f'<defs><clipPath id="{clip_id}"><rect x="0" y="0" width="{_f(w)}" height="{_f(h)}"/></clipPath></defs>')
    out.append(f'<g clip-path="url(#{clip_id})">')

    if plane.rim is not None:
        for run in _finite_runs(plane.rim):
            out.append(
                f'<polygon data-kind="rim" points="{_points_attr(run, integer=False)}" fill="none" stroke="{RIM_COLOUR}" '
                f'stroke-width="{_f(lw * 1.5)}" stroke-dasharray="{_f(lw * 6)} {_f(lw * 4)}"/>'
            )

    # Bulk formatting: one %-template per element kind (a 200-point panel in about a millisecond).
    dp = min(6, max(1, 3 - math.floor(math.log10(s))))
    c = f"%.{dp}f"
    if plane.lines is not None:
        L = np.asarray(plane.lines, float).reshape(-1, 4)
        ok = np.all(np.isfinite(L), axis=1)
        thick = f' stroke-width="{_f(lw * 3.0)}"'
        idx = np.flatnonzero(ok)
        table = np.empty((len(idx), 9), dtype=object)
        if len(idx):
            table[:, 0::2] = _line_tags(idx.tobytes(), selected_point, thick)
            table[:, 1:9:2] = _fixed_strs(L[ok], dp)
        out.append(f'<g stroke-width="{_f(lw * 1.2)}">{"".join(table.ravel().tolist())}</g>')

    if plane.conics is not None:
        out.append(f'<g fill="none" stroke-width="{_f(lw * 1.2)}">{_conics_svg(plane.conics, selected_point, lw, s)}</g>')

    P = np.asarray(plane.points, float).reshape(-1, 2)
    out.append(_points_group(P, in_image, selected_point, frozenset(highlighted), show_labels, c, r_pt, lw, font))
    out.append("</g>")  # end of clipped group

    # Epipoles: inside (a cross), outside (an arrow at the border), at infinity (an arrow and a label).
    n_inf = 0
    for ep in plane.epipoles or ():
        label = escape(str(ep.label))
        if ep.at_infinity or ep.xy is None:
            d = np.asarray(ep.direction, float) if ep.direction is not None else np.array([1.0, 0.0])
            target = np.array([w / 2.0, h / 2.0]) + d * s * 10.0
            tip, dd = _border_exit(w, h, target, inset=-margin * 0.15)
            ty = h + margin * (0.85 + 0.55 * n_inf)
            n_inf += 1
            out.append(
                f'<g data-kind="epipole" data-label="{label}" data-where="infinity">'
                f"{_arrow(tip, dd, margin * 0.7, EPIPOLE_COLOUR, lw * 2.5)}"
                f'<text x="0" y="{_f(ty)}" font-size="{_f(font)}" fill="{EPIPOLE_COLOUR}">'
                f"{label} at infinity, direction ({d[0]:.2f}, {d[1]:.2f})</text></g>"
            )
            continue
        x, y = (float(c) for c in ep.xy)
        if ep.inside:
            a = r_pt * 1.8
            out.append(
                f'<g data-kind="epipole" data-label="{label}" data-where="inside">'
                f'<line x1="{_f(x - a)}" y1="{_f(y - a)}" x2="{_f(x + a)}" y2="{_f(y + a)}" stroke="{EPIPOLE_COLOUR}" '
                f'stroke-width="{_f(lw * 2.5)}"/>'
                f'<line x1="{_f(x - a)}" y1="{_f(y + a)}" x2="{_f(x + a)}" y2="{_f(y - a)}" stroke="{EPIPOLE_COLOUR}" '
                f'stroke-width="{_f(lw * 2.5)}"/>'
                f'<text x="{_f(x + a)}" y="{_f(y + a + font)}" font-size="{_f(font)}" fill="{EPIPOLE_COLOUR}" '
                f'font-style="italic" paint-order="stroke" stroke="#fff" stroke-width="{_f(lw * 3)}">{label}</text></g>'
            )
        else:
            tip, dd = _border_exit(w, h, np.array([x, y]), inset=-margin * 0.15)
            tx = min(max(tip[0] - dd[0] * margin * 0.9, font), w - font * 5)
            ty = min(max(tip[1] - dd[1] * margin * 0.9, font), h - font * 0.5)
            out.append(
                f'<g data-kind="epipole" data-label="{label}" data-where="outside" data-x="{x:.5g}" data-y="{y:.5g}">'
                f'<g data-kind="epipole-arrow">{_arrow(tip, dd, margin * 0.7, EPIPOLE_COLOUR, lw * 2.5)}</g>'
                f'<text x="{_f(tx)}" y="{_f(ty)}" font-size="{_f(font * 0.85)}" fill="{EPIPOLE_COLOUR}" '
                f'paint-order="stroke" stroke="#fff" stroke-width="{_f(lw * 3)}">'
                f"{label} ({x:.4g}, {y:.4g})</text></g>"
            )

    # Status lines under the image: hidden points and messages.
    n_points = len(P)
    n_hidden = int(plane.n_hidden)
    n_outside = int(n_points - n_hidden - int(in_image.sum()))
    status = f"{int(in_image.sum())} of {n_points} points in the image"
    if n_hidden:
        why = "behind the camera" if plane.kind == "pinhole" else "in the blind cone"
        status += f"; {n_hidden} hidden ({why})"
    if n_outside > 0:
        status += f"; {n_outside} outside the image"
    ty = h + margin * (0.85 + 0.55 * n_inf)
    out.append(
        f'<text data-kind="hidden-count" data-hidden="{n_hidden}" x="{_f(w)}" y="{_f(ty)}" text-anchor="end" '
        f'font-size="{_f(font * 0.85)}" fill="#333">{escape(status)}</text>'
    )
    if numbering_note:  # a line of its own: appended to the status it ran off the panel
        out.append(
            f'<text data-kind="numbering-note" x="{_f(w)}" y="{_f(ty + margin * 0.55)}" text-anchor="end" '
            f'font-size="{_f(font * 0.85)}" fill="#333">numbers shown for the selected point only '
            f"(more than {MAX_NUMBERED_POINTS} points)</text>"
        )
    if plane.message:
        out.append(
            f'<text data-kind="message" x="{_f(w / 2)}" y="{_f(h / 2)}" text-anchor="middle" font-size="{_f(font * 1.1)}" '
            f'fill="#a00" paint-order="stroke" stroke="#fff" stroke-width="{_f(lw * 4)}">{escape(str(plane.message))}</text>'
        )
    out.append("</svg>")
    return "".join(out)
