"""Where an image-plane panel looks, and where its labels go: view boxes, fit, zoom, pan, ticks, label placement.

Pure layout on pixel coordinates that the scene layer computed (no geometry,
no viser). A :class:`ViewBox` is the rectangle of the image plane a panel
shows; the panel's axes frame is that rectangle.

How the GUI uses it (one ``ViewBox`` per panel, kept by the app, ``None`` =
the image rectangle)::

    view = fit_view(plane)                 # "fit": all content, as MATLAB's automatic axes
    view = zoom(view, 1.25)                # "zoom in" (zoom(view, 1 / 1.25): "zoom out")
    view = pan(view, 0.1, 0.0)             # "pan right" by a tenth of the view's width
    view = image_view(plane)               # "image": back to the image rectangle
    svg = image_plane_svg(plane, view=view, style=PRESENT, panel_px=620)

A view keeps its aspect ratio through ``zoom`` and ``pan``; ``fit_view``
gives the image's aspect ratio, so the panel keeps its size on screen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from ...scene.derived import ImagePlane

__all__ = [
    "FIT_MARGIN",
    "FIT_MAX_EXTENT",
    "STEADY_FILL",
    "STEADY_SLACK",
    "ViewBox",
    "aspect_box",
    "fit_view",
    "fit_with_content",
    "image_view",
    "pan",
    "place_labels",
    "steady_fit",
    "tick_values",
    "zoom",
]

#: Fraction of the content's span added on each side by :func:`fit_view`.
FIT_MARGIN = 0.06

#: During a drag a fitted panel keeps its view while the fit still fills this fraction of its width, and a new
#: view is the fit with this fraction of its size added on each side (:func:`steady_fit`).
STEADY_FILL = 0.7
STEADY_SLACK = 0.05

#: Content further than this many image sizes from the image is left out of the fit (it is shown by an arrow):
#: an epipole a million pixels away would otherwise shrink the image to a dot.
FIT_MAX_EXTENT = 20.0


@dataclass(frozen=True)
class ViewBox:
    """A rectangle of the image plane in pixels: ``u0 <= u <= u0 + width``, ``v0 <= v <= v0 + height``.

    ``v`` grows downwards, as in the image, so ``(u0, v0)`` is the top-left corner.
    """

    u0: float
    v0: float
    width: float
    height: float

    def __post_init__(self) -> None:
        values = (self.u0, self.v0, self.width, self.height)
        if not all(math.isfinite(float(x)) for x in values):
            raise ValueError(f"ViewBox: u0, v0, width, height must be finite, got {values}")
        if not (self.width > 0 and self.height > 0):
            raise ValueError(f"ViewBox: width and height must be > 0, got {self.width} x {self.height}")

    @property
    def u1(self) -> float:
        """Right edge."""
        return self.u0 + self.width

    @property
    def v1(self) -> float:
        """Bottom edge."""
        return self.v0 + self.height

    @property
    def centre(self) -> tuple[float, float]:
        """``(u, v)`` of the centre."""
        return self.u0 + self.width / 2.0, self.v0 + self.height / 2.0

    def contains(self, uv: npt.ArrayLike) -> np.ndarray:
        """``(N,)`` mask of the rows of ``uv`` (N, 2) inside the box (edges included; NaN rows are outside)."""
        P = np.asarray(uv, float).reshape(-1, 2)
        with np.errstate(invalid="ignore"):
            return ((P[:, 0] >= self.u0) & (P[:, 0] <= self.u1) & (P[:, 1] >= self.v0) & (P[:, 1] <= self.v1))


def image_view(plane: ImagePlane) -> ViewBox:
    """The image rectangle ``[0, width] x [0, height]`` of an ``ImagePlane``."""
    return ViewBox(0.0, 0.0, float(plane.width), float(plane.height))


def _content(plane: ImagePlane) -> np.ndarray:
    """Every finite pixel a panel draws: image corners, points, finite epipoles, rim, horizon and conic samples."""
    w, h = float(plane.width), float(plane.height)
    parts = [np.array([[0.0, 0.0], [w, h]])]
    parts.append(np.asarray(plane.points, float).reshape(-1, 2))
    for ep in plane.epipoles or ():
        if ep.xy is not None and not ep.at_infinity:
            parts.append(np.asarray(ep.xy, float).reshape(1, 2))
    if plane.rim is not None:
        parts.append(np.asarray(plane.rim, float).reshape(-1, 2))
    for arcs in plane.conics or ():
        parts.extend(np.asarray(a, float).reshape(-1, 2) for a in arcs)
    parts.extend(np.asarray(a, float).reshape(-1, 2) for a in plane.horizon)
    P = np.concatenate(parts)
    P = P[np.all(np.isfinite(P), axis=1)]
    # Leave out what lies absurdly far from the image (see FIT_MAX_EXTENT).
    reach = FIT_MAX_EXTENT * max(w, h)
    near = (P[:, 0] > -reach) & (P[:, 0] < w + reach) & (P[:, 1] > -reach) & (P[:, 1] < h + reach)
    return P[near]


def fit_view(plane: ImagePlane, *, margin: float = FIT_MARGIN) -> ViewBox:
    """The smallest view with the image's aspect ratio that shows all the panel's content, plus a margin.

    Content: the image rectangle, every visible point (also outside the
    image), every finite epipole, the mirror rim, the horizon and the epipolar conics'
    samples (not further than ``FIT_MAX_EXTENT`` image sizes from the image).
    With ``[a, b]`` the content's range along an axis and ``m`` the margin,
    the range shown is ``[a - m (b - a), b + m (b - a)]``, then the shorter
    side is widened about its centre until ``width / height`` is the image's.

    Args:
        plane: an :class:`egtviz.scene.ImagePlane`.
        margin: fraction of the span added on each side (>= 0).

    Returns:
        The fitted :class:`ViewBox`.
    """
    if not margin >= 0:
        raise ValueError(f"margin must be >= 0, got {margin}")
    return _fit_box(_content(plane), float(plane.width) / float(plane.height), margin)


def fit_with_content(plane: ImagePlane) -> tuple[ViewBox, ViewBox]:
    """``(fit_view(plane), fit_view(plane, margin=0))``: the fitted view and the content's own box, in one pass."""
    P = _content(plane)
    aspect = float(plane.width) / float(plane.height)
    return _fit_box(P, aspect, FIT_MARGIN), _fit_box(P, aspect, 0.0)


