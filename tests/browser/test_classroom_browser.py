"""The classroom in headless Chromium: an instructor and students, each in their own browser context.

The instructor's link holds the token (none, wrong, right); students join by name and follow the instructor's
scene: a follower's panels are the instructor's SVG, byte for byte, after the instructor drags a camera, and a
follower's own drag is refused. Release, lock, pause, the roster and the histogram are checked on what the pages
show.
"""

from __future__ import annotations

import re
import time
import types

import numpy as np
import pytest

from _waiting import PATIENCE
from egtviz.classroom import Classroom, Mode
from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom import ClassroomHost, instructor_url
from egtviz.viewer.server.browser import folder_field
from egtviz.viewer.server.viser_adapter import gizmo_moved_by_client
from egtviz.viewer.workbench.fields import safe_callback

pytestmark = pytest.mark.browser

WINDOW = {"width": 1366, "height": 768}
REV_JS = """(camera) => document.querySelector(`svg[data-egtviz="image-plane"][data-camera="${camera}"]`)?.dataset.rev"""
PANEL_JS = """(camera) => { const s = document.querySelector(
  `svg[data-egtviz="image-plane"][data-camera="${camera}"]`); return s ? s.outerHTML : null; }"""


def _serve(tmp_path, room=None):
    import viser

    from egtviz.viewer.server.guard import install_guards
    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    install_guards(server)
    app = EgtvizApp(server, None, field_delay=0.0, course=True, progress=ProgressStore(tmp_path / "progress.db"))
    base = f"http://127.0.0.1:{server.get_port()}"
    host = ClassroomHost(app, room, student_url=base)
    return server, app, host, base


def _wait(predicate, timeout=PATIENCE, what="condition", on_fail=None):
    """``predicate()``'s first truthy value, polled until ``timeout`` seconds have passed."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    value = predicate()
    if value:
        return value
    raise AssertionError(f"waited {timeout:.0f} s for {what}" + (f": {on_fail()}" if on_fail is not None else ""))


def _instructor(browser, base, token):
    context = browser.new_context(viewport=WINDOW)
    page = context.new_page()
    page.goto(instructor_url(base, token))
    return context, page


def _join(browser, host, base, name):
    """A new context's tab on ``base`` that joins the class of ``host`` as ``name``."""
    context = browser.new_context(viewport=WINDOW)
    page = context.new_page()
    page.goto(base)
    page.wait_for_selector("text=Join the class")
    page.locator('xpath=//label[normalize-space(.)="your name"]/following::input[1]').first.fill(name)
    page.get_by_role("button", name="Join").click()
    page.wait_for_selector('[data-egtviz="student-bar"]')
    return context, page


def _typed(values, text, what):
    """Wait until ``text`` is among ``values()`` (the server's values of a GUI field, as the tabs typed them)."""
    _wait(lambda: text in values(), what=what)


def _instructor_panel(room):
    """The server's instructor panel of the room's instructor tab (rebuilt whenever the tab is cleared)."""
    return room.host.panels[room.view.client.client_id]


def _field(page, label):
    """The input of the GUI field labelled ``label`` (a text box or a checkbox)."""
    return page.locator(f'xpath=//label[normalize-space(.)="{label}"]/following::input[1]').first


def _open_folder(page, title, inside):
    """Open the GUI folder ``title`` unless ``inside`` (a locator in it) is already visible."""
    if not inside.is_visible():
        page.get_by_text(title, exact=True).first.click()
    inside.wait_for(state="visible")


def _drag(view, name, dx):
    """Drag camera ``name`` of a workbench view by ``dx`` metres along x, as viser delivers a gizmo message."""
    gizmo = view.scene3d.gizmo(name)
    position = np.array(gizmo.position, float) + np.array([dx, 0.0, 0.0])
    gizmo_moved_by_client(gizmo, position)
    view.drag.camera_event(name, types.SimpleNamespace(target=gizmo, phase="update", client=None, client_id=None))


