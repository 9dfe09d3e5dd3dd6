"""The progress database's schema 2 (hints per task) upgraded from a version-1 file without losing anything, and
the records as CSV (``egtviz progress --csv``, ``--out``): one row per learner, lesson, step and task, names
guarded against spreadsheet formulas."""

from __future__ import annotations

import argparse
import csv
import io
import sqlite3

import pytest

from egtviz.lessons import ProgressStore
from egtviz.lessons.cli import add_progress_arguments, run_progress
from egtviz.lessons.progress import SCHEMA_VERSION
from egtviz.lessons.records import CSV_HEADER, records_csv, safe_cell

LESSON = "06-pinhole-epipolar"

#: The version-1 schema exactly as egtviz wrote it before hints were counted.
V1 = (
    "CREATE TABLE learners (name TEXT PRIMARY KEY, created REAL NOT NULL)",
    """CREATE TABLE lesson_state (learner TEXT NOT NULL REFERENCES learners(name), lesson TEXT NOT NULL,
       step INTEGER NOT NULL, updated REAL NOT NULL, PRIMARY KEY (learner, lesson))""",
    """CREATE TABLE task_state (learner TEXT NOT NULL REFERENCES learners(name), lesson TEXT NOT NULL,
       step INTEGER NOT NULL, task TEXT NOT NULL, attempts INTEGER NOT NULL, passed INTEGER NOT NULL,
       updated REAL NOT NULL, PRIMARY KEY (learner, lesson, step, task))""",
)


def version_1_file(path) -> None:
    conn = sqlite3.connect(path)
    with conn:
        for statement in V1:
            conn.execute(statement)
        conn.execute("PRAGMA user_version = 1")
        conn.execute("INSERT INTO learners VALUES ('Ada', 1.0)")
        conn.execute(f"INSERT INTO lesson_state VALUES ('Ada', '{LESSON}', 2, 2.0)")
        conn.execute(f"INSERT INTO task_state VALUES ('Ada', '{LESSON}', 0, 'meet', 3, 1, 1700000000.0)")
        conn.execute(f"INSERT INTO task_state VALUES ('Ada', '{LESSON}', 1, 'epipole-target', 2, 0, 1700000100.0)")
    conn.close()


def test_a_version_1_file_is_upgraded_keeping_its_progress(tmp_path):
    assert SCHEMA_VERSION == 2
    path = tmp_path / "progress.sqlite3"
    version_1_file(path)
    store = ProgressStore(path)
    assert store.persistent and store.problem is None
    with sqlite3.connect(path) as conn:
        assert conn.execute("PRAGMA user_version").fetchone()[0] == 2
    assert store.current_step("Ada", LESSON) == 2
    assert store.passed_tasks("Ada", LESSON) == {(0, "meet")}
    assert store.attempts("Ada", LESSON, 0, "meet") == 3 and store.attempts("Ada", LESSON, 1, "epipole-target") == 2
    assert [(r.task, r.hints, r.updated) for r in store.task_records()] == [
        ("meet", 0, 1700000000.0), ("epipole-target", 0, 1700000100.0)]
    assert store.record_attempt("Ada", LESSON, 1, "epipole-target", False, hint_tiers=3) == 1
    assert ProgressStore(path).hints_shown("Ada", LESSON, 1, "epipole-target") == 1


def test_a_report_reads_a_version_1_file_without_changing_it(tmp_path, capsys):
    path = tmp_path / "progress.sqlite3"
    version_1_file(path)
    before = path.read_bytes()
    store = ProgressStore(path, read_only=True)
    assert store.fault is None and [r.hints for r in store.task_records()] == [0, 0]
    assert run_progress(_args("--database", str(path), "--csv")) == 0
    rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert rows[1] == ["Ada", LESSON, "1", "meet", "yes", "3", "0", "2023-11-14 22:13:20"]
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["progress.sqlite3"]


def _args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_progress_arguments(parser)
    return parser.parse_args(argv)


HOSTILE = ("=HYPERLINK(\"http://x\")", "+1+1", "-2", "@SUM(A1)", "Ada, \"the\" first")


@pytest.fixture
def store(tmp_path):
    store = ProgressStore(tmp_path / "progress.sqlite3")
    for name in HOSTILE:
        store.record_attempt(name, LESSON, 0, "meet", False, hint_tiers=1)
        store.record_attempt(name, LESSON, 0, "meet", True, hint_tiers=1)
    store.record_attempt("Ada, \"the\" first", LESSON, 1, "epipole-target", False, hint_tiers=3)
    store.record_attempt("Ada, \"the\" first", LESSON, 1, "epipole-target", False, hint_tiers=3)
    return store


def test_the_csv_has_one_row_per_learner_lesson_step_and_task(store, capsys):
    assert run_progress(_args("--database", str(store.path), "--csv")) == 0
    rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert tuple(rows[0]) == CSV_HEADER
    body = [r[:7] for r in rows[1:]]
    assert len(body) == 6
    assert ["Ada, \"the\" first", LESSON, "1", "meet", "yes", "2", "1"] in body
    assert ["Ada, \"the\" first", LESSON, "2", "epipole-target", "no", "2", "2"] in body
    assert all(len(r[7]) == len("2026-12-02 00:00:00") for r in rows[1:])


def test_a_cell_that_would_be_a_formula_is_written_as_text(store):
    learners = [r[0] for r in csv.reader(io.StringIO(records_csv(store.task_records())))][1:]
    assert sorted(set(learners)) == sorted(["'=HYPERLINK(\"http://x\")", "'+1+1", "'-2", "'@SUM(A1)",
                                            "Ada, \"the\" first"])
    assert safe_cell("=1") == "'=1" and safe_cell("\tx") == "'\tx" and safe_cell("a=1") == "a=1"


def test_out_writes_the_csv_and_refuses_a_folder(store, tmp_path, capsys):
    out = tmp_path / "grades.csv"
    assert run_progress(_args("--database", str(store.path), "--out", str(out))) == 0
    assert out.read_bytes() == records_csv(store.task_records()).encode("utf-8")
    (tmp_path / "folder.csv").mkdir()
    assert run_progress(_args("--database", str(store.path), "--out", str(tmp_path / "folder.csv"))) == 2
    assert "will not replace a directory" in capsys.readouterr().err
