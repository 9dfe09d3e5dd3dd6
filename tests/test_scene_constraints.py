"""A lesson's ranges are the scene model's constraints: they hold for every edit in place (a raw update_camera, a
gizmo pose), a drag is clamped to the box or keeps its orientation, a typed value is refused, and a lesson step's
own changes are not judged."""

from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import GeometryError
from egtviz.geometry.poses import matrix_from_quat_wxyz

from egtviz.scene import SceneError, SceneModel
from egtviz.scene.constraints import CameraRanges
from egtviz.scene.examples import default_scene

from test_scene_camera_models import every_kind_scene


@dataclass(frozen=True)
class Limit:
    low: float
    high: float


def model_with(ranges: dict, refusal=None) -> SceneModel:
    model = SceneModel(default_scene())
    model.set_constraints(CameraRanges(lambda: ranges, refusal))
    return model


def test_a_raw_edit_outside_a_range_is_refused_with_the_range():
    model = model_with({("cam1", "focal_length"): Limit(0.005, 0.01)})
    before = model.scene
    with pytest.raises(SceneError, match=r"In this step cam1's focal_length must stay between 0.005 and 0.01 "
                                         r"\(it is 0.02\)"):
        model.update_camera("cam1", focal_length=0.02)
    assert model.scene is before
    model.update_camera("cam1", focal_length=0.009)
    assert model.scene.camera("cam1").focal_length == 0.009


def test_the_refusal_speaks_the_fields_words_when_given():
    model = model_with({("cam1", "focal_length"): Limit(0.005, 0.01)},
                       lambda camera, fields: f"{camera}: focal length 5..10 mm (it is {fields['focal_length'] * 1e3:g} mm)")
    with pytest.raises(SceneError, match=r"cam1: focal length 5..10 mm \(it is 20 mm\)"):
        model.update_camera("cam1", focal_length=0.02)


def test_a_gizmo_pose_is_clamped_to_the_box_and_keeps_an_orientation_out_of_range():
    model = model_with({("cam1", "position"): Limit(-8.0, 2.0), ("cam1", "ypr_deg"): Limit(-30.0, 30.0)})
    spec = model.scene.camera("cam1")
    R = spec.camera().pose.R
    model.set_camera_pose("cam1", (4.5, -10.8, 1.5), R)
    assert model.scene.camera("cam1").position == (2.0, -8.0, 1.5)
    # A yaw of 90 degrees leaves the range: the camera keeps its orientation (and its new, allowed, position).
    turned = model.scene.camera("cam1").with_pose(ypr_deg=(90.0, 0.0, 0.0)).camera().pose.R
    model.set_camera_pose("cam1", (1.0, -8.0, 1.5), turned)
    after = model.scene.camera("cam1")
    assert after.position == (1.0, -8.0, 1.5)
    np.testing.assert_allclose(after.ypr_deg, spec.ypr_deg, atol=1e-9)
    # The same pose through update_camera (a raw client's message) is clamped too.
    model.update_camera("cam1", position=(-20.0, 0.0, 0.0))
    assert model.scene.camera("cam1").position == (-8.0, 0.0, 0.0)


def test_a_lesson_step_is_not_judged_and_an_unchanged_field_is_not_either():
    model = model_with({("cam1", "position"): Limit(-1.0, 1.0)})
    with model.lesson_step("start"):
        model.update_camera("cam1", position=(5.0, 5.0, 5.0))
    assert model.scene.camera("cam1").position == (5.0, 5.0, 5.0)
    model.update_camera("cam1", focal_length=0.009)  # the position, outside, is not what changes
    assert model.scene.camera("cam1").focal_length == 0.009
    with pytest.raises(SceneError, match="ranges: expected CameraRanges or None"):
        model.set_constraints({("cam1", "position"): (0, 1)})
    model.set_constraints(None)
    model.update_camera("cam1", position=(9.0, 9.0, 9.0))
    assert model.scene.camera("cam1").position == (9.0, 9.0, 9.0)


@settings(max_examples=40, deadline=None)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_a_dragged_pose_stays_the_pose_the_gizmo_gave(seed):
    rng = np.random.default_rng(seed)
    model = SceneModel(every_kind_scene())
    for name in model.scene.camera_names:
        q = rng.normal(size=4)
        R = matrix_from_quat_wxyz(q / np.linalg.norm(q))  # what a gizmo's quaternion gives
        position = tuple(rng.uniform(-5.0, 5.0, 3).tolist())
        model.set_camera_pose(name, position, R)
        spec = model.scene.camera(name)
        # The camera's rotation is the gizmo's, bit for bit (no rotation -> angles -> rotation round trip) ...
        assert np.array_equal(spec.camera().pose.R, R) and spec.position == position
        # ... and the angles the fields show describe it: a spec rebuilt from its fields (a file) has it to rounding.
        np.testing.assert_allclose(spec.with_fields(name=spec.name + "x").pose.R, R, atol=1e-9)


def test_a_gizmo_rotation_that_is_not_one_is_refused():
    model = SceneModel(default_scene())
    with pytest.raises(GeometryError, match="R"):
        model.set_camera_pose("cam1", (0.0, 0.0, 0.0), np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(GeometryError, match="R"):
        model.set_camera_pose("cam1", (0.0, 0.0, 0.0), np.eye(3) * 1.01)
