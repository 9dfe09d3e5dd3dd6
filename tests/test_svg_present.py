"""Panel styles, views (fit, zoom, pan), ticks and label placement of the image-plane and servo SVGs."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from PIL import ImageFont
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.scene import SCENES, Epipole, ImagePlane, compute_derived
from egtviz.viewer.render.palette import POINT_COLOURS, PRESENT_POINT_COLOURS, contrast_ratio
from egtviz.viewer.render.panel_view import ViewBox, fit_view, image_view, pan, place_labels, tick_values, zoom
from egtviz.viewer.render.servo_svg import ServoImage, servo_image_svg, shared_zero_ranges
from egtviz.viewer.render.svg import NORMAL, PRESENT, image_plane_svg

NS = "{http://www.w3.org/2000/svg}"
FONTS = Path(matplotlib.get_data_path()) / "fonts" / "ttf"


def text_width(text: str, size: float, *, bold: bool = False, italic: bool = False) -> float:
    """Width of ``text`` in DejaVu Sans (the font of the PNG figures) at ``size``, measured with FreeType."""
    name = "DejaVuSans" + ("-Bold" if bold else "") + ("Oblique" if italic and bold else "-Oblique" if italic else "")
    font = ImageFont.truetype(str(FONTS / f"{name}.ttf"), 200)
    return font.getlength(text) * size / 200.0

#: Panel widths in CSS pixels: a 1920 x 1080 window gives a panel about 620 px wide, 1366 x 768 about 330 px.
PANEL_1920, PANEL_1366 = 620.0, 330.0


def plane(**kw) -> ImagePlane:
    pts = np.array([[100.0, 100.0], [320.0, 240.0], [700.0, 100.0], [np.nan, np.nan]])
    base = dict(camera="cam", width=640, height=480, points=pts,
                visible=np.array([True, True, True, False]), in_image=np.array([True, True, False, False]),
                n_hidden=1)
    base.update(kw)
    return ImagePlane(**base)


def text_sizes(svg: str) -> list[tuple[ET.Element, float]]:
    """Every ``<text>`` with its font size in user units (its own ``font-size``, else its nearest ancestor's)."""
    out = []

    def walk(el: ET.Element, inherited: float | None) -> None:
        fs = float(el.get("font-size")) if el.get("font-size") else inherited
        if el.tag == NS + "text":
            assert fs is not None, f"text {''.join(el.itertext())!r} has no font size"
            out.append((el, fs))
        for child in el:
            walk(child, fs)

    walk(ET.fromstring(svg), None)
    return out


def font_sizes_px(svg: str, rendered_width: float) -> list[tuple[str, float]]:
    """``(text, size on screen in CSS px)`` of every text, the SVG shown ``rendered_width`` CSS px wide.

    A font size in user units becomes ``size * rendered_width / viewBox_width`` on screen.
    """
    vb_w = float(ET.fromstring(svg).get("viewBox").split()[2])
    return [("".join(el.itertext()), fs * rendered_width / vb_w) for el, fs in text_sizes(svg)]


def text_extent(el: ET.Element, size: float, *, bold: bool = False) -> tuple[float, float]:
    """``(left, right)`` of a text element from its x, anchor and measured width (its widest line)."""
    lines = [t.text or "" for t in el.iter(NS + "tspan")] or ["".join(el.itertext())]
    width = max(text_width(line, size, bold=bold, italic=el.get("font-style") == "italic") for line in lines)
    x = float(el.get("x"))
    anchor = el.get("text-anchor", "start")
    left = x - width / 2 if anchor == "middle" else x - width if anchor == "end" else x
    return left, left + width


def example_planes() -> list[ImagePlane]:
    planes = []
    for name in ("default", "example1", "example3"):
        planes.extend(compute_derived(SCENES[name]()).image_planes.values())
    return planes


# -- presentation style: text sizes ----------------------------------------------------------------


@pytest.mark.parametrize("panel_px", [PANEL_1920, PANEL_1366])
def test_presentation_text_is_at_least_16_px_at_the_panel_width(panel_px):
    ep_out = Epipole("e1", np.array([2000.0, 200.0]), None, False, False)
    ep_inf = Epipole("e1'", None, np.array([0.0, 1.0]), True, False)
    p = plane(epipoles=(ep_out, ep_inf), message="a message")
    for pl in [p, *example_planes()]:
        for view in (None, fit_view(pl)):
            svg = image_plane_svg(pl, style=PRESENT, panel_px=panel_px, view=view, selected_point=0)
            sizes = font_sizes_px(svg, panel_px)
            texts = {t for t, _ in sizes}
            assert {"u", "v"} <= texts  # the axis names are among the measured texts
            if pl is p:
                assert "1" in texts  # and a point number
            assert min(px for _, px in sizes) >= 16.0, sorted(sizes, key=lambda x: x[1])[:3]


def test_text_size_does_not_depend_on_the_image_size_in_pixels():
    # The same scene content on a 2 px, a 640 px and a 4000 px image: the same on-screen sizes.
    sizes = []
    for scale in (2 / 640, 1.0, 4000 / 640):
        p = plane(width=640 * scale, height=480 * scale, points=plane().points * scale)
        svg = image_plane_svg(p, style=PRESENT, panel_px=PANEL_1920)
        by_text = dict(font_sizes_px(svg, PANEL_1920))
        sizes.append((by_text["u"], by_text["1"]))
    assert np.allclose(sizes, sizes[0], rtol=1e-3)
    assert sizes[0] == pytest.approx((PRESENT.tick_px, PRESENT.label_px), rel=1e-3)


def test_normal_style_is_smaller_than_presentation():
    svg = image_plane_svg(plane(), style=NORMAL, panel_px=PANEL_1920)
    assert min(px for _, px in font_sizes_px(svg, PANEL_1920)) < 16.0  # the bound above is not trivially met
    assert PRESENT.line_px > NORMAL.line_px and PRESENT.mark_px > NORMAL.mark_px


def test_presentation_colours_have_high_contrast_on_white():
    assert all(contrast_ratio(c, "#ffffff") >= 4.5 for c in PRESENT_POINT_COLOURS)
    assert any(contrast_ratio(c, "#ffffff") < 3.0 for c in POINT_COLOURS)  # why they were darkened
    # Hand-checked ends of the WCAG scale.
    assert contrast_ratio("#000000", "#ffffff") == pytest.approx(21.0)
    assert contrast_ratio("#777777", "#777777") == pytest.approx(1.0)
    svg = image_plane_svg(plane(), style=PRESENT)
    fills = set(re.findall(r'fill="(#[0-9A-Fa-f]{6})"', svg))
    assert PRESENT_POINT_COLOURS[0] in fills and POINT_COLOURS[0] not in fills


def test_status_wraps_inside_the_panel():
    n = 12
    p = plane(points=np.full((n, 2), 50.0), visible=np.ones(n, bool), in_image=np.zeros(n, bool), n_hidden=3)
    svg = image_plane_svg(p, style=PRESENT, panel_px=PANEL_1366)
    status = [el for el in ET.fromstring(svg).iter() if el.get("data-kind") == "hidden-count"][0]
    lines = [t.text for t in status.iter(NS + "tspan")]
    assert len(lines) >= 2 and "3 hidden (behind the camera)" in " ".join(lines)
    # Each line, right-aligned at the frame's right edge, starts inside the panel.
    root = ET.fromstring(svg)
    x0, _, w, _ = map(float, root.get("viewBox").split())
    size = float(status.get("font-size"))
    right = float(status.get("x"))
    assert all(right - text_width(s, size) >= x0 for s in lines)


# -- views: fit, zoom, pan, ticks --------------------------------------------------------------------


def content_pixels(pl: ImagePlane) -> np.ndarray:
    P = [pl.points[np.asarray(pl.visible, bool)]]
    P += [np.asarray(e.xy, float)[None] for e in pl.epipoles if e.xy is not None and not e.at_infinity]
    return np.concatenate(P)


def test_fit_shows_every_point_and_epipole_of_the_example_scenes():
    for pl in example_planes():
        view = fit_view(pl)
        P = content_pixels(pl)
        assert view.contains(P).all(), (pl.camera, P, view)
        assert view.contains([[0, 0], [pl.width, pl.height]]).all()  # and the image
        assert view.width / view.height == pytest.approx(pl.width / pl.height)
        svg = image_plane_svg(pl, view=view)
        root = ET.fromstring(svg)
        shown = [el for el in root.iter() if el.get("data-kind") in ("point", "point-outside")]
        assert len(shown) == int(np.asarray(pl.visible).sum())
        assert all(el.get("data-drawn") == "mark" for el in root.iter() if el.get("data-kind") == "epipole"
                   if el.get("data-where") != "infinity")


def test_fit_of_tutorial_example3_matches_its_printed_pixels():
    # EGT tutorial Example 3 (K = I): image 1 has m = (0, -0.7071), (-0.2357, -0.2357) and the epipole
    # e1 = (0.7071, -0.7071); image 2 has m = (0, -1), (-2, -1) and e2 = (1, 0). Hand-derived in the tutorial.
    d = compute_derived(SCENES["example3"]())
    for cam, expected in (("cam1", [[0.0, -0.70711], [-0.23570, -0.23570], [0.70711, -0.70711]]),
                          ("cam2", [[0.0, -1.0], [-2.0, -1.0], [1.0, 0.0]])):
        pl = d.image_planes[cam]
        np.testing.assert_allclose(content_pixels(pl), expected, atol=1e-4)
        svg = image_plane_svg(pl, view=fit_view(pl))
        root = ET.fromstring(svg)
        ticks = [t.text for g in root.iter() if g.get("data-kind") == "axes" for t in g.iter(NS + "text")]
        numbers = [float(t) for t in ticks if t not in ("u", "v")]
        assert len(numbers) >= 8  # at least four ticks per axis on a 2 x 2 px image
        assert any(x < 0 for x in numbers) and any(0 < x < 1 for x in numbers)  # fractions of a pixel, negative


def test_fit_leaves_out_an_epipole_far_away_and_shows_its_arrow():
    ep = Epipole("e1", np.array([1e9, 240.0]), None, False, False)
    pl = plane(epipoles=(ep,))
    view = fit_view(pl)
    assert view.u1 < 2000
    svg = image_plane_svg(pl, view=view)
    (el,) = [e for e in ET.fromstring(svg).iter() if e.get("data-kind") == "epipole"]
    assert el.get("data-drawn") == "arrow"


def test_lines_are_drawn_across_the_fitted_view():
    seg = np.array([[[0.0, 100.0], [640.0, 260.0]]])  # slope 1/4 through the image
    pl = plane(lines=seg, epipoles=(Epipole("e2", np.array([1040.0, 360.0]), None, False, False),))
    view = fit_view(pl)
    svg = image_plane_svg(pl, view=view)
    (line,) = [e for e in ET.fromstring(svg).iter() if e.get("data-kind") == "epipolar-line"]
    x1, y1, x2, y2 = (float(line.get(k)) for k in ("x1", "y1", "x2", "y2"))
    assert (y2 - y1) / (x2 - x1) == pytest.approx(0.25)  # the same line
    assert x2 > 1040 and x1 <= view.u0 + 1e-6 or y1 <= view.v0 + 1e-6  # reaches the epipole and the view's edge


views = st.builds(ViewBox, st.floats(-1e4, 1e4), st.floats(-1e4, 1e4), st.floats(1e-2, 1e4), st.floats(1e-2, 1e4))


@settings(max_examples=60, deadline=None)
@given(views, st.floats(0.1, 10.0), st.floats(0, 1), st.floats(0, 1))
def test_zoom_keeps_the_pivot_and_aspect_and_undoes(view, factor, fu, fv):
    about = (view.u0 + fu * view.width, view.v0 + fv * view.height)
    z = zoom(view, factor, about)
    assert z.width == pytest.approx(view.width / factor) and z.height == pytest.approx(view.height / factor)
    # The pivot is at the same fraction of the view before and after.
    assert (about[0] - z.u0) / z.width == pytest.approx(fu, abs=1e-6)
    assert (about[1] - z.v0) / z.height == pytest.approx(fv, abs=1e-6)
    back = zoom(z, 1.0 / factor, about)
    np.testing.assert_allclose([back.u0, back.v0, back.width, back.height],
                               [view.u0, view.v0, view.width, view.height], rtol=1e-9, atol=1e-6)


@settings(max_examples=60, deadline=None)
@given(views, st.floats(-3, 3), st.floats(-3, 3))
def test_pan_moves_by_fractions_of_the_view(view, du, dv):
    p = pan(view, du, dv)
    assert (p.width, p.height) == (view.width, view.height)
    assert p.u0 - view.u0 == pytest.approx(du * view.width, abs=1e-9 * (1 + abs(view.u0)))
    back = pan(p, -du, -dv)
    assert back.u0 == pytest.approx(view.u0, abs=1e-6) and back.v0 == pytest.approx(view.v0, abs=1e-6)


def test_view_errors_name_the_argument():
    with pytest.raises(ValueError, match="width and height must be > 0"):
        ViewBox(0, 0, 0, 1)
    with pytest.raises(ValueError, match="finite"):
        ViewBox(float("nan"), 0, 1, 1)
    with pytest.raises(ValueError, match="factor"):
        zoom(ViewBox(0, 0, 1, 1), 0.0)
    with pytest.raises(ValueError, match="panel_px"):
        image_plane_svg(plane(), panel_px=0)


@settings(max_examples=80, deadline=None)
@given(st.floats(-1e4, 1e4), st.floats(1e-3, 1e4), st.floats(0.01, 1e3), st.floats(5, 200))
def test_ticks_are_a_1_2_5_step_inside_the_range_far_enough_apart(lo, span, px_per_unit, gap):
    values, decimals = tick_values(lo, lo + span, px_per_unit, gap)
    tol = 1e-9 * (10 * gap / px_per_unit + abs(lo) + span)  # a tick within 1e-9 of a step of an end counts as in
    assert np.all(values >= lo - tol) and np.all(values <= lo + span + tol)
    if len(values) >= 2:
        step = values[1] - values[0]
        assert step * px_per_unit >= gap * (1 - 1e-6)
        mant = step / 10 ** np.floor(np.log10(step) + 1e-9)
        assert min(abs(mant - m) for m in (1, 2, 5, 10)) < 1e-6
        # The decimals write the step exactly.
        assert float(f"{step:.{decimals}f}") == pytest.approx(step, rel=1e-6)
        # And the step is the smallest such: half of it (or 2/5 of a 5) would be too close.
        smaller = step / (2.5 if round(mant) == 5 else 2)
        assert smaller * px_per_unit < gap


def test_image_view_is_the_image_rectangle():
    v = image_view(plane())
    assert (v.u0, v.v0, v.width, v.height) == (0, 0, 640, 480)


# -- labels never hide their marks -----------------------------------------------------------------------


def overlap(a, b) -> float:
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    return max(w, 0.0) * max(h, 0.0)


def mark_boxes(svg: str) -> list[tuple[str, tuple[float, float, float, float]]]:
    """Boxes of the drawn marks, read back from the SVG: discs, epipole crosses, arrows."""
    root = ET.fromstring(svg)
    out = []
    for el in root.iter():
        kind = el.get("data-kind")
        if kind in ("point", "point-outside"):
            for c in el.iter(NS + "circle"):
                x, y, r = (float(c.get(k)) for k in ("cx", "cy", "r"))
                out.append((f"point {el.get('data-index')}", (x - r, y - r, x + r, y + r)))
        elif kind in ("epipole", "epipole-arrow"):
            pts = []
            for c in el.iter():
                if c.tag == NS + "path":
                    pts += [float(v) for v in re.findall(r"-?[\d.]+(?:e-?\d+)?", c.get("d"))]
                elif c.tag == NS + "line":
                    pts += [float(c.get(k)) for k in ("x1", "y1", "x2", "y2")]
                elif c.tag == NS + "polygon":
                    pts += [float(v) for v in re.split(r"[ ,]", c.get("points"))]
            if pts:
                P = np.array(pts).reshape(-1, 2)
                out.append((f"{kind} {el.get('data-label')}", (*P.min(axis=0), *P.max(axis=0))))
    return out


def label_boxes(svg: str) -> list[tuple[str, tuple[float, ...]]]:
    root = ET.fromstring(svg)
    return [("".join(t.itertext()), tuple(map(float, t.get("data-box").split())))
            for t in root.iter(NS + "text") if t.get("data-box")]


def assert_labels_clear(svg: str) -> None:
    marks, labels = mark_boxes(svg), label_boxes(svg)
    assert labels
    # Each placed box holds its text as DejaVu Sans draws it (numbers are bold).
    for el, size in text_sizes(svg):
        if el.get("data-box"):
            x0, y0, x1, y1 = map(float, el.get("data-box").split())
            left, right = text_extent(el, size, bold="".join(el.itertext()).isdigit())
            tol = 1e-9 * (abs(x0) + abs(x1) + 1)
            assert x0 - tol <= left and right <= x1 + tol, "".join(el.itertext())
            assert y0 <= float(el.get("y")) - 0.73 * size and float(el.get("y")) <= y1  # cap height .73 em
    for text, box in labels:
        for name, m in marks:
            assert overlap(box, m) <= 1e-9, f"label {text!r} covers {name}"
    for i in range(len(labels)):
        for j in range(i):
            assert overlap(labels[i][1], labels[j][1]) <= 1e-9, f"labels {labels[i][0]!r} and {labels[j][0]!r}"


def test_labels_clear_their_marks_in_the_example_scenes():
    for pl in example_planes():
        for style in (NORMAL, PRESENT):
            for view in (None, fit_view(pl)):
                assert_labels_clear(image_plane_svg(pl, style=style, view=view, selected_point=0))


@pytest.mark.parametrize("target", [(2000, 240), (-900, 240), (320, -700), (320, 1500), (2000, 2000), (-500, -500)])
def test_an_epipole_label_never_covers_its_arrow(target):
    # A point right where the label would go first makes the placement work for it.
    ep = Epipole("e2", np.array(target, float), None, False, False)
    pts = np.array([[600.0, 200.0], [40.0, 240.0], [320.0, 30.0], [320.0, 450.0]])
    pl = plane(points=pts, visible=np.ones(4, bool), in_image=np.ones(4, bool), n_hidden=0, epipoles=(ep,))
    for style in (NORMAL, PRESENT):
        svg = image_plane_svg(pl, style=style)
        assert_labels_clear(svg)
        (el,) = [e for e in ET.fromstring(svg).iter() if e.get("data-kind") == "epipole"]
        assert el.get("data-drawn") == "arrow"
        assert f"({target[0]:.4g}, {target[1]:.4g})" in "".join(el.itertext())


def test_point_numbers_and_an_epipole_label_avoid_each_other_when_crowded():
    # Ten points and an epipole within a few pixels: every number still finds a free place.
    rng = np.random.default_rng(3)
    pts = np.array([320.0, 240.0]) + rng.uniform(-40, 40, size=(10, 2))
    eps = (Epipole("e1", np.array([322.0, 238.0]), None, False, True),)
    pl = plane(points=pts, visible=np.ones(10, bool), in_image=np.ones(10, bool), n_hidden=0, epipoles=eps)
    svg = image_plane_svg(pl, style=PRESENT)
    assert_labels_clear(svg)
    assert sorted(t for t, _ in label_boxes(svg)) == sorted([str(i) for i in range(1, 11)] + ["e1"])
    assert image_plane_svg(pl, style=PRESENT) == svg  # deterministic


def test_numbers_stay_readable_beyond_the_palette():
    # Points 1 and 7 share a colour; their numbers are dark with a white halo, not the colour.
    n = 8
    pts = np.column_stack([np.linspace(50, 590, n), np.full(n, 240.0)])
    pl = plane(points=pts, visible=np.ones(n, bool), in_image=np.ones(n, bool), n_hidden=0)
    svg = image_plane_svg(pl)
    root = ET.fromstring(svg)
    groups = {int(g.get("data-index")): g for g in root.iter() if g.get("data-kind") == "point"}
    disc_fill = {i: next(g.iter(NS + "circle")).get("fill") for i, g in groups.items()}
    assert disc_fill[0] == disc_fill[6]
    assert {next(g.iter(NS + "text")).text for g in (groups[0], groups[6])} == {"1", "7"}
    group_style = next(el for el in root.iter(NS + "g") if el.get("font-weight") == "bold")
    assert contrast_ratio(group_style.get("fill"), "#ffffff") >= 7.0


def test_place_labels_prefers_the_upper_right_and_moves_when_blocked():
    boxes = place_labels([[0.0, 0.0]], [1.0], [[4.0, 2.0]], np.zeros((0, 4)), (-100, -100, 100, 100), gap=0.5)
    np.testing.assert_allclose(boxes[0], [1.5, -3.5, 5.5, -1.5])  # touching the square |x|, |y| <= 1.5, upper right
    blocked = place_labels([[0.0, 0.0]], [1.0], [[4.0, 2.0]], [[1.0, -10.0, 10.0, 10.0]], (-100, -100, 100, 100),
                           gap=0.5)
    assert blocked[0][2] <= 1.0  # the whole right side is taken: the label goes left
    # Two labels on one anchor never share a box.
    two = place_labels([[0.0, 0.0], [0.0, 0.0]], [1.0, 1.0], [[4.0, 2.0]] * 2, np.zeros((0, 4)),
                       (-100, -100, 100, 100), gap=0.5)
    assert overlap(two[0], two[1]) == 0.0


# -- servo panels ----------------------------------------------------------------------------------------


def servo_image(demo: str = "panoramic", message: str = "") -> ServoImage:
    n = 10
    rng = np.random.default_rng(0)
    goal = np.array([320.0, 240.0]) + rng.uniform(-60, 60, (n, 2))
    cur = goal + rng.uniform(-1.0, 1.0, (n, 2))  # the end of a run: features on their goals
    trails = np.stack([goal + 40.0, cur])
    t = np.linspace(0, 2 * np.pi, 64)
    rim = np.column_stack([320 + 220 * np.cos(t), 240 + 220 * np.sin(t)])
    return ServoImage(demo=demo, width=640, height=480, frame=388, current=cur, desired=goal, trails=trails,
                      epipoles=[("e", np.array([330.0, 250.0])), ("e'", np.array([300.0, 230.0]))], rim=rim,
                      caption="t = 19.40 s  step 2: translation", message=message)


@pytest.mark.parametrize("style, panel_px", [(NORMAL, None), (PRESENT, None), (PRESENT, PANEL_1366)])
def test_servo_panel_texts_stay_inside_and_labels_do_not_overlap(style, panel_px):
    img = servo_image(message="did not converge (see the status on the left)")
    svg = servo_image_svg(img, style=style, panel_px=panel_px)
    root = ET.fromstring(svg)
    x0, y0, w, h = map(float, root.get("viewBox").split())
    for el, size in text_sizes(svg):
        for y in [float(el.get("y"))] + [float(t.get("y")) for t in el.iter(NS + "tspan")]:
            assert y0 + 0.73 * size <= y <= y0 + h - 0.2 * size, "".join(el.itertext())  # not cut at top or bottom
        left, right = text_extent(el, size, bold=el.get("font-weight") == "bold")
        assert x0 <= left and right <= x0 + w, "".join(el.itertext())  # nor at the sides
    # The caption and the message are under the image, not over it.
    for kind in ("caption", "message"):
        el = next(e for e in root.iter() if e.get("data-kind") == kind)
        assert float(el.get("y")) > img.height
    labels = label_boxes(svg)
    assert sorted(t for t, _ in labels) == sorted([str(i) for i in range(1, 11)] + ["e", "e'"])
    for i in range(len(labels)):
        for j in range(i):
            assert overlap(labels[i][1], labels[j][1]) <= 1e-9
    discs = [(float(c.get("cx")), float(c.get("cy")), float(c.get("r"))) for c in root.iter(NS + "circle")
             if c.get("data-kind") == "point"]
    for text, box in labels:
        for x, y, r in discs:
            assert overlap(box, (x - r, y - r, x + r, y + r)) <= 1e-9, text


def test_servo_tick_labels_are_inside_the_panel():
    svg = servo_image_svg(servo_image(), style=PRESENT, panel_px=PANEL_1366)
    root = ET.fromstring(svg)
    x0, y0, w, h = map(float, root.get("viewBox").split())
    texts = text_sizes(svg)
    assert len([t for t, _ in texts if t.text and t.text.replace(".", "").isdigit()]) >= 8  # ticks among them
    for t, size in texts:
        left, right = text_extent(t, size, bold=t.get("font-weight") == "bold")
        assert x0 <= left and right <= x0 + w, t.text
        assert float(t.get("y")) - 0.73 * size >= y0, t.text
    assert min(px for _, px in font_sizes_px(svg, PANEL_1366)) >= 16.0


@settings(max_examples=100, deadline=None)
@given(st.floats(-1e3, 1e3), st.floats(0, 1e3), st.floats(-1e3, 1e3), st.floats(0, 1e3))
def test_two_axes_share_their_zero(alo, aspan, blo, bspan):
    a, b = (alo, alo + aspan), (blo, blo + bspan)
    (la, ha), (lb, hb) = shared_zero_ranges(a, b)
    assert la <= min(a[0], 0) + 1e-9 and ha >= max(a[1], 0) - 1e-9
    assert lb <= min(b[0], 0) + 1e-9 and hb >= max(b[1], 0) - 1e-9
    # Zero at the same height: the same fraction of each axis from the bottom.
    assert -la / (ha - la) == pytest.approx(-lb / (hb - lb), abs=1e-9)


def test_shared_zero_ranges_by_hand():
    # a = [-1, 3] puts zero at 1/4; b = [0, 10] at 0; both take 1/4: b becomes [-10/3, 10] (+5 % padding).
    (la, ha), (lb, hb) = shared_zero_ranges((-1.0, 3.0), (0.0, 10.0))
    assert (la, ha) == pytest.approx((-1.05, 3.15))
    assert (lb, hb) == pytest.approx((-3.5, 10.5))
    with pytest.raises(ValueError, match="b: expected finite"):
        shared_zero_ranges((0, 1), (2, 1))


def test_zoomed_in_view_keeps_the_contract_and_numbers_only_what_it_shows():
    pl = plane()  # points 1 and 2 in the image, 3 outside it, 4 hidden
    view = zoom(image_view(pl), 4.0, about=(100.0, 100.0))  # u0 = 100 - 100 / 4: [75, 235] x [75, 195]
    svg = image_plane_svg(pl, view=view)
    root = ET.fromstring(svg)
    points = [el for el in root.iter() if el.get("data-kind") == "point"]
    assert [p.get("data-index") for p in points] == ["0", "1"]  # every point in the image, as the contract says
    assert [t for t, _ in label_boxes(svg)] == ["1"]
    assert root.get("data-view") == "75 75 160 120"  # only point 1 (100, 100) is in it
    assert_labels_clear(svg)


def test_fit_shows_the_horizon_of_a_unified_camera():
    """The horizon of a unified camera (radius f / xi about the principal point) may reach beyond the image."""
    from egtviz.scene import Scene, compute_derived
    from egtviz.scene import UnifiedSpec

    scene = Scene(cameras=(UnifiedSpec("uni", xi=0.9, focal_pixels=300.0),), points=((0.0, 3.0, 0.5),))
    plane = compute_derived(scene).image_planes["uni"]
    assert plane.horizon, "the scene should show a horizon"
    view = fit_view(plane)
    for arc in plane.horizon:
        assert (arc[:, 0] >= view.u0).all() and (arc[:, 0] <= view.u0 + view.width).all()
        assert (arc[:, 1] >= view.v0).all() and (arc[:, 1] <= view.v0 + view.height).all()
    assert view.height > 2 * 300.0 / 0.9  # the horizon's diameter (667 px) is taller than the 480 px image


def test_a_fitted_view_draws_the_lines_that_miss_the_image():
    """Example 3's cam1: both epipolar lines pass above its 2 x 2 image; the fitted view shows them through their
    points and the epipole."""
    from egtviz.scene import SCENES, compute_derived

    pl = compute_derived(SCENES["example3"]()).image_planes["cam1"]
    assert np.isnan(pl.lines).all()  # clipped to the image: nothing
    root = ET.fromstring(image_plane_svg(pl, view=fit_view(pl)))
    lines = [el for el in root.iter() if el.get("data-kind") == "epipolar-line"]
    assert len(lines) == 2
    for el, point in zip(lines, pl.points, strict=True):
        (x1, y1, x2, y2) = (float(el.get(k)) for k in ("x1", "y1", "x2", "y2"))
        for p in (point, pl.epipoles[0].xy):  # the line holds its point and the epipole
            cross = (x2 - x1) * (p[1] - y1) - (y2 - y1) * (p[0] - x1)
            assert abs(cross) / math.hypot(x2 - x1, y2 - y1) < 5e-3  # coordinates are written to 3 decimals
