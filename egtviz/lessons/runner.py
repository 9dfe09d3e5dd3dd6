"""A lesson being worked through, headless: the scene, the current step, the lab and lens settings, checks.

The viewer's lesson panel drives one :class:`LessonRun` per browser tab; tests drive it directly. Entering
a step applies its changes on top of the current scene (what the learner did so far stays), while
:meth:`LessonRun.go_to` (and "previous", and :meth:`LessonRun.reset_step`) rebuild the step's starting scene
by replaying the lesson's changes from its first step, so a step always starts the same way.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass

from ..scene import SceneError, SceneModel
from ..scene.lab import LabSettings
from ..scene.lens import LensToggles
from ..files import FileSafetyError, read_limited
from ..scene.limits import MAX_LESSON_FILE_BYTES
from .catalog import lessons_folder
from .changes import Change, OpenDemo, RandomiseCamera, RandomisePoint, SetLab, SetLens, SetRange
from .changes import apply as apply_change
from .format import Lesson, Step
from .markup import render_markdown
from .progress import ProgressStore, learner_key
from .locks import lock_breach
from .tasks import RESET_ADVICE, Task, TaskContext, TaskResult, task_seed

__all__ = ["Attempt", "LessonRun", "LessonSummary", "ResolvedTask", "UNDO_NOTE", "next_lesson_title"]

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
    """The hints shown so far, rendered like the prompt, each after its label (``**Hint:** *(1 of 3)* ...``),
    after a failed attempt; None after a passed one or when the task has no hint."""
    hints_shown: int = 0
    """How many of the task's hint tiers the learner has been shown (one more per failed attempt)."""


@dataclass(frozen=True)
class LessonSummary:
    """The end of a lesson: what the learner did in it, and what comes next."""

    tasks: int
    passed: int
    attempts: int
    hints: int
    next_title: str | None
    """The next lesson's title (None: this was the last lesson)."""

    def markdown(self) -> str:
        """The summary as the lesson panel shows it (Markdown; the title's own Markdown is escaped)."""
        nxt = ("this was the last lesson." if self.next_title is None
               else f"next lesson: *{_escape_markdown(self.next_title)}*.")
        return (f"**End of the lesson.** Tasks passed: {self.passed} of {self.tasks}; attempts: {self.attempts}; "
                f"hints used: {self.hints}; {nxt}")


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
        self._own: dict[tuple[int, str], tuple[int, bool, int]] = {}
        """``(step, task)``: attempts, passed, hints shown, of an anonymous learner (nothing goes to the store)."""
        self._next_title: tuple[str | None] | None = None
        self.keep_furthest = False
        """Record a step only when it is further than the one remembered (a class's pacing decides where the tab
        shows, not how far the learner got)."""
        self.step_index = 0
        start = self.progress.current_step(self.learner, lesson.name) if self.progress else 0
        self.go_to(min(max(start, 0), len(lesson.steps) - 1))

    @property
    def step(self) -> Step:
        """The current step."""
        return self.lesson.steps[self.step_index]

    def apply(self, change: Change, step: int | None = None) -> None:
        """Apply one change (of step ``step``, default the current one): to the scene, or to the lab, lens and
        ranges the runner holds. A ``randomise_camera`` or ``randomise_point`` draws for this learner, lesson and
        step."""
        if isinstance(change, (RandomiseCamera, RandomisePoint)):
            at = self.step_index if step is None else step
            change = change.seeded(task_seed(self.learner, self.lesson.name, at, change.seed_key))
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
                self.apply(change, index)
        self.step_index = index
        self.step_start = self.model.scene
        """The scene as the step started (its locks are verified by every scene task's check)."""
        if self.progress is not None and (not self.keep_furthest
                                          or index > self.progress.current_step(self.learner, self.lesson.name)):
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
                    self.apply(change, i)
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
        """Check one task of the current step (``answer``: the typed answer of a question); the attempt is recorded
        (an answer that could not be read, :attr:`TaskResult.unread`, is not)."""
        for resolved in self.tasks():
            if resolved.task.id == task_id:
                break
        else:
            raise KeyError(f"task: no task {task_id!r} in step {self.step_index}")
        ctx = TaskContext(self.model.scene, self.model.derived, answer, self.lab, self.lens, self.demo)
        breach = None if resolved.task.question else lock_breach(self.step_start, self.model.scene)
        result = (TaskResult(False, f"{breach}: {RESET_ADVICE}") if breach is not None
                  else resolved.task.check(ctx, resolved.params))
        tiers = resolved.task.hint
        if result.unread:  # not an answer: the hints shown so far stay, nothing is counted
            shown = (self.progress.hints_shown(self.learner, self.lesson.name, self.step_index, task_id)
                     if self.progress is not None else self._own.get((self.step_index, task_id), (0, False, 0))[2])
        elif self.progress is not None:
            shown = self.progress.record_attempt(self.learner, self.lesson.name, self.step_index, task_id,
                                                 result.passed, hint_tiers=len(tiers))
        else:
            attempts, passed, shown = self._own.get((self.step_index, task_id), (0, False, 0))
            shown = max(shown, min(shown + (not result.passed), len(tiers)))
            self._own[(self.step_index, task_id)] = (attempts + 1, passed or result.passed, shown)
        if result.passed or not shown:
            return Attempt(task_id, result, None, shown)
        labels = [f"**Hint:** *({k} of {len(tiers)})* " if len(tiers) > 1 else "**Hint:** "
                  for k in range(1, shown + 1)]
        hint = "\n\n".join(label + render_markdown(tier) for label, tier in zip(labels, tiers, strict=False))
        return Attempt(task_id, result, hint, shown)

    @property
    def on_last_step(self) -> bool:
        """Whether the learner is at the lesson's last step (where its summary is shown)."""
        return self.step_index == len(self.lesson.steps) - 1

    def summary(self) -> LessonSummary:
        """What this learner did in the lesson: tasks passed (of all), attempts and hints used, the next lesson."""
        if self.progress is not None:
            records = {(r.step, r.task): (r.attempts, r.passed, r.hints)
                       for r in self.progress.task_records(self.learner, self.lesson.name)}
        else:
            records = dict(self._own)
        tasks = {(i, t.id) for i, step in enumerate(self.lesson.steps) for t in step.tasks}
        mine = [v for k, v in records.items() if k in tasks]
        if self._next_title is None:
            self._next_title = (next_lesson_title(self.lesson.name),)
        return LessonSummary(len(tasks), sum(1 for _, ok, _ in mine if ok), sum(a for a, _, _ in mine),
                             sum(h for _, _, h in mine), self._next_title[0])


def next_lesson_title(name: str) -> str | None:
    """The title of the shipped lesson after ``name`` (file names sort in course order); None after the last one
    or for a lesson that is not shipped. Only the next file's ``title`` is read, not the whole lesson."""
    folder = lessons_folder()
    names = sorted(f.stem for f in folder.iterdir() if f.suffix.lower() == ".toml" and f.is_file()) \
        if folder.is_dir() else []
    if name not in names or names.index(name) + 1 >= len(names):
        return None
    try:
        doc = tomllib.loads(read_limited(folder / f"{names[names.index(name) + 1]}.toml",
                                         MAX_LESSON_FILE_BYTES).decode("utf-8"))
    except (FileSafetyError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return None
    title = doc.get("title")
    return title if isinstance(title, str) and title.strip() else None


def _escape_markdown(text: str) -> str:
    """Text shown as itself inside Markdown: its HTML and Markdown marks escaped."""
    out = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    for mark in "\\`*_[]#|$":
        out = out.replace(mark, "\\" + mark)
    return out
