"""What a classroom tells its listeners: small frozen values, each naming one change (read the new state from
the :class:`~egtviz.classroom.room.Classroom`)."""

from __future__ import annotations

import enum
import logging
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass

__all__ = [
    "AnswersChanged", "Broadcaster", "CamerasLocked", "Event", "FollowChanged", "Mode", "ModeChanged", "NamesShown",
    "PacingChanged", "PauseChanged", "QuestionAsked", "RosterChanged", "SharedChanged", "SnapshotShown",
]


class Mode(enum.Enum):
    """What students do: follow the instructor's scene, explore their own, or do the step's tasks."""

    FOLLOW = "follow"
    EXPLORE = "explore"
    TASKS = "tasks"


@dataclass(frozen=True)
class SharedChanged:
    """The instructor published a scene (or a lesson step): :meth:`Classroom.shared` has ``version``."""

    version: int


@dataclass(frozen=True)
class ModeChanged:
    mode: Mode


@dataclass(frozen=True)
class CamerasLocked:
    """Students' view cameras were locked (True) or unlocked."""

    locked: bool


@dataclass(frozen=True)
class PauseChanged:
    """Every student's screen is paused with ``message``; None: resumed."""

    message: str | None


@dataclass(frozen=True)
class NamesShown:
    """Students' names are shown beside their answers and snapshots on the projector (True) or hidden."""

    shown: bool


@dataclass(frozen=True)
class PacingChanged:
    """The lessons and steps students may open changed (ask :meth:`Classroom.may_open`)."""


@dataclass(frozen=True)
class FollowChanged:
    """The student tab ``tab`` now follows the instructor (True) or is on its own scene."""

    tab: int
    following: bool


@dataclass(frozen=True)
class RosterChanged:
    """Someone joined, left, moved to another lesson or step, or started or stopped following."""


@dataclass(frozen=True)
class AnswersChanged:
    """An answer to ``question`` was recorded (at most a few events per second per student)."""

    question: str


@dataclass(frozen=True)
class QuestionAsked:
    """The instructor asks every student ``question``; None: no question is asked."""

    question: str | None


@dataclass(frozen=True)
class SnapshotShown:
    """A student's snapshot is shown to the room under ``label``; None: none is shown."""

    label: str | None


Event = (SharedChanged | ModeChanged | CamerasLocked | PauseChanged | PacingChanged | FollowChanged
         | RosterChanged | AnswersChanged | SnapshotShown | NamesShown | QuestionAsked)

Listener = Callable[[Event], None]
_log = logging.getLogger("egtviz.classroom")


class Broadcaster:
    """Listeners, and events sent to them outside the owner's lock (a listener may call back into the owner).

    Args:
        lock: the owner's lock, held only while the list of listeners is read or changed.
    """

    def __init__(self, lock: threading.RLock) -> None:
        self._listeners_lock = lock
        self._listeners: list[Listener] = []

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener`` with every event from now on; returns a function that unsubscribes it."""
        with self._listeners_lock:
            self._listeners.append(listener)

        def unsubscribe() -> None:
            with self._listeners_lock:
                if listener in self._listeners:
                    self._listeners.remove(listener)

        return unsubscribe

    def _emit(self, events: Iterable[Event]) -> None:
        """Send ``events`` in order to every listener; call it with the owner's lock released. A listener that
        raises is logged and the others still hear."""
        events = list(events)
        if not events:
            return
        with self._listeners_lock:
            listeners = list(self._listeners)
        for event in events:
            for listener in listeners:
                try:
                    listener(event)
                except Exception:  # one broken panel must not stop the others from hearing
                    _log.exception("egtviz classroom: a listener failed on %s", type(event).__name__)
