"""Every displayed formula of the course in the lesson panel of headless Chromium at 1366 x 768, with and without
presentation mode: none runs past the panel's edge, and ``egtviz check``'s width estimate is never below the width
Chromium renders (so a formula the check lets through fits)."""

from __future__ import annotations

import pytest

from egtviz.lessons.catalog import lessons_folder
from egtviz.lessons.format import load_lesson
from egtviz.lessons.markup import (
    FORMULA_FONT_PX,
    PANEL_WIDTH_PX,
    displayed_formulas,
    formula_to_mathml,
    formula_width_px,
)
from egtviz.viewer.course.lesson_view import MATH_CSS
from egtviz.viewer.render.palette import PRESENT_GUI_CSS

pytestmark = pytest.mark.browser

# Each formula's width as rendered (max-content, not capped by the panel), its box's width in the panel, the
# scroll width in the panel (wider than the box: the formula is cut and scrolls) and its type size.
MEASURE = """() => [...document.querySelectorAll('math[display="block"]')].map(m => {
    const box = m.clientWidth, scroll = m.scrollWidth;
    m.style.maxWidth = 'none'; m.style.width = 'max-content';
    const natural = m.getBoundingClientRect().width;
    m.style.width = ''; m.style.maxWidth = '';
    return {natural, box, scroll, font: parseFloat(getComputedStyle(m).fontSize)};
})"""


def _course_formulas() -> list[tuple[str, str]]:
    out = []
    for path in sorted(lessons_folder().glob("*.toml")):
        for i, step in enumerate(load_lesson(path).steps):
            out += [(f"{path.name} step {i + 1}", latex) for _, latex in displayed_formulas(step.text)]
    return out


def _measure(browser, formulas: list[tuple[str, str]], *, present: bool) -> list[dict]:
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        gui = server.gui
        gui.configure_theme(dark_mode=False, show_logo=False)
        gui.add_html(MATH_CSS)
        gui.add_html(PRESENT_GUI_CSS if present else "")
        with gui.add_folder("Lesson"):  # the step text's place in a lesson tab
            for i, (_, latex) in enumerate(formulas):
                gui.add_markdown(f"formula {i}\n\n{formula_to_mathml(latex, display=True)}\n\n")
        page = browser.new_page(viewport={"width": 1366, "height": 768})
        try:
            page.goto(f"http://127.0.0.1:{server.get_port()}")
            page.get_by_text(f"formula {len(formulas) - 1}", exact=True).wait_for()
            page.evaluate("() => document.fonts.ready.then(() => true)")  # laid out in the fonts it will keep
            return page.evaluate(MEASURE)
        finally:
            page.close()
    finally:
        server.stop()


@pytest.mark.parametrize("present", [False, True], ids=["normal", "present"])
def test_no_displayed_formula_overflows_and_the_estimate_is_never_under(browser, present):
    formulas = _course_formulas()
    assert len(formulas) >= 25
    shown = _measure(browser, formulas, present=present)
    assert len(shown) == len(formulas)
    overflowing = [(where, s["scroll"], s["box"]) for (where, _), s in zip(formulas, shown, strict=True)
                   if s["scroll"] > s["box"]]
    assert overflowing == []
    under = [(where, latex, round(formula_width_px(formula_to_mathml(latex, display=True), s["font"]), 1),
              round(s["natural"], 1))
             for (where, latex), s in zip(formulas, shown, strict=True)
             if formula_width_px(formula_to_mathml(latex, display=True), s["font"]) < s["natural"]]
    assert under == []
    # The check's panel, in ems of the formula's type, is the narrowest the browser shows.
    panel_em = min(s["box"] / s["font"] for s in shown)
    assert PANEL_WIDTH_PX / FORMULA_FONT_PX <= panel_em + 0.01


def test_the_formulas_cut_before_are_wider_than_the_panel_and_the_check_says_so(browser):
    """Lesson 6 step 1's pair of epipoles, as it was written on one line, overflowed; the estimate refuses it."""
    latex = r"e_1 \simeq K_1 R_1^T (O_2 - O_1), \qquad e_2 \simeq K_2 R_2^T (O_1 - O_2) ."
    shown = _measure(browser, [("lesson 6 as it was", latex)], present=True)[0]
    assert shown["scroll"] > shown["box"]
    assert formula_width_px(formula_to_mathml(latex, display=True), shown["font"]) >= shown["natural"] > PANEL_WIDTH_PX
