"""Computed answers on a per-learner scene: the strict vector and matrix reading, the ``randomise_camera`` draw,
the answers computed by the core (checked against identities they must satisfy), two learners' answers that
differ, and every classic mistake recognised and named when its value is typed."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.lessons import LessonError, LessonRun, list_lessons, load
from egtviz.lessons.answers import AnswerError, read_matrix, read_vector
from egtviz.lessons.changes import RandomiseCamera, parse_change
from egtviz.lessons.errors import EntryError
from egtviz.lessons.format import parse_lesson
from egtviz.lessons.mistakes import MISTAKES, QUANTITIES, Where
from egtviz.lessons.proof import prove_counter_examples
from egtviz.lessons.tasks.computed import ComputedTask, distance, typed_text
from egtviz.scene import SceneModel

LEARNERS = ("Ada", "Grace", "Émilie du Châtelet")


def computed_tasks():
    """(lesson name, step index, task) of every computed task of the shipped course."""
    out = []
    for info in list_lessons():
        lesson = load(info.name)
        for i, step in enumerate(lesson.steps):
            out += [(info.name, i, t) for t in step.tasks if isinstance(t, ComputedTask)]
    return out


COMPUTED = computed_tasks()
MISTAKE_CASES = [(name, i, t.id, e.mistake) for name, i, t in COMPUTED
                 for e in load(name).steps[i].counter_examples_of(t.id)]
"""Each mistake a lesson names as a computed task's counter-example (the ones that apply in its scene)."""


def _run(name: str, step: int, learner: str) -> LessonRun:
    run = LessonRun(load(name), learner)
    run.go_to(step)
    return run


# -- typed vectors and matrices ------------------------------------------------------------------------------

def test_a_vector_is_read_in_brackets_with_its_unit_and_nothing_else():
    assert read_vector("[0.2, -0.1]", 2) == (0.2, -0.1)
    assert read_vector("  [1e2,3.5]px ", 2, "px") == (100.0, 3.5)
    assert read_vector("[1, 2] PX", 2, "px") == (1.0, 2.0)
    for text, why in (("0.2, -0.1", "in brackets"), ("[1, 2, 3]", "got 3 numbers"), ("[1, two]", "'two' is not"),
                      ("[1_0, 2]", "'1_0' is not"), ("[1, 2] m", "got"), ("[1e400, 2]", "too large"),
                      ("", "Type 2 numbers"), ("[[1, 2]]", "got")):
        with pytest.raises(AnswerError, match=why):
            read_vector(text, 2, "px" if "px" in why else "")
    with pytest.raises(AnswerError, match="got 2 numbers"):  # a decimal comma reads as two numbers, not 1.5
        read_vector("[1,5]", 3)


def test_a_matrix_is_read_row_by_row_in_either_layout():
    rows = ((1.0, 2.0, 3.0), (4.0, 5.0, 6.0), (7.0, 8.0, -9.5))
    assert read_matrix("[[1, 2, 3], [4, 5, 6], [7, 8, -9.5]]", 3, 3) == rows
    assert read_matrix("[1, 2, 3; 4, 5, 6; 7, 8, -9.5]", 3, 3) == rows
    for text, why in (("[1, 2, 3, 4, 5, 6, 7, 8, 9]", "got"), ("[[1, 2, 3], [4, 5, 6]]", "got 2 rows"),
                      ("[1, 2, 3; 4, 5; 7, 8, 9]", "row 2 has 2 numbers"), ("[[1, 2, 3] [4, 5, 6] [7, 8, 9]]",
                                                                             "separate the rows"),
                      ("[1, 2, 3; 4, 5, x; 7, 8, 9]", "'x' is not a number"), ("F", "got 'F'")):
        with pytest.raises(AnswerError, match=why):
            read_matrix(text, 3, 3)


def test_hostile_matrix_text_is_refused_at_once_and_no_stray_mark_is_taken_for_a_row():
    # A nested pattern with repeated optional whitespace backtracks exponentially on text like this; the
    # reader scans the rows without one, so these return (refused) instead of hanging the server.
    for text in ("[" + "[1]      " * 25 + "x", "[" + "[1]," * 60 + "]x", "[[" + " ," * 90 + "]]",
                 "[#, [1, 2, 3], [4, 5, 6], [7, 8, 9]]"):
        with pytest.raises(AnswerError):
            read_matrix(text, 3, 3)


def test_a_computed_answer_that_is_not_the_quantitys_shape_is_refused_with_what_to_type():
    name, i, task = next(c for c in COMPUTED if c[2].quantity == "fundamental")
    run = _run(name, i, "Ada")
    attempt = run.check(task.id, "[1, 2, 3]")
    assert not attempt.result.passed
    assert attempt.result.feedback.startswith("Type a 3 x 3 matrix row by row")


