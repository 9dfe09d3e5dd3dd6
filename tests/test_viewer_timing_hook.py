"""The viewer's public timing hook (``ClientView.on_update_timed``) and the benchmarks' use of it."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from egtviz.scene import default_scene
from egtviz.viewer.workbench.app import UpdateTiming
from egtviz.viewer.server.headless import start_headless

BENCH = Path(__file__).resolve().parents[1] / "egtviz" / "bench"


@pytest.fixture
def view():
    server, _app, fakes, views = start_headless(default_scene())
    yield views[0]
    for f in fakes:
        f.close()
    server.stop()


def test_each_applied_update_reports_its_parts_once(view):
    seen: list[UpdateTiming] = []
    view.on_update_timed = seen.append
    view.user_event(lambda: view.model.add_point((0.5, 0.5, 1.0)))
    assert [t.revision for t in seen] == [view.revision]
    (timing,) = seen
    assert set(timing.cpu) == {"derived", "svg", "fields", "scene3d", "flush", "render", "event"}
    assert set(timing.wall) == {"model", "derived", "svg", "fields", "scene3d", "flush"}
    # The parts are consecutive spans of the render, and the render is a span of the event.
    parts = sum(timing.cpu[k] for k in ("derived", "svg", "fields", "scene3d", "flush"))
    assert parts <= timing.cpu["render"] + 1e-9 <= timing.cpu["event"] + 2e-9
    assert timing.wall == view.breakdown


def test_a_redraw_no_event_started_reports_no_event_time(view):
    seen: list[UpdateTiming] = []
    view.on_update_timed = seen.append
    view.redraw()
    assert len(seen) == 1 and seen[0].cpu["event"] == 0.0 and seen[0].wall["model"] == 0.0


def _private_reaches(path: Path) -> list[str]:
    """Attribute names starting with one underscore that the module reads off anything but ``self``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if (isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")
                and not (isinstance(node.value, ast.Name) and node.value.id == "self")):
            found.append(f"{path.name}:{node.lineno} .{node.attr}")
    return found


@pytest.mark.parametrize("name", ["classroom.py", "viewer.py"])
def test_the_viewer_benchmarks_reach_no_private_names(name):
    # The viewer's timing hook and egtviz.viewer.server.viser_adapter are their only way in.
    assert _private_reaches(BENCH / name) == []
