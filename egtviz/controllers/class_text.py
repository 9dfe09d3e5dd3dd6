"""What a class member types, read as the class means it: a student's name, their answer, and the instructor's
"up to step". Each is refused in the field's own words (:class:`ClassRefusal`), and so is whatever the class itself
refuses (:func:`as_refusal`): a tab shows every refusal as a refusal, never as "Something went wrong".

The pacing field: "up to step" is a step of the chosen lesson (counted from 1, as the lesson panel shows them) or
blank for every step; anything else is refused naming the steps the lesson has (``999`` is not taken as "every
step" without a word).
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager

from ..classroom import ClassroomError
from ..lessons import Lesson
from ..lessons.answers import AnswerError, read_number
from ..lessons.progress import LearnerNameError
from ..scene import SceneError

__all__ = [
    "FIELD", "ClassRefusal", "as_refusal", "lesson_steps", "paced_step", "refusals", "typed_answer", "typed_name",
]

#: The pacing field's label, as its refusals name it.
FIELD = "up to step"
_WHOLE = re.compile(r"[+-]?[0-9]{1,9}")


class ClassRefusal(SceneError):
    """A class member's intent that is refused (the message is for the user, in the field's words)."""


def as_refusal(exc: BaseException) -> BaseException:
    """``exc`` as the user reads it: a name the course does not take (``"your name: ..."``) and anything else the
    class refuses (a question, an answer, a full class) become a :class:`ClassRefusal` in their own words; any
    other exception, a fault of the program, is returned as it is."""
    if isinstance(exc, LearnerNameError):
        return ClassRefusal(f"your {exc}")
    if isinstance(exc, ClassroomError):
        return ClassRefusal(str(exc))
    return exc


@contextmanager
def refusals() -> Iterator[None]:
    """Whatever the class refuses in the ``with`` block is raised again as :func:`as_refusal` says it."""
    try:
        yield
    except (LearnerNameError, ClassroomError) as exc:
        raise as_refusal(exc) from exc


def typed_name(text: object) -> str:
    """The name a student typed to join, as typed (the class trims and checks it by the course's rule).

    Raises:
        ClassRefusal: nothing typed.
    """
    if not isinstance(text, str) or not text.strip():
        raise ClassRefusal("your name: type it to join the class")
    return text


def typed_answer(text: object) -> float | str:
    """An answer as typed: a plain finite decimal (``1,5`` reads as 1.5) is a number, anything else its text.

    Raises:
        ClassRefusal: nothing typed.
    """
    if not isinstance(text, str) or not text.strip():
        raise ClassRefusal("your answer: type it first")
    typed = text.strip()
    try:  # the course's strict reader, with a poll's decimal comma taken as a point
        return read_number(typed.replace(",", ".") if typed.count(",") == 1 else typed)
    except AnswerError:
        return typed


def paced_step(text: object, lesson: str, steps: int) -> int | None:
    """The last step (0-based) students may open, from the field's text; None for blank (every step).

    Args:
        text: what the instructor typed.
        lesson: the lesson's name (said in a refusal).
        steps: how many steps the lesson has.

    Raises:
        ClassRefusal: not a whole number, below 1, or beyond the lesson's last step.
    """
    typed = str(text).strip()
    if not typed:
        return None
    choose = f"type 1 to {steps}, or leave it blank for every step"
    if not _WHOLE.fullmatch(typed):
        if re.fullmatch(r"[+]?[0-9]+", typed):  # more digits than any lesson has steps
            raise ClassRefusal(f"{FIELD}: {lesson} has {steps} steps: {choose}")
        raise ClassRefusal(f"{FIELD}: expected a step number or blank, got {typed[:20]!r}")
    number = int(typed)
    if number < 1:
        raise ClassRefusal(f"{FIELD}: steps count from 1: {choose}")
    if number > steps:
        raise ClassRefusal(f"{FIELD}: {lesson} has {steps} steps: {choose}")
    return number - 1


def lesson_steps(lessons: Mapping[str, Lesson] | None) -> dict[str, int]:
    """How many steps each of a course's ``lessons`` has, in the course's order (``{}``: no course)."""
    return {} if lessons is None else {name: len(lesson.steps) for name, lesson in lessons.items()}
