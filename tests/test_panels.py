"""Panel layout, per-panel views and the first 3D view (egtviz.viewer.render.panels): pure functions, no server."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.scene import SCENES, SceneModel, compute_derived, default_scene
from egtviz.scene.extent import scene_extent
from egtviz.viewer.workbench.app import PRESENT_LABEL_SCALE
from egtviz.viewer.server.headless import FakeTab, start_headless
from egtviz.viewer.render.panel_view import fit_view, image_view
from egtviz.viewer.render.panels import (
    CELL_CHROME_PX,
    CONTROL_PX,
    DEFAULT_WINDOW,
    DIVIDER_PX,
    FLOOR_CANVAS_PX,
    MIN_CANVAS_FRACTION,
    MIN_CANVAS_PX,
    MIN_PANEL_PX,
    PanelView,
    WindowSize,
    dock_plan,
    framed_camera,
    initial_view,
    plan_grid,
    window_from_canvas,
)
from egtviz.viewer.render.svg import NORMAL, PRESENT, panel_layout

from _waiting import PATIENCE, wait_for, wait_until  # noqa: E402


def _cams(n, w=640, h=480):
    return [(f"cam{i + 1}", w, h) for i in range(n)]


# -- the window ----------------------------------------------------------------------------


def test_window_from_canvas_keeps_ordinary_sizes_and_halves_high_density_ones():
    assert window_from_canvas(1366, 768) == WindowSize(1366, 768)
    assert window_from_canvas(1920, 1080) == WindowSize(1920, 1080)
    # A 13" laptop at pixel ratio 2: 2560 x 1500 device pixels is a 1280 x 750 window.
    assert window_from_canvas(2560, 1500) == WindowSize(1280, 750)
    # 2560 x 1300 (a QHD monitor at ratio 1 minus the browser's bars) stays as it is.
    assert window_from_canvas(2560, 1300) == WindowSize(2560, 1300)


@pytest.mark.parametrize("size", [(0, 0), (float("nan"), 768), (1366, float("inf")), ("a", 3), (None, 768)])
def test_window_from_canvas_falls_back_for_sizes_that_are_no_window(size):
    assert window_from_canvas(*size) == DEFAULT_WINDOW


def test_window_size_refuses_non_positive_sizes():
    with pytest.raises(ValueError, match="width and height must be finite CSS pixels > 0"):
        WindowSize(0, 768)


# -- the grid -------------------------------------------------------------------------------


@pytest.mark.parametrize("window", [WindowSize(1366, 768), WindowSize(1920, 1080)])
def test_four_cameras_get_a_two_by_two_grid_of_readable_panels(window):
    grid = plan_grid(_cams(4), window)
    assert [[list(cell) for cell in col] for col in grid.columns] == [[["cam1"], ["cam2"]], [["cam3"], ["cam4"]]]
    assert grid.column_px >= MIN_PANEL_PX
    # The 3D view keeps its share of the window.
    assert grid.canvas_px >= max(MIN_CANVAS_FRACTION * window.width, MIN_CANVAS_PX) - 15


def test_panel_widths_follow_the_window():
    small = plan_grid(_cams(4), WindowSize(1366, 768))
    large = plan_grid(_cams(4), WindowSize(1920, 1080))
    assert large.column_px > 1.4 * small.column_px


def test_two_cameras_stack_in_one_column_as_wide_as_the_height_allows():
    grid = plan_grid(_cams(2), WindowSize(1600, 900))
    assert grid.columns == ((("cam1",), ("cam2",)),)
    # The SVG at that width (4:3 view, two status rows) just fits half the window less the tab strip.
    view = image_view(compute_derived(default_scene()).image_planes["cam1"])
    h = panel_layout(view, NORMAL, grid.column_px, 2).height_px
    assert h <= 450 - CELL_CHROME_PX
    assert panel_layout(view, NORMAL, grid.column_px + 10, 2).height_px > 450 - CELL_CHROME_PX


def test_a_window_too_small_for_a_grid_gets_tabs():
    # Presentation mode at 1366 x 768: two columns of 300 px do not fit beside the wider controls.
    grid = plan_grid(_cams(4), WindowSize(1366, 768), style=PRESENT)
    assert grid.control_px == CONTROL_PX["present"]
    assert len(grid.columns) == 1
    assert grid.cells == (("cam1", "cam2"), ("cam3", "cam4"))
    assert grid.column_px >= MIN_PANEL_PX


def test_a_small_window_gets_one_panel_of_tabs_at_least_300_px_wide():
    # 800 x 600: the controls (330) and a 3D view of 360 leave 110 px; the 3D view gives way to 160 px instead.
    grid = plan_grid(_cams(4), WindowSize(800, 600))
    assert grid.cells == (("cam1", "cam2", "cam3", "cam4"),)
    assert grid.column_px == MIN_PANEL_PX
    assert grid.canvas_px == pytest.approx(800 - 330 - 300 - 2 * DIVIDER_PX)


def test_no_cameras_no_columns():
    grid = plan_grid([], WindowSize(1366, 768))
    assert grid.columns == () and grid.right_px == 0


@settings(max_examples=60, deadline=None)
@given(w=st.floats(800, 3000), h=st.floats(500, 1800), n=st.integers(1, 9),
       present=st.booleans(), aspect=st.sampled_from([(640, 480), (2, 2), (1920, 1080), (480, 640)]))
def test_grid_properties(w, h, n, present, aspect):
    style = PRESENT if present else NORMAL
    window = WindowSize(w, h)
    grid = plan_grid(_cams(n, *aspect), window, style=style)
    names = [name for cell in grid.cells for name in cell]
    assert sorted(names) == sorted(c[0] for c in _cams(n))  # every camera exactly once
    # Each panel's SVG fits its cell: no scrolling.
    view = image_view(type("P", (), {"width": aspect[0], "height": aspect[1]})())
    for col in grid.columns:
        cell_h = h / len(col) - CELL_CHROME_PX
        assert panel_layout.__wrapped__(view, style, grid.column_px, 2).height_px <= cell_h + 1e-6 or grid.column_px <= 61
    dividers = DIVIDER_PX * (len(grid.columns) + 1)
    assert grid.canvas_px >= FLOOR_CANVAS_PX - dividers - 1e-9
    if len(grid.cells) > 1:  # a real grid keeps the 3D view's share; only a lone panel of tabs may take more
        assert grid.canvas_px >= max(MIN_CANVAS_FRACTION * w, MIN_CANVAS_PX) - dividers - 1e-9


def test_rows_and_max_height():
    grid = plan_grid(_cams(3), WindowSize(1920, 1080))
    assert grid.rows("cam1") == len(grid.columns[0])
    assert grid.svg_max_height_px("cam1") == pytest.approx(1080 / grid.rows("cam1") - CELL_CHROME_PX)
    with pytest.raises(KeyError, match="no camera 'nope'"):
        grid.rows("nope")


# -- what a panel shows ------------------------------------------------------------------


def _plane(name, camera):
    return compute_derived(SCENES[name]()).image_planes[camera]


@pytest.mark.parametrize(("scene", "camera", "mode"), [
    ("default", "cam1", "image"),       # 640 x 480, every point inside
    ("example1", "cam", "fit"),        # K = I: a 2 x 2 image
    ("example3", "cam2", "fit"),
    ("panoramic", "pano1", "image"),
])
def test_initial_view(scene, camera, mode):
    assert initial_view(_plane(scene, camera)) == mode


def test_a_visible_point_outside_the_image_starts_in_fit():
    scene = default_scene()
    moved = scene.replace(points=tuple(scene.points) + ((30.0, 10.0, 1.0),))
    plane = compute_derived(moved).image_planes["cam1"]
    assert bool(np.any(np.asarray(plane.visible) & ~np.asarray(plane.in_image)))
    assert initial_view(plane) == "fit"


def test_fit_follows_the_content_and_image_is_the_rectangle():
    plane = _plane("example3", "cam1")
    assert PanelView("fit").resolve(plane) == fit_view(plane)
    assert PanelView("image").resolve(plane) is None
    # Every point of the tutorial's example is inside the fitted view.
    assert fit_view(plane).contains(plane.points).all()


def test_zoom_and_pan_buttons():
    plane = _plane("default", "cam1")  # 640 x 480
    zoomed = PanelView("image").after("+", plane)
    assert zoomed.mode == "custom"
    # Zoom 1.25 about the centre (320, 240): width 640 / 1.25 = 512, left edge 320 - 256 = 64.
    assert (zoomed.box.u0, zoomed.box.v0, zoomed.box.width, zoomed.box.height) == pytest.approx((64, 48, 512, 384))
    # "left" shows what lies to the left: the view moves by 0.2 of its width, 512 * 0.2 = 102.4.
    moved = zoomed.after("left", plane)
    assert moved.box.u0 == pytest.approx(64 - 102.4) and moved.box.width == pytest.approx(512)
    down = moved.after("down", plane)
    assert down.box.v0 == pytest.approx(48 + 0.2 * 384)
    back = down.after("-", plane)
    assert back.box.width == pytest.approx(640) and back.box.centre == pytest.approx(down.box.centre)
    assert back.after("fit", plane) == PanelView("fit")
    assert back.after("image", plane) == PanelView("image")


def test_zoom_starts_from_the_fitted_view():
    plane = _plane("example3", "cam1")
    fitted = fit_view(plane)
    zoomed = PanelView("fit").after("+", plane)
    assert zoomed.box.width == pytest.approx(fitted.width / 1.25)
    assert zoomed.box.centre == pytest.approx(fitted.centre)


def test_panel_view_refuses_bad_input():
    plane = _plane("default", "cam1")
    with pytest.raises(ValueError, match="view action: expected one of"):
        PanelView().after("rotate", plane)
    with pytest.raises(ValueError, match="mode: expected 'fit', 'image' or 'custom'"):
        PanelView("zoomed")
    with pytest.raises(ValueError, match="a box is given exactly when mode is 'custom'"):
        PanelView("custom")


# -- the first 3D view -----------------------------------------------------------------------


def test_framed_camera_by_hand():
    # One point: its padded extent (1.25 * 1 m) is under the minimum 1.25 * 3 m, seen from 3.75 / tan(a):
    # tan(30 deg) = 0.57735 in a wide canvas (2:1, the vertical angle binds): 6.495 m; in a 1:2 canvas the
    # horizontal half-angle has tan(a_h) = 0.57735 * 0.5 = 0.28868: 12.990 m.
    wide = framed_camera([[0, 0, 0]], 2.0)
    narrow = framed_camera([[0, 0, 0]], 0.5)
    assert np.linalg.norm(wide.position) == pytest.approx(3.75 / math.tan(math.pi / 6))
    assert np.linalg.norm(wide.position) == pytest.approx(6.495, abs=1e-3)
    assert np.linalg.norm(narrow.position) == pytest.approx(12.990, abs=1e-3)
    assert wide.look_at == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="canvas_aspect must be a finite number > 0"):
        framed_camera([[0, 0, 0]], 0.0)


def test_framed_camera_is_as_close_as_the_margin_allows():
    """Two points 20 m apart: the outermost padded point touches the canvas edge grown by the margin."""
    pts = np.array([[-10.0, 0, 0], [10.0, 0, 0]])
    for aspect in (0.5, 1.0, 2.0):
        cam = framed_camera(pts, aspect)
        c, t = np.array(cam.position), np.array(cam.look_at)
        forward = (t - c) / np.linalg.norm(t - c)
        right = np.cross(forward, [0, 0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        d = pts - c
        z = d @ forward
        tan_v = math.tan(cam.fov / 2)
        use = np.maximum(1.25 * (np.abs(d @ right) + 1) / (z * tan_v * aspect),
                         1.25 * (np.abs(d @ up) + 1) / (z * tan_v))
        assert use.max() == pytest.approx(1.0)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), aspect=st.floats(0.3, 3.0), n=st.integers(1, 30))
def test_framed_camera_sees_every_point(seed, aspect, n):
    """Project the points with the framed view (a pin-hole looking at the target, z up): all inside the canvas."""
    rng = np.random.default_rng(seed)
    P = rng.uniform(-8, 8, size=(n, 3)) * rng.uniform(0.1, 1.0, size=3)
    cam = framed_camera(P, aspect)
    c, t = np.array(cam.position), np.array(cam.look_at)
    forward = (t - c) / np.linalg.norm(t - c)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = P - c
    z = d @ forward
    assert (z > 0).all()
    tan_v = math.tan(cam.fov / 2)
    assert (np.abs(d @ up / z) <= tan_v + 1e-9).all()
    assert (np.abs(d @ right / z) <= tan_v * aspect + 1e-9).all()


def test_dock_plan_halves_the_column():
    assert dock_plan(1) == ([(0, None)], [1.0])
    assert dock_plan(2) == ([(0, None), (1, 0)], [0.5, 0.5])
    steps, shares = dock_plan(4)
    assert steps == [(0, None), (2, 0), (1, 0), (3, 2)] and shares == [0.25] * 4
    assert dock_plan(3)[1] == [0.25, 0.25, 0.5]
    with pytest.raises(ValueError, match="rows must be >= 1"):
        dock_plan(0)


# -- the app: a tab's panels, buttons, downloads and presentation mode (raw websocket tab, no browser) ------


def _svg_root(svg):
    return ET.fromstring(svg)


def _view_box(svg):
    return tuple(float(x) for x in _svg_root(svg).get("data-view").split())


@pytest.fixture
def four_camera_tab():
    m = SceneModel(default_scene())
    m.add_camera("pinhole")
    m.add_camera("pinhole")
    server, _app, fakes, views = start_headless(m.scene)
    yield views[0], fakes[0]
    server.stop()


def test_the_fake_tab_window_gives_the_grid(four_camera_tab):
    view, _ = four_camera_tab
    # The raw tab reports a 1280 x 720 canvas: two columns of 300 px do not fit beside the controls and a 3D
    # view of 30 %, so the four cameras are tabs of two panels in one column.
    assert view.grid.window == WindowSize(1280, 720)
    assert view.grid == plan_grid([(c.name, c.width, c.height) for c in view.model.scene.cameras],
                                  WindowSize(1280, 720))
    assert view.grid.columns == ((("cam1", "cam2"), ("cam3", "cam4")),)
    assert view.grid.column_px >= MIN_PANEL_PX
    # Each SVG is drawn for its column's width: its viewBox spans column_px CSS pixels at the style's scale.
    for name, svg in view.svgs.items():
        root = _svg_root(svg)
        assert root.get("data-style") == "normal"
        assert f"max-height:{view.grid.svg_max_height_px(name):.0f}px" in root.get("style")


def test_view_buttons_zoom_pan_and_fit(four_camera_tab):
    view, fake = four_camera_tab
    group = view.panel_buttons["cam1"]["panel view"]
    assert _view_box(view.svgs["cam1"]) == (0, 0, 640, 480)
    fake.send("GuiUpdateMessage", uuid=group._impl.uuid, updates={"value": "+"})
    assert wait_until(lambda: _view_box(view.svgs["cam1"])[2] == pytest.approx(512))
    # The same button again: zoomed twice (viser fires a button group on every click).
    fake.send("GuiUpdateMessage", uuid=group._impl.uuid, updates={"value": "+"})
    assert wait_until(lambda: _view_box(view.svgs["cam1"])[2] == pytest.approx(409.6))
    pan_group = view.panel_buttons["cam1"]["panel pan"]
    u0 = _view_box(view.svgs["cam1"])[0]
    fake.send("GuiUpdateMessage", uuid=pan_group._impl.uuid, updates={"value": "\u2192"})
    assert wait_until(lambda: _view_box(view.svgs["cam1"])[0] == pytest.approx(u0 + 0.2 * 409.6))
    fake.send("GuiUpdateMessage", uuid=group._impl.uuid, updates={"value": "fit"})
    plane = view.model.derived.image_planes["cam1"]
    fitted = fit_view(plane)
    assert wait_until(lambda: _view_box(view.svgs["cam1"]) == pytest.approx((fitted.u0, fitted.v0, fitted.width,
                                                                        fitted.height), rel=1e-4))
    # Other panels keep their view.
    assert _view_box(view.svgs["cam2"]) == (0, 0, 640, 480)


def test_a_forged_view_button_is_refused(four_camera_tab):
    view, fake = four_camera_tab
    notes = []
    view.client.add_notification = lambda title, body, **kw: notes.append((title, body))
    fake.send("GuiUpdateMessage", uuid=view.panel_buttons["cam2"]["panel view"]._impl.uuid,
              updates={"value": "rotate"})
    assert wait_until(lambda: notes)
    assert "cam2: no view button 'rotate'" in notes[0][1]
    assert _view_box(view.svgs["cam2"]) == (0, 0, 640, 480)


def test_downloads_send_the_panel_as_shown(four_camera_tab):
    view, fake = four_camera_tab
    sent = []
    view.client.send_file_download = lambda name, data, **kw: sent.append((name, data))
    fake.send("GuiUpdateMessage", uuid=view.panel_buttons["cam1"]["panel view"]._impl.uuid, updates={"value": "+"})
    assert wait_until(lambda: _view_box(view.svgs["cam1"])[2] == pytest.approx(512))
    uuid = view.panel_buttons["cam1"]["download panel"]._impl.uuid
    # One click at a time: viser's event carries the handle, whose value a second click would already have changed.
    fake.send("GuiUpdateMessage", uuid=uuid, updates={"value": "SVG"})
    wait_for(lambda: len(sent) == 1, "the SVG download")
    fake.send("GuiUpdateMessage", uuid=uuid, updates={"value": "PNG"})
    wait_for(lambda: len(sent) == 2, "the PNG download (rendered by a worker process)")
    files = dict(sent)
    assert set(files) == {"cam1-image-plane.svg", "cam1-image-plane.png"}
    svg, png = files["cam1-image-plane.svg"], files["cam1-image-plane.png"]
    root = ET.fromstring(svg)
    assert root.get("data-camera") == "cam1" and _view_box(svg.decode()) == pytest.approx((64, 48, 512, 384))
    assert len(root.findall(".//*[@data-kind='point']")) == 8
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    # PNG size: the figure's CSS width (the normal style's 480 px) at 2 device pixels per CSS pixel.
    width = int.from_bytes(png[16:20], "big")
    assert width == 2 * int(NORMAL.panel_px)


def test_presentation_mode_toggle(four_camera_tab):
    view, fake = four_camera_tab
    normal_grid = view.grid
    fake.send("GuiUpdateMessage", uuid=view.present_checkbox._impl.uuid, updates={"value": True})
    assert wait_until(lambda: all(_svg_root(s).get("data-style") == "present" for s in view.svgs.values()))
    assert view.present and view.grid.control_px == CONTROL_PX["present"] and view.grid != normal_grid
    assert "--mantine-scale" in view.dock.gui_style.content
    # The 3D view's labels grow too: every camera name and point number.
    labels = view.scene3d._labels
    assert len(labels) >= 4 + 8 and all(h.font_screen_scale == pytest.approx(size * PRESENT_LABEL_SCALE)
                                        for h, size in labels.values())
    fake.send("GuiUpdateMessage", uuid=view.present_checkbox._impl.uuid, updates={"value": False})
    assert wait_until(lambda: all(_svg_root(s).get("data-style") == "normal" for s in view.svgs.values()))
    assert view.grid == normal_grid and view.dock.gui_style.content == ""
    assert all(h.font_screen_scale == pytest.approx(size) for h, size in labels.values())


def test_present_option_starts_every_tab_in_presentation_mode():
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        app = EgtvizApp(server, default_scene(), field_delay=0.0, present=True)
        fake = FakeTab(server.get_port())
        (view,) = app.wait_for_view(timeout=PATIENCE)
        assert view.present and view.present_checkbox.value is True
        assert all(_svg_root(s).get("data-style") == "present" for s in view.svgs.values())
        fake.close()
    finally:
        server.stop()


def test_tiny_tutorial_images_start_fitted():
    server, _app, _fakes, views = start_headless(SCENES["example3"]())
    try:
        view = views[0]
        for name in ("cam1", "cam2"):
            plane = view.model.derived.image_planes[name]
            box = fit_view(plane)
            assert _view_box(view.svgs[name]) == pytest.approx((box.u0, box.v0, box.width, box.height), rel=1e-4, abs=1e-5)
            # Every point the tutorial prints is drawn (outside the 2 x 2 image, inside the view).
            root = _svg_root(view.svgs[name])
            assert len(root.findall(".//*[@data-kind='point-outside']")) == 2
    finally:
        server.stop()


def test_the_first_3d_view_frames_the_scene_in_the_free_canvas(four_camera_tab):
    view, _ = four_camera_tab
    # What the scene holds, with a glyph's room around it (gizmos are drawn at the scene's size).
    extent = scene_extent(view.model.scene, view.model.derived)
    expected = framed_camera(extent.points, view.grid.canvas_px / view.grid.window.height, pad=extent.glyph,
                             min_radius=3.0 * extent.glyph)
    assert view.client.camera.look_at == pytest.approx(expected.look_at)
    assert view.client.camera.position == pytest.approx(expected.position)


def test_serve_present_option_reaches_the_app():
    from egtviz.cli import build_parser
    from egtviz.viewer.server.launch import start

    assert build_parser("serve").parse_args(["serve", "--present"]).present is True
    assert build_parser("serve").parse_args(["serve"]).present is False
    server, app = start("127.0.0.1", 0, present=True)
    try:
        assert app.present is True
    finally:
        server.stop()


def test_fit_panels_to_the_window_uses_the_canvas_and_the_docks(four_camera_tab):
    view, fake = four_camera_tab
    grid = view.grid
    docked = grid.control_px + grid.right_px + 5.0 * (len(grid.columns) + 1)
    # The window grew: the tab now reports a 1400 x 1000 canvas beside the docks.
    fake.send("ViewerCameraMessage", wxyz=[1.0, 0.0, 0.0, 0.0], position=[0.0, -10.0, 3.0], fov=1.0, near=0.01,
              far=1000.0, image_height=1000, image_width=1400, look_at=[0.0, 0.0, 0.0], up_direction=[0.0, 0.0, 1.0])
    assert wait_until(lambda: view.client.camera.image_width == 1400)
    fake.send("GuiUpdateMessage", uuid=view.dock.btn_relayout._impl.uuid, updates={"value": True})
    assert wait_until(lambda: view.grid.window == WindowSize(1400 + docked, 1000))
    assert view.grid == plan_grid([(c.name, c.width, c.height) for c in view.model.scene.cameras],
                                  WindowSize(1400 + docked, 1000))
    assert [len(col) for col in view.grid.columns] == [2, 2]  # room for a grid now