@pytest.fixture(scope="module")
def room(browser, tmp_path_factory):
    server, app, host, base = _serve(tmp_path_factory.mktemp("classroom"))
    ctx, page = _instructor(browser, base, host.room.instructor_token)
    page.wait_for_selector("text=follow me")
    instructor = _wait(lambda: next(iter(app.views.values()), None), what="the instructor's workbench")
    yield types.SimpleNamespace(server=server, app=app, host=host, base=base, page=page, view=instructor)
    ctx.close()
    host.close()
    server.stop()


def test_the_token_decides_who_is_the_instructor(browser, tmp_path):
    now = [0.0]
    room = Classroom(token="t" * 8 + "right-token-0123", clock=lambda: now[0])
    server, app, host, base = _serve(tmp_path, room)
    try:
        # No token: a student's page (asks a name), no instructor panel.
        ctx, page = browser.new_context(viewport=WINDOW), None
        page = ctx.new_page()
        page.goto(base)
        page.wait_for_selector("text=Join the class")
        assert page.locator("text=follow me").count() == 0
        ctx.close()
        # A wrong token: refused, with no detail, and no instructor powers.
        ctx, page = _instructor(browser, base, "wrong-token-wrong-token")
        page.wait_for_selector('[data-egtviz="refused"]')
        assert page.locator('[data-egtviz="refused"]').inner_text().strip() == "This link is not valid."
        assert page.locator("text=follow me").count() == 0 and not room.instructor_present()
        ctx.close()
        # The right token: the instructor's panel.
        ctx, page = _instructor(browser, base, room.instructor_token)
        page.wait_for_selector("text=follow me")
        _wait(room.instructor_present, what="the instructor's tab")
        ctx.close()
        # Rate limited: after five wrong tries from this address even the right token is refused, for a while.
        for _ in range(5):
            assert not room.check_token("another-wrong-token-x", "127.0.0.1")
        ctx, page = _instructor(browser, base, room.instructor_token)
        page.wait_for_selector('[data-egtviz="refused"]')
        ctx.close()
        now[0] += 3600.0
        ctx, page = _instructor(browser, base, room.instructor_token)
        page.wait_for_selector("text=follow me")
        ctx.close()
    finally:
        host.close()
        server.stop()


def test_a_follower_shows_the_instructors_panels_and_cannot_change_them(browser, room):
    host_room = room.host.room
    host_room.set_mode(Mode.FOLLOW)
    ctx, page = _join(browser, room.host, room.base, "Ada")
    try:
        cid = _wait(lambda: next((c for c in room.host.followers), None), what="a follower")
        follower = room.host.followers[cid]
        _drag(room.view, "cam1", 0.4)
        want = room.view.svgs["cam1"]
        _wait(lambda: follower.frame is not None and follower._shown.get("cam1") is want, what="the new frame")
        for camera in ("cam1", "cam2"):
            _wait(lambda c=camera: page.evaluate(PANEL_JS, c) == room.page.evaluate(PANEL_JS, c),
                  what=f"{camera}'s panel equal in both tabs")
        moved = float(room.view.model.scene.camera("cam1").position[0])
        # The follower's drag is refused: the tab says why, the room's scene and the panels stay as they were.
        gizmo = follower.scene3d.gizmo("cam1")
        gizmo_moved_by_client(gizmo, np.array(gizmo.position, float) + 1.0)
        safe_callback(lambda e: follower.camera_event("cam1", e), follower.report)(
            types.SimpleNamespace(target=gizmo, phase="update", client=None, client_id=None))
        page.wait_for_selector("text=Following the instructor")
        assert float(room.view.model.scene.camera("cam1").position[0]) == moved
        assert np.allclose(gizmo.position, room.view.model.scene.camera("cam1").position)
        assert page.evaluate(PANEL_JS, "cam1") == room.page.evaluate(PANEL_JS, "cam1")
        # Locked: the follower's view camera goes where the instructor's is, and back there if it turns away.
        _field(room.page, "lock students' cameras").click()
        room.view.client.camera.position = (-8.0, -6.0, 4.0)
        room.view.client.camera.look_at = (0.0, 0.0, 1.0)
        _wait(lambda: np.allclose(follower.client.camera.position, (-8.0, -6.0, 4.0), atol=1e-3),
              what="the follower's camera at the instructor's")
        follower.client.camera.position = (3.0, 3.0, 9.0)  # as if the student turned their view
        _wait(lambda: np.allclose(follower.client.camera.position, (-8.0, -6.0, 4.0), atol=1e-3),
              what="the follower's camera put back")
        _field(room.page, "lock students' cameras").click()
        _wait(lambda: not host_room.cameras_locked, what="unlocked")
        # Released: the student's own scene, no longer the instructor's.
        room.page.get_by_role("button", name="explore").click()
        _wait(lambda: _bar(page) == "false" and cid not in room.host.followers, what="released")
        own = _wait(lambda: room.app.views.get(cid), what="the student's own workbench")
        _drag(room.view, "cam1", 0.2)  # handled at once (the drag's callback, here): the models are as it left them
        assert own.model.scene is not room.view.model.scene
        assert own.model.scene.camera("cam1").position[0] != room.view.model.scene.camera("cam1").position[0]
    finally:
        room.host.room.set_mode(Mode.FOLLOW)
        ctx.close()


