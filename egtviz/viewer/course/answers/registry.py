"""The answer widgets' registry: one skin per widget a task may declare
(:attr:`~egtviz.lessons.tasks.AnswerNeeds.widget`), each registered by its own module with :func:`skin`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, TypeVar

import viser

from ....lessons.tasks import AnswerNeeds
from ....controllers.workbench_fields import MAX_FIELD_CHARS, FieldError

__all__ = ["SKINS", "AnswerSkin", "AnswerWidget", "sent_text", "skin"]


class AnswerWidget(Protocol):
    """A task's answer widget in the lesson panel."""

    @property
    def field(self) -> viser.GuiInputHandle[str] | None:
        """The GUI handle the learner answers in (None: nothing to type)."""

    def text(self) -> str | None:
        """The learner's answer, checked for what a page can send (None: nothing to type).

        Raises:
            FieldError: the page sent what the widget cannot hold (a raw client can send anything).
        """


AnswerSkin = Callable[[viser.GuiApi, str, AnswerNeeds], AnswerWidget]
"""``skin(gui, label, needs)`` builds the widget under ``label`` (e.g. ``"answer 2"``) in the tab's ``gui``."""
SKINS: dict[str, AnswerSkin] = {}
"""The skin of each answer widget, by the widget's name."""

_Skin = TypeVar("_Skin", bound=AnswerSkin)


def skin(widget: str) -> Callable[[_Skin], _Skin]:
    """Register the decorated class as the skin of ``widget``.

    Raises:
        ValueError: ``widget`` has a skin already.
    """

    def register(cls: _Skin) -> _Skin:
        if widget in SKINS:
            raise ValueError(f"widget: {widget!r} has a skin already ({SKINS[widget]!r})")
        SKINS[widget] = cls
        return cls

    return register


def sent_text(label: str, value: object) -> str:
    """``value`` as the page's field ``label`` sent it, refused unless it is text such a field holds."""
    if not isinstance(value, str):
        raise FieldError(f"{label}: expected text, got {type(value).__name__}")
    if len(value) > MAX_FIELD_CHARS:
        raise FieldError(f"{label}: at most {MAX_FIELD_CHARS} characters, got {len(value)}")
    return value
