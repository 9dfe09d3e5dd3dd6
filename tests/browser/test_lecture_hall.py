"""The viewer in a lecture hall, measured in headless Chromium at 1366 x 768 and 1920 x 1080.

Panel sizes with four cameras, text sizes in presentation mode, the tutorial's
example scenes (every point inside its fitted panel), the view buttons and the
panel downloads. Text sizes are measured as the browser draws them: an SVG
text's computed font size (user units) times the SVG's screen scale.

``EGTVIZ_SCREENSHOTS=1`` also writes ``assets/screenshot-four-cameras.png``,
``assets/screenshot-present.png`` and ``assets/screenshot-example3.png``.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from _layout import only_view, settled_panels
from _waiting import PATIENCE
from egtviz.scene import SCENES, SceneModel, compute_derived, default_scene
from egtviz.viewer.server.browser import (
    close_notifications,
    folder_field,
    open_viewer,
    wait_for_3d_view,
    wait_for_js,
)
from egtviz.viewer.render.panels import MIN_PANEL_PX
from egtviz.viewer.render.svg import NORMAL, PRESENT

pytestmark = pytest.mark.browser


ASSETS = Path(__file__).resolve().parents[2] / "assets"
WINDOWS = [(1366, 768), (1920, 1080)]

#: Every shown image-plane panel: its camera, box on screen, frame box, and each text's size on screen in CSS px.
PANELS_JS = """() => [...document.querySelectorAll('svg[data-egtviz="image-plane"]')]
  .filter(s => s.getBoundingClientRect().width > 0)
  .map(s => {
    const scale = s.getScreenCTM().a;
    const texts = [...s.querySelectorAll('text')].filter(t => t.textContent.trim() && !t.querySelector('tspan'))
      .concat([...s.querySelectorAll('tspan')]);
    return {
      camera: s.dataset.camera, style: s.dataset.style, view: s.dataset.view,
      rect: s.getBoundingClientRect().toJSON(),
      frame: s.querySelector('[data-kind="frame"]').getBoundingClientRect().toJSON(),
      ticks: [...s.querySelectorAll('[data-kind="axes"] text')].map(
        t => parseFloat(getComputedStyle(t).fontSize) * scale),
      texts: texts.map(t => ({text: t.textContent, px: parseFloat(getComputedStyle(t).fontSize) * scale})),
    };
  })"""

#: Each drawn point of a panel (in or outside the image): its centre on screen and what the page shows there.
POINTS_JS = """(camera) => {
  const s = document.querySelector(`svg[data-egtviz="image-plane"][data-camera="${camera}"]`);
  return [...s.querySelectorAll('[data-kind="point"], [data-kind="point-outside"]')].map(p => {
    const c = p.tagName === 'circle' ? p : p.querySelector('circle');
    const r = c.getBoundingClientRect();
    const x = r.left + r.width / 2, y = r.top + r.height / 2;
    const hit = document.elementFromPoint(x, y);
    return {index: p.dataset.index, x, y, on_panel: hit !== null && s.contains(hit)};
  });
}"""


def _serve(scene, *, present=False):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, scene, present=present)
    return server, app, f"http://127.0.0.1:{server.get_port()}"


def _four_cameras():
    model = SceneModel(default_scene())
    model.add_camera("pinhole")
    model.add_camera("panoramic")
    return model.scene


def _settled_panels(page, app, n):
    """The panels once laid out as the tab's grid planned (:func:`_layout.settled_panels`), and the tab's view."""
    view = only_view(app)
    return settled_panels(page, view, n, lambda pg: pg.evaluate(PANELS_JS)), view()


def _disjoint(a, b) -> bool:
    return a["right"] <= b["left"] + 1 or b["right"] <= a["left"] + 1 or a["bottom"] <= b["top"] + 1 or b["bottom"] <= a["top"] + 1


def _screenshot(page, name):
    if os.environ.get("EGTVIZ_SCREENSHOTS"):
        close_notifications(page)
        wait_for_3d_view(page)  # software WebGL: the 3D view drawn and faded in
        page.screenshot(path=str(ASSETS / name))


@pytest.mark.parametrize(("width", "height"), WINDOWS)
def test_four_cameras_each_panel_readable(browser, width, height):
    server, app, url = _serve(_four_cameras())
    page = open_viewer(browser, url, width=width, height=height, n_panels=4)
    try:
        panels, view = _settled_panels(page, app, 4)
        assert sorted(p["camera"] for p in panels) == ["cam1", "cam2", "cam3", "pano1"]
        for i, p in enumerate(panels):
            r = p["rect"]
            assert r["width"] >= MIN_PANEL_PX
            assert r["left"] >= 0 and r["right"] <= width + 1 and r["bottom"] <= height + 1
            for q in panels[i + 1:]:
                assert _disjoint(r, q["rect"])
            # Drawn for the width it has: the axes' numbers are the style's size on screen, every text readable.
            assert p["ticks"] and all(abs(t - NORMAL.tick_px) < 0.3 for t in p["ticks"])
            assert min(t["px"] for t in p["texts"]) >= NORMAL.tick_px - 0.3
        # Panel width follows the window; the 3D view keeps a real share of it.
        canvas = page.evaluate("() => document.querySelector('canvas').getBoundingClientRect().toJSON()")
        assert canvas["width"] >= 0.28 * width
        assert all(canvas["right"] <= p["rect"]["left"] + 1 for p in panels)
        assert view.grid.column_px >= (0.22 * width if width >= 1900 else MIN_PANEL_PX)
        if (width, height) == (1366, 768):
            _screenshot(page, "screenshot-four-cameras.png")
    finally:
        page.close()
        server.stop()


def test_presentation_mode_text_is_16_px_at_1920(browser):
    server, app, url = _serve(_four_cameras(), present=True)
    page = open_viewer(browser, url, width=1920, height=1080, n_panels=4)
    try:
        panels, _view = _settled_panels(page, app, 4)
        for p in panels:
            assert p["style"] == "present"
            sizes = [t["px"] for t in p["texts"]]
            assert len(sizes) >= 10
            small = [t for t in p["texts"] if t["px"] < 16.0]
            assert not small, f"{p['camera']}: text under 16 px: {small}"
            assert all(abs(t - PRESENT.tick_px) < 0.3 for t in p["ticks"])
        # The GUI's type is larger too (Mantine's scale): a field label is at least 16 px.
        label_px = page.evaluate("() => parseFloat(getComputedStyle(document.querySelector('label')).fontSize)")
        assert label_px >= 16.0
        _screenshot(page, "screenshot-present.png")
    finally:
        page.close()
        server.stop()


def test_presentation_toggle_in_the_gui(browser):
    server, app, url = _serve(default_scene())
    page = open_viewer(browser, url, width=1920, height=1080, n_panels=2)
    try:
        panels, _ = _settled_panels(page, app, 2)
        assert {p["style"] for p in panels} == {"normal"}
        normal_label = page.evaluate("() => parseFloat(getComputedStyle(document.querySelector('label')).fontSize)")
        page.get_by_text("Panels", exact=True).first.click()
        page.get_by_text("presentation mode", exact=True).first.click()
        wait_for_js(page, """() => [...document.querySelectorAll('svg[data-egtviz="image-plane"]')]
            .every(s => s.dataset.style === 'present')""", "every panel drawn in the presentation style")
        panels, _ = _settled_panels(page, app, 2)
        assert min(t["px"] for p in panels for t in p["texts"]) >= 16.0
        label = page.evaluate("() => parseFloat(getComputedStyle(document.querySelector('label')).fontSize)")
        assert label == pytest.approx(1.25 * normal_label, rel=0.02)
    finally:
        page.close()
        server.stop()


@pytest.mark.parametrize("name", ["example1", "example2", "example3", "example4"])
@pytest.mark.parametrize(("width", "height"), WINDOWS)
def test_example_scenes_show_every_tutorial_point(browser, name, width, height):
    scene = SCENES[name]()
    derived = compute_derived(scene)
    server, app, url = _serve(scene)
    page = open_viewer(browser, url, width=width, height=height, n_panels=len(scene.cameras))
    try:
        panels, _ = _settled_panels(page, app, len(scene.cameras))
        for p in panels:
            plane = derived.image_planes[p["camera"]]
            points = page.evaluate(POINTS_JS, p["camera"])
            assert len(points) == int(np.asarray(plane.visible).sum()) >= 1
            f = p["frame"]
            for pt in points:
                assert f["left"] <= pt["x"] <= f["right"] and f["top"] <= pt["y"] <= f["bottom"], pt
                assert 0 <= pt["x"] <= width and 0 <= pt["y"] <= height
                assert pt["on_panel"], f"{name} {p['camera']}: point {pt['index']} is covered or scrolled away"
        if name == "example3" and (width, height) == (1366, 768):
            _screenshot(page, "screenshot-example3.png")
    finally:
        page.close()
        server.stop()


def _open_camera_folder(page, title):
    folder_field(page, title, "position x, y, z (m)")


def test_zoom_button_and_downloads(browser, tmp_path):
    server, app, url = _serve(default_scene())
    page = open_viewer(browser, url, width=1366, height=768, n_panels=2)
    try:
        _settled_panels(page, app, 2)
        _open_camera_folder(page, "cam1 (pin-hole)")
        page.get_by_role("button", name="+", exact=True).first.click()
        wait_for_js(page, """() => document.querySelector(
            'svg[data-egtviz="image-plane"][data-camera="cam1"]').dataset.view === '64 48 512 384'""",
            "cam1's panel zoomed to 64 48 512 384")

        with page.expect_download() as info:
            page.get_by_role("button", name="SVG", exact=True).first.click()
        svg_path = tmp_path / info.value.suggested_filename
        info.value.save_as(svg_path)
        assert svg_path.name == "cam1-image-plane.svg"
        root = ET.parse(svg_path).getroot()
        assert root.get("data-camera") == "cam1" and root.get("data-view") == "64 48 512 384"
        assert len(root.findall(".//*[@data-kind='point']")) == 8

        with page.expect_download() as info:
            page.get_by_role("button", name="PNG", exact=True).first.click()
        png_path = tmp_path / info.value.suggested_filename
        info.value.save_as(png_path)
        data = png_path.read_bytes()
        assert png_path.name == "cam1-image-plane.png" and data[:8] == b"\x89PNG\r\n\x1a\n"
        assert int.from_bytes(data[16:20], "big") == 2 * int(NORMAL.panel_px)
    finally:
        page.close()
        server.stop()


def test_high_density_screen_gets_the_layout_of_its_css_size(browser):
    """At 2 device pixels per CSS pixel the canvas reports 2732 x 1536: the grid is planned for 1366 x 768."""
    server, app, url = _serve(_four_cameras())
    page = browser.new_page(viewport={"width": 1366, "height": 768}, device_scale_factor=2)
    try:
        page.goto(url)
        wait_for_js(page, "() => document.querySelectorAll('svg[data-egtviz=\"image-plane\"]').length >= 4",
                    "4 image-plane panels")
        panels, view = _settled_panels(page, app, 4)
        assert view.grid.window.width == 1366 and view.grid.window.height == 768
        assert all(p["rect"]["width"] >= MIN_PANEL_PX for p in panels)
        assert all(p["rect"]["right"] <= 1366 + 1 for p in panels)
    finally:
        page.close()
        server.stop()


#: Every text a user can see on the page (not covered, not scrolled away; the browser's own "software WebGL" toast
#: aside): its size on screen in CSS px (an SVG text's computed size times the SVG's scale) and where it is.
PAGE_TEXTS_JS = """() => {
  const out = [];
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  while (walker.nextNode()) {
    const node = walker.currentNode, el = node.parentElement;
    if (!node.textContent.trim() || !el || el.closest('.mantine-Notification-root, style, script')) continue;
    const range = document.createRange(); range.selectNodeContents(node);
    const r = range.getBoundingClientRect();
    if (r.width < 1 || r.height < 1) continue;
    const x = r.left + r.width / 2, y = r.top + r.height / 2;
    if (x < 0 || y < 0 || x > innerWidth || y > innerHeight) continue;
    const hit = document.elementFromPoint(x, y);
    if (!hit || !(hit === el || el.contains(hit) || hit.contains(el))) continue;
    let px = parseFloat(getComputedStyle(el).fontSize);
    const svg = el.closest('svg');
    if (svg) px *= svg.getScreenCTM().a;
    out.push({text: node.textContent.trim().slice(0, 40), px, svg: svg ? svg.dataset.egtviz || '' : ''});
  }
  return out;
}"""

#: Each image-plane panel's scroll box: how far its content overflows (0: nothing scrolls).
PANEL_SCROLL_JS = """() => [...document.querySelectorAll('svg[data-egtviz="image-plane"]')]
  .filter(s => s.getBoundingClientRect().width > 0)
  .map(s => { let e = s.parentElement;
    while (e && !(['auto', 'scroll'].includes(getComputedStyle(e).overflowY))) e = e.parentElement;
    return {camera: s.dataset.camera, over: e ? e.scrollHeight - e.clientHeight : 0}; })"""


def _serve_app(*, present=False, **kw):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, present=present, **kw)
    return server, app, f"http://127.0.0.1:{server.get_port()}"


def _open(browser, url, selector, width, height):
    page = browser.new_page(viewport={"width": width, "height": height})
    page.goto(url)
    wait_for_js(page, f"() => document.querySelector('{selector}') !== null", selector)
    close_notifications(page)
    return page


def _smallest(page):
    """The smallest text a user sees on the page, and every such text, measured once the page's fonts are in."""
    page.evaluate("() => document.fonts.ready.then(() => true)")
    texts = page.evaluate(PAGE_TEXTS_JS)
    assert len(texts) >= 10
    return min(texts, key=lambda t: t["px"]), texts


