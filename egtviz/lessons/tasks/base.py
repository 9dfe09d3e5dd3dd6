"""What every task kind shares: the :class:`Task` base (parameters, prompt, ``check``), what a check may look
at (:class:`TaskContext`), its outcome (:class:`TaskResult`) and the per-learner draws (:class:`Uniform`,
:func:`task_seed`).

A kind is a frozen subclass of :class:`Task` that names its ``kind``, its ``table_keys`` and how it is read
from its ``[[steps.tasks]]`` table (:meth:`Task.from_table`); :data:`egtviz.lessons.tasks.TASK_KINDS` lists
them.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ...scene import Scene, SceneError
from ...scene.derived import Derived, compute_derived
from ...scene.lab import LabResult, LabSettings, run_lab
from ...scene.lens import LensToggles, LensView, lens_view
from ...scene.limits import Range
from .. import fields
from ..changes import Change
from ..errors import EntryError
from ..servo_runs import DemoRun
from .needs import NO_ANSWER, TaskNeeds

__all__ = ["RESET_ADVICE", "Param", "Task", "TaskContext", "TaskResult", "Uniform", "read_param", "task_seed"]

#: How a check that finds something missing tells the learner the way back (the lesson panel's step button).
RESET_ADVICE = "press \u201creset step\u201d to start this step again."


@dataclass(frozen=True)
class TaskResult:
    """One attempt's outcome: ``passed`` and the feedback to show."""

    passed: bool
    feedback: str
    unread: bool = False
    """The typed answer could not be read (not one number, no brackets...): a refusal saying what was expected,
    not a wrong answer, so it is neither counted as an attempt nor a reason to show the next hint."""


@dataclass(frozen=True)
class Uniform:
    """A parameter drawn per learner from ``low..high`` (a whole number when ``integer``)."""

    low: float
    high: float
    integer: bool = False

    def draw(self, rng: np.random.Generator) -> float:
        """One value: ``rng.integers(low, high + 1)`` or ``rng.uniform(low, high)`` rounded to 0.01."""
        if self.integer:
            return float(rng.integers(int(self.low), int(self.high) + 1))
        return round(float(rng.uniform(self.low, self.high)), 2)


Param = float | Uniform


def read_param(value: Any, key: str, limit: Range) -> Param:
    """``value`` as a number in ``limit``, or ``[low, high]`` inside it (a :class:`Uniform` drawn per learner);
    errors name ``key``."""
    if isinstance(value, list):
        if len(value) != 2:
            raise EntryError(key, f"expected a number or [low, high], got {fields.short(value)}")
        low, high = (fields.as_number(x, key, limit) for x in value)
        if not low < high:
            raise EntryError(key, f"expected low < high, got {fields.short(value)}")
        return Uniform(low, high, integer=all(type(x) is int for x in value))
    return fields.as_number(value, key, limit)


@dataclass(frozen=True, eq=False)
class TaskContext:
    """What a check may look at: the scene (and what is drawn of it), the learner's typed answer, the
    estimation lab's settings, the convention lens's toggles and the servo run of the step (its
    ``open_demo``) as the runner holds them."""

    scene: Scene
    derived: Derived | None = None
    answer: str | None = None
    lab: LabSettings = LabSettings()
    lens: LensToggles = LensToggles()
    demo: DemoRun | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    def drawn(self) -> Derived:
        """What is drawn of the scene (``compute_derived``, once)."""
        if self.derived is None:
            self._cache.setdefault("derived", compute_derived(self.scene))
            return self._cache["derived"]
        return self.derived

    def lab_result(self) -> LabResult:
        """The estimation lab on the scene with the runner's lab settings (once)."""
        if "lab" not in self._cache:
            self._cache["lab"] = run_lab(self.scene, self.lab, derived=self.drawn())
        return self._cache["lab"]

    def lens_view(self) -> LensView:
        """The drawn pair through the runner's convention lens (once)."""
        if "lens" not in self._cache:
            self._cache["lens"] = lens_view(self.scene, self.lens, self.drawn())
        return self._cache["lens"]


