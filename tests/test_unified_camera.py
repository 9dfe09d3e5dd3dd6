"""The unified sphere camera: projection, lifting, conics, horizon, and its equality with the pin-hole (xi = 0) and
with the parabolic (xi = 1) and hyperbolic catadioptric cameras."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from egtviz.geometry import GeometryError, Intrinsics, PinholeCamera, Pose
from egtviz.geometry.camera_model import CameraModel
from egtviz.geometry.catadioptric import UNIFIED_FLIP, CatadioptricCamera
from egtviz.geometry.epipolar import lines_of_planes
from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror
from egtviz.geometry.panoramic_epipolar import conic_from_plane
from egtviz.geometry.unified import UnifiedCamera

seeds = st.integers(min_value=0, max_value=2**32 - 1)
xis = st.floats(min_value=0.0, max_value=1.0)


def random_pose(rng: np.random.Generator) -> Pose:
    return Pose(Rotation.random(random_state=rng).as_matrix(), rng.uniform(-3.0, 3.0, 3))


def random_camera(rng: np.random.Generator, xi: float) -> UnifiedCamera:
    return UnifiedCamera(
        random_pose(rng), xi, rng.uniform(100.0, 800.0), tuple(rng.uniform(200.0, 400.0, 2)),
        int(rng.integers(300, 900)), int(rng.integers(200, 700)),
    )


def conic_residual(C: np.ndarray, m: np.ndarray, scale: float = 1000.0) -> np.ndarray:
    """Dimensionless algebraic residual of pixels m (k, 2) on the conic C, in coordinates of order one: with
    S = diag(scale, scale, 1), h = S^-1 (u, v, 1) and C' = S C S, |h^T C' h| / (|h|^2 |C'|). (A geometric distance
    would be 0 / 0 on a double line l l^T, the pin-hole's conic.)"""
    S = np.diag([scale, scale, 1.0])
    Cs = S @ C @ S
    h = np.column_stack([m / scale, np.ones(len(m))])
    return np.abs(np.einsum("ni,ij,nj->n", h, Cs, h)) / (np.einsum("ni,ni->n", h, h) * np.linalg.norm(Cs))


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"xi": 1.5}, r"xi: expected a number in \[0, 1\]"),
        ({"xi": -0.1}, "xi"),
        ({"xi": float("nan")}, "xi"),
        ({"focal_pixels": 0.0}, "focal_pixels: expected a number in"),
        ({"width": 0}, "width: expected a whole number"),
        ({"height": 10.5}, "height: expected a whole number"),
        ({"principal_point": (1.0,)}, r"principal_point: expected \(u0, v0\)"),
        ({"principal_point": (1.0, float("inf"))}, "v0"),
        ({"pose": np.eye(4)}, "pose: expected a Pose"),
    ],
)
def test_fields_are_checked_by_name(kwargs, match):
    with pytest.raises(GeometryError, match=match):
        UnifiedCamera(**kwargs)


def test_parameters_round_trip_and_interface():
    cam = UnifiedCamera(Pose(t=[1.0, 2.0, 3.0]), 0.3, 250.0, (100.0, 90.0), 320, 200)
    again = UnifiedCamera.from_parameters(cam.pose, **cam.parameters())
    assert again.parameters() == {"xi": 0.3, "focal_pixels": 250.0, "u0": 100.0, "v0": 90.0, "width": 320,
                                  "height": 200}
    assert isinstance(cam, CameraModel)
    assert np.array_equal(cam.centre, [1.0, 2.0, 3.0])
    moved = cam.moved(Pose(t=[0.0, 0.0, 1.0]))
    assert moved.parameters() == cam.parameters() and np.array_equal(moved.centre, [0.0, 0.0, 1.0])
    with pytest.raises(GeometryError, match="zeta: unknown parameter"):
        UnifiedCamera.from_parameters(Pose(), zeta=1.0)


