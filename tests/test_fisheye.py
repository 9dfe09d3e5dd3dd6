"""The equidistant fisheye camera (r = f theta): projection by hand, round trips, no image beyond the field of view,
and its epipolar curves (the one route of every model) through the partner point's image."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from egtviz.geometry import GeometryError, Pose
from egtviz.geometry.camera_model import CAMERA_MODELS, CameraModel
from egtviz.geometry.epipolar_curves import epipolar_curves
from egtviz.geometry.fisheye import FisheyeCamera

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def random_fisheye(rng: np.random.Generator) -> FisheyeCamera:
    pose = Pose(Rotation.random(random_state=rng).as_matrix(), rng.uniform(-3.0, 3.0, 3))
    return CAMERA_MODELS["fisheye"].build(pose, field_of_view=float(rng.uniform(60.0, 180.0)),
                                          focal_pixels=float(rng.uniform(80.0, 400.0)))


def angle_from_axis(cam: FisheyeCamera, X: np.ndarray) -> np.ndarray:
    d = (X - cam.centre) @ cam.pose.R
    return np.arctan2(np.hypot(d[:, 0], d[:, 1]), d[:, 2])


def distance_to_polyline(p: np.ndarray, P: np.ndarray) -> float:
    a, b = P[:-1], P[1:]
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


def test_projection_by_hand_and_the_registry_entry():
    cam = FisheyeCamera(Pose(), field_of_view=180.0, focal_pixels=100.0, principal_point=(300.0, 200.0))
    assert isinstance(cam, CameraModel) and CAMERA_MODELS["fisheye"].cls is FisheyeCamera
    # On the axis: the principal point. 45 degrees right: r = 100 * pi / 4 to the right. 90 degrees down (y down):
    # r = 100 * pi / 2. Straight back: no image.
    X = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 1.0], [0.0, 3.0, 0.0], [0.0, 0.0, -1.0]])
    p = cam.project(X)
    np.testing.assert_allclose(p.pixels[:3], [[300.0, 200.0], [300.0 + 25.0 * math.pi, 200.0],
                                              [300.0, 200.0 + 50.0 * math.pi]], atol=1e-12)
    assert p.visible.tolist() == [True, True, True, False] and np.isnan(p.pixels[3]).all()
    assert cam.projective_calibration is None and cam.plane_image_conics([0.0, 0.0, 1.0]) is None
    with pytest.raises(GeometryError, match=r"field_of_view: expected a number in \[1, 180\] deg, got 200"):
        CAMERA_MODELS["fisheye"].build(Pose(), field_of_view=200.0)


@settings(max_examples=40, deadline=None)
@given(seeds)
def test_points_beyond_the_field_of_view_have_no_image_and_the_others_round_trip(seed):
    rng = np.random.default_rng(seed)
    cam = random_fisheye(rng)
    X = cam.centre + rng.normal(size=(200, 3)) * rng.uniform(0.1, 10.0, (200, 1))
    theta = angle_from_axis(cam, X)
    p = cam.project(X)
    assert np.array_equal(p.visible, theta <= cam.half_angle)
    assert np.isnan(p.pixels[~p.visible]).all() and np.isfinite(p.pixels[p.visible]).all()
    # r = f theta about the principal point.
    r = np.hypot(*(p.pixels[p.visible] - cam.principal_point).T)
    np.testing.assert_allclose(r, cam.focal_pixels * theta[p.visible], rtol=1e-12, atol=1e-9)
    d = (X - cam.centre) / np.linalg.norm(X - cam.centre, axis=1, keepdims=True)
    np.testing.assert_allclose(cam.back_project(p.pixels[p.visible]), d[p.visible], atol=1e-12)
    # A pixel farther out than f * half the field of view is no ray's image.
    far = np.asarray(cam.principal_point) + (cam.focal_pixels * cam.half_angle + 1.0) * np.array([[0.6, 0.8]])
    assert np.isnan(cam.back_project(far)).all()


def points_in_front_of_both(rng: np.random.Generator, cams: list[FisheyeCamera], n: int) -> np.ndarray:
    X = rng.normal(size=(50 * n, 3)) * 4.0
    seen = np.all([c.project(X).visible for c in cams], axis=0)
    return X[seen][:n]


@settings(max_examples=60, deadline=None)
@given(seeds, st.sampled_from(["fisheye", "pinhole", "unified", "hyperbolic"]))
def test_the_epipolar_curve_passes_through_the_partner_points_image(seed, other):
    rng = np.random.default_rng(seed)
    fish = random_fisheye(rng)
    partner = CAMERA_MODELS[other].build(Pose(Rotation.random(random_state=rng).as_matrix(), rng.uniform(-3, 3, 3)))
    X = points_in_front_of_both(rng, [fish, partner], 8)
    if len(X) == 0:
        return
    for cams, side in (((partner, fish), "second"), ((fish, partner), "first")):
        pair = epipolar_curves(*cams, X, n_samples=4000)
        curves = getattr(pair, side)
        p = fish.project(X)
        for i, m in enumerate(p.pixels):
            n = pair.normals[i]
            # The image of the great circle through X's ray (X's direction, in the epipolar plane) is X's pixel.
            ray = (X[i] - fish.centre) - n * (n @ (X[i] - fish.centre))
            on_curve = fish.project(fish.centre + ray[None, :]).pixels[0]
            assert np.linalg.norm(on_curve - m) < 1e-6
            # The sampled arc is that image: its samples' rays lie in the plane, and it passes through the pixel.
            for arc in curves.arcs[i]:
                assert np.abs(fish.back_project(arc) @ n).max() < 1e-9
            if np.hypot(*(m - fish.principal_point)) < fish.rim_radius - 1e-6:  # inside the drawn disc
                (arc,) = curves.arcs[i]
                assert distance_to_polyline(m, arc) < 1e-3
        # The epipole towards the partner is on every curve the fisheye shows (when it shows it).
        if curves.epipoles_visible[0]:
            e = curves.epipoles[0, :2]
            towards = fish.back_project(e[None, :])[0]
            assert np.abs(pair.normals @ towards).max() < 1e-9


def test_the_unchecked_calls_are_the_checked_ones():
    rng = np.random.default_rng(3)
    cam = random_fisheye(rng)
    X = rng.normal(size=(30, 3)) * 3.0
    normals = rng.normal(size=(10, 3))
    normals[2] = np.nan
    normals[3] = 0.0
    np.testing.assert_array_equal(cam.project(X, check=False).pixels, cam.project(X).pixels)
    np.testing.assert_array_equal(cam.light_paths(X, check=False), cam.light_paths(X))
    a, b = cam.plane_image_arcs(normals, 24, check=False), cam.plane_image_arcs(normals, 24)
    assert [len(x) for x in a] == [len(x) for x in b] and a[2] == [] and a[3] == []
    for x, y in zip(a, b, strict=True):
        for u, v in zip(x, y, strict=True):
            np.testing.assert_array_equal(u, v)


def test_the_workbench_adds_a_fisheye_and_draws_its_epipolar_curves_through_the_points():
    import xml.etree.ElementTree as ET

    from egtviz.scene import default_scene
    from egtviz.viewer.server.headless import start_headless

    server, _app, fakes, views = start_headless(default_scene())
    try:
        view = views[0]
        view.controls.add_buttons["fisheye"].value = True  # the workbench's "Add equidistant fisheye camera"
        (name,) = [c.name for c in view.model.scene.cameras if c.model_kind == "fisheye"]
        assert view.scene3d.camera_nodes(name)["lens"].visible
        view.model.set_pair("cam1", name)
        ip = view.model.derived.image_planes[name]
        assert ip.lines is None and ip.rim is not None and ip.visible.any()
        svg = ET.fromstring(view.svgs[name])
        arcs = [np.array([[float(x) for x in p.split(",")] for p in el.get("points").split()])
                for el in svg.iter() if el.get("data-kind") == "epipolar-conic"]
        assert len(arcs) == ip.visible.sum()
        # Every drawn point lies on one of the drawn curves (the panel's coordinates are the image's, to a scale).
        for i in np.flatnonzero(ip.visible):
            (arc,) = ip.conics[i]
            assert distance_to_polyline(ip.points[i], arc) < 0.05
        assert {"position", "ypr"} <= set(view.cameras[name].fields) and len(view.cameras[name].fields) >= 5
    finally:
        for f in fakes:
            f.close()
        server.stop()
