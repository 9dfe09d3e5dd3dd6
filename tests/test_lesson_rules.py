"""A lesson's rules hold by every route, headless: undo stops at a step's start, locks hold for typed values,
a task whose camera or point has gone says so, and a typed number is read strictly."""

from __future__ import annotations

import pytest

from egtviz.lessons import LessonRun, load
from egtviz.lessons.answers import AnswerError, read_number
from egtviz.lessons.changes import SetField
from egtviz.lessons.tasks import TaskContext, parse_task
from egtviz.scene import SCENES, SceneError, SceneModel

INTRINSICS = "03-intrinsics"


def zoom_step() -> LessonRun:
    """Lesson 3 at its step 2: cam1 at 30 mm, locked, its focal length limited to 2..50 mm."""
    run = LessonRun(load(INTRINSICS))
    run.go_to(1)
    assert run.model.scene.locked == {"cam1"} and run.model.scene.camera("cam1").focal_length == 0.03
    return run


def task_ids(run: LessonRun) -> list[str]:
    return [r.task.id for r in run.tasks()]


# -- undo and locks ---------------------------------------------------------------------------------------


def test_undo_cannot_take_back_a_steps_own_changes():
    run = zoom_step()
    start = run.model.scene
    assert not run.model.undo() and not run.model.undo()  # the step's changes: focal length 30 mm, the lock
    assert run.model.scene is start and run.model.scene.locked == {"cam1"}
    assert "Undo stops at the start of this step" in run.model.undo_barrier_note
    assert all(not run.check(t).result.passed for t in task_ids(run))  # no work, no pass
    with pytest.raises(SceneError, match="cam1: the camera is locked"):
        run.model.update_camera("cam1", position=(0.0, -8.0, 1.5))  # still locked
    # What the learner does in the step can be undone, down to the step's start and no further.
    run.apply(SetField("cam1", "focal_length", 0.008))
    assert all(run.check(t).result.passed for t in task_ids(run))
    assert run.model.undo() and not run.model.undo()
    assert run.model.scene is start


def test_reset_comes_back_to_the_steps_start_not_the_lessons_scene():
    run = zoom_step()
    start = run.model.scene
    run.apply(SetField("cam1", "focal_length", 0.02))
    run.model.reset()  # the workbench's Reset button
    assert run.model.scene is start and run.model.scene.locked == {"cam1"}


def test_a_locked_cameras_pose_cannot_be_typed_but_its_intrinsics_can():
    run = zoom_step()
    before = run.model.scene.camera("cam1")
    for fields in ({"position": (1.0, -8.0, 2.0)}, {"ypr_deg": (5.0, 0.0, 0.0)}):
        with pytest.raises(SceneError, match="cam1: the camera is locked in this step"):
            run.model.update_camera("cam1", **fields)
    assert run.model.scene.camera("cam1") is before
    run.model.update_camera("cam1", focal_length=0.01)  # the step asks for exactly this
    assert run.model.scene.camera("cam1").position == before.position


def test_the_next_step_may_move_what_an_earlier_step_locked():
    run = LessonRun(load("06-pinhole-epipolar"))  # step 2 locks cam2; step 3 locks cam1 and unlocks cam2
    run.go_to(1)
    assert not run.model.undo()
    assert run.next() and run.model.scene.locked == {"cam1"} and not run.model.undo()
    run.go_to(2)  # replays every earlier step's changes, locks and all
    assert run.model.scene.locked == {"cam1"}


# -- a task whose camera or point has gone --------------------------------------------------------------------

KINDS = {
    "epipole_near": dict(camera="cam2", target={"u": 320, "v": 240}, within_px=5),
    "same_orientation": dict(cameras=["cam1", "cam2"], within_deg=5),
    "lines_parallel": dict(camera="cam2", within_deg=1),
    "point_on_line": dict(point=0, camera="cam2", within_px=1),
    "sampson_below": dict(method="normalized", below_px2=1),
    "inliers_recall": dict(method="ransac", at_least=0.9),
    "point_in_image": dict(point=0, camera="cam2"),
    "camera_field": dict(camera="cam2", field="focal_length", low=0.001, high=0.1),
    "xi_between": dict(camera="cam2", low=0, high=1),
    "triangulation_error": dict(point=0, noise_px=1, at_most=0.1),
}


