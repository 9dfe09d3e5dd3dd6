"""The workbench's controller, driven with no server: each intent changes the scene to the parsed value, or is
refused with the message the user reads and leaves the scene as it was."""

from __future__ import annotations

import numpy as np
import pytest

from egtviz.controllers.workbench import SavedScene, WorkbenchController
from egtviz.controllers.workbench_fields import FieldError
from egtviz.geometry.poses import Pose
from egtviz.scene import SceneError, SceneFileError, SceneModel, default_scene, limits, scene_from_bytes


@pytest.fixture
def wb() -> WorkbenchController:
    return WorkbenchController(SceneModel(default_scene()))


def _quat(spec) -> np.ndarray:
    return np.asarray(Pose(spec.pose.R, spec.pose.t).quat_wxyz)


def test_a_typed_focal_length_becomes_the_parsed_value_in_metres(wb):
    wb.set_field("cam1", "focal", "12.5")
    assert wb.scene.camera("cam1").focal_length == pytest.approx(0.0125)
    assert wb.field_values("cam1")["focal"] == pytest.approx((12.5,))
    wb.set_field("cam1", "position", " 1, -2.5, 3 ")
    assert wb.scene.camera("cam1").position == (1.0, -2.5, 3.0)


@pytest.mark.parametrize("text, message", [
    ("0", "cam1: focal length must be between 0.1 mm and 10000 mm, got 0 mm"),
    ("nan", "cam1: focal length: expected a number, got 'nan'"),
    ("1e400", "cam1: focal length: '1e400' is too large to be a number"),
    ("1, 2", "cam1: focal length: expected a number, got '1, 2'"),
])
def test_a_refused_field_raises_its_message_and_leaves_the_scene(wb, text, message):
    before = wb.scene
    with pytest.raises(FieldError) as refused:
        wb.set_field("cam1", "focal", text)
    assert str(refused.value) == message
    assert wb.scene is before


def test_a_lesson_guard_refuses_before_the_model_is_asked():
    model = SceneModel(default_scene())
    wb = WorkbenchController(model, field_guard=lambda camera, fields: f"{camera}: not in this lesson")
    before = model.scene
    with pytest.raises(FieldError, match=r"^cam1: not in this lesson$"):
        wb.set_field("cam1", "position", "1, 2, 3")
    assert model.scene is before


def test_the_text_shown_keeps_the_models_precision_and_commits_nothing(wb):
    before = wb.scene
    shown = ", ".join(f"{v:.6g}" for v in wb.field_values("cam1")["ypr"])
    wb.set_field("cam1", "ypr", shown)
    assert wb.scene is before and not wb.model.can_undo


def test_a_camera_drag_moves_it_and_one_drag_is_one_undo_step(wb):
    spec = wb.scene.camera("cam1")
    start = wb.scene
    drag = wb.start_drag()
    for k in range(1, 4):
        assert wb.drag_camera("cam1", np.add(spec.position, (0.1 * k, 0.0, 0.0)), _quat(spec), drag)
    assert wb.scene.camera("cam1").position == pytest.approx(np.add(spec.position, (0.3, 0.0, 0.0)))
    assert wb.undo() is None
    assert wb.scene is start


def test_a_drag_to_where_the_camera_is_commits_nothing(wb):
    spec = wb.scene.camera("cam1")
    before = wb.scene
    assert not wb.drag_camera("cam1", spec.position, _quat(spec), wb.start_drag(), last=True)
    assert wb.scene is before


def test_a_locked_camera_refuses_its_drag(wb):
    wb.model.lock("cam1")
    spec = wb.scene.camera("cam1")
    before = wb.scene
    moved = np.add(spec.position, (1.0, 0.0, 0.0))
    assert not wb.drag_camera("cam1", moved, _quat(spec), 1)
    with pytest.raises(SceneError, match=r"^cam1 is locked: its gizmo cannot move it now$"):
        wb.drag_camera("cam1", moved, _quat(spec), 1, last=True)
    assert wb.scene is before


