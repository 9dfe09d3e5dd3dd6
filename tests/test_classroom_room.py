"""The classroom's state machine: joins and reconnects, follow and release, camera lock, pause, pacing, events,
and its state carried as JSON."""

from __future__ import annotations

import pytest

from egtviz.classroom import (
    CamerasLocked, Classroom, ClassroomError, FollowChanged, Mode, ModeChanged, NamesShown, PacingChanged, PauseChanged,
    RosterChanged, SharedChanged,
)
from egtviz.lessons.progress import LearnerNameError
from egtviz.scene import default_scene

from _waiting import PATIENCE


def _room():
    room = Classroom(token="t" * 32, task_count=lambda lesson: 4)
    events = []
    room.subscribe(events.append)
    return room, events


def test_students_follow_in_follow_mode_and_are_released_by_explore():
    room, events = _room()
    room.instructor_join(0)
    room.join(1, "Ada")
    room.join(2, "Ben")
    assert room.mode is Mode.FOLLOW
    assert room.is_following(1) and room.is_following(2)
    events.clear()
    room.set_mode(Mode.EXPLORE)
    assert not room.is_following(1) and not room.is_following(2)
    assert events == [ModeChanged(Mode.EXPLORE), FollowChanged(1, False), FollowChanged(2, False), RosterChanged()]
    room.join(3, "Cy")  # joins a released class: on their own scene
    assert not room.is_following(3)
    room.set_mode(Mode.FOLLOW)
    assert [room.is_following(t) for t in (1, 2, 3)] == [True, True, True]
    assert not room.is_following(0)  # the instructor's tab never follows


def test_a_student_may_leave_follow_and_rejoin_it():
    room, events = _room()
    room.join(1, "Ada")
    events.clear()
    room.follow(1, False)
    assert not room.is_following(1)
    room.follow(1, False)  # no change, no event
    room.follow(1, True)
    assert room.is_following(1)
    assert events == [FollowChanged(1, False), RosterChanged(), FollowChanged(1, True), RosterChanged()]


def test_follow_on_an_instructor_or_unknown_tab_is_refused():
    room, _ = _room()
    room.instructor_join(0)
    with pytest.raises(ClassroomError, match="no student"):
        room.follow(0, True)
    with pytest.raises(ClassroomError, match="no student"):
        room.follow(9, True)


def test_publish_counts_versions_and_stores_the_latest_scene_once():
    room, events = _room()
    assert room.shared().version == 0 and room.shared().scene is None
    a = default_scene()
    b = a.replace(title="moved")
    assert room.publish(a, lesson="01-frames-and-poses", step=2) == 1
    assert room.publish(a, lesson="01-frames-and-poses", step=2) == 1  # the same scene again: nothing new
    assert room.publish(b) == 2
    shared = room.shared()
    assert (shared.version, shared.scene, shared.lesson, shared.step) == (2, b, None, None)
    assert events == [SharedChanged(1), SharedChanged(2)]
    with pytest.raises(ClassroomError, match="expected a Scene"):
        room.publish("scene")  # type: ignore[arg-type]
    with pytest.raises(ClassroomError, match="step"):
        room.publish(a, step=-1)


def test_lock_and_pause():
    room, events = _room()
    room.lock_cameras(True)
    room.lock_cameras(True)
    assert room.cameras_locked
    room.pause("Eyes on the projector")
    assert room.paused() == "Eyes on the projector"
    room.pause("")
    assert room.paused() == "The class is paused."
    room.pause(None)
    assert room.paused() is None
    room.lock_cameras(False)
    assert events == [CamerasLocked(True), PauseChanged("Eyes on the projector"),
                      PauseChanged("The class is paused."), PauseChanged(None), CamerasLocked(False)]


def test_a_pause_message_is_plain_text():
    room, _ = _room()
    room.pause("  <b>stop</b>\n now ")
    assert room.paused() == "<b>stop</b> now"  # kept as text: the viewer shows it as text, never as markup
    with pytest.raises(ClassroomError, match="control characters"):
        room.pause("evil\u202eright-to-left")
    with pytest.raises(ClassroomError, match="at most 200"):
        room.pause("x" * 201)


