"""The lesson controller without a server: the shipped lessons driven through its typed intents, its state read
back (checks and their hints, progress, steps and a class's pacing, what each task needs of the page, ranges,
locks, the lab and the lens)."""

from __future__ import annotations

import pytest

from egtviz.controllers.lesson import LessonController, StepClosed, typed_learner_key
from egtviz.controllers.lesson_rules import RangeLimit
from egtviz.controllers.workbench_fields import FieldError
from egtviz.lessons import LessonRun, ProgressStore, load
from egtviz.lessons.tasks import CHOICE, NO_ANSWER, NUMBER
from egtviz.scene import SceneError
from egtviz.scene.lens import LensToggles

LESSON6 = "06-pinhole-epipolar"
RIGHT = "at the epipole e1, the image of cam2's centre"


@pytest.fixture
def store(tmp_path):
    return ProgressStore(tmp_path / "progress.sqlite3")


def controller(name: str, learner: str = "", store: ProgressStore | None = None) -> LessonController:
    return LessonController(LessonRun(load(name), learner, progress=store), progress=store)


def test_a_right_answer_passes_and_is_recorded(store):
    lesson = controller(LESSON6, "Ada", store)
    outcome = lesson.check("meet", RIGHT)
    assert outcome.passed and outcome.counted and outcome.hint is None and outcome.summary is None
    assert lesson.attempts["meet"].result.passed
    assert (0, "meet") in store.passed_tasks("Ada", LESSON6) and store.attempts("Ada", LESSON6, 0, "meet") == 1
    # The next time the step is shown (a reload, another tab), the task is passed before.
    again = controller(LESSON6, "Ada", store)
    assert [t.passed_before for t in again.step_state().tasks] == [True]


def test_a_wrong_answer_returns_its_hint_one_tier_more_each_time(store):
    lesson = controller(LESSON6, "Grace", store)
    first = lesson.check("meet", "at the principal point")
    assert not first.passed and first.counted and not first.unread
    assert first.hints_shown == 1 and "Every epipolar plane contains the baseline" in first.hint
    assert lesson.hint("meet") == first.hint
    second = lesson.check("meet", "at the principal point")
    assert second.hints_shown == 2 and second.hint.startswith(first.hint)
    # No choice made: no verdict, nothing counted, the hints earned so far stay.
    unread = lesson.check("meet", "")
    assert unread.unread and not unread.passed and unread.hints_shown == 2
    assert store.attempts("Grace", LESSON6, 0, "meet") == 2
    # A number: the feedback says which way it is off.
    rank = controller("07-fundamental-and-essential", "Grace", store).check("rank", "3")
    assert not rank.passed and "too high" in rank.feedback and rank.hint


def test_an_anonymous_learner_is_checked_and_nothing_is_kept(store):
    lesson = controller(LESSON6, "", store)
    assert lesson.run.progress is None
    assert not lesson.check("meet", "at the principal point").passed
    assert lesson.check("meet", RIGHT).passed
    assert lesson.run.summary().attempts == 2 and lesson.run.summary().passed == 1  # kept in the run only


def test_the_steps_tasks_declare_what_they_need_of_the_page():
    lesson = controller(LESSON6)
    state = lesson.step_state()
    assert (state.index, state.count, state.lesson_title) == (0, 3, lesson.run.lesson.title)
    assert state.percent == pytest.approx(100 / 3) and "<math" in state.html
    (meet,) = state.tasks
    assert (meet.number, meet.task_id, meet.passed_before) == (1, "meet", False)
    assert meet.needs.answer.widget == CHOICE and RIGHT in meet.needs.answer.options
    lesson.go_to(2)
    widgets = {t.task_id: t.needs.answer.widget for t in lesson.step_state().tasks}
    assert widgets == {"parallel": NO_ANSWER, "infinite-why": CHOICE}
    lens = controller("07-fundamental-and-essential")
    assert (lens.needs.lab, lens.needs.lens) == (False, True)
    assert lens.step_state().tasks[0].needs.answer.widget == NUMBER
    assert controller("10-robust-estimation").needs.lab


