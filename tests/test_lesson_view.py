"""The lessons in the viewer, headless: the start page, the runner panel, progress across a restart, the
estimation lab's sliders and the convention lens's toggles, driven through their GUI handles (assigning a
handle's ``value`` runs its callbacks, as a click or a keystroke in the browser does)."""

from __future__ import annotations

import math
import re
import types
from contextlib import contextmanager

import numpy as np
import pytest
import viser
from scipy.optimize import least_squares

from egtviz.lessons import ProgressStore, load
from egtviz.scene import SceneError
from egtviz.viewer.tabs import EgtvizApp
from egtviz.controllers.workbench_fields import format_number
from egtviz.viewer.server.headless import FakeTab
from egtviz.controllers.lesson_instruments import lesson_instruments
from egtviz.controllers.lesson_rules import range_refusal
from egtviz.viewer.course.lesson_view import (
    CHOOSE,
    LessonPanel,
)
from egtviz.viewer.course.start_page import StartPage

from _waiting import PATIENCE, wait_for

LESSON6 = "06-pinhole-epipolar"


@contextmanager
def course(progress: ProgressStore, field_delay: float = 0.0, **kwargs):
    """A server serving the course, with ``open_tab()`` connecting one more fake browser tab."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, field_delay=field_delay, course=True, progress=progress, **kwargs)
    tabs: list[FakeTab] = []

    def open_tab() -> FakeTab:
        tabs.append(FakeTab(server.get_port()))
        return tabs[-1]

    try:
        yield app, open_tab
    finally:
        for t in tabs:
            t.close()
        server.stop()


@pytest.fixture
def store(tmp_path):
    return ProgressStore(tmp_path / "progress.sqlite3")


def start_page(app: EgtvizApp, count: int = 1) -> StartPage:
    return app.course.wait_for_tab(StartPage, count=count, timeout=PATIENCE)[-1]


def open_lesson(app: EgtvizApp, page: StartPage, name: str) -> LessonPanel:
    page.buttons[name].value = True
    (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
    return panel


def answer(panel: LessonPanel, task_id: str, text: str | None = None):
    """Type (or choose) an answer and press the task's Check button; returns the attempt."""
    row = panel.row(task_id)
    if text is not None:
        row.answer.value = text
    row.button.value = True
    return panel.attempts[task_id]


def next_step(panel: LessonPanel) -> None:
    panel.nav.buttons.value = "next"


def aim_ypr(scene, name: str, u: float, v: float) -> tuple[float, float, float]:
    """Yaw and pitch (deg) that image the other camera's centre at (u, v): solved here by least squares on the
    camera's own projection, independently of the lesson's check."""
    other = next(n for n in scene.drawn_pair if n != name)
    spec = scene.camera(name)
    centre = np.array(scene.camera(other).position)
    d = centre - np.array(spec.position)
    start = [math.degrees(math.atan2(d[0], d[1])), math.degrees(math.atan2(d[2], math.hypot(d[0], d[1])))]

    def residual(x):
        p = spec.with_pose(ypr_deg=(x[0], x[1], spec.ypr_deg[2])).camera().project(centre)
        return p.pixels[0] - (u, v) if p.in_front[0] else np.array([1e4, 1e4])

    fit = least_squares(residual, start, xtol=1e-12, ftol=1e-12)
    return float(fit.x[0]), float(fit.x[1]), float(spec.ypr_deg[2])


def type_ypr(panel: LessonPanel, camera: str, ypr: tuple[float, float, float]) -> None:
    panel.view.cameras[camera].fields["ypr"].value = ", ".join(f"{a:.6f}" for a in ypr)


def svg_kinds(svg: str, kind: str) -> int:
    return len(re.findall(f'data-kind="{kind}"', svg))


