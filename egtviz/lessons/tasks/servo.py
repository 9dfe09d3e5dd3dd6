"""Tasks about the step's servo run (its ``open_demo``): :class:`ServoNumberTask`, a number read off the run."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from ...scene.limits import COORDINATE, Range
from .. import fields
from ..errors import EntryError
from ..servo_runs import MEASURES, DemoRun, measure_run
from .base import Param, Task, TaskContext, TaskResult
from .common import TOLERANCE
from .needs import TaskNeeds, number_answer
from .questions import compare_number

__all__ = ["ServoNumberTask"]

_BELOW = {"deg": Range(1e-6, 180.0, "deg"), "cm": Range(1e-6, 100.0 * COORDINATE.high, "cm")}


@dataclass(frozen=True, kw_only=True)
class ServoNumberTask(Task):
    """A number read off the step's servo run (its ``open_demo``): ``measure`` (with ``below`` for the
    ``*_below_time`` measures) within ``tolerance``. The answer is computed by simulating the run headless,
    as the demo does (:mod:`egtviz.lessons.servo_runs`); the unit is the measure's."""

    measure: str
    below: float | None = None
    tolerance: float = 0.0

    kind: ClassVar[str] = "servo_number"
    table_keys: ClassVar[tuple[str, ...]] = ("measure", "below", "tolerance")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> ServoNumberTask:
        measure = fields.text(table, "measure")
        if measure not in MEASURES:
            raise EntryError("measure", f"expected one of {', '.join(MEASURES)}, got {fields.short(measure)}")
        below_unit = MEASURES[measure].below_unit
        if bool(below_unit) != ("below" in table):
            raise EntryError("below", f"{measure!r} needs 'below' (in {below_unit})" if below_unit
                             else f"{measure!r} takes no 'below'")
        below = fields.number(table, "below", _BELOW[below_unit]) if below_unit else None
        return cls(**common, measure=measure, below=below,
                   tolerance=fields.number(table, "tolerance", TOLERANCE, required=False, default=0.0))

    @property
    def unit(self) -> str:
        """The measure's unit (s, steps, deg, cm)."""
        return MEASURES[self.measure].unit

    @property
    def needs(self) -> TaskNeeds:
        return TaskNeeds(number_answer(self.unit))

    def params(self) -> dict[str, Param]:
        return {"tolerance": self.tolerance, **({"below": self.below} if self.below is not None else {})}

    def answer_for(self, run: DemoRun) -> float:
        """The right answer for ``run`` (NaN: the run never gets there)."""
        return measure_run(run, self.measure, math.nan if self.below is None else self.below)

    def validate_run(self, run: DemoRun | None) -> None:
        """Refuse a task without a servo run in its step, a measure the demo does not have, or a run that never
        gets where the measure asks (an :class:`EntryError` naming the key)."""
        if run is None:
            raise EntryError(None, "a servo_number task needs an open_demo change in its step or an earlier one")
        if run.demo not in MEASURES[self.measure].demos:
            raise EntryError("measure", f"the {run.demo} demo has no {self.measure!r}")
        if not math.isfinite(self.answer_for(run)):
            raise EntryError("below" if self.below is not None else "measure",
                             f"the {run.demo} run ({run.describe() or 'its defaults'}) never gets there")

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        if ctx.demo is None:
            return TaskResult(False, "This step opens no servo demo to read the answer from.")
        return compare_number(ctx.answer, self.answer_for(ctx.demo), params["tolerance"], self.unit)