@pytest.mark.parametrize("position, wxyz, message", [
    ((0.0, np.nan, 1.0), (1.0, 0.0, 0.0, 0.0), "cam1: the gizmo sent a position that is not 3 finite numbers"),
    ((0.0, 1.0), (1.0, 0.0, 0.0, 0.0), "cam1: the gizmo sent a position that is not 3 finite numbers"),
    ((0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0), "cam1: the gizmo sent an orientation that is not a rotation"),
])
def test_a_forged_gizmo_pose_is_refused(wb, position, wxyz, message):
    before = wb.scene
    with pytest.raises(SceneError) as refused:
        wb.drag_camera("cam1", position, wxyz, None)
    assert str(refused.value).startswith(message)
    assert wb.scene is before


def test_a_point_drag_selects_and_moves_the_point(wb):
    drag = wb.start_point_drag(2)
    assert wb.scene.selected_point == 2
    wb.drag_point(2, (0.5, 0.25, 1.0), drag)
    wb.drag_point(2, (0.5, 0.5, 1.0), drag)
    assert wb.scene.points[2] == (0.5, 0.5, 1.0)
    wb.undo()
    assert wb.scene.points[2] != (0.5, 0.5, 1.0) and wb.scene.selected_point == 2  # the drag was one step
    wb.drag_point(99, (0.0, 0.0, 1.0), drag)  # a point removed meanwhile: ignored


def test_the_controls(wb):
    wb.select_point("point 3")
    assert wb.scene.selected_point == 2
    with pytest.raises(FieldError, match=r"^selected point: no 'point 99' \(have 8 points\)$"):
        wb.select_point("point 99")
    wb.set_option("show_rays", False)
    assert not wb.scene.options.show_rays
    with pytest.raises(FieldError, match=r"^show_rays: expected true or false, got 'yes'$"):
        wb.set_option("show_rays", "yes")
    name = wb.add_camera("pinhole")
    assert name in wb.scene.camera_names and f"cam1 & {name}" in wb.pair_choices()
    wb.set_pair(f"cam1 & {name}")
    assert wb.scene.drawn_pair == ("cam1", name)
    with pytest.raises(FieldError, match=r"^drawn pair: no pair 'cam1 & cam9'$"):
        wb.set_pair("cam1 & cam9")
    wb.remove_camera(name)
    assert name not in wb.scene.camera_names


def test_points_and_surfaces(wb):
    with pytest.raises(FieldError, match=r"^how many points must be a whole number, got 2.5$"):
        wb.set_point_count("2.5")
    wb.set_point_count("5")
    assert wb.point_count_text == "5"
    wb.randomise_points("5")
    assert len(wb.scene.points) == 5
    assert wb.add_point() == 5 and wb.scene.points[5] == (0.0, 0.0, 1.0)
    wb.select_point("point 2")
    wb.remove_point()
    assert len(wb.scene.points) == 5 and wb.scene.selected_point is None
    wb.add_surface("sphere")
    assert wb.scene.surfaces[-1].kind == "sphere"
    with pytest.raises(FieldError, match=r"^surface: no surface 'mesh: /etc/passwd'$"):
        wb.add_surface("mesh: /etc/passwd")


def test_undo_reset_and_built_in_scenes(wb):
    first = wb.scene
    assert not wb.undo_enabled
    wb.open_builtin("panoramic")
    assert wb.scene is not first and wb.undo_enabled
    with pytest.raises(FieldError, match=r"^built-in scene: no scene 'nope'"):
        wb.open_builtin("nope")
    wb.reset()
    assert wb.scene == first
    wb.model.set_undo_barrier("The step's start.")
    assert wb.undo() == "The step's start."


def test_scene_bytes_round_trip(wb):
    wb.set_field("cam1", "focal", "9")
    saved = wb.save()
    assert isinstance(saved, SavedScene) and saved.name.endswith(".json")
    assert scene_from_bytes(saved.content, "x") == wb.scene
    other = WorkbenchController(SceneModel(default_scene()))
    other.load("mine.json", saved.content)
    assert other.scene == wb.scene


@pytest.mark.parametrize("content, message", [
    (None, "big.json: the upload holds no file"),
    (b" " * (limits.MAX_SCENE_FILE_BYTES + 1),
     f"big.json: the file has {limits.MAX_SCENE_FILE_BYTES + 1} bytes; a scene file has at most "
     f"{limits.MAX_SCENE_FILE_BYTES} bytes"),
])
def test_a_bad_upload_is_refused_and_leaves_the_scene(wb, content, message):
    before = wb.scene
    with pytest.raises(SceneFileError) as refused:
        wb.load("big.json", content)
    assert str(refused.value) == message and wb.scene is before
