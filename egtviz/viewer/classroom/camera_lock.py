"""Locked cameras: while the class locks them, every follower's view camera is where the instructor's is, and a
follower who turns their view is put back; every camera of a released student's own scene is locked by its scene
model (:mod:`.scene_lock`), and the student's tab is told why."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import viser

from ...classroom import Classroom
from ..workbench.fields import notify_error
from .follow_view import FollowView
from .scene_lock import LOCKED_TITLE, SceneLocks

if TYPE_CHECKING:
    from ..workbench.app import ClientView

__all__ = ["CameraLock"]

#: A follower's camera this far (scene units) from the instructor's is put back.
SNAP_TOLERANCE = 1e-3
_LOCKED_BODY = "You can look around, but no camera of your scene can move until the instructor unlocks them."
_UNLOCKED_TITLE = "The instructor has unlocked the cameras"


def _tell(client: viser.ClientHandle, locked: bool) -> None:
    """Say in ``client``'s tab that the class locked (or unlocked) the cameras; a tab gone is left alone."""
    try:
        if locked:
            client.add_notification(LOCKED_TITLE, _LOCKED_BODY, color="yellow", auto_close_seconds=8.0)
        else:
            client.add_notification(_UNLOCKED_TITLE, "", color="blue", auto_close_seconds=4.0)
    except Exception:  # noqa: BLE001 - the client may be gone
        pass


class CameraLock:
    """The instructor's view camera, and the followers held at it while :attr:`room` locks cameras.

    Args:
        room: the classroom (its ``cameras_locked``).
        followers: the followers' views now, by tab.
        released: the tabs' roles and this process's views now, by tab: a student's view that is not a follower's
            shows their own scene or a lesson's.
    """

    def __init__(self, room: Classroom, followers: Callable[[], dict[int, FollowView]],
                 released: Callable[[], tuple[dict[int, str], dict[int, ClientView]]] = lambda: ({}, {})) -> None:
        self.room = room
        self._followers = followers
        self._released = released
        #: The released students' scene models, locked by the class with it.
        self.scenes = SceneLocks(lambda: bool(self.room.cameras_locked))
        #: The instructor's view camera: ``(position, look_at, up)``; None until their tab reports one.
        self.pose: tuple | None = None

    def instructor_moved(self, camera: viser.CameraHandle) -> None:
        """The instructor's tab reported its view camera."""
        try:
            pose = (tuple(camera.position), tuple(camera.look_at), tuple(camera.up_direction))
        except (AssertionError, AttributeError):
            return
        self.pose = pose
        if self.room.cameras_locked:
            self.hold_all()

    def class_changed(self) -> None:
        """The class locked (or unlocked) the cameras: followers' view cameras and released students' scenes, as
        the class is now (two quick changes applied out of order still end where the class is)."""
        locked = bool(self.room.cameras_locked)
        if locked:
            self.hold_all()
        self.scenes.set_locked(locked)
        roles, views = self._released()
        followers = self._followers()
        for cid, view in views.items():
            if roles.get(cid) != "student" or cid in followers:
                continue
            try:
                self.scenes.watch(view.model)
            except Exception as exc:  # noqa: BLE001 - that tab says why; the others are still locked
                notify_error(view.client, exc)
            _tell(view.client, locked)

    def released(self, view: ClientView | None, shown: bool) -> None:
        """A released student's tab shows ``view`` (``shown``: just now; None: no view): its scene is locked while
        the class locks cameras, and a tab just shown is told so."""
        if view is None:
            return
        self.scenes.watch(view.model)
        if shown and self.room.cameras_locked:
            _tell(view.client, True)

    def hold_all(self) -> None:
        """Put every follower's camera where the instructor's is (the class just locked them)."""
        if self.pose is not None:
            for view in list(self._followers().values()):
                view.set_camera(*self.pose)

    def hold(self, view: FollowView) -> None:
        """A new follower: at the instructor's camera if cameras are locked."""
        if self.room.cameras_locked and self.pose is not None:
            view.set_camera(*self.pose)

    def follower_moved(self, cid: int) -> None:
        """A follower turned their view: back to the instructor's while cameras are locked."""
        view = self._followers().get(cid)
        pose = self.pose
        if view is None or pose is None or not self.room.cameras_locked:
            return
        try:
            now = tuple(view.client.camera.position)
        except (AssertionError, AttributeError):
            return
        if max(abs(a - b) for a, b in zip(now, pose[0])) > SNAP_TOLERANCE:
            view.set_camera(*pose)
