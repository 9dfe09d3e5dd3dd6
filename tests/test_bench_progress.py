"""The start page's progress bench runs on today's schema and times the one-query read against the old one."""

from __future__ import annotations

import sqlite3

from egtviz.bench.progress import build_database, progress_rows
from egtviz.lessons import list_lessons


def test_the_bench_database_has_the_learners_and_their_tasks(tmp_path):
    path = tmp_path / "p.sqlite3"
    build_database(path, 7, [info.name for info in list_lessons()])
    conn = sqlite3.connect(path)
    try:
        assert conn.execute("SELECT COUNT(*) FROM learners").fetchone() == (7,)
        assert conn.execute("SELECT COUNT(*) FROM lesson_state").fetchone() == (21,)
        assert conn.execute("SELECT COUNT(*) FROM task_state").fetchone() == (63,)
    finally:
        conn.close()


def test_the_bench_rows_compare_the_read_with_the_old_one():
    (row,) = progress_rows((40,), repeats=1)
    assert row["case"] == "start page progress read, 40 learners"
    assert row["ours_ms"] > 0 and row["opencv_ms"] is None and row["ratio"] is None
    assert "3 queries a lesson" in row["note"] and "times as long" in row["note"]
