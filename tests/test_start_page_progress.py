"""The start page reads progress in one indexed query per render and takes a name once the typing stops; a
refused name is not left in a name field (it shows the name in use again)."""

from __future__ import annotations

import sqlite3

import pytest

from egtviz.lessons import ProgressStore, list_lessons
from egtviz.viewer.course.lesson_view import LessonPanel

from test_progress_unusable import LESSON6, course, start_page

from _waiting import PATIENCE, wait_for


@pytest.fixture
def traced(monkeypatch):
    """The SELECT statements every new SQLite connection runs from now on (as run: parameters filled in)."""
    statements: list[str] = []
    real = sqlite3.connect

    def connect(*args, **kwargs):
        conn = real(*args, **kwargs)
        conn.set_trace_callback(statements.append)
        return conn

    def selects() -> list[str]:
        return [s for s in statements if s.lstrip().upper().startswith("SELECT")]

    def start() -> None:
        statements.clear()
        monkeypatch.setattr(sqlite3, "connect", connect)

    return start, selects


def test_one_render_of_the_start_page_is_one_indexed_query(tmp_path, traced):
    path = tmp_path / "progress.sqlite3"
    store = ProgressStore(path)
    for i in range(50):
        store.set_step(f"learner {i}", LESSON6, 1)
        store.record_attempt(f"learner {i}", LESSON6, 0, "meet", True)
    store.set_step("Ada", LESSON6, 1)
    store.record_attempt("Ada", LESSON6, 0, "meet", True)
    start, selects = traced
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        start()
        page.name.value = "Ada"
        assert page.learner == "Ada" and 'data-status="step 2 of 3"' in page.status[LESSON6].content
        assert len(page.status) == len(list_lessons()) > 1
        (query,) = selects()  # one query for every lesson's line, not three per lesson
    with sqlite3.connect(f"file:{path}?mode=ro", uri=True) as conn:
        plan = [row[3] for row in conn.execute("EXPLAIN QUERY PLAN " + query)]
    reads = [step for step in plan if step.startswith(("SCAN", "SEARCH"))]
    assert reads and all(step.startswith("SEARCH") and "INDEX" in step for step in reads), plan  # no table scan


def test_typing_a_name_renders_the_page_once_the_typing_stops(tmp_path, traced):
    store = ProgressStore(tmp_path / "progress.sqlite3")
    start, selects = traced
    # A delay that the three keystrokes and the check after them stay well inside on a busy machine.
    with course(store, field_delay=2.0) as (app, open_tab):
        open_tab()
        page = start_page(app)
        start()
        for text in ("A", "Ad", "Ada"):
            page.name.value = text
        assert selects() == [] and page.learner == ""  # nothing yet: "A" and "Ad" are not learners
        # The page takes the name, then renders it: wait for the render's query too, then count the renders.
        wait_for(lambda: page.learner == "Ada" and selects(), "the start page to take and render the name once "
                 "the typing stopped")
        assert len(selects()) == 1


def test_a_refused_name_on_the_start_page_shows_the_name_in_use(tmp_path):
    with course(ProgressStore(tmp_path / "p.sqlite3")) as (app, open_tab):
        open_tab()
        page = start_page(app)
        told = []
        page.client.add_notification = lambda title, body, **_: told.append(body)
        page.name.value = "Ada"
        page.name.value = "Ada\u202eecalvol"
        assert page.learner == "Ada" and page.name.value == "Ada"  # not the refused text
        assert told == ["name: control characters are not allowed (U+202E)"]
        family = "\U0001f468\u200d\U0001f469\u200d\U0001f467"
        page.name.value = family
        assert page.learner == family and page.name.value == family


def test_a_refused_name_in_a_lesson_shows_the_name_in_use(tmp_path):
    store = ProgressStore(tmp_path / "p.sqlite3")
    store.set_step("Hypatia", LESSON6, 2)
    with course(store, lesson=LESSON6) as (app, open_tab):
        open_tab()
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        told = []
        panel.view.client.add_notification = lambda title, body, **_: told.append(body)
        panel.learner.value = "x" * 41
        assert panel.run.learner == "" and panel.learner.value == ""  # still anonymous, and the field says so
        panel.learner.value = "Hypatia"
        panel.learner.value = "Hyp\u200batia"
        assert panel.run.learner == "Hypatia" and panel.learner.value == "Hypatia" and panel.run.step_index == 2
        assert told == ["name: at most 40 characters, got 41", "name: control characters are not allowed (U+200B)"]
