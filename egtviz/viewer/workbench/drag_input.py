"""Gizmo input of a workbench tab: late events dropped by their timestamps, each drag handed to the controller.

viser runs callbacks in a thread pool, so a gizmo's events can arrive out of order: an event older than one already
applied is dropped. A drag's ``start`` asks the tab's controller for a new drag id; every step of that drag carries
it, so the drag is one undo step. What a pose does to the scene is the controller's
(:meth:`~egtviz.controllers.workbench.WorkbenchController.drag_camera`, ``drag_point``).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import viser

    from .tab_context import TabContext

__all__ = ["DragInput"]


class DragInput:
    """The tab's camera and point gizmo events.

    Args:
        tab: the tab's services (its lock, controller and render are used).
    """

    def __init__(self, tab: TabContext) -> None:
        self.tab = tab
        #: The camera being dragged while its update is drawn (its 3D nodes take the fast path).
        self.moving: str | None = None
        #: Whether the update being drawn is a step of a gizmo drag (fitted panels then keep a steady view).
        self.step = False
        self._stamp: dict[str, float] = {}
        #: The drag id of each gizmo's current drag (a camera's name, ``point:i``).
        self._drag: dict[str, int] = {}

    def _fresh(self, key: str, target: viser.TransformControlsHandle) -> bool:
        """Whether this event is not older than one already applied (and remember its stamp)."""
        stamp = float(getattr(target, "update_timestamp", 0.0))
        if stamp < self._stamp.get(key, -1.0):
            return False
        self._stamp[key] = stamp
        return True

    def camera_event(self, name: str, event: viser.TransformControlsEvent) -> None:
        """A camera gizmo moved (``phase``: start, update or end of a drag)."""
        tab = self.tab
        t0, c0 = time.perf_counter(), time.thread_time()
        with tab.lock:
            if tab.is_closed() or not self._fresh(name, event.target):
                return
            phase = getattr(event, "phase", "update")
            if phase == "start":
                self._drag[name] = tab.controller.start_drag()  # one drag = one undo step
                return
            tab.event_started(t0, c0)
            self.moving = name if phase == "update" else None
            self.step = phase == "update"
            try:
                last = phase == "end"
                target = event.target
                moved = tab.controller.drag_camera(name, target.position, target.wxyz, self._drag.get(name),
                                                   last=last)
                if last and not moved and name in tab.controller.scene.camera_names:
                    tab.redraw_now()  # put the gizmo (perhaps past a range's stop) and the fields on the camera
            finally:
                self.moving = None
                self.step = False

    def point_event(self, index: int, event: viser.TransformControlsEvent) -> None:
        """A point gizmo moved; its drag's start selects the point."""
        tab = self.tab
        t0, c0 = time.perf_counter(), time.thread_time()
        with tab.lock:
            key = f"point:{index}"
            if tab.is_closed() or not self._fresh(key, event.target):
                return
            tab.event_started(t0, c0)
            phase = getattr(event, "phase", "update")
            if phase == "start":
                self._drag[key] = tab.controller.start_point_drag(index)  # one drag = one undo step
                return
            self.step = phase == "update"
            try:
                tab.controller.drag_point(index, event.target.position, self._drag.get(key))
            finally:
                self.step = False
