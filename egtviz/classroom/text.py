"""Plain text typed by a person: checked, normalised and bounded before a classroom keeps it."""

from __future__ import annotations

import unicodedata

__all__ = ["ClassroomError", "plain_text"]


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
