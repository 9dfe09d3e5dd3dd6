"""The shipped course: every lesson validates, every step applies headlessly, and every task passes in a
solved state and fails in the step's starting state, for several learners (so several random draws)."""

from __future__ import annotations

import argparse
import math
import re

import numpy as np
import pytest
from scipy.optimize import least_squares

from egtviz.lessons import LessonError, LessonRun, list_lessons, load
from egtviz.lessons.catalog import lessons_folder
from egtviz.lessons.changes import MoveCamera
from egtviz.lessons.cli import run_lessons
from egtviz.lessons.tasks import EpipoleNearTask
from egtviz.lessons.tasks.computed import typed_text
from egtviz.scene.lab import run_lab

LEARNERS = ("", "Ada Lovelace", "Grace", "Émilie du Châtelet")
NAMES = [info.name for info in list_lessons()]


def test_the_course_has_at_least_twelve_numbered_lessons_with_known_prerequisites():
    assert len(NAMES) >= 12
    assert all(re.fullmatch(r"\d\d-[a-z0-9-]+", n) for n in NAMES)
    assert [int(n[:2]) for n in NAMES] == list(range(1, len(NAMES) + 1))
    for name in NAMES:
        lesson = load(name)
        assert lesson.title and lesson.summary and lesson.steps
        assert all(p in NAMES and p < name for p in lesson.prerequisites)  # earlier lessons only: no cycles
        assert sum(len(s.text) for s in lesson.steps) > 600  # real teaching text, not a stub
        assert lesson.task_count >= 2


def test_every_lesson_file_in_the_folder_is_in_the_catalog():
    files = sorted(f.name[:-5] for f in lessons_folder().iterdir() if f.name.endswith(".toml"))
    assert files == NAMES


def aim_epipole(run: LessonRun, task: EpipoleNearTask, params: dict) -> None:
    """Solve an epipole_near task: turn the camera (yaw, pitch) until the other centre is imaged at the target."""
    scene = run.model.scene
    name = task.camera
    other = next(n for n in scene.drawn_pair if n != name)
    spec = scene.camera(name)
    d = np.array(scene.camera(other).position) - np.array(spec.position)
    yaw0 = math.degrees(math.atan2(d[0], d[1]))  # EGT yaw turns the optical axis from +y towards +x
    pitch0 = math.degrees(math.atan2(d[2], math.hypot(d[0], d[1])))
    target = np.array([params["u"], params["v"]])

    def residual(x):
        cam = spec.with_pose(ypr_deg=(x[0], x[1], spec.ypr_deg[2])).camera()
        p = cam.project(scene.camera(other).position)
        return (p.pixels[0] - target) if p.in_front[0] else np.array([1e4, 1e4])

    fit = least_squares(residual, [yaw0, pitch0], xtol=1e-12, ftol=1e-12)
    run.apply(MoveCamera(name, ypr_deg=(float(fit.x[0]), float(fit.x[1]), spec.ypr_deg[2])))


def right_answer(task, run: LessonRun) -> str:
    if task.kind == "computed":  # computed from this learner's scene by the function the check uses
        return task.answer_text(run.model.scene)
    if task.kind == "servo_number":  # computed by simulating the step's servo run, as the demo does
        return f"{task.answer_for(run.demo):.12g}"
    return f"{task.answer:g}" if task.kind == "number" else task.answer


def wrong_answer(task, run: LessonRun) -> str:
    if task.kind == "computed":  # every component off by more than the tolerance (a line or F: a new scale)
        return typed_text(task.value(run.model.scene) + 10 * task.tolerance + 1)
    if task.kind in ("number", "servo_number"):
        return f"{float(right_answer(task, run)) + 10 * task.tolerance + 1:g}"
    return next(o for o in task.options if o != task.answer)


@pytest.mark.parametrize("name", NAMES)
def test_every_task_fails_at_the_start_of_its_step_and_passes_when_solved(name):
    lesson = load(name)
    for learner in LEARNERS:
        run = LessonRun(lesson, learner)
        for index in range(len(lesson.steps)):
            run.go_to(index)
            for resolved in run.tasks():
                t = resolved.task
                if t.question:
                    attempt = run.check(t.id, wrong_answer(t, run))
                    assert not attempt.result.passed, (name, index, t.id)
                    assert (attempt.hint is not None) == bool(t.hint)
                    assert run.check(t.id, right_answer(t, run)).result.passed
                    continue
                start = run.check(t.id)
                assert not start.result.passed, (name, index, t.id, learner, start.result.feedback)
                assert start.hint is not None  # every scene task has a hint for a failed attempt
                if t.solution:
                    for change in t.solution:
                        run.apply(change)
                else:
                    assert isinstance(t, EpipoleNearTask), f"{name}: task {t.id} has no solution"
                    aim_epipole(run, t, resolved.params)
                solved = run.check(t.id)
                assert solved.result.passed, (name, index, t.id, learner, solved.result.feedback)
                assert solved.hint is None
                run.reset_step()


