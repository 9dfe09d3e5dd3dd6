"""The roster from the course's own progress database, and its CSV (formula injection, odd names)."""

from __future__ import annotations

import csv
import io

from egtviz.classroom import Classroom, RosterRow
from egtviz.lessons import load
from egtviz.lessons.progress import ProgressStore

LESSON = "02-pinhole-projection"


def _room(tmp_path):
    store = ProgressStore(tmp_path / "progress.sqlite3")
    assert store.persistent
    return store, Classroom(store)


def test_roster_after_scripted_progress(tmp_path):
    store, room = _room(tmp_path)
    total = load(LESSON).task_count
    assert total > 2
    room.join(1, "Ada")
    room.join(2, "Ben")
    room.join(3, "Cy")
    store.set_step("Ada", LESSON, 3)
    store.record_attempt("Ada", LESSON, 1, "t1", False)
    store.record_attempt("Ada", LESSON, 1, "t1", True)
    store.record_attempt("Ada", LESSON, 2, "t2", True)
    store.record_attempt("Ben", LESSON, 1, "t1", False)
    store.set_step("Cy", "01-frames-and-poses", 1)
    room.report_step(1, LESSON, 3)
    room.report_step(2, LESSON, 1)
    room.follow(2, False)
    room.leave(3)
    assert room.roster() == [
        RosterRow("Ada", True, True, LESSON, 3, 2, total),
        RosterRow("Ben", True, False, LESSON, 1, 0, total),
        # gone, so no live step: the lesson they last had progress in, from the database
        RosterRow("Cy", False, False, "01-frames-and-poses", 1, 0, load("01-frames-and-poses").task_count),
    ]


def test_a_student_without_progress_has_no_lesson(tmp_path):
    _, room = _room(tmp_path)
    room.join(1, "Newcomer")
    assert room.roster() == [RosterRow("Newcomer", True, True, None, None, 0, 0)]


def test_roster_without_a_progress_store_uses_live_state():
    room = Classroom(task_count=lambda lesson: 7 if lesson == "L" else 0)
    room.join(1, "zoe")
    room.join(2, "Adam")
    room.report_step(2, "L", 4)
    assert room.roster() == [RosterRow("Adam", True, True, "L", 4, 0, 7),
                             RosterRow("zoe", True, True, None, None, 0, 0)]


def test_two_tabs_of_one_student_are_one_row(tmp_path):
    _, room = _room(tmp_path)
    room.join(1, "Ada")
    room.join(2, "Ada")
    room.leave(1)
    rows = room.roster()
    assert [(r.name, r.connected) for r in rows] == [("Ada", True)]


def test_csv_escapes_formulas_and_keeps_odd_names_as_text(tmp_path):
    store, room = _room(tmp_path)
    names = ["=HYPERLINK(\"http://x\")", "+1", "-2", "@SUM(A1)", 'Quote "me", please', "Zoë 👩‍👩‍👧",
             "<b>bold</b>"]
    for tab, name in enumerate(names, start=1):
        room.join(tab, name)
    store.record_attempt("+1", LESSON, 0, "t0", True)
    room.report_step(2, LESSON, 0)
    room.record_answer(1, "=cmd|' /C calc'!A0", "-evil")
    room.record_answer(2, "=cmd|' /C calc'!A0", -1.5)
    text = room.roster_csv()
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == ["name", "connected", "following", "lesson", "step", "tasks passed", "tasks in lesson",
                       "answer: =cmd|' /C calc'!A0"]
    by_name = {r[0]: r for r in rows[1:]}
    assert set(by_name) == {"'=HYPERLINK(\"http://x\")", "'+1", "'-2", "'@SUM(A1)", 'Quote "me", please',
                            "Zoë 👩‍👩‍👧", "<b>bold</b>"}
    assert by_name["'+1"][1:] == ["yes", "yes", LESSON, "1", "1", str(load(LESSON).task_count), "-1.5"]
    assert by_name["'=HYPERLINK(\"http://x\")"][-1] == "'-evil"
    assert by_name["<b>bold</b>"][-1] == ""
    assert text.endswith("\r\n")