def test_lesson_6_walked_from_start_to_finish_through_the_panel(store):
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        page.name.value = "Ada"
        assert 'data-status="not started"' in page.status[LESSON6].content
        panel = open_lesson(app, page, LESSON6)
        assert panel.run.learner == "Ada" and panel.run.step_index == 0
        assert 'data-step="0"' in panel.nav.head.content and panel.nav.bar.value == pytest.approx(100 / 3)
        assert "<math" in panel.text.content  # the step's formulas as MathML
        # Step 1: the selected point's plane is shown; a choice task.
        assert panel.view.model.scene.selected_point == 6 and panel.view.model.scene.options.show_planes
        assert answer(panel, "meet", "at the epipole e1, the image of cam2's centre").result.passed
        assert "Passed" in panel.row("meet").feedback.content
        next_step(panel)
        # Step 2: cam2 locked; cam1's epipole steered to this learner's target by typing its angles.
        assert panel.run.step_index == 1 and "cam2" in panel.view.model.scene.locked
        params = panel.run.tasks()[0].params
        assert f"({params['u']:g}, {params['v']:g})" in panel.row("epipole-target").prompt.content
        assert not answer(panel, "epipole-target").result.passed
        type_ypr(panel, "cam1", aim_ypr(panel.view.model.scene, "cam1", params["u"], params["v"]))
        attempt = answer(panel, "epipole-target")
        assert attempt.result.passed, attempt.result.feedback
        next_step(panel)
        # Step 3: parallel epipolar lines in cam2 by turning it to look along the baseline's normal.
        assert panel.run.step_index == 2 and "cam1" in panel.view.model.scene.locked
        assert not answer(panel, "parallel").result.passed
        type_ypr(panel, "cam2", (-4.3987, 0.0, 0.0))
        e2 = panel.view.model.derived.pair.e2
        assert abs(e2[2]) < 1e-3 * np.linalg.norm(e2)  # the epipole is (nearly) at infinity
        assert answer(panel, "parallel").result.passed
        assert answer(panel, "infinite-why", "the epipole is at infinity").result.passed
        panel.nav.buttons.value = "next"  # the last step: stays
        assert panel.run.step_index == 2
        # Back to the course: the lesson is done for this learner.
        panel.btn_back.value = True
        page = start_page(app)
        assert page.learner == "Ada"
        assert 'data-status="done"' in page.status[LESSON6].content


def test_a_wrong_answer_is_refused_with_its_hint_and_counted(store):
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        page.name.value = "Grace"
        panel = open_lesson(app, page, LESSON6)
        attempt = answer(panel, "meet", "at the principal point")
        assert not attempt.result.passed
        shown = panel.row("meet").feedback.content
        assert "Not yet" in shown and "Hint:" in shown and "Every epipolar plane contains the baseline" in shown
        # No choice made: refused, not passed, and not counted (it is no answer).
        assert not answer(panel, "meet", CHOOSE).result.passed
        assert store.attempts("Grace", LESSON6, 0, "meet") == 1
        assert (0, "meet") not in store.passed_tasks("Grace", LESSON6)
        # A number task: a wrong number says which way it is off, and the hint follows.
        panel.btn_back.value = True
        panel = open_lesson(app, start_page(app), "07-fundamental-and-essential")
        wrong = answer(panel, "rank", "3")
        assert not wrong.result.passed and "too high" in wrong.result.feedback
        assert "Hint:" in panel.row("rank").feedback.content
        assert answer(panel, "rank", "2").result.passed
        assert "Hint:" not in panel.row("rank").feedback.content


def fire(handle, value) -> None:
    """What viser does for a value from the browser: store it unconverted and run the handle's callbacks."""
    handle._impl.value = value
    for cb in handle._impl.update_cb:
        cb(types.SimpleNamespace(target=handle, client=None, client_id=None))


def test_forged_answers_and_buttons_become_notifications_not_crashes(store):
    with course(store) as (app, open_tab):
        open_tab()
        panel = open_lesson(app, start_page(app), LESSON6)
        told = []
        panel.view.client.add_notification = lambda title, body, **_: told.append(body)
        fire(panel.row("meet").answer, "not an option")  # what a hand-written client could send
        panel.row("meet").button.value = True
        assert "meet" not in panel.attempts and told[-1] == "answer 1: not one of the options"
        fire(panel.nav.buttons, "jump")
        assert panel.run.step_index == 0 and told[-1] == "step: no button 'jump'"
        fire(panel.learner, 12)
        assert told[-1] == "your name: expected text, got int"
        panel.row("meet").answer.value = "at the epipole e1, the image of cam2's centre"
        panel.row("meet").button.value = True
        assert panel.attempts["meet"].result.passed  # the tab carries on


