"""A lesson step's ``set_range`` holds under a gizmo drag: the camera stops at the range's edge.

The drags are sent over the websocket as a browser (or a forging client) sends them: a drag start, pose
updates, a drag end (viser's ``TransformControls*Message``), to a headless server with a lesson panel on the tab.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry.poses import matrix_from_quat_wxyz
from egtviz.lessons import LessonRun, parse_lesson
from egtviz.viewer.server.headless import start_headless
from egtviz.controllers.lesson_rules import pose_within_ranges, range_refusal
from egtviz.viewer.course.lesson_view import LessonPanel

from _waiting import PATIENCE, PATIENCE_MS, wait_for, wait_until  # noqa: E402

# cam1 of the default scene is at (-3, -8, 1.5) with yaw 20.6, pitch -3.3, roll 0 (degrees).
LESSON = """
title = "Ranges under a drag"
summary = "A step that narrows cam1's position, then one that narrows its angles."
prerequisites = []
scene = "default"

[[steps]]
title = "Slide cam1 right"
text = "Drag cam1 to the right, as far as it goes."

[[steps.changes]]
do = "set_range"
camera = "cam1"
field = "position"
low = -8
high = 2

[[steps.tasks]]
id = "right"
kind = "camera_field"
prompt = "Bring cam1 to x between 1.5 and 2."
camera = "cam1"
field = "position"
component = 0
low = 1.5
high = 2

[[steps]]
title = "Turn cam1"
text = "Turn cam1, within 30 degrees."

[[steps.changes]]
do = "set_range"
camera = "cam1"
field = "ypr_deg"
low = -30
high = 30