@pytest.mark.parametrize(("width", "height"), WINDOWS)
@pytest.mark.parametrize("present", [False, True])
def test_start_page_uses_its_width_and_presentation_mode(browser, present, width, height):
    from egtviz.viewer.render.palette import PRESENT_MIN_TEXT_PX

    server, app, url = _serve_app(present=present, course=True)
    page = _open(browser, url, '[data-egtviz="start-preview"] svg[data-egtviz="image-plane"]', width, height)
    try:
        small, texts = _smallest(page)
        floor = PRESENT_MIN_TEXT_PX if present else NORMAL.tick_px
        assert small["px"] >= floor - 0.3, small
        assert any(t["svg"] == "image-plane" for t in texts)  # the preview's panels are seen, not covered
        # The preview fills the right of the window beside the page's column: no blank 60 %.
        box = page.evaluate("""() => { const p = document.querySelector('[data-egtviz="start-preview"]');
            const svgs = [...p.querySelectorAll('svg')].map(s => s.getBoundingClientRect().toJSON());
            const page = document.querySelector('[data-egtviz="start-page"]').getBoundingClientRect().toJSON();
            return {svgs, page}; }""")
        assert box["svgs"] and all(s["left"] >= box["page"]["right"] for s in box["svgs"])
        assert max(s["right"] for s in box["svgs"]) >= 0.9 * width
        assert sum(s["width"] for s in box["svgs"]) >= 0.4 * width
        # "Open the workbench" is a coloured button, not a grey (disabled-looking) one.
        rgb = page.evaluate("""() => { const b = [...document.querySelectorAll('button')]
            .find(b => b.textContent.includes('Open the workbench'));
            return getComputedStyle(b).backgroundColor.match(/\\d+/g).slice(0, 3).map(Number); }""")
        assert max(rgb) - min(rgb) >= 60, rgb
    finally:
        page.close()
        server.stop()