def test_progress_survives_a_server_restart(tmp_path):
    path = tmp_path / "progress.sqlite3"
    with course(ProgressStore(path)) as (app, open_tab):
        open_tab()
        page = start_page(app)
        page.name.value = "Émilie"
        panel = open_lesson(app, page, LESSON6)
        assert answer(panel, "meet", "at the epipole e1, the image of cam2's centre").result.passed
        next_step(panel)
        assert panel.run.step_index == 1
    # A new server process's store on the same file (the first server is stopped).
    with course(ProgressStore(path)) as (app, open_tab):
        open_tab()
        page = start_page(app)
        assert 'data-status="not started"' in page.status[LESSON6].content  # no name typed yet
        page.name.value = "  Émilie "  # the same learner, typed a little differently
        assert 'data-status="step 2 of 3"' in page.status[LESSON6].content
        panel = open_lesson(app, page, LESSON6)
        assert panel.run.step_index == 1 and 'data-step="1"' in panel.nav.head.content
        assert "cam2" in panel.view.model.scene.locked  # the step's changes replayed
        panel.nav.buttons.value = "previous"
        assert "passed before" in panel.row("meet").feedback.content


def test_a_name_typed_in_the_lesson_resumes_that_learner(store):
    store.set_step("Hypatia", LESSON6, 2)
    with course(store, lesson=LESSON6) as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        assert panel.run.learner == "" and panel.run.step_index == 0  # anonymous: nothing kept
        panel.learner.value = "Hypatia"
        assert panel.run.learner == "Hypatia" and panel.run.step_index == 2
        assert 'data-step="2"' in panel.nav.head.content
        panel.learner.value = "x" * 41
        assert panel.run.learner == "Hypatia"  # refused (a notification), the run unchanged


def test_a_name_is_taken_once_the_typing_stops(store):
    # A delay that the four keystrokes, sent back to back, stay well inside on a busy machine.
    with course(store, field_delay=2.0, lesson=LESSON6) as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        for text in ("L", "Li", "Lis", "Lise"):  # one update per keystroke, as the browser sends them
            panel.learner.value = text
        wait_for(lambda: panel.run.learner == "Lise", "the lesson to take the name typed, once the typing stopped")
        assert store.learners() == ["Lise"]  # no learner "L", "Li" or "Lis"


def test_the_workbench_is_one_click_from_the_start_page_and_back(store):
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        page.btn_workbench.value = True
        (view,) = app.wait_for_view(timeout=PATIENCE)
        assert view.panel_filter is None and set(view.svgs) == {"cam1", "cam2"}
        back = app.course.tabs[next(iter(app.views))]
        assert back is view


def test_a_set_range_limit_refuses_the_field_and_is_enforced_when_a_task_is_checked(store):
    with course(store, lesson="03-intrinsics") as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        lesson = panel.run.lesson
        index = next(i for i, s in enumerate(lesson.steps) if any(c.do == "set_range" for c in s.changes))
        panel.go_to(index)
        assert ("cam1", "focal_length") in panel.run.ranges
        assert "focal length 2 to 50 mm" in panel.ranges.content  # in the field's unit, as the learner types it
        assert range_refusal(panel.run) is None
        before = panel.view.model.scene.camera("cam1").focal_length
        panel.view.cameras["cam1"].fields["focal"].value = "60"  # mm: above the step's 50 mm
        assert panel.view.model.scene.camera("cam1").focal_length == before  # refused, not committed
        assert panel.view.cameras["cam1"].fields["focal"].value == format_number(before * 1e3)  # the field reverts
        # The model holds the range for every route: a raw edit (a script, a client message) is refused too.
        with pytest.raises(SceneError, match=r"cam1's focal length must stay between 2 mm and 50 mm \(it is 60 mm\)"):
            panel.view.model.update_camera("cam1", focal_length=0.06)
        assert panel.view.model.scene.camera("cam1").focal_length == before
        # A scene loaded whole (not an edit in place) may leave the range: it blocks the step's tasks.
        scene = panel.view.model.scene
        panel.view.model.load_scene(scene.replace(cameras=tuple(
            c.with_fields(focal_length=0.06) if c.name == "cam1" else c for c in scene.cameras)))
        refusal = range_refusal(panel.run)
        assert refusal is not None and "focal length must stay between 2 mm and 50 mm (it is 60 mm)" in refusal
        task = panel.rows[0]
        task.button.value = True
        assert task.task_id not in panel.attempts and "must stay between" in task.feedback.content