def _rev_of(view, camera):
    """The revision of the panel the server last drew for ``view``'s tab (read under the view's lock: not in the
    middle of a redraw)."""
    with view.lock:
        return re.search(r'data-rev="([^"]*)"', view.svgs[camera]).group(1)


def _bar(page):
    return page.locator('[data-egtviz="student-bar"]').first.get_attribute("data-following")


def test_release_lock_and_rejoin_with_three_tabs(browser, room):
    host = room.host
    host.room.set_mode(Mode.FOLLOW)
    (c1, p1), (c2, p2) = _join(browser, room.host, room.base, "Bea"), _join(browser, room.host, room.base, "Cy")
    try:
        _wait(lambda: len(host.followers) >= 2, what="two followers")
        # Released: each student works on their own scene; the instructor's drags no longer reach them.
        room.page.get_by_role("button", name="explore").click()  # the instructor's "release to" button
        _wait(lambda: _bar(p1) == "false" and _bar(p2) == "false", what="both released")
        _wait(lambda: len(host.followers) == 0, what="no follower")
        own = {cid: v for cid, v in room.app.views.items() if v is not room.view}
        assert len(own) == 2
        # Their workbench is laid out for the whole window (not the canvas the follow view's controls left):
        # both image planes side by side in view, as in the instructor's tab of the same size.
        for v in own.values():
            assert v.window[0] == room.view.window[0] and v.grid.columns == room.view.grid.columns
        before = [p.evaluate(PANEL_JS, "cam1") for p in (p1, p2)]
        frame = host.sender.latest
        _drag(room.view, "cam1", 0.3)
        # The drag was handled (the instructor's own tab shows it), and it made no frame for the room: the students'
        # panels stay as they were.
        _wait(lambda: room.page.evaluate(REV_JS, "cam1") == _rev_of(room.view, "cam1"),
              what="the instructor's tab to show the drag")
        assert host.sender.latest is frame
        assert [p.evaluate(PANEL_JS, "cam1") for p in (p1, p2)] == before
        # One student's own drag changes their panel only.
        a, b = own.values()
        _drag(a, "cam1", -0.5)
        _wait(lambda: a.model.scene.camera("cam1").position[0] != b.model.scene.camera("cam1").position[0],
              what="one student's own scene to move")
        # Follow me again: both follow, and show the instructor's panels.
        _field(room.page, "follow me").click()
        _wait(lambda: _bar(p1) == "true" and _bar(p2) == "true", what="both following")
        for p in (p1, p2):
            _wait(lambda p=p: p.evaluate(PANEL_JS, "cam1") == room.page.evaluate(PANEL_JS, "cam1"),
                  what="the instructor's panel")
        # Locked cameras: the followers' view cameras go where the instructor's is.
        _field(room.page, "lock students' cameras").click()
        _wait(lambda: host.room.cameras_locked, what="cameras locked from the panel")
        room.view.client.camera.position = (9.0, -7.0, 5.0)
        room.view.client.camera.look_at = (0.0, 0.0, 1.0)
        for v in list(host.followers.values()):
            _wait(lambda v=v: np.allclose(v.client.camera.position, (9.0, -7.0, 5.0), atol=1e-3),
                  what="a follower's camera at the instructor's")
        _field(room.page, "lock students' cameras").click()
        _wait(lambda: not host.room.cameras_locked, what="cameras unlocked from the panel")
        # A student leaves follow with their button, and comes back to it.
        p1.get_by_role("button", name="Leave follow (my own scene)").click()
        _wait(lambda: _bar(p1) == "false", what="left follow")
        assert _bar(p2) == "true"
        p1.get_by_role("button", name="Follow the instructor").click()
        _wait(lambda: _bar(p1) == "true", what="following again")
    finally:
        c1.close()
        c2.close()


