"""Three checks of issue 18 that could be passed without the understanding: lesson 1's "turn cam2 (not cam1)"
passed by turning cam1, lesson 9's "more points" passed by a tiny cluster of points, and lesson 7's "which mistake
is on?" said only "not yet" for a wrong choice."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from egtviz.geometry.error_metrics import sampson_distance
from egtviz.lessons import LessonError, LessonRun, load
from egtviz.lessons.changes import Lock, MoveCamera, RandomPoints
from egtviz.lessons.format import parse_lesson
from egtviz.lessons.proof import PROOF_LEARNERS
from egtviz.lessons.tasks import ChoiceTask, TaskContext
from egtviz.lessons.tasks.estimation import held_out_correspondences


def step_of(lesson, task_id: str) -> int:
    return next(i for i, step in enumerate(lesson.steps) if any(t.id == task_id for t in step.tasks))


def task_of(run: LessonRun, task_id: str):
    return next(t for t in run.step.tasks if t.id == task_id)


# -- lesson 1: turn cam2, not cam1 ---------------------------------------------------------------------------


def test_turning_cam1_to_cam2s_orientation_does_not_pass_lesson_1s_turn_cam2():
    lesson = load("01-frames-and-poses")
    run = LessonRun(lesson, "")
    run.go_to(step_of(lesson, "same-orientation"))
    cam2 = run.model.scene.camera("cam2").ypr_deg
    run.apply(Lock(("cam1",), False))  # the route round the step's lock, as a careless learner's GUI would not allow
    run.apply(MoveCamera("cam1", ypr_deg=tuple(cam2)))
    result = run.check("same-orientation").result
    assert not result.passed
    assert "cam1" in result.feedback


def test_turning_cam2_still_passes_and_cam1_is_locked_only_in_that_step():
    lesson = load("01-frames-and-poses")
    run = LessonRun(lesson, "")
    run.go_to(step_of(lesson, "same-orientation"))
    for change in task_of(run, "same-orientation").solution:
        run.apply(change)
    assert run.check("same-orientation").result.passed
    run.go_to(step_of(lesson, "roll"))  # the next step turns cam1 again
    for change in task_of(run, "roll").solution:
        run.apply(change)
    assert run.check("roll").result.passed


def test_lesson_1_has_the_turn_cam1_counter_example():
    lesson = load("01-frames-and-poses")
    step = lesson.steps[step_of(lesson, "same-orientation")]
    examples = step.counter_examples_of("same-orientation")
    assert any(Lock(("cam1",), False) in e.changes and any(isinstance(c, MoveCamera) and c.camera == "cam1"
                                                              for c in e.changes) for e in examples)


# -- lesson 9: more points, spread ---------------------------------------------------------------------------


def more_points_run(learner: str = "") -> LessonRun:
    lesson = load("09-estimating-f")
    run = LessonRun(lesson, learner)
    run.go_to(step_of(lesson, "more-points"))
    return run


@pytest.mark.parametrize("learner", PROOF_LEARNERS)
def test_a_tiny_cluster_of_points_does_not_pass_more_points(learner):
    run = more_points_run(learner)
    solution = task_of(run, "more-points").solution[0]
    assert isinstance(solution, RandomPoints)
    run.apply(dataclasses.replace(solution, extent=0.05))
    result = run.check("more-points").result
    assert not result.passed
    assert "held-out" in result.feedback and "spread" in result.feedback
    # The error where the data is was small: only the held-out correspondences refuse it.
    ctx = TaskContext(run.model.scene, run.model.derived, None, run.lab, run.lens, run.demo)
    assert ctx.lab_result().fit("normalized").sampson_true < 0.2


def test_points_spread_over_the_scene_pass_more_points_on_the_held_out_correspondences():
    run = more_points_run()
    for change in task_of(run, "more-points").solution:
        run.apply(change)
    result = run.check("more-points").result
    assert result.passed, result.feedback
    assert "held-out" in result.feedback


def test_the_held_out_correspondences_are_true_and_spread_over_both_images():
    run = more_points_run()
    ctx = TaskContext(run.model.scene, run.model.derived, None, run.lab, run.lens, run.demo)
    lab = ctx.lab_result()
    u1, u2 = held_out_correspondences(run.model.scene, lab)
    assert len(u1) >= 30
    assert float(np.max(sampson_distance(lab.F_true, u1, u2))) < 1e-12  # on the true geometry, exactly
    for u, (w, h) in ((u1, (640, 480)), (u2, (640, 480))):
        assert np.ptp(u[:, 0]) > 0.5 * w and np.ptp(u[:, 1]) > 0.5 * h
    # They do not depend on the lab's data, only on where it sits: the same for a spread and a tiny cluster.
    solution = task_of(run, "more-points").solution[0]
    run.apply(dataclasses.replace(solution, extent=0.05))
    ctx = TaskContext(run.model.scene, run.model.derived, None, run.lab, run.lens, run.demo)
    assert held_out_correspondences(run.model.scene, ctx.lab_result())[0].shape[0] >= 30


# -- lesson 7: feedback on each wrong diagnosis ------------------------------------------------------------

DIAGNOSES = ("diagnose-svd", "diagnose-broken", "diagnose-axes")


@pytest.mark.parametrize("task_id", DIAGNOSES)
def test_each_wrong_diagnosis_shows_its_own_message(task_id):
    lesson = load("07-fundamental-and-essential")
    run = LessonRun(lesson, "")
    run.go_to(step_of(lesson, task_id))
    task = task_of(run, task_id)
    assert isinstance(task, ChoiceTask)
    said = dict(task.feedback)
    assert set(said) == set(task.options)
    messages = set()
    for number, option in enumerate(task.options, start=1):
        for typed in (option, str(number)):
            result = run.check(task_id, typed).result
            assert result.passed == (option == task.answer)
            assert said[option] in result.feedback
            assert result.feedback.startswith("Right" if option == task.answer else f"Not {option!r}.")
        messages.add(said[option])
    assert len(messages) == len(task.options)


LENS_LESSON = '''title = "T"
summary = "S"
scene = "default"

[[steps]]
title = "Step"
text = "Text."

[[steps.changes]]
do = "set_lens"
f_transposed = {on}

[[steps.tasks]]
id = "which"
kind = "choice"
prompt = "Which mistake is on?"
options = ["a", "b"]
answer = "a"
'''


def test_a_diagnosis_without_feedback_for_every_option_is_refused_at_its_line():
    with pytest.raises(LessonError) as caught:
        parse_lesson(LENS_LESSON.format(on="true"), source="l.toml", name="l")
    assert caught.value.line == 13 and "feedback for every option" in caught.value.reason
    assert "'a', 'b'" in caught.value.reason
    with pytest.raises(LessonError) as caught:
        parse_lesson(LENS_LESSON.format(on="true") + '\n[steps.tasks.feedback]\na = "Yes."\n', source="l.toml",
                     name="l")
    assert "none for 'b'" in caught.value.reason
    # Not a diagnosis (no mistake on): feedback stays optional; a diagnosis with all of it loads.
    parse_lesson(LENS_LESSON.format(on="false"), source="l.toml", name="l")
    lesson = parse_lesson(LENS_LESSON.format(on="true") + '\n[steps.tasks.feedback]\na = "Yes."\nb = "No."\n',
                          source="l.toml", name="l")
    assert dict(lesson.steps[0].tasks[0].feedback) == {"a": "Yes.", "b": "No."}


@pytest.mark.parametrize("bad, reason", [
    ('feedback = "text"', "expected a table"),
    ('feedback = { c = "no such option" }', "expected options as keys"),
    ('feedback = { a = 3 }', "expected text"),
])
def test_a_choice_tasks_bad_feedback_is_refused(bad, reason):
    with pytest.raises(LessonError) as caught:
        parse_lesson(LENS_LESSON.format(on="false") + bad + "\n", source="l.toml", name="l")
    assert "feedback" in caught.value.reason and reason in caught.value.reason
