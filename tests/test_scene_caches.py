"""What the scene layer reuses between changes (checked points and their array, specs' cameras, intrinsics),
and that none of it goes stale: a drag must give exactly the scene a full rebuild would give."""

import copy
import dataclasses
import pickle

import numpy as np
import pytest

from egtviz.geometry import GeometryError, Pose
from egtviz.geometry.poses import egt_rotation_from_ypr, ypr_from_egt_rotation
from egtviz.scene import PanoramicSpec, PinholeSpec, Scene, SceneError, SceneModel, default_scene, panoramic_scene
from egtviz.scene.io import scene_from_dict
from egtviz.scene.cameras.catadioptric import panoramic_rotation_from_ypr


def rebuilt(scene: Scene) -> Scene:
    """The same scene made from scratch (plain tuples, fresh specs): what the caches must agree with."""
    return scene_from_dict(scene.to_dict())


def random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


# -- points ------------------------------------------------------------------------------------------


def test_points_array_is_shared_read_only_and_matches_the_points():
    model = SceneModel(default_scene())
    scene = model.scene
    X = scene.points_array()
    assert X is scene.points_array()  # made once
    assert not X.flags.writeable
    np.testing.assert_array_equal(X, np.array(scene.points, float))
    with pytest.raises(ValueError):
        X[0, 0] = 1.0


def test_a_camera_change_keeps_the_checked_points():
    model = SceneModel(default_scene())
    before = model.scene
    R = before.camera("cam1").pose.R
    model.set_camera_pose("cam1", (0.5, -8.0, 1.5), R, drag_id=1)
    model.update_camera("cam2", focal_length=0.01)
    model.select_point(3)
    after = model.scene
    assert after.points is before.points and after.points_array() is before.points_array()
    assert after.to_dict() == rebuilt(after).to_dict()  # a dragged pose reads back from its angles to rounding


def test_moving_a_point_changes_its_row_only_and_undo_restores_the_arrays():
    model = SceneModel(default_scene())
    start = model.scene
    X0 = start.points_array().copy()
    for z in (1.0, 2.0, 3.0):
        model.set_point(2, (0.25, 0.5, z), drag_id=7)
    X = model.scene.points_array()
    expected = X0.copy()
    expected[2] = (0.25, 0.5, 3.0)
    np.testing.assert_array_equal(X, expected)
    assert model.scene.points[2] == (0.25, 0.5, 3.0)
    assert all(type(c) is float for p in model.scene.points for c in p)
    np.testing.assert_array_equal(start.points_array(), X0)  # the old scene's array is untouched
    assert model.scene == rebuilt(model.scene)
    assert model.undo()  # one drag, one step
    assert model.scene is start
    np.testing.assert_array_equal(model.scene.points_array(), X0)


@pytest.mark.parametrize("change", ["set_points", "add_point", "remove_point", "randomize", "load"])
def test_every_points_change_gives_a_matching_array(change, tmp_path):
    model = SceneModel(default_scene())
    if change == "set_points":
        model.set_points([[1, 2, 3], [4, 5, 6]])
    elif change == "add_point":
        model.add_point((7, 8, 9))
    elif change == "remove_point":
        model.remove_point(0)
    elif change == "randomize":
        model.randomize_points(40, seed=3)
    else:
        other = SceneModel(default_scene())
        other.randomize_points(12, seed=5)
        other.save(tmp_path / "s.json")
        model.load(tmp_path / "s.json")
    scene = model.scene
    np.testing.assert_array_equal(scene.points_array(), np.array(scene.points, float).reshape(-1, 3))
    assert all(type(c) is float for p in scene.points for c in p)
    assert scene == rebuilt(scene)


def test_points_are_checked_and_converted_every_one():
    s = Scene(points=((1.0, 2.0, 3.0), (1, 2, 3), [4, 5, np.float64(6)]))
    assert s.points == ((1.0, 2.0, 3.0), (1.0, 2.0, 3.0), (4.0, 5.0, 6.0))
    assert all(type(c) is float for p in s.points for c in p)
    with pytest.raises(SceneError, match=r"points\[1\]: expected three finite numbers"):
        Scene(points=((1.0, 2.0, 3.0), (1.0, float("nan"), 3.0)))
    with pytest.raises(SceneError, match=r"points\[0\]: expected three numbers"):
        Scene(points=(("a", 1, 2),))
    with pytest.raises(SceneError, match=r"points\[0\]: expected three finite numbers"):
        Scene(points=((1.0, 2.0),))
    model = SceneModel(default_scene())
    before = model.scene
    with pytest.raises(SceneError, match="point 1: expected three finite numbers"):
        model.set_point(1, (0, 0, float("inf")))
    with pytest.raises(SceneError, match="index: no point 99"):
        model.set_point(99, (0, 0, 0))
    assert model.scene is before


