"""Locked cameras: while the class locks them, every follower's view camera is where the instructor's is, and a
follower who turns their view is put back."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .follow_view import FollowView

__all__ = ["CameraLock"]

#: A follower's camera this far (scene units) from the instructor's is put back.
SNAP_TOLERANCE = 1e-3


class CameraLock:
    """The instructor's view camera, and the followers held at it while :attr:`room` locks cameras.

    Args:
        room: the classroom (its ``cameras_locked``).
        followers: the followers' views now, by tab.
    """

    def __init__(self, room: Any, followers: Callable[[], dict[int, FollowView]]) -> None:
        self.room = room
        self._followers = followers
        #: The instructor's view camera: ``(position, look_at, up)``; None until their tab reports one.
        self.pose: tuple | None = None

    def instructor_moved(self, camera: Any) -> None:
        """The instructor's tab reported its view camera."""
        try:
            pose = (tuple(camera.position), tuple(camera.look_at), tuple(camera.up_direction))
        except (AssertionError, AttributeError):
            return
        self.pose = pose
        if self.room.cameras_locked:
            self.hold_all()

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
