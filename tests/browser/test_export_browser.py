"""An exported lesson step opened from disk (``file://``) in Chromium: the step's text, its formulas and the 3D
scene, with nothing fetched from anywhere but the export's own files."""

from __future__ import annotations

import time

import pytest

from _waiting import PATIENCE
from egtviz.viewer.export import export_lesson

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("export") / "step"
    return export_lesson("06-pinhole-epipolar", 1, out)


def _colours(png: bytes) -> int:
    """How many colours (4 bits a channel) a sample of the picture's pixels has."""
    import imageio.v3 as iio
    import numpy as np

    pixels = np.asarray(iio.imread(png, extension=".png"))[..., :3].reshape(-1, 3)
    return len({tuple(int(v) // 16 for v in p) for p in pixels[:: max(1, len(pixels) // 20000)]})


def test_the_page_opens_from_disk_with_the_step_text_and_a_drawn_3d_scene(browser, exported):
    page = browser.new_page(viewport={"width": 1400, "height": 800})
    fetched, console = [], []
    try:
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
        canvas.wait_for()
        box = canvas.bounding_box()
        assert box is not None and box["width"] > 500 and box["height"] > 500
        # Drawn: the grid, the cameras, the points and the panels' pictures leave many colours on the canvas.
        # Software WebGL takes a few frames to draw the recorded nodes: the canvas is looked at until it has.
        deadline, colours = time.monotonic() + PATIENCE, 0
        while colours <= 40 and time.monotonic() < deadline:
            colours = _colours(canvas.screenshot())
        assert colours > 40, f"waited {PATIENCE:.0f} s for the scene drawn on the canvas: {colours} colours"
        assert any("Embedded data loaded" in line for line in console), console[-10:]
        page.wait_for_load_state("networkidle")  # whatever the page fetches, it has asked for it
    finally:
        page.close()
    assert fetched and all(url.startswith(("file:", "data:", "blob:")) for url in fetched), fetched
