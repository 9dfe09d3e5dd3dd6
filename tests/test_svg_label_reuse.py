"""A panel's point numbers placed once for its points serve while its epipoles stay out of their reach.

The drag path places the epipole labels first and reuses the numbers placed without them when no epipole mark or
label comes within any number's reach (``svg._clear_of_numbers``); otherwise it places the numbers after the epipole
labels (``place_labels(..., placed=...)``). Either way the SVG must be the one the single placement of every label
gives: the tests compare it with the route that never reuses.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.scene import SceneModel, compute_derived, default_scene, panoramic_scene
from egtviz.viewer.render import svg
from egtviz.viewer.render.panel_view import place_labels


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, 12), split=st.integers(0, 12), seed=st.integers(0, 2**32 - 1))
def test_labels_placed_after_earlier_ones_are_one_placement(n, split, seed):
    rng = np.random.default_rng(seed)
    split = min(split, n)
    anchors = rng.uniform(0, 100, (n, 2))
    radii = rng.uniform(1, 4, n)
    sizes = rng.uniform(4, 20, (n, 2))
    centres = rng.uniform(0, 100, (15, 2))
    obstacles = np.column_stack([centres - 3, centres + 3])
    bounds = (0.0, 0.0, 100.0, 100.0)
    whole = place_labels(anchors, radii, sizes, obstacles, bounds, gap=2.0)
    first = place_labels(anchors[:split], radii[:split], sizes[:split], obstacles, bounds, gap=2.0)
    rest = place_labels(anchors[split:], radii[split:], sizes[split:], obstacles, bounds, gap=2.0, placed=first)
    assert np.array_equal(np.concatenate([first.reshape(-1, 4), rest.reshape(-1, 4)]), whole)


def _drag_planes(scene, n_points: int, seed: int, steps: int):
    """The image planes of a drag of the first camera (each step a new place), on a scene with random points."""
    model = SceneModel(scene)
    X = model.scene.points_array()
    model.randomize_points(n_points, seed=seed, center=tuple(X.mean(axis=0)), extent=2.0)
    spec = model.scene.cameras[0]
    pose = spec.camera().pose
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        position = np.asarray(pose.t, float) + rng.normal(0.0, 0.15, 3)
        model.set_camera_pose(spec.name, tuple(position), pose.R)
        out.extend(compute_derived(model.scene).image_planes.values())
    return out


@pytest.mark.parametrize(("make", "n_points", "reused"), [(default_scene, 3, True), (default_scene, 8, True),
                                                          (default_scene, 30, False), (default_scene, 200, True),
                                                          (panoramic_scene, 8, False)])
def test_reused_numbers_give_the_svg_of_one_placement(monkeypatch, make, n_points, reused):
    planes = _drag_planes(make(), n_points, seed=n_points, steps=12)
    verdicts = []
    clear = svg._clear_of_numbers

    def spy(plan, boxes):
        verdicts.append(clear(plan, boxes))
        return verdicts[-1]

    monkeypatch.setattr(svg, "_clear_of_numbers", spy)
    kinds = [dict(), dict(selected_point=1), dict(selected_point=0, highlighted={2}), dict(style=svg.PRESENT)]
    drawn = [svg.image_plane_svg(p, revision=1, **kw) for p in planes for kw in kinds]
    monkeypatch.setattr(svg, "_clear_of_numbers", lambda plan, boxes: False)
    for cache in (svg._point_marks, svg._number_plan, svg._point_group):
        cache.cache_clear()
    fresh = [svg.image_plane_svg(p, revision=1, **kw) for p in planes for kw in kinds]
    assert drawn == fresh
    # Both routes were taken where the seeds make them occur (a crowd of numbers is never clear).
    assert any(verdicts) == reused and not all(verdicts)


def test_epipoles_in_reach_are_not_clear():
    planes = _drag_planes(default_scene(), 8, seed=1, steps=1)
    plane = planes[0]
    P = np.ascontiguousarray(np.asarray(plane.points, float).reshape(-1, 2))
    in_image = np.ascontiguousarray(np.asarray(plane.in_image, bool))
    plan = svg._number_plan(P.tobytes(), in_image.tobytes(), in_image.tobytes(), None, frozenset(), True,
                            svg.NORMAL, 1.0)
    assert len(plan.numbered) == int(in_image.sum()) > 0
    x0, y0, x1, y1 = plan.reach[0]
    assert not svg._clear_of_numbers(plan, np.array([[x1 - 1.0, y1 - 1.0, x1 + 5.0, y1 + 5.0]]))
    assert not svg._clear_of_numbers(plan, np.array([[x1, y0, x1 + 5.0, y0 + 5.0]]))  # touching is near
    assert svg._clear_of_numbers(plan, np.array([[1e6, 1e6, 1e6 + 1.0, 1e6 + 1.0]]))
    assert not svg._clear_of_numbers(plan, np.array([[np.nan, 0.0, 1.0, 1.0]]))  # NaN: never clear


# -- the numpy forms of the placement's inner loops give the loops' answers -------------------------------------


@settings(max_examples=200, deadline=None)
@given(m=st.integers(41, 300), seed=st.integers(0, 2**32 - 1), grid=st.booleans())
def test_many_boxes_are_costed_as_by_the_loop(m, seed, grid):
    from egtviz.viewer.render import panel_view

    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 60, (m, 2))
    if grid:  # touching boxes and exact ties between candidates
        centres = np.round(centres / 4.0) * 4.0
    half = rng.uniform(0.5, 4.0, (m, 1)) if not grid else np.full((m, 1), 2.0)
    boxes = np.column_stack([centres - half, centres + half]).tolist()
    ax, ay = (float(v) for v in rng.uniform(10, 50, 2))
    reach, w, h = float(rng.uniform(1, 5)), float(rng.uniform(2, 12)), float(rng.uniform(2, 8))
    bounds = (0.0, 0.0, 60.0, float(rng.choice([45.0, 60.0])))
    fast = panel_view._best_box(ax, ay, reach, w, h, boxes, bounds)
    many = panel_view._MANY_BOXES
    panel_view._MANY_BOXES = 10**9  # the loop, whatever the number of boxes
    try:
        assert panel_view._best_box(ax, ay, reach, w, h, boxes, bounds) == fast
    finally:
        panel_view._MANY_BOXES = many


def _fates_by_label(boxes, n_first, anchors, reach, obstacles, shown):
    """number_fates as it was written first: each number in turn, numpy over the points for its leader test."""
    import math

    keep, far = [], []
    B = boxes[n_first:]
    tiny = 1e-6 * (B[:, 2] - B[:, 0]) * (B[:, 3] - B[:, 1])
    drawn = [tuple(b) for b in boxes[:n_first].tolist()]
    for j, (x0, y0, x1, y1), t in zip(range(n_first, len(boxes)), B.tolist(), tiny.tolist()):
        hit = any((w := min(x1, o[2]) - max(x0, o[0])) > 0 and (h := min(y1, o[3]) - max(y0, o[1])) > 0
                  and w * h > t for o in list(map(tuple, obstacles.tolist())) + drawn)
        keep.append(not hit)
        if hit:
            far.append(False)
            continue
        drawn.append((x0, y0, x1, y1))
        ax, ay = anchors[j].tolist()
        own = math.hypot(max(x0 - ax, 0.0, ax - x1), max(y0 - ay, 0.0, ay - y1))
        dx = np.maximum(np.maximum(x0 - shown[:, 0], shown[:, 0] - x1), 0.0)
        dy = np.maximum(np.maximum(y0 - shown[:, 1], shown[:, 1] - y1), 0.0)
        d = np.hypot(dx, dy)
        others = d[(shown[:, 0] != ax) | (shown[:, 1] != ay)]
        far.append(own > svg.NUMBER_NEAR * float(reach[j])
                   or bool(len(others)) and float(others.min()) < svg.NUMBER_CLEAR * own)
    return keep, far


@settings(max_examples=300, deadline=None)
@given(n=st.integers(0, 12), n_first=st.integers(0, 2), m=st.integers(0, 15), seed=st.integers(0, 2**32 - 1))
def test_number_fates_are_decided_as_one_number_at_a_time(n, n_first, m, seed):
    rng = np.random.default_rng(seed)
    anchors = np.round(rng.uniform(0, 40, (n_first + n, 2)), 1)
    shown = np.concatenate([anchors[n_first:], np.round(rng.uniform(0, 40, (3, 2)), 1)])
    corner = anchors + np.round(rng.uniform(-6, 6, anchors.shape), 1)
    boxes = np.column_stack([corner, corner + np.round(rng.uniform(1, 8, anchors.shape), 1)])
    oc = np.round(rng.uniform(0, 40, (m, 2)), 1)
    obstacles = np.column_stack([oc - 1.5, oc + 1.5]).reshape(-1, 4)
    reach = rng.uniform(1, 4, n_first + n)
    assert svg.number_fates(boxes, n_first, anchors, reach, obstacles, shown) == _fates_by_label(
        boxes, n_first, anchors, reach, obstacles, shown)


@settings(max_examples=300, deadline=None)
@given(box=st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=4, max_size=4),
       size=st.floats(0.1, 100.0), mark_x=st.floats(-1e6, 1e6))
def test_a_label_is_written_with_the_panels_number_format(box, size, mark_x):
    x0, y0, x1, y1 = box
    got = svg.label_text(box, size, "7", ' fill="#000"', mark_x)
    x = x1 if x1 <= mark_x else x0 if x0 >= mark_x else (x0 + x1) / 2
    n = svg.svg_number
    assert f'x="{n(x)}" y="{n(y1 - 0.17 * size)}" ' in got
    assert f'data-box="{n(x0)} {n(y0)} {n(x1)} {n(y1)}" fill="#000">7</text>' in got
