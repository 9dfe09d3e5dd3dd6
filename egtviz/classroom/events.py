"""What a classroom tells its listeners: small frozen values, each naming one change (read the new state from
the :class:`~egtviz.classroom.room.Classroom`)."""

from __future__ import annotations

import enum
from dataclasses import dataclass

__all__ = [
    "AnswersChanged", "CamerasLocked", "Event", "FollowChanged", "Mode", "ModeChanged", "PacingChanged",
    "PauseChanged", "RosterChanged", "SharedChanged", "SnapshotShown",
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
class SnapshotShown:
    """A student's snapshot is shown to the room under ``label``; None: none is shown."""

    label: str | None


Event = (SharedChanged | ModeChanged | CamerasLocked | PauseChanged | PacingChanged | FollowChanged
         | RosterChanged | AnswersChanged | SnapshotShown)
