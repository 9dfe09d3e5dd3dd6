"""Real-browser tests of ``egtviz serve --demo pinhole`` and ``--demo panoramic`` (headless Debian Chromium,
in-process server, a 1366x768 window).

Skips only when /usr/bin/chromium is missing and ``CI`` is unset.
"""

from __future__ import annotations

import pytest

from _waiting import PATIENCE
from egtviz.viewer.server.browser import wait_for_js

pytestmark = pytest.mark.browser


SVG = 'svg[data-egtviz="servo-image"]'


@pytest.mark.parametrize("kind, curve", [("pinhole", "epipolar-line"), ("panoramic", "epipolar-conic")])
def test_demo_plays_in_the_browser(browser, kind, curve):
    from egtviz.viewer.server.launch import start

    server, app = start("127.0.0.1", 0, demo=kind)
    page = browser.new_page(viewport={"width": 1366, "height": 768})
    try:
        page.goto(f"http://127.0.0.1:{server.get_port()}")
        page.wait_for_selector(SVG)
        demo = app.wait_for_demo(timeout=PATIENCE)[0]
        assert demo.kind == kind and demo.wait(PATIENCE), f"the {kind} demo's run did not finish"
        demo.pause()
        demo.seek(0)
        wait_for_js(page, f"() => document.querySelector('{SVG}')?.dataset.frame === '0'", "the image at frame 0")
        n = len(demo.result.desired_features)
        counts = page.evaluate(f"""() => {{ const s = document.querySelector('{SVG}');
            return {{point: s.querySelectorAll('[data-kind="point"]').length,
                     curve: new Set([...s.querySelectorAll('[data-kind="{curve}"]')].map(e => e.dataset.index)).size,
                     epipole: s.querySelectorAll('[data-kind="epipole"]').length,
                     desired: s.querySelectorAll('[data-kind="desired"]').length}}; }}""")
        # Every feature and its desired position; a line or bi-conic per feature; e (and e' through a mirror).
        assert counts["point"] == n and counts["desired"] == n and counts["curve"] >= n - 1
        assert counts["epipole"] == len(demo.frames.at(0).epipoles) >= 1
        # Press the real Play button: the image plane changes (new frame, trails appear).
        page.get_by_role("button", name="Play").first.click()
        wait_for_js(page, f"() => Number(document.querySelector('{SVG}')?.dataset.frame) > 3 && "
                    f"document.querySelectorAll('{SVG} [data-kind=\"trail\"]').length > 0",
                    "the image past frame 3, with trails")
        assert demo.playing or demo.frame > 3
        # The uPlot charts are canvases in the panel.
        assert page.locator(".uplot canvas").count() >= 2
    finally:
        page.close()
        server.stop()
