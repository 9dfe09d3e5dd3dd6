"""The unified sphere camera in the viewer, headless (a real viser server, no browser): its xi slider morphs the
panel's epipolar conics and horizon live, its 3D drawing (sphere, projection centre, the selected point's ray and
epipolar great circle), the GUI built from its parameters; and the 3D labels thinning out above 40 points."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from egtviz.scene import Scene, UnifiedSpec, default_scene
from egtviz.controllers.workbench_fields import FieldError
from egtviz.viewer.server.headless import start_headless
from egtviz.viewer.workbench.models.unified import SPHERE_RADIUS
from egtviz.viewer.workbench.scene3d import MAX_LABELLED_POINTS


def kinds(svg: str, kind: str) -> list[ET.Element]:
    return [el for el in ET.fromstring(svg).iter() if el.get("data-kind") == kind]


def polyline(el: ET.Element) -> np.ndarray:
    return np.array([[float(x) for x in p.split(",")] for p in el.get("points").split()])


def conic_points(svg: str) -> np.ndarray:
    return np.vstack([polyline(e) for e in kinds(svg, "epipolar-conic")])


@pytest.fixture
def view():
    base = default_scene()
    scene = Scene(cameras=(UnifiedSpec("uni", (-3.0, -8.0, 1.5), (20.0, -3.0, 0.0), xi=0.8), base.cameras[1]),
                  points=base.points)
    server, _app, fakes, views = start_headless(scene)
    v = views[0]
    v.notes = []
    v.client.add_notification = lambda title, body, **kw: v.notes.append((title, body))
    yield v
    for f in fakes:
        f.close()
    server.stop()


def test_the_xi_slider_morphs_the_conics_and_the_horizon(view):
    svg = view.svgs["uni"]
    assert len(kinds(svg, "epipolar-conic")) == 8 and len(kinds(svg, "epipole")) >= 1
    # The horizon is the circle of radius f / xi about the principal point (300 / 0.8 = 375 px, by hand).
    (h,) = kinds(svg, "horizon")
    np.testing.assert_allclose(np.hypot(*(polyline(h) - (320.0, 240.0)).T), 375.0, rtol=1e-4)
    before = conic_points(svg)
    slider = view.cameras["uni"].fields["xi"]
    assert (slider.min, slider.max) == (0.0, 1.0) and slider.value == pytest.approx(0.8)
    undo_depth = len(view.model._undo)
    for xi in (0.85, 0.9):  # one slide: the image follows each step
        slider.value = xi
        assert view.model.scene.camera("uni").xi == pytest.approx(xi)
    after = conic_points(view.svgs["uni"])
    assert after.shape != before.shape or np.abs(after - before).max() > 5.0
    (h,) = kinds(view.svgs["uni"], "horizon")
    np.testing.assert_allclose(np.hypot(*(polyline(h) - (320.0, 240.0)).T), 300.0 / 0.9, rtol=1e-4)
    assert len(view.model._undo) == undo_depth + 1  # the slide is one undo step
    view.model.undo()
    assert view.model.scene.camera("uni").xi == pytest.approx(0.8)
    # The folder's fields come from the model's parameters, with their units.
    assert set(view.cameras["uni"].fields) == {"position", "ypr", "xi", "focal_px", "pp", "size"}
    assert view.cameras["uni"].fields["focal_px"].label == "focal length (px)"


def test_a_raw_client_cannot_push_xi_out_of_range(view):
    for bad in (1.5, -0.1, float("nan"), "0.5", True):
        with pytest.raises(FieldError, match="uni: xi"):
            view.controller.slide("uni", "xi", bad)
    assert view.model.scene.camera("uni").xi == 0.8


def test_the_sphere_its_centre_and_the_selected_points_great_circle_in_3d(view):
    nodes = view.scene3d.camera_nodes("uni")
    assert nodes["sphere"].visible and nodes["sphere"].opacity < 1
    np.testing.assert_allclose(nodes["centre"].position, (0.0, 0.0, -0.8 * SPHERE_RADIUS), atol=1e-9)
    assert not nodes["circle"].visible
    view.model.select_point(2)
    derived = view.model.derived
    cam = derived.cameras["uni"]
    X = view.model.scene.points_array()[2]
    assert nodes["circle"].visible and nodes["on_sphere"].visible
    seg = np.asarray(nodes["circle"].points, float).reshape(-1, 3)
    # On the sphere about the centre, in the epipolar plane through the centre (by hand: |p - c| = r, n . (p - c) = 0).
    np.testing.assert_allclose(np.linalg.norm(seg - cam.centre, axis=1), SPHERE_RADIUS, atol=1e-5)
    assert np.abs((seg - cam.centre) @ derived.selected_normal).max() < 1e-5
    p = np.asarray(nodes["on_sphere"].position, float)
    np.testing.assert_allclose(p, cam.centre + SPHERE_RADIUS * (X - cam.centre) / np.linalg.norm(X - cam.centre),
                               atol=1e-9)
    view.cameras["uni"].fields["xi"].value = 0.3
    np.testing.assert_allclose(nodes["centre"].position, (0.0, 0.0, -0.3 * SPHERE_RADIUS), atol=1e-9)


def test_3d_labels_thin_out_above_40_points_as_the_panels_do():
    scene = default_scene()
    X = np.random.default_rng(3).uniform(-1.0, 1.0, (MAX_LABELLED_POINTS + 5, 3)) + (0.0, 0.0, 1.0)
    server, _app, fakes, views = start_headless(scene.replace(points=tuple(map(tuple, X))))
    try:
        view = views[0]
        labels = view.scene3d._point_labels
        assert len(labels) == len(X) and not any(h.visible for h in labels)
        view.model.select_point(7)
        view.model.highlight(["point:3"])
        assert [i for i, h in enumerate(labels) if h.visible] == [3, 7]
        view.model.set_points(X[:MAX_LABELLED_POINTS])
        assert all(h.visible for h in labels[:MAX_LABELLED_POINTS])
    finally:
        for f in fakes:
            f.close()
        server.stop()


def test_switching_a_mirror_rebuilds_its_fields_and_keeps_its_panel_populated():
    from egtviz.scene import panoramic_scene

    server, _app, fakes, views = start_headless(panoramic_scene())
    try:
        view = views[0]
        name = view.model.scene.cameras[0].name
        assert {"a", "b"} <= set(view.cameras[name].fields)
        view.cameras[name].fields["mirror"].value = "parabolic"
        assert view.model.scene.camera(name).mirror == "parabolic"
        assert "h" in view.cameras[name].fields and "b" not in view.cameras[name].fields
        assert len(kinds(view.svgs[name], "point")) >= 5
    finally:
        for f in fakes:
            f.close()
        server.stop()