def test_pacing():
    room, events = _room()
    assert room.may_open("02-pinhole-projection", 7)
    room.pace("02-pinhole-projection", 2)
    assert room.may_open("02-pinhole-projection", 2)
    assert not room.may_open("02-pinhole-projection", 3)
    assert room.may_open("03-intrinsics", 5)
    room.allow_lessons(["02-pinhole-projection"])
    assert not room.may_open("03-intrinsics", 0)
    assert room.may_open("02-pinhole-projection", 0)
    room.pace("02-pinhole-projection", None)
    assert room.may_open("02-pinhole-projection", 9)
    room.allow_lessons(None)
    assert room.may_open("03-intrinsics", 0)
    assert events == [PacingChanged()] * 4
    assert room.pacing() == (None, {})


def test_the_instructor_who_reconnects_keeps_the_class():
    room, _ = _room()
    room.instructor_join(0)
    room.join(1, "Ada")
    scene = default_scene()
    room.publish(scene, lesson="03-intrinsics", step=1)
    room.set_mode(Mode.TASKS)
    room.lock_cameras(True)
    room.pause("back in 5")
    room.pace("03-intrinsics", 1)
    room.instructor_leave(0)
    assert not room.instructor_present()
    assert (room.mode, room.cameras_locked, room.paused()) == (Mode.TASKS, True, "back in 5")
    room.instructor_join(5)
    assert room.is_instructor(5) and room.instructor_present()
    assert room.shared().scene is scene and room.shared().version == 1
    assert (room.mode, room.cameras_locked, room.paused()) == (Mode.TASKS, True, "back in 5")
    assert not room.may_open("03-intrinsics", 2)


def test_a_student_who_reconnects_gets_their_scene_back():
    room, _ = _room()
    room.join(1, "Ada")
    mine = default_scene().replace(title="Ada's try")
    room.keep_scene("Ada", mine)
    room.leave(1)
    assert room.name_of(1) is None
    room.join(7, "  Ada ")  # the same learner key
    assert room.own_scene("Ada") is mine
    assert room.own_scene("Ben") is None
    assert [r.name for r in room.roster()] == ["Ada"]


def test_keep_scene_of_a_stranger_is_refused():
    room, _ = _room()
    with pytest.raises(ClassroomError, match="not joined"):
        room.keep_scene("Zed", default_scene())


def test_names_are_checked_like_the_course_checks_them():
    room, _ = _room()
    with pytest.raises(LearnerNameError):
        room.join(1, "")
    with pytest.raises(LearnerNameError):
        room.join(1, "a\u202eb")
    with pytest.raises(ClassroomError, match="tab"):
        room.join(-1, "Ada")


def test_a_listener_that_raises_does_not_stop_the_others(caplog):
    room = Classroom(task_count=lambda lesson: 0)
    heard = []

    def broken(event):
        raise RuntimeError("panel gone")

    room.subscribe(broken)
    room.subscribe(heard.append)
    room.pause("x")
    assert heard == [PauseChanged("x")]
    assert "listener failed on PauseChanged" in caplog.text


def test_unsubscribe():
    room, events = _room()
    other = []
    stop = room.subscribe(other.append)
    stop()
    stop()
    room.pause("x")
    assert other == [] and events == [PauseChanged("x")]


def test_listeners_run_outside_the_lock():
    room, _ = _room()
    seen = []
    room.subscribe(lambda event: seen.append(room.paused()))  # would deadlock on a held plain lock in another thread
    import threading
    t = threading.Thread(target=room.pause, args=("hi",))
    t.start()
    t.join(PATIENCE)
    assert not t.is_alive(), f"waited {PATIENCE:.0f} s for the pause in another thread (a deadlock)"
    assert seen == ["hi"]


def test_state_goes_through_json_and_back():
    room, _ = _room()
    room.instructor_join(0)
    room.join(1, "Ada")
    room.join(2, "Ben")
    room.keep_scene("Ada", default_scene().replace(title="Ada's"))
    room.publish(default_scene(), lesson="03-intrinsics", step=1)
    room.set_mode(Mode.EXPLORE)
    room.follow(2, True)
    room.pause("wait")
    room.show_names(True)
    room.pace("03-intrinsics", 1)
    room.allow_lessons(["03-intrinsics"])
    room.record_answer(1, "f?", 800.0)
    room.record_answer(2, "f?", "big")
    shot = room.snapshot(1)
    room.show_snapshot(shot)
    text = room.to_json()
    assert room.instructor_token not in text
    again = Classroom.from_json(text, token="u" * 32, task_count=lambda lesson: 4)
    assert again.to_json() == text
    assert again.mode is Mode.EXPLORE and again.is_following(2) and not again.is_following(1)
    assert again.paused() == "wait" and not again.may_open("03-intrinsics", 2) and not again.may_open("x", 0)
    assert again.shared().version == 1 and again.shared().scene == room.shared().scene
    assert again.own_scene("Ada") == room.own_scene("Ada")
    assert again.histogram("f?").categories == (("big", 1),)
    assert again.shown_snapshot() == shot
    assert again.names_shown()


