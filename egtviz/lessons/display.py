"""What a lesson step lets the image-plane panels show, so that they stay readable.

A step may write, next to its ``text``:

* ``max_lines = 20``: at most this many epipolar lines per panel (chosen evenly over the points, the same ones at
  every redraw; the selected point's line is always among them);
* ``labels = "none" | "selected" | "all"``: which point numbers the panels write (``selected``: the selected point's
  and the points the step highlights, however few points there are; the rings an instrument such as the
  estimation lab adds are drawn without numbers);
* ``view = { cam2 = { u = [-100, 740], v = [-60, 540] }, pano = "fit" }``: per camera, the part of the image plane
  its panel shows when the step opens (a box in pixels, ``"fit"`` to follow the content at every update, or
  ``"image"``); the view buttons still move it afterwards.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from .fields import EntryError

__all__ = ["LABELS", "MAX_LINES", "PanelDisplay", "parse_display", "thin_lines"]

LabelMode = Literal["none", "selected", "all"]
LABELS: tuple[str, ...] = ("none", "selected", "all")
#: Largest ``max_lines`` a step may ask for.
MAX_LINES = 10_000
#: Largest ``|u|`` or ``|v|`` of a fixed view, pixels.
MAX_VIEW_PX = 1e6
KEYS = ("max_lines", "labels", "view")


@dataclass(frozen=True)
class PanelDisplay:
    """A step's say over the panels; the defaults leave them as the workbench draws them."""

    max_lines: int | None = None
    """At most this many epipolar lines per panel (None: all)."""
    labels: LabelMode = "all"
    """Which point numbers the panels write."""
    views: tuple[tuple[str, Any], ...] = field(default=())
    """Per camera name, ``"fit"``, ``"image"`` or ``(u0, u1, v0, v1)`` in pixels."""

    def view_of(self, camera: str) -> Any:
        """``camera``'s view in this step (None: the panel keeps its own)."""
        return dict(self.views).get(camera)


def _range(value: object, what: str) -> tuple[float, float]:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)):
        raise EntryError("view", f"{what}: expected [low, high] in pixels, got {value!r:.60}")
    lo, hi = float(value[0]), float(value[1])
    if not (math.isfinite(lo) and math.isfinite(hi) and -MAX_VIEW_PX <= lo < hi <= MAX_VIEW_PX):
        raise EntryError("view", f"{what}: expected low < high within +-{MAX_VIEW_PX:g} px, got [{lo:g}, {hi:g}]")
    return lo, hi


def _view(camera: str, value: object) -> Any:
    what = f"view.{camera}"
    if value in ("fit", "image"):
        return value
    if not isinstance(value, dict) or set(value) != {"u", "v"}:
        raise EntryError("view", f'{what}: expected "fit", "image" or {{ u = [low, high], v = [low, high] }}')
    return (*_range(value["u"], f"{what}.u"), *_range(value["v"], f"{what}.v"))


def parse_display(data: dict[str, Any], cameras: frozenset[str]) -> PanelDisplay:
    """A step's ``max_lines``, ``labels`` and ``view`` keys (absent keys keep the defaults).

    Raises:
        EntryError: a value of the wrong type or out of range, or a view of a camera the scene does not have.
    """
    max_lines = data.get("max_lines")
    if max_lines is not None and (isinstance(max_lines, bool) or not isinstance(max_lines, int)
                                  or not 1 <= max_lines <= MAX_LINES):
        raise EntryError("max_lines", f"expected a whole number from 1 to {MAX_LINES}, got {max_lines!r:.40}")
    labels = data.get("labels", "all")
    if labels not in LABELS:
        raise EntryError("labels", f"expected one of {', '.join(LABELS)}, got {labels!r:.40}")
    views = data.get("view", {})
    if not isinstance(views, dict):
        raise EntryError("view", "expected a table of cameras, e.g. { cam2 = { u = [0, 640], v = [0, 480] } }")
    unknown = sorted(set(views) - cameras)
    if unknown:
        raise EntryError("view", f"no camera {unknown[0]!r:.40} in the scene (cameras: {', '.join(sorted(cameras))})")
    return PanelDisplay(max_lines, labels, tuple((c, _view(c, v)) for c, v in views.items()))


def thin_lines(plane: Any, max_lines: int | None, selected: int | None) -> Any:
    """``plane`` with at most ``max_lines`` epipolar lines: evenly spaced over the points that have one, the
    selected point's always kept; the others become NaN rows, so each line keeps its point's colour."""
    lines = plane.lines
    if max_lines is None or lines is None:
        return plane
    L = np.asarray(lines, float)
    have = np.flatnonzero(np.all(np.isfinite(L.reshape(len(L), -1)), axis=1))
    if len(have) <= max_lines:
        return plane
    keep = set(have[np.linspace(0, len(have) - 1, max_lines).round().astype(int)].tolist())
    if selected is not None and selected in set(have.tolist()) and selected not in keep:
        keep.discard(max(keep - {int(have[0])}, default=int(have[0])))
        keep.add(selected)
    drop = np.setdiff1d(np.arange(len(L)), sorted(keep))
    L = L.copy()
    L[drop] = np.nan
    changes: dict[str, Any] = {"lines": L}
    if plane.line_coefficients is not None:
        C = np.asarray(plane.line_coefficients, float).copy()
        C[drop[drop < len(C)]] = np.nan
        changes["line_coefficients"] = C
    return dataclasses.replace(plane, **changes)