def without_cam2():
    model = SceneModel(SCENES["default"]())
    model.remove_camera("cam2")
    return model.scene


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_scene_task_says_what_is_missing_when_a_camera_has_gone(kind):
    t = parse_task({"kind": kind, "prompt": "x", **KINDS[kind]}, "t1")
    t.validate(SCENES["default"]())  # a valid task of the step's scene
    result = t.check(TaskContext(without_cam2()), t.resolve(0))
    assert not result.passed
    if kind in ("sampson_below", "inliers_recall", "triangulation_error"):  # they measure the drawn pair
        assert result.feedback.startswith("the scene has fewer than two cameras: no pair is drawn")
    else:
        assert result.feedback.startswith("cam2 is not in the scene any more")
    assert result.feedback.endswith("press \u201creset step\u201d to start this step again.")


@pytest.mark.parametrize("kind", ["point_in_image", "point_on_line", "triangulation_error"])
def test_a_task_whose_point_has_gone_says_so(kind):
    t = parse_task({"kind": kind, "prompt": "x", **KINDS[kind], "point": 7}, "t1")
    model = SceneModel(SCENES["default"]())
    model.set_points([(0.0, 0.0, 1.0), (0.5, 0.0, 1.0), (0.0, 0.5, 1.0)])
    result = t.check(TaskContext(model.scene), t.resolve(0))
    assert not result.passed and result.feedback.startswith("point 8 is not in the scene any more (it has 3 points)")


def test_another_built_in_scene_opened_in_a_lesson_fails_the_check_with_the_reason():
    run = zoom_step()
    run.model.load_scene(SCENES["example2"]())  # a panoramic scene: no cam1
    attempt = run.check("zoom-out")
    assert not attempt.result.passed
    assert attempt.result.feedback == ("cam1 is not in the scene any more: "
                                       "press \u201creset step\u201d to start this step again.")


def test_a_camera_field_task_on_a_camera_of_another_kind_says_the_field_has_gone():
    t = parse_task({"kind": "camera_field", "prompt": "x", "camera": "pano", "field": "focal_length",
                    "low": 0.001, "high": 0.1}, "t1")
    result = t.check(TaskContext(SCENES["example2"]()), t.resolve(0))  # "pano" is a panoramic camera
    assert not result.passed and result.feedback.startswith("pano has no focal length any more")


# -- typed numbers --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("text, unit, value", [
    ("14.85", "", 14.85), ("  14.85 \n", "", 14.85), ("-3", "", -3.0), ("+.5", "", 0.5), ("8e2", "", 800.0),
    ("1.5E-3", "", 0.0015), ("7.", "", 7.0), ("800 px", "px", 800.0), ("800px", "px", 800.0),
    ("33.4 DEG", "deg", 33.4), ("800", "px", 800.0),
])
def test_one_number_optionally_with_the_tasks_unit_is_read(text, unit, value):
    assert read_number(text, unit) == value


@pytest.mark.parametrize("text, unit, words", [
    ("14.85.3", "", "got '14.85.3'"),
    ("14.85 is my answer", "", "Type one number, e.g. 2.5;"),
    ("14.85\n7", "", "Type one number"),
    ("0x0E", "", "Type one number"),
    ("14_85", "", "Type one number"),
    ("1,5", "", "Write the decimals after a point: 1.5, not 1,5."),
    ("1,5 px", "px", "Write the decimals after a point: 1.5"),
    ("1,5,3", "", "Type one number"),
    ("800 px", "", "Type one number"),  # a task without a unit takes none
    ("800 mm", "px", "(in px: 2.5 or 2.5 px)"),
    ("px", "px", "Type one number"),
    ("", "", "Type one number, e.g. 2.5."),
    ("inf", "", "Type one number"),
    ("nan", "", "Type one number"),
    ("1e400", "", "is too large"),
    ("\u0661\u0664", "", "Type one number"),  # Arabic-Indic digits, which float() would read as 14
])
def test_anything_but_one_number_is_refused_with_what_was_expected(text, unit, words):
    with pytest.raises(AnswerError) as caught:
        read_number(text, unit)
    assert words in str(caught.value)


def test_a_number_task_refuses_a_lenient_reading_of_its_answer():
    t = parse_task({"kind": "number", "prompt": "x", "answer": 14.85, "tolerance": 0.01}, "t1")
    for text in ("14.85.3", "14.85 is my answer", "14.85\n7"):
        result = t.check(TaskContext(SCENES["default"](), answer=text), t.resolve(0))
        assert not result.passed and "Type one number" in result.feedback
    assert t.check(TaskContext(SCENES["default"](), answer="14.85"), t.resolve(0)).passed
    one = parse_task({"kind": "number", "prompt": "x", "answer": 1.5, "tolerance": 0.01}, "t2")
    result = one.check(TaskContext(SCENES["default"](), answer="1,5"), one.resolve(0))
    assert not result.passed and "1.5, not 1,5" in result.feedback
