"""The classroom: an instructor, a room of students, follow-me, pacing, answers, snapshots and the roster.

Layer 3 of egtviz beside :mod:`egtviz.scene` and :mod:`egtviz.lessons`: headless, it never imports viser
(the viewer's classroom panels are built on it). The model is described in ``docs/classroom.md``.
"""

from .answers import Histogram as Histogram
from .events import AnswersChanged as AnswersChanged
from .events import CamerasLocked as CamerasLocked
from .events import Event as Event
from .events import FollowChanged as FollowChanged
from .events import Mode as Mode
from .events import ModeChanged as ModeChanged
from .events import NamesShown as NamesShown
from .events import PacingChanged as PacingChanged
from .events import PauseChanged as PauseChanged
from .events import QuestionAsked as QuestionAsked
from .events import RosterChanged as RosterChanged
from .events import SharedChanged as SharedChanged
from .events import SnapshotShown as SnapshotShown
from .roster import RosterRow as RosterRow
from .room import Classroom as Classroom
from .snapshots import Snapshot as Snapshot
from .state import ClassState as ClassState
from .state import SharedState as SharedState
from .text import ClassroomError as ClassroomError
from .tokens import RedactingFilter as RedactingFilter
from .tokens import TokenGuard as TokenGuard
from .tokens import redact as redact
from .tokens import redact_url as redact_url

__all__ = [
    "AnswersChanged", "CamerasLocked", "ClassState", "Classroom", "ClassroomError", "Event", "FollowChanged",
    "Histogram", "Mode", "ModeChanged", "NamesShown", "PacingChanged", "PauseChanged", "QuestionAsked",
    "RedactingFilter", "RosterChanged", "RosterRow", "SharedChanged", "SharedState", "Snapshot", "SnapshotShown",
    "TokenGuard", "redact", "redact_url",
]