# ------------------------------------------------------------------ golden values (by hand)
def test_projection_by_hand():
    # s = (1, 0, 1) / sqrt 2, xi = 1/2: u = 100 (1/sqrt2) / (1/sqrt2 + 1/2) = 100 (2 - sqrt 2) (rationalised by hand).
    cam = UnifiedCamera(Pose(), 0.5, 100.0, (0.0, 0.0), 10, 10)
    p = cam.project([[1.0, 0.0, 1.0], [0.0, 3.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, 0.0]])
    assert p.pixels[0] == pytest.approx([100.0 * (2.0 - math.sqrt(2.0)), 0.0], abs=1e-12)
    # Sideways (s_z = 0): radius f / xi = 200, on the horizon.
    assert p.pixels[1] == pytest.approx([0.0, 200.0], abs=1e-12)
    # Straight back (s_z = -1 < -xi) and the centre itself have no image.
    assert p.visible.tolist() == [True, True, False, False]
    assert np.isnan(p.pixels[2:]).all()
    assert p.in_image.tolist() == [False, False, False, False]


def test_visibility_is_the_positive_denominator():
    # s_z = -0.4 > -xi = -0.5 is seen (behind the centre!), s_z = -0.6 is not.
    cam = UnifiedCamera(Pose(), 0.5, 100.0, (0.0, 0.0), 10, 10)
    d = np.array([[math.sqrt(1 - 0.16), 0.0, -0.4], [math.sqrt(1 - 0.36), 0.0, -0.6]])
    assert cam.project(d).visible.tolist() == [True, False]
    # xi = 0 sees exactly the front hemisphere.
    pin = UnifiedCamera(Pose(), 0.0, 100.0, (0.0, 0.0), 10, 10)
    assert pin.project([[1.0, 0.0, 1e-9], [1.0, 0.0, 0.0], [1.0, 0.0, -1e-9]]).visible.tolist() == [True, False, False]


# ------------------------------------------------------------------ identities
@settings(max_examples=60)
@given(seeds, xis)
def test_project_of_back_project_is_identity(seed, xi):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, xi)
    m = np.array(cam.principal_point) + rng.uniform(-4.0, 4.0, (20, 2)) * cam.rim_radius
    rays = cam.back_project(m)
    assert np.allclose(np.linalg.norm(rays, axis=1), 1.0)
    p = cam.project(cam.centre + rng.uniform(0.1, 10.0, (20, 1)) * rays)
    assert p.visible.all()
    np.testing.assert_allclose(p.pixels, m, atol=1e-7 * cam.rim_radius)


@settings(max_examples=60)
@given(seeds, xis)
def test_back_project_of_project_is_the_ray(seed, xi):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, xi)
    X = cam.centre + rng.normal(size=(40, 3)) * rng.uniform(0.1, 5.0)
    p = cam.project(X)
    d = (X - cam.centre) / np.linalg.norm(X - cam.centre, axis=1, keepdims=True)
    s_z = cam.pose.to_local(X)[:, 2] / np.linalg.norm(X - cam.centre, axis=1)
    assert np.array_equal(p.visible, s_z + xi > 0)
    keep = s_z + xi > 1e-3  # well inside the visible region (the pixel grows without bound at s_z = -xi)
    np.testing.assert_allclose(cam.back_project(p.pixels[keep]), d[keep], atol=1e-9)


@settings(max_examples=40)
@given(seeds)
def test_xi_zero_is_the_pinhole_camera(seed):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, 0.0)
    pin = PinholeCamera(cam.pose, Intrinsics.from_K(cam.K, cam.width, cam.height))
    X = cam.centre + rng.normal(size=(50, 3)) * 3.0
    a, b = cam.project(X), pin.project(X)
    assert np.array_equal(a.visible, b.in_front)
    assert np.array_equal(a.in_image, b.in_image)
    np.testing.assert_allclose(a.pixels, b.pixels, rtol=1e-10, atol=1e-8)
    # Planes through the centre: the pin-hole's lines, and the double line as the conic.
    n = rng.normal(size=(5, 3))
    l_pin = lines_of_planes(pin, n)
    l_uni = cam.plane_image_lines(n)
    cross = np.cross(l_pin, l_uni)
    assert np.abs(cross).max() <= 1e-10 * np.abs(l_pin).max() * np.abs(l_uni).max()
    unit = l_pin / np.linalg.norm(l_pin, axis=1, keepdims=True)
    np.testing.assert_allclose(cam.plane_image_conics(n), unit[:, :, None] * unit[:, None, :], atol=1e-12)


