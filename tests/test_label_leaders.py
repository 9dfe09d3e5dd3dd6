"""Point numbers in crowded panels stay with their points (the ``data-kind`` contract of :mod:`egtviz.viewer.render.svg`).

A drawn number's box is within ``NUMBER_NEAR`` times (its mark's radius plus the placement gap) of its point,
and no other point stands nearly as close to it; otherwise a ``label-leader`` line in the point's group ends at the
point's centre; a number that found no free place is not drawn and the ``crowded-note`` counts it.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from egtviz.scene import SCENES, ImagePlane
from egtviz.viewer.render.figure_export import panel_svg
from egtviz.viewer.render.svg import NORMAL, NUMBER_CLEAR, NUMBER_NEAR, PRESENT, image_plane_svg


def _box_distance(box: tuple[float, ...], x: float, y: float) -> float:
    x0, y0, x1, y1 = box
    return math.hypot(max(x0 - x, 0.0, x - x1), max(y0 - y, 0.0, y - y1))


def check_numbers(svg: str, style=NORMAL) -> tuple[int, int, int]:
    """Assert the rule on every point group; return (numbers drawn, leaders, numbers not drawn)."""
    root = ET.fromstring(svg)
    groups = [g for g in root.iter() if g.get("data-kind") in ("point", "point-outside") and g.tag.endswith("g")]
    discs = [c for c in root.iter() if c.tag.endswith("circle") and c.get("data-kind") in (None, "point",
                                                                                         "point-outside")]
    centres = np.array([[float(c.get("cx")), float(c.get("cy"))] for c in discs if c.get("r")
                        and c.get("fill") != "none"])
    drawn = leaders = 0
    for g in groups:
        texts = [t for t in g if t.tag.endswith("text")]
        if not texts:
            continue
        drawn += 1
        disc = [c for c in g if c.tag.endswith("circle") and c.get("fill") != "none"][0]
        x, y, r = float(disc.get("cx")), float(disc.get("cy")), float(disc.get("r"))
        box = tuple(float(v) for v in texts[0].get("data-box").split())
        lines = [el for el in g if el.get("data-kind") == "label-leader"]
        if lines:
            leaders += 1
            line = lines[0]
            assert line.get("data-index") == g.get("data-index")
            assert (float(line.get("x2")), float(line.get("y2"))) == pytest.approx((x, y), abs=0.01)
            # ... and starts on its number's box.
            assert _box_distance(box, float(line.get("x1")), float(line.get("y1"))) < 0.01
            continue
        own = _box_distance(box, x, y)
        # The mark's radius (a ringed point's ring is twice the disc) plus the gap, 0.3 * the label size.
        gap = 0.3 * style.label_px * r / style.mark_px
        ringed = any(c.get("fill") == "none" for c in g if c.tag.endswith("circle"))
        reach = (2.0 * r if ringed else r) + gap
        assert own <= NUMBER_NEAR * reach + 1e-6, (g.get("data-index"), own, reach)
        others = [_box_distance(box, cx, cy) for cx, cy in centres if (cx, cy) != (x, y)]
        assert not others or min(others) >= NUMBER_CLEAR * own - 0.05, (g.get("data-index"), own, min(others))
    notes = [el for el in root.iter() if el.get("data-kind") == "crowded-note"]
    hidden = int(notes[0].get("data-unnumbered")) if notes else 0
    return drawn, leaders, hidden


@pytest.mark.parametrize("present", [False, True])
def test_example4_pano1_numbers_stay_with_their_points(present):
    svg = panel_svg(SCENES["example4"](), "pano1", present=present)
    drawn, leaders, hidden = check_numbers(svg, PRESENT if present else NORMAL)
    assert drawn + hidden == 8
    # The crowd of eight points near the epipole cannot all be numbered next to their discs.
    assert leaders >= 1


def crowded_plane(seed: int, n: int) -> ImagePlane:
    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.normal([320, 240], 25, (n // 2, 2)), rng.uniform([0, 0], [640, 480], (n - n // 2, 2))])
    return ImagePlane(camera="crowd", width=640, height=480, points=pts, visible=np.ones(n, bool),
                      in_image=np.ones(n, bool), n_hidden=0)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("style", [NORMAL, PRESENT])
def test_a_crowded_random_panel_has_no_free_floating_number(seed, style):
    n = 40
    svg = image_plane_svg(crowded_plane(seed, n), style=style, selected_point=3, fixed_size=True)
    drawn, leaders, hidden = check_numbers(svg, style)
    assert drawn + hidden == n
    assert drawn > n // 2


def test_numbers_with_no_free_place_are_counted_in_a_note():
    # 40 points inside a 30 px square: most numbers have nowhere to go.
    rng = np.random.default_rng(3)
    pts = rng.uniform([300, 220], [330, 250], (40, 2))
    plane = ImagePlane(camera="heap", width=640, height=480, points=pts, visible=np.ones(40, bool),
                       in_image=np.ones(40, bool), n_hidden=0)
    svg = image_plane_svg(plane, fixed_size=True)
    drawn, _, hidden = check_numbers(svg)
    assert hidden > 0 and drawn + hidden == 40
    note = [el for el in ET.fromstring(svg).iter() if el.get("data-kind") == "crowded-note"][0]
    assert note.text.startswith(f"{hidden} point numbers not shown")
    # The note has its own row, under the frame, inside the SVG.
    root = ET.fromstring(svg)
    vb = [float(v) for v in root.get("viewBox").split()]
    assert float(note.get("y")) < vb[1] + vb[3]
    assert float(note.get("y")) > 480


def test_servo_feature_numbers_stay_with_their_features():
    from egtviz.viewer.render.servo_svg import ServoImage, servo_image_svg

    rng = np.random.default_rng(7)
    n = 12
    current = rng.normal([320, 240], 30, (n, 2))  # a crowd, as near the end of a run
    img = ServoImage(demo="pinhole", width=640, height=480, frame=0, current=current,
                     desired=current + rng.normal(0, 8, (n, 2)), trails=np.zeros((0, n, 2)))
    root = ET.fromstring(servo_image_svg(img, fixed_size=True))
    els = list(root.iter())
    leaders = {el.get("data-index"): el for el in els if el.get("data-kind") == "label-leader"}
    discs = {el.get("data-index"): el for el in els if el.get("data-kind") == "point"}
    texts = [el for el in els if el.tag.endswith("text") and el.get("data-box") and el.text and el.text.isdigit()]
    assert len(texts) == n
    r = float(next(iter(discs.values())).get("r"))
    reach = r + 0.3 * NORMAL.label_px * r / NORMAL.mark_px
    for t in texts:
        i = str(int(t.text) - 1)
        x, y = float(discs[i].get("cx")), float(discs[i].get("cy"))
        box = tuple(float(v) for v in t.get("data-box").split())
        if i in leaders:
            assert (float(leaders[i].get("x2")), float(leaders[i].get("y2"))) == pytest.approx((x, y), abs=0.01)
        else:
            assert _box_distance(box, x, y) <= NUMBER_NEAR * reach + 1e-6
    assert leaders  # the crowd needs some
