"""The course in a real browser (headless Debian Chromium, playwright): the start page, a lesson walked from
start to finish by answering its tasks through the page (choosing options, typing camera angles), a wrong
answer refused with its hint, and the screenshots of a lesson (1366 x 768, and in presentation mode).

``EGTVIZ_SCREENSHOTS=1`` writes the screenshots to ``assets/`` (the README's and the lessons guide's pictures);
otherwise to the test's own temporary folder (a test run leaves the repository as it was, and another test that
reads ``assets/`` at the same time under ``pytest-xdist`` never sees a half-written file).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from _waiting import PATIENCE, wait_for
from egtviz.lessons import ProgressStore
from egtviz.viewer.server.browser import (
    PANEL_SELECTOR,
    close_notifications,
    folder_field,
    wait_for_3d_view,
    wait_for_js,
)

pytestmark = pytest.mark.browser


LESSON6 = "06-pinhole-epipolar"
ASSETS = Path(__file__).resolve().parents[2] / "assets"


@pytest.fixture
def course(tmp_path):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, course=True, progress=ProgressStore(tmp_path / "progress.sqlite3"))
    yield app, f"http://127.0.0.1:{server.get_port()}"
    server.stop()


def _start(browser, url, *, width=1366, height=768):
    page = browser.new_page(viewport={"width": width, "height": height})
    page.goto(url)
    page.get_by_role("button", name="Open the workbench").wait_for()
    close_notifications(page)
    return page


def _panel(app):
    from egtviz.viewer.course.lesson_view import LessonPanel

    (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
    return panel


def _open_lesson(page, title: str) -> None:
    page.get_by_role("button", name=title).click()
    wait_for_js(page, f"() => document.querySelectorAll('{PANEL_SELECTOR}').length >= 2", f"the panels of {title}")
    page.mouse.move(700, 700)  # away from the controls: no tooltip in the way


def _labelled_input(page, label: str):
    return page.locator(f'xpath=//label[normalize-space(.)="{label}"]/following::input[1]').first


def _choose(page, panel, number: int, option: str) -> None:
    """Pick ``option`` in the answer list of task ``number`` (a Mantine select), and wait until the server has it
    (the check button's press is not held back behind it)."""
    _labelled_input(page, f"answer {number}").click()
    page.get_by_role("option", name=option, exact=True).click()
    task = panel.run.lesson.steps[panel.run.step_index].tasks[number - 1]
    wait_for(lambda: panel.row(task.id).answer.value == option, f"the server to have answer {number}: {option!r}")


def _check(page, number: int, verdict: str) -> None:
    """Press "Check task n" and wait for its verdict ("Passed" or "Not yet") in the page."""
    # Only shown verdicts count: a step's page may keep the previous step's elements, hidden.
    shown = "(v) => [...document.querySelectorAll('strong')].filter(e => e.textContent.includes(v) && e.offsetParent !== null)"
    before = page.evaluate(f"(v) => ({shown})(v).length", verdict)
    page.get_by_role("button", name=f"Check task {number}").click()
    wait_for_js(page, f"([v, n]) => ({shown})(v).length > n",
                f"one more verdict {verdict!r} after checking task {number}", arg=[verdict, before])


def _next(page, step: int) -> None:
    page.get_by_role("button", name="next", exact=True).click()
    wait_for_js(page, f"() => !!document.querySelector('[data-egtviz=\"lesson-head\"][data-step=\"{step}\"]')",
                f"step {step + 1}'s head")


def _type_angles(page, panel, camera: str, ypr: tuple[float, float, float]) -> None:
    """Type yaw, pitch, roll into the camera's field (opening its folder if needed) and press Enter; wait until the
    server has judged the text (a field is judged when the typing stops)."""
    field = folder_field(page, f"{camera} (pin-hole)", "yaw, pitch, roll (deg)")
    field.click()
    field.fill(", ".join(f"{a:.6f}" for a in ypr))
    field.press("Enter")
    wait_for(lambda: np.allclose(panel.view.model.scene.camera(camera).ypr_deg, ypr, atol=1e-5),
             f"the server to take {camera}'s typed angles")


def _aim(scene, name: str, u: float, v: float) -> tuple[float, float, float]:
    """Yaw and pitch (deg) that image the other camera's centre at (u, v), by least squares on the projection."""
    other = next(n for n in scene.drawn_pair if n != name)
    spec = scene.camera(name)
    centre = np.array(scene.camera(other).position)
    d = centre - np.array(spec.position)
    x0 = [math.degrees(math.atan2(d[0], d[1])), math.degrees(math.atan2(d[2], math.hypot(d[0], d[1])))]

    def residual(x):
        p = spec.with_pose(ypr_deg=(x[0], x[1], spec.ypr_deg[2])).camera().project(centre)
        return p.pixels[0] - (u, v) if p.in_front[0] else np.array([1e4, 1e4])

    fit = least_squares(residual, x0, xtol=1e-12, ftol=1e-12)
    return float(fit.x[0]), float(fit.x[1]), float(spec.ypr_deg[2])


def test_lesson_6_walked_from_start_to_finish_in_the_browser(browser, course):
    app, url = course
    page = _start(browser, url)
    try:
        name = _labelled_input(page, "your name")
        name.fill("Ada")
        name.press("Enter")
        wait_for(lambda: any(getattr(t, "learner", "") == "Ada" for t in app.course.tabs.values()),
                 "the server to take the name Ada")
        _open_lesson(page, "6. Pin-hole epipolar geometry")
        panel = _panel(app)
        assert panel.run.learner == "Ada"
        # The step's formulas are MathML that the browser lays out (not markup shown as text).
        page.locator("math").first.wait_for()
        assert page.evaluate("() => document.querySelector('math').getBoundingClientRect().width") > 5
        assert page.get_by_text("<math").count() == 0 and page.get_by_text("msub").count() == 0
        # Step 1: a choice.
        _choose(page, panel, 1, "at the epipole e1, the image of cam2's centre")
        _check(page, 1, "Passed")
        _next(page, 1)
        # Step 2: cam1's epipole to this learner's target, by typing cam1's angles.
        params = panel.run.tasks()[0].params
        page.get_by_text(f"({params['u']:g}, {params['v']:g})").first.wait_for()
        _type_angles(page, panel, "cam1", _aim(panel.view.model.scene, "cam1", params["u"], params["v"]))
        _check(page, 1, "Passed")
        _next(page, 2)
        # Step 3: cam2's lines parallel, then why.
        _type_angles(page, panel, "cam2", (-4.3987, 0.0, 0.0))
        _check(page, 1, "Passed")
        _choose(page, panel, 2, "the epipole is at infinity")
        _check(page, 2, "Passed")
        store = app.course.progress
        steps = panel.run.lesson.steps
        assert store.passed_tasks("Ada", LESSON6) == {(i, t.id) for i, s in enumerate(steps) for t in s.tasks}
        # Back on the start page the lesson is done.
        page.get_by_role("button", name="Back to the course").click()
        page.locator(f'[data-lesson="{LESSON6}"][data-status="done"]').wait_for()
    finally:
        page.close()


def test_a_wrong_answer_is_refused_with_its_hint_in_the_browser(browser, course):
    app, url = course
    page = _start(browser, url)
    try:
        _open_lesson(page, "6. Pin-hole epipolar geometry")
        panel = _panel(app)
        _choose(page, panel, 1, "at the principal point")
        _check(page, 1, "Not yet")
        page.get_by_text("Every epipolar plane contains the baseline.").wait_for()
        assert page.get_by_text("Hint:").count() == 1
        assert not panel.attempts["meet"].result.passed
    finally:
        page.close()


def test_screenshots_of_a_lesson(browser, course, tmp_path):
    """The README's pictures: the start page and lesson 10 (the estimation lab) at 1366 x 768, and lesson 6 in
    presentation mode."""
    app, url = course
    out = ASSETS if os.environ.get("EGTVIZ_SCREENSHOTS") else tmp_path
    page = _start(browser, url)
    try:
        out.mkdir(exist_ok=True)
        page.mouse.move(1000, 500)
        page.screenshot(path=str(out / "screenshot-lesson-start.png"))
        _open_lesson(page, "10. Outliers and robust estimation")
        panel = _panel(app)
        panel.go_to(1)  # "A threshold in pixels", with the threshold set well
        panel.lab.threshold.value = 1.5
        panel.view.panel_buttons["cam2"]["panel view"].value = "image"  # the image, not the far epipole
        page.get_by_text("ringed in the panels").first.wait_for()
        page.get_by_text("of the mean Sampson error").first.scroll_into_view_if_needed()
        page.mouse.move(700, 700)
        page.locator(".uplot canvas").first.wait_for()  # the lab's plot draws after the panels
        wait_for_3d_view(page)
        page.screenshot(path=str(out / "screenshot-lesson.png"))
        assert (out / "screenshot-lesson.png").stat().st_size > 20_000
    finally:
        page.close()
    page = _start(browser, url)
    try:
        _open_lesson(page, "6. Pin-hole epipolar geometry")
        panel = _panel(app)
        panel.view.present_checkbox.value = True  # as the "presentation mode" box does
        wait_for_js(page, f"() => [...document.querySelectorAll('{PANEL_SELECTOR}')].every("
                    "s => s.dataset.style === 'present')", "every panel drawn in the presentation style")
        wait_for_3d_view(page)
        page.screenshot(path=str(out / "screenshot-lesson-present.png"))
        assert (out / "screenshot-lesson-present.png").stat().st_size > 20_000
    finally:
        page.close()
