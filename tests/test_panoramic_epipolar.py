"""Epipolar geometry of a panoramic pair (EGT reference, sections 5 and 7)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from egtviz.geometry._validate import DegenerateConfigurationError, GeometryError
from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror
from egtviz.geometry.panoramic_epipolar import (
    PanoramicEpipoles,
    biconic,
    conic_from_plane,
    epipolar_conics,
    panoramic_epipoles,
    panoramic_essential,
    sample_epipolar_conics,
    sample_plane_conic,
    sample_plane_conics,
)
from egtviz.geometry.poses import Pose, rotx, roty, rotz

from _mirrors import K_EGT, kinds, random_mirror, seeds  # noqa: E402


def random_rotation(rng: np.random.Generator, tilt: float = 0.3) -> np.ndarray:
    return rotz(rng.uniform(-np.pi, np.pi)) @ rotx(rng.uniform(-tilt, tilt)) @ roty(rng.uniform(-tilt, tilt))


def random_pair(rng: np.random.Generator, kind1: str, kind2: str):
    t1 = rng.uniform(-5, 5, 3)
    u = rng.normal(size=3)
    t2 = t1 + rng.uniform(1.0, 10.0) * u / np.linalg.norm(u)
    cam1 = CatadioptricCamera(Pose(random_rotation(rng), t1), random_mirror(rng, kind1), K_EGT)
    cam2 = CatadioptricCamera(Pose(random_rotation(rng), t2), random_mirror(rng, kind2), K_EGT)
    return cam1, cam2


def scene(rng: np.random.Generator, cam1, cam2, n: int = 300) -> np.ndarray:
    centre = 0.5 * (cam1.pose.t + cam2.pose.t)
    return centre + rng.uniform([-15, -15, -6], [15, 15, 3], size=(n, 3))


def homogeneous(pixels: np.ndarray) -> np.ndarray:
    return np.column_stack([pixels, np.ones(len(pixels))])


def conic_residual(C: np.ndarray, m: np.ndarray) -> np.ndarray:
    """|m^T C m| / (|C|_F |m|^2) for (N, 3, 3) conics and (N, 3) homogeneous points."""
    num = np.abs(np.einsum("ni,nij,nj->n", m, C, m))
    return num / (np.linalg.norm(C, axis=(1, 2)) * np.sum(m * m, axis=1))


def pixel_distance(C: np.ndarray, m: np.ndarray) -> np.ndarray:
    """First-order (Sampson) distance in pixels from points m (N, 3), last coordinate 1, to conics C."""
    num = np.abs(np.einsum("ni,nij,nj->n", m, C, m))
    grad = 2.0 * np.einsum("nij,nj->ni", C, m)[:, :2]
    return num / np.linalg.norm(grad, axis=1)


TOL = 1e-10


# --------------------------------------------------------------------------- properties
@settings(max_examples=50, deadline=None)
@given(seed=seeds, k1=kinds, k2=kinds)
def test_essential_constraint_on_mirror_points(seed, k1, k2):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pair(rng, k1, k2)
    X = scene(rng, cam1, cam2)
    p1, p2 = cam1.project(X), cam2.project(X)
    both = p1.visible & p2.visible
    assume(both.sum() >= 3)
    E = panoramic_essential(cam1, cam2)
    R = cam2.pose.R.T @ cam1.pose.R
    t = cam2.pose.R.T @ (cam1.pose.t - cam2.pose.t)
    np.testing.assert_allclose(E, np.cross(t, R.T).T, atol=1e-12)  # columns t x R[:, j]
    Xh1, Xh2 = p1.mirror_points[both], p2.mirror_points[both]
    r = np.einsum("ni,ij,nj->n", Xh2, E, Xh1)
    scale = np.linalg.norm(Xh1, axis=1) * np.linalg.norm(Xh2, axis=1) * np.linalg.norm(E)
    assert np.all(np.abs(r) <= 1e-12 * scale)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, k1=kinds, k2=kinds)
def test_points_lie_on_their_epipolar_conics(seed, k1, k2):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pair(rng, k1, k2)
    X = scene(rng, cam1, cam2)
    C1, C2 = epipolar_conics(cam1, cam2, X)
    assert C1.shape == C2.shape == (len(X), 3, 3)
    np.testing.assert_allclose(np.linalg.norm(C1, axis=(1, 2)), 1.0)
    np.testing.assert_allclose(C1, np.swapaxes(C1, 1, 2), atol=1e-15)
    for cam, C in ((cam1, C1), (cam2, C2)):
        p = cam.project(X)
        assert p.visible.any()
        m = homogeneous(p.pixels[p.visible])
        assert np.all(conic_residual(C[p.visible], m) < TOL)
        assert np.all(pixel_distance(C[p.visible], m) < 1e-6)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, k1=kinds, k2=kinds)
def test_conics_pass_through_both_epipoles(seed, k1, k2):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pair(rng, k1, k2)
    X = scene(rng, cam1, cam2, 50)
    C1, C2 = epipolar_conics(cam1, cam2, X)
    ep = panoramic_epipoles(cam1, cam2)
    assert isinstance(ep, PanoramicEpipoles)
    for e, C in ((ep.e1, C1), (ep.e1p, C1), (ep.e2, C2), (ep.e2p, C2)):
        assert e.shape == (3,) and e[2] == 1.0
        assert np.all(conic_residual(C, np.broadcast_to(e, (len(C), 3))) < TOL)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, k1=kinds, k2=kinds)
def test_epipoles_are_images_of_the_baseline(seed, k1, k2):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pair(rng, k1, k2)
    ep = panoramic_epipoles(cam1, cam2)
    b = cam2.pose.t - cam1.pose.t
    cases = (
        (cam1, b, ep.e1, ep.e1_visible, ep.e1_mirror),
        (cam1, -b, ep.e1p, ep.e1p_visible, ep.e1p_mirror),
        (cam2, -b, ep.e2, ep.e2_visible, ep.e2_mirror),
        (cam2, b, ep.e2p, ep.e2p_visible, ep.e2p_mirror),
    )
    for cam, direction, e, visible, Xh in cases:
        p = cam.project(cam.pose.t + direction)
        assert visible == bool(p.visible[0])
        if visible:
            np.testing.assert_allclose(e[:2], p.pixels[0], rtol=1e-9)
            np.testing.assert_allclose(Xh, p.mirror_points[0], rtol=1e-9, atol=1e-12)
            d = cam.pose.direction_to_world(Xh)[0]
            np.testing.assert_allclose(d / np.linalg.norm(d), direction / np.linalg.norm(direction), atol=1e-9)
        else:
            assert np.all(np.isnan(Xh))


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_conic_from_plane_contains_visible_images_of_the_plane(seed, kind):
    rng = np.random.default_rng(seed)
    cam = CatadioptricCamera(Pose(random_rotation(rng), rng.uniform(-3, 3, 3)), random_mirror(rng, kind), K_EGT)
    n = rng.normal(size=3)
    u = np.cross(n, rng.normal(size=3))
    v = np.cross(n, u)
    theta = rng.uniform(0, 2 * np.pi, 400)
    d = np.cos(theta)[:, None] * u / np.linalg.norm(u) + np.sin(theta)[:, None] * v / np.linalg.norm(v)
    p = cam.project_directions(d)
    assume(p.visible.any())
    C = conic_from_plane(cam, np.broadcast_to(n, (int(p.visible.sum()), 3)))
    on = conic_residual(C, homogeneous(p.pixels[p.visible]))
    assert np.all(on < TOL)
    # A direction off the plane does not satisfy the conic (the test above is not vacuous).
    off = cam.project_directions(d[p.visible][:1] + 0.2 * n / np.linalg.norm(n))
    if off.visible[0]:
        assert conic_residual(C[:1], homogeneous(off.pixels))[0] > 1e3 * max(on.max(), 1e-18)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_sampled_arcs_are_real_visible_and_on_the_conic(seed, kind):
    rng = np.random.default_rng(seed)
    cam = CatadioptricCamera(Pose(random_rotation(rng), rng.uniform(-3, 3, 3)), random_mirror(rng, kind), K_EGT)
    n = rng.normal(size=3)
    n_samples = 200
    arcs = sample_plane_conic(cam, n, n=n_samples)
    C = conic_from_plane(cam, n)[0]
    # The visible field of a mirror is {elevation below the rim's}: a great circle (elevations
    # between -tilt and +tilt) meets it in one arc, the whole circle, or nothing, wherever the
    # sampling starts: no split, no phantom branch.
    tilt = np.arccos(abs(n[2]) / np.linalg.norm(n))
    rim_el = np.arctan2(cam.mirror.rim_z, cam.mirror.rim_radius)
    if -tilt > rim_el:
        assert arcs == []
        return
    assume(-tilt < rim_el - 0.1 and abs(tilt - rim_el) > 1e-3)  # skip arcs shorter than a few samples
    assert len(arcs) == 1
    arc = arcs[0]
    assert np.array_equal(arc[0], arc[-1]) == bool(tilt < rim_el)  # closed loop iff fully visible
    assert arc.ndim == 2 and arc.shape[1] == 2 and len(arc) >= 2
    m = homogeneous(arc)
    assert np.all(conic_residual(np.broadcast_to(C, (len(m), 3, 3)), m) < TOL)
    d = cam.back_project(arc)  # NaN for any pixel that is not a visible mirror point
    assert np.all(np.isfinite(d))
    d_mirror = d @ cam.pose.R
    np.testing.assert_allclose(d_mirror @ (n / np.linalg.norm(n)), 0.0, atol=1e-9)
    # No jump segment: the samples are evenly spaced on the circle, a closed loop at 2 pi / n,
    # an open arc at most 2 pi / (n - 1) apart.
    step = np.arccos(np.clip(np.sum(d_mirror[1:] * d_mirror[:-1], axis=1), -1, 1))
    closed = np.array_equal(arc[0], arc[-1])
    np.testing.assert_allclose(step, step.mean(), atol=1e-6)
    assert np.all(step <= 2 * np.pi / (n_samples if closed else n_samples - 1) + 1e-6)
    if not closed:
        # Open arcs end where the circle leaves the visible field: on the rim.
        ends = d_mirror[[0, -1]] * cam.mirror.intersect(d_mirror[[0, -1]], rim_tol=1e-9).lam[:, None]
        np.testing.assert_allclose(np.hypot(ends[:, 0], ends[:, 1]), cam.mirror.rim_radius, rtol=1e-6)


def test_hyperbolic_arc_excludes_phantom_branch_and_wraps():
    """A near-vertical plane crosses the blind cone: one arc from rim to rim, even when sampling starts mid-arc."""
    cam = CatadioptricCamera(Pose(), HyperbolicMirror(3.0, 1.0), K_EGT)
    for normal in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.3], [-0.2, 1.0, 0.0], [0.3, -1.0, 0.2]):
        arcs = sample_plane_conic(cam, normal, n=512)
        assert len(arcs) == 1
        arc = arcs[0]
        assert not np.allclose(arc[0], arc[-1])  # an open arc, not a closed loop
        # Its ends are on the rim's image (the arc is clipped there, not at a phantom branch),
        # and every other sample is inside it.
        rim_r = np.linalg.norm(cam.rim_image(4)[0] - [320.0, 240.0])
        radius = np.linalg.norm(arc - [320.0, 240.0], axis=1)
        np.testing.assert_allclose(radius[[0, -1]], rim_r, rtol=1e-9)
        assert np.all(radius <= rim_r * (1 + 1e-12))
        # The algebraic conic also holds the phantom branch: unified images of in-plane rays
        # beyond the asymptote satisfy m^T C m = 0, yet no sampled pixel comes near them.
        # (Checked for tilted planes; a plane through the axis images as a line pair whose
        # phantom part folds back onto the real segment through the image centre.)
        if normal[2] == 0.0:
            continue
        C = conic_from_plane(cam, normal)
        n_unit = np.asarray(normal) / np.linalg.norm(normal)
        horizontal = np.cross(n_unit, [0.0, 0.0, 1.0])
        up = np.cross(horizontal, n_unit)
        up = up / np.linalg.norm(up) * np.sign(up[2])
        horizontal /= np.linalg.norm(horizontal)
        max_el = np.arcsin(up[2])
        asym = np.arcsin(cam.mirror.a / cam.mirror.e)
        assert max_el > asym
        for el in np.linspace(asym, max_el, 7)[1:]:
            # A unit in-plane direction with elevation el: cos(phi) horizontal + sin(phi) up.
            phi = np.arcsin(np.sin(el) / up[2])
            d = np.cos(phi) * horizontal + np.sin(phi) * up
            assert not cam.project_directions(d).visible[0]
            q = cam._unified_homogeneous(d[None, :])[0]
            phantom = q[:2] / q[2]
            assert conic_residual(C, homogeneous(phantom[None, :]))[0] < TOL
            assert np.min(np.linalg.norm(arc - phantom, axis=1)) > 1.0
    # A horizontal plane is fully visible: one closed loop.
    loop = sample_plane_conic(cam, [0.0, 0.0, 1.0], n=64)
    assert len(loop) == 1 and loop[0].shape == (65, 2)
    np.testing.assert_array_equal(loop[0][0], loop[0][-1])


@settings(max_examples=50, deadline=None)
@given(seed=seeds, k1=kinds, k2=kinds)
def test_sample_epipolar_conics_contain_the_point(seed, k1, k2):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pair(rng, k1, k2)
    X = scene(rng, cam1, cam2, 20)
    arcs1, arcs2 = sample_epipolar_conics(cam1, cam2, X, n=128)
    C1, C2 = epipolar_conics(cam1, cam2, X)
    assert len(arcs1) == len(arcs2) == len(X)
    for arcs, C in ((arcs1, C1), (arcs2, C2)):
        for i, polylines in enumerate(arcs):
            for poly in polylines:
                m = homogeneous(poly)
                assert np.all(conic_residual(np.broadcast_to(C[i], (len(m), 3, 3)), m) < TOL)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, k1=kinds, k2=kinds)
def test_world_frame_invariance_of_conics(seed, k1, k2):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pair(rng, k1, k2)
    X = scene(rng, cam1, cam2, 30)
    G = Rotation.random(random_state=rng).as_matrix()
    g = rng.uniform(-20, 20, 3)

    def move(cam):
        return cam.moved(Pose(G @ cam.pose.R, G @ cam.pose.t + g))

    C1, C2 = epipolar_conics(cam1, cam2, X)
    D1, D2 = epipolar_conics(move(cam1), move(cam2), X @ G.T + g)
    for C, D in ((C1, D1), (C2, D2)):
        sign = np.sign(np.einsum("nij,nij->n", C, D))[:, None, None]  # conics are defined up to sign
        np.testing.assert_allclose(sign * D, C, atol=1e-8)
    np.testing.assert_allclose(panoramic_essential(move(cam1), move(cam2)), panoramic_essential(cam1, cam2), atol=1e-9)


@settings(max_examples=50, deadline=None)
@given(seed=seeds, kind=kinds)
def test_biconic_contains_current_and_desired(seed, kind):
    rng = np.random.default_rng(seed)
    cam = CatadioptricCamera(Pose(random_rotation(rng)), random_mirror(rng, kind), K_EGT)
    top = np.arctan2(cam.mirror.rim_z, cam.mirror.rim_radius) - 1e-3

    def dirs():
        el = rng.uniform(-1.2, top, 20)
        az = rng.uniform(-np.pi, np.pi, 20)
        return np.column_stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])

    dc, dd = dirs(), dirs()
    C = biconic(cam, dc, dd)
    for d in (dc, dd):
        p = cam.project_directions(d)
        assert p.visible.all()
        assert np.all(conic_residual(C, homogeneous(p.pixels)) < TOL)


# --------------------------------------------------------------------------- degenerate cases
def test_points_on_the_baseline_give_nan_conics():
    cam1 = CatadioptricCamera(Pose(rotz(np.pi / 4), [-10.0, -10.0, 0.0]), HyperbolicMirror(), K_EGT)
    cam2 = CatadioptricCamera(Pose(np.eye(3), [0.0, 0.0, 0.0]), ParabolicMirror(), K_EGT)
    X = np.array([[5.0, 5.0, 0.0], [-10.0, -10.0, 0.0], [0.0, 10.0, 1.0]])  # on the baseline, focus 1, regular
    C1, C2 = epipolar_conics(cam1, cam2, X)
    assert np.all(np.isnan(C1[:2])) and np.all(np.isnan(C2[:2]))
    assert np.all(np.isfinite(C1[2])) and np.all(np.isfinite(C2[2]))
    arcs1, arcs2 = sample_epipolar_conics(cam1, cam2, X)
    assert arcs1[0] == [] and arcs2[1] == [] and len(arcs1[2]) >= 1
    parallel = biconic(cam1, [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    assert np.all(np.isnan(parallel[0])) and np.all(np.isfinite(parallel[1]))


def test_egt_example4_like_configuration():
    """Two upright mirrors as in EGT Example 3/4: eight points, all conics through the epipoles."""
    cam1 = CatadioptricCamera(Pose(rotz(np.pi / 4), [-10.0, -10.0, 0.0]), HyperbolicMirror(), K_EGT)
    cam2 = CatadioptricCamera(Pose(np.eye(3), [0.0, 0.0, 0.0]), HyperbolicMirror(), K_EGT)
    X = np.array(
        [[0, 10, 10], [-10, 5, 5], [5, -5, -2], [-5, 5, -3], [3, 3, 1], [-8, 2, -1], [2, -9, 0.5], [-3, -2, -4]],
        dtype=float,
    )
    ep = panoramic_epipoles(cam1, cam2)
    # Level mirrors and a horizontal baseline: all four epipoles are seen on the mirrors.
    assert ep.e1_visible and ep.e1p_visible and ep.e2_visible and ep.e2p_visible
    # e1 and e1p are symmetric about the principal point (opposite horizontal rays).
    np.testing.assert_allclose(ep.e1[:2] + ep.e1p[:2], [640.0, 480.0], atol=1e-9)
    C1, C2 = epipolar_conics(cam1, cam2, X)
    p1, p2 = cam1.project(X), cam2.project(X)
    for cam, C, p, e, ep_ in ((cam1, C1, p1, ep.e1, ep.e1p), (cam2, C2, p2, ep.e2, ep.e2p)):
        assert conic_residual(C[p.visible], homogeneous(p.pixels[p.visible])).max() < TOL
        assert conic_residual(C, np.broadcast_to(e, (8, 3))).max() < TOL
        assert conic_residual(C, np.broadcast_to(ep_, (8, 3))).max() < TOL


def test_sample_plane_conics_matches_single_plane_version():
    rng = np.random.default_rng(7)
    for mirror in (HyperbolicMirror(2.0, 1.0), ParabolicMirror(0.6)):
        cam = CatadioptricCamera(Pose(rotz(0.4)), mirror, K_EGT)
        normals = np.vstack([rng.normal(size=(6, 3)), np.zeros((1, 3))])
        many = sample_plane_conics(cam, normals, n=96)
        assert len(many) == 7 and many[-1] == []
        for normal, arcs in zip(normals[:-1], many[:-1], strict=True):
            single = sample_plane_conic(cam, normal, n=96)
            assert len(single) == len(arcs)
            for a, b in zip(single, arcs, strict=True):
                np.testing.assert_allclose(a, b, rtol=1e-12)


def test_epipoles_on_the_mirror_axis():
    """Baseline along both axes: the nadir images at the principal point; the zenith is blind."""
    K = K_EGT
    hyp = CatadioptricCamera(Pose(np.eye(3), [0.0, 0.0, 0.0]), HyperbolicMirror(), K)
    par = CatadioptricCamera(Pose(np.eye(3), [0.0, 0.0, 5.0]), ParabolicMirror(), K)
    ep = panoramic_epipoles(hyp, par)
    # Image 1 (hyperbolic, other focus straight up): e1 is the phantom image of the zenith,
    # the principal point too (s_z + xi = xi - 1 != 0), not visible; e1p is the nadir.
    np.testing.assert_allclose(ep.e1, [320.0, 240.0, 1.0])
    np.testing.assert_allclose(ep.e1p, [320.0, 240.0, 1.0])
    assert not ep.e1_visible and ep.e1p_visible
    # Image 2 (parabolic, other focus straight down): e2 is the nadir; the zenith is the
    # projection centre of the stereographic model, so e2p is undefined (NaN).
    np.testing.assert_allclose(ep.e2, [320.0, 240.0, 1.0])
    assert ep.e2_visible and not ep.e2p_visible
    assert np.all(np.isnan(ep.e2p)) and np.all(np.isnan(ep.e2p_mirror))
    np.testing.assert_allclose(ep.e1p_mirror, [0.0, 0.0, HyperbolicMirror().apex_z], atol=1e-12)


def test_epipole_at_infinity_is_unit_norm():
    """A hyperbola whose baseline ray has d_z = xi images it at infinity: last coordinate 0."""
    mirror = HyperbolicMirror(3.0, 1.0)
    el = np.arcsin(mirror.xi)
    cam1 = CatadioptricCamera(Pose(), mirror, K_EGT)
    cam2 = CatadioptricCamera(Pose(np.eye(3), 10.0 * np.array([np.cos(el), 0.0, np.sin(el)])), mirror, K_EGT)
    ep = panoramic_epipoles(cam1, cam2)
    assert ep.e1[2] == 0.0 and np.linalg.norm(ep.e1) == pytest.approx(1.0)
    np.testing.assert_allclose(np.abs(ep.e1), [1.0, 0.0, 0.0], atol=1e-6)
    assert not ep.e1_visible


# --------------------------------------------------------------------------- errors
def test_coincident_foci_raise():
    cam1 = CatadioptricCamera(Pose(rotz(0.3), [1.0, 2.0, 3.0]))
    cam2 = CatadioptricCamera(Pose(np.eye(3), [1.0, 2.0, 3.0]), ParabolicMirror())
    for call in (
        lambda: panoramic_essential(cam1, cam2),
        lambda: panoramic_epipoles(cam1, cam2),
        lambda: epipolar_conics(cam1, cam2, [[0.0, 5.0, 0.0]]),
        lambda: sample_epipolar_conics(cam1, cam2, [[0.0, 5.0, 0.0]]),
    ):
        with pytest.raises(DegenerateConfigurationError, match="the centres coincide"):
            call()
    assert issubclass(DegenerateConfigurationError, GeometryError)


def test_bad_arguments():
    cam1 = CatadioptricCamera(Pose(np.eye(3), [0.0, 0.0, 0.0]))
    cam2 = CatadioptricCamera(Pose(np.eye(3), [5.0, 0.0, 0.0]))
    with pytest.raises(GeometryError, match="X_world: contains NaN"):
        epipolar_conics(cam1, cam2, [[np.nan, 0.0, 0.0]])
    with pytest.raises(GeometryError, match="n_mirror: a zero normal"):
        sample_plane_conic(cam1, [0.0, 0.0, 0.0])
    with pytest.raises(GeometryError, match="n: expected a whole number at least 3"):
        sample_plane_conic(cam1, [0.0, 0.0, 1.0], n=2)
    with pytest.raises(GeometryError, match=r"n_mirror: expected shape \(N, 3\)"):
        conic_from_plane(cam1, np.ones((2, 2)))
    with pytest.raises(GeometryError, match="d_desired:"):
        biconic(cam1, np.ones((2, 3)), np.ones((3, 3)))
    with pytest.raises(GeometryError, match="cam2: expected a CatadioptricCamera"):
        panoramic_essential(cam1, "camera 2")


def test_sampled_biconics_pass_through_both_features():
    from egtviz.geometry.panoramic_epipolar import sample_biconics

    rng = np.random.default_rng(11)
    cam = CatadioptricCamera(Pose(), HyperbolicMirror(3.0, 1.0), K_EGT)
    d_cur = np.column_stack([rng.normal(size=(6, 2)), rng.uniform(-1.0, 0.5, 6)])
    d_des = np.column_stack([rng.normal(size=(6, 2)), rng.uniform(-1.0, 0.5, 6)])
    d_des[0] = 2.0 * d_cur[0]  # parallel rays: no plane, no arc
    arcs = sample_biconics(cam, d_cur, d_des, n=400)
    assert arcs[0] == []
    m_cur = cam.project_directions(d_cur).pixels
    m_des = cam.project_directions(d_des).pixels
    for i in range(1, 6):
        pts = np.concatenate(arcs[i])
        for m in (m_cur[i], m_des[i]):
            if np.all(np.isfinite(m)):
                assert np.min(np.linalg.norm(pts - m, axis=1)) < 2.0  # within a sample step of the arc