def test_a_locked_camera_gizmo_is_put_back_with_a_message(store):
    with course(store, lesson=LESSON6) as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        panel.go_to(1)
        view = panel.view
        before = view.model.scene.camera("cam2")
        target = type("T", (), {"wxyz": (1.0, 0.0, 0.0, 0.0), "position": (9.0, 9.0, 9.0), "update_timestamp": 1e12})
        with pytest.raises(SceneError, match="cam2 is locked"):
            view.drag.camera_event("cam2", type("E", (), {"target": target, "phase": "end"})())
        assert view.model.scene.camera("cam2") is before


def zoom_step_panel(app) -> LessonPanel:
    """Lesson 3's step 2 in a tab: cam1 at 30 mm, locked ("without moving the camera"), 2..50 mm allowed."""
    (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
    panel.go_to(1)
    assert panel.view.model.scene.locked == {"cam1"}
    return panel


def test_undo_stops_at_the_steps_start_and_says_so(store):
    with course(store, lesson="03-intrinsics") as (app, open_tab):
        open_tab()
        panel = zoom_step_panel(app)
        view = panel.view
        told = []
        view.client.add_notification = lambda title, body, **_: told.append((title, body))
        start = view.model.scene
        assert not view.controls.btn_undo.disabled  # enabled at the barrier, so that it can say why it does nothing
        view.controls.btn_undo.value = True
        view.controls.btn_undo.value = True
        assert view.model.scene is start and start.locked == {"cam1"} and start.camera("cam1").focal_length == 0.03
        assert told and all(t == "Nothing to undo" and "Undo stops at the start of this step" in b for t, b in told)
        for row in panel.rows:  # no work done: both tasks still fail
            row.button.value = True
            assert not panel.attempts[row.task_id].result.passed


def test_typing_a_locked_cameras_position_is_refused_and_the_field_reverts(store):
    with course(store, lesson="03-intrinsics") as (app, open_tab):
        open_tab()
        panel = zoom_step_panel(app)
        view = panel.view
        told = []
        view.client.add_notification = lambda title, body, **_: told.append(body)
        shown = view.cameras["cam1"].fields["position"].value
        before = view.model.scene.camera("cam1")
        view.cameras["cam1"].fields["position"].value = "0, -20, 1.5"
        assert view.model.scene.camera("cam1") is before
        assert view.cameras["cam1"].fields["position"].value == shown
        assert told[-1] == "cam1: the camera is locked in this step; its position and orientation cannot change"
        view.cameras["cam1"].fields["focal"].value = "8"  # the intrinsics are the step's instrument
        assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.008)
        assert all(answer(panel, row.task_id).result.passed for row in panel.rows)


def test_a_check_finds_a_locked_camera_moved_or_gone_and_offers_the_reset(store):
    with course(store, lesson="03-intrinsics") as (app, open_tab):
        open_tab()
        panel = zoom_step_panel(app)
        model = panel.view.model
        moved = model.scene.replace(
            cameras=tuple(c.with_pose(position=(0.0, -30.0, 1.5)) if c.name == "cam1" else c
                          for c in model.scene.cameras), locked=frozenset())
        model.load_scene(moved)  # e.g. a scene file uploaded in the lesson: the lock went with the old scene
        row = panel.rows[0]
        row.button.value = True
        assert row.task_id not in panel.attempts  # not counted
        assert "cam1 must stay where this step put it (it is locked)" in row.feedback.content
        assert "reset step" in row.feedback.content
        model.remove_camera("cam1")
        row.button.value = True
        assert "cam1 is not in the scene any more" in row.feedback.content and "reset step" in row.feedback.content
        panel.nav.buttons.value = "reset step"
        assert model.scene.camera("cam1").position == panel.run.model.barrier_scene.camera("cam1").position


def test_a_task_whose_camera_was_removed_says_so_at_check(store):
    with course(store, lesson=LESSON6) as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        panel.go_to(2)  # cam1 locked; the task measures the epipolar lines in cam2
        panel.view.model.remove_camera("cam2")
        attempt = answer(panel, "parallel")
        assert not attempt.result.passed
        assert attempt.result.feedback == ("cam2 is not in the scene any more: "
                                           "press \u201creset step\u201d to start this step again.")


