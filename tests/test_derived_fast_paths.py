"""The internal fast paths of the core agree with the public, checked functions and with the straightforward
formulas they replace (kept here as references); ``compute_derived`` (which uses only the core's public API, the
camera-model interface) gives what the public functions give.
"""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import PinholeCamera, Pose
from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry._shared import epipolar_normals_columns as _epipolar_normals
from egtviz.geometry._shared import matrix_rank3 as _matrix_rank3
from egtviz.geometry.epipolar import epipolar_pair, epipolar_planes, epipole_of_centre, lines_of_planes
from egtviz.geometry.homogeneous import _clip_lines, clip_lines_to_rect, normalize_homogeneous
from egtviz.geometry.panoramic_epipolar import _sample_circles, sample_plane_conics
from egtviz.geometry.unified_sphere import great_circle_arcs
from egtviz.geometry.pinhole import Intrinsics
from egtviz.geometry.poses import look_at
from egtviz.scene import PanoramicSpec, PinholeSpec, Scene, compute_derived, default_scene, panoramic_scene
from egtviz.scene.derived import COINCIDENT_MESSAGE
from egtviz.scene.io import scene_from_dict

from _mirrors import K_EGT, kinds, random_mirror, seeds  # noqa: E402


def random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def random_pinhole(rng) -> PinholeCamera:
    f = rng.uniform(0.004, 0.02)
    intr = Intrinsics(f, tuple(rng.uniform(5e4, 2e5, 2)), tuple(rng.uniform(100, 500, 2)), rng.uniform(-2, 2),
                      int(rng.integers(200, 1000)), int(rng.integers(200, 800)))
    return PinholeCamera(Pose(random_rotation(rng), rng.normal(size=3) * 3), intr)


# --------------------------------------------------------------------------- references (the replaced code)


