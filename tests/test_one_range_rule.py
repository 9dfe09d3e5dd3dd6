"""A lesson's ranges have one rule, the scene's (``CameraRanges.breaches``): a dragged pose passes it once on its
way from the gizmo to the model, and the typed fields, the model and the check at answer time all ask it."""

from __future__ import annotations

import dataclasses
import types

import numpy as np
import pytest

from egtviz.geometry.poses import matrix_from_quat_wxyz
from egtviz.lessons import LessonRun, parse_lesson
from egtviz.scene import SceneModel
from egtviz.scene.constraints import Breach, CameraRanges
from egtviz.scene.examples import default_scene
from egtviz.controllers.lesson_rules import range_refusal
from egtviz.viewer.course.lesson_view import LessonPanel
from egtviz.viewer.server.headless import start_headless
from egtviz.viewer.server.viser_adapter import gizmo_moved_by_client
from egtviz.controllers.workbench_fields import FieldError

from test_lesson_gizmo_ranges import LESSON


@pytest.fixture
def panel():
    """A headless tab running the ranges lesson (cam1's position in -8..2, then its angles in -30..30)."""
    server, _app, fakes, (view,) = start_headless()
    try:
        yield LessonPanel(view, LessonRun(parse_lesson(LESSON, source="ranges.toml", name="ranges"), model=view.model))
    finally:
        for f in fakes:
            f.close()
        server.stop()


@pytest.fixture
def rule_calls(monkeypatch):
    """How often the range rule has run (a spy on ``CameraRanges.breaches``)."""
    calls = []
    rule = CameraRanges.breaches

    def spy(self, camera, fields):
        calls.append((camera, dict(fields)))
        return rule(self, camera, fields)

    monkeypatch.setattr(CameraRanges, "breaches", spy)
    return calls


def gizmo_event(view, phase: str, position) -> types.SimpleNamespace:
    """A ``phase`` event of cam1's gizmo, moved to ``position`` by an update (its rotation unchanged), as viser
    hands it over."""
    gizmo = view.scene3d.gizmo("cam1")
    if phase == "update":
        gizmo_moved_by_client(gizmo, np.asarray(position, float))
    return types.SimpleNamespace(target=gizmo, phase=phase, client=None, client_id=None)


def test_a_dragged_pose_passes_the_range_rule_once_per_update(panel, rule_calls):
    view = panel.view
    view.drag.camera_event("cam1", gizmo_event(view, "start", None))
    assert rule_calls == []
    for x in (0.0, 1.5, 6.0, 9.0, -20.0):
        before = len(rule_calls)
        view.drag.camera_event("cam1", gizmo_event(view, "update", (x, -9.0, 1.5)))
        assert len(rule_calls) == before + 1, f"the rule ran {len(rule_calls) - before} times for x = {x}"
        assert view.model.scene.camera("cam1").position == (min(max(x, -8.0), 2.0), -8.0, 1.5)
    before = len(rule_calls)
    view.drag.camera_event("cam1", gizmo_event(view, "end", None))
    assert len(rule_calls) == before + 1


def test_every_route_asks_the_one_rule(panel, monkeypatch):
    # With the rule allowing everything, nothing else stops the camera or refuses a value: no second rule.
    view = panel.view
    monkeypatch.setattr(CameraRanges, "breaches", lambda self, camera, fields: [])
    view.drag.camera_event("cam1", gizmo_event(view, "start", None))
    view.drag.camera_event("cam1", gizmo_event(view, "update", (9.0, -11.0, 1.5)))
    assert view.model.scene.camera("cam1").position == (9.0, -11.0, 1.5)  # the drag
    view.controller.set_field("cam1", "position", "12, -8, 1.5")
    assert view.model.scene.camera("cam1").position == (12.0, -8.0, 1.5)  # a typed value
    assert range_refusal(panel.run) is None  # the check at answer time
    panel.row("right").button.value = True
    assert "must stay between" not in panel.row("right").feedback.content
    # And with a rule that refuses every value, every route refuses, with the rule's breach in the GUI's words.
    monkeypatch.setattr(CameraRanges, "breaches", lambda self, camera, fields: [
        Breach(camera, f, v, self.ranges()[(camera, f)]) for f, v in fields.items() if (camera, f) in self.ranges()])
    with pytest.raises(FieldError, match=r"cam1's position must stay between -8 m and 2 m \(it is 1 m, -8 m, 1.5 m\)"):
        view.controller.set_field("cam1", "position", "1, -8, 1.5")
    assert range_refusal(panel.run).startswith("In this step cam1's position must stay between -8 m and 2 m")


