"""Following is cheap: a drag's node arrays are prepared once (the instructor's tab) and every follower is handed
the same ones; each follower's 3D scene still equals the instructor's, and a fresh computation of it."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from egtviz.geometry.pinhole import PinholeCamera
from egtviz.scene import SceneModel, compute_derived, default_scene, panoramic_scene
from egtviz.viewer.classroom.follow_view import FollowView, RoomFrame
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.workbench.models.pinhole import IMAGE_PLANE_DEPTH
from egtviz.viewer.workbench.models.shared import SharedArrays
from egtviz.viewer.workbench.scene3d import Scene3D

from _waiting import wait_for

FOLLOWERS = 4


@pytest.fixture
def room():
    """``(instructor's Scene3D, followers)`` on a real viser server, one fake tab each."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tabs = [FakeTab(server.get_port()) for _ in range(FOLLOWERS + 1)]
    wait_for(lambda: len(server.get_clients()) == len(tabs), f"the {len(tabs)} headless tabs to connect")
    clients = [c for _, c in sorted(server.get_clients().items())]
    assert len(clients) == len(tabs)
    state: dict = {"server": server, "clients": clients}
    yield state
    for view in state.get("followers", ()):
        view.close()
    for tab in tabs:
        tab.close()
    server.stop()


def _frame(model: SceneModel, number: int) -> RoomFrame:
    return RoomFrame(number, number, model.scene, model.derived, (), "", False)


def _start(room, model: SceneModel) -> tuple[Scene3D, list[FollowView]]:
    instructor = Scene3D(room["clients"][0].scene, lambda *a: None, lambda *a: None)
    instructor.draw(model.scene, model.derived)
    room["followers"] = [FollowView(c, _frame(model, 1)) for c in room["clients"][1:]]
    return instructor, room["followers"]


def _drag(model: SceneModel, instructor: Scene3D, followers: list[FollowView], number: int, step: float) -> None:
    name = model.scene.cameras[0].name
    spec = model.scene.camera(name)
    model.set_camera_pose(name, np.add(spec.position, (step, 0.5 * step, 0.0)), spec.pose.R, drag_id=1)
    instructor.draw(model.scene, model.derived, moving=name)
    frame = _frame(model, number)
    for view in followers:
        view.show(frame)


_ARRAYS = {"points": "points", "colors": "colors", "vertices": "vertices", "faces": "faces"}


def _node_values(s3: Scene3D) -> dict[str, object]:
    """Every array and visibility of the camera-dependent nodes, by node name."""
    nodes: dict[str, object] = {"baseline": s3.baseline, "epiplane": s3.epiplane, "points": s3.points}
    for name, cam in s3.every_camera_nodes().items():
        for key, handle in cam.drawing.named_nodes().items():
            nodes[f"{name}/{key}"] = handle
        nodes[f"{name}/rays"] = s3._rays[name]
    out: dict[str, object] = {}
    for key, handle in nodes.items():
        out[f"{key}.visible"] = bool(handle.visible)
        for prop in _ARRAYS:
            value = getattr(handle._impl.props, prop, None)
            if isinstance(value, np.ndarray):
                out[f"{key}.{prop}"] = value.copy()
    return out


def _assert_same(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


@pytest.mark.parametrize("factory", [default_scene, panoramic_scene])
def test_every_follower_shows_the_instructors_nodes_after_each_drag(room, factory):
    model = SceneModel(factory())
    instructor, followers = _start(room, model)
    for number, step in enumerate((0.2, 0.05, -0.3), start=2):
        _drag(model, instructor, followers, number, step)
        want = _node_values(instructor)
        assert any(k.endswith("img_pts.points") for k in want) or factory is panoramic_scene
        for view in followers:
            _assert_same(_node_values(view.scene3d), want)


def test_the_image_on_the_frustum_is_the_fresh_one_after_a_drag(room):
    """The shared arrays are those of the scene just dragged to (never an earlier drag's)."""
    model = SceneModel(default_scene())
    model.select_point(2)
    instructor, followers = _start(room, model)
    _drag(model, instructor, followers, 2, 0.25)
    derived = compute_derived(model.scene)
    for name, camera in derived.cameras.items():
        plane = derived.image_planes[name]
        ok = np.flatnonzero(plane.visible)
        want = camera.image_to_world(plane.points[ok], IMAGE_PLANE_DEPTH).astype(np.float32)
        for view in followers:
            node = view.scene3d.camera_nodes(name)["img_pts"]
            np.testing.assert_allclose(node.points, want, atol=2e-3)  # the cloud holds float16


def test_a_drag_projects_each_image_once_for_the_whole_room(room, monkeypatch):
    """The instructor's tab computes the image-plane arrays; the followers only assign them (before: once per
    follower, image_to_world ran 1 + FOLLOWERS times per camera and per kind)."""
    model = SceneModel(default_scene())
    instructor, followers = _start(room, model)
    calls: list[int] = []
    original = PinholeCamera.image_to_world

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(PinholeCamera, "image_to_world", counted)
    _drag(model, instructor, followers, 2, 0.2)
    cameras = len(model.scene.cameras)
    assert 0 < len(calls) <= 2 * cameras  # points and epipolar lines of each camera, for one tab


def test_shared_arrays_are_found_by_the_identity_of_their_sources():
    store = SharedArrays(capacity=2)
    a = np.zeros(3)
    made: list[int] = []

    def make() -> int:
        made.append(1)
        return len(made)

    assert store.get("k", (a,), None, make) == 1
    assert store.get("k", (a,), None, make) == 1  # the same array: not made again
    assert store.get("k", (a.copy(),), None, make) == 2  # an equal but other array: made
    assert store.get("k", (a,), (3,), make) == 3  # another key
    assert store.get("other", (a,), None, make) == 4  # another kind
    assert store.get("k", (a,), None, make) == 5  # capacity 2: the first entry went
    assert (store.hits, store.misses) == (1, 5)