[[steps.tasks]]
id = "yaw"
kind = "camera_field"
prompt = "Turn cam1 to a yaw between 24 and 30 degrees."
camera = "cam1"
field = "ypr_deg"
component = 0
low = 24
high = 30
"""


@pytest.fixture
def lesson_tab():
    """A headless tab running the lesson above: ``(fake browser tab, its view, its lesson panel)``."""
    server, _app, fakes, (view,) = start_headless()
    try:
        run = LessonRun(parse_lesson(LESSON, source="ranges.toml", name="ranges"), model=view.model)
        panel = LessonPanel(view, run)
        yield fakes[0], view, panel
    finally:
        for f in fakes:
            f.close()
        server.stop()


def drag(fake, view, name: str, poses: list[tuple[np.ndarray, np.ndarray]]) -> None:
    """Drag ``name``'s gizmo through ``poses`` (``(wxyz, position)``) as the browser does: a start, the updates
    50 ms apart (the page's throttle; viser runs each callback in its thread pool), an end."""
    gizmo = view.scene3d.camera_nodes(name)["gizmo"]
    owner = view.client.scene._owner_id
    fake.send("TransformControlsDragStartMessage", name=gizmo.name, owner=owner)
    for wxyz, position in poses:
        time.sleep(0.05)
        fake.send("TransformControlsUpdateMessage", name=gizmo.name, wxyz=[float(v) for v in wxyz],
                  position=[float(v) for v in position], owner=owner)
    time.sleep(0.05)
    fake.send("TransformControlsDragEndMessage", name=gizmo.name, owner=owner)


def spec_pose(spec) -> tuple[np.ndarray, np.ndarray]:
    pose = spec.camera().pose
    return np.array(pose.quat_wxyz), np.array(pose.t)


def test_a_drag_past_a_position_range_stops_the_camera_at_its_edge_and_the_task_passes(lesson_tab):
    fake, view, panel = lesson_tab
    cam1 = view.model.scene.camera("cam1")
    wxyz, _ = spec_pose(cam1)
    assert ("cam1", "position") in panel.run.ranges and cam1.position == (-3.0, -8.0, 1.5)
    # x past the range's high end (2), y past its low end (-8), z inside: stop at the edge, slide along it.
    drag(fake, view, "cam1", [(wxyz, np.array([0.0, -8.5, 1.5])), (wxyz, np.array([9.0, -11.0, 1.0]))])
    gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
    # The gizmo, which the page leaves where the pointer was, is put at the applied pose when the drag ends.
    assert wait_until(lambda: np.allclose(gizmo.position, (2.0, -8.0, 1.0), atol=1e-9)), gizmo.position
    moved = view.model.scene.camera("cam1")
    assert moved.position == (2.0, -8.0, 1.0)
    assert moved.ypr_deg == pytest.approx(cam1.ypr_deg, abs=1e-9)
    assert range_refusal(panel.run) is None
    panel.row("right").button.value = True
    attempt = panel.attempts["right"]
    assert attempt.result.passed, attempt.result.feedback
    assert "must stay between" not in panel.row("right").feedback.content


def test_a_turn_past_a_ypr_range_keeps_the_last_orientation_that_respected_it(lesson_tab):
    fake, view, panel = lesson_tab
    panel.go_to(1)
    cam1 = view.model.scene.camera("cam1")
    assert ("cam1", "ypr_deg") in panel.run.ranges and ("cam1", "position") in panel.run.ranges
    pitch, roll = cam1.ypr_deg[1:]
    inside, _ = spec_pose(dataclasses.replace(cam1, ypr_deg=(27.0, pitch, roll)))
    past, _ = spec_pose(dataclasses.replace(cam1, ypr_deg=(41.0, pitch, roll)))
    # The position still follows (within its range) while the turn past 30 degrees is held back.
    drag(fake, view, "cam1", [(inside, np.array([-3.0, -8.0, 1.5])), (past, np.array([-2.0, -8.0, 1.0]))])
    gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
    assert wait_until(lambda: view.model.scene.camera("cam1").position == (-2.0, -8.0, 1.0))  # the last update
    # Then the end: the gizmo shows yaw 27 degrees again, not 41 (q and -q are the same rotation).
    assert wait_until(lambda: np.isclose(abs(np.dot(gizmo.wxyz, inside)), 1.0, atol=1e-9)), gizmo.wxyz
    turned = view.model.scene.camera("cam1")
    assert turned.ypr_deg == pytest.approx((27.0, pitch, roll), abs=1e-6)
    assert turned.position == (-2.0, -8.0, 1.0)
    panel.row("yaw").button.value = True
    attempt = panel.attempts["yaw"]
    assert attempt.result.passed, attempt.result.feedback


def test_a_pose_the_ranges_allow_is_applied_as_sent(lesson_tab):
    _fake, view, panel = lesson_tab
    panel.go_to(1)
    cam1 = view.model.scene.camera("cam1")
    R = dataclasses.replace(cam1, ypr_deg=(-29.0, 10.0, 5.0)).camera().pose.R
    position, R_out = pose_within_ranges(panel.run, "cam1", np.array([1.0, -7.5, 0.5]), R)
    assert np.array_equal(position, [1.0, -7.5, 0.5]) and R_out is R
    # An angle a rotation matrix gives back a hair past the bound (rounding: 1e-12 here) is inside; 1e-6 is not.
    hair = dataclasses.replace(cam1, ypr_deg=(30.0 + 1e-12, -30.0, 0.0))
    assert hair.ypr_from_world_rotation(hair.camera().pose.R)[0] > 30.0
    edge = hair.camera().pose.R
    assert pose_within_ranges(panel.run, "cam1", np.zeros(3), edge)[1] is edge
    past = dataclasses.replace(cam1, ypr_deg=(30.0 + 1e-6, -30.0, 0.0)).camera().pose.R
    assert pose_within_ranges(panel.run, "cam1", np.zeros(3), past)[1] is not past
    # The guard reads the current step's ranges: back in the first step the angles are free again.
    wide = dataclasses.replace(cam1, ypr_deg=(41.0, 0.0, 0.0)).camera().pose.R
    assert pose_within_ranges(panel.run, "cam1", np.zeros(3), wide)[1] is not wide
    panel.nav.buttons.value = "previous"
    assert panel.run.step_index == 0 and pose_within_ranges(panel.run, "cam1", np.zeros(3), wide)[1] is wide


@pytest.fixture(scope="module")
def first_step_run():
    return LessonRun(parse_lesson(LESSON, source="ranges.toml", name="ranges"))


@settings(max_examples=200, deadline=None)
@given(sent=st.lists(st.floats(-50.0, 50.0), min_size=3, max_size=3))
def test_the_clamped_position_is_the_nearest_point_of_the_range_box(first_step_run, sent):
    # The box [-8, 2]^3 of the lesson's first step. No point of the box (its 8 corners, 64 random points inside)
    # is nearer to the sent point than the applied one, and a point inside is applied as sent.
    run = first_step_run
    R = run.model.scene.camera("cam1").camera().pose.R
    p = np.array(sent)
    got, R_out = pose_within_ranges(run, "cam1", p, R)
    assert R_out is R
    assert np.all((got >= -8.0) & (got <= 2.0))
    corners = np.array([[x, y, z] for x in (-8.0, 2.0) for y in (-8.0, 2.0) for z in (-8.0, 2.0)])
    rng = np.random.default_rng(0)
    inside = rng.uniform(-8.0, 2.0, size=(64, 3))
    others = np.vstack([corners, inside])
    assert np.linalg.norm(got - p) <= np.linalg.norm(others - p, axis=1).min() + 1e-12
    if np.all((p >= -8.0) & (p <= 2.0)):
        assert np.array_equal(got, p)


def _screen(camera, box: dict, X: np.ndarray) -> tuple[float, float]:
    """Where world point ``X`` is on the page: viser's view camera is OpenCV-like (x right, y down, z forward)
    with a vertical field of view ``fov`` over the 3D canvas ``box``."""
    R = matrix_from_quat_wxyz(camera.wxyz)
    x = R.T @ (np.asarray(X, float) - camera.position)
    f = (box["height"] / 2) / np.tan(camera.fov / 2)
    return box["x"] + box["width"] / 2 + f * x[0] / x[2], box["y"] + box["height"] / 2 + f * x[1] / x[2]


def _drag_arrow(page, camera, box: dict, centre: np.ndarray, axis: np.ndarray, distance: float, length: float) -> None:
    """Press the gizmo's arrow along ``axis`` (near its tip) and drag it ``distance`` metres along that axis.

    ``length`` is the arrow's length in metres (the gizmo's scale: the scene's glyph size).
    """
    grip = 0.85 * length  # the arrow's cone, clear of the plane squares and rotation arcs
    page.mouse.move(*_screen(camera, box, centre + grip * axis))
    page.mouse.down()
    for d in np.linspace(grip, grip + distance, 12)[1:]:
        page.mouse.move(*_screen(camera, box, centre + d * axis), steps=2)
        time.sleep(0.05)
    page.mouse.up()


@pytest.mark.browser
def test_in_the_browser_a_dragged_camera_stops_at_the_range_and_its_gizmo_is_put_there():
    import viser

    from egtviz.viewer.tabs import EgtvizApp
    from egtviz.viewer.server.browser import open_viewer, shared_chromium

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    page = None
    try:
        app = EgtvizApp(server)
        # The test process's Chromium (the browser tests' too: playwright runs one instance per thread at a time),
        # without the software-WebGL notification over the 3D view's corner.
        browser = shared_chromium(timeout_ms=PATIENCE_MS, quiet=True)
        page = open_viewer(browser, f"http://127.0.0.1:{server.get_port()}")
        (view,) = app.wait_for_view(timeout=PATIENCE)
        LessonPanel(view, LessonRun(parse_lesson(LESSON, source="ranges.toml", name="ranges"), model=view.model))
        camera = view.client.camera
        # The page reports its view camera once it has moved it: then the arrow's place on screen is known.
        reported = []
        camera.on_update(lambda cam: reported.append((np.array(cam.position), np.array(cam.look_at))))

        def look(position, look_at) -> None:
            """Move the page's view camera and wait until the page reports it there: every message the server sent
            the page before (a gizmo put somewhere, say) has then been handled too (one connection, in order)."""
            reported.clear()
            camera.position, camera.look_at = position, look_at
            wait_for(lambda: any(np.allclose(p, position, atol=1e-3) and np.allclose(a, look_at, atol=1e-3)
                                 for p, a in list(reported)), f"the page to report its view camera at {position}")

        look((-1.0, -14.0, 4.0), (0.0, -8.0, 1.5))  # close to cam1, so its arrow is large on screen
        box = page.evaluate("(() => { const r = [...document.querySelectorAll('canvas')].pop()"
                            ".getBoundingClientRect(); return {x: r.x, y: r.y, width: r.width, height: r.height} })()")
        gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
        R = matrix_from_quat_wxyz(gizmo.wxyz)
        axis = R[:, 0]  # cam1's x axis (image right): mostly world +x, a little -y (yaw 20.6 degrees)
        assert axis[0] > 0.9 and axis[1] < 0
        # 8 m along it would reach x = 4.5 and y = -10.8: the range -8..2 stops cam1 at x = 2, y = -8.
        _drag_arrow(page, camera, box, np.array(gizmo.position), axis, 8.0, gizmo.scale)
        assert wait_until(lambda: view.model.scene.camera("cam1").position[0] == 2.0), "cam1 never stopped at x = 2"
        edge = np.array(view.model.scene.camera("cam1").position)
        assert edge == pytest.approx((2.0, -8.0, 1.5), abs=1e-9)
        # The server puts the gizmo at the edge when the drag ends; the page has it there once it has handled a
        # later message (a view camera a hair higher).
        wait_for(lambda: np.allclose(gizmo.position, edge, atol=1e-9), "the server to put cam1's gizmo at the edge")
        look((-1.0, -14.0, 4.001), (0.0, -8.0, 1.501))
        # The page's gizmo was put at the edge: its arrow is grabbed there and drags cam1 back 1 m.
        _drag_arrow(page, camera, box, edge, axis, -1.0, gizmo.scale)
        assert wait_until(lambda: view.model.scene.camera("cam1").position[0] < 1.5), "cam1 was not dragged back"
        back = np.array(view.model.scene.camera("cam1").position)
        assert back == pytest.approx(edge - axis, abs=0.05)
    finally:
        if page is not None:
            page.close()
        server.stop()
