"""Plain text typed by a person: checked, normalised and bounded before a classroom keeps it."""

from __future__ import annotations

import unicodedata

__all__ = ["ClassroomError", "lesson_name", "plain_text", "step_number", "tab_id"]


class ClassroomError(ValueError):
    """A classroom call that cannot be done (an unknown tab, a value that cannot be kept); the message says why."""


def plain_text(value: object, what: str, limit: int, *, empty: bool = False) -> str:
    """``value`` NFC-normalised, trimmed, inner runs of white space made one; at most ``limit`` characters and no
    control or format characters (bidi overrides included), so it reads the same wherever it is shown.

    Raises:
        ClassroomError: naming ``what`` and what is wrong.
    """
    if not isinstance(value, str):
        raise ClassroomError(f"{what}: expected text, got {type(value).__name__}")
    text = " ".join(unicodedata.normalize("NFC", value).split())
    if not text and not empty:
        raise ClassroomError(f"{what}: expected text (it is empty)")
    if len(text) > limit:
        raise ClassroomError(f"{what}: at most {limit} characters, got {len(text)}")
    for c in text:
        if unicodedata.category(c)[0] == "C" and c not in "\u200c\u200d":
            raise ClassroomError(f"{what}: control characters are not allowed (U+{ord(c):04X})")
    return text


MAX_LESSON_NAME = 120


def tab_id(tab: object) -> int:
    """A tab's id: a whole number 0 or more.

    Raises:
        ClassroomError: anything else.
    """
    if isinstance(tab, bool) or not isinstance(tab, int) or tab < 0:
        raise ClassroomError(f"tab: expected a whole number 0 or more, got {tab!r}")
    return tab


def step_number(step: object, what: str = "step") -> int | None:
    """A lesson step (0-based, below 10,000) or None.

    Raises:
        ClassroomError: naming ``what``.
    """
    if step is None:
        return None
    if isinstance(step, bool) or not isinstance(step, int) or not 0 <= step < 10_000:
        raise ClassroomError(f"{what}: expected a whole number 0 to 9999 or none, got {step!r}")
    return step


def lesson_name(lesson: object) -> str:
    """A lesson's name as plain text (:func:`plain_text`, at most :data:`MAX_LESSON_NAME` characters)."""
    return plain_text(lesson, "lesson", MAX_LESSON_NAME)