def _fit_box(P: np.ndarray, aspect: float, margin: float) -> ViewBox:
    """:func:`fit_view` of the content pixels ``P`` (n, 2) for an image of aspect ``aspect``."""
    lo, hi = P.min(axis=0), P.max(axis=0)
    span = hi - lo
    return aspect_box(lo - margin * span, hi + margin * span, aspect)


def aspect_box(lo: np.ndarray, hi: np.ndarray, aspect: float) -> ViewBox:
    """The box ``[lo, hi]`` (corners (2,)) with its shorter side widened about its centre until
    ``width / height == aspect``."""
    w, h = hi - lo
    if w / h < aspect:
        w = h * aspect
    else:
        h = w / aspect
    cu, cv = (lo + hi) / 2.0
    return ViewBox(float(cu - w / 2.0), float(cv - h / 2.0), float(w), float(h))


def steady_fit(fitted: ViewBox, kept: ViewBox | None, *, content: ViewBox | None = None,
               fill: float = STEADY_FILL, slack: float = STEADY_SLACK) -> ViewBox:
    """The view a fitted panel shows during a drag: ``kept`` while it still does the fit's job, else a new one.

    ``kept`` (the view of the drag's previous step) stays as long as it
    contains ``content`` (the content's own box, default ``fitted``) and that
    box is at least ``fill`` of its width (the content has not shrunk to a
    corner). Otherwise the view becomes ``fitted`` grown by ``slack`` of its
    size on each side, so that the next steps' small moves stay inside it. The
    axes then hold still while the points move, and the panel's layout is not
    made again at every step. Without ``kept`` (no drag) the fit is exact.
    """
    if kept is None:
        return fitted
    box = fitted if content is None else content
    inside = box.u0 >= kept.u0 and box.v0 >= kept.v0 and box.u1 <= kept.u1 and box.v1 <= kept.v1
    if inside and box.width >= fill * kept.width:
        return kept
    return ViewBox(fitted.u0 - slack * fitted.width, fitted.v0 - slack * fitted.height,
                   (1.0 + 2.0 * slack) * fitted.width, (1.0 + 2.0 * slack) * fitted.height)