def task_seed(learner: str, lesson: str, step: int, task: str) -> int:
    """A 63-bit seed from (learner, lesson, step index, task id): the same learner always gets the same draw."""
    digest = hashlib.sha256("\x1f".join((learner, lesson, str(step), task)).encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") >> 1


class _Shown(float):
    """A drawn value in a prompt: ``{u}`` shows it with ``g`` (106, not 106.0), ``{u:.1f}`` as asked."""

    def __format__(self, spec: str) -> str:
        return format(float(self), spec or "g")


class _SafeValues(dict):
    """``format_map`` values: a placeholder without a value stays as written."""

    def __missing__(self, key: str) -> str:
        return "{" + key + "}"


@dataclass(frozen=True, kw_only=True)
class Task:
    """Fields every task has; subclasses add their kind's parameters, ``from_table`` and ``check``."""

    id: str
    prompt: str
    hint: tuple[str, ...] = ()
    """The hints in tiers (at most three): the idea, a concrete pointer, the answer; tier k is
    shown after the k-th failed attempt."""
    solution: tuple[Change, ...] = ()
    """Changes that solve the task from the step's starting scene (for the tests and the docs)."""

    kind: ClassVar[str] = ""
    table_keys: ClassVar[tuple[str, ...]] = ()
    """The keys of the kind's table besides the common ones (``kind``, ``id``, ``prompt``, ``hint``,
    ``solution``); any other key is refused."""

    @property
    def needs(self) -> TaskNeeds:
        """What the lesson page shows for this task: its answer widget, the lab or lens it is judged on (nothing
        by default: a task done in the scene)."""
        return TaskNeeds()

    @property
    def question(self) -> bool:
        """Answered by typing (number, choice) rather than by acting in the scene."""
        return self.needs.answer.widget != NO_ANSWER

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> Task:  # pragma: no cover - abstract
        """The task from its ``[[steps.tasks]]`` table, ``common`` holding the fields every task has (already
        read); types and ranges are checked, names of cameras and points later by :meth:`validate`.

        Raises:
            EntryError: naming the offending key.
        """
        raise NotImplementedError

    def params(self) -> dict[str, Param]:
        """The parameters that may be drawn per learner, by the names the prompt and the check use."""
        return {}

    def resolve(self, seed: int) -> dict[str, float]:
        """The parameters with every :class:`Uniform` drawn from ``default_rng(seed)`` (in name order)."""
        rng = np.random.default_rng(seed)
        return {k: (v.draw(rng) if isinstance(v, Uniform) else float(v)) for k, v in sorted(self.params().items())}

    def prompt_for(self, params: dict[str, float]) -> str:
        """The prompt with its ``{name}`` placeholders replaced by the drawn values."""
        return self.prompt.format_map(_SafeValues({k: _Shown(v) for k, v in params.items()}))

    def check(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        """Measure the goal in ``ctx`` with the drawn ``params``: passed, and feedback saying what was measured.

        A scene that no longer has what the task measures (a camera removed, another scene opened) fails with
        what is missing and the way back (the step's *reset step*), never an exception.
        """
        gone = self.missing(ctx.scene)
        if gone is None:
            try:
                return self.judge(ctx, params)
            except SceneError as exc:  # e.g. the lab or the lens cannot be computed on this scene
                gone = str(exc)
        return TaskResult(False, f"{gone}: {RESET_ADVICE}")

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:  # pragma: no cover - abstract
        """The check on a scene that has what the task names (:meth:`missing` found nothing)."""
        raise NotImplementedError

    def missing(self, scene: Scene) -> str | None:
        """What the task measures that ``scene`` does not have, e.g. ``"cam2 is not in the scene any more"``."""
        return None

    def validate(self, scene: Scene) -> None:
        """Refuse a task that names what the step's scene does not have (an :class:`EntryError` naming the key)."""
