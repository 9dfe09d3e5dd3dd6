"""A classroom student is the name they joined with, and the pacing holds them where it says:

* the name fields of the course's start page and of the lesson panel show the joined name read-only for a student,
  and a raw message setting them is refused in that tab (an instructor's tab, and a course without a class, keep
  the field);
* an instructor tightening the pacing moves a student already past it back to the last open step (or to the start
  page when their lesson closes), with a note in their tab;
* the progress database keeps the furthest step the student reached, not the step the pacing showed.
"""

from __future__ import annotations

import viser

from egtviz.classroom import Classroom
from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom.course_gate import CourseGate
from egtviz.viewer.course.lesson_view import HELD_NAME_HINT, LessonPanel
from egtviz.viewer.course.start_page import StartPage
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.tabs import EgtvizApp

from _class_course import classroom, paced  # noqa: F401 - the fixture
from _waiting import PATIENCE, wait_for

LESSON = "07-fundamental-and-essential"  # seven steps


def _notes(client) -> list[tuple[str, str]]:
    notes: list[tuple[str, str]] = []
    client.add_notification = lambda title, body, **kw: notes.append((title, body))
    return notes


def _open_lesson(app, cid, fake) -> LessonPanel:
    """The student opens LESSON from their start page (a click sent by their tab)."""
    app.course.remember(cid, app.course.gate.room.name_of(cid))  # as a lesson the class opened for them did
    page = app.course.show_start(app.views[cid].client)
    fake.send("GuiUpdateMessage", uuid=page.buttons[LESSON]._impl.uuid, updates={"value": True})
    wait_for(lambda: isinstance(app.course.tabs.get(cid), LessonPanel), f"the click to open {LESSON} in the tab")
    return app.course.tabs[cid]


def test_a_students_name_on_the_start_page_is_the_joined_one_and_cannot_be_changed(classroom):
    app, host, progress, join = classroom
    cid, fake = join("Ada")
    page = app.course.show_start(app.views[cid].client)
    notes = _notes(page.client)
    assert page.name.value == "Ada" and page.name.disabled and page.learner == "Ada"
    assert page.name.hint == HELD_NAME_HINT
    fake.send("GuiUpdateMessage", uuid=page.name._impl.uuid, updates={"value": "Bea"})
    wait_for(lambda: notes, "the start page to refuse the name sent")
    assert notes[-1][0] == "Value refused" and "Ada" in notes[-1][1]
    assert page.learner == "Ada" and page.name.value == "Ada"
    assert app.course.tabs[cid] is page and app.course.show_start(page.client).learner == "Ada"


def test_a_students_name_in_the_lesson_panel_cannot_be_changed(classroom):
    app, host, progress, join = classroom
    progress.set_step("Bea", LESSON, 2)  # another student's progress, which Ada must not take over
    cid, fake = join("Ada")
    panel = _open_lesson(app, cid, fake)
    notes = _notes(panel.view.client)
    assert panel.learner.value == "Ada" and panel.learner.disabled and panel.run.learner == "Ada"
    assert panel.learner.hint == HELD_NAME_HINT
    fake.send("GuiUpdateMessage", uuid=panel.learner._impl.uuid, updates={"value": "Bea"})
    wait_for(lambda: notes, "the lesson panel to refuse the name sent")
    assert notes[-1][0] == "Value refused" and "Ada" in notes[-1][1]
    assert app.course.tabs[cid] is panel and panel.run.learner == "Ada" and panel.learner.value == "Ada"
    assert progress.current_step("Bea", LESSON) == 2


def test_the_instructors_name_fields_stay_free(classroom):
    app, host, progress, join = classroom
    cid, fake = join("Ada")
    assert host.gate.student_name(cid) == "Ada"
    host.room.instructor_join(cid)  # the tab is the instructor's now (as a checked token makes it)
    assert host.gate.student_name(cid) is None and host.gate.student_name(cid + 1000) is None
    page = app.course.show_start(app.views[cid].client)
    assert not page.name.disabled
    fake.send("GuiUpdateMessage", uuid=page.name._impl.uuid, updates={"value": "Zed"})
    wait_for(lambda: page.learner == "Zed", "the instructor's start page to take the name Zed")
    fake.send("GuiUpdateMessage", uuid=page.buttons[LESSON]._impl.uuid, updates={"value": True})
    wait_for(lambda: isinstance(app.course.tabs.get(cid), LessonPanel), f"the click to open {LESSON} in the tab")
    panel = app.course.tabs[cid]
    assert not panel.learner.disabled and panel.run.learner == "Zed"
    fake.send("GuiUpdateMessage", uuid=panel.learner._impl.uuid, updates={"value": "Ann"})
    wait_for(lambda: panel.run.learner == "Ann", "the instructor's lesson panel to take the name Ann")


