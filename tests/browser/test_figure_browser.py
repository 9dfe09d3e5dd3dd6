"""A real browser shows an EGT figure: the EGT paper's Example 3 run as a script against the figure server.

The page must draw, besides both cameras' own image panels, the two plot panels the script's plotting
arguments asked for (``Figure 1``, ``Figure 2``), each with the two points, their two epipolar lines and the
epipole, counted in the page by ``data-kind``.
"""

from __future__ import annotations

import runpy
from pathlib import Path

import pytest

import egtviz.egt_figure as ef
from egtviz.egt_figure import _server
from _layout import only_view, settled_panels
from egtviz.scene import compute_derived
from egtviz.viewer.server.browser import COUNT_JS, open_viewer

pytestmark = pytest.mark.browser


EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture
def example_3_served(monkeypatch):
    """Example 3 run as a script (``--no-wait``) with the figure server on a free port."""
    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    monkeypatch.setattr(_server, "FIRST_PORT", 0)  # any free port
    monkeypatch.setattr("sys.argv", ["03_pinhole_epipolar.py", "--no-wait"])
    ef.reset()
    try:
        runpy.run_path(str(EXAMPLES / "03_pinhole_epipolar.py"), run_name="__main__")
        yield ef.server_url(), ef.current_figure().scene()
    finally:
        ef.stop_server()
        ef.reset()


def test_example_3_figure_in_the_browser(browser, example_3_served):
    url, scene = example_3_served
    assert url is not None
    derived = compute_derived(scene)
    page = open_viewer(browser, url, width=1366, height=768, n_panels=4)
    try:
        counts = settled_panels(page, only_view(ef._running.app), 4, lambda pg: pg.evaluate(COUNT_JS))
        assert set(counts) == {"cam1", "cam2", "Figure 1", "Figure 2"}
        for name in ("Figure 1", "Figure 2"):
            c = counts[name]
            # Two points, a line through each, one epipole; K = I gives no image rectangle.
            assert (c["point"], c["line"], c["epipole"], c["border"]) == (2, 2, 1, 0), (name, c)
        for name in ("cam1", "cam2"):
            c, plane = counts[name], derived.image_planes[name]
            assert c["point"] == int(plane.in_image.sum())
            assert c["line"] == 2 and c["epipole"] == len(plane.epipoles) == 1 and c["border"] == 1
        # Every panel is on screen and none overlaps another.
        rects = [c["rect"] for c in counts.values()]
        for i, a in enumerate(rects):
            assert a["width"] > 150 and a["bottom"] <= 768 + 1
            for b in rects[i + 1:]:
                assert (a["right"] <= b["left"] + 1 or b["right"] <= a["left"] + 1
                        or a["bottom"] <= b["top"] + 1 or b["bottom"] <= a["top"] + 1)
    finally:
        page.close()