def test_points_behave_as_a_plain_tuple():
    scene = default_scene()
    plain = tuple(tuple(p) for p in scene.points)
    assert scene.points == plain and hash(scene.points) == hash(plain)
    assert {plain: 1}[scene.points] == 1
    for other in (copy.copy(scene), copy.deepcopy(scene), pickle.loads(pickle.dumps(scene))):
        assert other == scene and hash(other) == hash(scene)
        np.testing.assert_array_equal(other.points_array(), scene.points_array())
    assert dataclasses.asdict(scene)["points"] == plain
    assert Scene(points=plain).points_array().shape == (len(plain), 3)
    assert Scene().points_array().shape == (0, 3)


# -- cameras -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("factory", [default_scene, panoramic_scene])
def test_a_dragged_camera_equals_a_freshly_built_one(factory):
    model = SceneModel(factory())
    name = model.scene.cameras[0].name
    rng = np.random.default_rng(0)
    for k in range(5):
        model.scene.camera(name).camera()  # as the viewer does between events
        R = random_rotation(rng)
        model.set_camera_pose(name, (0.1 * k, -7.0, 1.0 + 0.1 * k), R, drag_id=1)
        spec = model.scene.camera(name)
        fresh = dataclasses.replace(spec)  # __post_init__ and a new camera
        assert spec == fresh
        cam, ref = spec.camera(), fresh.camera()
        np.testing.assert_allclose(cam.pose.R, ref.pose.R, atol=1e-12)
        np.testing.assert_array_equal(cam.pose.t, ref.pose.t)
        np.testing.assert_allclose(cam.pose.R, R, atol=1e-9)
        np.testing.assert_array_equal(cam.K, ref.K)
        X = model.scene.points_array()
        np.testing.assert_allclose(cam.project(X).pixels, ref.project(X).pixels, atol=1e-9, equal_nan=True)
    assert model.undo() and model.scene == factory()  # one drag, one undo step


def test_a_parameter_change_after_a_drag_builds_a_new_camera():
    model = SceneModel(panoramic_scene())
    name = model.scene.cameras[0].name
    R = model.scene.camera(name).pose.R
    model.set_camera_pose(name, (0.0, 0.0, 2.0), R, drag_id=1)
    model.update_camera(name, a=2.0, b=0.5, focal_pixels=800.0)
    cam = model.scene.camera(name).camera()
    assert (cam.mirror.a, cam.mirror.b) == (2.0, 0.5) and cam.K[0, 0] == 800.0
    np.testing.assert_array_equal(cam.pose.t, (0.0, 0.0, 2.0))
    model = SceneModel(default_scene())
    model.set_camera_pose("cam1", (0.0, -8.0, 1.5), model.scene.camera("cam1").pose.R, drag_id=1)
    model.update_camera("cam1", focal_length=0.012, principal_point=(300, 200))
    cam = model.scene.camera("cam1").camera()
    assert cam.intrinsics.focal_length == 0.012 and cam.intrinsics.principal_point == (300.0, 200.0)
    assert cam.K[0, 0] == pytest.approx(1200.0)


def test_with_pose_checks_only_what_changes_with_the_same_messages():
    spec = PinholeSpec("c", (1.0, 2.0, 3.0), (10.0, 20.0, 30.0))
    assert spec.with_pose(position=(4, 5, 6)) == dataclasses.replace(spec, position=(4.0, 5.0, 6.0))
    assert spec.with_pose(ypr_deg=[1, 2, 3]).ypr_deg == (1.0, 2.0, 3.0)
    with pytest.raises(SceneError, match="position: expected three finite numbers"):
        spec.with_pose(position=(0, float("nan"), 0))
    with pytest.raises(SceneError, match="ypr_deg: expected three numbers"):
        spec.with_pose(ypr_deg="abc")
    model = SceneModel(default_scene())
    before = model.scene
    with pytest.raises(SceneError, match="position: expected three finite numbers"):
        model.update_camera("cam1", position=(0, float("inf"), 0))
    with pytest.raises(SceneError, match="R_world"):
        model.set_camera_pose("cam1", (0, 0, 0), np.eye(2))
    with pytest.raises(ValueError, match="expected a 3x3 rotation matrix"):
        model.set_camera_pose("cam1", (0, 0, 0), 2 * np.eye(3))
    assert model.scene is before


