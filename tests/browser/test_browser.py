"""Real-browser tests: headless Debian Chromium (playwright) against an in-process egtviz server.

They skip only when /usr/bin/chromium is missing on a developer machine; with
``CI`` set, a missing browser is a failure.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from _layout import settled_panels
from _waiting import wait_for
from egtviz.scene import compute_derived, default_scene, panoramic_scene
from egtviz.viewer.server.browser import (
    COUNT_JS,
    LINES_JS,
    folder_field,
    open_viewer,
    wait_for_js,
)

pytestmark = pytest.mark.browser



def _serve(scene):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, scene)
    return server, app, f"http://127.0.0.1:{server.get_port()}"


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
    before_ids = set(app.views)
    page = open_viewer(browser, url)
    try:
        view = _the_view(app, before_ids)
        counts = settled_panels(page, lambda: view, 2, lambda pg: pg.evaluate(COUNT_JS))
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


#: The revision of a panel as the page shows it.
REV_JS = """(camera) => document.querySelector(`svg[data-egtviz="image-plane"][data-camera="${camera}"]`)?.dataset.rev"""


def _server_rev(view, camera) -> str:
    """The revision of the panel the server last drew for ``view``'s tab (under its lock: not mid-redraw)."""
    with view.lock:
        return re.search(r'data-rev="([^"]*)"', view.svgs[camera]).group(1)


def _the_view(app, before: set[int]):
    """The server's view of the tab that connected after ``before`` (a set of client ids)."""
    new: list[int] = []
    wait_for(lambda: new.extend(set(app.views) - before) or new, "the page's tab to connect")
    return app.views[new[0]]


def _wait_caught_up(page, view, camera) -> None:
    """Wait until ``page`` shows the panel the server last drew for its tab."""
    wait_for(lambda: page.evaluate(REV_JS, camera) == _server_rev(view, camera),
             f"{camera}'s panel in the page at the server's last revision")


def _edit_focal(page, value: str) -> None:
    field = folder_field(page, "cam1 (pin-hole)", "focal length (mm)")
    field.click()
    field.fill(value)
    field.press("Enter")


def test_editing_a_field_moves_the_epipolar_lines(browser, pinhole_server):
    app, url = pinhole_server
    before_ids = set(app.views)
    page = open_viewer(browser, url)
    try:
        view = _the_view(app, before_ids)
        before = np.array(page.evaluate(LINES_JS, "cam1"))
        _edit_focal(page, "12")
        # Typing may send a few updates: the last one (12 mm) judged, and the page showing what followed it.
        wait_for(lambda: abs(view.model.scene.camera("cam1").focal_length - 0.012) < 1e-12,
                 "the server to take cam1's focal length 12 mm")
        _wait_caught_up(page, view, "cam1")
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
        page.get_by_text("Value refused").first.wait_for()
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
        page.get_by_text("Value refused").first.wait_for()
        wait_for_js(page, "(el) => el.value === '8'", "the field to show 8 again", arg=field.element_handle())
        assert page.get_by_text("cam1: focal length").count() >= 1
        assert all(v.model.scene.camera("cam1").focal_length == pytest.approx(0.008) for v in app.views.values())
    finally:
        page.close()


def test_second_tab_edits_do_not_reach_the_first(browser, pinhole_server):
    app, url = pinhole_server
    before_ids = set(app.views)
    first = open_viewer(browser, url)
    view_first = _the_view(app, before_ids)
    second = open_viewer(browser, url)
    view_second = _the_view(app, before_ids | {view_first.client.client_id})
    try:
        lines_first = first.evaluate(LINES_JS, "cam1")
        rev_first = first.evaluate(COUNT_JS)["cam1"]["rev"]
        _edit_focal(second, "15")
        wait_for(lambda: abs(view_second.model.scene.camera("cam1").focal_length - 0.015) < 1e-12,
                 "the server to take the second tab's focal length 15 mm")
        _wait_caught_up(second, view_second, "cam1")
        # The second tab's edit was handled (the server drew it, its page shows it): the first tab's model, the
        # panel the server drew for it and the panel its page shows are as they were.
        assert view_first.model.scene.camera("cam1").focal_length == pytest.approx(0.008)
        assert _server_rev(view_first, "cam1") == rev_first
        assert first.evaluate(COUNT_JS)["cam1"]["rev"] == rev_first
        assert first.evaluate(LINES_JS, "cam1") == lines_first
        assert np.array(second.evaluate(LINES_JS, "cam1")).shape == (8, 4)
    finally:
        first.close()
        second.close()


def test_screenshot_script_writes_a_png(browser, tmp_path, monkeypatch):
    import types

    from egtviz.viewer.server import screenshot
    from egtviz.viewer.server.screenshot import take_screenshot

    # The script sleeps 6 s for the 3D view to draw and fade in: its picture's looks, which nothing here judges.
    monkeypatch.setattr(screenshot, "time", types.SimpleNamespace(sleep=lambda seconds: None))
    out = take_screenshot(tmp_path / "shot.png", browser=browser)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