def test_next_keeps_the_learners_scene_and_go_to_replays_the_steps():
    lesson = load("06-pinhole-epipolar")
    run = LessonRun(lesson)
    run.apply(MoveCamera("cam2", position=(2.0, -7.0, 2.0)))
    assert run.next() and run.step_index == 1
    assert run.model.scene.camera("cam2").position == (2.0, -7.0, 2.0)  # kept
    assert run.model.scene.locked == {"cam2"}  # step 1's change applied on top
    run.go_to(1)
    assert run.model.scene.camera("cam2").position == (3.5, -7.5, 2.5)  # the replayed start
    assert run.previous() and run.step_index == 0 and run.model.scene.selected_point == 6
    assert not run.previous()
    run.go_to(len(lesson.steps) - 1)
    assert not run.next()


def test_next_falls_back_to_the_replayed_start_when_the_learner_removed_what_a_step_changes():
    lesson = load("07-fundamental-and-essential")  # step 2 selects point 1 and turns the lens's F^T on
    run = LessonRun(lesson)
    run.go_to(1)
    for _ in range(7):
        run.model.remove_point(0)  # one point left: there is no point 1 to select
    assert run.next()
    assert run.step_index == 2 and len(run.model.scene.points) == 8  # replayed from the lesson's scene
    assert run.model.scene.selected_point == 1 and run.lens.f_transposed and not run.lens.wrong_singular_vector


def test_random_targets_differ_between_learners_and_show_in_the_prompt():
    lesson = load("06-pinhole-epipolar")
    prompts = set()
    for learner in ("Ada", "Bob", "Cy", "Di"):
        run = LessonRun(lesson, learner)
        run.go_to(1)
        (resolved,) = run.tasks()
        u, v = resolved.params["u"], resolved.params["v"]
        assert 100 <= u <= 540 and 80 <= v <= 400
        assert f"({u:g}, {v:g})" in resolved.prompt and "{u}" not in resolved.prompt_html
        prompts.add(resolved.prompt)
    assert len(prompts) == 4


def test_lab_questions_agree_with_the_lab():
    """The answers of the lab's multiple-choice questions are what the lab shows in that step's state."""
    run = LessonRun(load("09-estimating-f"))
    run.go_to(1)
    result = run_lab(run.model.scene, run.lab)
    worst = max(result.fits[:3], key=lambda f: f.sampson_true)
    assert worst.title == "linear 8-point" == next(t for t in run.step.tasks if t.id == "worse").answer
    run = LessonRun(load("10-robust-estimation"))
    result = run_lab(run.model.scene, run.lab)
    ruined = result.fit("normalized").sampson_true
    assert ruined > 100 * max(result.fit(m).sampson_true for m in ("ransac", "lmeds", "mestimator"))


def test_numeric_answers_agree_with_the_scene():
    """Answers typed in the lesson files, recomputed here from the scene (hand formulas in comments)."""
    run = LessonRun(load("02-pinhole-projection"))
    depth, u1 = (t.answer for t in run.step.tasks)
    cam = run.model.scene.camera("cam").camera()
    Xc = cam.pose.to_local([3.0, 3.0, -3.0])[0]
    assert depth == pytest.approx(21 / math.sqrt(2), abs=1e-5) == pytest.approx(Xc[2], abs=1e-5)  # (13 + 8) cos 45
    assert u1 == pytest.approx(run.model.derived.image_planes["cam"].points[1, 0], abs=1e-6)
    run = LessonRun(load("04-panoramic-cameras"))
    ccd, u = (t.answer for t in run.step.tasks)
    assert ccd == pytest.approx(2 * math.sqrt(10), abs=1e-6)
    assert u == pytest.approx(run.model.derived.image_planes["pano"].points[0, 0], abs=0.005)
    run = LessonRun(load("03-intrinsics"))
    assert run.step.tasks[1].answer == pytest.approx(math.degrees(2 * math.atan(240 / 800)), abs=1e-3)


def test_egtviz_lessons_prints_one_line_per_lesson_name_first(capsys):
    assert run_lessons(argparse.Namespace()) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == NAMES
    assert lines[0].split(None, 1)[1] == load(NAMES[0]).title


def test_an_installed_wheel_reads_the_lessons_bundled_in_the_package(tmp_path, monkeypatch):
    """In a wheel (no checkout around the package) the lessons sit in ``egtviz/_lessons`` (hatch force-include)."""
    from egtviz import resources
    from egtviz.lessons import catalog

    bundled = tmp_path / "site-packages" / "egtviz" / "_lessons"
    bundled.mkdir(parents=True)
    source = lessons_folder() / "01-frames-and-poses.toml"
    (bundled / "01-frames-and-poses.toml").write_bytes(source.read_bytes())
    monkeypatch.setattr(resources, "_PACKAGE", bundled.parent)
    assert catalog.lessons_folder() == bundled
    assert [info.name for info in list_lessons()] == ["01-frames-and-poses"]
    assert load("01-frames-and-poses").source == "lessons/01-frames-and-poses.toml"
    with pytest.raises(LessonError, match="no lesson of that name"):
        load("06-pinhole-epipolar")