def test_spec_poses_match_the_core_constructors():
    rng = np.random.default_rng(1)
    for _ in range(20):
        ypr = tuple(rng.uniform(-180, 180, 3))
        pos = tuple(rng.uniform(-5, 5, 3))
        pin = PinholeSpec("p", pos, ypr)
        ref = Pose.from_egt(egt_rotation_from_ypr(*np.radians(ypr)), pos)
        np.testing.assert_allclose(pin.pose.R, ref.R, atol=1e-12)
        pano = PanoramicSpec("q", pos, ypr)
        ref = Pose(panoramic_rotation_from_ypr(*np.radians(ypr)), pos)
        np.testing.assert_allclose(pano.pose.R, ref.R, atol=1e-12)
        for pose in (pin.pose, pano.pose):
            assert set(vars(pose)) == set(vars(ref)) and not pose.R.flags.writeable and not pose.t.flags.writeable
            np.testing.assert_array_equal(pose.t, pos)
    # A spec's pose is made by Pose's own constructor (checked): a spec camera is never built around its checks.
    assert type(PinholeSpec("p").pose) is Pose and PinholeSpec("p").camera().pose == PinholeSpec("p").pose


@pytest.mark.filterwarnings("ignore:Gimbal lock")
def test_pinhole_angles_from_a_rotation_match_the_reference():
    rng = np.random.default_rng(2)
    rotations = [random_rotation(rng) for _ in range(50)]
    # near and at the gimbal lock (pitch +-90 degrees): the scipy path
    rotations += [Pose.from_egt(egt_rotation_from_ypr(0.3, s * np.pi / 2, 0.0), (0, 0, 0)).R for s in (-1, 1)]
    for R in rotations:
        ypr = PinholeSpec.ypr_from_world_rotation(R)
        ref = np.degrees(ypr_from_egt_rotation(Pose(R, np.zeros(3)).egt_rotation))
        np.testing.assert_allclose(ypr, ref, atol=1e-9)
        assert all(type(a) is float for a in ypr)
        spec = PinholeSpec("c", (0.0, 0.0, 0.0), ypr)
        np.testing.assert_allclose(spec.pose.R, R, atol=1e-9)
    with pytest.raises(GeometryError, match="expected a 3x3 rotation matrix"):
        PinholeSpec.ypr_from_world_rotation(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(GeometryError, match="NaN"):
        PinholeSpec.ypr_from_world_rotation(np.full((3, 3), np.nan))


def test_intrinsics_are_shared_but_follow_every_field():
    a = PinholeSpec("a")
    b = PinholeSpec("b", (1.0, 2.0, 3.0))
    assert a.intrinsics is b.intrinsics  # same values: one object
    for field, value in (("focal_length", 0.01), ("pixels_per_metre", (9e4, 8e4)), ("principal_point", (1.0, 2.0)),
                         ("skew", 0.5), ("width", 800), ("height", 600)):
        c = dataclasses.replace(a, **{field: value})
        assert getattr(c.intrinsics, field) == value and c.camera().intrinsics == c.intrinsics
    assert PinholeSpec("i", focal_length=1).intrinsics.focal_length == 1  # typed: 1 and 1.0 are distinct entries
    with pytest.raises(SceneError, match="focal_length"):
        PinholeSpec("bad", focal_length=-1.0)


def test_a_moved_catadioptric_camera_has_what_its_constructor_sets():
    cam = PanoramicSpec("p", (1.0, 2.0, 3.0), (10.0, 5.0, 0.0), mirror="parabolic", a=2.0).camera()
    pose = PanoramicSpec("p", (0.0, 0.0, 1.0), (40.0, 0.0, 0.0)).pose
    fresh, moved = dataclasses.replace(cam, pose=pose), cam.moved(pose)
    assert set(vars(moved)) == set(vars(fresh))  # nothing that __post_init__ sets is missing
    assert moved.pose is pose and moved.mirror is cam.mirror
    X = np.random.default_rng(3).normal(size=(20, 3)) * 3
    np.testing.assert_array_equal(moved.project(X).pixels, fresh.project(X).pixels)


def test_drags_between_uses_of_the_camera_still_give_the_right_camera():
    spec = panoramic_scene().cameras[0]
    spec.camera()
    moved = spec.with_pose(position=(1.0, 1.0, 1.0)).with_pose(ypr_deg=(30.0, 10.0, 0.0))
    fresh = PanoramicSpec(spec.name, (1.0, 1.0, 1.0), (30.0, 10.0, 0.0), spec.mirror, spec.a, spec.b,
                          spec.focal_pixels, spec.principal_point, spec.width, spec.height)
    assert moved == fresh
    np.testing.assert_allclose(moved.camera().pose.R, fresh.camera().pose.R, atol=1e-12)
    np.testing.assert_array_equal(moved.camera().pose.t, (1.0, 1.0, 1.0))
    assert moved.camera() is moved.camera()
