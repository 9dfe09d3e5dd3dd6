"""The scene model: validation, notifications, undo, the file format, and the derived drawing data."""

import json

import numpy as np
import pytest

from egtviz.geometry import GeometryError
from egtviz.scene import (
    OutOfRangeError,
    PanoramicSpec,
    PinholeSpec,
    Scene,
    SceneError,
    SceneFileError,
    SceneModel,
    SurfaceSpec,
    compute_derived,
    default_scene,
    limits,
    mesh_names,
    panoramic_scene,
    scene_from_bytes,
    scene_to_bytes,
)
from egtviz.scene.derived import COINCIDENT_MESSAGE
from egtviz.scene.surfaces import ASSETS


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
        assert d.cameras[name].kind == "hyperbolic" and ip.visible.all()
        assert ip.rim is not None and ip.no_image == "in the blind cone"
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
    with pytest.raises(SceneError, match=r"camera 'pano1': a: expected 0.001..100 m, got -1"):
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
        (lambda d: d["cameras"][0].update(kind="orthographic"), r"cameras\[0\]\.kind"),
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
    from egtviz.scene import load_scene_file

    with pytest.raises(SceneFileError, match=r"broken.json: line 2"):
        load_scene_file(path)


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
    from egtviz.scene.surfaces import check_surface, sample_surface

    pts, normals = sample_surface(SurfaceSpec("mesh", (1.0, 2.0, 0.0), 2.0, samples=200, path="house.obj"))
    assert 100 <= len(pts) <= 200 and pts.shape == normals.shape
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-9)
    # The house (1 x 1 x 1.2, scaled by 2) stands on the ground at (1, 2).
    assert pts[:, 2].min() >= -1e-9 and pts[:, 2].max() <= 2.4 + 1e-9
    assert np.all(np.abs(pts[:, :2] - [1.0, 2.0]) <= 1.0 + 1e-9)
    with pytest.raises(SceneError, match=r"no mesh named 'no-such-mesh.obj' in the assets \(have house.obj\)"):
        check_surface(SurfaceSpec("mesh", path="no-such-mesh.obj"))
    for forged in ("/etc/passwd", "../assets/house.obj", "mesh: /any/path.obj", str(ASSETS / "house.obj")):
        spec = SurfaceSpec("mesh", path=forged)  # a spec holds the name only: nothing is read
        with pytest.raises(SceneError, match="expected the name of a mesh in the assets"):
            check_surface(spec)
        with pytest.raises(SceneError, match="expected the name of a mesh in the assets"):
            SceneModel().add_surface(spec)
        with pytest.raises(SceneError, match="expected the name of a mesh in the assets"):
            sample_surface(spec)
    assert mesh_names() == ("house.obj",)


def test_out_of_range_errors_carry_the_limit_for_the_gui():
    with pytest.raises(OutOfRangeError) as info:
        PinholeSpec("c", focal_length=1e-300)
    err = info.value
    assert (err.camera, err.field, err.value, err.limit) == ("c", "focal_length", 1e-300, limits.FOCAL_LENGTH)
    assert str(err) == "camera 'c': focal_length: expected 0.0001..10 m, got 1e-300"
    assert err.limit.describe(1e3, "mm") == "0.1..10000 mm"  # restated in the field's own unit
    with pytest.raises(OutOfRangeError, match=r"camera 'p': b: expected 0.001..100 m, got 1e-200"):
        PanoramicSpec("p", b=1e-200)
    with pytest.raises(SceneError, match=r"width: expected a whole number in 1..8192 px, got 640.5"):
        PinholeSpec("c", width=640.5)
    assert PinholeSpec("c", width=640.0).width == 640  # a whole number typed as a float is that number


def test_undrawable_change_is_refused_before_commit(monkeypatch):
    from egtviz.scene import derived as derived_module

    model = SceneModel()
    before, before_derived = model.scene, model.derived
    seen = []
    model.subscribe(lambda scene, change: seen.append(change.kind))
    real = derived_module._compute_derived

    def refuse_wide_images(scene):
        if any(c.width > 1000 for c in scene.cameras):
            raise GeometryError("K: too wide to draw")
        return real(scene)

    monkeypatch.setattr(derived_module, "_compute_derived", refuse_wide_images)
    with pytest.raises(SceneError, match="cannot be drawn: K: too wide to draw"):
        model.update_camera("cam1", width=2000)
    assert model.scene is before and model.derived is before_derived and seen == []
    with pytest.raises(SceneError, match="cannot be drawn"):
        with model.batch():
            model.update_camera("cam1", width=2000)
            model.update_camera("cam2", focal_length=0.01)
    assert model.scene is before and model.derived is before_derived and seen == []
    model.update_camera("cam1", width=800)
    assert model.derived.image_planes["cam1"].width == 800 and seen == ["camera"]


def test_model_derived_is_the_committed_scene_s():
    model = SceneModel()
    got = []
    model.subscribe(lambda scene, change: got.append((scene, model.derived)))
    model.set_point(0, (0.5, 0.5, 0.5))
    scene, derived = got[-1]
    assert scene is model.scene and derived is model.derived
    np.testing.assert_allclose(derived.image_planes["cam1"].points, compute_derived(scene).image_planes["cam1"].points)
    assert model.undo() and model.derived.image_planes["cam1"].points[0].tolist() != derived.image_planes["cam1"].points[0].tolist()


