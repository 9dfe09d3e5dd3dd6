"""The class members' controllers without a server: a student joins, follows and answers from typed text, the
instructor releases, locks, pauses, asks, paces from typed text and downloads the roster; each refusal is the
message the tab shows, and the state is what the bar and the panel draw."""

from __future__ import annotations

import csv
import io

import pytest

from egtviz.classroom import Classroom, Mode
from egtviz.controllers.class_member import HISTOGRAM_BINS, InstructorController, StudentController
from egtviz.controllers.class_state import PacedLesson, RosterLine, RoomStatus, StudentState
from egtviz.controllers.class_text import ClassRefusal, as_refusal, typed_name
from egtviz.scene import SceneError, default_scene

STEPS = {"01-frames": 4, "02-pinhole": 6}


def _class():
    room = Classroom(None, token="t" * 20)
    return room, InstructorController(room, lambda: dict(STEPS))


def _student(room, tab, name):
    student = StudentController(room, tab)
    assert student.join(name) == name
    return student


@pytest.mark.parametrize("typed, message", [
    ("", "your name: type it to join the class"),
    ("   ", "your name: type it to join the class"),
    (None, "your name: type it to join the class"),
    ("x" * 41, "your name: at most 40 characters, got 41"),
    ("a\x00b", "your name: control characters are not allowed (U+0000)"),
])
def test_a_refused_name_is_refused_in_the_fields_words_and_nobody_joins(typed, message):
    room, _ = _class()
    with pytest.raises(ClassRefusal) as caught:
        StudentController(room, 1).join(typed)
    assert str(caught.value) == message and isinstance(caught.value, SceneError)  # the tab says "Value refused"
    assert room.name_of(1) is None and room.roster() == []


def test_a_student_joins_follows_and_leaves_follow():
    room, _ = _class()
    student = _student(room, 1, " Ada ")
    assert student.state() == StudentState("Ada", True, None, None)  # the class's mode is follow
    student.follow(False)
    assert not room.is_following(1) and not student.state().following
    student.follow(True)
    assert room.is_following(1)


def test_an_answer_typed_is_recorded_in_the_histogram():
    room, teacher = _class()
    ada, ben = _student(room, 1, "Ada"), _student(room, 2, "Ben")
    teacher.ask("where is e1?")
    question = ada.state().question
    assert question == "where is e1?"
    assert ada.answer(question, " 1,5 ") == 1.5
    assert ben.answer(question, "left") == "left"
    answers = teacher.state().answers
    assert answers is not None and (answers.question, answers.n) == ("where is e1?", 2)
    assert answers.bars[-1] == ("left", 1) and sum(c for _, c in answers.bars) == 2
    assert len(answers.bars) == HISTOGRAM_BINS + 1 and answers.by_name == ()  # names hidden
    teacher.show_names(True)
    assert teacher.state().answers.by_name == (("Ada", "1.5"), ("Ben", "left"))


@pytest.mark.parametrize("question, typed, message", [
    (None, "12", "your answer: no question is asked at the moment"),
    ("q?", "   ", "your answer: type it first"),
])
def test_a_refused_answer_says_why_and_records_nothing(question, typed, message):
    room, teacher = _class()
    ada = _student(room, 1, "Ada")
    teacher.ask("q?")
    with pytest.raises(ClassRefusal) as caught:
        ada.answer(question, typed)
    assert str(caught.value) == message and room.answers("q?") == {}


def test_an_answer_the_class_cannot_keep_is_a_refusal_in_its_words():
    room, teacher = _class()
    ada = _student(room, 1, "Ada")
    teacher.ask("q?")
    with pytest.raises(ClassRefusal, match="80"):
        ada.answer("q?", "x" * 200)
    assert room.answers("q?") == {}