def test_next_previous_and_the_last_steps_summary(store):
    lesson = controller(LESSON6, "Ada", store)
    lesson.check("meet", "at the principal point")
    lesson.next()
    assert lesson.run.step_index == 1 and lesson.attempts == {} and store.current_step("Ada", LESSON6) == 1
    assert "cam2" in lesson.run.model.scene.locked
    lesson.previous()
    assert lesson.run.step_index == 0
    lesson.go_to(2)
    state = lesson.step_state()
    assert state.summary is not None and "Tasks passed: 0 of" in state.summary
    lesson.next()  # the last step: stays
    assert lesson.run.step_index == 2
    # A scene task: cam2 turned to look along the baseline's normal puts its epipole at infinity.
    assert not lesson.check("parallel", None).passed
    lesson.run.model.update_camera("cam2", ypr_deg=(-4.3987, 0.0, 0.0))
    outcome = lesson.check("parallel", None)
    assert outcome.passed and outcome.summary is not None and "Tasks passed: 1 of" in outcome.summary


def test_going_past_a_paced_step_is_refused():
    lesson = controller(LESSON6)
    lesson.may_enter = lambda name, step: name == LESSON6 and step <= 1
    lesson.next()
    assert lesson.run.step_index == 1
    with pytest.raises(StepClosed, match="step 3: the instructor has not opened it yet"):
        lesson.next()
    assert lesson.run.step_index == 1
    # Pacing tightened: the learner is held back, and only when past the step.
    assert lesson.hold_back(0) and lesson.run.step_index == 0
    assert not lesson.hold_back(0)


def test_a_scene_that_breaks_the_steps_lock_is_refused_and_not_counted(store):
    lesson = controller(LESSON6, "Ada", store)
    lesson.go_to(1)  # cam2 locked
    scene = lesson.run.model.scene
    moved = scene.replace(cameras=tuple(c.with_fields(position=(0.0, 0.0, 9.0)) if c.name == "cam2" else c
                                        for c in scene.cameras))
    lesson.run.model.load_scene(moved)
    outcome = lesson.check("epipole-target", None)
    assert not outcome.counted and not outcome.passed and "cam2 must stay where this step put it" in outcome.feedback
    assert "epipole-target" not in lesson.attempts and store.attempts("Ada", LESSON6, 1, "epipole-target") == 0
    lesson.reset_step()
    assert lesson.check("epipole-target", None).counted


def test_the_steps_ranges_are_the_models_constraints_in_the_fields_words():
    lesson = controller("03-intrinsics")
    index = next(i for i, s in enumerate(lesson.run.lesson.steps) if any(c.do == "set_range" for c in s.changes))
    lesson.go_to(index)
    assert RangeLimit("cam1", "focal length", "2 to 50 mm") in lesson.step_state().ranges
    assert lesson.constraints.refusal("cam1", {"focal_length": 0.06}) == (
        "In this step cam1's focal length must stay between 2 mm and 50 mm (it is 60 mm)")
    model = lesson.run.model
    with pytest.raises(SceneError, match="must stay between 2 mm and 50 mm"):
        model.update_camera("cam1", focal_length=0.06)
    scene = model.scene
    model.load_scene(scene.replace(cameras=tuple(c.with_fields(focal_length=0.06) if c.name == "cam1" else c
                                                 for c in scene.cameras)))
    task = lesson.step_state().tasks[0].task_id
    outcome = lesson.check(task, None)
    assert not outcome.counted and outcome.feedback.endswith("bring it back into that range and check again.")


def test_a_learners_name_switches_the_run_and_resumes_their_step(store):
    controller(LESSON6, "Ada", store).next()
    lesson = controller(LESSON6, "", store)
    model = lesson.run.model
    assert lesson.set_learner(typed_learner_key("  Ada "))
    assert lesson.run.learner == "Ada" and lesson.run.step_index == 1 and lesson.run.model is model
    assert not lesson.set_learner("Ada")
    assert typed_learner_key("   ") == ""
    with pytest.raises(FieldError, match="your name: expected text"):
        typed_learner_key(3)


def test_the_lab_and_the_lens_change_through_the_run():
    lab = controller("10-robust-estimation")
    lab.set_lab("noise_px", 2.5)
    assert lab.run.lab.noise_px == 2.5
    lens = controller("07-fundamental-and-essential")
    lens.go_to(2)  # F in place of F transposed, shown
    assert lens.lens_shown().f_transposed
    lens.toggle_lens("f_transposed", False)
    assert lens.run.lens == LensToggles() and lens.check("fix-transpose", None).passed
    lens.go_to(1)  # a hidden mistake: the boxes show what was switched, and ticking it repairs the lens
    assert lens.run.lens.wrong_singular_vector and not lens.lens_shown().any
    lens.toggle_lens("wrong_singular_vector", True)
    assert not lens.run.lens.any and lens.lens_shown().wrong_singular_vector
