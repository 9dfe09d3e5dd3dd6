"""Tasks answered by typing: a number (:class:`NumberTask`) or one of a few options (:class:`ChoiceTask`).

A typed number is read strictly (:func:`egtviz.lessons.answers.read_number`) and compared by
:func:`compare_number`, which the servo tasks use too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from .. import fields
from ..answers import AnswerError, read_number
from ..errors import EntryError
from .base import Task, TaskContext, TaskResult
from .common import ANSWER, TOLERANCE, fmt
from .needs import CHOICE, AnswerNeeds, TaskNeeds, number_answer

__all__ = ["ChoiceTask", "NumberTask", "compare_number"]

_MAX_OPTIONS = 12
_MAX_FEEDBACK = 600
"""Characters of one option's feedback."""


def compare_number(typed: str | None, answer: float, tolerance: float, unit: str) -> TaskResult:
    """The typed number (:func:`~egtviz.lessons.answers.read_number`: one number, then optionally ``unit``)
    against ``answer`` within ``tolerance``."""
    try:
        x = read_number(typed, unit)
    except AnswerError as exc:
        return TaskResult(False, str(exc), unread=True)
    shown = f" {unit}" if unit else ""
    if abs(x - answer) <= tolerance:
        return TaskResult(True, f"Right: {fmt(x)}{shown}.")
    return TaskResult(False, f"{fmt(x)}{shown} is too {'high' if x > answer else 'low'}.")


@dataclass(frozen=True, kw_only=True)
class NumberTask(Task):
    """A numeric answer within ``tolerance`` of ``answer``: one number, optionally followed by ``unit``."""

    answer: float
    tolerance: float = 0.0
    unit: str = ""

    kind: ClassVar[str] = "number"
    table_keys: ClassVar[tuple[str, ...]] = ("answer", "tolerance", "unit")

    @property
    def needs(self) -> TaskNeeds:
        return TaskNeeds(number_answer(self.unit))

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> NumberTask:
        return cls(**common, answer=fields.number(table, "answer", ANSWER),
                   tolerance=fields.number(table, "tolerance", TOLERANCE, required=False, default=0.0),
                   unit=fields.text(table, "unit", required=False))

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        return compare_number(ctx.answer, self.answer, self.tolerance, self.unit)


@dataclass(frozen=True, kw_only=True)
class ChoiceTask(Task):
    """One of ``options``; the learner types the option or its number (1, 2, ...). ``feedback`` pairs an option
    with what choosing it tells the learner (for a wrong option: what it would have shown, and why the evidence
    points elsewhere); an option without feedback gets the plain verdict."""

    options: tuple[str, ...]
    answer: str
    feedback: tuple[tuple[str, str], ...] = ()

    kind: ClassVar[str] = "choice"
    table_keys: ClassVar[tuple[str, ...]] = ("options", "answer", "feedback")

    @property
    def needs(self) -> TaskNeeds:
        # Any choice may be a diagnosis: it is one while the step's lens has a mistake on.
        return TaskNeeds(AnswerNeeds(CHOICE, options=self.options), diagnosis=True)

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> ChoiceTask:
        options = fields.name_list(table, "options", limit=_MAX_OPTIONS)
        if len(options) < 2 or len(set(options)) != len(options):
            raise EntryError("options", "expected at least two different options")
        answer = fields.text(table, "answer")
        if answer not in options:
            raise EntryError("answer", f"expected one of the options, got {fields.short(answer)}")
        return cls(**common, options=options, answer=answer, feedback=_option_feedback(table, options))

    @property
    def options_without_feedback(self) -> tuple[str, ...]:
        """The options that have no ``feedback`` (a diagnosis task must have none)."""
        given = {option for option, _ in self.feedback}
        return tuple(o for o in self.options if o not in given)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        given = (ctx.answer or "").strip()
        if given.isdigit() and 1 <= int(given) <= len(self.options):
            given = self.options[int(given) - 1]
        if given not in self.options:
            return TaskResult(False, "Pick one of the options.", unread=True)
        said = dict(self.feedback).get(given)
        if given == self.answer:
            return TaskResult(True, f"Right: {given}." + (f" {said}" if said else ""))
        return TaskResult(False, f"Not {given!r}." + (f" {said}" if said else ""))


def _option_feedback(table: dict, options: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    """A choice task's optional ``feedback`` table: option text = what choosing it tells the learner."""
    value = table.get("feedback", {})
    if not isinstance(value, dict):
        raise EntryError("feedback", f"expected a table of option = text, got {fields.short(value)}")
    for option in value:
        if option not in options:
            raise EntryError("feedback", f"expected options as keys, got {fields.short(option)}")
    out = []
    for option in options:
        if option in value:
            try:
                out.append((option, fields.text(value, option, limit=_MAX_FEEDBACK)))
            except EntryError as exc:
                raise EntryError("feedback", f"{fields.short(option)}: {exc.reason}") from None
    return tuple(out)