# -- the learner's own scene ---------------------------------------------------------------------------------

def test_randomise_camera_is_read_strictly():
    change = parse_change({"do": "randomise_camera", "camera": "cam2", "position": [[1, 2], 0.5, [-1, 1]],
                           "focal_length": [0.006, 0.012]})
    assert change == RandomiseCamera("cam2", position=((1.0, 2.0), (0.5, 0.5), (-1.0, 1.0)),
                                     focal_length=(0.006, 0.012))
    for table, key in (({"position": [[2, 1], 0, 0]}, "position"), ({"position": [0, 0]}, "position"),
                       ({"ypr_deg": [[0, 1, 2], 0, 0]}, "ypr_deg"), ({}, "position"),
                       ({"focal_length": [0.012, 0.006]}, "focal_length"),
                       ({"focal_length": [-1, 0.01]}, "focal_length")):
        with pytest.raises(EntryError) as err:
            parse_change({"do": "randomise_camera", "camera": "cam2", **table})
        assert err.value.key == key


def test_each_learner_gets_their_own_camera_the_same_every_time_within_the_ranges():
    name, i, _ = next(c for c in COMPUTED if c[0] == "03-intrinsics")
    poses = {}
    for learner in LEARNERS:
        run = _run(name, i, learner)
        cam2 = run.model.scene.camera("cam2")
        again = _run(name, i, learner).model.scene.camera("cam2")
        assert again == cam2  # the same learner, a new run (or a reload): the same camera
        run.next() if run.step_index + 1 < len(run.lesson.steps) else None
        run.go_to(i)
        assert run.model.scene.camera("cam2") == cam2  # "reset step" replays the same draw
        assert 3.0 <= cam2.position[0] <= 4.0 and -28.0 <= cam2.ypr_deg[0] <= -22.0
        assert 0.006 <= cam2.focal_length <= 0.012 and 300 <= cam2.principal_point[0] <= 340
        assert all(round(x, 2) == x for x in (*cam2.position, *cam2.ypr_deg, *cam2.principal_point))
        poses[learner] = (cam2.position, cam2.ypr_deg, cam2.focal_length)
    assert len(set(poses.values())) == len(LEARNERS)


def test_randomise_point_is_read_strictly():
    change = parse_change({"do": "randomise_point", "point": 1, "position": [[2, 4], 3, [-4, -2]]})
    assert (change.do, change.point, change.position) == ("randomise_point", 1, ((2.0, 4.0), (3.0, 3.0), (-4.0, -2.0)))
    for table, key in (({"point": 1, "position": [[4, 2], 0, 0]}, "position"), ({"point": 1, "position": [0, 0]},
                       "position"), ({"point": 1}, "position"), ({"position": [0, 0, 0]}, "point"),
                       ({"point": -1, "position": [0, 0, 0]}, "point"),
                       ({"point": 1, "position": [0, 0, 0], "camera": "cam"}, "camera")):
        with pytest.raises(EntryError) as err:
            parse_change({"do": "randomise_point", **table})
        assert err.value.key == key


def test_each_learner_gets_their_own_points_the_same_every_time_within_the_ranges():
    """Lesson 2's last step draws points 2 and 4 per learner too (before, only the camera was theirs: every
    learner read the same points from the point list)."""
    name = "02-pinhole-projection"
    step = len(load(name).steps) - 1
    drawn = {}
    for learner in LEARNERS:
        run = _run(name, step, learner)
        points = run.model.scene.points
        assert _run(name, step, learner).model.scene.points == points  # a reload: the same points
        run.go_to(step)
        assert run.model.scene.points == points  # "reset step" replays the same draw
        (x1, y1, z1), (x3, y3, z3) = points[1], points[3]
        assert 2 <= x1 <= 4 and 2 <= y1 <= 4 and -4 <= z1 <= -2 and -4 <= x3 <= -2 and 2 <= y3 <= 4 and 2 <= z3 <= 4
        assert all(round(c, 2) == c for c in (*points[1], *points[3]))
        assert points[0] == (-3.0, 3.0, -3.0) and points[2] == (3.0, 3.0, 3.0)  # the others stay the lesson's
        drawn[learner] = (points[1], points[3])
    assert len(set(drawn.values())) == len(LEARNERS)


def test_the_course_has_at_least_15_computed_tasks_over_8_lessons_each_with_a_mistake_counter_example():
    assert len(COMPUTED) >= 15
    assert len({name for name, _, _ in COMPUTED}) >= 8
    for name, i, task in COMPUTED:
        examples = load(name).steps[i].counter_examples_of(task.id)
        assert examples and all(e.mistake for e in examples), (name, task.id)