def test_a_mirrors_virtual_camera_follows_its_camera_without_breaking_its_lock():
    from egtviz.scene import SCENES, SceneModel
    from egtviz.controllers.lesson_rules import lock_refusal

    model = SceneModel(SCENES["mirror"]())  # cam_virtual: locked by the scene, the reflection of cam
    model.set_undo_barrier("Undo stops here.")
    run = types.SimpleNamespace(model=model)
    before = model.scene.camera("cam_virtual").position
    model.update_camera("cam", position=(-2.0, -8.0, 1.5))
    assert model.scene.camera("cam_virtual").position != before and lock_refusal(run) is None
    model.lock("cam")
    model.set_undo_barrier("Undo stops here.")
    model.load_scene(SCENES["mirror"]())
    assert lock_refusal(run).startswith("cam must stay where this step put it (it is locked)")


def test_lessons_use_the_instruments_their_changes_and_tasks_name():
    assert lesson_instruments(load("07-fundamental-and-essential")) == (False, True)
    assert lesson_instruments(load("09-estimating-f")) == (True, False)
    assert lesson_instruments(load("10-robust-estimation")) == (True, False)
    assert lesson_instruments(load(LESSON6)) == (False, False)


def test_lab_sliders_change_the_fits_and_the_panels(store):
    with course(store, lesson="10-robust-estimation") as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        lab, view = panel.lab, panel.view
        assert lab is not None and view.panel_filter == lab.panel_filter
        # The step's set_lab reached the sliders.
        assert (lab.noise.value, lab.outliers.value, lab.threshold.value) == (0.5, 30.0, 30.0)
        result = lab.result
        assert result is not None and result.settings == panel.run.lab
        assert 'data-method="ransac"' in lab.table.content and "30 outliers" in lab.table.content
        # The panels draw the measured pixels and the drawn fit's lines (one per correspondence).
        n = len(result.data.point_indices)
        assert svg_kinds(view.svgs["cam2"], "epipolar-line") <= n
        assert svg_kinds(view.svgs["cam2"], "epipolar-line") >= n - 10
        # Outliers off: the least-squares fit recovers.
        ruined = result.fit("normalized").sampson_true
        lab.outliers.value = 0.0
        assert panel.run.lab.outlier_percent == 0.0 and lab.result.settings.outlier_percent == 0.0
        assert lab.result.fit("normalized").sampson_true < 0.01 * ruined
        # More noise: larger errors against the truth.
        quiet = lab.result.fit("normalized").sampson_true
        lab.noise.value = 5.0
        assert lab.result.fit("normalized").sampson_true > 10 * quiet
        assert "\u03c3 = 5 px" in lab.meaning.content and "10 to 15 px" in lab.meaning.content
        # The threshold: too strict rejects most true inliers; 3 sigma keeps them. The mask follows in the panels.
        lab.noise.value = 0.5
        lab.outliers.value = 30.0
        lab.fit_dropdown.value = "RANSAC"
        lab.threshold.value = 0.1
        strict = lab.result.fit("ransac")
        assert strict.inlier_recall < 0.6
        assert view.svgs["cam1"].count('data-selected="false"') == 0  # too many rejects to ring
        assert "too many to ring" in lab.table.content
        lab.threshold.value = 1.5
        kept = lab.result.fit("ransac")
        assert kept.inlier_recall >= 0.9
        # A ring on each correspondence RANSAC rejected whose measured pixel is inside image 1.
        m1 = lab.result.data.measured1
        plane = view.model.derived.image_planes["cam1"]
        inside = (m1[:, 0] >= 0) & (m1[:, 0] <= plane.width) & (m1[:, 1] >= 0) & (m1[:, 1] <= plane.height)
        rejected = int((~kept.inliers & inside).sum())
        assert 0 < rejected <= 40
        assert view.svgs["cam1"].count('data-selected="false"') == rejected
        assert "ringed in the panels" in lab.table.content
        # The plot holds each fit's errors, as base-10 logarithms, in the table's order.
        y = np.asarray(lab.plot.data[1])
        assert y.shape == (6,) and y[3] == pytest.approx(math.log10(kept.sampson_true))
        assert np.asarray(lab.plot.data[2])[0] == pytest.approx(math.log10(lab.result.fit("linear").sampson_noisy))
        # The task of this step passes once the threshold is right.
        panel.go_to(1)
        lab.threshold.value = 1.5
        assert answer(panel, "tune-threshold").result.passed


