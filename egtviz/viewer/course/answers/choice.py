"""The skin of a choice: a drop-down of the options."""

from __future__ import annotations

import viser

from ....lessons.tasks import CHOICE, AnswerNeeds
from ....controllers.workbench_fields import FieldError
from .registry import sent_text, skin

__all__ = ["CHOOSE", "ChoiceAnswer"]

CHOOSE = "(choose an answer)"
"""The drop-down's value before the learner picks an option."""


@skin(CHOICE)
class ChoiceAnswer:
    """The options in a drop-down that opens on :data:`CHOOSE`, which sends an empty answer."""

    def __init__(self, gui: viser.GuiApi, label: str, needs: AnswerNeeds) -> None:
        self.label = label
        self.options = needs.options
        self.field = gui.add_dropdown(label, (CHOOSE, *self.options), initial_value=CHOOSE)

    def text(self) -> str | None:
        value = sent_text(self.label, self.field.value)
        if value == CHOOSE:
            return ""
        if value not in self.options:  # a raw client can send any string
            raise FieldError(f"{self.label}: not one of the options")
        return value
