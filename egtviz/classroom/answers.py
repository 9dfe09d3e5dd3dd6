"""Students' answers to the instructor's questions and their histogram (no names in it).

The latest answer of each student counts. Recording one is O(1) (a dictionary entry replaced), so a student
who floods answers costs no one else more than that; their events are thinned to a few per second.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np

from .text import ClassroomError, plain_text

__all__ = ["MAX_QUESTIONS", "AnswerBook", "Histogram", "answer_value"]

MAX_QUESTIONS = 64
"""Questions remembered (the one asked longest ago is forgotten first)."""
MAX_QUESTION_LENGTH = 120
MAX_TEXT_ANSWER = 80
MAX_BINS = 100
EVENT_INTERVAL_S = 0.2
"""At most one :class:`~egtviz.classroom.events.AnswersChanged` per student per this many seconds."""


@dataclass(frozen=True)
class Histogram:
    """The answers to one question, counted: numbers in bins, texts by category. It holds no names."""

    question: str
    edges: tuple[float, ...]
    """Bin edges of the numeric answers (``len(counts) + 1`` values); empty when there are none."""
    counts: tuple[int, ...]
    """Numeric answers per bin (a bin holds ``edges[i] <= x < edges[i+1]``, the last one its right edge too)."""
    categories: tuple[tuple[str, int], ...]
    """Text answers as ``(text, count)``, most frequent first (then alphabetical); texts are compared after
    case folding and shown folded."""
    n: int
    """Students who answered."""
    version: int
    """Grows with every answer recorded to this question (a panel that polls redraws when it changes)."""


def answer_value(value: Any) -> float | str:
    """A student's answer as kept: a finite float, or text (:func:`plain_text`, folded for counting).

    Raises:
        ClassroomError: not a finite number or text of at most :data:`MAX_TEXT_ANSWER` characters.
    """
    if isinstance(value, str):
        return plain_text(value, "answer", MAX_TEXT_ANSWER).casefold()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ClassroomError(f"answer: expected a number or text, got {type(value).__name__}")
    number = float(value)
    if not math.isfinite(number):
        raise ClassroomError(f"answer: expected a finite number, got {number}")
    return number


class _Question:
    __slots__ = ("answers", "version")

    def __init__(self) -> None:
        self.answers: dict[str, float | str] = {}
        self.version = 0


class AnswerBook:
    """Answers by question and student key. Not thread-safe: the classroom calls it under its lock."""

    def __init__(self) -> None:
        self._questions: OrderedDict[str, _Question] = OrderedDict()
        self._last_event: dict[str, float] = {}

    def record(self, student: str, question: str, value: Any, now: float) -> tuple[str, bool]:
        """Keep ``value`` as ``student``'s answer to ``question``; returns the question as kept and whether an
        event is due (False while the student's last event is younger than :data:`EVENT_INTERVAL_S`).

        Raises:
            ClassroomError: a question or answer that cannot be kept.
        """
        question = plain_text(question, "question", MAX_QUESTION_LENGTH)
        kept = answer_value(value)
        entry = self._questions.get(question)
        if entry is None:
            entry = self._questions[question] = _Question()
            while len(self._questions) > MAX_QUESTIONS:
                self._questions.popitem(last=False)
        entry.answers[student] = kept
        entry.version += 1
        last = self._last_event.get(student)
        due = last is None or now - last >= EVENT_INTERVAL_S
        if due:
            self._last_event[student] = now
        return question, due

    def has_answered(self, student: str) -> bool:
        """Whether ``student`` answered any question kept."""
        return any(student in q.answers for q in self._questions.values())

    def answers(self, question: str) -> dict[str, float | str]:
        """A copy of the answers to ``question`` by student key (empty if none)."""
        entry = self._questions.get(question)
        return dict(entry.answers) if entry is not None else {}

    def questions(self) -> list[str]:
        """The questions asked, oldest first."""
        return list(self._questions)

    def histogram(self, question: str, bins: int = 10) -> Histogram:
        """The answers to ``question`` counted (see :class:`Histogram`).

        Raises:
            ClassroomError: ``bins`` not a whole number 1 to :data:`MAX_BINS`.
        """
        if isinstance(bins, bool) or not isinstance(bins, int) or not 1 <= bins <= MAX_BINS:
            raise ClassroomError(f"bins: expected a whole number 1 to {MAX_BINS}, got {bins!r}")
        entry = self._questions.get(question)
        values = list(entry.answers.values()) if entry is not None else []
        version = entry.version if entry is not None else 0
        return histogram_of(question, values, bins, version)

    def to_dict(self) -> dict[str, Any]:
        return {q: {"version": e.version, "answers": dict(e.answers)} for q, e in self._questions.items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> AnswerBook:
        book = cls()
        for question, entry in list(data.items())[-MAX_QUESTIONS:]:
            q = book._questions[plain_text(question, "question", MAX_QUESTION_LENGTH)] = _Question()
            q.version = int(entry["version"])
            q.answers = {str(k): answer_value(v) for k, v in entry["answers"].items()}
        return book


def histogram_of(question: str, values: list[float | str], bins: int, version: int) -> Histogram:
    """The :class:`Histogram` of ``values`` (finite floats and folded texts)."""
    numbers = np.array([v for v in values if isinstance(v, float)], dtype=np.float64)
    texts: dict[str, int] = {}
    for v in values:
        if isinstance(v, str):
            texts[v] = texts.get(v, 0) + 1
    categories = tuple(sorted(texts.items(), key=lambda kv: (-kv[1], kv[0])))
    if numbers.size == 0:
        return Histogram(question, (), (), categories, len(values), version)
    low, high = float(numbers.min()), float(numbers.max())
    if low == high:  # one value: a bin of width 1 centred on it (wider where 0.5 is below the float spacing)
        half = max(0.5, abs(low) * 1e-9)
        low, high = low - half, high + half
    counts, edges = np.histogram(numbers, bins=bins, range=(low, high))
    return Histogram(question, tuple(float(e) for e in edges), tuple(int(c) for c in counts), categories,
                     len(values), version)
