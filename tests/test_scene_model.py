"""The scene model: validation, notifications, undo, the file format, and the derived drawing data."""

import json

import numpy as np
import pytest

from egtviz.scene import (
    PanoramicSpec,
    PinholeSpec,
    Scene,
    SceneError,
    SceneFileError,
    SceneModel,
    SurfaceSpec,
    compute_derived,
    default_scene,
    panoramic_scene,
)
from egtviz.scene.derived import COINCIDENT_MESSAGE


def distance_to_polyline(p, poly):
    a, b = poly[:-1], poly[1:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))


def test_default_scene_sees_all_points_in_both_cameras():
    d = compute_derived(default_scene())
    for ip in d.image_planes.values():
        assert ip.in_image.all() and ip.n_hidden == 0
        assert ip.lines is not None and np.isfinite(ip.lines).all()
    assert d.pair.rank == 2


def test_panoramic_scene_draws_conics_through_the_points():
    d = compute_derived(panoramic_scene())
    for name, ip in d.image_planes.items():
        assert ip.kind == "panoramic" and ip.visible.all()
        assert ip.conics is not None and len(ip.conics) == 8
        assert len(ip.epipoles) == 2
        for i, arcs in enumerate(ip.conics):
            # The point's own image lies on its conic: within a pixel of the sampled polyline.
            assert min(distance_to_polyline(ip.points[i], arc) for arc in arcs) < 1.0, (name, i)


def test_notifications_once_per_change_and_once_per_batch():
    model = SceneModel()
    seen = []
    unsubscribe = model.subscribe(lambda scene, change: seen.append(change.kind))
    model.update_camera("cam1", focal_length=0.01)
    with model.batch():
        model.set_point(0, (0, 0, 0))
        model.set_point(1, (1, 0, 0))
    assert seen == ["camera", "batch"]
    unsubscribe()
    model.select_point(2)
    assert seen == ["camera", "batch"]


def test_invalid_change_leaves_scene_unchanged():
    model = SceneModel()
    before = model.scene
    for bad in ({"focal_length": 0.0}, {"focal_length": float("nan")}, {"width": -3}, {"position": (0, float("inf"), 0)}):
        with pytest.raises(SceneError):
            model.update_camera("cam1", **bad)
        assert model.scene is before
    with pytest.raises(SceneError, match="no camera named"):
        model.update_camera("nope", focal_length=0.01)
    model.add_camera("panoramic")
    with pytest.raises(SceneError, match="a: expected a positive"):
        model.update_camera("pano1", a=-1.0)


def test_undo_and_reset():
    model = SceneModel()
    start = model.scene
    model.update_camera("cam1", focal_length=0.01)
    model.add_point((1, 2, 3))
    assert model.undo() and len(model.scene.points) == 8
    assert model.undo() and model.scene.camera("cam1").focal_length == 0.008
    assert not model.undo()
    model.randomize_points(20, seed=1)
    model.reset()
    assert model.scene is start


def test_gizmo_pose_round_trips_through_the_spec_angles():
    model = SceneModel()
    for name in ("cam1",):
        cam = model.scene.camera(name).camera()
        R = cam.pose.R @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])  # a 90 degree roll
        model.set_camera_pose(name, (1, 2, 3), R)
        np.testing.assert_allclose(model.scene.camera(name).pose.R, R, atol=1e-9)
        np.testing.assert_allclose(model.scene.camera(name).position, (1, 2, 3))
    model.add_camera("panoramic")
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    model.set_camera_pose("pano1", (0, 0, 1), R)
    np.testing.assert_allclose(model.scene.camera("pano1").pose.R, R, atol=1e-9)


def test_coincident_centres_show_a_message_not_an_error():
    model = SceneModel()
    model.update_camera("cam2", position=model.scene.camera("cam1").position)
    d = compute_derived(model.scene)
    assert d.image_planes["cam1"].message == COINCIDENT_MESSAGE
    assert d.pair.message == COINCIDENT_MESSAGE and d.pair.F is None


def test_points_behind_are_counted_hidden():
    model = SceneModel()
    model.add_point((0, -20, 1))  # behind both cameras
    d = compute_derived(model.scene)
    assert d.image_planes["cam1"].n_hidden == 1
    assert np.isnan(d.image_planes["cam1"].points[-1]).all()
    assert np.isnan(d.rays["cam1"][-1]).all()