def test_a_drag_held_at_the_stop_commits_nothing_and_its_gizmo_goes_back_when_released(panel):
    view = panel.view
    gizmo = view.scene3d.gizmo("cam1")
    view.drag.camera_event("cam1", gizmo_event(view, "start", None))
    view.drag.camera_event("cam1", gizmo_event(view, "update", (9.0, -8.0, 1.5)))
    view.drag.camera_event("cam1", gizmo_event(view, "end", None))
    at_stop = view.model.scene
    assert at_stop.camera("cam1").position == (2.0, -8.0, 1.5)
    assert np.allclose(gizmo.position, (2.0, -8.0, 1.5))
    # Dragged on past the stop: the camera stays, nothing is committed, the gizmo follows the pointer...
    view.drag.camera_event("cam1", gizmo_event(view, "start", None))
    view.drag.camera_event("cam1", gizmo_event(view, "update", (12.0, -8.0, 1.5)))
    assert view.model.scene is at_stop and np.allclose(gizmo.position, (12.0, -8.0, 1.5))
    # ... and is put back on the camera when released.
    view.drag.camera_event("cam1", gizmo_event(view, "end", None))
    assert view.model.scene is at_stop and np.allclose(gizmo.position, (2.0, -8.0, 1.5))


@dataclasses.dataclass(frozen=True)
class Limit:
    low: float
    high: float


def test_an_orientation_out_of_range_keeps_the_cameras_very_rotation():
    model = SceneModel(default_scene())
    model.set_constraints(CameraRanges(lambda: {("cam1", "ypr_deg"): Limit(-30.0, 30.0)}))
    spec = model.scene.camera("cam1")
    q = np.array([0.7, -0.7, 0.13, -0.12])
    R = matrix_from_quat_wxyz(q / np.linalg.norm(q))  # a gizmo's rotation within the range
    assert model.set_camera_pose("cam1", spec.position, R) is True
    kept = model.scene.camera("cam1").pose.R
    assert np.array_equal(kept, R)
    turned = spec.with_pose(ypr_deg=(80.0, 0.0, 0.0)).pose.R
    assert model.set_camera_pose("cam1", (1.0, -8.0, 1.5), turned) is True  # the centre moves, the rotation stays
    after = model.scene.camera("cam1")
    assert after.position == (1.0, -8.0, 1.5) and np.array_equal(after.pose.R, kept)
    same = model.scene
    assert model.set_camera_pose("cam1", (1.0, -8.0, 1.5), turned) is False and model.scene is same
    # A pose the caller deems unmoved (a gizmo's rounding) is not committed either.
    nudged = np.add(after.position, 1e-12)
    assert model.set_camera_pose("cam1", nudged, R, unmoved=lambda a, b: True) is False and model.scene is same


def test_the_rule_reports_each_breach_in_field_order_and_reads_a_missing_value_as_outside():
    ranges = CameraRanges(lambda: {("cam1", "position"): Limit(-1.0, 1.0), ("cam1", "focal_length"): Limit(0.005, 0.01)})
    found = ranges.breaches("cam1", {"position": (0.0, 2.0, 0.0), "focal_length": 0.02, "ypr_deg": (90.0, 0, 0)})
    assert [(b.field, b.value) for b in found] == [("focal_length", 0.02), ("position", (0.0, 2.0, 0.0))]
    assert ranges.breaches("cam1", {"position": (1.0 + 1e-12, -1.0, 0.0)}) == []  # rounding: inside
    assert ranges.breaches("cam2", {"position": (9.0, 9.0, 9.0)}) == []
    assert [b.field for b in ranges.breaches("cam1", {"focal_length": None})] == ["focal_length"]
    assert ranges.scene_refusal(default_scene()).startswith("In this step cam1's")
