"""Gizmo input of a workbench tab: late events dropped by their timestamps, one undo step per drag.

viser runs callbacks in a thread pool, so a gizmo's events can arrive out of order: an event older than one already
applied is dropped. A drag's ``start`` opens a new drag id; every update of that drag merges into one undo step.
The pose a camera gizmo sent goes to the scene model as sent: the model's constraints (a lesson's ranges) decide
where the camera goes, once (:mod:`egtviz.scene.constraints`).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np

from ...geometry import GeometryError
from ...geometry.poses import Pose, matrix_from_quat_wxyz
from ...scene import SceneError

if TYPE_CHECKING:
    import viser

    from .tab_context import TabContext

__all__ = ["DragInput"]


def _allclose(a: np.ndarray, b: np.ndarray, atol: float) -> bool:
    """``np.allclose(a, b, atol=atol)`` (rtol 1e-5) without its per-call overhead (runs on every drag event)."""
    return bool((np.abs(a - b) <= atol + 1e-5 * np.abs(b)).all())


def _unmoved(current: Pose, allowed: Pose) -> bool:
    """Whether a gizmo's pose, as the model allows it, is where the camera is (the gizmo resends it rounded)."""
    return _allclose(current.t, allowed.t, 1e-9) and _allclose(current.R, allowed.R, 1e-9)


def _position(target: viser.TransformControlsHandle, who: str) -> np.ndarray:
    position = np.asarray(target.position, float)
    if position.shape != (3,) or not np.isfinite(position).all():
        raise SceneError(f"{who}: the gizmo sent a position that is not 3 finite numbers")
    return position


class DragInput:
    """The tab's camera and point gizmo events.

    Args:
        tab: the tab's services (its lock, model and render are used).
    """

    def __init__(self, tab: TabContext) -> None:
        self.tab = tab
        #: The camera being dragged while its update is drawn (its 3D nodes take the fast path).
        self.moving: str | None = None
        #: Whether the update being drawn is a step of a gizmo drag (fitted panels then keep a steady view).
        self.step = False
        self._stamp: dict[str, float] = {}
        self._seq: dict[str, int] = {}

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
                self._seq[name] = self._seq.get(name, 0) + 1  # one drag = one undo step
                return
            tab.event_started(t0, c0)
            self.moving = name if phase == "update" else None
            self.step = phase == "update"
            try:
                self._move_camera(name, event.target, phase)
            finally:
                self.moving = None
                self.step = False

    def _move_camera(self, name: str, target: viser.TransformControlsHandle, phase: str) -> None:
        model = self.tab.model
        if name not in model.scene.camera_names:
            return
        if name in model.scene.locked:  # a lesson's lock: the drag is undone when it ends
            if phase == "end":
                raise SceneError(f"{name} is locked: its gizmo cannot move it now")
            return
        try:
            R = matrix_from_quat_wxyz(target.wxyz)
        except GeometryError as exc:
            raise SceneError(f"{name}: the gizmo sent an orientation that is not a rotation ({exc})") from exc
        # The model applies its ranges to whatever the browser sent: the pose may stop short of the pointer.
        moved = model.set_camera_pose(name, tuple(_position(target, name)), R, drag_id=self._seq.get(name),
                                      unmoved=_unmoved)
        if not moved and phase == "end":  # put the gizmo (perhaps past a range's stop) and the fields on the camera
            self.tab.redraw_now()

    def point_event(self, index: int, event: viser.TransformControlsEvent) -> None:
        """A point gizmo moved; its drag's start selects the point."""
        tab = self.tab
        t0, c0 = time.perf_counter(), time.thread_time()
        with tab.lock:
            key = f"point:{index}"
            if tab.is_closed() or not self._fresh(key, event.target):
                return
            tab.event_started(t0, c0)
            model = tab.model
            scene = model.scene
            phase = getattr(event, "phase", "update")
            if phase == "start":
                self._seq[key] = self._seq.get(key, 0) + 1  # one drag = one undo step
                if scene.selected_point != index and index < len(scene.points):
                    model.select_point(index)
                return
            if index < len(scene.points):
                position = _position(event.target, f"point {index + 1}")
                self.step = phase == "update"
                try:
                    model.set_point(index, tuple(position), drag_id=self._seq.get(key))
                finally:
                    self.step = False
