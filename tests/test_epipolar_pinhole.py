"""Epipolar geometry of pin-hole pairs: the identities of H&Z chapter 9 over random configurations."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import DegenerateConfigurationError, GeometryError, Intrinsics, PinholeCamera, Pose
from egtviz.geometry.epipolar import (
    epipolar_constraint,
    epipolar_lines,
    epipolar_lines_in_first,
    epipolar_pair,
    epipolar_planes,
    epipoles_from_fundamental,
    lines_of_planes,
)
from egtviz.geometry.homogeneous import clip_lines_to_rect, normalize_lines
from egtviz.geometry.poses import look_at, matrix_from_quat_wxyz

seeds = st.integers(0, 2**32 - 1)


def random_pair(rng):
    """Two cameras at random positions looking near a cloud around the origin, random intrinsics."""
    cams = []
    for _ in range(2):
        eye = rng.normal(size=3)
        eye = 6 * eye / np.linalg.norm(eye)
        pose = look_at(eye, rng.normal(scale=0.5, size=3), up=rng.normal(size=3))
        intr = Intrinsics(rng.uniform(0.004, 0.02), tuple(rng.uniform(5e4, 2e5, 2)), tuple(rng.uniform(200, 400, 2)), rng.uniform(-2, 2))
        cams.append(PinholeCamera(pose, intr))
    X = rng.normal(scale=1.0, size=(30, 3))
    return cams[0], cams[1], X


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@settings(max_examples=60, deadline=None)
@given(seeds)
def test_epipolar_identities(seed):
    rng = np.random.default_rng(seed)
    c1, c2, X = random_pair(rng)
    ep = epipolar_pair(c1, c2)
    m1, m2 = c1.project(X).pixels, c2.project(X).pixels
    F = ep.F
    # Rank 2, unit norm.
    s = np.linalg.svd(F, compute_uv=False)
    assert s[2] < 1e-12 * s[0] and abs(np.linalg.norm(F) - 1) < 1e-12
    # m2^T F m1 = 0, measured as a distance in pixels to the epipolar line.
    d = np.abs(np.einsum("ni,ni->n", normalize_lines(epipolar_lines(F, m1)), np.column_stack([m2, np.ones(len(m2))])))
    assert d.max() < 1e-6
    # Epipoles span the null spaces.
    assert np.linalg.norm(F @ ep.e1) < 1e-9 * np.linalg.norm(ep.e1)
    assert np.linalg.norm(F.T @ ep.e2) < 1e-9 * np.linalg.norm(ep.e2)
    # Every epipolar line passes through its image's epipole.
    l2 = normalize_lines(epipolar_lines(F, m1))
    l1 = normalize_lines(epipolar_lines_in_first(F, m2))
    for lines, e in ((l1, ep.e1), (l2, ep.e2)):
        e_dir = e / np.linalg.norm(e)
        assert np.abs(lines @ e_dir).max() < 1e-8 * max(1.0, np.abs(e[:2]).max())
    # Epipoles from the SVD of F agree with the images of the centres.
    e1s, e2s = epipoles_from_fundamental(F)
    assert abs(abs(unit(e1s) @ unit(ep.e1)) - 1) < 1e-9
    assert abs(abs(unit(e2s) @ unit(ep.e2)) - 1) < 1e-9


@settings(max_examples=40, deadline=None)
@given(seeds)
def test_invariant_to_a_change_of_world_frame(seed):
    rng = np.random.default_rng(seed)
    c1, c2, X = random_pair(rng)
    g = Pose(matrix_from_quat_wxyz(rng.normal(size=4)), rng.normal(scale=5, size=3))
    moved = [c.moved(g.compose(c.pose)) for c in (c1, c2)]
    Xg = g.to_world(X)
    for a, b in zip((c1, c2), moved):
        np.testing.assert_allclose(a.project(X).pixels, b.project(Xg).pixels, atol=1e-7)
    np.testing.assert_allclose(epipolar_pair(c1, c2).F, epipolar_pair(*moved).F, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(seeds)
def test_lines_of_epipolar_planes_equal_F_lines(seed):
    rng = np.random.default_rng(seed)
    c1, c2, X = random_pair(rng)
    F = epipolar_pair(c1, c2).F
    planes = epipolar_planes(c1.center, c2.center, X)
    # Every epipolar plane contains both centres and its point.
    for P in (c1.center, c2.center):
        assert np.abs(planes[:, :3] @ P + planes[:, 3]).max() < 1e-9
    assert np.abs(np.einsum("ni,ni->n", planes[:, :3], X) + planes[:, 3]).max() < 1e-9
    l2_plane = normalize_lines(lines_of_planes(c2, planes[:, :3]))
    l2_F = normalize_lines(epipolar_lines(F, c1.project(X).pixels))
    cos = np.abs(np.einsum("ni,ni->n", unit(l2_plane), unit(l2_F)))
    assert np.all(cos > 1 - 1e-9)


def test_epipole_at_infinity_is_handled_without_division():
    # Baseline along camera x: both epipoles at infinity, F still rank 2 and lines parallel.
    K = Intrinsics()
    c1 = PinholeCamera(look_at([0, 0, 0], [0, 10, 0]), K)
    c2 = PinholeCamera(look_at([1, 0, 0], [1, 10, 0]), K)
    ep = epipolar_pair(c1, c2)
    assert ep.e1_at_infinity and ep.e2_at_infinity
    assert ep.e1[2] == 0.0 and abs(np.linalg.norm(ep.e1) - 1) < 1e-12
    lines = normalize_lines(epipolar_lines(ep.F, [[100, 100], [300, 400]]))
    np.testing.assert_allclose(np.abs(lines[:, :2]), [[0, 1], [0, 1]], atol=1e-12)  # horizontal lines


def test_coincident_centres_have_no_epipolar_geometry():
    c1 = PinholeCamera(look_at([1, 2, 3], [0, 10, 0]))
    c2 = PinholeCamera(look_at([1, 2, 3], [5, 10, 0]))
    with pytest.raises(DegenerateConfigurationError, match="centres coincide"):
        epipolar_pair(c1, c2)


def test_clip_lines_to_rect():
    segs, hit = clip_lines_to_rect([[1, 1, -100], [0, 1, -50], [1, 0, -700], [1, -1, 0], [0, 0, 1]], 640, 480)
    assert hit.tolist() == [True, True, False, True, False]
    np.testing.assert_allclose(np.sort(segs[0], axis=0), [[0, 0], [100, 100]])
    np.testing.assert_allclose(np.sort(segs[1], axis=0), [[0, 50], [640, 50]])
    np.testing.assert_allclose(np.sort(segs[3], axis=0), [[0, 0], [480, 480]])
    assert np.isnan(segs[2]).all() and np.isnan(segs[4]).all()


def test_bad_input():
    with pytest.raises(GeometryError, match=r"F: expected shape \(3, 3\)"):
        epipolar_lines(np.eye(4), [[1, 2]])
    with pytest.raises(GeometryError, match="m2: expected as many points as m1"):
        epipolar_constraint(np.eye(3), [[1, 2]], [[1, 2], [3, 4]])
    with pytest.raises(GeometryError, match="m1: contains NaN"):
        epipolar_lines(np.eye(3), [[np.nan, 2]])
