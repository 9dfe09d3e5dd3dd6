"""Progress in SQLite: keyed by the learner's typed name, versioned schema, safe across threads, and kept when
the database (the server) is closed and opened again."""

from __future__ import annotations

import argparse
import sqlite3
import threading
import unicodedata

import pytest

from egtviz.lessons import LessonRun, ProgressStore, load
from egtviz.lessons.cli import run_progress
from egtviz.lessons.progress import (
    MAX_LEARNER_NAME,
    SCHEMA_VERSION,
    LearnerNameError,
    ProgressRow,
    default_database_path,
    learner_key,
    migrate,
)


def test_progress_survives_closing_and_reopening_the_database(tmp_path):
    path = tmp_path / "progress.sqlite3"
    store = ProgressStore(path)
    store.set_step("Ada", "06-pinhole-epipolar", 2)
    store.record_attempt("Ada", "06-pinhole-epipolar", 1, "epipole-target", False)
    store.record_attempt("Ada", "06-pinhole-epipolar", 1, "epipole-target", True)
    store.record_attempt("Ada", "06-pinhole-epipolar", 1, "epipole-target", False)  # passed stays passed
    del store
    reopened = ProgressStore(path)
    assert reopened.current_step("Ada", "06-pinhole-epipolar") == 2
    assert reopened.passed_tasks("Ada", "06-pinhole-epipolar") == {(1, "epipole-target")}
    assert reopened.attempts("Ada", "06-pinhole-epipolar", 1, "epipole-target") == 3
    assert reopened.current_step("Ada", "01-frames-and-poses") == 0
    assert reopened.summary() == [ProgressRow("Ada", "06-pinhole-epipolar", 2, 1, 3)]


def test_a_runner_resumes_where_the_learner_was_after_a_restart(tmp_path):
    path = tmp_path / "p.sqlite3"
    lesson = load("07-fundamental-and-essential")
    run = LessonRun(lesson, "  Grace  Hopper ", progress=ProgressStore(path))
    run.next()
    run.next()
    attempt = run.check("fix-transpose")
    assert not attempt.result.passed
    # A new server process: a new store on the same file, a new runner for the same typed name.
    again = LessonRun(lesson, "Grace Hopper", progress=ProgressStore(path))
    assert again.step_index == 2 and again.lens.f_transposed  # the step's lens state replayed
    again.apply(again.step.tasks[0].solution[0])
    assert again.check("fix-transpose").result.passed
    assert ProgressStore(path).passed_tasks("Grace Hopper", lesson.name) == {(2, "fix-transpose")}
    assert ProgressStore(path).attempts("Grace Hopper", lesson.name, 2, "fix-transpose") == 2


def test_learner_names_are_trimmed_and_checked():
    assert learner_key("  Ada   Lovelace ") == "Ada Lovelace"
    assert learner_key("E\u0301milie") == "\u00c9milie"  # NFC: one name however it was typed
    for bad, words in (("", "empty"), ("   ", "empty"), ("x" * (MAX_LEARNER_NAME + 1), "at most"),
                       ("a\x1b[31m", "control"), (None, "expected text")):
        with pytest.raises(LearnerNameError, match=words):
            learner_key(bad)


@pytest.mark.parametrize("name", [
    "\U0001f468\u200d\U0001f469\u200d\U0001f467",  # a family: three emoji joined by zero-width joiners
    "Ada \U0001f469\U0001f3fd\u200d\U0001f4bb",  # a technologist with a skin tone
    "\U0001f441\ufe0f\u200d\U0001f5e8\ufe0f",  # variation selectors around a joiner
    "\u0645\u06cc\u200c\u062e\u0648\u0627\u0647\u0645",  # Persian: a zero-width non-joiner inside a word
    "\u2764\ufe0e",  # text presentation selector
])
def test_emoji_sequences_and_joined_scripts_are_names(name):
    assert learner_key(name) == unicodedata.normalize("NFC", name)


@pytest.mark.parametrize("name", [
    "Ada\u202eecalvol",  # right-to-left override: shows as another name
    "Ada\u2066x\u2069",  # bidi isolates
    "A\u200bda",  # zero-width space
    "\u200dAda", "Ada\u200d", "Ada \u200d Lovelace", "A\u200d\u200dda",  # a joiner with nothing to join
    "\U0001f3f4\U000e0067\U000e0062\U000e007f",  # tag characters (invisible text)
    "Ada\u00ad", "\ufeffAda", "Ada\u200e",  # soft hyphen, BOM, direction mark
])
def test_format_characters_that_can_hide_or_reorder_text_are_refused(name):
    with pytest.raises(LearnerNameError, match="control characters"):
        learner_key(name)


def test_several_threads_record_attempts_without_losing_any(tmp_path):
    store = ProgressStore(tmp_path / "p.sqlite3")
    errors = []

    def work(i: int) -> None:
        try:
            for _ in range(10):
                store.record_attempt(f"learner {i % 3}", "09-estimating-f", 0, "eight", False)
        except Exception as exc:  # noqa: BLE001 - collected and asserted below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert [store.attempts(f"learner {i}", "09-estimating-f", 0, "eight") for i in range(3)] == [20, 20, 20]
    assert store.learners() == ["learner 0", "learner 1", "learner 2"]


def test_the_schema_is_versioned_and_a_newer_one_is_refused(tmp_path):
    path = tmp_path / "p.sqlite3"
    ProgressStore(path)
    with sqlite3.connect(path) as conn:
        assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION
        assert migrate(conn) == SCHEMA_VERSION  # nothing to do
        conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    with pytest.raises(sqlite3.DatabaseError, match="newer|version"):
        migrate(sqlite3.connect(path))
    newer = ProgressStore(path)  # the course still starts: progress is kept in memory, the file is left alone
    assert not newer.persistent and f"schema version {SCHEMA_VERSION + 1}" in newer.problem


def test_the_database_lives_in_the_users_data_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("EGTVIZ_DATA_DIR", str(tmp_path / "a"))
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "b"))
    assert default_database_path() == tmp_path / "a" / "progress.sqlite3"
    monkeypatch.delenv("EGTVIZ_DATA_DIR")
    assert default_database_path() == tmp_path / "b" / "egtviz" / "progress.sqlite3"
    monkeypatch.delenv("XDG_DATA_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_database_path() == tmp_path / "home" / ".local" / "share" / "egtviz" / "progress.sqlite3"


def test_egtviz_progress_prints_a_table(tmp_path, capsys):
    path = tmp_path / "p.sqlite3"
    assert run_progress(argparse.Namespace(database=str(path))) == 0
    assert capsys.readouterr().out == "no progress recorded yet\n"
    store = ProgressStore(path)
    store.set_step("Bob", "01-frames-and-poses", 3)
    store.record_attempt("Ada", "02-pinhole-projection", 0, "depth", True)
    assert run_progress(argparse.Namespace(database=str(path))) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["learner", "lesson", "step", "tasks", "done", "attempts"]
    assert lines[1].split() == ["Ada", "02-pinhole-projection", "1", "1", "1"]
    assert lines[2].split() == ["Bob", "01-frames-and-poses", "4", "0", "0"]
    folder = tmp_path / "dir.sqlite3"
    folder.mkdir()
    assert run_progress(argparse.Namespace(database=str(folder))) == 2
