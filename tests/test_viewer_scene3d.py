"""The 3D nodes (``Scene3D``) on a real viser server without a browser: what is drawn, and that a node is
re-sent only when its content changed."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from egtviz.scene import SceneModel, compute_derived, default_scene, panoramic_scene
from egtviz.viewer.server.headless import start_headless
from egtviz.viewer.render.palette import point_rgb
from egtviz.viewer.workbench.models.pinhole import IMAGE_PLANE_DEPTH
from egtviz.viewer.workbench.scene3d import MAX_RAY_POINTS, Scene3D


@pytest.fixture
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def scene3d_on(server) -> Scene3D:
    return Scene3D(server.scene, lambda *a: None, lambda *a: None)


def count_messages(api, monkeypatch) -> list:
    sent: list = []
    original = api._queue_scene_message
    monkeypatch.setattr(api, "_queue_scene_message", lambda m: (sent.append(m), original(m)))
    return sent


def expected_rays(derived, name: str, rows) -> np.ndarray:
    """The finite segments of the polylines of ``rows``, as the node should hold them."""
    segs = []
    for i in rows:
        P = derived.rays[name][i]
        for a, b in zip(P[:-1], P[1:]):
            if np.isfinite(a).all() and np.isfinite(b).all():
                segs.append((a, b))
    return np.array(segs, np.float32).reshape(-1, 2, 3)


@pytest.mark.parametrize("factory", [default_scene, panoramic_scene])
def test_rays_of_every_point_up_to_the_limit_then_only_the_selected_one(factory):
    model = SceneModel(factory())
    model.randomize_points(40, seed=4, center=tuple(model.scene.points_array().mean(axis=0)), extent=2.0)
    assert len(model.scene.points) > MAX_RAY_POINTS
    server, app, fakes, views = start_headless(model.scene)
    try:
        view = views[0]
        rays = view.scene3d._rays
        assert set(rays) == set(view.model.scene.camera_names)
        assert not any(r.visible for r in rays.values())  # 40 points, none selected: no rays
        for sel in (5, 17):
            view.model.select_point(sel)
            derived = compute_derived(view.model.scene)
            for name, node in rays.items():
                want = expected_rays(derived, name, [sel])
                assert len(want), "the test scene should let every camera see these points"
                assert node.visible
                np.testing.assert_array_equal(node.points, want)
                assert (node.colors.reshape(-1, 3) == point_rgb(sel)).all()
        # the selected point's rays follow a camera drag
        name = view.model.scene.cameras[0].name
        spec = view.model.scene.camera(name)
        view.model.set_camera_pose(name, np.add(spec.position, (0.3, 0.0, 0.0)), spec.pose.R, drag_id=1)
        derived = compute_derived(view.model.scene)
        np.testing.assert_array_equal(rays[name].points, expected_rays(derived, name, [17]))
        view.model.select_point(None)
        assert not any(r.visible for r in rays.values())
        # few points: every point's rays again, selection or not
        view.model.set_points(view.model.scene.points_array()[:MAX_RAY_POINTS])
        derived = compute_derived(view.model.scene)
        for name, node in rays.items():
            np.testing.assert_array_equal(node.points, expected_rays(derived, name, range(MAX_RAY_POINTS)))
            assert node.visible
        view.model.set_option("show_rays", False)
        assert not any(r.visible for r in rays.values())
    finally:
        for f in fakes:
            f.close()
        server.stop()


@pytest.mark.parametrize("factory", [default_scene, panoramic_scene])
def test_an_unchanged_scene_sends_nothing(server, monkeypatch, factory):
    s3 = scene3d_on(server)
    scene = factory()
    s3.draw(scene, compute_derived(scene))
    sent = count_messages(s3.api, monkeypatch)
    s3.draw(scene, compute_derived(scene))
    assert sent == []
    # moving one camera re-sends that camera's nodes, not the points or their labels
    model = SceneModel(scene)
    name = scene.cameras[0].name
    spec = scene.camera(name)
    model.set_camera_pose(name, np.add(spec.position, (0.2, 0.0, 0.0)), spec.pose.R)
    s3.draw(model.scene, compute_derived(model.scene))
    touched = {m.name for m in sent}
    assert f"/egt/cam_{s3._cam_ids[name]}" in touched
    assert not any(n.startswith("/egt/plabel_") or n == "/egt/points" for n in touched)


def test_the_dragged_gizmo_is_not_re_posed_and_points_follow_the_model(server):
    s3 = scene3d_on(server)
    model = SceneModel(default_scene())
    s3.draw(model.scene, compute_derived(model.scene))
    gizmo = s3.camera_nodes("cam1")["gizmo"]
    before = np.array(gizmo.position)
    model.update_camera("cam1", position=(1.0, -7.0, 2.0))
    s3.draw(model.scene, compute_derived(model.scene), moving="cam1")
    np.testing.assert_array_equal(gizmo.position, before)
    s3.draw(model.scene, compute_derived(model.scene))
    np.testing.assert_allclose(gizmo.position, (1.0, -7.0, 2.0))
    # points: the cloud and the moved point's label follow, and undo brings them back
    X0 = model.scene.points_array().copy()
    model.set_point(3, (0.5, 0.25, 1.0))
    s3.draw(model.scene, compute_derived(model.scene))
    np.testing.assert_allclose(s3.points.points[3], (0.5, 0.25, 1.0), atol=1e-3)  # float16 cloud
    np.testing.assert_allclose(s3._point_labels[3].position, (0.58, 0.25, 1.08))
    np.testing.assert_allclose(s3._point_gizmos[3].position, (0.5, 0.25, 1.0))
    model.undo()
    s3.draw(model.scene, compute_derived(model.scene))
    np.testing.assert_allclose(s3.points.points, X0, atol=1e-2)
    np.testing.assert_allclose(s3._point_labels[3].position, X0[3] + (0.08, 0.0, 0.08))
    # locking and highlighting still reach the nodes after the cached look of a camera
    model.lock("cam1")
    model.highlight(["cam1"])
    s3.draw(model.scene, compute_derived(model.scene))
    assert gizmo.disable_axes and gizmo.disable_rotations
    assert tuple(s3.camera_nodes("cam1")["frustum"].color) == (230, 159, 0)
    model.lock("cam1", False)
    model.highlight([])
    s3.draw(model.scene, compute_derived(model.scene))
    assert not gizmo.disable_axes and tuple(s3.camera_nodes("cam1")["frustum"].color) != (230, 159, 0)


def test_image_plane_lines_in_3d_follow_the_ray_rule():
    model = SceneModel(default_scene())
    model.randomize_points(40, seed=4, center=tuple(model.scene.points_array().mean(axis=0)), extent=2.0)
    server, app, fakes, views = start_headless(model.scene)
    try:
        view = views[0]
        cams = view.scene3d.every_camera_nodes()
        assert not any(c["img_lines"].visible for c in cams.values())  # 40 points, none selected
        view.model.select_point(9)
        derived = compute_derived(view.model.scene)
        for name, nodes in cams.items():
            seg = derived.image_planes[name].lines[9]  # the epipolar line's ends on the image plane (pixels)
            L = derived.cameras[name].image_to_world(seg, IMAGE_PLANE_DEPTH)
            want = np.array([(a, b) for a, b in zip(L[:-1], L[1:]) if np.isfinite(a).all() and np.isfinite(b).all()],
                            np.float32).reshape(-1, 2, 3)
            assert len(want) and nodes["img_lines"].visible
            np.testing.assert_array_equal(nodes["img_lines"].points, want)
            assert (nodes["img_lines"].colors.reshape(-1, 3) == point_rgb(9)).all()
        view.model.set_points(view.model.scene.points_array()[:MAX_RAY_POINTS])
        derived = compute_derived(view.model.scene)
        for name, nodes in cams.items():
            n_lines = int(np.isfinite(derived.image_planes[name].lines).all(axis=2).all(axis=1).sum())
            assert len(nodes["img_lines"].points) >= n_lines > 1
    finally:
        for f in fakes:
            f.close()
        server.stop()


def test_the_mirror_is_a_reflective_mesh_above_its_ccd_sent_once_per_shape(server, monkeypatch):
    import io

    import trimesh

    from egtviz.viewer.workbench.models.catadioptric import MIRROR_METALLIC, MIRROR_ROUGHNESS

    model = SceneModel(panoramic_scene())
    s3 = scene3d_on(server)
    s3.draw(model.scene, model.derived)
    name = model.scene.cameras[0].name
    drawing = s3.camera_nodes(name).drawing
    mirror_node = drawing.mirror
    cam = model.derived.cameras[name]
    # A glTF mesh under the camera's gizmo (the mirror frame), with a metallic, smooth material.
    assert mirror_node.name == f"{s3.camera_nodes(name)['gizmo'].name}/mirror"
    mesh = trimesh.load(io.BytesIO(mirror_node.glb_data), file_type="glb", force="mesh")
    V = np.asarray(mesh.vertices)
    material = mesh.visual.material
    assert material.metallicFactor == pytest.approx(MIRROR_METALLIC)
    assert material.roughnessFactor == pytest.approx(MIRROR_ROUGHNESS)
    # The mesh is the mirror's surface in its own frame (glTF stores y up: rotate back), about the focus.
    v_ref, _ = cam.mirror.surface(16, 48)
    assert len(V) == len(v_ref)
    assert np.abs(np.sort(np.linalg.norm(V, axis=1)) - np.sort(np.linalg.norm(v_ref, axis=1))).max() < 1e-5
    # The CCD sits on the axis below the focus, ccd_offset away: the mirror is above its CCD.
    np.testing.assert_allclose(drawing.ccd.position, (0.0, 0.0, -cam.mirror.ccd_offset), atol=1e-9)
    assert cam.mirror.ccd_offset > 0
    # A drag moves the gizmo only: the mesh is not sent again; a new mirror shape is.
    sent = count_messages(server.scene, monkeypatch)
    spec = model.scene.camera(name)
    model.set_camera_pose(name, np.add(spec.position, (0.3, 0.0, 0.0)), spec.pose.R, drag_id=1)
    s3.draw(model.scene, model.derived)
    assert drawing.mirror is mirror_node and not any("Glb" in type(m).__name__ for m in sent)
    model.update_camera(name, b=0.2)
    s3.draw(model.scene, model.derived)
    assert drawing.mirror is not mirror_node and any("Glb" in type(m).__name__ for m in sent)