def test_unified_lesson_answers_agree_with_the_model():
    """Lesson 5: the typed answers by hand, and what the slider steps claim, measured on the scene."""
    from egtviz.geometry.catadioptric import HyperbolicMirror

    lesson = load("05-unified-sphere")
    answers = {t.id: t for s in lesson.steps for t in s.tasks}
    e = math.sqrt(10.0)
    assert answers["tutorial-xi"].answer == pytest.approx(6 * e / 19, abs=1e-5)  # 2 a e / (2 a^2 + b^2), a=3, b=1
    assert HyperbolicMirror(3.0, 1.0).xi == pytest.approx(6 * e / 19, abs=1e-12)
    assert answers["horizon-radius"].answer == 300 / 0.5
    horizon = answers["horizon-400"]  # f / xi within 10 px of 400 with f = 300
    assert (horizon.low, horizon.high) == (pytest.approx(300 / 410, abs=1e-4), pytest.approx(300 / 390, abs=1e-4))
    run = LessonRun(lesson)
    run.go_to(1)
    assert run.model.scene.camera("uni").focal_pixels == 300

    def bend(xi: float) -> float:
        """Largest distance (px) of the line's images from the line through the first and last of them."""
        run.model.update_camera("uni", xi=xi)
        px = run.model.derived.image_planes["uni"].points
        a, b = px[0], px[-1]
        n = np.array([b[1] - a[1], a[0] - b[0]]) / np.hypot(*(b - a))
        return float(np.max(np.abs((px - a) @ n)))

    assert bend(0.0) < 1e-9  # xi = 0: the images of the points of one line are collinear
    assert bend(0.8) > 8.0  # the row bends: a conic
    assert answers["lines-at-zero"].answer == "straight lines"


def servo_run(name: str, step: int) -> LessonRun:
    run = LessonRun(load(name))
    run.go_to(step)
    assert run.demo is not None
    return run


def test_pinhole_servo_lesson_answers_agree_with_the_simulation():
    """Lesson 12: the choices about the runs, read off the simulations by plain scans of their error series."""
    from egtviz.servo import simulate_pinhole

    rotation_only = servo_run("12-visual-servoing", 3)
    assert rotation_only.demo.simulation_kwargs() == {"seed": 0, "noise_px": 0.0, "steps": 1000, "beta": 0.0,
                                                       "f_algorithm": None}
    r0 = simulate_pinhole(seed=0, beta=0.0)
    assert abs(r0.final_translation_error - r0.initial_translation_error) < 0.01 * r0.initial_translation_error
    assert next(t for t in rotation_only.step.tasks if t.id == "distance-compared").answer.startswith("about the same")
    hybrid = servo_run("12-visual-servoing", 4)
    r1 = simulate_pinhole(seed=0, beta=1.0)
    assert r1.converged

    def first(times, values, below):
        return next(float(t) for t, v in zip(times, values) if v < below)

    t_rot = first(r1.time, np.degrees(r1.errors["rotation_error_rad"]), 0.1)
    t_trans = first(r1.time, 100 * r1.errors["translation_error"], 1.0)
    assert t_rot < t_trans
    assert next(t for t in hybrid.step.tasks if t.id == "first-phase").answer == "the rotation error"
    # The secondary task acts in the null space of the priority task: the rotation converges as fast as alone.
    assert t_rot == pytest.approx(first(r0.time, np.degrees(r0.errors["rotation_error_rad"]), 0.1))
    assert hybrid.check("steps", str(r1.steps)).result.passed
    assert not hybrid.check("steps", str(r1.steps + 1)).result.passed
    assert hybrid.check("translation-time", f"{t_trans:g}").result.passed


def test_panoramic_servo_lesson_answers_agree_with_the_simulation():
    from egtviz.servo import simulate_panoramic

    run = servo_run("13-panoramic-servoing", 3)
    r = simulate_panoramic(seed=0)
    assert r.converged and r.extras["phase"][0] == 1  # the run starts in step 1, the rotation
    assert next(t for t in run.step.tasks if t.id == "first-phase").answer == "the rotation (step 1)"
    k = int(np.flatnonzero(r.extras["phase"] == 2)[0])
    assert run.check("switch-time", f"{r.time[k]:g}").result.passed
    assert run.check("start-heading", f"{math.degrees(r.initial_rotation_error_rad):.1f}").result.passed
    assert run.check("steps", str(r.steps)).result.passed