@pytest.mark.parametrize(("name", "step", "task"), COMPUTED, ids=[f"{n}:{t.id}" for n, _, t in COMPUTED])
def test_two_learners_get_two_answers_and_each_is_accepted_only_for_its_own_scene(name, step, task):
    runs = [_run(name, step, learner) for learner in LEARNERS[:2]]
    answers = [task.answer_text(r.model.scene) for r in runs]
    assert answers[0] != answers[1]
    values = [task.value(r.model.scene) for r in runs]
    assert distance(values[0], values[1], task.spec.up_to_scale) > task.tolerance
    for run, own, other in ((runs[0], answers[0], answers[1]), (runs[1], answers[1], answers[0])):
        assert run.check(task.id, own).result.passed
        assert not run.check(task.id, other).result.passed


# -- mistakes, each typed and named --------------------------------------------------------------------------

@pytest.mark.parametrize(("name", "step", "task_id", "mistake"), MISTAKE_CASES,
                         ids=[f"{n}:{t}:{m}" for n, _, t, m in MISTAKE_CASES])
def test_a_typed_mistake_is_named_with_why_it_is_wrong(name, step, task_id, mistake):
    for learner in LEARNERS:
        run = _run(name, step, learner)
        task = next(t for t in run.step.tasks if t.id == task_id)
        spec = next(m for m in task.spec.mistakes if m.name == mistake)
        attempt = run.check(task_id, task.mistake_text(mistake, run.model.scene))
        assert not attempt.result.passed
        assert f"is {spec.title}: {spec.why}." in attempt.result.feedback, attempt.result.feedback


def test_at_least_ten_different_mistakes_are_diagnosed_in_the_course():
    assert len({m for *_, m in MISTAKE_CASES}) >= 10
    documented = open("docs/lessons.md", encoding="utf-8").read()
    for mistake in {m for *_, m in MISTAKE_CASES}:
        assert f"| `{mistake}` |" in documented


def test_the_misconception_list_names_every_lesson_that_diagnoses_each_mistake():
    """docs/lessons.md's "taught in" column lists each lesson whose computed task names the mistake (before,
    ``normalised_for_pixels`` said lesson 3 only, although lesson 7's epipole task diagnoses it too)."""
    documented = open("docs/lessons.md", encoding="utf-8").read()
    missing = []
    for name, _, _, mistake in MISTAKE_CASES:
        row = re.search(rf"^\| `{mistake}` \|.*\|([^|]*)\|$", documented, re.M)
        assert row, mistake
        taught = {int(n) for n in re.findall(r"\b(\d{1,2})\b(?=[.,]|\s*$)", row.group(1))}
        if int(name[:2]) not in taught:
            missing.append((mistake, name))
    assert missing == []


def test_a_wrong_answer_that_is_no_known_mistake_says_only_how_far():
    name, i, task = next(c for c in COMPUTED if c[2].quantity == "pixel" and c[2].camera == "cam2")
    run = _run(name, i, "Ada")
    u, v = task.value(run.model.scene)
    attempt = run.check(task.id, f"[{u + 7:.3f}, {v - 3:.3f}]")
    assert not attempt.result.passed
    assert attempt.result.feedback.endswith("is not within 0.5 px of the answer.")
    assert run.check(task.id, f"[{u + 0.3:.3f}, {v - 0.3:.3f}] px").result.passed  # within 0.5 px


def test_f_transposed_is_named_and_an_f_at_another_scale_or_sign_is_right():
    name, i, task = next(c for c in COMPUTED if c[2].quantity == "fundamental")
    run = _run(name, i, "Grace")
    F = task.value(run.model.scene)
    assert run.check(task.id, typed_text(-250.0 * F)).result.passed
    feedback = run.check(task.id, typed_text(3.0 * F.T)).result.feedback
    assert feedback.endswith("is F transposed: with m2^T F m1 = 0, F maps points of image 1 to lines of image 2; "
                             "F^T goes the other way.")


def test_degrees_typed_as_radians_are_named():
    name, i, task = next(c for c in COMPUTED if c[2].quantity == "angle_deg")
    run = _run(name, i, "Ada")
    degrees = float(task.value(run.model.scene))
    feedback = run.check(task.id, f"{math.radians(degrees):.6f}").result.feedback
    assert "radians, not degrees" in feedback
    assert run.check(task.id, f"{degrees:.4f} deg").result.passed


# -- the core's answers satisfy what they must ---------------------------------------------------------------