def _drag_to_end(view, name, dx):
    """A whole gizmo drag of camera ``name`` by ``dx`` metres along x: its updates, then its end."""
    _drag(view, name, dx)
    gizmo = view.scene3d.gizmo(name)
    try:
        view.drag.camera_event(name, types.SimpleNamespace(target=gizmo, phase="end", client=None, client_id=None))
    except Exception:  # noqa: BLE001 - a locked camera's drag ends refused: the camera stays
        pass


def test_the_class_lock_holds_a_released_students_own_cameras_until_unlocked(browser, room):
    host = room.host
    host.room.set_mode(Mode.EXPLORE)
    ctx, page = _join(browser, room.host, room.base, "Gil")
    try:
        cid = _wait(lambda: host.student_tabs().get("Gil"), what="Gil's tab")
        view = _wait(lambda: room.app.views.get(cid), what="Gil's own workbench")
        page.wait_for_selector('svg[data-egtviz="image-plane"][data-camera="cam1"]')
        _field(room.page, "lock students' cameras").click()
        _wait(lambda: host.room.cameras_locked, what="cameras locked from the panel")
        _wait(lambda: set(view.model.scene.camera_names) <= view.model.scene.locked, what="Gil's cameras locked")
        page.get_by_text("The instructor has locked the cameras").first.wait_for()
        # The lock's own redraw shown: the page's panel is the one the server last drew for Gil's tab.
        _wait(lambda: page.evaluate(REV_JS, "cam1") == _rev_of(view, "cam1"), what="Gil's panel redrawn as locked")
        where, panel = tuple(view.model.scene.camera("cam1").position), page.evaluate(PANEL_JS, "cam1")
        # A gizmo drag (as the browser sends it) and a typed position are both refused.
        _drag_to_end(view, "cam1", 0.8)
        field = folder_field(page, "cam1 (pin-hole)", "position x, y, z (m)")
        field.click()
        field.fill("1.5, -6, 2")
        field.press("Enter")
        # The typed position judged, and refused: the tab says why.
        page.get_by_text("the camera is locked").first.wait_for()
        assert tuple(view.model.scene.camera("cam1").position) == where
        assert page.evaluate(PANEL_JS, "cam1") == panel
        # Unlocked: the same drag moves the camera, and the panel shows it.
        _field(room.page, "lock students' cameras").click()
        _wait(lambda: not host.room.cameras_locked, what="cameras unlocked from the panel")
        _wait(lambda: not view.model.scene.locked, what="Gil's cameras unlocked")
        _drag_to_end(view, "cam1", 0.8)
        _wait(lambda: abs(view.model.scene.camera("cam1").position[0] - (where[0] + 0.8)) < 1e-9,
              what="the drag to move Gil's camera")
        _wait(lambda: page.evaluate(PANEL_JS, "cam1") != panel, what="Gil's panel to show the move")
    finally:
        if host.room.cameras_locked:
            host.room.lock_cameras(False)
        host.room.set_mode(Mode.FOLLOW)
        ctx.close()