def test_a_course_without_a_class_keeps_its_name_field(tmp_path):
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        progress = ProgressStore(tmp_path / "p.db")
        app = EgtvizApp(server, None, field_delay=0.0, course=True, progress=progress)
        fake = FakeTab(server.get_port())
        (page,) = app.course.wait_for_tab(StartPage, timeout=PATIENCE)
        assert not page.name.disabled
        fake.send("GuiUpdateMessage", uuid=page.name._impl.uuid, updates={"value": "Cy"})
        wait_for(lambda: page.learner == "Cy", "the start page to take the name Cy")
        fake.close()
    finally:
        server.stop()


def test_tightening_the_pacing_moves_a_student_past_it_back_with_a_note(classroom):
    app, host, progress, join = classroom
    progress.set_step("Ada", LESSON, 3)
    cid, fake = join("Ada")
    panel = _open_lesson(app, cid, fake)
    assert panel.run.step_index == 3
    notes = _notes(panel.view.client)
    host.room.pace(LESSON, 1)
    wait_for(lambda: panel.run.step_index == 1, "the pacing to move the lesson back to step 2")
    wait_for(lambda: notes, "the note that the pacing moved the tab")
    assert notes[-1][0] == "Paced by the instructor" and "step 2" in notes[-1][1]
    assert 'data-step="1"' in panel.nav.head.content
    # The furthest step reached stays in the progress database: the pacing moved the tab, not the learner.
    assert progress.current_step("Ada", LESSON) == 3
    # Closing the lesson sends the student to the start page, with a note.
    client = panel.view.client
    notes2 = _notes(client)
    host.room.allow_lessons([])
    wait_for(lambda: isinstance(app.course.tabs.get(cid), StartPage), "the closed lesson's tab sent to the start page")
    wait_for(lambda: notes2, "the note that the closed lesson's tab was moved")
    assert notes2[-1][0] == "Paced by the instructor"
    assert app.course.tabs[cid].buttons[LESSON].disabled
    assert progress.current_step("Ada", LESSON) == 3


def test_a_student_within_the_pacing_and_the_instructor_stay_where_they_are(classroom):
    app, host, progress, join = classroom
    progress.set_step("Ada", LESSON, 1)
    cid, fake = join("Ada")
    panel = _open_lesson(app, cid, fake)
    notes = _notes(panel.view.client)
    host.room.pace(LESSON, 2)
    paced(host)
    assert panel.run.step_index == 1 and not notes and app.course.tabs[cid] is panel


def test_a_lesson_reopened_at_an_earlier_step_keeps_the_furthest_step_in_the_database(classroom):
    app, host, progress, join = classroom
    progress.set_step("Bea", LESSON, 3)
    host.room.pace(LESSON, 1)
    cid, fake = join("Bea")
    panel = _open_lesson(app, cid, fake)
    assert panel.run.step_index == 1
    assert progress.current_step("Bea", LESSON) == 3
    panel.go_to(0)  # "previous" in a paced lesson does not forget how far the student got either
    assert progress.current_step("Bea", LESSON) == 3
    host.room.pace(LESSON, None)
    panel.go_to(4)  # further than before: recorded
    assert progress.current_step("Bea", LESSON) == 4


def test_the_gate_moves_no_tab_of_a_course_it_does_not_pace():
    room = Classroom(None, token="t" * 20)
    gate = CourseGate(room)
    room.join(2, "Ada")
    room.pace(LESSON, 0)  # no course: nothing to move, nothing raised
    assert gate.student_name(2) == "Ada"
    gate.close()


def test_a_run_that_keeps_the_furthest_step_records_no_step_back(tmp_path):
    from egtviz.lessons import LessonRun, load

    progress = ProgressStore(tmp_path / "p.db")
    lesson = load(LESSON)
    run = LessonRun(lesson, "Ada", progress=progress)
    run.go_to(4)
    run.go_to(2)  # a run of the course alone remembers where the learner is
    assert progress.current_step("Ada", LESSON) == 2
    run.keep_furthest = True
    run.go_to(4)
    run.previous()
    run.go_to(0)
    assert progress.current_step("Ada", LESSON) == 4 and run.step_index == 0
    run.go_to(5)
    run.next()
    assert progress.current_step("Ada", LESSON) == 6


def test_a_lesson_back_from_a_servo_demo_follows_a_pacing_tightened_meanwhile(classroom):
    app, host, progress, join = classroom
    progress.set_step("Ada", LESSON, 3)
    cid, fake = join("Ada")
    panel = _open_lesson(app, cid, fake)
    client = panel.view.client
    assert app.open_demo(client, "pinhole") is not None  # the step's "Open the demo" button
    host.room.pace(LESSON, 1)
    paced(host)  # the gate moves no tab showing a demo: its lesson view is closed
    app.close_demo(client)  # the demo's Back button
    back = app.course.tabs[cid]
    assert isinstance(back, LessonPanel) and back.run is panel.run
    assert back.run.step_index == 1 and back.held_name == "Ada" and back.learner.disabled
    assert progress.current_step("Ada", LESSON) == 3
