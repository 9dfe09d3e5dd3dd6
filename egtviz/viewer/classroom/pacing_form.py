"""The instructor's pacing field read as the lecturer means it: "up to step" is a step of the chosen lesson
(counted from 1, as the lesson panel shows them) or blank for every step; anything else is refused, in the
field's own words, naming the steps the lesson has (``999`` is not taken as "every step" without a word)."""

from __future__ import annotations

import re
from html import escape
from typing import TYPE_CHECKING

from ..workbench.fields import FieldError

if TYPE_CHECKING:
    from ..course.start_page import Course

__all__ = ["FIELD", "lesson_steps", "pacing_html", "paced_step"]

#: The field's label, as the refusals name it.
FIELD = "up to step"
_WHOLE = re.compile(r"[+-]?[0-9]{1,9}")


def paced_step(text: object, lesson: str, steps: int) -> int | None:
    """The last step (0-based) students may open, from the field's text; None for blank (every step).

    Args:
        text: what the instructor typed.
        lesson: the lesson's name (said in a refusal).
        steps: how many steps the lesson has.

    Raises:
        FieldError: not a whole number, below 1, or beyond the lesson's last step.
    """
    typed = str(text).strip()
    if not typed:
        return None
    choose = f"type 1 to {steps}, or leave it blank for every step"
    if not _WHOLE.fullmatch(typed):
        if re.fullmatch(r"[+]?[0-9]+", typed):  # more digits than any lesson has steps
            raise FieldError(f"{FIELD}: {lesson} has {steps} steps: {choose}")
        raise FieldError(f"{FIELD}: expected a step number or blank, got {typed[:20]!r}")
    number = int(typed)
    if number < 1:
        raise FieldError(f"{FIELD}: steps count from 1: {choose}")
    if number > steps:
        raise FieldError(f"{FIELD}: {lesson} has {steps} steps: {choose}")
    return number - 1


def pacing_html(allowed: frozenset[str] | None, paced: dict[str, int], steps: dict[str, int]) -> str:
    """What the panel says of the pacing: the lessons open, and the last step open of each paced one, "of n"."""
    lines = "all lessons" if allowed is None else escape(", ".join(sorted(allowed)))
    for name, last in sorted(paced.items()):
        total = steps.get(name)
        lines += f"<br>{escape(name)}: up to step {last + 1}" + (f" of {total}" if total else "")
    return f'<div data-egtviz="pacing" style="padding:0 0.6em">{lines}</div>'


def lesson_steps(course: Course | None) -> dict[str, int]:
    """How many steps each lesson of ``course`` has (``{}``: no course)."""
    return {} if course is None else {name: len(lesson.steps) for name, lesson in course.lessons.items()}
