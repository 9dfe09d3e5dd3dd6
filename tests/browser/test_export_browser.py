"""An exported lesson step opened from disk (``file://``) in Chromium: the step's text, its formulas and the 3D
scene, with nothing fetched from anywhere but the export's own files."""

from __future__ import annotations

import pytest

from egtviz.viewer.export import export_lesson
from egtviz.viewer.server.browser import chromium

pytestmark = pytest.mark.browser
TIMEOUT_MS = 60_000


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("export") / "step"
    return export_lesson("06-pinhole-epipolar", 1, out)


def test_the_page_opens_from_disk_with_the_step_text_and_a_drawn_3d_scene(exported):
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 800})
        fetched, console = [], []
        page.on("request", lambda r: fetched.append(r.url))
        page.on("console", lambda m: console.append(m.text))
        page.goto(exported.as_uri())
        assert page.locator("h1").inner_text() == "Step 1 of 3: The epipolar plane"
        text = page.locator('[data-egtviz="export-text"]')
        assert "the segment" in text.inner_text() and "baseline" in text.inner_text()
        assert text.locator("math").count() >= 5  # the formulas, as MathML
        assert text.locator("strong", has_text="epipolar plane").count() == 1
        frame = page.frame_locator('iframe[data-egtviz="export-scene"]')
        canvas = frame.locator("canvas").first
        canvas.wait_for(timeout=TIMEOUT_MS)
        page.wait_for_function("() => true")  # let the frame's scripts run
        box = canvas.bounding_box()
        assert box is not None and box["width"] > 500 and box["height"] > 500
        page.wait_for_timeout(4000)  # software WebGL: a few frames to draw the recorded nodes
        shot = canvas.screenshot()
        assert any("Embedded data loaded" in line for line in console), console[-10:]
        page.close()
    assert fetched and all(url.startswith(("file:", "data:", "blob:")) for url in fetched), fetched
    # Drawn: the grid, the cameras, the points and the panels' pictures leave many colours on the canvas.
    import imageio.v3 as iio
    import numpy as np

    pixels = np.asarray(iio.imread(shot, extension=".png"))[..., :3].reshape(-1, 3)
    colours = {tuple(int(v) // 16 for v in p) for p in pixels[:: max(1, len(pixels) // 20000)]}
    assert len(colours) > 40, len(colours)
