"""Proving a lesson's tasks against wrong answers: every counter-example of every task must fail.

A task's ``[[steps.tasks.counter_examples]]`` (:class:`~egtviz.lessons.format.CounterExample`) are the
mistakes a careless learner makes. :func:`prove_counter_examples` replays each from the step's start, as the
lesson panel would (:class:`~egtviz.lessons.runner.LessonRun`, for each of :data:`PROOF_LEARNERS`, so for
several per-learner draws), and refuses the lesson when the task passes.

The rule for a change the scene refuses (e.g. moving a camera the step locked): a counter-example must be
something a learner *can* do, so a refused change is an error of the lesson file ("cannot be applied"), not
a proof. A mistake the lesson already forbids is written as the route that would get round it, e.g.
``unlock`` then ``move`` for "a moved locked camera": the check must then still fail.
"""

from __future__ import annotations

from typing import cast

from ..scene import SceneError
from .errors import EntryError, LessonError
from .format import CounterExample, Lesson
from .runner import LessonRun
from .tasks.computed import ComputedTask

__all__ = ["PROOF_LEARNERS", "prove_counter_examples"]

PROOF_LEARNERS = ("", "proof learner 1", "proof learner 2")
"""The learners whose draws each counter-example is tried with (the anonymous learner first)."""


def prove_counter_examples(lesson: Lesson, learners: tuple[str, ...] = PROOF_LEARNERS) -> None:
    """Apply every counter-example of ``lesson`` from its step's start and check its task.

    Raises:
        LessonError: ``file:line: task X: counter-example N passes: <feedback>`` for the first one that passes,
            or ``... cannot be applied: <reason>`` for one the scene refuses (``N`` counts from 1 in the task).
    """
    for learner in learners:
        run = LessonRun(lesson, learner)
        for index, step in enumerate(lesson.steps):
            for task in step.tasks:
                if hasattr(task, "answer_text"):
                    _prove_computed(lesson, run, index, task)
                for number, example in enumerate(step.counter_examples_of(task.id), start=1):
                    _prove_one(lesson, run, index, task.id, number, example)


def _prove_computed(lesson: Lesson, run: LessonRun, index: int, task) -> None:
    """A computed task is solvable for this learner: the answer the check computes, typed, passes."""
    run.go_to(index)
    try:
        typed = task.answer_text(run.model.scene)
    except SceneError as exc:
        raise LessonError(lesson.source, 1, f"task {task.id}: no answer in learner {run.learner!r}'s scene: "
                                            f"{exc}") from None
    attempt = run.check(task.id, typed)
    if not attempt.result.passed:
        raise LessonError(lesson.source, 1, f"task {task.id}: its computed answer {typed} does not pass: "
                                            f"{attempt.result.feedback}")


def _prove_one(lesson: Lesson, run: LessonRun, index: int, task_id: str, number: int,
               example: CounterExample) -> None:
    run.go_to(index)
    where = f"task {task_id}: counter-example {number}"
    for change in example.changes:
        try:
            run.apply(change)
        except (SceneError, EntryError) as exc:
            raise LessonError(lesson.source, example.line, f"{where} cannot be applied: {exc}") from None
    answer = example.answer
    if example.mistake is not None:  # a computed task: the mistake's value in this learner's scene
        # A counter-example names a mistake only for a computed task.
        task = cast(ComputedTask, next(t for t in run.step.tasks if t.id == task_id))
        try:
            answer = task.mistake_text(example.mistake, run.model.scene)
        except SceneError as exc:
            raise LessonError(lesson.source, example.line, f"{where} cannot be applied: {exc}") from None
    attempt = run.check(task_id, answer)
    if attempt.result.unread:  # refused before it was judged: it shows nothing about the check
        raise LessonError(lesson.source, example.line,
                          f"{where} is not read as an answer: {attempt.result.feedback} [{example.why}]")
    if attempt.result.passed:
        learner = f" (learner {run.learner!r})" if run.learner else ""
        raise LessonError(lesson.source, example.line,
                          f"{where} passes{learner}: {attempt.result.feedback} [{example.why}]")
