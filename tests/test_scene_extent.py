"""The 3D view frames what the scene holds (mirrors and their CCDs, not only camera centres) and draws its glyphs
at the scene's size: a table-top scene of 0.4 m mirrors is not hidden under 1 m gizmos and world axes."""

from __future__ import annotations

import math

import numpy as np
import pytest
import viser

from egtviz.scene import SCENES, SceneModel, compute_derived, panoramic_scene
from egtviz.scene.extent import GLYPH_RANGE, scene_extent
from egtviz.viewer.render.panels import WindowSize, framed_camera, plan_grid
from egtviz.viewer.workbench.scene3d import Scene3D
from egtviz.viewer.render.svg import NORMAL, PRESENT


def _in_view(framed, aspect: float, P: np.ndarray) -> np.ndarray:
    """(N,) each point's place in the view as a fraction of the half-width and half-height (<= 1: inside)."""
    eye, target = np.array(framed.position), np.array(framed.look_at)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    Q = P - eye
    depth = Q @ forward
    assert np.all(depth > 0)
    tan_v = math.tan(framed.fov / 2)
    return np.maximum(np.abs(Q @ right) / depth / (tan_v * aspect), np.abs(Q @ up) / depth / tan_v)


def _mirror_points(scene):
    derived = compute_derived(scene)
    out = []
    for model in derived.cameras.values():
        V, _ = model.mirror.surface(16, 48)
        V = np.vstack([np.asarray(V).reshape(-1, 3), [[0, 0, -model.mirror.ccd_offset]]])
        out.append(V @ model.pose.R.T + model.pose.t)
    return np.vstack(out)


@pytest.mark.parametrize("name", ["example2", "example4", "panoramic"])
@pytest.mark.parametrize(("window", "style"), [(WindowSize(1920, 1080), NORMAL), (WindowSize(1366, 768), NORMAL),
                                               (WindowSize(1920, 1080), PRESENT)])
def test_every_mirror_and_its_ccd_are_in_the_framed_view(name, window, style):
    scene = panoramic_scene() if name == "panoramic" else SCENES[name]()
    extent = scene_extent(scene, compute_derived(scene))
    grid = plan_grid([(c.name, float(c.width), float(c.height)) for c in scene.cameras], window, style=style)
    aspect = grid.canvas_px / window.height
    framed = framed_camera(extent.points, aspect, pad=extent.glyph, min_radius=3 * extent.glyph)
    # The whole drawn mirror (finer than the extent's samples) and its CCD: inside the canvas, with a margin.
    assert _in_view(framed, aspect, _mirror_points(scene)).max() < 0.95
    # ... and the scene fills the view: no table top seen from across the room.
    assert _in_view(framed, aspect, extent.points).max() > 0.6


def test_the_mirror_scene_was_cut_off_when_framed_on_centres_alone():
    # What the view framed before: camera centres and points with a metre of room.
    scene = SCENES["example2"]()
    grid = plan_grid([(c.name, float(c.width), float(c.height)) for c in scene.cameras], WindowSize(1920, 1080))
    aspect = grid.canvas_px / 1080
    centres = np.vstack([[c.position for c in scene.cameras], scene.points_array()])
    old = framed_camera(centres, aspect)
    assert _in_view(old, aspect, _mirror_points(scene)).max() > 1.0


def test_glyphs_follow_the_scene_size():
    small = scene_extent(panoramic_scene(), compute_derived(panoramic_scene()))
    room = scene_extent(SCENES["example3"](), compute_derived(SCENES["example3"]()))
    # The tutorial's example 3 spans 25 m: its gizmos grow past 1 m (seen from 30 m away), within the bound.
    assert 1.2 < room.glyph <= GLYPH_RANGE[1]
    # The panoramic scene's mirrors are 0.4 m wide: a gizmo about their size, not 1 m.
    assert 0.2 <= small.glyph <= 0.5
    assert np.all(small.lo <= small.points.min(axis=0)) and small.diagonal > 4.0


def test_scene3d_draws_gizmos_axes_and_marks_at_the_glyph_size():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = panoramic_scene()
        model = SceneModel(scene)
        s3 = Scene3D(server.scene, lambda *a: None, lambda *a: None)
        s3.draw(model.scene, model.derived)
        extent = scene_extent(model.scene, model.derived)
        s3.set_glyph(extent.glyph)
        g = extent.glyph
        for nodes in s3.every_camera_nodes().values():
            assert nodes["gizmo"].scale == pytest.approx(g)
            assert nodes["axes"].axes_length == pytest.approx(0.5 * g)
        assert s3._world.axes_length == pytest.approx(g)
        assert s3.points.point_size == pytest.approx(0.12 * g)
        # A camera added later is drawn at the same size.
        model.add_camera("panoramic")
        s3.draw(model.scene, model.derived)
        assert all(n["gizmo"].scale == pytest.approx(g) for n in s3.every_camera_nodes().values())
    finally:
        server.stop()


def test_a_tab_draws_glyphs_at_the_scene_size_and_frames_again_when_a_camera_is_added():
    from egtviz.viewer.server.headless import start_headless

    server, app, fakes, views = start_headless(panoramic_scene())
    try:
        view = views[0]
        extent = scene_extent(view.model.scene, view.model.derived)
        assert view.scene3d.glyph == pytest.approx(extent.glyph) and extent.glyph < 0.5
        framed = []
        original = view.dock.frame_camera
        view.dock.frame_camera = lambda: (framed.append(len(view.model.scene.cameras)), original())
        view.model.select_point(1)  # not a change of what the scene holds: the view stays
        assert framed == []
        view.model.add_camera("pinhole")
        assert framed == [3]
    finally:
        for f in fakes:
            f.close()
        server.stop()
