"""Mirrors and the central catadioptric camera (EGT reference, section 3)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from egtviz.geometry._validate import GeometryError
from egtviz.geometry.catadioptric import CatadioptricCamera, PanoramicProjection
from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror
from egtviz.geometry.poses import Pose, rotx, roty, rotz

from _mirrors import K_EGT, kinds, random_mirror, seeds  # noqa: E402


def random_pose(rng: np.random.Generator, tilt: float = 0.3, spread: float = 5.0) -> Pose:
    R = rotz(rng.uniform(-np.pi, np.pi)) @ rotx(rng.uniform(-tilt, tilt)) @ roty(rng.uniform(-tilt, tilt))
    return Pose(R, rng.uniform(-spread, spread, 3))


def random_camera(rng: np.random.Generator, kind: str) -> CatadioptricCamera:
    return CatadioptricCamera(random_pose(rng), random_mirror(rng, kind), K_EGT)


def max_visible_elevation(mirror) -> float:
    return float(np.arctan2(mirror.rim_z, mirror.rim_radius))


def directions_at(elevation: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    c = np.cos(elevation)
    return np.column_stack([c * np.cos(azimuth), c * np.sin(azimuth), np.sin(elevation)])


def visible_directions(rng: np.random.Generator, mirror, n: int) -> np.ndarray:
    """Unit mirror-frame directions safely inside the visible field (below the rim, above the nadir)."""
    top = max_visible_elevation(mirror) - 1e-3
    return directions_at(rng.uniform(-np.pi / 2 + 1e-3, top, n), rng.uniform(-np.pi, np.pi, n))


def visible_world_points(rng: np.random.Generator, cam: CatadioptricCamera, n: int) -> np.ndarray:
    d = visible_directions(rng, cam.mirror, n)
    return cam.pose.to_world(d * rng.uniform(0.5, 30.0, (n, 1)))


# --------------------------------------------------------------------------- golden
def test_egt_example2_golden():
    """EGT Example 2: H = [rotz(pi/4), (-5, -5, 0)], default mirror a=3, b=1, Xw = (0, 0, 4)."""
    cam = CatadioptricCamera(Pose(rotz(np.pi / 4), [-5.0, -5.0, 0.0]), HyperbolicMirror(3.0, 1.0), K_EGT)
    proj = cam.project([0.0, 0.0, 4.0])

    # Independent route: the point in the mirror frame by hand, the sheet crossing by brentq
    # on the height difference between the ray s * X and the sheet, then the CCD pin-hole by hand.
    a, b = 3.0, 1.0
    e = np.sqrt(a * a + b * b)
    c = s = np.sqrt(0.5)
    X = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array([5.0, 5.0, 4.0])  # R^T (Xw - t)
    np.testing.assert_allclose(X, [5.0 * np.sqrt(2.0), 0.0, 4.0], atol=1e-12)

    def height_above_sheet(t: float) -> float:
        r = t * np.hypot(X[0], X[1])
        return t * X[2] - (-e + a * np.sqrt(1.0 + r * r / (b * b)))

    lam = brentq(height_above_sheet, 0.0, 1.0, xtol=1e-15, rtol=1e-15)
    Xh = lam * X
    u = 320.0 + 1e3 * Xh[0] / (Xh[2] + 2.0 * e)
    v = 240.0 + 1e3 * Xh[1] / (Xh[2] + 2.0 * e)

    assert proj.visible.tolist() == [True] and proj.in_image.tolist() == [True]
    np.testing.assert_allclose(proj.mirror_points[0], Xh, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(proj.pixels[0], [u, v], rtol=1e-9)
    # Literal values (produced by the two routes above; lam = 1 / (3 sqrt(66) - 4 sqrt(10))):
    np.testing.assert_allclose(proj.pixels[0], [410.48906145334036, 240.0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(
        proj.mirror_points[0], [0.6031787983781852, 0.0, 0.3412094548809345], rtol=1e-9, atol=1e-12
    )
    np.testing.assert_allclose(lam, 1.0 / (3.0 * np.sqrt(66.0) - 4.0 * np.sqrt(10.0)), rtol=1e-12)


def test_unified_parameters_closed_form():
    m = HyperbolicMirror(3.0, 1.0)
    e = np.sqrt(10.0)
    assert m.e == pytest.approx(e)
    p = 1.0**2 / (2 * 3.0)  # latus rectum 4p = 2 b^2 / a
    assert m.xi == pytest.approx(2 * e / np.sqrt(4 * e**2 + 4 * p**2))  # d / sqrt(d^2 + 4p^2), d = 2e
    assert m.xi == pytest.approx(6 * e / 19.0)
    assert m.gamma == pytest.approx(1.0 / 19.0)
    assert m.ccd_offset == pytest.approx(2 * e)
    assert m.rim_radius == 2.0
    assert m.rim_z == pytest.approx(-e + 3.0 * np.sqrt(5.0))
    par = ParabolicMirror(0.5)
    assert (par.xi, par.gamma, par.rim_radius, par.rim_z) == (1.0, 0.5, 1.0, pytest.approx(0.75))


# --------------------------------------------------------------------------- properties
@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_mirror_points_on_quadric_and_on_the_ray(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, kind)
    X = cam.pose.t + rng.normal(size=(300, 3)) * rng.uniform(0.5, 20.0)
    proj = cam.project(X)
    vis = proj.visible
    assert vis.any()
    Xh, Xm = proj.mirror_points[vis], cam.pose.to_local(X)[vis]
    m = cam.mirror
    scale = max(m.rim_radius, abs(m.rim_z), 1.0)
    assert np.all(np.abs(m.implicit(Xh)) < 1e-9 * scale**2)
    # On the visible sheet (never the other one): z equals the profile of the sheet.
    r = np.hypot(Xh[:, 0], Xh[:, 1])
    np.testing.assert_allclose(Xh[:, 2], m.profile_z(r), atol=1e-9 * scale)
    assert np.all(r <= m.rim_radius * (1 + 1e-9))
    # Collinear with focus and point, on the same side (lambda > 0).
    lam = np.sum(Xh * Xm, axis=1) / np.sum(Xm * Xm, axis=1)
    assert np.all(lam > 0)
    np.testing.assert_allclose(Xh, lam[:, None] * Xm, atol=1e-9 * scale)
    # Invisible rows are NaN, never a wrong finite value.
    assert np.all(np.isnan(proj.pixels[~vis])) and np.all(np.isnan(proj.mirror_points[~vis]))
    assert np.all(np.isfinite(proj.pixels[vis]))


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_intersect_root_matches_brentq_and_right_sheet(seed, kind):
    rng = np.random.default_rng(seed)
    m = random_mirror(rng, kind)
    d = visible_directions(rng, m, 5) * rng.uniform(0.1, 10.0, (5, 1))
    lam, hit = m.intersect(d)
    assert hit.all()
    for lam_i, di in zip(lam, d, strict=True):
        rho = np.hypot(di[0], di[1])

        def gap(t, di=di, rho=rho):
            return t * di[2] - m.profile_z(t * rho)

        upper = 1.0
        while gap(upper) > 0:
            upper *= 2.0
        assert lam_i == pytest.approx(brentq(gap, 0.0, upper, xtol=1e-14, rtol=1e-13), rel=1e-9)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_back_project_returns_the_ray(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, kind)
    X = visible_world_points(rng, cam, 100)
    proj = cam.project(X)
    assert proj.visible.all()
    d = cam.back_project(proj.pixels)
    expected = (X - cam.pose.t) / np.linalg.norm(X - cam.pose.t, axis=1, keepdims=True)
    np.testing.assert_allclose(d, expected, atol=1e-8)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_unified_route_equals_direct_route(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, kind)
    X = np.vstack([visible_world_points(rng, cam, 100), cam.pose.t + rng.normal(size=(100, 3)) * 10])
    direct = cam.project(X)
    unified = cam.project_unified(X)
    assert np.array_equal(np.isnan(unified).any(axis=1), ~direct.visible)
    vis = direct.visible
    scale = np.linalg.norm(direct.pixels[vis], axis=1, keepdims=True)
    assert np.all(np.abs(unified[vis] - direct.pixels[vis]) <= 1e-9 * scale)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_blind_cone_is_not_visible(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, kind)
    m = cam.mirror
    az = rng.uniform(-np.pi, np.pi, 50)
    # Above the rim (between the rim's elevation and the zenith).
    above = directions_at(rng.uniform(max_visible_elevation(m) + 1e-6, np.pi / 2, 50), az)
    blind = [above]
    if kind == "hyperbolic":
        # At or steeper than the asymptote (sin(elevation) >= a / e), even with no rim at all.
        asym = np.arcsin(m.a / m.e)
        steep = directions_at(rng.uniform(asym, np.pi / 2, 50), az)
        blind.append(steep)
        unbounded = HyperbolicMirror(m.a, m.b, rim_radius=1e12)
        assert not unbounded.intersect(steep).hit.any()
        assert not unbounded.intersect(directions_at(np.full(1, asym), np.zeros(1))).hit.any()
    d = np.vstack(blind)
    proj = cam.project(cam.pose.to_world(d * 5.0))
    assert not proj.visible.any() and not proj.in_image.any()
    assert np.all(np.isnan(proj.pixels)) and np.all(np.isnan(proj.mirror_points))
    assert np.all(np.isnan(cam.project_unified(cam.pose.to_world(d))))
    lam, hit = m.intersect(d)
    assert not hit.any() and np.all(np.isnan(lam))


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_world_frame_invariance(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng, kind)
    X = np.vstack([visible_world_points(rng, cam, 50), cam.pose.t + rng.normal(size=(50, 3)) * 10])
    G = Rotation.random(random_state=rng).as_matrix()
    g = rng.uniform(-20, 20, 3)
    moved = cam.moved(Pose(G @ cam.pose.R, G @ cam.pose.t + g))
    before, after = cam.project(X), moved.project(X @ G.T + g)
    assert np.array_equal(before.visible, after.visible)
    np.testing.assert_allclose(after.pixels, before.pixels, rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(after.mirror_points, before.mirror_points, rtol=1e-9, atol=1e-10)


def test_back_project_outside_mirror_image_is_nan():
    cam = CatadioptricCamera(Pose(), HyperbolicMirror(3.0, 1.0), K_EGT)
    # The rim images on a circle around the principal point; far outside it there is no mirror.
    rim = cam.rim_image(64)
    radius = np.linalg.norm(rim - [320.0, 240.0], axis=1)
    np.testing.assert_allclose(radius, radius[0], rtol=1e-12)
    d = cam.back_project([[320.0 + 1.5 * radius[0], 240.0], [320.0, 240.0]])
    assert np.all(np.isnan(d[0]))
    np.testing.assert_allclose(d[1], [0.0, 0.0, -1.0], atol=1e-12)  # principal point = nadir


def test_rim_image_matches_projection_of_rim():
    rng = np.random.default_rng(3)
    for kind in ("hyperbolic", "parabolic"):
        cam = random_camera(rng, kind)
        rim_world = cam.pose.to_world(cam.mirror.rim_points(32))
        proj = cam.project(rim_world)
        assert proj.visible.all()  # the rim itself is (just) on the mirror
        np.testing.assert_allclose(proj.pixels, cam.rim_image(32), rtol=1e-9)


def test_in_image_flags_and_projection_type():
    cam = CatadioptricCamera(Pose(), ParabolicMirror(1.0), K_EGT, width=640, height=480)
    # Parabolic: m = K (x_h, y_h, 1). Horizontal ray along +x meets the mirror at x_h = h = 1.
    proj = cam.project([[5.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 10.0]])
    assert isinstance(proj, PanoramicProjection)
    np.testing.assert_allclose(proj.pixels[0], [1320.0, 240.0])
    np.testing.assert_allclose(proj.mirror_points[0], [1.0, 0.0, 0.0])
    assert proj.visible.tolist() == [True, True, False]
    assert proj.in_image.tolist() == [False, False, False]  # (1320, 240), (320, 1240) are outside
    K_small = np.array([[100.0, 0.0, 320.0], [0.0, 100.0, 240.0], [0.0, 0.0, 1.0]])
    small = CatadioptricCamera(Pose(), ParabolicMirror(1.0), K_small)
    assert small.project([[5.0, 0.0, 0.0]]).in_image.tolist() == [True]


def test_directions_and_frames():
    mirror = HyperbolicMirror(2.0, 1.0)
    cam = CatadioptricCamera(Pose(rotz(0.7), [1.0, 2.0, 3.0]), mirror)
    np.testing.assert_array_equal(cam.focus_world, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(cam.ccd_center_world, [1.0, 2.0, 3.0 - 2.0 * np.sqrt(5.0)])
    d = np.array([[1.0, 0.5, -0.2]])
    a = cam.project_directions(d)
    b = cam.project(cam.pose.to_world(3.0 * d))
    np.testing.assert_allclose(a.pixels, b.pixels)
    moved = cam.moved(Pose(np.eye(3), [0.0, 0.0, 0.0]))
    assert moved.mirror is cam.mirror and moved.pose.t.tolist() == [0.0, 0.0, 0.0]
    assert cam.pose.t.tolist() == [1.0, 2.0, 3.0]
    np.testing.assert_array_equal(CatadioptricCamera(Pose(), mirror).K, K_EGT)


@pytest.mark.parametrize("mirror", [HyperbolicMirror(3.0, 1.0), ParabolicMirror(0.8, rim_radius=2.0)])
def test_surface_mesh(mirror):
    V, F = mirror.surface(n_radial=8, n_angular=16)
    assert V.shape == (1 + 8 * 16, 3) and F.shape == (16 + 2 * 7 * 16, 3)
    assert F.dtype.kind == "i" and F.min() == 0 and F.max() == len(V) - 1
    assert np.all(np.abs(mirror.implicit(V)) < 1e-9)
    np.testing.assert_allclose(V[0], [0.0, 0.0, mirror.apex_z])
    np.testing.assert_allclose(np.hypot(V[-16:, 0], V[-16:, 1]), mirror.rim_radius)
    # Normals point away from the focus (the reflecting side).
    tri = V[F]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(np.sum(normals * tri.mean(axis=1), axis=1) > 0)
    rim = mirror.rim_points(10)
    assert rim.shape == (10, 3) and np.all(np.abs(mirror.implicit(rim)) < 1e-9)


# --------------------------------------------------------------------------- errors
@pytest.mark.parametrize(
    ("factory", "match"),
    [
        (lambda: HyperbolicMirror(a=0.0), "a:"),
        (lambda: HyperbolicMirror(a=-1.0), "a:"),
        (lambda: HyperbolicMirror(b=0.0), "b:"),
        (lambda: HyperbolicMirror(b=float("nan")), "b:"),
        (lambda: HyperbolicMirror(rim_radius=-2.0), "rim_radius:"),
        (lambda: ParabolicMirror(h=0.0), "h:"),
        (lambda: ParabolicMirror(h=-0.5), "h:"),
        (lambda: CatadioptricCamera(Pose(), HyperbolicMirror(), np.zeros((3, 3))), "K:"),
        (lambda: CatadioptricCamera(Pose(), HyperbolicMirror(), np.eye(2)), "K:"),
        (lambda: CatadioptricCamera(np.eye(4), HyperbolicMirror()), "pose:"),
        (lambda: CatadioptricCamera(Pose(), "hyperbolic"), "mirror:"),
        (lambda: CatadioptricCamera(Pose(), HyperbolicMirror(), width=0), "width:"),
        (lambda: HyperbolicMirror().surface(n_angular=2), "n_angular:"),
    ],
)
def test_bad_construction(factory, match):
    with pytest.raises(GeometryError, match=match):
        factory()


def test_bad_points():
    cam = CatadioptricCamera()
    with pytest.raises(GeometryError, match="X_world: contains NaN"):
        cam.project([[0.0, np.nan, 1.0]])
    with pytest.raises(GeometryError, match=r"X_world: expected shape \(N, 3\)"):
        cam.project(np.zeros((4, 2)))
    with pytest.raises(GeometryError, match="pixels: contains NaN"):
        cam.back_project([[np.nan, 1.0]])
    with pytest.raises(GeometryError, match="directions:"):
        cam.mirror.intersect(np.zeros((2, 4)))
    with pytest.raises(GeometryError, match="d_mirror:"):
        cam.project_directions([[1.0, 2.0, np.inf]])