def zoom(view: ViewBox, factor: float, about: tuple[float, float] | None = None) -> ViewBox:
    """The view magnified by ``factor`` (> 1 zooms in) about the pixel ``about`` (default: the view's centre).

    The pixel ``about`` stays where it is on screen: ``u' = c + (u - c) / factor``.
    """
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"factor must be a finite number > 0, got {factor}")
    cu, cv = view.centre if about is None else (float(about[0]), float(about[1]))
    return ViewBox(cu + (view.u0 - cu) / factor, cv + (view.v0 - cv) / factor,
                   view.width / factor, view.height / factor)


def pan(view: ViewBox, du: float, dv: float) -> ViewBox:
    """The view moved by ``du`` of its width to the right and ``dv`` of its height down (fractions, any sign)."""
    return ViewBox(view.u0 + du * view.width, view.v0 + dv * view.height, view.width, view.height)


def tick_values(lo: float, hi: float, px_per_unit: float, min_gap_px: float) -> tuple[np.ndarray, int]:
    """Ticks on ``[lo, hi]`` at the smallest 1-2-5 step at least ``min_gap_px`` apart on screen.

    Args:
        lo, hi: the axis range (pixels of the image).
        px_per_unit: CSS pixels per image pixel on screen.
        min_gap_px: the least distance between two ticks on screen (room for a label).

    Returns:
        ``(values, decimals)``: the tick values, and the number of decimals
        that writes the step exactly (``0.5`` -> 1, ``20`` -> 0).
    """
    raw = min_gap_px / px_per_unit
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1.0, 2.0, 5.0, 10.0) if m * mag >= raw * (1 - 1e-9))
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    values = np.arange(first, last + 1) * step
    decimals = max(0, -math.floor(math.log10(step) + 1e-9))
    return values, decimals


#: Label positions tried around a mark, in order (EGT writes numbers to the upper right):
#: unit offsets (dx, dy) of the label's box from the mark, v downwards.
_DIRECTIONS = ((1, -1), (1, 0), (1, 1), (-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1))
#: Distances of the candidate rings, in units of (mark radius + gap).
PLACEMENT_RINGS = (1.0, 2.0, 3.5)


def place_labels(anchors: npt.ArrayLike, radii: npt.ArrayLike, sizes: npt.ArrayLike, obstacles: npt.ArrayLike,
                 bounds: tuple[float, float, float, float], gap: float, placed: npt.ArrayLike = ()) -> np.ndarray:
    """Greedy, deterministic label placement: each label next to its mark, clear of marks and earlier labels.

    Label ``i`` (in the given order, most important first) tries boxes of
    size ``sizes[i]`` touching the square of half-side ``radii[i] + gap``
    around ``anchors[i]``, on eight sides (upper right first), then the same
    eight at 2 and 3.5 times the distance. The cost of a box is its area overlapping
    the ``obstacles`` and the labels already placed, plus its area outside
    ``bounds``; the first box of least cost wins.

    Args:
        anchors: (n, 2) mark centres.
        radii: (n,) half-size of each mark.
        sizes: (n, 2) label widths and heights.
        obstacles: (m, 4) boxes ``(x0, y0, x1, y1)`` to keep clear (the marks, arrows).
        bounds: ``(x0, y0, x1, y1)`` the labels should stay inside.
        gap: space between a mark and its label.
        placed: (p, 4) boxes of labels placed before these (by an earlier call with the same obstacles): the
            result is then the last n rows of one call for all p + n labels.

    Returns:
        (n, 4) the chosen label boxes ``(x0, y0, x1, y1)``.
    """
    A = np.asarray(anchors, float).reshape(-1, 2)
    R = np.asarray(radii, float).reshape(-1)
    S = np.asarray(sizes, float).reshape(-1, 2)
    O = np.asarray(obstacles, float).reshape(-1, 4)
    n = len(A)
    if n == 0:
        return np.empty((0, 4))
    # Each label walks its candidates in plain Python among the obstacles near it (_near_obstacles), stops adding
    # up a candidate's cost once it cannot beat the best so far (costs only grow), and stops at the first free box.
    near_boxes, reach_x, reach_y = _near_obstacles(A, R, S, O, gap)
    box_bounds = tuple(float(b) for b in bounds)
    earlier: list[tuple[float, float, float, float]] = [tuple(b) for b in np.asarray(placed, float).reshape(-1, 4).tolist()]
    boxes = earlier[:]
    for (ax, ay), r, (w, h), others, rx, ry in zip(A.tolist(), R.tolist(), S.tolist(), near_boxes,
                                                  reach_x.tolist(), reach_y.tolist()):
        lo_x, hi_x, lo_y, hi_y = ax - rx, ax + rx, ay - ry, ay + ry
        # The obstacles, then the earlier labels, in the order given: the same sums as over all of them.
        near_placed = [o for o in boxes if o[0] <= hi_x and o[2] >= lo_x and o[1] <= hi_y and o[3] >= lo_y]
        if isinstance(others, np.ndarray):  # many obstacles near (an epipole among 200 points): kept in numpy
            if near_placed:
                others = np.concatenate([others, np.array(near_placed, float)])
            box = _best_box_many(ax, ay, r + gap, w, h, others, box_bounds)
        else:
            box = _best_box(ax, ay, r + gap, w, h, others + near_placed, box_bounds)
        if box is None:  # every cost compared false: a NaN anchor, radius or size
            raise ValueError(f"place_labels: label {len(boxes) - len(earlier)} has no finite box")
        boxes.append(box)
    return np.array(boxes[len(earlier):])


