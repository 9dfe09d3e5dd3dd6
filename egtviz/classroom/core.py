"""What every part of a classroom shares: the one lock, the class's state, the clock and the listeners."""

from __future__ import annotations

import threading
from collections.abc import Callable

from .events import Broadcaster
from .state import ClassState, TabState
from .text import ClassroomError, tab_id

__all__ = ["RoomCore"]


class RoomCore(Broadcaster):
    """The lock that guards :class:`~egtviz.classroom.state.ClassState`, and the listeners told of its changes.

    Args:
        state: the class (a new, empty one if None).
        clock: monotonic seconds, for the rate limits.
    """

    def __init__(self, state: ClassState | None, clock: Callable[[], float]) -> None:
        self._lock = threading.RLock()
        super().__init__(self._lock)
        self._state = state if state is not None else ClassState()
        self._clock = clock

    def _student_tab(self, tab: int) -> TabState:
        """The student tab ``tab`` (call with the lock held).

        Raises:
            ClassroomError: no student has joined on it.
        """
        t = self._state.tabs.get(tab_id(tab))
        if t is None or t.instructor:
            raise ClassroomError(f"tab {tab}: no student has joined on it")
        return t
