"""The skin of a typed answer: a text field whose label shows the unit and whose hint says how to type it."""

from __future__ import annotations

import viser

from ....lessons.tasks import TEXT, AnswerNeeds
from .registry import sent_text, skin

__all__ = ["TextAnswer"]


@skin(TEXT)
class TextAnswer:
    """A text field; the task reads what was typed."""

    def __init__(self, gui: viser.GuiApi, label: str, needs: AnswerNeeds) -> None:
        self.label = label
        self.field = gui.add_text(label + (f" ({needs.unit})" if needs.unit else ""), "", hint=needs.hint)

    def text(self) -> str | None:
        return sent_text(self.label, self.field.value)
