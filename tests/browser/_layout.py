"""Waiting for a workbench tab's panels to be laid out as the server planned them.

A tab's panels come first at the dock's default width; once the tab has reported its canvas the server plans the
grid for the window, docks the panels and sends their widths, then sends them again once the docks are in place
(``PanelDock._width_pending``). A test that measures the panels waits for that, and for the same boxes at two
looks in a row (the dock may still be moving when the widths are right).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from _waiting import PATIENCE


def _rects(panels: Any) -> list[dict]:
    return [p["rect"] for p in (panels.values() if isinstance(panels, dict) else panels)]


def settled_panels(page: Any, view: Callable[[], Any], n: int, read: Callable[[Any], Any],
                   timeout: float = PATIENCE) -> Any:
    """``read(page)`` (the panels, a list or a dict of entries with a ``rect``) once the page shows ``n`` panels
    as wide as the grid of the tab's view (``view()``; None while there is none) planned, after its last widths
    were sent, and the same boxes as 0.3 s before.

    Raises:
        AssertionError: naming what was awaited, after ``timeout`` seconds.
    """
    deadline = time.monotonic() + timeout
    last = panels = None
    want = None
    while time.monotonic() < deadline:
        panels = read(page)
        v = view()
        grid = getattr(v, "grid", None)
        rects = _rects(panels)
        if len(rects) == n and grid is not None and v.dock._width_pending is None:
            want = grid.column_px
            if all(abs(r["width"] - want) <= 1.0 for r in rects) and rects == last:
                return panels
            last = rects
        time.sleep(0.3)
    raise AssertionError(f"waited {timeout:.0f} s for {n} panels laid out as the grid planned (columns {want} px "
                         f"wide) and still: {[r['width'] for r in _rects(panels or [])]}")


def only_view(app: Any) -> Callable[[], Any]:
    """``view`` for :func:`settled_panels`: the app's one tab's view (None unless there is exactly one)."""
    def view() -> Any:
        views = list(app.views.values())
        return views[0] if len(views) == 1 else None
    return view
