"""The lesson controller: one learner's lesson in a tab, headless.

A :class:`LessonController` owns the tab's :class:`~egtviz.lessons.LessonRun` (on the tab's own
:class:`~egtviz.scene.SceneModel`) and takes the lesson panel's intents as typed calls:

* the answer path: :meth:`~LessonController.check` a task with the learner's typed answer, which returns a
  :class:`CheckOutcome` (passed, the feedback or the refusal, the hints earned so far); a check is refused, and
  not counted, while the scene breaks the step's locks or ranges (:mod:`.lesson_rules`);
* the way through: :meth:`~LessonController.next` (refused with :class:`StepClosed` when a class's pacing has
  not opened the step), :meth:`~LessonController.previous`, :meth:`~LessonController.reset_step`,
  :meth:`~LessonController.go_to`, and :meth:`~LessonController.hold_back` when the pacing tightens;
* the learner: :meth:`~LessonController.set_learner` switches the run to that learner, who resumes at their
  remembered step;
* the instruments: the estimation lab's sliders (:meth:`~LessonController.set_lab`) and the convention lens's
  boxes (:meth:`~LessonController.toggle_lens`), applied through the run (:mod:`.lesson_instruments`).

It exposes what the skin draws: :meth:`~LessonController.step_state` (the step's title and text, each task with
what it needs of the page and whether it was passed, the servo run it offers, the ranges it sets, the summary on
the last step), the instruments the lesson uses (:attr:`~LessonController.needs`) and whether progress is kept
(:attr:`~LessonController.progress_problem`). The step's ranges are the scene's constraints: the controller puts
them on the model, which holds them for every edit, and a typed field asks :attr:`~LessonController.constraints`
first.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..lessons import LessonRun, ProgressStore
from ..lessons.changes import OpenDemo
from ..lessons.instruments import LessonNeeds, lesson_needs
from ..lessons.progress import LearnerNameError, learner_key
from ..lessons.runner import Attempt, ResolvedTask
from ..lessons.tasks import TaskNeeds
from ..scene import SceneError
from ..scene.constraints import CameraRanges
from ..scene.lens import LensToggles
from .lesson_instruments import lens_shown, set_lab, toggle_lens
from .lesson_rules import RangeLimit, lesson_constraints, lock_refusal, range_limit, range_refusal
from .workbench_fields import FieldError

__all__ = ["CheckOutcome", "LessonController", "StepClosed", "StepGate", "StepState", "TaskState",
           "typed_learner_key"]

StepGate = Callable[[str, int], bool]
"""``may_enter(lesson, step)``: whether "next" may open that step (a class's pacing)."""


def typed_learner_key(name: object) -> str:
    """The progress key of the name typed in a *your name* field; ``""`` for a blank field (no learner yet).

    Raises:
        FieldError: the name cannot be used (the field reverts, with the reason).
    """
    if not isinstance(name, str):
        raise FieldError(f"your name: expected text, got {type(name).__name__}")
    if not name.strip():
        return ""
    try:
        return learner_key(name)
    except LearnerNameError as exc:
        raise FieldError(str(exc)) from exc


class StepClosed(SceneError):
    """"next" was asked for a step the class's pacing has not opened (the message is for the learner)."""


@dataclass(frozen=True)
class CheckOutcome:
    """What one check of a task gave, as the page shows it."""

    task_id: str
    passed: bool
    feedback: str
    """The check's feedback (plain text), or why the check was refused."""
    hint: str | None = None
    """The hints earned so far after a failed attempt (Markdown, each labelled); None after a pass or a refusal."""
    hints_shown: int = 0
    """How many of the task's hint tiers the learner has been shown."""
    unread: bool = False
    """The answer could not be read: it was not judged (no verdict, nothing counted)."""
    counted: bool = True
    """False: the check was refused (the scene breaks the step's locks or ranges); no attempt was recorded."""
    summary: str | None = None
    """The lesson's summary after this check (Markdown) on the last step; None elsewhere or when refused."""


@dataclass(frozen=True)
class TaskState:
    """One task of the step as the page shows it."""

    number: int
    """The task's number in the step, from 1."""
    resolved: ResolvedTask
    """The task with its parameters drawn for this learner and its prompt as shown."""
    passed_before: bool
    """The learner passed it before the step was shown (kept in the progress store)."""

    @property
    def task_id(self) -> str:
        return self.resolved.task.id

    @property
    def needs(self) -> TaskNeeds:
        """What the page shows for the task: its answer widget, the lab or the lens it is judged on."""
        return self.resolved.task.needs

    @property
    def prompt_html(self) -> str:
        return self.resolved.prompt_html


@dataclass(frozen=True)
class StepState:
    """The run's current step as the page shows it."""

    lesson_title: str
    index: int
    """The step, from 0."""
    count: int
    """The lesson's steps."""
    title: str
    html: str
    """The step's text (Markdown with the formulas as MathML)."""
    tasks: tuple[TaskState, ...]
    demo: OpenDemo | None
    """The servo run the step offers (None: none)."""
    ranges: tuple[RangeLimit, ...]
    """The ``set_range`` limits in force, by camera and field, in the GUI fields' words and units."""
    summary: str | None
    """The lesson's summary (Markdown) on the last step; None on the others."""

    @property
    def percent(self) -> float:
        """How far through the lesson the step is, in percent."""
        return 100.0 * (self.index + 1) / self.count


class LessonController:
    """One learner's lesson in a tab.

    Args:
        run: the lesson run (already at the learner's remembered step); its model is the tab's.
        progress: where progress is kept when the learner types a name (None: the run's own store, if any).
    """

    def __init__(self, run: LessonRun, *, progress: ProgressStore | None = None) -> None:
        self._run = run
        self.progress = progress
        #: ``may_enter(lesson, step)``: whether "next" may open that step (a class's pacing); None: always.
        self.may_enter: StepGate | None = None
        #: The last attempt per task id in this step.
        self.attempts: dict[str, Attempt] = {}
        #: The step's ranges as the scene's constraints: the model and the typed fields ask them.
        self.constraints: CameraRanges = lesson_constraints(lambda: self._run)
        self.needs: LessonNeeds = lesson_needs(run.lesson)
        # The model holds the ranges, for every route into it (a gizmo, a raw client message, a script).
        run.model.set_constraints(self.constraints)

    @property
    def run(self) -> LessonRun:
        """The lesson run (a new one when the learner changes)."""
        return self._run

    @property
    def progress_problem(self) -> str | None:
        """Why progress is not being kept (the store fell back to memory), or None."""
        store = self.progress if self.progress is not None else self._run.progress
        return store.problem if store is not None else None

    # -- the answer path ---------------------------------------------------------------------

    def check(self, task_id: str, answer: str | None) -> CheckOutcome:
        """Check task ``task_id`` of the step with the learner's ``answer`` (None: the task asks no question).

        A scene that breaks the step's locks or ranges is refused with the way back, and nothing is counted.

        Raises:
            KeyError: no such task in the step.
        """
        refusal = lock_refusal(self._run) or range_refusal(self._run)
        if refusal is not None:
            return CheckOutcome(task_id, False, refusal, counted=False)
        attempt = self._run.check(task_id, answer)
        self.attempts[task_id] = attempt
        result = attempt.result
        return CheckOutcome(task_id, result.passed, result.feedback, attempt.hint, attempt.hints_shown,
                            unread=result.unread, summary=self._summary())

    def hint(self, task_id: str) -> str | None:
        """The hints of task ``task_id`` earned so far in this step (one tier more per failed attempt), or None."""
        attempt = self.attempts.get(task_id)
        return attempt.hint if attempt is not None else None

    # -- the way through ---------------------------------------------------------------------

    def next(self) -> None:
        """Go to the next step (nothing on the last one).

        Raises:
            StepClosed: the class's pacing has not opened it.
        """
        ahead = self._run.step_index + 1
        if (self.may_enter is not None and ahead < len(self._run.lesson.steps)
                and not self.may_enter(self._run.lesson.name, ahead)):
            raise StepClosed(f"step {ahead + 1}: the instructor has not opened it yet")
        self._run.next()
        self.attempts = {}

    def previous(self) -> None:
        """Go back one step, to its starting scene (nothing on the first one)."""
        self._run.previous()
        self.attempts = {}

    def reset_step(self) -> None:
        """Start the step afresh."""
        self._run.reset_step()
        self.attempts = {}

    def go_to(self, index: int) -> None:
        """Start step ``index`` afresh.

        Raises:
            IndexError: no such step.
        """
        self._run.go_to(index)
        self.attempts = {}

    def hold_back(self, step: int) -> bool:
        """Go back to ``step`` if the run is past it (a class's pacing tightened); False: it is not."""
        if self._run.step_index <= step:
            return False
        self.go_to(step)
        return True

    def set_learner(self, key: str) -> bool:
        """The learner is now ``key`` (a progress key, ``""``: anonymous): the run is keyed by it and resumes where
        that learner was. False: ``key`` is the learner already (nothing changes)."""
        if key == self._run.learner:
            return False
        self._run = LessonRun(self._run.lesson, key, model=self._run.model, progress=self.progress)
        self.attempts = {}
        return True

    # -- the instruments ------------------------------------------------------------------------

    def set_lab(self, key: str, value: float) -> None:
        """The lab's slider ``key`` (``noise_px``, ``outlier_percent``, ``threshold_px``) moved to ``value``.

        Raises:
            SceneError: outside the lab's range.
        """
        set_lab(self._run, key, value)

    def toggle_lens(self, key: str, shown: bool) -> None:
        """The lens's box ``key`` now shows ``shown`` (while the step hides its lens: a switch of that step)."""
        toggle_lens(self._run, key, shown)

    def lens_shown(self) -> LensToggles:
        """What the lens's boxes show: its toggles, or what was switched since the step hid its mistake."""
        return lens_shown(self._run)

    # -- what the page shows ---------------------------------------------------------------------

    def step_state(self) -> StepState:
        """The current step: header, text, tasks (with what was passed before), the servo run, ranges, summary."""
        run = self._run
        i = run.step_index
        passed = run.progress.passed_tasks(run.learner, run.lesson.name) if run.progress is not None else frozenset()
        tasks = tuple(TaskState(k, resolved, (i, resolved.task.id) in passed)
                      for k, resolved in enumerate(run.tasks(), start=1))
        return StepState(run.lesson.title, i, len(run.lesson.steps), run.step.title, run.step.html, tasks,
                         run.demo, tuple(range_limit(run, c, f) for c, f in sorted(run.ranges)), self._summary())

    def _summary(self) -> str | None:
        """The lesson's summary on the last step (kept current by each check); None on the others."""
        return self._run.summary().markdown() if self._run.on_last_step else None
