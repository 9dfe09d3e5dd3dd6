"""The skin of a task done in the scene: no answer widget."""

from __future__ import annotations

import viser

from ....lessons.tasks import NO_ANSWER, AnswerNeeds
from .registry import skin

__all__ = ["NoAnswer"]


@skin(NO_ANSWER)
class NoAnswer:
    """Nothing to type: the check reads the scene."""

    field: None = None

    def __init__(self, gui: viser.GuiApi, label: str, needs: AnswerNeeds) -> None:
        pass

    def text(self) -> str | None:
        return None
