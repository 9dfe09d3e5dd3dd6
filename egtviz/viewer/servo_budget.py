"""The server's budget of servo-run frames: every tab's demo together keeps at most a fixed number for playback.

A demo keeps each frame of its run (poses, features and the derived geometry it plays back) in the one process
every tab shares, so a few long runs in a few tabs would use the server's memory for all. Before a run starts,
its tab reserves ``steps + 1`` frames (the most the run can have) from :data:`SERVER_BUDGET`; when the run is
drawn the reservation shrinks to the frames the run has (most runs converge long before their *max steps*);
it is released when the run fails, when the tab's next run replaces it and when the demo closes (or its player
is garbage). A run that does not fit is refused with :class:`ServoBusy`, whose message says how many other runs
hold the budget.
"""

from __future__ import annotations

import threading
import weakref
from typing import Any

from egtviz.scene.limits import SERVO_SERVER_FRAMES

__all__ = ["SERVER_BUDGET", "ServoBudget", "ServoBusy", "notify_busy"]


class ServoBusy(RuntimeError):
    """A run that does not fit in the budget (its message is for the tab that asked)."""


class ServoBudget:
    """Frames held per owner (a demo's player), at most ``frames`` in all. Thread-safe.

    Args:
        frames: the budget (:data:`~egtviz.scene.limits.SERVO_SERVER_FRAMES` by default).
    """

    def __init__(self, frames: int = SERVO_SERVER_FRAMES) -> None:
        self.frames = int(frames)
        self._lock = threading.Lock()
        self._held: weakref.WeakKeyDictionary[Any, int] = weakref.WeakKeyDictionary()

    def reserve(self, owner: Any, frames: int) -> None:
        """Hold ``frames`` for ``owner``, in place of what it held (its run is replaced).

        Raises:
            ServoBusy: the other owners hold too much for ``frames`` more; nothing changes.
        """
        frames = int(frames)
        with self._lock:
            others = {o: n for o, n in self._held.items() if o is not owner and n > 0}
            used = sum(others.values())
            if used + frames > self.frames:
                runs = len(others)
                raise ServoBusy(
                    f"The server is busy with {runs} other servo run{'s' if runs != 1 else ''} "
                    f"({used:,} of its {self.frames:,} frames); this run needs up to {frames:,}. "
                    "Try again in a moment, or with fewer max steps.")
            self._held[owner] = frames

    def shrink(self, owner: Any, frames: int) -> None:
        """Lower ``owner``'s hold to ``frames`` (never raises it)."""
        with self._lock:
            if owner in self._held:
                self._held[owner] = min(self._held[owner], int(frames))

    def release(self, owner: Any) -> None:
        """Free what ``owner`` holds (nothing if it holds nothing)."""
        with self._lock:
            self._held.pop(owner, None)

    def held(self, owner: Any | None = None) -> int:
        """Frames ``owner`` holds; None: all owners together."""
        with self._lock:
            if owner is None:
                return sum(self._held.values())
            return self._held.get(owner, 0)


SERVER_BUDGET = ServoBudget()
"""The budget every demo of this process (the server's tabs) shares."""


def notify_busy(client: Any, exc: ServoBusy) -> None:
    """Tell ``client``'s tab its run was refused (a yellow notification); a tab already gone is left alone."""
    try:
        client.add_notification("Server busy", str(exc), color="yellow", auto_close_seconds=8.0)
    except Exception:  # noqa: BLE001 - the client may be gone
        pass
