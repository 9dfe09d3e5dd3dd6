"""A progress database that cannot be used, from the start or from some moment on, never stops the course: it
says once why (naming the file), keeps this session's progress in memory, and leaves the file as it was."""

from __future__ import annotations

import argparse
import logging
import os
import random
import sqlite3
import stat
import subprocess
from contextlib import contextmanager
from pathlib import Path

import pytest
import viser

from egtviz.lessons import LessonRun, ProgressStore, load
from egtviz.lessons.cli import run_progress
from egtviz.lessons.progress import SCHEMA_VERSION
from egtviz.viewer.tabs import EgtvizApp
from egtviz.viewer.workbench.app import ClientView
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.course.lesson_view import LessonPanel
from egtviz.viewer.course.start_page import StartPage

from _waiting import PATIENCE

LESSON6 = "06-pinhole-epipolar"
MEET = "at the epipole e1, the image of cam2's centre"
CASES = ("random bytes", "newer schema", "folder", "FIFO", "read-only folder", "full disk")


@contextmanager
def course(progress: ProgressStore | None, field_delay: float = 0.0, **kwargs):
    """A server serving the course, with ``open_tab()`` connecting one more fake browser tab."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tabs: list[FakeTab] = []
    try:
        app = EgtvizApp(server, field_delay=field_delay, course=True, progress=progress, **kwargs)

        def open_tab() -> FakeTab:
            tabs.append(FakeTab(server.get_port()))
            return tabs[-1]

        yield app, open_tab
    finally:
        for t in tabs:
            t.close()
        server.stop()


def start_page(app: EgtvizApp) -> StartPage:
    return app.course.wait_for_tab(StartPage, timeout=PATIENCE)[-1]


def open_lesson(app: EgtvizApp, page: StartPage, name: str) -> LessonPanel:
    page.buttons[name].value = True
    (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
    return panel


def snapshot(folder: Path) -> dict[str, object]:
    """Everything in ``folder``: each file's bytes, each folder's listing, other kinds by name (a FIFO is not read)."""
    out: dict[str, object] = {}
    for entry in sorted(folder.iterdir()):
        mode = entry.lstat().st_mode
        if stat.S_ISREG(mode):
            out[entry.name] = entry.read_bytes()
        elif stat.S_ISDIR(mode):
            out[entry.name] = sorted(p.name for p in entry.iterdir())
        else:
            out[entry.name] = stat.filemode(mode)
    return out


def database_with_ada(path: Path, learner: str = "Ada") -> None:
    """A progress database in which Ada (or ``learner``) is at step 3 of lesson 6."""
    ProgressStore(path).set_step(learner, LESSON6, 2)


@contextmanager
def read_only_folder(folder: Path, monkeypatch):
    """``folder`` made read-only by what this machine allows: its mode for a user; for root (who ignores modes)
    the immutable flag; for root without the right to set it, the store's write check is told the folder is
    read-only (os.access answers for the folder as it would for a user)."""
    folder.chmod(0o555)
    immutable = False
    if os.geteuid() == 0:
        try:
            immutable = subprocess.run(["chattr", "+i", str(folder)], capture_output=True).returncode == 0
        except OSError:  # no chattr on this machine
            immutable = False
        if not immutable:
            real = os.access
            monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if mode & os.W_OK and Path(p) == folder
                                else real(p, mode, **kw))
    try:
        yield
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(folder)], check=True)
        folder.chmod(0o755)


@pytest.fixture(params=CASES)
def unusable(request, tmp_path, monkeypatch):
    """``(path, store options, words the reason must have)`` of a progress database that cannot be used."""
    folder = tmp_path / "data"
    folder.mkdir()
    path = folder / "progress.sqlite3"
    case = request.param
    options: dict = {}
    if case == "random bytes":
        path.write_bytes(random.Random(15).randbytes(8192))
        words = "is not a progress database"
    elif case == "newer schema":
        database_with_ada(path, "Bob")
        with sqlite3.connect(path) as conn:
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
        words = f"newer egtviz (schema version {SCHEMA_VERSION + 1}"
    elif case == "folder":
        path.mkdir()
        (path / "kept.txt").write_text("not progress")
        words = "is a folder"
    elif case == "FIFO":
        os.mkfifo(path)
        words = "is a FIFO"
    elif case == "full disk":
        path.write_bytes(b"")  # a new database that cannot grow past its first page
        options["max_pages"] = 1
        words = "database or disk is full"
    else:
        database_with_ada(path, "Bob")
        words = "is read-only"
    with read_only_folder(folder, monkeypatch) if case == "read-only folder" else contextmanager(lambda: (yield))():
        yield case, path, options, words


def test_a_database_that_cannot_be_used_leaves_a_working_store_and_the_file_as_it_was(unusable, caplog):
    case, path, options, words = unusable
    before = snapshot(path.parent)
    with caplog.at_level(logging.WARNING, logger="egtviz.lessons.progress"):
        store = ProgressStore(path, **options)
        assert not store.persistent
        assert store.problem.startswith("Progress is not being kept: ")
        assert str(path) in store.problem and words in store.problem
        # The read-only database can still be read: Bob's earlier progress is shown.
        assert store.current_step("Bob", LESSON6) == (2 if case == "read-only folder" else 0)
        run = LessonRun(load(LESSON6), "Ada", progress=store)
        assert run.check("meet", MEET).result.passed
        assert run.next()
        assert store.current_step("Ada", LESSON6) == run.step_index == 1
        assert store.passed_tasks("Ada", LESSON6) == {(0, "meet")} and store.attempts("Ada", LESSON6, 0, "meet") == 1
    assert [r.getMessage() for r in caplog.records] == [f"egtviz: {store.problem}"]  # said once
    assert snapshot(path.parent) == before  # not written, no journal, not migrated


def test_the_course_starts_and_says_why_progress_is_not_kept(unusable):
    _, path, options, words = unusable
    before = snapshot(path.parent)
    with course(ProgressStore(path, **options)) as (app, open_tab):
        open_tab()
        page = start_page(app)
        assert 'data-egtviz="progress-notice"' in page.notice.content and words in page.notice.content
        page.name.value = "Ada"
        panel = open_lesson(app, page, LESSON6)
        assert 'data-egtviz="progress-notice"' in panel.notice.content
        panel.row("meet").answer.value = MEET
        panel.row("meet").button.value = True
        assert panel.attempts["meet"].result.passed
        panel.btn_back.value = True
        page = start_page(app)
        assert 'data-status="step' in page.status[LESSON6].content  # kept for the session
        page.btn_workbench.value = True  # the workbench opens too
        (view,) = app.course.wait_for_tab(ClientView, timeout=PATIENCE)
        assert view.model.scene.cameras
    assert snapshot(path.parent) == before


def test_a_data_folder_that_is_a_file_is_named(tmp_path, monkeypatch):
    target = tmp_path / "notes.txt"
    target.write_text("my notes")
    monkeypatch.setenv("EGTVIZ_DATA_DIR", str(target))
    with course(None) as (app, open_tab):  # the course's default store, in the data folder
        open_tab()
        page = start_page(app)
        assert f"the data folder {target} is a file, not a folder" in page.notice.content
    assert target.read_text() == "my notes" and sorted(tmp_path.iterdir()) == [target]


def test_a_data_folder_below_a_file_is_named(tmp_path, monkeypatch):
    target = tmp_path / "notes.txt"
    target.write_text("my notes")
    monkeypatch.setenv("EGTVIZ_DATA_DIR", str(target / "egtviz"))
    store = ProgressStore()
    assert store.fault == f"the data folder {target / 'egtviz'} cannot be made (a part of its path is a file)"
    assert target.read_text() == "my notes"


def fill_to_the_brim(path: Path) -> None:
    """Fill the task table's page so that one more row of a real learner needs a new page (with the page count
    capped: SQLITE_FULL, a full disk)."""
    conn = sqlite3.connect(path, isolation_level=None)
    try:
        for i in range(10_000):
            pages = conn.execute("PRAGMA page_count").fetchone()[0]
            conn.execute("SAVEPOINT fill")
            conn.execute("INSERT INTO task_state (learner, lesson, step, task, attempts, passed, updated) "
                         "VALUES ('~', 'x', 0, ?, 1, 0, 0.0)", (str(i),))
            grew = conn.execute("PRAGMA page_count").fetchone()[0] > pages
            conn.execute("ROLLBACK TO fill" if grew else "RELEASE fill")
            if grew:
                conn.execute("RELEASE fill")
                return
    finally:
        conn.close()
    raise AssertionError("the page never filled")


@pytest.mark.parametrize("how", ["full disk", "file replaced by a folder"])
def test_checks_and_steps_keep_working_when_the_database_fails_mid_lesson(how, tmp_path):
    path = tmp_path / "progress.sqlite3"
    store = ProgressStore(path)
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        page.name.value = "Ada"
        panel = open_lesson(app, page, LESSON6)
        told = []
        panel.view.client.add_notification = lambda title, body, **_: told.append((title, body))
        if how == "full disk":
            fill_to_the_brim(path)
            store.max_pages = 1  # the disk is full now: no page beyond those the file has
        else:
            path.rename(tmp_path / "moved.sqlite3")
            path.mkdir()
        assert panel.notice.content == "" and store.persistent
        panel.row("meet").answer.value = MEET
        panel.row("meet").button.value = True
        assert "Passed" in panel.row("meet").feedback.content  # a verdict, not an OperationalError
        panel.nav.buttons.value = "next"
        assert panel.run.step_index == 1 and 'data-step="1"' in panel.nav.head.content  # page and lesson agree
        for _ in range(2):
            panel.rows[0].button.value = True
            assert panel.rows[0].task_id in panel.attempts  # the next Check works (no KeyError)
        assert not store.persistent and str(path) in store.problem
        assert told == [("Progress is not being kept", store.problem)]  # one notice in the tab, not one per click
        assert 'data-egtviz="progress-notice"' in panel.notice.content
        assert store.current_step("Ada", LESSON6) == 1 and store.passed_tasks("Ada", LESSON6) == {(0, "meet")}
    if how == "full disk":
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True) as conn:  # the file holds what it held
            assert conn.execute("SELECT count(*) FROM task_state WHERE learner = 'Ada'").fetchone()[0] == 0


def test_a_store_falls_back_once_and_keeps_what_the_file_held(tmp_path, caplog):
    path = tmp_path / "p.sqlite3"
    store = ProgressStore(path)
    store.set_step("Ada", LESSON6, 2)
    fill_to_the_brim(path)
    store.max_pages = 1
    with caplog.at_level(logging.WARNING, logger="egtviz.lessons.progress"):
        for k in range(3):
            store.record_attempt("Grace", LESSON6, 0, "meet", passed=k == 2)
    assert len(caplog.records) == 1 and "database or disk is full" in caplog.records[0].getMessage()
    assert store.current_step("Ada", LESSON6) == 2  # carried over from the file
    assert store.attempts("Grace", LESSON6, 0, "meet") == 3 and store.passed_tasks("Grace", LESSON6) == {(0, "meet")}


# -- egtviz progress: a report opens read-only and creates nothing ------------------------------------------------


def report(path) -> int:
    return run_progress(argparse.Namespace(database=str(path)))


def test_the_report_creates_nothing_for_a_path_that_does_not_exist(tmp_path, capsys):
    assert report(tmp_path / "new" / "folder" / "p.sqlite3") == 0
    assert capsys.readouterr().out == "no progress recorded yet\n"
    assert list(tmp_path.iterdir()) == []


def test_the_report_reads_a_database_without_writing_or_journalling(tmp_path, capsys):
    path = tmp_path / "p.sqlite3"
    database_with_ada(path)
    before = snapshot(tmp_path)
    (tmp_path).chmod(0o555)  # a user's read-only folder (root ignores it; the snapshot below still checks)
    try:
        assert report(path) == 0
    finally:
        tmp_path.chmod(0o755)
    assert capsys.readouterr().out.splitlines()[1].split() == ["Ada", LESSON6, "3", "0", "0"]
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("content, words", [
    (b"", "is not a progress database (it holds no progress tables)"),
    (b"remember the milk\n", "is not a progress database (file is not a database)"),
    ("other sqlite", "is not a progress database (it holds other tables)"),
    ("newer", "newer egtviz"),
])
def test_the_report_refuses_what_is_not_a_progress_database(tmp_path, capsys, content, words):
    path = tmp_path / "notes.txt"
    if content == "other sqlite":
        with sqlite3.connect(path) as conn:
            conn.execute("CREATE TABLE recipes (name TEXT)")
    elif content == "newer":
        database_with_ada(path)
        with sqlite3.connect(path) as conn:
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    else:
        path.write_bytes(content)
    before = snapshot(tmp_path)
    assert report(path) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"egtviz: progress: {path} ") and words in err
    assert snapshot(tmp_path) == before


def test_the_report_leaves_device_paths_alone(capsys):
    assert not os.path.exists("/dev/null-journal")
    assert report("/dev/null") == 2
    assert "is a device" in capsys.readouterr().err
    assert not os.path.exists("/dev/null-journal")
