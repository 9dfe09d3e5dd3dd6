"""Real-browser tests: headless Debian Chromium (playwright) against an in-process egtviz server.

They skip only when /usr/bin/chromium is missing on a developer machine; with
``CI`` set, a missing browser is a failure.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from egtviz.scene import compute_derived, default_scene, panoramic_scene
from egtviz.viewer.server.browser import (
    COUNT_JS,
    LINES_JS,
    chromium,
    folder_field,
    open_viewer,
)

pytestmark = pytest.mark.browser



def _serve(scene):
    import viser

    from egtviz.viewer.workbench.app import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, scene)
    return server, app, f"http://127.0.0.1:{server.get_port()}"


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


@pytest.fixture(scope="module")
def pinhole_server():
    server, app, url = _serve(default_scene())
    yield app, url
    server.stop()


@pytest.fixture(scope="module")
def panoramic_server():
    server, app, url = _serve(panoramic_scene())
    yield app, url
    server.stop()


def _disjoint(a, b) -> bool:
    return a["right"] <= b["left"] + 1 or b["right"] <= a["left"] + 1 or a["bottom"] <= b["top"] + 1 or b["bottom"] <= a["top"] + 1


def test_default_scene_panels(browser, pinhole_server):
    app, url = pinhole_server
    page = open_viewer(browser, url)
    try:
        counts = page.evaluate(COUNT_JS)
        assert set(counts) == {"cam1", "cam2"}
        derived = compute_derived(default_scene())
        for name, c in counts.items():
            ip = derived.image_planes[name]
            assert c["border"] == 1
            assert c["point"] == int(ip.in_image.sum()) == 8
            assert c["line"] == 8
            assert c["epipole"] == len(ip.epipoles) == 1
        # Panels side by side with nothing overlapping, inside the window, right of the 3D view's centre.
        r1, r2 = counts["cam1"]["rect"], counts["cam2"]["rect"]
        assert _disjoint(r1, r2)
        for r in (r1, r2):
            assert r["width"] > 250 and r["left"] > 800 and r["bottom"] <= 900 + 1
    finally:
        page.close()


def test_panoramic_scene_panels(browser, panoramic_server):
    app, url = panoramic_server
    page = open_viewer(browser, url)
    try:
        counts = page.evaluate(COUNT_JS)
        derived = compute_derived(panoramic_scene())
        assert set(counts) == {"pano1", "pano2"}
        for name, c in counts.items():
            ip = derived.image_planes[name]
            assert c["rim"] >= 1
            assert c["point"] == int(ip.in_image.sum())
            assert c["epipole"] == len(ip.epipoles) == 2
            assert c["conic"] == sum(1 for arcs in ip.conics if any(len(a) >= 2 for a in arcs))
            assert c["conic"] > 0 and c["line"] == 0
    finally:
        page.close()


def _wait_rev_change(page, camera, rev, timeout=15.0):
    deadline = time.time() + timeout
    while time.time() < deadline:
        now = page.evaluate(COUNT_JS)[camera]["rev"]
        if now != rev:
            return now
        time.sleep(0.05)
    raise AssertionError(f"panel {camera} did not update (data-rev stayed {rev})")


def _edit_focal(page, value: str) -> None:
    field = folder_field(page, "cam1 (pin-hole)", "focal length (mm)")
    field.click()
    field.fill(value)
    field.press("Enter")


def test_editing_a_field_moves_the_epipolar_lines(browser, pinhole_server):
    app, url = pinhole_server
    page = open_viewer(browser, url)
    try:
        before = np.array(page.evaluate(LINES_JS, "cam1"))
        rev = page.evaluate(COUNT_JS)["cam1"]["rev"]
        _edit_focal(page, "12")
        _wait_rev_change(page, "cam1", rev)
        time.sleep(0.3)  # typing may send a few updates; let them settle
        after = np.array(page.evaluate(LINES_JS, "cam1"))
        assert before.shape == after.shape == (8, 4)
        assert not np.allclose(before, after, atol=0.5)
        views = [v for v in app.views.values() if abs(v.model.scene.camera("cam1").focal_length - 0.012) < 1e-12]
        assert len(views) == 1
    finally:
        page.close()


def test_invalid_value_is_refused_in_the_browser(browser, pinhole_server):
    app, url = pinhole_server
    page = open_viewer(browser, url)
    try:
        _edit_focal(page, "-3")
        page.get_by_text("Value refused").first.wait_for(timeout=10_000)
        assert all(v.model.scene.camera("cam1").focal_length > 0 for v in app.views.values())
    finally:
        page.close()


@pytest.mark.parametrize("text", ["nan", "abc", "1e400", "8.5e"])
def test_text_a_number_field_cannot_read_is_refused_and_reverted(browser, pinhole_server, text):
    """Typed key by key, as a user would: the server sees the text, refuses it, and the field shows 8 again."""
    app, url = pinhole_server
    page = open_viewer(browser, url)
    try:
        field = folder_field(page, "cam1 (pin-hole)", "focal length (mm)")
        field.click()
        field.press("Control+a")
        field.press_sequentially(text, delay=30)
        page.get_by_text("Value refused").first.wait_for(timeout=10_000)
        page.wait_for_function(
            "(el) => el.value === '8'", arg=field.element_handle(), timeout=10_000)
        assert page.get_by_text("cam1: focal length").count() >= 1
        assert all(v.model.scene.camera("cam1").focal_length == pytest.approx(0.008) for v in app.views.values())
    finally:
        page.close()


def test_second_tab_edits_do_not_reach_the_first(browser, pinhole_server):
    app, url = pinhole_server
    first = open_viewer(browser, url)
    second = open_viewer(browser, url)
    try:
        lines_first = first.evaluate(LINES_JS, "cam1")
        rev_first = first.evaluate(COUNT_JS)["cam1"]["rev"]
        rev_second = second.evaluate(COUNT_JS)["cam1"]["rev"]
        _edit_focal(second, "15")
        _wait_rev_change(second, "cam1", rev_second)
        time.sleep(0.5)
        assert first.evaluate(COUNT_JS)["cam1"]["rev"] == rev_first
        assert first.evaluate(LINES_JS, "cam1") == lines_first
        assert np.array(second.evaluate(LINES_JS, "cam1")).shape == (8, 4)
    finally:
        first.close()
        second.close()


def test_screenshot_script_writes_a_png(browser, tmp_path):
    from egtviz.viewer.server.screenshot import take_screenshot

    out = take_screenshot(tmp_path / "shot.png", browser=browser)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