def reference_normalize_lines(lines):
    """``normalize_lines`` without its checks: NaN rows for NaN, zero and at-infinity lines."""
    lines = np.atleast_2d(np.asarray(lines, dtype=np.float64))
    n = np.hypot(lines[:, 0], lines[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        out = lines / n[:, None]
        out[~(n > 1e-12 * np.linalg.norm(lines, axis=1))] = np.nan
    return out


def reference_clip(lines, width, height):
    """``clip_lines_to_rect`` as it was: (N, 4) candidates, argmin/argmax, ``np.clip``."""
    L = reference_normalize_lines(lines)
    a, b, c = L[:, 0:1], L[:, 1:2], L[:, 2:3]
    eps = 1e-9 * max(width, height, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        xs = np.array([0.0, width])[None, :]
        v_at_x = -(a * xs + c) / b
        ys = np.array([0.0, height])[None, :]
        u_at_y = -(b * ys + c) / a
    cand_u = np.concatenate([np.broadcast_to(xs, v_at_x.shape), u_at_y], axis=1)
    cand_v = np.concatenate([v_at_x, np.broadcast_to(ys, u_at_y.shape)], axis=1)
    ok = (np.isfinite(cand_u) & np.isfinite(cand_v) & (cand_u >= -eps) & (cand_u <= width + eps)
          & (cand_v >= -eps) & (cand_v <= height + eps))
    s = np.where(ok, cand_u * -b + cand_v * a, np.nan)
    i_lo = np.argmin(np.where(ok, s, np.inf), axis=1)
    i_hi = np.argmax(np.where(ok, s, -np.inf), axis=1)
    rows = np.arange(len(L))
    seg = np.stack([np.column_stack([cand_u[rows, i_lo], cand_v[rows, i_lo]]),
                    np.column_stack([cand_u[rows, i_hi], cand_v[rows, i_hi]])], axis=1)
    with np.errstate(invalid="ignore"):
        hit = ok.any(axis=1) & (np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1) > eps)
    seg[~hit] = np.nan
    return np.clip(seg, [0.0, 0.0], [width, height]), hit


def reference_sample_circles(camera, normals, n):
    """``_sample_circles`` as it was: every sample projected by the checked ``project_directions``."""
    norm = np.linalg.norm(normals, axis=1)
    good = np.flatnonzero(np.isfinite(norm) & (norm > 0))
    out = [[] for _ in range(len(normals))]
    if len(good) == 0:
        return out
    nn = normals[good] / norm[good, None]
    helper = np.where(np.abs(nn[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(nn, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(nn, u)
    m = camera.mirror
    c_rim = m.rim_z / np.hypot(m.rim_radius, m.rim_z)
    A = np.hypot(u[:, 2], v[:, 2])
    theta0 = np.arctan2(v[:, 2], u[:, 2])
    full = A <= c_rim
    some = ~full & (c_rim > -A)
    with np.errstate(divide="ignore", invalid="ignore"):
        half_blind = np.arccos(np.clip(c_rim / np.where(A > 0, A, 1.0), -1.0, 1.0))
    start = np.where(full, 0.0, theta0 + half_blind + 1e-13)
    span = np.where(full, 2.0 * np.pi * (n - 1) / n, 2.0 * (np.pi - half_blind - 1e-13))
    for k in np.flatnonzero(full | some):
        theta = start[k] + span[k] * np.linspace(0.0, 1.0, n)
        d = np.cos(theta)[:, None] * u[k] + np.sin(theta)[:, None] * v[k]
        px = camera.project_directions(d).pixels
        out[good[k]] = [np.vstack([px, px[:1]]) if full[k] else px]
    return out


def assert_same_arcs(arcs, ref, rtol=1e-10):
    assert len(arcs) == len(ref)
    for a, r in zip(arcs, ref):
        assert len(a) == len(r)
        for p, q in zip(a, r):
            assert p.shape == q.shape
            np.testing.assert_allclose(p, q, rtol=0, atol=rtol * max(1.0, np.nanmax(np.abs(q))))


# --------------------------------------------------------------------------- lines


@settings(max_examples=60)
@given(seed=seeds, size=st.sampled_from([(640, 480), (1, 1), (100, 3000), (5e9, 2e9)]))
def test_clip_matches_the_reference_on_random_and_special_lines(seed, size):
    rng = np.random.default_rng(seed)
    w, h = size
    special = [[1, 1, -min(w, h)], [0, 1, 0], [0, 1, -h], [1, 0, 0], [1, 0, -w], [1, -1, 0], [1, 1, 0],
               [0, 0, 1], [0, 0, 0], [1e-13, 0, 1], [1e-11, 1e-12, -1], [1, 1e-17, -w / 2], [1e-17, 1, -h / 2],
               [np.nan, 1, 2]]
    lines = np.vstack([special, rng.normal(size=(60, 3)) * [1, 1, max(w, h)],
                       rng.normal(size=(10, 3)) * rng.choice([1e-12, 1, 1e6], size=(10, 3))])
    # The public function refuses the zero line and the NaN row; the internal one takes them.
    public = np.delete(lines, [special.index([0, 0, 0]), len(special) - 1], axis=0)
    assert np.isfinite(public).all() and (np.abs(public).max(axis=1) > 0).all()
    seg, hit = clip_lines_to_rect(public, w, h)
    ref_seg, ref_hit = reference_clip(public, w, h)
    np.testing.assert_array_equal(hit, ref_hit)
    np.testing.assert_allclose(seg, ref_seg, rtol=0, atol=1e-12 * max(w, h), equal_nan=True)
    assert seg.shape == (len(public), 2, 2) and seg.flags.c_contiguous
    # The internal entry point takes the lines coordinate-major and not normalised (any moderate scale).
    ref_seg, ref_hit = reference_clip(lines, w, h)
    scaled = lines * rng.uniform(1e-3, 1e3, size=(len(lines), 1))
    seg2, hit2 = _clip_lines(np.ascontiguousarray(scaled.T), float(w), float(h))
    np.testing.assert_array_equal(hit2, ref_hit)
    np.testing.assert_allclose(seg2, ref_seg, rtol=0, atol=1e-12 * max(w, h), equal_nan=True)


def test_clip_of_no_lines():
    seg, hit = clip_lines_to_rect(np.zeros((0, 3)), 640, 480)
    assert seg.shape == (0, 2, 2) and hit.shape == (0,)


@settings(max_examples=60)
@given(seed=seeds)
def test_epipolar_normals_match_the_cross_product_and_nan_the_baseline(seed):
    rng = np.random.default_rng(seed)
    c1, c2 = rng.normal(size=3) * 3, rng.normal(size=3) * 3
    X = rng.normal(size=(30, 3)) * 5
    X[0] = c1
    X[1] = c1 + rng.uniform(-2, 3) * (c2 - c1)  # on the baseline
    n = np.cross(c2 - c1, X - c1)
    with np.errstate(invalid="ignore"):
        ref = n / np.linalg.norm(n, axis=1, keepdims=True)
    ref[:2] = np.nan
    normals_T = _epipolar_normals(c1, c2, np.ascontiguousarray(X.T))
    np.testing.assert_allclose(normals_T.T, ref, atol=1e-12, equal_nan=True)
    planes = epipolar_planes(c1, c2, X)
    np.testing.assert_allclose(planes[:, :3], ref, atol=1e-12, equal_nan=True)
    np.testing.assert_allclose(planes[2:, 3], -ref[2:] @ c1, atol=1e-11 * (1 + np.abs(c1).max()))


@settings(max_examples=60)
@given(seed=seeds)
def test_epipolar_pair_matches_the_textbook_formulas(seed):
    rng = np.random.default_rng(seed)
    cam1, cam2 = random_pinhole(rng), random_pinhole(rng)
    ep = epipolar_pair(cam1, cam2)
    R1, R2, t1, t2 = cam1.pose.R, cam2.pose.R, cam1.center, cam2.center
    R, t = R2.T @ R1, R2.T @ (t1 - t2)
    tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])

    def canonical(M):
        M = M / np.linalg.norm(M)
        return M if M.flat[np.argmax(np.abs(M))] >= 0 else -M

    E = canonical(tx @ R)
    F = canonical(np.linalg.inv(cam2.K).T @ E @ np.linalg.inv(cam1.K))
    np.testing.assert_allclose(ep.E, E, atol=1e-12)
    np.testing.assert_allclose(ep.F, F, atol=1e-12)
    for e, in_front, cam, other in ((ep.e1, ep.e1_in_front, cam1, t2), (ep.e2, ep.e2_in_front, cam2, t1)):
        raw = cam.K @ cam.pose.R.T @ (other - cam.center)
        np.testing.assert_allclose(e, normalize_homogeneous(raw), atol=1e-12 * max(1.0, np.abs(e).max()))
        assert in_front == (raw[2] > 0)
        public, public_front = epipole_of_centre(cam, other)
        np.testing.assert_array_equal(public, e)
        assert public_front == in_front
    assert ep.e1_at_infinity == (ep.e1[2] == 0.0) and ep.e2_at_infinity == (ep.e2[2] == 0.0)
    assert _matrix_rank3(ep.F, 1e-9) == np.linalg.matrix_rank(ep.F, tol=1e-9) == 2


def test_epipoles_behind_both_cameras():
    # (Epipoles at infinity: tests/test_epipolar_pinhole.py.)
    intr = Intrinsics()
    c1 = PinholeCamera(look_at([0, 0, 0], [0, 10, 0]), intr)
    c3 = PinholeCamera(look_at([0, -5, 0], [0, -10, 0]), intr)  # looks away from c1
    ep = epipolar_pair(c1, c3)
    assert not ep.e1_in_front and not ep.e2_in_front


@settings(max_examples=100)
@given(seed=seeds, tol=st.sampled_from([1e-12, 1e-9, 1e-3]), scale=st.sampled_from([1e-6, 1.0, 1e6]))
def test_matrix_rank3_matches_numpy(seed, tol, scale):
    rng = np.random.default_rng(seed)
    for _ in range(20):
        s = np.sort(10.0 ** rng.uniform(-20, 1, 3))[::-1] * scale
        s[rng.random(3) < 0.2] = 0.0
        s[rng.random(3) < 0.3] = tol * 10.0 ** rng.uniform(-0.7, 0.7)  # near the threshold: the SVD must decide
        M = random_rotation(rng) @ np.diag(np.sort(s)[::-1]) @ random_rotation(rng)
        if rng.random() < 0.3:
            M = np.diag(10.0 ** rng.uniform(-3, 3, 3)) @ M
        assert _matrix_rank3(M, tol) == np.linalg.matrix_rank(M, tol=tol)
    assert _matrix_rank3(np.zeros((3, 3)), 1e-9) == 0
    assert _matrix_rank3(np.eye(3), 1e-9) == 3


@settings(max_examples=40)
@given(seed=seeds)
def test_lines_of_planes_match_the_solve(seed):
    rng = np.random.default_rng(seed)
    cam = random_pinhole(rng)
    n = rng.normal(size=(20, 3))
    # A normal is defined up to scale: the public function divides each by its largest entry first.
    n_unit_max = n / np.abs(n).max(axis=1, keepdims=True)
    ref = np.linalg.solve(cam.K.T, cam.pose.R.T @ n_unit_max.T).T
    np.testing.assert_allclose(lines_of_planes(cam, n), ref, rtol=1e-10, atol=1e-14 * np.abs(ref).max())


# --------------------------------------------------------------------------- panoramic


def random_catadioptric(rng, kind) -> CatadioptricCamera:
    K = K_EGT.copy()
    K[0, 1] = rng.choice([0.0, 2.0])
    return CatadioptricCamera(Pose(random_rotation(rng), rng.normal(size=3)), random_mirror(rng, kind), K)


@settings(max_examples=60)
@given(seed=seeds, kind=kinds, n=st.sampled_from([3, 7, 24, 96]))
def test_conic_arcs_match_the_projected_samples(seed, kind, n):
    rng = np.random.default_rng(seed)
    cam = random_catadioptric(rng, kind)
    normals = rng.normal(size=(40, 3)) * rng.choice([1e-3, 1.0, 50.0], size=(40, 1))
    normals[:4] = [[0, 0, 1], [1, 0, 0], [0.95, 0.2, 0.1], [0, 0, 0]]
    normals[4] = np.nan
    ref = reference_sample_circles(cam, normals, n)
    arcs = great_circle_arcs(np.ascontiguousarray(normals.T), n, cam.mirror.rim_cosine, cam._unit_ray_pixels)
    assert_same_arcs(arcs, ref)
    assert all(isinstance(a, tuple) for a in arcs)
    assert_same_arcs(_sample_circles(cam, normals, n), ref)
    finite = normals[5:]
    assert_same_arcs(sample_plane_conics(cam, finite, n), ref[5:])


@settings(max_examples=60)
@given(seed=seeds, kind=kinds)
def test_scalar_and_unit_ray_projections_match_project_directions(seed, kind):
    rng = np.random.default_rng(seed)
    cam = random_catadioptric(rng, kind)
    d = rng.normal(size=(200, 3))
    proj = cam.project_directions(d)
    for di, px, vis in zip(d.tolist(), proj.pixels, proj.visible):
        got = cam._direction_pixel(*di)
        assert (got is not None) == vis
        if vis:
            np.testing.assert_allclose(got, px, rtol=0, atol=1e-12 * max(1.0, np.abs(px).max()))
    unit = d[proj.visible] / np.linalg.norm(d[proj.visible], axis=1, keepdims=True)
    u, v = np.empty(len(unit)), np.empty(len(unit))
    cam._unit_ray_pixels(unit[:, 0], unit[:, 1], unit[:, 2], u, v)
    ref = cam.project_directions(unit).pixels
    np.testing.assert_allclose(np.column_stack([u, v]), ref, rtol=0, atol=1e-10 * max(1.0, np.abs(ref).max()))


# --------------------------------------------------------------------------- the whole update


def moved(scene: Scene, rng, scale=1.0) -> Scene:
    c0 = scene.cameras[0]
    c0 = dataclasses.replace(c0, position=tuple(np.array(c0.position) + rng.normal(0, scale, 3)),
                             ypr_deg=tuple(np.array(c0.ypr_deg) + rng.normal(0, 30, 3)))
    return scene.replace(cameras=(c0,) + scene.cameras[1:])


def check_against_public_functions(scene: Scene) -> None:
    """Every array of ``compute_derived`` recomputed with the public, checked functions."""
    d = compute_derived(scene)
    X = scene.points_array()
    cams = {s.name: s.camera() for s in scene.cameras}
    n1, n2 = scene.drawn_pair
    c1, c2 = cams[n1], cams[n2]
    planes = epipolar_planes(c1.pose.t, c2.pose.t, X)
    normals = planes[:, :3]
    for name, cam in cams.items():
        ip = d.image_planes[name]
        other = c2.pose.t if name == n1 else c1.pose.t
        if isinstance(cam, PinholeCamera):
            proj = cam.project(X)
            np.testing.assert_allclose(ip.points, proj.pixels, equal_nan=True)
            np.testing.assert_array_equal(ip.visible, proj.in_front)
            ray = np.full((len(X), 2, 3), np.nan)
            ray[proj.in_front, 0] = X[proj.in_front]
            ray[proj.in_front, 1] = cam.pose.t
            np.testing.assert_array_equal(d.rays[name], ray)
            assert ip.rim is None and ip.horizon == ()  # the image rectangle; the horizon is at infinity
            if name in (n1, n2):
                seg, hit = clip_lines_to_rect(lines_of_planes(cam, normals), ip.width, ip.height)
                np.testing.assert_allclose(ip.lines, seg, atol=1e-9, equal_nan=True)
                (e,) = ip.epipoles
                raw = epipole_of_centre(cam, other)[0]
                if raw[2] == 0:
                    np.testing.assert_allclose(e.direction, raw[:2] / np.linalg.norm(raw[:2]), atol=1e-12)
                else:
                    np.testing.assert_allclose(e.xy, raw[:2] / raw[2], rtol=1e-12)
            else:
                assert ip.lines is None and ip.conics is None
        else:
            proj = cam.project(X)
            np.testing.assert_allclose(ip.points, proj.pixels, equal_nan=True)
            rim = cam.rim_image(128)
            np.testing.assert_allclose(ip.rim, np.vstack([rim, rim[:1]]))
            ray = np.full((len(X), 3, 3), np.nan)
            ray[proj.visible, 0] = X[proj.visible]
            ray[proj.visible, 1] = cam.pose.to_world(proj.mirror_points[proj.visible])
            ray[proj.visible, 2] = cam.ccd_center_world
            np.testing.assert_allclose(d.rays[name], ray, atol=1e-12, equal_nan=True)
            if name in (n1, n2):
                dirs = cam.pose.R.T @ (other - cam.pose.t)
                ref = cam.project_directions(np.stack([dirs, -dirs]))
                assert [e.label[-1] == "'" for e in ip.epipoles] == [k == 1 for k in np.flatnonzero(ref.visible)]
                for e, px in zip(ip.epipoles, ref.pixels[ref.visible]):
                    np.testing.assert_allclose(e.xy, px, rtol=1e-12)
                lo, hi = 24, 96
                n_samples = int(np.clip(4800 // max(len(X), 1), lo, hi))
                good = np.isfinite(normals).all(axis=1)
                expected = [[] for _ in range(len(X))]
                for k, arcs in zip(np.flatnonzero(good), sample_plane_conics(cam, normals[good] @ cam.pose.R,
                                                                           n_samples)):
                    expected[k] = arcs
                assert_same_arcs(ip.conics, expected, rtol=1e-9)
    if all(isinstance(c, PinholeCamera) for c in (c1, c2)):
        ep = epipolar_pair(c1, c2)
        # F = K2^-T E K1^-1 from the poses' E: the pair's F up to scale (both of unit norm, same sign).
        np.testing.assert_allclose(d.pair.F * np.sign(np.vdot(d.pair.F, ep.F)), ep.F / np.linalg.norm(ep.F),
                                   atol=1e-12)
        assert d.pair.rank == np.linalg.matrix_rank(ep.F, tol=1e-9) == 2
    else:
        assert d.pair.F is None and d.pair.rank is None and d.pair.E is not None


@settings(max_examples=25)
@given(seed=seeds, factory=st.sampled_from([default_scene, panoramic_scene]), n_points=st.sampled_from([1, 8, 60]))
def test_compute_derived_matches_the_public_functions(seed, factory, n_points):
    rng = np.random.default_rng(seed)
    scene = factory()
    X = rng.normal(size=(n_points, 3)) * 2 + scene.points_array().mean(axis=0)
    scene = moved(scene.replace(points=tuple(map(tuple, X)), selected_point=0), rng)
    check_against_public_functions(scene)


def test_compute_derived_mixed_pair_and_parabolic():
    pin, pan = default_scene(), panoramic_scene()
    spec = dataclasses.replace(pan.cameras[0], name="pano")
    for cams in ((pin.cameras[0], spec), (spec, pin.cameras[1]),
                 tuple(dataclasses.replace(c, mirror="parabolic", a=1.0) for c in pan.cameras)):
        check_against_public_functions(Scene(cameras=cams, points=pin.points))


def test_a_drag_gives_what_a_fresh_computation_gives():
    """The caches (points by identity, per-camera blocks, per-camera matrices) never go stale."""
    rng = np.random.default_rng(4)
    for factory in (default_scene, panoramic_scene):
        scene = factory()
        for _ in range(6):
            scene = moved(scene, rng, 0.3)
            a = compute_derived(scene)
            fresh = scene_from_dict(scene.to_dict())  # new points tuple, new specs and cameras
            b = compute_derived(fresh)
            for name in a.image_planes:
                pa, pb = a.image_planes[name], b.image_planes[name]
                np.testing.assert_array_equal(pa.points, pb.points)
                for x, y in ((pa.lines, pb.lines), (a.rays[name], b.rays[name])):
                    if x is not None:
                        np.testing.assert_allclose(x, y, atol=1e-12, equal_nan=True)
            scene = scene.replace(points=tuple((x + 0.1, y, z) for x, y, z in scene.points))
            check_against_public_functions(scene)


def test_coincident_centres_give_the_message_with_or_without_points():
    for factory in (default_scene, panoramic_scene):
        scene = factory()
        c0, c1 = scene.cameras[:2]
        for points in (scene.points, ()):
            s = scene.replace(cameras=(dataclasses.replace(c0, position=c1.position), c1) + scene.cameras[2:],
                              points=points, selected_point=None)
            d = compute_derived(s)
            assert d.pair.message == COINCIDENT_MESSAGE and d.baseline is None
            for name in (c0.name, c1.name):
                assert d.image_planes[name].message == COINCIDENT_MESSAGE and d.image_planes[name].in_pair


def test_points_on_the_baseline_have_no_epipolar_curve():
    for factory in (default_scene, panoramic_scene):
        scene = factory()
        c0, c1 = scene.cameras[:2]
        mid = tuple((np.array(c0.position) + np.array(c1.position)) / 2)
        s = scene.replace(points=(mid,) + scene.points[1:], selected_point=0)
        d = compute_derived(s)  # the panoramic pair used to raise here (NaN normal)
        assert d.epipolar_plane is None
        for name in (c0.name, c1.name):
            ip = d.image_planes[name]
            if ip.lines is not None:
                assert np.isnan(ip.lines[0]).all() and np.isfinite(ip.lines[1:]).any()
            else:
                assert ip.conics[0] == () and all(len(a) == 1 for a in ip.conics[1:])


@pytest.mark.parametrize("spec", [PinholeSpec("p", (0.0, -5.0, 1.0)), PanoramicSpec("q", (0.0, 0.0, 1.0))])
def test_one_camera_has_no_pair(spec):
    d = compute_derived(Scene(cameras=(spec,), points=default_scene().points))
    assert d.pair.names is None and d.baseline is None
    assert d.image_planes[spec.name].lines is None and d.image_planes[spec.name].conics is None
