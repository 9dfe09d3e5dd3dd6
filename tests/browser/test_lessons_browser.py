"""The course in a real browser (headless Debian Chromium, playwright): the start page, a lesson walked from
start to finish by answering its tasks through the page (choosing options, typing camera angles), a wrong
answer refused with its hint, and the screenshots of a lesson (1366 x 768, and in presentation mode)."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

from egtviz.lessons import ProgressStore
from egtviz.viewer.server.browser import (
    PANEL_SELECTOR,
    chromium,
    close_notifications,
    folder_field,
)

pytestmark = pytest.mark.browser


LESSON6 = "06-pinhole-epipolar"
ASSETS = Path(__file__).resolve().parents[2] / "assets"
TIMEOUT_MS = 60_000


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


@pytest.fixture
def course(tmp_path):
    import viser

    from egtviz.viewer.workbench.app import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, course=True, progress=ProgressStore(tmp_path / "progress.sqlite3"))
    yield app, f"http://127.0.0.1:{server.get_port()}"
    server.stop()


def _start(browser, url, *, width=1366, height=768):
    page = browser.new_page(viewport={"width": width, "height": height})
    page.goto(url)
    page.get_by_role("button", name="Open the workbench").wait_for(timeout=TIMEOUT_MS)
    close_notifications(page)
    return page


def _panel(app):
    from egtviz.viewer.course.lesson_view import LessonPanel

    (panel,) = app.course.wait_for_tab(LessonPanel, timeout=30)
    return panel


def _open_lesson(page, title: str) -> None:
    page.get_by_role("button", name=title).click()
    page.wait_for_function(f"() => document.querySelectorAll('{PANEL_SELECTOR}').length >= 2", timeout=TIMEOUT_MS)
    page.mouse.move(700, 700)  # away from the controls: no tooltip in the way


def _labelled_input(page, label: str):
    return page.locator(f'xpath=//label[normalize-space(.)="{label}"]/following::input[1]').first


def _choose(page, number: int, option: str) -> None:
    """Pick ``option`` in the answer list of task ``number`` (a Mantine select)."""
    _labelled_input(page, f"answer {number}").click()
    page.get_by_role("option", name=option, exact=True).click()


def _check(page, number: int, verdict: str) -> None:
    """Press "Check task n" and wait for its verdict ("Passed" or "Not yet") in the page."""
    # Only shown verdicts count: a step's page may keep the previous step's elements, hidden.
    shown = "(v) => [...document.querySelectorAll('strong')].filter(e => e.textContent.includes(v) && e.offsetParent !== null)"
    before = page.evaluate(f"(v) => ({shown})(v).length", verdict)
    page.get_by_role("button", name=f"Check task {number}").click()
    page.wait_for_function(f"([v, n]) => ({shown})(v).length > n", arg=[verdict, before], timeout=TIMEOUT_MS)


def _next(page, step: int) -> None:
    page.get_by_role("button", name="next", exact=True).click()
    page.wait_for_function(f"() => !!document.querySelector('[data-egtviz=\"lesson-head\"][data-step=\"{step}\"]')",
                           timeout=TIMEOUT_MS)


def _type_angles(page, panel, camera: str, ypr: tuple[float, float, float]) -> None:
    """Type yaw, pitch, roll into the camera's field (opening its folder if needed) and press Enter; wait until the
    server has judged the text (a field is judged when the typing stops)."""
    field = folder_field(page, f"{camera} (pin-hole)", "yaw, pitch, roll (deg)")
    field.click()
    field.fill(", ".join(f"{a:.6f}" for a in ypr))
    field.press("Enter")
    _wait(lambda: np.allclose(panel.view.model.scene.camera(camera).ypr_deg, ypr, atol=1e-5))


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


def _wait(predicate, timeout=20.0) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    raise AssertionError("the server did not reach the expected state")


def test_lesson_6_walked_from_start_to_finish_in_the_browser(browser, course):
    app, url = course
    page = _start(browser, url)
    try:
        name = _labelled_input(page, "your name")
        name.fill("Ada")
        name.press("Enter")
        _wait(lambda: any(getattr(t, "learner", "") == "Ada" for t in app.course.tabs.values()))
        _open_lesson(page, "6. Pin-hole epipolar geometry")
        panel = _panel(app)
        assert panel.run.learner == "Ada"
        # The step's formulas are MathML that the browser lays out (not markup shown as text).
        page.locator("math").first.wait_for(timeout=TIMEOUT_MS)
        assert page.evaluate("() => document.querySelector('math').getBoundingClientRect().width") > 5
        assert page.get_by_text("<math").count() == 0 and page.get_by_text("msub").count() == 0
        # Step 1: a choice.
        _choose(page, 1, "at the epipole e1, the image of cam2's centre")
        _check(page, 1, "Passed")
        _next(page, 1)
        # Step 2: cam1's epipole to this learner's target, by typing cam1's angles.
        params = panel.run.tasks()[0].params
        page.get_by_text(f"({params['u']:g}, {params['v']:g})").first.wait_for(timeout=TIMEOUT_MS)
        _type_angles(page, panel, "cam1", _aim(panel.view.model.scene, "cam1", params["u"], params["v"]))
        _check(page, 1, "Passed")
        _next(page, 2)
        # Step 3: cam2's lines parallel, then why.
        _type_angles(page, panel, "cam2", (-4.3987, 0.0, 0.0))
        _check(page, 1, "Passed")
        _choose(page, 2, "the epipole is at infinity")
        _check(page, 2, "Passed")
        store = app.course.progress
        steps = panel.run.lesson.steps
        assert store.passed_tasks("Ada", LESSON6) == {(i, t.id) for i, s in enumerate(steps) for t in s.tasks}
        # Back on the start page the lesson is done.
        page.get_by_role("button", name="Back to the course").click()
        page.locator(f'[data-lesson="{LESSON6}"][data-status="done"]').wait_for(timeout=TIMEOUT_MS)
    finally:
        page.close()


def test_a_wrong_answer_is_refused_with_its_hint_in_the_browser(browser, course):
    app, url = course
    page = _start(browser, url)
    try:
        _open_lesson(page, "6. Pin-hole epipolar geometry")
        _choose(page, 1, "at the principal point")
        _check(page, 1, "Not yet")
        page.get_by_text("Every epipolar plane contains the baseline.").wait_for(timeout=TIMEOUT_MS)
        assert page.get_by_text("Hint:").count() == 1
        assert not _panel(app).attempts["meet"].result.passed
    finally:
        page.close()


def test_screenshots_of_a_lesson(browser, course):
    """The README's pictures: the start page and lesson 10 (the estimation lab) at 1366 x 768, and lesson 6 in
    presentation mode."""
    app, url = course
    page = _start(browser, url)
    try:
        ASSETS.mkdir(exist_ok=True)
        page.mouse.move(1000, 500)
        page.screenshot(path=str(ASSETS / "screenshot-lesson-start.png"))
        _open_lesson(page, "10. Outliers and robust estimation")
        panel = _panel(app)
        panel.go_to(1)  # "A threshold in pixels", with the threshold set well
        panel.lab.threshold.value = 1.5
        panel.view.panel_buttons["cam2"]["panel view"].value = "image"  # the image, not the far epipole
        page.get_by_text("ringed in the panels").first.wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("of the mean Sampson error").first.scroll_into_view_if_needed()
        page.mouse.move(700, 700)
        time.sleep(1.5)  # the lab's plot draws after the panels
        page.screenshot(path=str(ASSETS / "screenshot-lesson.png"))
        assert (ASSETS / "screenshot-lesson.png").stat().st_size > 20_000
    finally:
        page.close()
    page = _start(browser, url)
    try:
        _open_lesson(page, "6. Pin-hole epipolar geometry")
        panel = _panel(app)
        panel.view.present_checkbox.value = True  # as the "presentation mode" box does
        page.wait_for_function(f"() => document.querySelector('{PANEL_SELECTOR}')?.dataset.style === 'present'",
                               timeout=TIMEOUT_MS)
        time.sleep(1.0)
        page.screenshot(path=str(ASSETS / "screenshot-lesson-present.png"))
        assert (ASSETS / "screenshot-lesson-present.png").stat().st_size > 20_000
    finally:
        page.close()