def test_roster_histogram_and_pause_in_the_instructors_panel(browser, room):
    host = room.host
    host.room.set_mode(Mode.FOLLOW)
    (c1, p1) = _join(browser, room.host, room.base, "<b>Dee</b>")
    (c2, p2) = _join(browser, room.host, room.base, "Eve <i>x</i>")
    try:
        tabs = _wait(lambda: (t := host.student_tabs()) and len(t) >= 2 and t, what="two students")
        host.room.ask("Where is e1 (u, in px)?")
        for p in (p1, p2):
            p.wait_for_selector('[data-egtviz="question"]')
        host.room.record_answer(tabs["<b>Dee</b>"], "Where is e1 (u, in px)?", 120.0)
        host.room.record_answer(tabs["Eve <i>x</i>"], "Where is e1 (u, in px)?", 120.0)
        page = room.page
        _open_folder(page, "Students", page.locator('[data-egtviz="roster"]').first)
        _wait(lambda: page.locator('[data-egtviz="histogram"]').first.get_attribute("data-n") == "2",
              what="two answers in the histogram")
        counts = [int(c) for c in page.locator('[data-egtviz="histogram"] [data-kind="bar"]').evaluate_all(
            "els => els.map(e => e.dataset.count)")]
        assert sorted(counts, reverse=True)[0] == 2 and sum(counts) == 2
        hist_text = page.locator('[data-egtviz="histogram"]').first.inner_text()
        assert "Dee" not in hist_text and "Eve" not in hist_text  # names hidden by default
        _field(page, "show names").click()
        page.wait_for_selector('[data-egtviz="answers-by-name"]')
        items = page.locator('[data-egtviz="answers-by-name"] li').all_inner_texts()
        assert items == ["<b>Dee</b>: 120", "Eve <i>x</i>: 120"] and host.room.names_shown()
        _field(page, "show names").click()
        page.wait_for_selector('[data-egtviz="answers-by-name"]', state="detached")
        roster = page.locator('[data-egtviz="roster"]').first
        _wait(lambda: roster.get_attribute("data-rows") is not None and int(roster.get_attribute("data-rows")) >= 2,
              what="the roster")
        text = roster.inner_text()
        assert "<b>Dee</b>" in text and "Eve <i>x</i>" in text  # names as text, not markup
        assert roster.locator("b, i").count() == 0
        # A student answers through their bar: the histogram counts it.
        p1.locator('xpath=//label[normalize-space(.)="your answer"]/following::input[1]').first.fill("130")
        _typed(lambda: [host.bars[tabs["<b>Dee</b>"]].answer.value], "130", "the server to have Dee's typed answer")
        p1.get_by_role("button", name="Send my answer").click()
        _wait(lambda: host.room.histogram("Where is e1 (u, in px)?").n == 2
              and 130.0 in _edges_hit(host.room.histogram("Where is e1 (u, in px)?")), what="the typed answer")
        # Pause every screen: each student's page shows the message.
        _field(room.page, "pause message").fill("Look at the board <now>")
        _typed(lambda: [_instructor_panel(room).pause_text.value], "Look at the board <now>",
               "the server to have the typed pause message")
        room.page.get_by_role("button", name="Pause every screen").click()
        for p in (p1, p2):
            p.wait_for_selector('[data-egtviz="paused"]')
            assert p.locator('[data-egtviz="paused"]').inner_text().strip() == "Look at the board <now>"
        room.page.get_by_role("button", name="Resume every screen").click()
        for p in (p1, p2):
            p.wait_for_selector('[data-egtviz="paused"]', state="detached")
    finally:
        host.room.ask(None)
        c1.close()
        c2.close()


def _edges_hit(hist):
    """The answers a histogram can hold: its range's ends (two distinct answers span exactly their range)."""
    return {hist.edges[0], hist.edges[-1]} if hist.edges else set()


