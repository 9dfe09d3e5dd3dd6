"""The server's budget of servo-run frames: every tab's demo together keeps at most a fixed number for playback.

A demo keeps each frame of its run (poses, features and the derived geometry it plays back) in the one process
every tab shares, so a few long runs in a few tabs would use the server's memory for all. Before a run is
simulated, its tab reserves ``steps + 1`` frames (the most the run can have) from :data:`SERVER_BUDGET`; when the
run is drawn the reservation shrinks to the frames the run has (most runs converge long before their *max
steps*); it is released when the run fails, when the tab's next run replaces it and when the demo closes (or its
player is garbage). A run that does not fit waits in a queue for up to :data:`QUEUE_SECONDS` (the other runs
shrink or end) and is then refused with :class:`ServoBusy`, whose message says how many other runs hold the
budget.
"""

from __future__ import annotations

import threading
import time
import weakref
from collections.abc import Callable

from ..scene.limits import SERVO_SERVER_FRAMES

__all__ = ["QUEUE_SECONDS", "SERVER_BUDGET", "ServoBudget", "ServoBusy"]

QUEUE_SECONDS = 30.0
"""How long a run that does not fit waits for the frames of other runs before it is refused."""
_POLL_SECONDS = 0.25
"""How often a waiting run looks whether it was cancelled (its tab closed) or an owner was garbage."""


class ServoBusy(RuntimeError):
    """A run that does not fit in the budget (its message is for the tab that asked)."""


class ServoBudget:
    """Frames held per owner (a demo's tab), at most ``frames`` in all. Thread-safe.

    Args:
        frames: the budget (:data:`~egtviz.scene.limits.SERVO_SERVER_FRAMES` by default).
        queue_seconds: how long :meth:`reserve` waits for frames before it refuses (:data:`QUEUE_SECONDS`).
    """

    def __init__(self, frames: int = SERVO_SERVER_FRAMES, *, queue_seconds: float = QUEUE_SECONDS) -> None:
        self.frames = int(frames)
        self.queue_seconds = float(queue_seconds)
        self._cond = threading.Condition()
        self._held: weakref.WeakKeyDictionary[object, int] = weakref.WeakKeyDictionary()

    def _busy(self, owner: object, frames: int) -> str | None:
        """Why ``frames`` more for ``owner`` do not fit now (None: they do). Call holding the condition."""
        others = [n for o, n in self._held.items() if o is not owner and n > 0]
        used = sum(others)
        if used + frames <= self.frames:
            return None
        runs = len(others)
        return (f"The server is busy with {runs} other servo run{'s' if runs != 1 else ''} ({used:,} of its "
                f"{self.frames:,} frames); this run needs up to {frames:,}")

    def reserve(self, owner: object, frames: int, *, cancelled: Callable[[], bool] | None = None,
                waiting: Callable[[str], None] | None = None) -> None:
        """Hold ``frames`` for ``owner`` in place of what it held (its run is replaced), waiting up to
        :attr:`queue_seconds` for them.

        Args:
            cancelled: stop waiting (and refuse) when it returns True.
            waiting: called once, outside the lock, with the reason when the run has to wait.

        Raises:
            ServoBusy: the frames did not come free in time (or the wait was cancelled); nothing changes.
        """
        frames = int(frames)
        deadline = time.monotonic() + self.queue_seconds
        told = False
        while True:
            with self._cond:
                reason = self._busy(owner, frames)
                if reason is None:
                    self._held[owner] = frames
                    return
                left = deadline - time.monotonic()
                if left <= 0 or frames > self.frames or (cancelled is not None and cancelled()):
                    raise ServoBusy(f"{reason}. Try again in a moment, or with fewer max steps.")
                if told or waiting is None:
                    self._cond.wait(min(left, _POLL_SECONDS))
                    continue
            told = True
            waiting(f"{reason}; it waits up to {self.queue_seconds:g} s for them.")

    def shrink(self, owner: object, frames: int) -> None:
        """Lower ``owner``'s hold to ``frames`` (never raises it)."""
        with self._cond:
            if owner in self._held:
                self._held[owner] = min(self._held[owner], int(frames))
                self._cond.notify_all()

    def release(self, owner: object) -> None:
        """Free what ``owner`` holds (nothing if it holds nothing)."""
        with self._cond:
            self._held.pop(owner, None)
            self._cond.notify_all()

    def held(self, owner: object | None = None) -> int:
        """Frames ``owner`` holds; None: all owners together."""
        with self._cond:
            if owner is None:
                return sum(self._held.values())
            return self._held.get(owner, 0)


SERVER_BUDGET = ServoBudget()
"""The budget every demo of this process (the server's tabs) shares."""
