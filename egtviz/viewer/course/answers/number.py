"""The skin of a number answer."""

from __future__ import annotations

from ....lessons.tasks import NUMBER
from .registry import skin
from .text import TextAnswer

__all__ = ["NumberAnswer"]


@skin(NUMBER)
class NumberAnswer(TextAnswer):
    """A text field, not a number input: the learner may type the unit after the number, and a malformed number
    reaches the strict reader, which says what is wrong with it, instead of being dropped by the page."""