def catadioptric_twin(rng: np.random.Generator, mirror) -> tuple[CatadioptricCamera, UnifiedCamera]:
    """A catadioptric camera and the unified camera with its pixels: the unified calibration K_g of the mirror
    camera is the unified camera's K (so the CCD's K = K_g diag(1/gamma, -1/gamma, 1)), and the model frame is the
    mirror frame turned half a turn about x (UNIFIED_FLIP), as docs/conventions.md derives."""
    pose = random_pose(rng)
    f, u0, v0 = rng.uniform(100.0, 800.0), rng.uniform(200.0, 400.0), rng.uniform(150.0, 300.0)
    g = mirror.gamma
    K_ccd = np.array([[f / g, 0.0, u0], [0.0, -f / g, v0], [0.0, 0.0, 1.0]])
    cat = CatadioptricCamera(pose, mirror, K_ccd, 640, 480)
    assert np.allclose(cat.unified_calibration, [[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]])
    uni = UnifiedCamera(Pose(pose.R @ UNIFIED_FLIP, pose.t), mirror.xi, f, (u0, v0), 640, 480)
    return cat, uni


@settings(max_examples=60)
@given(seeds, st.sampled_from(["hyperbolic", "parabolic"]))
def test_xi_of_a_mirror_gives_the_catadioptric_pixels(seed, kind):
    rng = np.random.default_rng(seed)
    if kind == "hyperbolic":
        mirror = HyperbolicMirror(rng.uniform(0.3, 4.0), rng.uniform(0.3, 2.0))
        assert 0.0 < mirror.xi < 1.0
    else:
        mirror = ParabolicMirror(rng.uniform(0.3, 2.0))
        assert mirror.xi == 1.0
    cat, uni = catadioptric_twin(rng, mirror)
    X = cat.pose.t + rng.normal(size=(200, 3)) * 4.0
    a, b = cat.project(X), uni.project(X)
    assert a.visible.sum() > 0
    # Everything the mirror shows, the sphere model shows, at the same pixel.
    assert not (a.visible & ~b.visible).any()
    np.testing.assert_allclose(b.pixels[a.visible], a.pixels[a.visible], rtol=1e-9, atol=1e-7)
    # And the same conics for planes through the focus (up to the arbitrary sign).
    n = rng.normal(size=(6, 3))
    C_uni = uni.plane_image_conics(n)
    C_cat = conic_from_plane(cat, n @ cat.pose.R)
    sign = np.sign(np.einsum("nij,nij->n", C_uni, C_cat))
    np.testing.assert_allclose(C_uni, sign[:, None, None] * C_cat, atol=1e-9)


# ------------------------------------------------------------------ planes, arcs, rim, horizon
@settings(max_examples=60)
@given(seeds, xis)
def test_visible_points_of_a_plane_lie_on_its_conic_and_the_arcs_too(seed, xi):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, xi)
    n = rng.normal(size=3)
    C = cam.plane_image_conics(n)[0]
    assert np.allclose(C, C.T) and np.linalg.norm(C) == pytest.approx(1.0)
    # Points of the plane through the centre.
    u = np.cross(n, rng.normal(size=3))
    v = np.cross(n, u)
    X = cam.centre + rng.normal(size=(30, 1)) * u + rng.normal(size=(30, 1)) * v
    p = cam.project(X)
    ok = p.visible & (np.linalg.norm(p.pixels - cam.principal_point, axis=1) < 20 * cam.rim_radius)
    assert (conic_residual(C, p.pixels[ok]) < 1e-10).all()
    for arc in cam.plane_image_arcs(n, 64)[0]:
        assert (conic_residual(C, arc) < 1e-10).all()
        r = np.linalg.norm(arc - cam.principal_point, axis=1)
        assert (r <= cam.rim_radius * (1.0 + 1e-9)).all()