def _near_obstacles(A: np.ndarray, R: np.ndarray, S: np.ndarray, O: np.ndarray, gap: float
                    ) -> tuple[list[list[list[float]]], np.ndarray, np.ndarray]:
    """Per label, the obstacles that can cost any of its candidates something, and how far its candidates reach.

    A candidate box lies within (r + gap) * the last ring plus the label's width (height) of its anchor along x
    (y): only obstacles reaching into that rectangle can cost it anything. One numpy pass finds them.

    Returns:
        ``(near_boxes, reach_x, reach_y)``: per label the near obstacles as lists ``[x0, y0, x1, y1]`` in the
        given order (above ``_MANY_BOXES`` of them, as an (m, 4) array), and the reach of its candidates along x
        and y.
    """
    reach = (R + gap)[:, None] * PLACEMENT_RINGS[-1] + S  # (n, 2): along x, along y
    if not len(O):
        return [[] for _ in range(len(A))], reach[:, 0], reach[:, 1]
    # Both axes at once: an obstacle is near when it starts before the rectangle's far side and ends after its near
    # side, along x and along y.
    hi, lo = (A + reach)[:, None, :], (A - reach)[:, None, :]
    near = ((O[None, :, :2] <= hi) & (O[None, :, 2:] >= lo)).all(axis=2)
    few = [count <= _MANY_BOXES for count in near.sum(axis=1).tolist()]
    rows = O.tolist() if any(few) else []  # once: a list per label would copy the crowded rows again for each label
    # Many near ones (an epipole among 200 points): their rows stay in numpy, for _best_box_many.
    out = [[row for row, hit in zip(rows, m) if hit] if f else O[near[j]]
           for j, (m, f) in enumerate(zip(near.tolist(), few))]
    return out, reach[:, 0], reach[:, 1]


