"""The image-plane SVG builder: a pure function, tested on hand-made ImagePlanes."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from egtviz.scene import Epipole, ImagePlane, compute_derived, default_scene
from egtviz.viewer.render.svg import MAX_NUMBERED_POINTS, image_plane_svg

NS = "{http://www.w3.org/2000/svg}"


def kinds(svg: str, kind: str) -> list[ET.Element]:
    root = ET.fromstring(svg)
    return [el for el in root.iter() if el.get("data-kind") == kind]


def plane(**kw) -> ImagePlane:
    pts = np.array([[100.0, 100.0], [320.0, 240.0], [700.0, 100.0], [np.nan, np.nan]])
    base = dict(
        camera="cam A",
        width=640,
        height=480,
        points=pts,
        visible=np.array([True, True, True, False]),
        in_image=np.array([True, True, False, False]),
        n_hidden=1,
    )
    base.update(kw)
    return ImagePlane(**base)


def test_root_carries_the_contract_attributes():
    svg = image_plane_svg(plane(), revision=7)
    root = ET.fromstring(svg)
    assert root.tag == NS + "svg"
    assert root.get("data-egtviz") == "image-plane"
    assert root.get("data-camera") == "cam A"
    assert root.get("data-rev") == "7"
    # viewBox in pixel units: the image plus a margin on each side.
    x, y, w, h = map(float, root.get("viewBox").split())
    assert x < 0 and y < 0 and w > 640 and h > 480
    assert len(kinds(svg, "border")) == 1


def test_points_only_inside_the_image_with_index_and_count():
    svg = image_plane_svg(plane())
    pts = kinds(svg, "point")
    assert [p.get("data-index") for p in pts] == ["0", "1"]
    status = kinds(svg, "hidden-count")[0]
    assert status.get("data-hidden") == "1"
    text = " ".join(status.itertext())  # the status wraps onto lines (tspans) when the panel is narrow
    assert "1 hidden (behind the camera)" in text
    assert "1 outside the image" in text


def test_point_labels_are_one_based_and_optional():
    svg = image_plane_svg(plane())
    labels = [t.text for p in kinds(svg, "point") for t in p.iter(NS + "text")]
    assert labels == ["1", "2"]
    svg = image_plane_svg(plane(), show_labels=False)
    assert not [t for p in kinds(svg, "point") for t in p.iter(NS + "text")]


def test_many_points_are_numbered_only_when_selected():
    rng = np.random.default_rng(1)
    n = MAX_NUMBERED_POINTS + 10
    pts = rng.uniform(10, 470, size=(n, 2))
    many = plane(points=pts, visible=np.ones(n, bool), in_image=np.ones(n, bool), n_hidden=0)
    svg = image_plane_svg(many, selected_point=7)
    pts_el = kinds(svg, "point")
    assert [int(p.get("data-index")) for p in pts_el] == list(range(n))
    labels = [t.text for p in pts_el for t in p.iter(NS + "text")]
    assert labels == ["8"]
    # Every disc still sits at its pixel, in its colour.
    discs = [next(c for c in p.iter(NS + "circle") if c.get("fill") != "none") for p in pts_el]
    assert np.allclose([[float(d.get("cx")), float(d.get("cy"))] for d in discs], pts, atol=0.051)
    assert "numbers: selected point only" in kinds(svg, "numbering-note")[0].text
    # On its own line, inside the viewBox.
    note_y = float(kinds(svg, "numbering-note")[0].get("y"))
    x, y, w, h = map(float, ET.fromstring(svg).get("viewBox").split())
    assert float(kinds(svg, "hidden-count")[0].get("y")) < note_y < y + h
    # At the limit every point is numbered again.
    few = plane(points=pts[:MAX_NUMBERED_POINTS], visible=np.ones(MAX_NUMBERED_POINTS, bool),
                in_image=np.ones(MAX_NUMBERED_POINTS, bool), n_hidden=0)
    labels = [t.text for p in kinds(image_plane_svg(few), "point") for t in p.iter(NS + "text")]
    assert labels == [str(i + 1) for i in range(MAX_NUMBERED_POINTS)]
    assert not kinds(image_plane_svg(few), "numbering-note")


def test_selected_point_gets_a_ring():
    svg = image_plane_svg(plane(), selected_point=1)
    rings = [el for el in ET.fromstring(svg).iter() if el.get("data-selected") == "true"]
    assert len(rings) == 1


def test_epipolar_lines_skip_nan_rows():
    lines = np.array([[[0, 0], [640, 480]], [[0, 10], [640, 10]], [[np.nan] * 2] * 2, [[0, 5], [5, 0]]], float)
    svg = image_plane_svg(plane(lines=lines))
    els = kinds(svg, "epipolar-line")
    assert [e.get("data-index") for e in els] == ["0", "1", "3"]
    assert float(els[0].get("x2")) == pytest.approx(640.0)


def test_epipole_inside_is_a_marker():
    ep = Epipole("e1", np.array([300.0, 200.0]), None, False, True)
    els = kinds(image_plane_svg(plane(epipoles=(ep,))), "epipole")
    assert len(els) == 1 and els[0].get("data-where") == "inside" and els[0].get("data-label") == "e1"


def test_epipole_outside_gets_an_arrow_at_the_border_pointing_to_it():
    ep = Epipole("e2", np.array([2000.0, 240.0]), None, False, False)
    svg = image_plane_svg(plane(epipoles=(ep,)))
    els = kinds(svg, "epipole")
    assert len(els) == 1 and els[0].get("data-where") == "outside"
    arrow = [el for el in els[0].iter() if el.get("data-kind") == "epipole-arrow"]
    assert len(arrow) == 1
    line = next(arrow[0].iter(NS + "line"))
    x1, x2 = float(line.get("x1")), float(line.get("x2"))
    assert x2 > x1  # points right, towards the epipole at u = 2000
    assert 640 * 0.98 <= x2 <= 640  # at the border, just inside the frame
    assert "(2000, 240)" in "".join(els[0].itertext())


def test_epipole_at_infinity_is_labelled():
    ep = Epipole("e1", None, np.array([0.0, 1.0]), True, False)
    svg = image_plane_svg(plane(epipoles=(ep,)))
    els = kinds(svg, "epipole")
    assert len(els) == 1 and els[0].get("data-where") == "infinity"
    assert "at infinity" in "".join(els[0].itertext())


def test_conics_and_rim_for_a_panoramic_plane():
    t = np.linspace(0, np.pi, 20)
    arc = np.column_stack([320 + 100 * np.cos(t), 240 + 100 * np.sin(t)])
    broken = arc.copy()
    broken[10] = np.nan  # a NaN splits the polyline in two pieces
    rim = np.column_stack([320 + 200 * np.cos(2 * t), 240 + 200 * np.sin(2 * t)])
    eps = (Epipole("e1", np.array([320.0, 100.0]), None, False, True),
           Epipole("e1'", np.array([320.0, 400.0]), None, False, True))
    p = plane(no_image="in the blind cone", conics=((arc,), (broken,), (), (arc,)), rim=rim, epipoles=eps)
    svg = image_plane_svg(p)
    conics = kinds(svg, "epipolar-conic")
    assert sorted({c.get("data-index") for c in conics}) == ["0", "1", "3"]
    assert len([c for c in conics if c.get("data-index") == "1"]) == 2
    assert len(kinds(svg, "rim")) == 1
    assert len(kinds(svg, "epipole")) == 2
    assert "blind cone" in " ".join(kinds(svg, "hidden-count")[0].itertext())


def test_message_and_escaping():
    svg = image_plane_svg(plane(camera='a<b"', message="no epipolar geometry: the centres coincide"))
    root = ET.fromstring(svg)  # well-formed despite the name
    assert root.get("data-camera") == 'a<b"'
    assert kinds(svg, "message")[0].text == "no epipolar geometry: the centres coincide"


def test_tiny_images_keep_their_precision():
    # Tutorial example 1 has a 2 x 2 pixel image with K = I.
    p = plane(width=2, height=2, points=np.array([[0.25, 1.5]]), visible=np.array([True]),
              in_image=np.array([True]), n_hidden=0)
    svg = image_plane_svg(p)
    circle = next(kinds(svg, "point")[0].iter(NS + "circle"))
    assert float(circle.get("cx")) == pytest.approx(0.25, abs=1e-3)


def test_default_scene_counts_match_the_derived_data():
    d = compute_derived(default_scene())
    for name, ip in d.image_planes.items():
        svg = image_plane_svg(ip)
        assert len(kinds(svg, "point")) == int(ip.in_image.sum())
        n_lines = int(np.all(np.isfinite(ip.lines.reshape(len(ip.lines), -1)), axis=1).sum())
        assert len(kinds(svg, "epipolar-line")) == n_lines
        assert len(kinds(svg, "epipole")) == len(ip.epipoles)
        assert re.search(r'data-camera="%s"' % name, svg)


def test_many_conics_are_thinned_but_keep_their_ends():
    from egtviz.viewer.render.svg import CONIC_VERTEX_BUDGET

    t = np.linspace(0, 2 * np.pi, 129)
    arc = np.column_stack([320 + 100 * np.cos(t), 240 + 100 * np.sin(t)])
    n = 200
    pts = np.full((n, 2), np.nan)
    p = plane(no_image="in the blind cone", points=pts, visible=np.zeros(n, bool), in_image=np.zeros(n, bool), n_hidden=n,
              conics=tuple((arc,) for _ in range(n)))
    conics = kinds(image_plane_svg(p), "epipolar-conic")
    assert len(conics) == n
    vertices = [c.get("points").split() for c in conics]
    assert sum(len(v) for v in vertices) <= CONIC_VERTEX_BUDGET + n
    assert vertices[0][0] == "420,240" and vertices[0][-1] == "420,240"  # both ends kept (whole pixels)