@pytest.mark.parametrize(("width", "height"), WINDOWS)
@pytest.mark.parametrize("present", [False, True])
def test_servo_demo_image_panel_is_readable(browser, present, width, height):
    from egtviz.viewer.render.palette import PRESENT_MIN_TEXT_PX

    server, app, url = _serve_app(present=present, demo="pinhole")
    page = _open(browser, url, 'svg[data-egtviz="servo-image"]', width, height)
    try:
        demo = app.wait_for_demo(timeout=PATIENCE)[0]
        assert demo.wait(PATIENCE), "the demo's run did not finish"
        demo.pause()
        demo.seek(0)  # a frame the page is known to show: the run's first
        wait_for_js(page, "() => document.querySelector('svg[data-egtviz=\"servo-image\"]')?.dataset.frame === '0'",
                    "the servo image at frame 0")
        small, texts = _smallest(page)
        image = [t for t in texts if t["svg"] == "servo-image"]
        assert image
        floor = PRESENT_MIN_TEXT_PX if present else NORMAL.tick_px
        assert min(t["px"] for t in image) >= floor - 0.3, min(image, key=lambda t: t["px"])
        if present:
            assert small["px"] >= PRESENT_MIN_TEXT_PX - 0.3, small
    finally:
        page.close()
        server.stop()


