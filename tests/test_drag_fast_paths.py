"""The drag path's fast paths give exactly what the checked or straightforward code gives.

- ``clip_lines_to_rect(..., check=False)`` (validated-once lines) against the checked call;
- ``compute_derived``'s clipped epipolar lines against the checked call on the core's lines;
- ``place_labels`` (column-filtered candidates, obstacles listed once) against the straightforward greedy
  search it replaced, kept here as the reference.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry.epipolar_curves import epipolar_curves
from egtviz.geometry.homogeneous import clip_lines_to_rect
from egtviz.scene import compute_derived, default_scene
from egtviz.scene.derived import CONIC_SAMPLES, CONIC_VERTEX_BUDGET
from egtviz.viewer.render.panel_view import place_labels

seeds = st.integers(min_value=0, max_value=2**32 - 1)

# --------------------------------------------------------------------------- clipping


@settings(max_examples=80)
@given(seed=seeds, size=st.sampled_from([(640, 480), (1, 1), (100, 3000), (5e9, 2e9), (7, 1e4)]))
def test_unchecked_clip_is_the_checked_clip(seed, size):
    rng = np.random.default_rng(seed)
    w, h = size
    special = np.array([[1, 1, -min(w, h)], [0, 1, 0], [0, 1, -h], [1, 0, 0], [1, 0, -w], [1, -1, 0], [1, 1, 0],
                        [0, 0, 1], [1e-13, 0, 1], [1e-11, 1e-12, -1], [1, 1e-17, -w / 2], [1e-17, 1, -h / 2]],
                       float)
    lines = np.vstack([special, rng.normal(size=(50, 3)) * [1, 1, max(w, h)],
                       rng.normal(size=(10, 3)) * rng.choice([1e-12, 1, 1e6], size=(10, 3))])
    rng.shuffle(lines)
    seg, hit = clip_lines_to_rect(lines, w, h)
    fast_seg, fast_hit = clip_lines_to_rect(lines, w, h, check=False)
    np.testing.assert_array_equal(fast_hit, hit)
    np.testing.assert_array_equal(fast_seg, seg)  # bit for bit, NaN rows included
    assert fast_seg.shape == (len(lines), 2, 2) and fast_hit.dtype == bool


@settings(max_examples=40)
@given(seed=seeds)
def test_unchecked_clip_gives_nan_rows_for_rows_the_checked_call_refuses(seed):
    rng = np.random.default_rng(seed)
    good = rng.normal(size=(12, 3)) * [1, 1, 500]
    bad = np.array([[0.0, 0.0, 0.0], [np.nan, 1.0, 2.0], [np.inf, 1.0, 0.0], [1.0, -np.inf, 3.0]])
    order = rng.permutation(len(good) + len(bad))
    lines = np.vstack([good, bad])[order]
    is_bad = order >= len(good)
    seg, hit = clip_lines_to_rect(lines, 640, 480, check=False)
    assert np.isnan(seg[is_bad]).all() and not hit[is_bad].any()
    ref_seg, ref_hit = clip_lines_to_rect(lines[~is_bad], 640, 480)  # the checked call takes the valid rows
    np.testing.assert_array_equal(seg[~is_bad], ref_seg)
    np.testing.assert_array_equal(hit[~is_bad], ref_hit)


def test_checked_clip_still_refuses_what_it_refused():
    from egtviz.geometry import GeometryError

    with pytest.raises(GeometryError, match="lines"):
        clip_lines_to_rect([[0.0, 0.0, 0.0]], 640, 480)
    with pytest.raises(GeometryError, match="width"):
        clip_lines_to_rect([[1.0, 0.0, -3.0]], -1, 480)


@settings(max_examples=20)
@given(seed=seeds, n_points=st.sampled_from([1, 8, 200]))
def test_derived_lines_are_the_checked_clip_of_the_cores_lines(seed, n_points):
    rng = np.random.default_rng(seed)
    scene = default_scene()
    X = rng.normal(size=(n_points, 3)) * 2 + scene.points_array().mean(axis=0)
    c0 = scene.cameras[0]
    c0 = c0.with_pose(position=tuple(np.array(c0.position) + rng.normal(0, 0.5, 3)))
    X[0] = c0.camera().centre  # a point on the baseline: no epipolar plane, no line
    scene = scene.replace(cameras=(c0,) + scene.cameras[1:], points=tuple(map(tuple, X)))
    d = compute_derived(scene)
    cams = [s.camera() for s in scene.cameras]
    lo, hi = CONIC_SAMPLES
    n_samples = min(max(CONIC_VERTEX_BUDGET // n_points, lo), hi)
    curves = epipolar_curves(cams[0], cams[1], scene.points_array(), n_samples=n_samples, conics=False, arcs=False)
    for cam, side in zip(cams, (curves.first, curves.second)):
        plane = d.image_planes[[s.name for s in scene.cameras][cams.index(cam)]]
        ok = np.isfinite(side.lines).all(axis=1) & (side.lines != 0).any(axis=1)
        assert not ok[0]  # the baseline point
        expected = np.full((n_points, 2, 2), np.nan)
        if ok.any():
            expected[ok] = clip_lines_to_rect(side.lines[ok], plane.width, plane.height)[0]
        np.testing.assert_array_equal(plane.lines, expected)


# --------------------------------------------------------------------------- label placement

_DIRECTIONS = ((1, -1), (1, 0), (1, 1), (-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1))
_RINGS = (1.0, 2.0, 3.5)


def reference_place_labels(anchors, radii, sizes, obstacles, bounds, gap):
    """The greedy search written out: every candidate costed against every obstacle and earlier label."""
    A = np.asarray(anchors, float).reshape(-1, 2)
    R = np.asarray(radii, float).reshape(-1)
    S = np.asarray(sizes, float).reshape(-1, 2)
    O = np.asarray(obstacles, float).reshape(-1, 4).tolist()
    bx0, by0, bx1, by1 = (float(b) for b in bounds)
    placed = []
    for (ax, ay), r, (w, h) in zip(A.tolist(), R.tolist(), S.tolist()):
        area = w * h
        tiny = 1e-6 * area
        best, best_cost = None, math.inf
        for ring in _RINGS:
            d = (r + gap) * ring
            for dx, dy in _DIRECTIONS:
                x0 = ax + d if dx > 0 else ax - d - w if dx < 0 else ax - w / 2
                y0 = ay + d if dy > 0 else ay - d - h if dy < 0 else ay - h / 2
                x1, y1 = x0 + w, y0 + h
                iw = min(x1, bx1) - max(x0, bx0)
                ih = min(y1, by1) - max(y0, by0)
                c = area - max(iw, 0.0) * max(ih, 0.0)
                for o in O + placed:  # obstacles, then earlier labels, in order
                    ow = min(x1, o[2]) - max(x0, o[0])
                    oh = min(y1, o[3]) - max(y0, o[1])
                    if ow > 0 and oh > 0:
                        c += ow * oh
                if c <= tiny:
                    c = 0.0
                if c < best_cost:
                    best, best_cost = [x0, y0, x1, y1], c
        placed.append(best)
    return np.array(placed).reshape(-1, 4)


@settings(max_examples=150, deadline=None)
@given(seed=seeds, n_labels=st.integers(1, 5), n_obstacles=st.sampled_from([0, 3, 40, 250]),
       spread=st.sampled_from([30.0, 150.0, 600.0]))
def test_place_labels_is_the_straightforward_greedy_search(seed, n_labels, n_obstacles, spread):
    rng = np.random.default_rng(seed)
    centre = np.array([320.0, 240.0])
    pts = centre + rng.normal(0, spread, (n_obstacles, 2))
    half = rng.uniform(2, 15, (n_obstacles, 1))
    obstacles = np.hstack([pts - half, pts + half])
    # Labels on marks among the obstacles (crowded), some on the same anchor, one maybe at the edge.
    anchors = pts[rng.integers(0, n_obstacles, n_labels)] if n_obstacles else centre + rng.normal(0, 50, (n_labels, 2))
    if n_labels > 1:
        anchors[1] = anchors[0]
    anchors[-1] = rng.choice([anchors[-1], [0.0, 0.0], [640.0, 10.0]])
    radii = rng.uniform(1, 20, n_labels)
    sizes = np.column_stack([rng.uniform(8, 300, n_labels), rng.uniform(8, 40, n_labels)])
    bounds = (0.0, 0.0, 640.0, 480.0)
    gap = float(rng.uniform(0.5, 10))
    got = place_labels(anchors, radii, sizes, obstacles, bounds, gap)
    ref = reference_place_labels(anchors, radii, sizes, obstacles, bounds, gap)
    np.testing.assert_array_equal(got, ref)


def test_place_labels_in_a_crowd_takes_the_first_free_box_further_out():
    # A 3 x 3 block of 10 px marks 12 px apart around the anchor: rings 1 and 2 (the label 8 px from the anchor,
    # then 16 px) all overlap a mark; at 3.5 x 8 = 28 px, upper right, the box (28, -38, 48, -28) is free.
    grid = [(12.0 * i, 12.0 * j) for i in (-1, 0, 1) for j in (-1, 0, 1)]
    obstacles = [(x - 5, y - 5, x + 5, y + 5) for x, y in grid]
    boxes = place_labels([[0.0, 0.0]], [5.0], [[20.0, 10.0]], obstacles, (-100, -100, 100, 100), gap=3.0)
    np.testing.assert_array_equal(boxes, [[28.0, -38.0, 48.0, -28.0]])


# --------------------------------------------------------------------------- conic tags (cached per drag)


def test_cached_conic_tags_follow_the_selection_and_the_style():
    import xml.etree.ElementTree as ET

    from egtviz.scene import panoramic_scene
    from egtviz.viewer.render.svg import NORMAL, PRESENT, image_plane_svg

    scene = panoramic_scene()
    plane = compute_derived(scene).image_planes[scene.drawn_pair[0]]
    n = len(plane.conics)
    assert n >= 4
    for style, sel in ((NORMAL, 0), (NORMAL, 3), (PRESENT, 3), (NORMAL, 0), (NORMAL, None)):
        root = ET.fromstring(image_plane_svg(plane, selected_point=sel, style=style))
        conics = [e for e in root.iter("{http://www.w3.org/2000/svg}polyline")
                  if e.get("data-kind") == "epipolar-conic"]
        assert sorted({int(e.get("data-index")) for e in conics}) == [i for i in range(n) if plane.conics[i]]
        thick = {int(e.get("data-index")) for e in conics if e.get("stroke-width") is not None}
        assert thick == (set() if sel is None else {sel})
        colours = style.point_colours
        assert all(e.get("stroke") == colours[int(e.get("data-index")) % len(colours)] for e in conics)
