"""What a task needs of the lesson page (:class:`TaskNeeds`): its answer widget, the estimation lab, the lens.

Each task declares it (:attr:`~egtviz.lessons.tasks.base.Task.needs`) and the page is built from the
declaration alone: the viewer never asks which kind a task is, so a new answer widget (say a 3 x 3 grid for a
computed matrix) is one declaration here and one skin in the viewer
(:mod:`egtviz.viewer.course.answers`).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..answers import EXAMPLE

__all__ = ["ANSWER_WIDGETS", "CHOICE", "NO_ANSWER", "NUMBER", "TEXT", "AnswerNeeds", "LabNeeds", "TaskNeeds",
           "number_answer"]

NO_ANSWER = "none"
"""Answered by acting in the scene: nothing to type."""
NUMBER = "number"
"""One number, optionally followed by its unit."""
TEXT = "text"
"""Free text read strictly by the task (a vector, a matrix)."""
CHOICE = "choice"
"""One of the task's options."""
ANSWER_WIDGETS = (NO_ANSWER, NUMBER, TEXT, CHOICE)
"""The widgets tasks declare today; the viewer has a skin for each (a test holds it to that)."""


@dataclass(frozen=True)
class AnswerNeeds:
    """The answer widget a task asks for, and what the widget shows."""

    widget: str = NO_ANSWER
    """One of :data:`ANSWER_WIDGETS` (the key of the viewer's skin)."""
    unit: str = ""
    """The answer's unit, shown in the widget's label (empty: none)."""
    hint: str = ""
    """How to type the answer (empty: nothing to type)."""
    options: tuple[str, ...] = ()
    """A choice's options, in their order (their numbers are what a learner may type instead)."""

    def __post_init__(self) -> None:
        if not isinstance(self.widget, str) or not self.widget.isidentifier():
            raise ValueError(f"widget: expected a name such as {NUMBER!r}, got {self.widget!r}")
        if (self.widget == CHOICE) != bool(self.options):
            raise ValueError("options: a choice has options, and only a choice has them")


@dataclass(frozen=True)
class LabNeeds:
    """The estimation lab a task is judged on."""

    draws: str | None = None
    """The fit the lab's panels show first (a method of :mod:`egtviz.scene.lab`); None: the lab's default."""


@dataclass(frozen=True)
class TaskNeeds:
    """What the lesson page shows for a task besides its prompt, its *Check* button and its feedback."""

    answer: AnswerNeeds = AnswerNeeds()
    lab: LabNeeds | None = None
    """The estimation lab the task is judged on (None: the task does not use it)."""
    lens: bool = False
    """The task reads the epipolar geometry through the convention lens."""
    diagnosis: bool = False
    """The task may ask which of the lens's mistakes is on: while the step's lens has one on, the lens hides its
    settings (the learner must find it from the panels)."""


def number_answer(unit: str = "") -> AnswerNeeds:
    """A number field in ``unit``, with the hint the strict reader (:func:`~egtviz.lessons.answers.read_number`)
    goes by."""
    tail = f", in {unit} (the unit may follow it)" if unit else ""
    return AnswerNeeds(NUMBER, unit=unit, hint=f"One number, e.g. {EXAMPLE}{tail}.")