@settings(max_examples=25, deadline=None)
@given(st.text(alphabet="abcdefghij ", min_size=1, max_size=12))
def test_computed_answers_satisfy_the_epipolar_identities_for_any_learner(learner):
    name, i, _ = next(c for c in COMPUTED if c[0] == "07-fundamental-and-essential")
    run = _run(name, i, learner)
    scene = run.model.scene
    cam1, cam2 = scene.camera("cam1").camera(), scene.camera("cam2").camera()
    where = Where("cam1", "cam2", 2)
    F = QUANTITIES["fundamental"].value(scene, where)
    e1 = QUANTITIES["epipole"].value(scene, Where("cam1", "cam2"))
    line = QUANTITIES["epipolar_line"].value(scene, where)
    m1 = cam1.project(np.array(scene.points[2])[None, :]).pixels[0]
    m2 = cam2.project(np.array(scene.points[2])[None, :]).pixels[0]
    h1, h2 = np.append(m1, 1.0), np.append(m2, 1.0)
    assert abs(h2 @ F @ h1) < 1e-9 * np.linalg.norm(F) * np.linalg.norm(h1) * np.linalg.norm(h2)
    assert np.linalg.norm(F @ np.append(e1, 1.0)) < 1e-9 * np.linalg.norm(F) * np.linalg.norm(np.append(e1, 1.0))
    assert abs(line @ h1) / math.hypot(line[0], line[1]) < 1e-6  # m1 lies on its line l1 = F^T m2 (pixels)
    E = QUANTITIES["essential"].value(scene, where)
    K1, K2 = cam1.K, cam2.K
    assert distance(np.linalg.inv(K2).T @ E @ np.linalg.inv(K1), F, "pixels") < 1e-9


@settings(max_examples=25, deadline=None)
@given(st.text(alphabet="klmnopqrst ", min_size=1, max_size=12))
def test_depth_pixel_and_camera_coordinates_agree_with_the_projection(learner):
    name, i, _ = next(c for c in COMPUTED if c[0] == "01-frames-and-poses")
    scene = _run(name, i, learner).model.scene
    cam = scene.camera("cam1").camera()
    X = np.array(scene.points[4])
    projection = cam.project(X[None, :])
    xc = QUANTITIES["camera_coordinates"].value(scene, Where("cam1", None, 4))
    assert float(QUANTITIES["depth"].value(scene, Where("cam1", None, 4))) == pytest.approx(projection.depth[0])
    assert np.allclose(cam.pose.R @ xc + cam.centre, X)  # back to the world
    assert np.allclose((cam.K @ xc)[:2] / xc[2], projection.pixels[0])
    assert np.isclose(np.linalg.norm(xc), np.linalg.norm(X - cam.centre))


# -- the proof --------------------------------------------------------------------------------------------------

LESSON = """
title = "Computed"
summary = "A computed task."
scene = "default"
[[steps]]
title = "Yours"
text = "Your own camera."
[[steps.changes]]
do = "randomise_camera"
camera = "cam2"
position = [[3.0, 4.0], [-8.0, -7.0], [2.0, 3.0]]
[[steps.tasks]]
id = "F"
kind = "computed"
quantity = "fundamental"
camera = "cam1"
other = "cam2"
tolerance = TOL
prompt = "Type F."
[[steps.tasks.counter_examples]]
why = "F transposed"
mistake = "MISTAKE"
"""


def _lesson(tol: str = "0.01", mistake: str = "f_transposed"):
    return parse_lesson(LESSON.replace("TOL", tol).replace("MISTAKE", mistake), source="c.toml", name="c")


def test_egtviz_check_proves_a_computed_task_solvable_and_its_mistakes_refused():
    prove_counter_examples(_lesson())
    with pytest.raises(LessonError, match=r"c.toml:\d+: task F: counter-example 1 passes"):
        prove_counter_examples(_lesson(tol="1.9"))  # so loose that F^T passes: the proof refuses the lesson


def test_a_counter_example_naming_a_mistake_the_quantity_does_not_have_is_refused():
    with pytest.raises(LessonError, match="mistake: expected one of e_for_f, f_transposed, got 'f_for_e'"):
        _lesson(mistake="f_for_e")


def test_every_quantity_has_its_mistakes_and_every_mistake_list_a_quantity():
    assert set(MISTAKES) <= set(QUANTITIES)
    assert sum(len(v) for v in MISTAKES.values()) >= 10


def test_a_scene_without_the_point_the_task_reads_fails_with_the_way_back():
    name, i, task = next(c for c in COMPUTED if c[2].point is not None and c[0] == "02-pinhole-projection")
    run = _run(name, i, "Ada")
    model: SceneModel = run.model
    while len(model.scene.points) > task.point:
        model.remove_point(len(model.scene.points) - 1)
    attempt = run.check(task.id, "1")
    assert not attempt.result.passed and "reset step" in attempt.result.feedback
