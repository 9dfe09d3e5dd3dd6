"""The unified sphere camera in a real browser (headless Chromium): moving its xi slider moves the epipolar
conics in its panel. Skipped only when Chromium is missing on a developer machine (a failure under ``CI``)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from _waiting import PATIENCE, wait_for, wait_until
from egtviz.scene import Scene, UnifiedSpec, default_scene
from egtviz.viewer.server.browser import COUNT_JS, open_viewer

pytestmark = pytest.mark.browser


CONICS_JS = """(camera) => [...document.querySelectorAll(
  `svg[data-egtviz="image-plane"][data-camera="${camera}"] [data-kind="epipolar-conic"]`)].map(e => e.getAttribute('points'))"""


def test_moving_the_xi_slider_moves_the_conics(browser):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    base = default_scene()
    scene = Scene(cameras=(UnifiedSpec("uni", (-3.0, -8.0, 1.5), (20.0, -3.0, 0.0), xi=0.8), base.cameras[1]),
                  points=base.points)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, scene)
    page = None
    try:
        page = open_viewer(browser, f"http://127.0.0.1:{server.get_port()}")
        (view,) = app.wait_for_view(timeout=PATIENCE)
        before = page.evaluate(CONICS_JS, "uni")
        assert len(before) == 8
        # The xi slider of uni's folder, once the folder is on the page (clicking its title before it is drawn
        # open would close it).
        folder = page.get_by_text("uni (unified sphere)", exact=True).first
        folder.wait_for()
        slider = page.locator('xpath=//*[normalize-space(text())="uni (unified sphere)"]'
                              '/following::*[@role="slider"][1]').first
        if not slider.is_visible():  # the first two cameras' folders start open, others closed
            folder.click()
        slider.wait_for(state="visible")
        slider.focus()
        for _ in range(10):  # ten steps of 0.01: xi 0.8 -> 0.9
            slider.press("ArrowRight")
        # Every step answered (the last one, 0.9, is the model's), and the page showing the panel drawn after it.
        if not wait_until(lambda: view.model.scene.camera("uni").xi == pytest.approx(0.9)):
            raise AssertionError(f"waited {PATIENCE:.0f} s for the server to take xi = 0.9: it has "
                                 f"{view.model.scene.camera('uni').xi}, the slider shows "
                                 f"{slider.get_attribute('aria-valuenow')}")
        wait_for(lambda: page.evaluate(COUNT_JS)["uni"]["rev"] == _server_rev(view, "uni"),
                 "uni's panel in the page at the server's last revision")
        after = page.evaluate(CONICS_JS, "uni")
        assert len(after) == 8 and after != before
        first = np.array([[float(x) for x in p.split(",")] for p in before[0].split()])
        moved = np.array([[float(x) for x in p.split(",")] for p in after[0].split()])
        assert first.shape != moved.shape or np.abs(first - moved).max() > 1.0
    finally:
        if page is not None:
            page.close()
        server.stop()


def _server_rev(view, camera) -> str:
    """The revision of the panel the server last drew for ``view``'s tab (under its lock: not mid-redraw)."""
    with view.lock:
        return re.search(r'data-rev="([^"]*)"', view.svgs[camera]).group(1)