def test_model_enforces_the_limits_the_page_shows():
    model = SceneModel()
    before = model.scene
    for bad in (100_000, 2001, -1, 2.5, True, "8"):
        with pytest.raises(SceneError, match="n: expected"):
            model.randomize_points(bad)
    with pytest.raises(SceneError, match="points: at most 2000"):
        model.set_points(np.zeros((2001, 3)))
    with pytest.raises(SceneError, match="cameras: at most 8"):
        for _ in range(10):
            model.add_camera("pinhole")
    assert len(model.scene.cameras) == 8
    model.reset()
    with pytest.raises(SceneError, match="highlighted: expected a list"):
        model.highlight("cam1")
    with pytest.raises(SceneError, match="highlighted: .*'point:abc'"):
        model.highlight(["point:abc"])
    with pytest.raises(SceneError, match="selected_point"):
        model.select_point(True)
    with pytest.raises(SceneError, match="show_rays: expected true or false"):
        model.set_option("show_rays", "yes")
    assert model.scene is before
    model.randomize_points(2000, seed=3)
    assert len(model.scene.points) == 2000


def test_point_marks_follow_removed_points_and_renamed_cameras():
    model = SceneModel()
    model.lock("point:2")
    model.lock("point:5")
    model.highlight(["point:5", "cam2"])
    model.remove_point(2)
    assert model.scene.locked == {"point:4"} and model.scene.highlighted == {"point:4", "cam2"}
    model.update_camera("cam2", name="right")
    assert model.scene.highlighted == {"point:4", "right"}
    model.set_points(np.zeros((2, 3)))
    assert model.scene.locked == frozenset() and model.scene.highlighted == {"right"}


def test_load_scene_commits_an_uploaded_scene_and_is_undoable():
    model = SceneModel()
    start = model.scene
    kinds = []
    model.subscribe(lambda scene, change: kinds.append(change.kind))
    model.load_scene(scene_from_bytes(scene_to_bytes(panoramic_scene()), "upload.json"))
    assert model.scene.camera_names == ("pano1", "pano2") and kinds == ["load"]
    assert model.undo() and model.scene is start


def test_an_undo_barrier_stops_undo_and_reset_comes_back_to_it():
    model = SceneModel()
    model.update_camera("cam1", focal_length=0.01)
    with model.batch("step", barrier="Undo stops here."):
        model.update_camera("cam1", focal_length=0.03)
        model.lock("cam1")
    at_barrier = model.scene
    assert model.barrier_scene is at_barrier and model.undo_barrier_note == "Undo stops here."
    assert not model.can_undo and not model.undo()  # the batch and what came before are behind the barrier
    assert model.scene is at_barrier and model.scene.camera("cam1").focal_length == 0.03
    model.update_camera("cam1", focal_length=0.02)
    assert model.undo() and not model.undo()
    assert model.scene.camera("cam1").focal_length == 0.03 and model.scene.locked == {"cam1"}
    model.randomize_points(20, seed=1)
    model.reset()  # to the barrier, not to the scene the model started with
    assert model.scene is at_barrier
    with pytest.raises(SceneError, match="note"):
        model.set_undo_barrier("")


def test_a_lock_holds_for_every_edit_of_the_pose_not_only_the_gizmo():
    model = SceneModel()
    model.lock("cam1")
    model.lock("point:2")
    before = model.scene
    spec = before.camera("cam1")
    with pytest.raises(SceneError, match="cam1: the camera is locked"):
        model.update_camera("cam1", position=(1.0, 2.0, 3.0))  # a typed position
    with pytest.raises(SceneError, match="cam1: the camera is locked"):
        model.update_camera("cam1", ypr_deg=(10.0, 0.0, 0.0))  # typed angles
    with pytest.raises(SceneError, match="cam1: the camera is locked"):
        model.set_camera_pose("cam1", (0.0, 0.0, 9.0), spec.camera().pose.R)  # a gizmo or a raw message
    with pytest.raises(SceneError, match="point 3 is locked"):
        model.set_point(2, (0.5, 0.5, 0.5))
    with pytest.raises(SceneError, match="cam1: the camera is locked"), model.batch():
        model.update_camera("cam2", focal_length=0.01)
        model.update_camera("cam1", position=(1.0, 2.0, 3.0))
    assert model.scene is before  # nothing committed, the batch all or nothing
    model.update_camera("cam1", focal_length=0.012)  # a lock holds the pose: the intrinsics may change
    model.set_point(3, (0.5, 0.5, 0.5))
    assert model.scene.camera("cam1").focal_length == 0.012 and model.scene.points[3] == (0.5, 0.5, 0.5)


def test_a_lesson_steps_own_changes_may_move_what_it_locked_and_end_at_a_barrier():
    model = SceneModel()
    model.lock("cam1")
    with model.lesson_step("Undo stops at the step."):
        model.update_camera("cam1", position=(1.0, -8.0, 1.5))
    assert model.scene.camera("cam1").position == (1.0, -8.0, 1.5)
    assert model.undo_barrier_note == "Undo stops at the step." and not model.undo()
    with pytest.raises(SceneError, match="locked"):  # the step's authority ended with it
        model.update_camera("cam1", position=(2.0, -8.0, 1.5))
