"""The roster reads without scrolling sideways in the instructor's panel, at a laptop's size and at a lecture
hall's (1920x1080, also with ``--present``): every column inside the panel, no header broken over two lines."""

from __future__ import annotations

import pytest

from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom import ClassroomHost, instructor_url

pytestmark = pytest.mark.browser

LESSON = "06-pinhole-epipolar"
NAMES = ("Ada Lovelace", "Bartholomew Featherstonehaugh", "W" * 40, "Dora")
FIT_JS = """(e) => {
  const box = e.getBoundingClientRect();
  const heads = Array.from(e.querySelectorAll('th')).map(t => t.getBoundingClientRect().height);
  const cells = Array.from(e.querySelectorAll('td')).map(t => t.getBoundingClientRect().right);
  const line = parseFloat(getComputedStyle(e.querySelector('th')).lineHeight)
    || 1.3 * parseFloat(getComputedStyle(e.querySelector('th')).fontSize);
  return {scroll: e.scrollWidth, client: e.clientWidth, right: box.right, cells: Math.max(...cells), heads, line};
}"""


@pytest.mark.parametrize("width, height, present", [(1366, 768, False), (1920, 1080, False), (1920, 1080, True)])
def test_the_roster_fits_the_instructors_panel(browser, tmp_path, width, height, present):
    import viser

    from egtviz.viewer.server.guard import install_guards
    from egtviz.viewer.tabs import EgtvizApp

    store = ProgressStore(tmp_path / "progress.db")
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    install_guards(server)
    app = EgtvizApp(server, None, field_delay=0.0, course=True, progress=store, present=present)
    base = f"http://127.0.0.1:{server.get_port()}"
    host = ClassroomHost(app, student_url=base)
    context = browser.new_context(viewport={"width": width, "height": height})
    try:
        for k, name in enumerate(NAMES):  # scripted students: the roster is the class's, not the tabs'
            host.room.join(10_000 + k, name)
            host.room.report_step(10_000 + k, LESSON, 2)
        page = context.new_page()
        page.goto(instructor_url(base, host.room.instructor_token))
        page.wait_for_selector("text=follow me")
        page.get_by_text("Students", exact=True).first.click()
        roster = page.locator(f'[data-egtviz="roster"][data-rows="{len(NAMES)}"]').first
        roster.wait_for(state="visible")
        fit = roster.evaluate(FIT_JS)
        assert fit["scroll"] <= fit["client"], fit  # nothing to scroll sideways to
        assert fit["cells"] <= fit["right"] + 0.5, fit  # the tasks column is inside the panel
        assert max(fit["heads"]) < 1.5 * fit["line"] + 4, fit  # each header on one line
        assert roster.locator('[data-col="where"]').first.inner_text() == "following · lesson 6 · step 3"
    finally:
        context.close()
        host.close()
        server.stop()