def test_pacing_from_the_typed_text():
    room, teacher = _class()
    teacher.pace("02-pinhole", " 3 ", only=True)
    assert room.pacing() == (frozenset({"02-pinhole"}), {"02-pinhole": 2})
    pacing = teacher.state().pacing
    assert pacing.allowed == ("02-pinhole",) and pacing.paced == (PacedLesson("02-pinhole", 3, 6),)
    teacher.pace("01-frames", "", only=False)
    assert room.pacing() == (None, {"02-pinhole": 2})  # blank: every step of 01-frames


@pytest.mark.parametrize("lesson, typed, message", [
    ("02-pinhole", "999", "up to step: 02-pinhole has 6 steps: type 1 to 6, or leave it blank for every step"),
    ("02-pinhole", "0", "up to step: steps count from 1: type 1 to 6, or leave it blank for every step"),
    ("02-pinhole", "abc", "up to step: expected a step number or blank, got 'abc'"),
    ("(no lessons)", "1", "pacing: no lesson to pace"),
])
def test_a_refused_pacing_keeps_the_class_as_it_was(lesson, typed, message):
    room, teacher = _class()
    room.pace("02-pinhole", 0)
    with pytest.raises(ClassRefusal) as caught:
        teacher.pace(lesson, typed, only=True)
    assert str(caught.value) == message and room.pacing() == (None, {"02-pinhole": 0})


def test_release_lock_pause_and_follow_me_change_the_room():
    room, teacher = _class()
    ada = _student(room, 1, "Ada")
    assert teacher.release("tasks") is Mode.TASKS and room.mode is Mode.TASKS and not room.is_following(1)
    assert teacher.follow_me(False) is False and room.mode is Mode.TASKS  # released already: stays so
    assert teacher.follow_me(True) is True and room.mode is Mode.FOLLOW and room.is_following(1)
    teacher.follow_me(False)
    assert room.mode is Mode.EXPLORE
    with pytest.raises(ClassRefusal, match=r"release to: expected one of \['explore', 'tasks'\]"):
        teacher.release("lunch")
    teacher.lock_cameras(True)
    assert room.cameras_locked and teacher.state().cameras_locked
    teacher.toggle_pause("Eyes on me")
    assert room.paused() == "Eyes on me" and ada.state().paused == "Eyes on me"
    assert teacher.state().status == RoomStatus(1, 0, Mode.EXPLORE, "Eyes on me")
    teacher.toggle_pause("ignored")
    assert room.paused() is None
    teacher.clear_question()
    assert room.asked() is None and teacher.state().answers is None


def test_a_snapshot_needs_a_chosen_student_with_a_scene():
    room, teacher = _class()
    _student(room, 1, "Ada")
    with pytest.raises(ClassRefusal, match="snapshot: choose a connected student first"):
        teacher.show_snapshot(None)
    with pytest.raises(ClassRefusal, match="no scene of their own yet"):
        teacher.show_snapshot(1)
    room.keep_scene("Ada", default_scene())
    teacher.show_snapshot(1)
    assert room.shown_snapshot() is not None
    teacher.hide_snapshot()
    assert room.shown_snapshot() is None


def test_the_roster_rows_and_its_csv():
    room, teacher = _class()
    _student(room, 1, "Ada")
    _student(room, 2, "=Bob").follow(False)
    room.report_step(2, "02-pinhole", 1)
    assert teacher.state().roster == (
        RosterLine("=Bob", "0", "own scene", "own scene · lesson 2 · step 2", True),
        RosterLine("Ada", "0", "following", "following", True))
    rows = list(csv.reader(io.StringIO(teacher.roster_csv().decode("utf-8"))))
    assert rows[0][:3] == ["name", "connected", "following"]
    assert {r[0] for r in rows[1:]} == {"Ada", "'=Bob"}  # a formula is written as text


def test_the_refusals_of_the_class_are_said_in_their_words():
    assert typed_name(" Ada ") == " Ada "  # the class trims it
    fault = KeyError("/srv/path")
    assert as_refusal(fault) is fault  # a fault of the program is not a refusal
