"""The instructor's roster: who is in the class, where each is in the course, what each has passed; and its CSV.

Progress comes from the same :class:`~egtviz.lessons.progress.ProgressStore` the course keeps, so the roster
agrees with what each student's lesson panel shows. Names are data everywhere: the CSV writes a cell a
spreadsheet would read as a formula with a leading ``'`` (:func:`egtviz.lessons.records.safe_cell`).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from ..lessons.catalog import load
from ..lessons.errors import LessonError
from ..lessons.progress import ProgressStore
from ..lessons.records import safe_cell

__all__ = ["ROSTER_HEADER", "RosterRow", "StudentPlace", "build_roster", "roster_csv", "shipped_task_count"]

ROSTER_HEADER = ("name", "connected", "following", "lesson", "step", "tasks passed", "tasks in lesson")
"""The CSV's first columns (``step`` counts from 1, as the lesson panel shows it); one ``answer: <question>``
column per question follows."""


@dataclass(frozen=True)
class RosterRow:
    """One student of the class."""

    name: str
    connected: bool
    """Whether a tab of theirs is open."""
    following: bool
    """Whether a tab of theirs follows the instructor."""
    lesson: str | None
    """The lesson their tab is on (else the one they last moved in); None if none."""
    step: int | None
    """Their step in :attr:`lesson` (0-based)."""
    tasks_passed: int
    """Tasks of :attr:`lesson` they have passed (from the progress database)."""
    tasks_total: int
    """Tasks in :attr:`lesson` (0 when the lesson is unknown)."""


@dataclass(frozen=True)
class StudentPlace:
    """A student's live state, read under the classroom's lock (the database is read after it is released)."""

    name: str
    connected: bool
    following: bool
    lesson: str | None
    step: int | None


_TASK_COUNTS: dict[str, int] = {}


def shipped_task_count(lesson: str) -> int:
    """Tasks in the shipped lesson ``lesson``; 0 if there is no such lesson (not remembered, so a lesson that
    appears later is counted then)."""
    count = _TASK_COUNTS.get(lesson)
    if count is None:
        try:
            count = load(lesson).task_count
        except LessonError:
            return 0
        if len(_TASK_COUNTS) < 256:
            _TASK_COUNTS[lesson] = count
    return count


def build_roster(places: Iterable[StudentPlace], progress: ProgressStore | None,
                 task_count: Callable[[str], int]) -> list[RosterRow]:
    """One row per student, sorted by name (case folded)."""
    rows = []
    for p in places:
        lesson, step, passed = p.lesson, p.step, 0
        if progress is not None:
            if lesson is None:
                lesson, step = _last_lesson(progress, p.name)
            if lesson is not None:
                passed = len(progress.passed_tasks(p.name, lesson))
                if step is None:
                    step = progress.current_step(p.name, lesson)
        total = task_count(lesson) if lesson is not None else 0
        rows.append(RosterRow(p.name, p.connected, p.following, lesson, step, passed, total))
    return sorted(rows, key=lambda r: (r.name.casefold(), r.name))


def _last_lesson(progress: ProgressStore, name: str) -> tuple[str | None, int | None]:
    """The last lesson (in course order) ``name`` has progress in, and their step there."""
    lessons = progress.lessons_of(name)
    if not lessons:
        return None, None
    last = max(lessons)
    return last, lessons[last].step


def roster_csv(rows: Iterable[RosterRow], answers: Mapping[str, Mapping[str, float | str]] | None = None) -> str:
    """The roster as CSV text (``\\r\\n`` line ends); ``answers`` maps a question to each student's answer."""
    answers = answers or {}
    questions = list(answers)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    writer.writerow(ROSTER_HEADER + tuple(safe_cell(f"answer: {q}") for q in questions))
    for r in rows:
        cells: list[object] = [safe_cell(r.name), "yes" if r.connected else "no", "yes" if r.following else "no",
                               safe_cell(r.lesson or ""), "" if r.step is None else r.step + 1, r.tasks_passed,
                               r.tasks_total]
        for q in questions:
            value = answers[q].get(r.name, "")
            cells.append(safe_cell(value) if isinstance(value, str) else repr(value))
        writer.writerow(cells)
    return out.getvalue()