def test_four_cameras_and_pair_selection():
    model = SceneModel()
    model.add_camera("pinhole")
    model.add_camera("panoramic")
    assert model.scene.camera_names == ("cam1", "cam2", "cam3", "pano1")
    model.set_pair("cam3", "pano1")
    d = compute_derived(model.scene)
    assert d.image_planes["cam3"].lines is not None and d.image_planes["pano1"].conics is not None
    assert d.image_planes["cam1"].lines is None
    model.remove_camera("pano1")
    assert model.scene.pair is None and model.scene.drawn_pair == ("cam1", "cam2")
    with pytest.raises(SceneError, match="pair"):
        model.set_pair("cam1", "cam1")


def test_save_and_load_round_trip(tmp_path):
    model = SceneModel()
    model.add_camera("panoramic", mirror="parabolic", a=1.0, focal_pixels=100.0)
    model.add_surface(SurfaceSpec("sphere", (0, 0, 1), 0.5, samples=50))
    model.select_point(3)
    model.lock("cam1")
    path = tmp_path / "scene.json"
    model.save(path)
    data = json.loads(path.read_text())
    assert data["format"] == "egtviz-scene" and data["cameras"][2]["kind"] == "panoramic"
    other = SceneModel()
    other.load(path)
    assert other.scene.to_dict() == model.scene.to_dict()
    assert other.scene.surface_points()[0].shape == (50, 3)


@pytest.mark.parametrize(
    "mutate, match",
    [
        (lambda d: d["cameras"][1].update(focal_length=-1), r"cameras\[1\].*focal_length"),
        (lambda d: d["cameras"][0].update(kind="fisheye"), r"cameras\[0\]\.kind"),
        (lambda d: d["cameras"][0].update(zoom=2), r"cameras\[0\]\.zoom: unknown field"),
        (lambda d: d["points"].append([1, "x", 2]), r"points\[8\]"),
        (lambda d: d.update(version=99), "version"),
        (lambda d: d.update(pair=["cam1", "ghost"]), "pair"),
    ],
)
def test_malformed_scene_file_names_file_and_entry(tmp_path, mutate, match):
    data = default_scene().to_dict()
    mutate(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    model = SceneModel()
    before = model.scene
    with pytest.raises(SceneFileError, match=match) as info:
        model.load(path)
    assert str(path) in str(info.value)
    assert model.scene is before


def test_not_json_reports_the_line(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{"cameras": [\n  oops\n]}')
    with pytest.raises(SceneFileError, match=r"broken.json: line 2"):
        Scene.load(path)


def test_specs_convert_to_core_cameras():
    pin = PinholeSpec("c", (1, 2, 3), (30, 0, 0))
    np.testing.assert_allclose(pin.camera().pose.R[:, 2], [0.5, np.sqrt(3) / 2, 0], atol=1e-12)
    pano = PanoramicSpec("p", (0, 0, 0), (90, 0, 0))
    np.testing.assert_allclose(pano.camera().pose.R[:, 0], [0, 1, 0], atol=1e-12)


def test_one_drag_is_one_undo_step_and_no_op_changes_are_silent():
    model = SceneModel()
    seen = []
    model.subscribe(lambda scene, change: seen.append(change.kind))
    start = model.scene
    R = start.camera("cam1").pose.R
    for x in (0.0, 0.5, 1.0):
        model.set_camera_pose("cam1", (x, -8, 1.5), R, drag_id=1)
    for z in (1.0, 2.0):
        model.set_point(0, (0, 0, z), drag_id=2)
    assert len(seen) == 5
    model.update_camera("cam2", focal_length=model.scene.camera("cam2").focal_length)
    model.set_point(0, (0, 0, 2.0))
    assert len(seen) == 5  # nothing changed: no notification
    assert model.undo()  # the whole point drag
    assert model.scene.points[0] == start.points[0]
    assert model.undo()  # the whole camera drag
    assert model.scene.camera("cam1") == start.camera("cam1")
    assert not model.undo()


def test_mesh_surface_from_assets_is_sampled_with_unit_normals():
    from egtviz.scene.surfaces import sample_surface

    pts, normals = sample_surface(SurfaceSpec("mesh", (1.0, 2.0, 0.0), 2.0, samples=200, path="house.obj"))
    assert 100 <= len(pts) <= 200 and pts.shape == normals.shape
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-9)
    # The house (1 x 1 x 1.2, scaled by 2) stands on the ground at (1, 2).
    assert pts[:, 2].min() >= -1e-9 and pts[:, 2].max() <= 2.4 + 1e-9
    assert np.all(np.abs(pts[:, :2] - [1.0, 2.0]) <= 1.0 + 1e-9)
    with pytest.raises(SceneError, match="cannot load mesh"):
        sample_surface(SurfaceSpec("mesh", path="no-such-mesh.obj"))
