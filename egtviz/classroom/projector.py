"""What the projector shows: the question asked, the answers' histogram (no names), anonymised snapshots of
students' scenes, and whether names are shown. A part of :class:`~egtviz.classroom.room.Classroom`."""

from __future__ import annotations

from .answers import MAX_QUESTION_LENGTH, Histogram
from .core import RoomCore
from .events import AnswersChanged, NamesShown, QuestionAsked, SnapshotShown
from .snapshots import Snapshot, anonymise, label_for
from .text import ClassroomError, plain_text

__all__ = ["ProjectorControls"]


class ProjectorControls(RoomCore):
    """The instructor's question, students' answers, snapshots and the names flag."""

    def ask(self, question: str | None) -> None:
        """Ask every student ``question`` (plain text); None: no question is asked."""
        if question is not None:
            question = plain_text(question, "question", MAX_QUESTION_LENGTH)
        with self._lock:
            if self._state.question == question:
                return
            self._state.question = question
        self._emit([QuestionAsked(question)])

    def asked(self) -> str | None:
        """The question asked now, None if none."""
        with self._lock:
            return self._state.question

    def record_answer(self, tab: int, question: str, value: float | str) -> None:
        """The student on ``tab`` answers ``question`` (their latest answer counts); O(1).

        Raises:
            ClassroomError: no student on ``tab``, or a question or answer that cannot be kept.
        """
        now = self._clock()
        with self._lock:
            t = self._student_tab(tab)
            question, due = self._state.answers.record(t.name or "", question, value, now)
        if due:
            self._emit([AnswersChanged(question)])

    def histogram(self, question: str, bins: int = 10) -> Histogram:
        """The answers to ``question`` counted; no names."""
        with self._lock:
            return self._state.answers.histogram(question, bins)

    def questions(self) -> list[str]:
        with self._lock:
            return self._state.answers.questions()

    def snapshot(self, tab: int) -> Snapshot:
        """An anonymised copy of the own scene of the student on ``tab``, labelled ``Student A``, ...

        Raises:
            ClassroomError: no student on ``tab``, or they have no scene of their own yet.
        """
        with self._lock:
            s = self._state
            name = self._student_tab(tab).name or ""
            scene = s.scenes.get(name)
            if scene is None:
                raise ClassroomError(f"tab {tab}: that student has no scene of their own yet")
            label = s.labels.get(name)
            if label is None:
                label = s.labels[name] = label_for(len(s.labels))
            s.snapshots_taken += 1
            number = s.snapshots_taken
        return Snapshot(label, anonymise(scene, name, label), number)

    def show_snapshot(self, snapshot: Snapshot | None) -> None:
        """Show ``snapshot`` to the room beside each student's own scene; None: show none."""
        if snapshot is not None and not isinstance(snapshot, Snapshot):
            raise ClassroomError(f"snapshot: expected a Snapshot, got {type(snapshot).__name__}")
        with self._lock:
            if self._state.shown is snapshot:
                return
            self._state.shown = snapshot
        self._emit([SnapshotShown(None if snapshot is None else snapshot.label)])

    def shown_snapshot(self) -> Snapshot | None:
        with self._lock:
            return self._state.shown

    def show_names(self, shown: bool) -> None:
        """Show students' names on the projector (True) or hide them (the default)."""
        shown = bool(shown)
        with self._lock:
            if self._state.names_shown == shown:
                return
            self._state.names_shown = shown
        self._emit([NamesShown(shown)])

    def names_shown(self) -> bool:
        with self._lock:
            return self._state.names_shown

    def answers(self, question: str) -> dict[str, float | str]:
        """Each student's latest answer to ``question`` by name (for the instructor's eyes and the CSV)."""
        with self._lock:
            return self._state.answers.answers(question)
