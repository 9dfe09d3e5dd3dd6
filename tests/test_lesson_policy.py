"""A tab's lesson policy: the workbench's allows everything; a lesson's filters the panels and narrows the ranges."""

from __future__ import annotations

import re

import numpy as np
import pytest

from egtviz.bench.viewer import _drag_event
from egtviz.scene import default_scene
from egtviz.scene.constraints import CameraRanges
from egtviz.controllers.workbench_fields import FieldError
from egtviz.viewer.server.headless import start_headless
from egtviz.viewer.workbench.lesson_policy import ALLOW_ALL, LessonPolicy


@pytest.fixture
def view():
    server, _app, fakes, views = start_headless(default_scene())
    yield views[0]
    for f in fakes:
        f.close()
    server.stop()


def test_the_workbench_policy_allows_everything():
    assert ALLOW_ALL.panels("scene", "derived") == ("derived", frozenset())
    assert ALLOW_ALL.refusal("cam1", {"position": (1.0, 2.0, 3.0)}) is None


def test_a_policys_field_guard_refuses_a_typed_value_and_the_model_keeps_its_own(view):
    assert view.policy is ALLOW_ALL and view.panel_filter is None
    view.policy = LessonPolicy(field_guard=lambda camera, fields: f"{camera}: not in this lesson")
    before = view.model.scene.camera("cam1").position
    with view.lock, pytest.raises(FieldError, match="cam1: not in this lesson"):
        view.controller.set_field("cam1", "position", "1, 2, 3")
    assert view.model.scene.camera("cam1").position == before


def test_a_dragged_camera_goes_where_the_models_constraints_put_it(view):
    # No policy hook rewrites a gizmo's pose: the scene model's ranges stop the camera.
    assert not hasattr(LessonPolicy(), "pose_guard")
    limit = type("Limit", (), {"low": -1.0, "high": 0.5})
    view.model.set_constraints(CameraRanges(lambda: {("cam1", "position"): limit}))
    gizmo = view.scene3d.gizmo("cam1")
    view.drag.camera_event("cam1", _drag_event(gizmo, np.array([2.0, 0.25, 3.0])))
    assert view.model.scene.camera("cam1").position == pytest.approx((0.5, 0.25, 0.5))


def test_a_policys_panel_filter_draws_the_panels(view):
    rung = []

    def ring_point_one(scene, derived):
        rung.append(scene.title)
        return derived, frozenset({0})

    view.redraw()
    plain = re.sub(r' data-rev="\d+"', "", view.svgs["cam1"])
    view.policy = LessonPolicy(panel_filter=ring_point_one)
    view.redraw()
    ringed = re.sub(r' data-rev="\d+"', "", view.svgs["cam1"])
    assert rung == [view.model.scene.title] and view.panel_filter is ring_point_one
    assert ringed != plain  # point 1 is ringed: the panel is drawn from what the filter returned