def test_a_student_gets_their_own_scene_back_on_reconnect_and_the_instructor_keeps_the_class(browser, room):
    host = room.host
    host.room.set_mode(Mode.EXPLORE)
    ctx, page = _join(browser, room.host, room.base, "Fay")
    try:
        cid = _wait(lambda: next((c for c, n in host.student_tabs().items() if c == "Fay"), None) and
                    host.student_tabs()["Fay"], what="Fay's tab")
        view = _wait(lambda: room.app.views.get(cid), what="Fay's own workbench")
        _drag(view, "cam2", 0.7)
        moved = view.model.scene.camera("cam2").position
        _wait(lambda: host.room.own_scene("Fay") is view.model.scene, what="Fay's scene kept")
        # The tab reloads: the browser still holds the name, so the student is back without typing it.
        page.reload()
        page.wait_for_selector('[data-egtviz="student-bar"]')
        assert page.locator("text=Join the class").count() == 0
        new = _wait(lambda: host.student_tabs().get("Fay") not in (None, cid) and host.student_tabs()["Fay"],
                    what="Fay's new tab")
        again = _wait(lambda: room.app.views.get(new), what="Fay's workbench again")
        assert np.array_equal(again.model.scene.camera("cam2").position, moved)
        # The instructor reloads: the class carries on (mode, the room's scene) and the panel says so.
        shared = host.room.shared().scene
        room.page.reload()
        room.page.wait_for_selector("text=follow me")
        assert host.room.mode is Mode.EXPLORE and host.room.instructor_present()
        room.view = _wait(lambda: next((v for c, v in room.app.views.items() if host.room.is_instructor(c)), None),
                          what="the instructor's new workbench")
        assert room.view.model.scene is shared
        assert room.page.locator('[data-egtviz="room-status"]').first.inner_text().endswith("mode: explore")
    finally:
        host.room.set_mode(Mode.FOLLOW)
        ctx.close()


def test_snapshot_shown_to_the_room_without_the_name_and_roster_downloaded(browser, room):
    host = room.host
    host.room.set_mode(Mode.EXPLORE)
    ctx, page = _join(browser, room.host, room.base, "Gus Secretname")
    try:
        cid = _wait(lambda: host.student_tabs().get("Gus Secretname"), what="Gus's tab")
        _wait(lambda: host.room.own_scene("Gus Secretname") is not None, what="Gus's own scene")
        host.room.show_snapshot(host.room.snapshot(cid))
        for p in (room.page, page):
            p.wait_for_selector('[data-egtviz="snapshot"]')
            label = p.locator('[data-egtviz="snapshot"]').first
            assert label.get_attribute("data-label").startswith("Student ")
            assert "Secretname" not in label.inner_text()
            assert label.locator('svg[data-egtviz="image-plane"]').count() == 1
        host.room.show_snapshot(None)
        for p in (room.page, page):  # gone from both pages: the instructor's panel no longer moves under a click
            p.wait_for_selector('[data-egtviz="snapshot"]', state="detached")
        # The roster as a download (the server writes no file): a CSV naming the student.
        _open_folder(room.page, "Students", room.page.get_by_role("button", name="Download roster (CSV)"))
        with room.page.expect_download() as download:
            room.page.get_by_role("button", name="Download roster (CSV)").click()
        text = open(download.value.path(), encoding="utf-8").read()
        assert text.splitlines()[0].startswith("name,connected,following") and "Gus Secretname" in text
    finally:
        host.room.set_mode(Mode.FOLLOW)
        ctx.close()


