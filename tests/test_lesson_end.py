"""The lesson panel's summary at the last step, kept current by each check, and the start page's "download my
record" (a CSV of the learner's own rows, sent through the browser; the server writes no file)."""

from __future__ import annotations

import csv
import io

from egtviz.lessons import ProgressStore

from test_progress_unusable import LESSON6, course, open_lesson, start_page


def test_the_last_step_shows_the_summary_and_each_check_updates_it(tmp_path):
    store = ProgressStore(tmp_path / "progress.sqlite3")
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        page.name.value = "Ada"
        panel = open_lesson(app, page, LESSON6)
        panel.row("meet").answer.value = "at the principal point"
        panel.row("meet").button.value = True
        shown = panel.row("meet").feedback.content
        assert "*(1 of 3)* Every epipolar plane contains the baseline" in shown and "(2 of 3)" not in shown
        panel.row("meet").button.value = True  # a second failure: the pointer joins the idea
        shown = panel.row("meet").feedback.content
        assert "(1 of 3)" in shown and "*(2 of 3)* Where does the baseline cross" in shown and "(3 of 3)" not in shown
        assert store.hints_shown("Ada", LESSON6, 0, "meet") == 2
        assert panel.summary is None  # not the last step
        last = len(panel.run.lesson.steps) - 1
        panel.go_to(last)
        total = panel.run.lesson.task_count
        assert panel.summary.content == (
            f"**End of the lesson.** Tasks passed: 0 of {total}; attempts: 2; hints used: 2; "
            "next lesson: *The fundamental and essential matrices*.")
        row = panel.rows[0]
        row.button.value = True  # the step's starting scene: not solved yet
        assert f"Tasks passed: 0 of {total}; attempts: 3; hints used: 3;" in panel.summary.content


def test_download_my_record_sends_the_learners_rows_as_csv(tmp_path):
    store = ProgressStore(tmp_path / "progress.sqlite3")
    store.record_attempt("Ada", LESSON6, 0, "meet", False, hint_tiers=3)
    store.record_attempt("Ada", LESSON6, 0, "meet", True, hint_tiers=3)
    store.record_attempt("=Eve", LESSON6, 0, "meet", True, hint_tiers=3)
    with course(store) as (app, open_tab):
        open_tab()
        page = start_page(app)
        sent, told = [], []
        page.client.send_file_download = lambda name, data, **kw: sent.append((name, data))
        page.client.add_notification = lambda title, body, **_: told.append(body)
        page.btn_record.value = True  # no name yet: nothing to download
        assert sent == [] and "type your name first" in told[-1]
        page.name.value = "Ada"
        page.btn_record.value = True
        ((name, data),) = sent
        rows = list(csv.reader(io.StringIO(data.decode("utf-8"))))
        assert name == "egtviz-record.csv" and len(rows) == 2
        assert rows[1][:7] == ["Ada", LESSON6, "1", "meet", "yes", "2", "1"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["progress.sqlite3"]