@pytest.mark.parametrize(("width", "height"), WINDOWS)
def test_workbench_in_presentation_mode_reads_and_no_panel_scrolls(browser, width, height):
    from egtviz.viewer.render.palette import PRESENT_MIN_TEXT_PX

    scene = SCENES["example3"]()
    server, app, url = _serve(scene, present=True)
    page = open_viewer(browser, url, width=width, height=height, n_panels=2)
    try:
        close_notifications(page)
        _settled_panels(page, app, 2)
        page.evaluate("() => document.fonts.ready.then(() => true)")
        assert all(p["over"] <= 1 for p in page.evaluate(PANEL_SCROLL_JS)), page.evaluate(PANEL_SCROLL_JS)
        # Every status line is on screen (none hidden under the cell's edge).
        texts = page.evaluate(PAGE_TEXTS_JS)
        assert sum("outside the image" in t["text"] for t in texts) == 2
        readout = page.evaluate("""() => { const r = document.querySelector('[data-egtviz="readout"]');
            return [...r.querySelectorAll('*')].concat([r]).filter(e => e.childNodes.length && [...e.childNodes]
              .some(n => n.nodeType === 3 && n.textContent.trim())).map(e => parseFloat(getComputedStyle(e).fontSize)); }""")
        assert readout and min(readout) >= PRESENT_MIN_TEXT_PX - 0.3, readout
        if width >= 1900:
            small = min(texts, key=lambda t: t["px"])
            assert small["px"] >= PRESENT_MIN_TEXT_PX - 0.3, small
    finally:
        page.close()
        server.stop()
