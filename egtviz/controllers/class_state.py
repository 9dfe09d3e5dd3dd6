"""What the class members' tabs draw, as frozen values: a student's bar (:class:`StudentState`) and the instructor's
panel (:class:`PanelState`: the room's status, the roster, the answers to the question asked, the pacing).

Every name, question and message here is plain text; the viewer turns these values into HTML (escaping each) and
reads nothing else of the class to draw them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from ..classroom import Histogram, Mode, RosterRow

__all__ = [
    "AnswersView", "PacedLesson", "PacingView", "PanelState", "RosterLine", "RoomStatus", "StudentState",
    "answers_view", "number_text", "pacing_view", "roster_lines",
]


@dataclass(frozen=True)
class StudentState:
    """What a student's bar shows."""

    name: str
    """The student's name ("" before they joined)."""
    following: bool
    """The tab shows the instructor's scene."""
    question: str | None
    """The question asked of the room (None: none)."""
    paused: str | None
    """The instructor's pause message (None: not paused)."""


@dataclass(frozen=True)
class RoomStatus:
    """The instructor's summary of the room."""

    connected: int
    """Students with a tab open."""
    following: int
    """Of them, those following."""
    mode: Mode
    paused: str | None
    """The pause message (None: not paused)."""


@dataclass(frozen=True)
class RosterLine:
    """One student of the roster as the panel says it."""

    name: str
    tasks: str
    """Tasks passed of the lesson's, ``"3/12"`` (``"3"``: a lesson without tasks, or none)."""
    state: str
    """``"following"``, ``"own scene"`` or ``"away"``."""
    where: str
    """The state and, if known, the lesson (``"lesson 6"``, or its name) and step from 1."""
    connected: bool


@dataclass(frozen=True)
class AnswersView:
    """The answers to the question asked: the bars of its histogram, and each student's answer if names are shown."""

    question: str
    n: int
    """How many students answered."""
    bars: tuple[tuple[str, int], ...]
    """``(label, count)``: the numbers' bins (``"100 to 110"``), then the texts' categories."""
    by_name: tuple[tuple[str, str], ...]
    """``(name, answer)`` by name, case folded (empty: names hidden)."""


@dataclass(frozen=True)
class PacedLesson:
    """How far students may go in one paced lesson."""

    lesson: str
    up_to: int
    """The last step open, counted from 1."""
    of: int | None
    """How many steps the lesson has (None: not a lesson of the course)."""


@dataclass(frozen=True)
class PacingView:
    """The pacing as the panel says it."""

    allowed: tuple[str, ...] | None
    """The lessons students may open, sorted (None: every lesson)."""
    paced: tuple[PacedLesson, ...]
    """The paced lessons, by name."""


@dataclass(frozen=True)
class PanelState:
    """What the instructor's panel shows, and the state of its checkboxes."""

    status: RoomStatus
    follow_me: bool
    cameras_locked: bool
    names_shown: bool
    roster: tuple[RosterLine, ...]
    answers: AnswersView | None
    """None: no question asked."""
    pacing: PacingView


def number_text(x: float) -> str:
    """A number of the answers as the panel writes it (four significant digits)."""
    return f"{x:.4g}"


def _where(row: RosterRow, numbers: Mapping[str, int]) -> tuple[str, str]:
    """Where a roster row's student is: following, on their own scene, or away; and the lesson and step."""
    state = "away" if not row.connected else "following" if row.following else "own scene"
    if row.lesson is None:
        return state, ""
    lesson = f"lesson {numbers[row.lesson]}" if row.lesson in numbers else row.lesson
    return state, lesson if row.step is None else f"{lesson} · step {row.step + 1}"


def roster_lines(rows: Sequence[RosterRow], numbers: Mapping[str, int] | None = None) -> tuple[RosterLine, ...]:
    """The roster's :class:`egtviz.classroom.RosterRow` as the panel says them; ``numbers`` gives each lesson's
    number in the course (the lesson is said as "lesson 6"; a lesson not in it by its name)."""
    numbers = numbers or {}
    lines = []
    for r in rows:
        state, lesson = _where(r, numbers)
        tasks = f"{r.tasks_passed}/{r.tasks_total}" if r.tasks_total else str(r.tasks_passed)
        lines.append(RosterLine(r.name, tasks, state, f"{state} · {lesson}" if lesson else state, r.connected))
    return tuple(lines)


def answers_view(hist: Histogram, names: Mapping[str, float | str] | None = None) -> AnswersView:
    """The bars of a :class:`egtviz.classroom.Histogram` (no names in them); ``names`` (each student's answer)
    adds them by name, for the instructor's eyes only."""
    bars = [(f"{number_text(hist.edges[i])} to {number_text(hist.edges[i + 1])}", count)
            for i, count in enumerate(hist.counts)]
    bars += [(text, count) for text, count in hist.categories]
    by_name = tuple((n, v if isinstance(v, str) else number_text(v))
                    for n, v in sorted((names or {}).items(), key=lambda kv: kv[0].casefold()))
    return AnswersView(hist.question, hist.n, tuple(bars), by_name)


def pacing_view(allowed: frozenset[str] | None, paced: Mapping[str, int], steps: Mapping[str, int]) -> PacingView:
    """The class's pacing (:meth:`egtviz.classroom.Classroom.pacing`, steps from 0) with each lesson's number of
    ``steps``: the lessons open, and the last step open of each paced one, from 1."""
    lessons = tuple(PacedLesson(name, last + 1, steps.get(name) or None) for name, last in sorted(paced.items()))
    return PacingView(None if allowed is None else tuple(sorted(allowed)), lessons)
