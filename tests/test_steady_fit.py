"""A fitted panel during a drag (egtviz.viewer.render.panel_view.steady_fit): still axes while everything stays in view."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.viewer.render.panel_view import (
    STEADY_FILL,
    STEADY_SLACK,
    ViewBox,
    steady_fit,
    zoom,
)
from egtviz.viewer.render.panels import PanelView

KEPT = ViewBox(-100.0, -50.0, 800.0, 600.0)


def test_without_a_previous_view_the_fit_is_exact():
    fitted = ViewBox(0.0, 0.0, 640.0, 480.0)
    assert steady_fit(fitted, None) == fitted


def test_the_kept_view_stays_while_it_holds_the_fit():
    # 700 x 525 inside the kept 800 x 600: 700 / 800 = 0.875 >= 0.7.
    assert steady_fit(ViewBox(-60.0, -20.0, 700.0, 525.0), KEPT) == KEPT


def _grown(fitted):
    """The fit with STEADY_SLACK of its size added on each side, by hand."""
    s = STEADY_SLACK
    return ViewBox(fitted.u0 - s * fitted.width, fitted.v0 - s * fitted.height, (1 + 2 * s) * fitted.width,
                   (1 + 2 * s) * fitted.height)


def test_content_leaving_the_kept_view_gets_a_new_view_with_room_to_move():
    # The same size, moved 150 px right: its right edge 790 passes the kept one at 700.
    fitted = ViewBox(90.0, -20.0, 700.0, 525.0)
    new = steady_fit(fitted, KEPT)
    # 5 % of 700 = 35 px on each side: u from 55 to 825, width 770.
    assert (new.u0, new.v0, new.width, new.height) == pytest.approx((55.0, -46.25, 770.0, 577.5))
    assert new == _grown(fitted)
    # The next step, 10 px further right, stays in it.
    assert steady_fit(ViewBox(100.0, -20.0, 700.0, 525.0), new) == new


def test_content_shrunk_to_a_corner_gets_a_new_view():
    # Inside, but 400 / 800 = 0.5 of the width: the panel would waste most of its area.
    fitted = ViewBox(0.0, 0.0, 400.0, 300.0)
    assert steady_fit(fitted, KEPT) == _grown(fitted)
    # At the threshold itself it is kept (0.7 * 800 = 560).
    assert steady_fit(ViewBox(0.0, 0.0, STEADY_FILL * 800.0, STEADY_FILL * 600.0), KEPT) == KEPT


@settings(max_examples=300, deadline=None)
@given(u=st.floats(-2000, 2000), v=st.floats(-2000, 2000), w=st.floats(1, 4000), ku=st.floats(-2000, 2000),
       kv=st.floats(-2000, 2000), kw=st.floats(1, 4000), fill=st.floats(0.0, 0.9))
def test_the_view_shown_always_contains_the_fit(u, v, w, ku, kv, kw, fill):
    fitted, kept = ViewBox(u, v, w, 0.75 * w), ViewBox(ku, kv, kw, 0.75 * kw)
    shown = steady_fit(fitted, kept, fill=fill)
    assert shown in (_grown(fitted), kept)
    assert shown.u0 <= fitted.u0 and shown.v0 <= fitted.v0 and shown.u1 >= fitted.u1 and shown.v1 >= fitted.v1
    # The shown view is never much larger than the fit: at most 1 / fill of its width.
    assert fitted.width >= fill * shown.width - 1e-9


def test_the_content_box_decides_when_given():
    # The exact fit of the moved content pokes out of the kept view by its margin, but the content itself is
    # inside: the view stays (no jump at a drag's first step).
    fitted, content = ViewBox(-110.0, -40.0, 780.0, 585.0), ViewBox(-50.0, 5.0, 660.0, 495.0)
    assert steady_fit(fitted, KEPT) == _grown(fitted)
    assert steady_fit(fitted, KEPT, content=content) == KEPT
    # The content itself leaving the view does move it.
    assert steady_fit(fitted, KEPT, content=ViewBox(-120.0, 5.0, 660.0, 495.0)) == _grown(fitted)


def test_only_fit_panels_hold_their_view():
    from egtviz.scene import compute_derived, default_scene

    plane = compute_derived(default_scene()).image_planes["cam1"]
    fitted = PanelView("fit").resolve(plane)
    larger = zoom(fitted, 0.9)  # 1 / 0.9 wider: still >= 0.7 filled
    assert PanelView("fit").resolve(plane, kept=larger) == larger
    assert PanelView("fit").resolve(plane, kept=None) == fitted
    assert PanelView("image").resolve(plane, kept=larger) is None
    box = ViewBox(10.0, 10.0, 100.0, 75.0)
    assert PanelView("custom", box).resolve(plane, kept=larger) == box
    assert larger.width == pytest.approx(fitted.width / 0.9)


def _shown_view(view, name):
    import xml.etree.ElementTree as ET

    return tuple(float(x) for x in ET.fromstring(view.svgs[name]).get("data-view").split())


def test_a_fitted_panel_holds_its_axes_during_a_drag_and_fits_exactly_at_its_end():
    import types

    import numpy as np

    from egtviz.bench.viewer import _scenes
    from egtviz.viewer.server.headless import start_headless
    from egtviz.viewer.render.panel_view import fit_view

    scene = _scenes(200)["pin-hole"]
    server, _app, fakes, views = start_headless(scene)
    try:
        view = views[0]
        view.dock.view_action("cam2", "fit")  # the panel's "fit" button
        gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
        start = np.array(gizmo.position, float)

        def drag(dx, phase, dy=0.0):
            gizmo._impl.position = start + np.array([dx, dy, 0.0])
            gizmo._impl_aux.last_updated += 1.0
            view.drag.camera_event("cam1", types.SimpleNamespace(target=gizmo, phase=phase, client=None,
                                                                   client_id=None))

        first = _shown_view(view, "cam2")  # the exact fit before the drag
        seen = set()
        for k in range(1, 11):  # 2 mm steps: the fit moves a little at each one, the content stays in view
            drag(0.002 * k, "update")
            plane = view.model.derived.image_planes["cam2"]
            fitted, content = fit_view(plane), fit_view(plane, margin=0.0)
            seen.add((fitted.u0, fitted.width))
            shown = _shown_view(view, "cam2")
            assert shown == first  # the axes hold still ...
            # ... and still show all the content (every point, the epipole).
            assert shown[0] <= content.u0 and shown[1] <= content.v0
            assert shown[0] + shown[2] >= content.u1 and shown[1] + shown[3] >= content.v1
            assert plane.points[plane.visible].min(axis=0)[0] >= shown[0]
        assert len(seen) > 1  # the exact fit did change during the drag
        # A long move takes the content out of the view: a new one, with room, holds the next steps.
        drag(0.02, "update", dy=-1.0)  # e2 moves from u = -1683 px to about -2900 px
        assert fit_view(view.model.derived.image_planes["cam2"], margin=0.0).u0 < first[0]
        moved = _shown_view(view, "cam2")
        assert moved[0] < first[0]
        drag(0.02, "update", dy=-1.002)
        assert _shown_view(view, "cam2") == moved
        drag(0.02, "end")
        fitted = fit_view(view.model.derived.image_planes["cam2"])
        assert _shown_view(view, "cam2") == pytest.approx((fitted.u0, fitted.v0, fitted.width, fitted.height),
                                                          rel=1e-4)
    finally:
        for f in fakes:
            f.close()
        server.stop()
