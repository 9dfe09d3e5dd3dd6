"""Real browser (headless Debian Chromium, playwright): the start page's "Download my record" gives a CSV file of
the learner's own rows, through the browser's download (the server writes no file)."""

from __future__ import annotations

import csv
import io

import pytest

from _waiting import PATIENCE, wait_for
from egtviz.lessons import ProgressStore
from egtviz.viewer.server.browser import close_notifications

pytestmark = pytest.mark.browser

LESSON6 = "06-pinhole-epipolar"


def test_download_my_record_gives_the_learners_rows_as_csv(browser, tmp_path):
    import viser

    from egtviz.viewer.tabs import EgtvizApp
    from egtviz.viewer.course.start_page import StartPage

    store = ProgressStore(tmp_path / "data" / "progress.sqlite3")
    store.record_attempt("Ada", LESSON6, 0, "meet", False, hint_tiers=3)
    store.record_attempt("Ada", LESSON6, 0, "meet", False, hint_tiers=3)
    store.record_attempt("Ada", LESSON6, 0, "meet", True, hint_tiers=3)
    store.record_attempt("Ada", LESSON6, 1, "epipole-target", False, hint_tiers=3)
    store.record_attempt("@Bob", LESSON6, 0, "meet", True, hint_tiers=3)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        app = EgtvizApp(server, course=True, progress=store)
        page = browser.new_page(viewport={"width": 1366, "height": 768}, accept_downloads=True)
        try:
            page.goto(f"http://127.0.0.1:{server.get_port()}")
            button = page.get_by_role("button", name="Download my record")
            button.wait_for()
            close_notifications(page)
            name = page.locator('xpath=//label[normalize-space(.)="your name"]/following::input[1]').first
            name.fill("Ada")
            (start,) = app.course.wait_for_tab(StartPage, timeout=PATIENCE)
            wait_for(lambda: start.learner == "Ada", "the name taken once the typing stops")
            with page.expect_download() as info:
                button.click()
            download = info.value
            saved = tmp_path / "got.csv"
            download.save_as(saved)
        finally:
            page.close()
        rows = list(csv.reader(io.StringIO(saved.read_text(encoding="utf-8"))))
        assert download.suggested_filename == "egtviz-record.csv"
        assert rows[0][:7] == ["learner", "lesson", "step", "task", "passed", "attempts", "hints used"]
        assert [r[:7] for r in rows[1:]] == [["Ada", LESSON6, "1", "meet", "yes", "3", "2"],
                                             ["Ada", LESSON6, "2", "epipole-target", "no", "1", "1"]]
        assert sorted(p.name for p in (tmp_path / "data").iterdir()) == ["progress.sqlite3"]  # no file written
    finally:
        server.stop()