def test_released_to_tasks_students_open_the_instructors_step_and_pacing_holds_next(browser, room):
    host, app = room.host, room.app
    lesson = "02-pinhole-projection"
    instructor = room.view.client
    panel = app.course.open_lesson(instructor, lesson, "")
    panel.go_to(1)
    _wait(lambda: host.room.shared().lesson == lesson and host.room.shared().step == 1, what="the step published")
    # The tab shows the lesson's step: its GUI, and the instructor's panel rebuilt before it, are the new ones.
    room.page.wait_for_selector(f'[data-egtviz="lesson-head"][data-step="1"]')
    # Pacing from the panel: the first lesson in the list, up to step 2 (the one asked is paced below).
    _open_folder(room.page, "Pacing", _field(room.page, "up to step"))
    _field(room.page, "up to step").fill("2")
    _typed(lambda: [_instructor_panel(room).max_step.value], "2", "the server to have the typed 'up to step'")
    room.page.get_by_role("button", name="Apply pacing").click()
    first = next(iter(app.course.lessons))
    _wait(lambda: host.room.pacing() == (None, {first: 1}), what="the pacing applied from the panel")
    room.page.wait_for_selector(f'[data-egtviz="pacing"]:has-text("{first}: up to step 2")')
    host.room.pace(first, None)
    host.room.pace(lesson, 1)
    ctx, page = _join(browser, room.host, room.base, "Hal")
    try:
        # Following, the student sees the instructor's step: its titles and text above the room's scene.
        page.wait_for_selector(f'[data-egtviz="room-step"][data-lesson="{lesson}"][data-step="1"]')
        host.room.set_mode(Mode.TASKS)
        cid = _wait(lambda: host.student_tabs().get("Hal"), what="Hal's tab")
        student = _wait(lambda: getattr(app.course.tabs.get(cid), "run", None) and app.course.tabs[cid],
                        what="Hal's lesson")
        assert student.run.lesson.name == lesson
        # The class opens the lesson, then takes it to the instructor's step: the tab may be seen in between.
        _wait(lambda: student.run.step_index == 1, what="Hal on the instructor's step")
        page.get_by_role("button", name="next").click()
        page.wait_for_selector("text=the instructor has not opened it yet")
        assert student.run.step_index == 1
        host.room.pace(lesson, None)
        page.get_by_role("button", name="next").click()
        _wait(lambda: student.run.step_index == 2, what="the next step once paced open")
        # Released to explore from the tasks: the student leaves the lesson for their own scene.
        room.page.get_by_role("button", name="explore").click()
        _wait(lambda: cid in app.views and app.views[cid].model is not student.run.model
              and _bar(page) == "false", what="back on their own scene")
        _wait(lambda: app.views[cid].model.scene is host.room.own_scene("Hal"), what="their own scene kept")
        assert host.room.own_scene("Hal") is not student.run.model.scene
    finally:
        host.room.pace(lesson, None)
        host.room.set_mode(Mode.FOLLOW)
        app.course.open_workbench(instructor)
        room.view = _wait(lambda: app.views.get(instructor.client_id), what="the instructor's workbench")
        ctx.close()


def test_a_follower_on_another_server_process_shows_the_instructors_scene(browser, room, tmp_path):
    """What ``--workers`` builds on: a second server shares the class's state (adopted as another process would
    read it) and draws the published scene once for its own followers."""
    from egtviz.classroom import ClassState
    from egtviz.viewer.server.browser import LINES_JS

    host_a = room.host
    host_a.room.set_mode(Mode.FOLLOW)
    server_b, app_b, host_b, base_b = _serve(tmp_path)
    ctx, page = _join(browser, host_b, base_b, "Ivy")
    try:
        follower = _wait(lambda: next(iter(host_b.followers.values()), None), what="a follower on server B")
        _drag(room.view, "cam2", -0.6)
        version = _wait(lambda: host_a.room.shared().scene is room.view.model.scene and host_a.room.shared().version,
                        what="the drag published")
        state = ClassState.from_json(host_a.room.to_json())
        state.tabs = ClassState.from_json(host_b.room.to_json()).tabs  # B keeps its own tabs
        host_b.room.adopt(state)
        _wait(lambda: follower.frame is not None and follower.frame.version == version, what="B's frame")
        # The class's state is JSON: the pose comes back equal to rounding (R from the stored angles).
        there, here = follower.frame.scene.camera("cam2").pose, room.view.model.scene.camera("cam2").pose
        assert np.allclose(there.t, here.t, atol=1e-12) and np.allclose(there.R, here.R, atol=1e-12)
        for camera in ("cam1", "cam2"):
            theirs, ours = follower.frame.derived.image_planes[camera], room.view.model.derived.image_planes[camera]
            assert np.allclose(theirs.lines, ours.lines, atol=1e-9) and all(
                np.allclose(a.xy, b.xy) for a, b in zip(theirs.epipoles, ours.epipoles, strict=True))
            _wait(lambda c=camera: page.evaluate(REV_JS, c) == str(version),
                  what=f"{camera}'s panel of the version", on_fail=lambda c=camera: (page.evaluate(REV_JS, c), version,
                  [(k, t) for k, t, _ in follower.frame.panels]))
    finally:
        ctx.close()
        host_b.close()
        server_b.stop()
