"""The class's pacing holds on the course's start page too, for students only: a lesson the instructor has not
opened is shown as not yet open (its button disabled, the reason said), a click forged by a raw message is refused,
and a lesson opened from the page starts at a step the pacing allows, its "next" held."""

from __future__ import annotations


import viser

from egtviz.classroom import Classroom
from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom.course_gate import NOT_OPEN, CourseGate
from egtviz.viewer.course.lesson_view import LessonPanel
from egtviz.viewer.course.start_page import StartPage
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.tabs import EgtvizApp

from _class_course import classroom  # noqa: F401 - the fixture
from _waiting import PATIENCE, wait_for

OPEN, CLOSED = "02-pinhole-projection", "03-intrinsics"


def test_the_gate_paces_students_only():
    room = Classroom(None, token="t" * 20)
    gate = CourseGate(room)
    room.instructor_join(1)
    room.join(2, "Ada")
    room.allow_lessons([OPEN])
    room.pace(OPEN, 1)
    assert gate.refusal(2, CLOSED) == NOT_OPEN and gate.refusal(2, OPEN) is None
    assert gate.refusal(1, CLOSED) is None and gate.refusal(3, CLOSED) is None  # the instructor; no student
    assert gate.note(2, OPEN, 6) == "open up to step 2 of 6" and gate.note(1, OPEN, 6) == ""
    assert gate.last_open(OPEN, 4) == 1 and gate.last_open(OPEN, 0) == 0
    assert gate.paced_run(1, None) is None  # the instructor's lessons are not paced
    room.pace(OPEN, 5)
    assert gate.note(2, OPEN, 6) == ""  # every step of a six-step lesson
    gate.close()


def _start_page(app, cid, name) -> StartPage:
    client = app.views[cid].client
    app.course.remember(cid, name)  # as a lesson the class opened for them did
    page = app.course.show_start(client)  # "Back to the course" from that lesson
    page.notes = []
    client.add_notification = lambda title, body, **kw: page.notes.append((title, body))
    return page


def test_a_students_start_page_shows_the_lessons_not_yet_open_and_refuses_a_forged_click(classroom):
    app, host, _, join = classroom
    cid, fake = join("Ada")
    host.room.allow_lessons([OPEN])
    host.room.pace(OPEN, 1)
    page = _start_page(app, cid, "Ada")
    steps = len(app.course.lessons[OPEN].steps)
    assert page.buttons[CLOSED].disabled and not page.buttons[OPEN].disabled
    assert 'data-open="false"' in page.status[CLOSED].content and NOT_OPEN in page.status[CLOSED].content
    assert f"open up to step 2 of {steps}" in page.status[OPEN].content
    # A click on the disabled button, forged by a raw message: refused in the tab, the page stays.
    fake.send("GuiUpdateMessage", uuid=page.buttons[CLOSED]._impl.uuid, updates={"value": True})
    wait_for(lambda: page.notes, "the start page to refuse the forged click")
    assert page.notes[-1] == ("Value refused", f"{app.course.lessons[CLOSED].title}: {NOT_OPEN}")
    assert app.course.tabs[cid] is page
    # The instructor opens the lesson: the page says so at once.
    host.room.allow_lessons(None)
    wait_for(lambda: not page.buttons[CLOSED].disabled, f"the start page to show {CLOSED} open")
    assert 'data-open="true"' in page.status[CLOSED].content



def test_a_lesson_opened_from_the_start_page_starts_at_a_step_the_pacing_allows(classroom):
    app, host, progress, join = classroom
    progress.set_step("Bea", OPEN, 3)  # Bea was at step 4 before the class
    cid, fake = join("Bea")
    host.room.pace(OPEN, 1)
    page = _start_page(app, cid, "Bea")
    fake.send("GuiUpdateMessage", uuid=page.buttons[OPEN]._impl.uuid, updates={"value": True})
    wait_for(lambda: isinstance(app.course.tabs.get(cid), LessonPanel), f"the click to open {OPEN} in the tab")
    panel = app.course.tabs[cid]
    assert panel.run.lesson.name == OPEN and panel.run.step_index == 1
    notes = []
    panel.view.client.add_notification = lambda title, body, **kw: notes.append((title, body))
    fake.send("GuiUpdateMessage", uuid=panel.nav.buttons._impl.uuid, updates={"value": "next"})
    wait_for(lambda: notes, "the lesson panel to refuse the step the pacing keeps closed")
    assert notes[-1] == ("Value refused", "step 3: the instructor has not opened it yet")
    assert panel.run.step_index == 1


def test_the_pacing_leaves_a_course_without_a_class_alone(tmp_path):
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        app = EgtvizApp(server, None, field_delay=0.0, course=True, progress=ProgressStore(tmp_path / "p.db"))
        fake = FakeTab(server.get_port())
        (page,) = app.course.wait_for_tab(StartPage, timeout=PATIENCE)
        assert app.course.gate is None and not any(b.disabled for b in page.buttons.values())
        assert all('data-open="true"' in s.content for s in page.status.values())
        fake.close()
    finally:
        server.stop()


def test_the_workbench_opened_from_a_students_start_page_is_their_own_scene(classroom):
    app, host, _, join = classroom
    cid, fake = join("Cy")  # released to explore: their own scene
    own = app.views[cid].model
    cam = own.scene.camera("cam2")
    own.set_camera_pose("cam2", (cam.position[0] + 0.4, *cam.position[1:]), cam.pose.R)  # their work
    wait_for(lambda: host.room.own_scene("Cy") is own.scene, "the class to keep Cy's edited scene")
    page = _start_page(app, cid, "Cy")
    fake.send("GuiUpdateMessage", uuid=page.btn_workbench._impl.uuid, updates={"value": True})
    wait_for(lambda: app.course.tabs.get(cid) is not page and cid in app.views, "the click to open the workbench")
    assert app.views[cid].model is own
    wait_for(lambda: host.room.own_scene("Cy") is own.scene, "the class to keep Cy's scene, the workbench's")
