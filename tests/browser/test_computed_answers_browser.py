"""Two learners, two browser contexts, one lesson with computed answers (headless Debian Chromium, playwright):
each reads the camera they got from the page, computes where the point lands with the core, types it, and is
accepted; the two answers differ, and each learner's answer is refused in the other's scene."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from _waiting import wait_for
from egtviz.lessons import ProgressStore, load
from egtviz.viewer.server.browser import PANEL_SELECTOR, close_notifications, folder_field, wait_for_js

pytestmark = pytest.mark.browser

LESSON = "03-intrinsics"
TITLE = "3. Intrinsics"


@pytest.fixture
def course(tmp_path):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, course=True, progress=ProgressStore(tmp_path / "progress.sqlite3"))
    yield app, f"http://127.0.0.1:{server.get_port()}"
    server.stop()


def _labelled_input(page, label: str):
    return page.locator(f'xpath=//label[normalize-space(.)="{label}"]/following::input[1]').first


def _panel_of(app, learner: str):
    from egtviz.viewer.course.lesson_view import LessonPanel

    found = []
    wait_for(lambda: found.extend(t for t in app.course.tabs.values()
                                  if isinstance(t, LessonPanel) and t.run.learner == learner) or bool(found),
             f"{learner}'s lesson tab")
    return found[0]


def _enter_as(browser, app, url: str, learner: str):
    """A new browser context (its own storage), the learner's name typed, the lesson opened at its last step."""
    context = browser.new_context(viewport={"width": 1366, "height": 900})
    page = context.new_page()
    page.goto(url)
    page.get_by_role("button", name="Open the workbench").wait_for()
    close_notifications(page)
    name = _labelled_input(page, "your name")
    name.fill(learner)
    name.press("Enter")
    wait_for(lambda: any(getattr(t, "learner", "") == learner for t in app.course.tabs.values()),
             f"the server to take the name {learner}")
    page.get_by_role("button", name=TITLE).click()
    wait_for_js(page, f"() => document.querySelectorAll('{PANEL_SELECTOR}').length >= 2", "the lesson's panels")
    page.mouse.move(700, 800)
    panel = _panel_of(app, learner)
    last = len(panel.run.lesson.steps) - 1
    for step in range(1, last + 1):
        page.get_by_role("button", name="next", exact=True).click()
        head = f"[data-egtviz=\"lesson-head\"][data-step=\"{step}\"]"
        wait_for_js(page, f"() => !!document.querySelector('{head}')", f"step {step + 1}'s head")
    return context, page, panel


def _numbers(page, label: str) -> tuple[float, ...]:
    field = folder_field(page, "cam2 (pin-hole)", label)
    return tuple(float(x) for x in field.input_value().split(","))


def _camera_read_off_the_page(page, spec):
    """cam2 as the learner reads it in its panel: position, angles, focal length (mm), principal point."""
    (focal_mm,) = _numbers(page, "focal length (mm)")
    return dataclasses.replace(spec, position=_numbers(page, "position x, y, z (m)"),
                               ypr_deg=_numbers(page, "yaw, pitch, roll (deg)"), focal_length=focal_mm / 1000,
                               principal_point=_numbers(page, "principal point u, v (px)"))


_VERDICTS = "(v) => [...document.querySelectorAll('strong')].filter(e => e.textContent.includes(v)).length"


def _check(page, number: int, verdict: str) -> None:
    """Press "Check task n" and wait until one more verdict ``verdict`` is shown in the page."""
    before = page.evaluate(_VERDICTS, verdict)
    page.get_by_role("button", name=f"Check task {number}").click()
    wait_for_js(page, f"([v, n]) => ({_VERDICTS})(v) > n", f"one more verdict {verdict!r} after checking task {number}",
                arg=[verdict, before])


def test_two_learners_read_their_own_camera_and_each_ones_computed_answer_is_accepted(browser, course):
    app, url = course
    lesson = load(LESSON)
    task = lesson.steps[-1].tasks[0]
    assert task.kind == "computed" and task.quantity == "pixel" and task.camera == "cam2"
    point = np.array(lesson.scene.points[task.point])  # the points are the lesson's; the camera is each learner's
    typed = {}
    contexts = []
    try:
        for learner in ("Ada", "Grace"):
            context, page, panel = _enter_as(browser, app, url, learner)
            contexts.append(context)
            assert panel.run.step_index == len(lesson.steps) - 1 and panel.run.learner == learner
            read = _camera_read_off_the_page(page, panel.run.model.scene.camera("cam2"))
            assert read == panel.run.model.scene.camera("cam2")  # the page shows the camera the check uses
            u, v = read.camera().project(point[None, :]).pixels[0]
            typed[learner] = f"[{u:.2f}, {v:.2f}]"
            field = _labelled_input(page, "answer 1 (px)")
            field.fill(typed[learner])
            field.press("Enter")
            wait_for(lambda: panel.row(task.id).answer.value == typed[learner], "the server to have the typed answer")
            _check(page, 1, "Passed")
            assert panel.attempts[task.id].result.passed
            assert (len(lesson.steps) - 1, task.id) in app.course.progress.passed_tasks(learner, LESSON)
        assert typed["Ada"] != typed["Grace"]
        # Ada's answer in Grace's scene is wrong (and the other way round): the scene is the question.
        grace = _panel_of(app, "Grace")
        assert not grace.run.check(task.id, typed["Ada"]).result.passed
        assert not _panel_of(app, "Ada").run.check(task.id, typed["Grace"]).result.passed
    finally:
        for context in contexts:
            context.close()
