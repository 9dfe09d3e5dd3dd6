"""A drag redraws only what it changes: a panel whose camera neither moved nor is in the drawn pair keeps its SVG,
and a panel whose points stay put keeps their discs' text.

Run on a real viser server with a websocket stand-in for the browser (``egtviz.viewer.server.headless``); the drag
events are made as viser makes them (``egtviz.bench.viewer._drag_event``).
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.bench.viewer import _drive
from egtviz.scene import SceneModel, default_scene
from egtviz.viewer.render import svg
from egtviz.viewer.server.headless import start_headless
from egtviz.viewer.render.svg import image_plane_svg


def _rev(svg: str) -> int:
    return int(re.search(r'data-rev="(\d+)"', svg).group(1))


@pytest.fixture
def four_cameras():
    model = SceneModel(default_scene())
    model.add_camera("pinhole")
    model.add_camera("pinhole")
    scene = model.scene
    assert scene.drawn_pair == ("cam1", "cam2") and len(scene.cameras) == 4
    server, _app, fakes, views = start_headless(scene)
    yield views[0]
    for f in fakes:
        f.close()
    server.stop()


def test_a_drag_keeps_the_panels_it_does_not_change(four_cameras):
    view = four_cameras
    others = [c.name for c in view.model.scene.cameras[2:]]
    kept = {name: view.svgs[name] for name in others}
    _drive(view, "cam1", 5, 0.0)
    rev = view.revision
    # The moved camera and its partner are drawn anew; the two others keep the very same SVG (not re-sent).
    assert _rev(view.svgs["cam1"]) == _rev(view.svgs["cam2"]) == rev
    for name in others:
        assert view.svgs[name] is kept[name]
        assert view.dock.html[name].content is kept[name]
        assert _rev(kept[name]) < rev


def test_a_kept_panel_is_what_a_fresh_drawing_gives(four_cameras):
    view = four_cameras
    _drive(view, "cam1", 3, 0.0)
    scene, derived = view.model.scene, view.model.derived
    for spec in scene.cameras[2:]:
        plane = derived.image_planes[spec.name]
        kept = view.svgs[spec.name]
        grid = view.grid
        fresh = image_plane_svg(plane, selected_point=scene.selected_point, highlighted=set(),
                                show_labels=scene.options.show_labels, revision=_rev(kept),
                                view=view.dock.panel_view(spec.name, plane).resolve(plane), style=view.dock.style,
                                panel_px=grid.column_px, max_height=f"{grid.svg_max_height_px(spec.name):.0f}px")
        assert fresh == kept


@pytest.mark.parametrize("change", ["select", "labels", "present"])
def test_what_every_panel_shows_redraws_every_panel(four_cameras, change):
    view = four_cameras
    _drive(view, "cam1", 2, 0.0)
    before = dict(view.svgs)
    if change == "select":
        view.model.select_point(3)
    elif change == "labels":
        view.model.set_option("show_labels", not view.model.scene.options.show_labels)
    else:
        view.present_checkbox.value = True
    rev = view.revision
    for name, drawn in view.svgs.items():
        assert drawn is not before[name] and _rev(drawn) == rev, name
    if change == "select":
        # The selected point's ring is in every panel that shows it.
        shown = [n for n, p in view.model.derived.image_planes.items() if bool(np.asarray(p.in_image)[3])]
        assert shown and all('data-selected="true"' in view.svgs[n] for n in shown)


# -- the points' discs, formatted once per set of pixels ----------------------------------------------------------


def _disc_rows_by_hand(P, in_image, in_view, style, k, dp):
    """The discs as the panel wrote them point by point: ``"%.{dp}f" % x`` for each coordinate."""
    c = f"%.{dp}f"
    r = svg.svg_number(style.mark_px * k)
    rows = []
    for i in np.flatnonzero(in_image).tolist():
        col = style.point_colours[i % len(style.point_colours)]
        rows.append(f'<circle data-kind="point" data-index="{i}" cx="{c % P[i, 0]}" cy="{c % P[i, 1]}" r="{r}" '
                    f'fill="{col}"/>')
    for i in np.flatnonzero(in_view & ~in_image).tolist():
        col = style.point_colours[i % len(style.point_colours)]
        rows.append(f'<circle data-kind="point-outside" data-index="{i}" cx="{c % P[i, 0]}" cy="{c % P[i, 1]}" '
                    f'r="{r}" fill="#fff" stroke="{col}" stroke-width="{svg.svg_number(style.line_px * k * 1.6)}"/>')
    return tuple(rows)


@settings(max_examples=200, deadline=None)
@given(n=st.integers(0, 60), dp=st.integers(0, 6), k=st.floats(0.01, 8.0), seed=st.integers(0, 2**32 - 1),
       scale=st.sampled_from([1.0, 1e3, 1e5]))
def test_disc_rows_are_the_per_point_formatting(n, dp, k, seed, scale):
    rng = np.random.default_rng(seed)
    P = np.ascontiguousarray(rng.normal(0.0, scale, (n, 2)))
    P[rng.random(n) < 0.1] = 0.5 / 10**dp  # ties of the decimal rounding
    P[rng.random(n) < 0.05] = -0.0
    in_view = rng.random(n) < 0.8
    in_image = in_view & (rng.random(n) < 0.7)
    style = svg.PRESENT if seed % 2 else svg.NORMAL
    got = svg._plain_point_rows(P.tobytes(), in_image.tobytes(), in_view.tobytes(), style, k, dp)
    assert tuple("".join(row) for row in got.tolist()) == _disc_rows_by_hand(P, in_image, in_view, style, k, dp)