def test_arcs_full_partial_and_missing():
    cam = UnifiedCamera(Pose(), 0.8, 300.0, (320.0, 240.0), 640, 480)
    assert cam.rim_radius == pytest.approx(400.0)  # the corner (0, 0) is 400 px from (320, 240)
    # The plane z = 0 (normal along the axis): its circle is the horizon, radius f / xi = 375 < 400: all drawn.
    full = cam.plane_image_arcs([0.0, 0.0, 1.0], 50)[0]
    assert len(full) == 1 and full[0].shape == (51, 2) and np.array_equal(full[0][0], full[0][-1])
    np.testing.assert_allclose(np.linalg.norm(full[0] - [320.0, 240.0], axis=1), 375.0)
    np.testing.assert_allclose(np.linalg.norm(cam.horizon(50) - [320.0, 240.0], axis=1), 375.0)
    # The plane x = 0 (contains the axis): the image is the line u = u0, cut at the rim, ends on it.
    part = cam.plane_image_arcs([1.0, 0.0, 0.0], 40)[0]
    assert len(part) == 1 and part[0].shape == (40, 2)
    np.testing.assert_allclose(part[0][:, 0], 320.0, atol=1e-9)
    np.testing.assert_allclose(sorted([part[0][0, 1], part[0][-1, 1]]), [240.0 - 400.0, 240.0 + 400.0])
    # A narrow pin-hole whose drawn disc sees only near the axis: the plane z = 0 is not drawn.
    narrow = UnifiedCamera(Pose(), 0.0, 1000.0, (320.0, 240.0), 640, 480)
    assert narrow.plane_image_arcs([[0.0, 0.0, 1.0], [np.nan] * 3, [0.0] * 3], 10) == [[], [], []]
    assert narrow.horizon() is None
    assert np.isnan(narrow.plane_image_conics([[np.nan] * 3, [0.0] * 3])).all()
    assert np.isnan(narrow.plane_image_lines([[np.nan] * 3, [0.0] * 3])).all()
    assert cam.plane_image_lines([0.0, 0.0, 1.0]) is None  # xi > 0: plane images are conics
    with pytest.raises(GeometryError, match="n_samples: expected an integer >= 3"):
        cam.plane_image_arcs([0.0, 0.0, 1.0], 2)


@settings(max_examples=40)
@given(seeds, st.floats(min_value=0.05, max_value=1.0))
def test_horizon_is_the_image_of_the_sideways_rays(seed, xi):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, xi)
    phi = rng.uniform(0.0, 2.0 * np.pi, 20)
    sideways = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(20)])
    m = cam.project(cam.pose.to_world(sideways)).pixels
    np.testing.assert_allclose(np.linalg.norm(m - cam.principal_point, axis=1), cam.focal_pixels / xi)
    h = cam.horizon(64)
    np.testing.assert_allclose(np.linalg.norm(h - cam.principal_point, axis=1), cam.focal_pixels / xi)


@settings(max_examples=40)
@given(seeds, xis)
def test_baseline_images_lie_on_every_conic_through_the_line(seed, xi):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, xi)
    d = rng.normal(size=3)
    e = cam.baseline_images(d)
    assert e.points.shape == (2, 3)
    s_z = (cam.pose.R.T @ d)[2] / np.linalg.norm(d)
    assert e.visible.tolist() == [s_z + xi > 0, -s_z + xi > 0]
    # The visible one is the projection of a point along +-d.
    if e.visible[0]:
        np.testing.assert_allclose(e.points[0, :2], cam.project(cam.centre + d).pixels[0], rtol=1e-9, atol=1e-6)
    normals = np.cross(d, rng.normal(size=(10, 3)))
    C = cam.plane_image_conics(normals)
    for p in e.points:
        r = np.einsum("i,nij,j->n", p, C, p) / np.dot(p, p)
        assert np.abs(r).max() < 1e-9


def test_sphere_drawing_helpers():
    pose = Pose(np.diag([1.0, -1.0, -1.0]), [1.0, 2.0, 3.0])  # optical axis along world -z
    cam = UnifiedCamera(pose, 0.25)
    np.testing.assert_allclose(cam.projection_centre(2.0), [1.0, 2.0, 3.5])  # 2 * 0.25 behind, i.e. up
    s = cam.sphere_points([[1.0, 2.0, 0.0], [1.0, 2.0, 3.0]], radius=0.5)
    np.testing.assert_allclose(s[0], [1.0, 2.0, 2.5])
    assert np.isnan(s[1]).all()
    circle = cam.great_circle([0.0, 0.0, 1.0], 16, radius=2.0)
    assert circle.shape == (17, 3) and np.array_equal(circle[0], circle[-1])
    np.testing.assert_allclose(np.linalg.norm(circle - cam.centre, axis=1), 2.0)
    np.testing.assert_allclose(circle[:, 2], 3.0)
    with pytest.raises(GeometryError, match="normal_world: a zero normal"):
        cam.great_circle([0.0, 0.0, 0.0])