def test_lens_toggles_change_the_residuals_shown(store):
    with course(store, lesson="07-fundamental-and-essential") as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        lens, view = panel.lens, panel.view
        assert lens is not None and view.panel_filter == lens.panel_filter
        panel.go_to(2)  # F in place of F transposed
        assert lens.toggles["f_transposed"].value is True and panel.run.lens.f_transposed

        def worst() -> float:
            return float(re.search(r'data-kind="worst">([^<]+)<', lens.readout.content).group(1))

        broken, lines_broken = worst(), view.svgs["cam2"]
        assert broken > 1e-3
        assert not answer(panel, "fix-transpose").result.passed
        lens.toggles["f_transposed"].value = False
        assert not panel.run.lens.f_transposed
        assert worst() < 1e-9 * max(broken, 1.0) + 1e-12
        assert view.svgs["cam2"] != lines_broken  # the panels redraw through the lens
        assert answer(panel, "fix-transpose").result.passed
        # Every mistake breaks the residual of a true correspondence (or, for the epipoles, leaves it).
        for key in ("r_tx", "k_transposed", "opengl_axes"):
            lens.toggles[key].value = True
            assert worst() > 1e-6, key
            lens.toggles[key].value = False
        lens.toggles["wrong_singular_vector"].value = True
        assert worst() < 1e-9
        ep = re.search(r'data-kind="epipole"[^>]*', view.svgs["cam1"])
        assert ep is not None


def test_a_servo_demo_opened_from_a_lesson_comes_back_to_the_lesson(store):
    with course(store, lesson=LESSON6) as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        panel.go_to(1)
        client = panel.view.client
        panel.view.controls.servo_buttons["pinhole"].value = True
        app.wait_for_demo(timeout=PATIENCE)
        app.close_demo(client)
        (again,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        assert again is not panel and again.run is panel.run and again.run.step_index == 1
        assert again.view is app.views[client.client_id] and again.view.model is panel.run.model


def test_egtviz_without_arguments_serves_the_course_and_lesson_opens_one(monkeypatch):
    import egtviz.viewer.server.cli as serve_cli
    from egtviz.cli import main

    calls = []
    monkeypatch.setattr(serve_cli, "serve", lambda *args, **kwargs: calls.append(kwargs) or 0)
    assert main([]) == 0
    assert calls[-1]["course"] is True and calls[-1]["lesson"] is None
    assert main(["serve", "--port", "0"]) == 0 and calls[-1]["course"] is True
    assert main(["lesson", LESSON6, "--port", "0"]) == 0
    assert calls[-1]["lesson"] == LESSON6 and calls[-1]["course"] is False
    assert main(["--scene", "default"]) == 0 and calls[-1]["course"] is False
    assert main(["--demo", "pinhole"]) == 0 and calls[-1]["course"] is False


def test_an_unknown_lesson_is_refused_before_a_server_starts(capsys):
    from egtviz.cli import main

    assert main(["lesson", "99-nothing", "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert "cannot open the lesson" in err and "06-pinhole-epipolar" in err


def test_a_servo_step_opens_its_demo_with_the_lessons_run_fields_and_comes_back(store):
    from egtviz.lessons.servo_runs import simulate

    with course(store, lesson="12-visual-servoing") as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        panel.go_to(0)
        assert panel.demo_button is None  # the hand-servoing steps offer no run
        panel.go_to(3)
        info = panel.demo_info.content
        assert 'data-demo="pinhole"' in info and "beta 0, seed 0" in info
        client = panel.view.client
        panel.demo_button.value = True
        (demo,) = app.wait_for_demo(timeout=PATIENCE)
        assert demo.wait(PATIENCE) and demo.result is not None
        opened = panel.run.demo
        assert demo.params() == opened.simulation_kwargs()  # the same keywords the task's answer is computed with
        assert demo.result.steps == simulate(opened).steps
        assert demo.fields["beta"].value in (0, 0.0, "0")
        app.close_demo(client)
        (again,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        assert again.run is panel.run and again.run.step_index == 3 and again.demo_button is not None
        t = simulate(opened).time[np.flatnonzero(np.degrees(simulate(opened).errors["rotation_error_rad"]) < 0.1)[0]]
        assert answer(again, "rotation-time", f"{t:g} s").result.passed
        wrong = answer(again, "rotation-time", f"{t + 1:g}")
        assert not wrong.result.passed and "too high" in again.row("rotation-time").feedback.content
        assert "Hint" in again.row("rotation-time").feedback.content
