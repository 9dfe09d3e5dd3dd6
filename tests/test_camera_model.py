"""The camera-model interface, its registry (the pin-hole, catadioptric and unified cameras themselves), and the
epipolar curves of any pair of models."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from egtviz.geometry import (
    DegenerateConfigurationError,
    GeometryError,
    PinholeCamera,
    Pose,
)
from egtviz.geometry.camera_model import (
    CAMERA_MODELS,
    CameraModel,
    CameraModelInfo,
    ParameterSpec,
    Projection,
    camera_model_info,
    parameters_from_specs,
)
from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry.epipolar import epipolar_pair
from egtviz.geometry.epipolar_curves import epipolar_curves
from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror
from egtviz.geometry.panoramic_epipolar import epipolar_conics
from egtviz.geometry.poses import look_at
from egtviz.geometry.unified import UnifiedCamera

KINDS = ("pinhole", "hyperbolic", "parabolic", "unified", "fisheye")
#: The models whose planes through the centre image to conics (the fisheye's do not: tests/test_fisheye.py).
CONIC_KINDS = ("pinhole", "hyperbolic", "parabolic", "unified")
seeds = st.integers(min_value=0, max_value=2**32 - 1)


def conic_residual(C: np.ndarray, m: np.ndarray, scale: float = 1000.0) -> np.ndarray:
    """Dimensionless algebraic residual of pixels m (k, 2) on conics C (3, 3) or (k, 3, 3), in coordinates of order
    one: S = diag(scale, scale, 1), h = S^-1 (u, v, 1), C' = S C S, |h^T C' h| / (|h|^2 |C'|). (A geometric
    distance would be 0 / 0 on a double line, the pin-hole's conic.)"""
    S = np.diag([scale, scale, 1.0])
    Cs = np.broadcast_to(S @ C @ S, (len(m), 3, 3))
    h = np.column_stack([m / scale, np.ones(len(m))])
    return np.abs(np.einsum("ni,nij,nj->n", h, Cs, h)) / (
        np.einsum("ni,ni->n", h, h) * np.linalg.norm(Cs, axis=(1, 2))
    )


def random_model(rng: np.random.Generator, kind: str) -> CameraModel:
    pose = Pose(Rotation.random(random_state=rng).as_matrix(), rng.uniform(-3.0, 3.0, 3))
    values = {"xi": float(rng.uniform(0.0, 1.0))} if kind == "unified" else {}
    return CAMERA_MODELS[kind].build(pose, **values)


def points_seen_by(rng: np.random.Generator, cam: CameraModel, n: int) -> np.ndarray:
    """n scene points that ``cam`` sees: random pixels in its drawn region back-projected to random depths."""
    rim = cam.rim()
    lo, hi = rim.min(axis=0), rim.max(axis=0)
    rays = cam.back_project(rng.uniform(lo, hi, (4 * n, 2)))
    rays = rays[np.isfinite(rays).all(axis=1)][:n]
    assert len(rays) > 0
    return cam.centre + rng.uniform(0.5, 6.0, (len(rays), 1)) * rays


# ------------------------------------------------------------------ registry and parameters
def test_registry_lists_every_model_once_with_its_class_and_parameters():
    assert tuple(CAMERA_MODELS) == KINDS
    for kind, info in CAMERA_MODELS.items():
        assert isinstance(info, CameraModelInfo) and info.kind == kind and info.label
        assert info.cls.kind == kind
        names = [p.name for p in info.parameters]
        assert len(names) == len(set(names)) and {"width", "height"} <= set(names)
        cam = info.build(Pose())
        assert isinstance(cam, CameraModel)
        assert cam.parameters() == {p.name: p.default for p in info.parameters}
        again = info.build(Pose(t=[1.0, 0.0, 0.0]), **cam.parameters())
        assert again.parameters() == cam.parameters() and np.array_equal(again.centre, [1.0, 0.0, 0.0])
        assert isinstance(cam.project([[0.0, 5.0, 1.0]]), Projection)


def test_registry_entry_with_the_wrong_class_is_refused():
    info = CameraModelInfo("pinhole", "x", "egtviz.geometry.unified:UnifiedCamera")
    with pytest.raises(GeometryError, match="its kind 'unified' is not 'pinhole'"):
        info.cls


def test_the_cameras_themselves_are_the_models_and_report_their_kind():
    assert isinstance(PinholeCamera(), CameraModel)
    assert isinstance(CatadioptricCamera(), CameraModel)
    assert PinholeCamera().kind == "pinhole"
    assert CatadioptricCamera(mirror=HyperbolicMirror()).kind == "hyperbolic"
    assert CatadioptricCamera(mirror=ParabolicMirror()).kind == "parabolic"
    assert camera_model_info(CatadioptricCamera(mirror=ParabolicMirror())) is CAMERA_MODELS["parabolic"]
    assert camera_model_info(UnifiedCamera()) is CAMERA_MODELS["unified"]
    # A catadioptric camera's parameters are its kind's: a, b (hyperbolic) or h (parabolic), then the CCD's.
    assert [p.name for p in CatadioptricCamera(mirror=ParabolicMirror()).PARAMETERS][:2] == ["h", "focal_pixels"]
    with pytest.raises(GeometryError, match="camera: expected a registered camera model"):
        camera_model_info(np.eye(3))


def test_cross_parameter_ranges_are_refused_by_the_models():
    with pytest.raises(GeometryError, match=r"b/a: expected 0.01..100, got 0.001"):
        CAMERA_MODELS["hyperbolic"].build(Pose(), a=10.0, b=0.01)
    with pytest.raises(GeometryError, match=r"focal_length \* ku: expected 1..1e\+06 px, got 0.5"):
        CAMERA_MODELS["pinhole"].build(Pose(), focal_length=0.001, ku=500.0)
    with pytest.raises(GeometryError, match=r"skew / \(focal_length \* ku\): expected -1..1, got 2"):
        CAMERA_MODELS["pinhole"].build(Pose(), skew=1600.0)


@pytest.mark.parametrize(
    ("value", "match"),
    [(1.5, r"xi: expected a number in \[0, 1\], got 1.5"), ("a", "xi: expected a number"), (True, "xi"),
     (float("nan"), "xi")],
)
def test_parameter_spec_check_names_the_parameter(value, match):
    spec = ParameterSpec("xi", "xi", "", 0.0, 1.0, 0.5)
    assert spec.check(1) == 1.0 and isinstance(spec.check(1), float)
    with pytest.raises(GeometryError, match=match):
        spec.check(value)


def test_parameter_specs_integer_ranges_and_unknown_names():
    width = ParameterSpec("width", "width", "px", 1, 100, 10, integer=True)
    assert width.check(12.0) == 12 and isinstance(width.check(12.0), int)
    with pytest.raises(GeometryError, match=r"width: expected a whole number in \[1, 100\] px, got 12.5"):
        width.check(12.5)
    with pytest.raises(GeometryError, match="default 5 outside"):
        ParameterSpec("a", "a", "m", 0.0, 1.0, 5.0)
    with pytest.raises(GeometryError, match="finite range"):
        ParameterSpec("a", "a", "m", 1.0, 0.0, 0.5)
    assert parameters_from_specs((width,), {}) == {"width": 10}
    with pytest.raises(GeometryError, match="depth: unknown parameter"):
        parameters_from_specs((width,), {"depth": 1.0})
    with pytest.raises(GeometryError, match="b: expected a number in"):
        CAMERA_MODELS["hyperbolic"].build(Pose(), b=0.0)


# ------------------------------------------------------------------ every model keeps the interface's promises
@settings(max_examples=30)
@given(seeds, st.sampled_from(CONIC_KINDS))
def test_each_model_round_trips_and_draws_on_its_conics(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_model(rng, kind)
    X = points_seen_by(rng, cam, 30)
    p = cam.project(X)
    assert p.visible.all() and np.isfinite(p.pixels).all()
    d = (X - cam.centre) / np.linalg.norm(X - cam.centre, axis=1, keepdims=True)
    np.testing.assert_allclose(cam.back_project(p.pixels), d, atol=1e-8)
    rim = cam.rim()
    assert np.array_equal(rim[0], rim[-1])
    normals = rng.normal(size=(8, 3))
    C = cam.plane_image_conics(normals)
    assert C.shape == (8, 3, 3)
    for k, arcs in enumerate(cam.plane_image_arcs(normals, 48)):
        for arc in arcs:
            assert arc.ndim == 2 and arc.shape[1] == 2 and len(arc) >= 2
            assert conic_residual(C[k], arc).max() < 1e-9
    e = cam.baseline_images(normals[0])
    for point in e.points:
        C_through = cam.plane_image_conics(np.cross(normals[0], rng.normal(size=(5, 3))))
        r = np.einsum("i,nij,j->n", point, C_through, point) / point.dot(point)
        assert np.abs(r).max() < 1e-9


# ------------------------------------------------------------------ epipolar curves of any pair
@settings(max_examples=40)
@given(seeds, st.sampled_from(list(itertools.product(CONIC_KINDS, CONIC_KINDS))))
def test_epipolar_curves_pass_through_the_images_and_the_epipoles(seed, kinds):
    rng = np.random.default_rng(seed)
    cams = [random_model(rng, k) for k in kinds]
    X = np.vstack([points_seen_by(rng, cams[0], 10), points_seen_by(rng, cams[1], 10)])
    pair = epipolar_curves(cams[0], cams[1], X, n_samples=40)
    assert np.allclose(np.linalg.norm(pair.normals, axis=1), 1.0)
    assert np.abs(np.einsum("ni,ni->n", pair.normals, X - cams[0].centre)).max() < 1e-9 * np.abs(X).max()
    for cam, curves in zip(cams, (pair.first, pair.second), strict=True):
        p = cam.project(X)
        seen = np.flatnonzero(p.visible)
        assert curves.conics.shape == (len(X), 3, 3)
        assert conic_residual(curves.conics[seen], p.pixels[seen]).max() < 1e-9
        for k, arcs in enumerate(curves.arcs):
            for arc in arcs:
                assert conic_residual(curves.conics[k], arc).max() < 1e-9
        assert len(curves.epipoles) == (1 if cam.kind == "pinhole" else 2)
        for e in curves.epipoles:
            r = np.einsum("i,nij,j->n", e, curves.conics, e) / e.dot(e)
            assert np.abs(r).max() < 1e-9
        if cam.kind == "pinhole":
            lines = curves.lines / np.hypot(curves.lines[:, :1], curves.lines[:, 1:2])
            dist = np.abs(np.einsum("ni,ni->n", lines[seen], np.column_stack([p.pixels[seen], np.ones(len(seen))])))
            assert dist.max() < 1e-6  # pixels
        else:
            assert curves.lines is None or cam.parameters().get("xi") == 0.0


@settings(max_examples=40)
@given(seeds, st.sampled_from([("pinhole", "unified"), ("unified", "pinhole")]))
def test_mixed_pinhole_unified_pair_the_ray_of_one_image_meets_the_other_image(seed, kinds):
    # The epipolar curve of an image point m1 is that of any point on its back-projected ray: build it from the
    # ray (not from X) and the image m2 of X lies on it.
    rng = np.random.default_rng(seed)
    cam1, cam2 = (random_model(rng, k) for k in kinds)
    X = points_seen_by(rng, cam1, 20)
    cam2 = cam2.moved(look_at(cam2.centre, X.mean(axis=0)))  # so that it sees some of them
    m1 = cam1.project(X).pixels
    on_ray = cam1.centre + 0.37 * cam1.back_project(m1)
    pair = epipolar_curves(cam1, cam2, on_ray)
    p2 = cam2.project(X)
    seen = np.flatnonzero(p2.visible)
    assert len(seen) > 0
    assert conic_residual(pair.second.conics[seen], p2.pixels[seen]).max() < 1e-9
    if cam2.kind == "pinhole":
        l2 = pair.second.lines[seen]
        l2 = l2 / np.hypot(l2[:, :1], l2[:, 1:2])
        assert np.abs(np.einsum("ni,ni->n", l2, np.column_stack([p2.pixels[seen], np.ones(len(seen))]))).max() < 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_pinhole_pair_lines_are_those_of_the_fundamental_matrix(seed):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_model(rng, "pinhole"), random_model(rng, "pinhole")
    X = points_seen_by(rng, cam1, 15)
    pair = epipolar_curves(cam1, cam2, X)
    F = epipolar_pair(cam1, cam2).F
    l_F = np.column_stack([cam1.project(X).pixels, np.ones(len(X))]) @ F.T  # l2 = F m1
    cross = np.cross(l_F / np.linalg.norm(l_F, axis=1, keepdims=True),
                     pair.second.lines / np.linalg.norm(pair.second.lines, axis=1, keepdims=True))
    assert np.abs(cross).max() < 1e-9
    # The single epipole of each image spans F's null spaces (F e1 = 0, F^T e2 = 0), with the pair's flags.
    ep = epipolar_pair(cam1, cam2)
    e1, e2 = pair.first.epipoles[0], pair.second.epipoles[0]
    assert np.linalg.norm(F @ e1) < 1e-9 * np.linalg.norm(e1)
    assert np.linalg.norm(F.T @ e2) < 1e-9 * np.linalg.norm(e2)
    assert pair.first.epipoles_visible.tolist() == [ep.e1_in_front]
    assert pair.second.epipoles_visible.tolist() == [ep.e2_in_front]


def test_catadioptric_pair_conics_are_those_of_the_panoramic_route():
    rng = np.random.default_rng(11)
    cam1, cam2 = random_model(rng, "hyperbolic"), random_model(rng, "parabolic")
    X = rng.normal(size=(12, 3)) * 3.0
    pair = epipolar_curves(cam1, cam2, X)
    for mine, theirs in zip((pair.first.conics, pair.second.conics), epipolar_conics(cam1, cam2, X),
                             strict=True):
        sign = np.sign(np.einsum("nij,nij->n", mine, theirs))
        np.testing.assert_allclose(mine, sign[:, None, None] * theirs, atol=1e-9)


def test_points_on_the_baseline_have_no_curve_and_coincident_centres_raise():
    cam1 = UnifiedCamera(Pose(t=[0.0, 0.0, 0.0]), 0.5)
    cam2 = PinholeCamera(Pose(t=[2.0, 0.0, 0.0]))
    X = np.array([[1.0, 0.0, 0.0], [5.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    pair = epipolar_curves(cam1, cam2, X)
    assert np.isnan(pair.normals[:2]).all() and np.isfinite(pair.normals[2]).all()
    for curves in (pair.first, pair.second):
        assert np.isnan(curves.conics[:2]).all() and np.isfinite(curves.conics[2]).all()
        assert curves.arcs[0] == [] and curves.arcs[1] == []
    assert np.isnan(pair.second.lines[:2]).all()
    # The unified camera's epipoles, by hand: s = (+-1, 0, 0), u = 320 +- 300 / (0 + 1/2); xi = 1/2 sees both.
    np.testing.assert_allclose(pair.first.epipoles, [[920.0, 240.0, 1.0], [-280.0, 240.0, 1.0]])
    assert pair.first.epipoles_visible.tolist() == [True, True]
    with pytest.raises(DegenerateConfigurationError, match="centres coincide"):
        epipolar_curves(cam1, cam1.moved(Pose(np.diag([1.0, -1.0, -1.0]))), X)
    with pytest.raises(GeometryError, match="cam2: expected a camera model"):
        epipolar_curves(cam1, np.eye(3), X)