def _best_box(ax: float, ay: float, reach: float, w: float, h: float, boxes: list, bounds: tuple[float, ...]
              ) -> tuple[float, float, float, float] | None:
    """The first box of least cost among a label's candidates (see :func:`place_labels`).

    Args:
        ax, ay: the mark's centre.
        reach: the mark's half-size plus the gap (the first ring's distance).
        w, h: the label's size.
        boxes: what may overlap a candidate (the near obstacles, then the earlier labels).
        bounds: ``(x0, y0, x1, y1)`` the label should stay inside.
    """
    if len(boxes) > _MANY_BOXES:
        return _best_box_many(ax, ay, reach, w, h, boxes, bounds)
    bx0, by0, bx1, by1 = bounds
    best, best_cost = None, math.inf
    area = w * h
    tiny = 1e-6 * area  # rounding, not an overlap
    # Conditional expressions, not min()/max(): here the builtin calls cost more than the comparisons.
    for ring in PLACEMENT_RINGS:
        d = reach * ring
        # The boxes overlapping each column of candidates (a ring's candidates share three columns, left,
        # centred and right), with their overlap width, in the given order: a candidate then tests only its
        # column's boxes, and adds up the same overlaps in the same order as over all of them.
        columns: dict[int, list[tuple[float, float, float]]] = {}
        for dx, dy in _DIRECTIONS:
            # The box touches the square of half-side d around the anchor; above/below it is centred.
            x0 = ax + d if dx > 0 else ax - d - w if dx < 0 else ax - w / 2
            y0 = ay + d if dy > 0 else ay - d - h if dy < 0 else ay - h / 2
            x1, y1 = x0 + w, y0 + h
            column = columns.get(dx)
            if column is None:
                column = columns[dx] = [
                    (ow, o[1], o[3]) for o in boxes
                    if (ow := (x1 if x1 < o[2] else o[2]) - (x0 if x0 > o[0] else o[0])) > 0
                ]
            iw = (x1 if x1 < bx1 else bx1) - (x0 if x0 > bx0 else bx0)
            ih = (y1 if y1 < by1 else by1) - (y0 if y0 > by0 else by0)
            c = area - (iw if iw > 0.0 else 0.0) * (ih if ih > 0.0 else 0.0)
            for ow, oy0, oy1 in column:
                oh = (y1 if y1 < oy1 else oy1) - (y0 if y0 > oy0 else oy0)
                if oh > 0:
                    c += ow * oh
                    if c >= best_cost and c > tiny:
                        break  # this box cannot win
            if c <= tiny:  # take the first free box
                c = 0.0
            if c < best_cost:
                best, best_cost = (x0, y0, x1, y1), c
            if best_cost == 0.0:
                return best
    return best


#: Above this many boxes near a label, its candidates' costs are added up in numpy (an epipole among 200 points).
_MANY_BOXES = 40


def _best_box_many(ax: float, ay: float, reach: float, w: float, h: float, boxes: list, bounds: tuple[float, ...]
                   ) -> tuple[float, float, float, float] | None:
    """:func:`_best_box` for many boxes, in numpy, with the same result.

    Each candidate's cost is the same sum in the same order (``cumsum`` adds left to right; a box that does not
    overlap adds 0.0, which changes no sum); the winner is the first of least cost, as in the loop, whose early
    exits (a candidate that cannot win, the first free box) never change which box wins.
    """
    bx0, by0, bx1, by1 = bounds
    area = w * h
    tiny = 1e-6 * area
    cands = []
    for ring in PLACEMENT_RINGS:
        d = reach * ring
        for dx, dy in _DIRECTIONS:
            x0 = ax + d if dx > 0 else ax - d - w if dx < 0 else ax - w / 2
            y0 = ay + d if dy > 0 else ay - d - h if dy < 0 else ay - h / 2
            x1, y1 = x0 + w, y0 + h
            iw = (x1 if x1 < bx1 else bx1) - (x0 if x0 > bx0 else bx0)
            ih = (y1 if y1 < by1 else by1) - (y0 if y0 > by0 else by0)
            cands.append((x0, y0, x1, y1, area - (iw if iw > 0.0 else 0.0) * (ih if ih > 0.0 else 0.0)))
    C = np.array(cands)
    O = np.asarray(boxes, float).reshape(-1, 4)
    ow = np.minimum(C[:, 2, None], O[None, :, 2]) - np.maximum(C[:, 0, None], O[None, :, 0])
    oh = np.minimum(C[:, 3, None], O[None, :, 3]) - np.maximum(C[:, 1, None], O[None, :, 1])
    terms = np.where((ow > 0) & (oh > 0), ow * oh, 0.0)
    cost = np.cumsum(np.concatenate([C[:, 4:], terms], axis=1), axis=1)[:, -1]
    cost[cost <= tiny] = 0.0  # NaN stays NaN: never a winner, as in the loop
    valid = cost < math.inf
    if not valid.any():
        return None
    i = int(np.argmin(np.where(valid, cost, math.inf)))
    x0, y0, x1, y1, _ = cands[i]
    return (x0, y0, x1, y1)
