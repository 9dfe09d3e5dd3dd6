"""A lesson being worked through, headless: the scene, the current step, the lab and lens settings, checks.

The viewer's lesson panel drives one :class:`LessonRun` per browser tab; tests drive it directly. Entering
a step applies its changes on top of the current scene (what the learner did so far stays), while
:meth:`LessonRun.go_to` (and "previous", and :meth:`LessonRun.reset_step`) rebuild the step's starting scene
by replaying the lesson's changes from its first step, so a step always starts the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..scene import SceneError, SceneModel
from ..scene.lab import LabSettings
from ..scene.lens import LensToggles
from .changes import Change, OpenDemo, SetLab, SetLens, SetRange
from .changes import apply as apply_change
from .format import Lesson, Step
from .markup import render_markdown
from .progress import ProgressStore, learner_key
from .locks import lock_breach
from .tasks import RESET_ADVICE, Task, TaskContext, TaskResult, task_seed

__all__ = ["Attempt", "LessonRun", "ResolvedTask", "UNDO_NOTE"]

#: What Undo says at the start of a step: a step's own changes (its locks, the values it sets) are the lesson's.
UNDO_NOTE = ("Undo stops at the start of this step: the step's own changes cannot be undone "
             "(\u201creset step\u201d starts the step again).")


@dataclass(frozen=True)
class ResolvedTask:
    """A task with its parameters drawn for this learner, and its prompt as shown."""

    task: Task
    params: dict
    prompt: str
    """The prompt with the drawn values (Markdown with ``$...$`` formulas)."""
    prompt_html: str
    """The prompt as shown: formulas rendered to MathML (:func:`~egtviz.lessons.markup.render_markdown`)."""


@dataclass(frozen=True)
class Attempt:
    """The outcome of one check: the result, and the hint when it failed (None when passed)."""

    task_id: str
    result: TaskResult
    hint: str | None
    """The task's hint, rendered like the prompt, after a failed attempt; None after a passed one or when the
    task has no hint."""


class LessonRun:
    """One learner in one lesson.

    Args:
        lesson: a loaded lesson.
        learner: the name the learner typed (:func:`~egtviz.lessons.progress.learner_key`); empty: anonymous,
            nothing is recorded.
        model: the scene model to drive (the viewer's); default a new one.
        progress: where attempts and the current step are recorded; the run starts at the remembered step.
    """

    def __init__(self, lesson: Lesson, learner: str = "", *, model: SceneModel | None = None,
                 progress: ProgressStore | None = None) -> None:
        self.lesson = lesson
        self.learner = learner_key(learner) if learner.strip() else ""
        self.model = model if model is not None else SceneModel(lesson.scene)
        self.progress = progress if self.learner else None
        self.lab = LabSettings()
        self.lens = LensToggles()
        self.ranges: dict[tuple[str, str], SetRange] = {}
        """``(camera, field)``: the range the GUI offers, from the ``set_range`` changes so far."""
        self.demo: OpenDemo | None = None
        """The servo demo and run fields the step offers (the last ``open_demo`` so far); its tasks measure it."""
        self.step_index = 0
        start = self.progress.current_step(self.learner, lesson.name) if self.progress else 0
        self.go_to(min(max(start, 0), len(lesson.steps) - 1))

    @property
    def step(self) -> Step:
        """The current step."""
        return self.lesson.steps[self.step_index]

    def apply(self, change: Change) -> None:
        """Apply one change: to the scene, or to the lab, lens and ranges the runner holds."""
        record = apply_change(self.model, change)
        if isinstance(record, SetLab):
            self.lab = record.applied_to(self.lab)
        elif isinstance(record, SetLens):
            self.lens = record.applied_to(self.lens)
        elif isinstance(record, SetRange):
            self.ranges[(record.camera, record.field)] = record
        elif isinstance(record, OpenDemo):
            self.demo = record

    def _enter(self, index: int) -> None:
        with self.model.lesson_step(UNDO_NOTE):
            for change in self.lesson.steps[index].changes:
                self.apply(change)
        self.step_index = index
        self.step_start = self.model.scene
        """The scene as the step started (its locks are verified by every scene task's check)."""
        if self.progress is not None:
            self.progress.set_step(self.learner, self.lesson.name, index)

    def go_to(self, index: int) -> None:
        """Start step ``index`` afresh: the lesson's scene with the changes of steps ``0..index`` replayed."""
        if not 0 <= index < len(self.lesson.steps):
            raise IndexError(f"step: expected 0..{len(self.lesson.steps) - 1}, got {index}")
        self.lab, self.lens, self.ranges, self.demo = LabSettings(), LensToggles(), {}, None
        with self.model.lesson_step(UNDO_NOTE):
            self.model.load_scene(self.lesson.scene)
            for i in range(index):
                for change in self.lesson.steps[i].changes:
                    self.apply(change)
        self._enter(index)

    def next(self) -> bool:
        """Go to the next step (keeping the scene as the learner left it); False on the last step.

        If the learner's scene no longer has what the step changes (e.g. a removed point), the step starts
        from its replayed starting scene instead.
        """
        if self.step_index + 1 >= len(self.lesson.steps):
            return False
        lab, lens, ranges, demo = self.lab, self.lens, dict(self.ranges), self.demo
        try:
            self._enter(self.step_index + 1)
        except SceneError:
            self.lab, self.lens, self.ranges, self.demo = lab, lens, ranges, demo
            self.go_to(self.step_index + 1)
        return True

    def previous(self) -> bool:
        """Go back one step (its starting scene); False on the first step."""
        if self.step_index == 0:
            return False
        self.go_to(self.step_index - 1)
        return True

    def reset_step(self) -> None:
        """Start the current step afresh (:meth:`go_to`)."""
        self.go_to(self.step_index)

    def tasks(self) -> tuple[ResolvedTask, ...]:
        """The current step's tasks, drawn for this learner."""
        out = []
        for task in self.step.tasks:
            params = task.resolve(task_seed(self.learner, self.lesson.name, self.step_index, task.id))
            prompt = task.prompt_for(params)
            out.append(ResolvedTask(task, params, prompt, render_markdown(prompt)))
        return tuple(out)

    def check(self, task_id: str, answer: str | None = None) -> Attempt:
        """Check one task of the current step (``answer``: the typed answer of a question); the attempt is recorded."""
        for resolved in self.tasks():
            if resolved.task.id == task_id:
                break
        else:
            raise KeyError(f"task: no task {task_id!r} in step {self.step_index}")
        ctx = TaskContext(self.model.scene, self.model.derived, answer, self.lab, self.lens, self.demo)
        breach = None if resolved.task.question else lock_breach(self.step_start, self.model.scene)
        result = (TaskResult(False, f"{breach}: {RESET_ADVICE}") if breach is not None
                  else resolved.task.check(ctx, resolved.params))
        if self.progress is not None:
            self.progress.record_attempt(self.learner, self.lesson.name, self.step_index, task_id, result.passed)
        hint = render_markdown(resolved.task.hint) if resolved.task.hint and not result.passed else None
        return Attempt(task_id, result, hint)