def test_bad_state_is_refused_with_a_reason():
    with pytest.raises(ClassroomError, match="not JSON"):
        Classroom.from_json("{")
    with pytest.raises(ClassroomError, match="egtviz-classroom"):
        Classroom.from_json('{"format": "other"}')
    text = Classroom().to_json().replace('"mode":"follow"', '"mode":"dance"')
    with pytest.raises(ClassroomError, match="dance"):
        Classroom.from_json(text)


def test_followers_and_student_tabs():
    room, _ = _room()
    room.instructor_join(0)
    room.join(1, "Ada")
    room.join(2, "Ben")
    room.join(3, "Ada")
    room.follow(2, False)
    assert room.followers() == [1, 3]
    assert room.student_tabs() == {1: "Ada", 2: "Ben", 3: "Ada"}
    room.leave(1)
    assert room.followers() == [3]


def test_names_are_hidden_until_the_instructor_shows_them():
    room, events = _room()
    assert room.names_shown() is False
    room.show_names(True)
    room.show_names(True)
    room.show_names(False)
    assert events == [NamesShown(True), NamesShown(False)]


def test_adopting_another_process_state_tells_listeners_what_changed():
    from egtviz.classroom import AnswersChanged, ClassState, QuestionAsked, SnapshotShown

    a, _ = _room()
    b, heard = _room()
    b.join(1, "Ada")
    a.join(1, "Ada")
    a.join(2, "Ben")
    a.keep_scene("Ada", default_scene())
    a.set_mode(Mode.EXPLORE)
    a.publish(default_scene(), lesson="L", step=0)
    a.pause("wait")
    a.pace("L", 0)
    a.ask("q")
    a.record_answer(2, "q", 1.0)
    a.show_snapshot(a.snapshot(1))
    a.show_names(True)
    heard.clear()
    b.adopt(ClassState.from_json(a.to_json()))
    assert b.to_json() == a.to_json()
    assert heard == [SharedChanged(1), ModeChanged(Mode.EXPLORE), FollowChanged(1, False), FollowChanged(2, False),
                     PauseChanged("wait"), PacingChanged(), QuestionAsked("q"), AnswersChanged("q"),
                     SnapshotShown("Student A"), NamesShown(True), RosterChanged()]
    heard.clear()
    b.adopt(ClassState.from_json(a.to_json()))
    assert heard == []  # nothing changed: nothing said
    with pytest.raises(ClassroomError, match="ClassState"):
        b.adopt(a.to_json())  # type: ignore[arg-type]


def test_a_tab_that_renames_itself_leaves_no_empty_student_behind():
    room, events = _room()
    for i in range(2000):  # more than MAX_STUDENTS: the class would be full if each name stayed
        room.join(1, f"name {i}")
    assert [r.name for r in room.roster()] == ["name 1999"]
    room.keep_scene("name 1999", default_scene())
    room.join(1, "final")
    assert [r.name for r in room.roster()] == ["final", "name 1999"]  # kept: they have a scene


def test_joining_again_on_the_same_tab_keeps_its_place():
    room, events = _room()
    room.join(1, "Ada")
    room.report_step(1, "L", 3)
    room.follow(1, False)
    events.clear()
    room.join(1, "Ada ")
    assert events == [] and not room.is_following(1)
    assert (room.roster()[0].lesson, room.roster()[0].step) == ("L", 3)


def test_a_full_class_refuses_a_new_name_but_not_a_returning_one(monkeypatch):
    import egtviz.classroom.room as room_module

    monkeypatch.setattr(room_module, "MAX_STUDENTS", 3)
    room, _ = _room()
    for tab, name in enumerate(["a", "b", "c"]):
        room.join(tab, name)
    with pytest.raises(ClassroomError, match="full"):
        room.join(9, "d")
    room.leave(0)
    room.join(9, "a")
    assert room.name_of(9) == "a"
