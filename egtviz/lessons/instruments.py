"""What a lesson needs of the page beside its steps: the estimation lab, the convention lens, and when the lens
hides its settings.

Read from the lesson's changes and from what its tasks declare (:class:`~egtviz.lessons.tasks.TaskNeeds`), so
that the page builds its instruments without asking which kind a task is.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..scene.lens import LensToggles
from .changes import SetLab, SetLens
from .format import Lesson

__all__ = ["DEFAULT_LAB_FIT", "LessonNeeds", "hidden_lens", "lesson_needs"]

DEFAULT_LAB_FIT = "normalized"
"""The fit the lab's panels show first when no task asks for another."""


@dataclass(frozen=True)
class LessonNeeds:
    """The instruments a lesson uses."""

    lab: bool
    """The estimation lab: a step sets it, or a task is judged on it."""
    lens: bool
    """The convention lens: a step sets it, or a task reads through it."""
    lab_draws: str
    """The fit the lab's panels show first: the first one a task asks for, else :data:`DEFAULT_LAB_FIT`."""


def lesson_needs(lesson: Lesson) -> LessonNeeds:
    """The instruments ``lesson`` uses (its changes and its tasks' declared needs)."""
    changes = [c for s in lesson.steps for c in s.changes]
    needs = [t.needs for s in lesson.steps for t in s.tasks]
    asked = [n.lab.draws for n in needs if n.lab is not None and n.lab.draws is not None]
    return LessonNeeds(
        lab=any(isinstance(c, SetLab) for c in changes) or any(n.lab is not None for n in needs),
        lens=any(isinstance(c, SetLens) for c in changes) or any(n.lens for n in needs),
        lab_draws=asked[0] if asked else DEFAULT_LAB_FIT,
    )


def hidden_lens(lesson: Lesson, index: int) -> LensToggles | None:
    """The lens step ``index`` set, when the step hides it; None when the lens shows its settings (or there is no
    such step).

    A step hides its lens while it asks which mistake is on: one of its tasks is a possible diagnosis
    (:attr:`~egtviz.lessons.tasks.TaskNeeds.diagnosis`) and its lens (the ``set_lens`` changes of the steps so
    far, replayed) has a mistake on.
    """
    if not 0 <= index < len(lesson.steps) or not any(t.needs.diagnosis for t in lesson.steps[index].tasks):
        return None
    lens = LensToggles()
    for step in lesson.steps[: index + 1]:
        for change in step.changes:
            if isinstance(change, SetLens):
                lens = change.applied_to(lens)
    return lens if lens.any else None
