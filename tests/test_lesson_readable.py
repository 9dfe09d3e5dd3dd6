"""Lessons readable where they are used: a displayed formula that cannot fit the control panel is refused by
``egtviz check`` with its line and width, every shipped formula fits."""

from __future__ import annotations

import pytest

from egtviz.lessons import LessonError, parse_lesson
from egtviz.lessons.catalog import lessons_folder
from egtviz.lessons.cli import check_file
from egtviz.lessons.markup import PANEL_WIDTH_PX, displayed_formulas, formula_to_mathml, formula_width_px

LESSON = """\
title = "A lesson"
summary = "For the tests."
scene = "default"

[[steps]]
title = "First"
text = '''
The epipoles:

$$FORMULA$$

and more text.
'''
"""
WIDE = r"e_1 \simeq K_1 R_1^T (O_2 - O_1), \qquad e_2 \simeq K_2 R_2^T (O_1 - O_2) ."


def _parse(formula: str):
    return parse_lesson(LESSON.replace("FORMULA", formula).encode(), source="t.toml", name="01-test")


def test_a_formula_wider_than_the_panel_is_refused_with_its_line_and_width():
    with pytest.raises(LessonError) as info:
        _parse(WIDE)
    wide = formula_width_px(formula_to_mathml(WIDE, display=True))
    assert info.value.line == 10
    assert str(info.value) == (f"t.toml:10: formula is {wide:.0f} px wide, the panel shows {PANEL_WIDTH_PX:.0f} px "
                               "(break it into two displayed lines, or shorten it)")
    assert wide > 1.3 * PANEL_WIDTH_PX


def test_the_same_formula_on_two_displayed_lines_fits():
    lesson = _parse(r"e_1 \simeq K_1 R_1^T (O_2 - O_1),$$" "\n\n" r"$$e_2 \simeq K_2 R_2^T (O_1 - O_2) .")
    assert len(displayed_formulas(lesson.steps[0].text)) == 2


def test_a_formula_in_code_is_not_measured():
    lesson = _parse(r"x$$" "\n\n`$$" + WIDE + "$$`\n\n$$y")
    assert [latex for _, latex in displayed_formulas(lesson.steps[0].text)] == ["x", "y"]


@pytest.mark.parametrize(("narrow", "wide"), [
    ("x", "xxxxxxxx"), ("a + b", "a + b + c"), (r"x_1", r"x_{123}"),
    (r"\begin{bmatrix} a & b \end{bmatrix}", r"\begin{bmatrix} a & b & c \end{bmatrix}"),
    (r"\frac{a}{b}", r"\frac{a + b + c}{b}"), ("x", r"x \qquad y"),
])
def test_the_estimate_grows_with_what_is_written(narrow, wide):
    assert formula_width_px(formula_to_mathml(narrow, display=True)) < formula_width_px(
        formula_to_mathml(wide, display=True))


def test_every_lesson_of_the_course_passes_the_width_check():
    paths = sorted(lessons_folder().glob("*.toml"))
    assert len(paths) == 13
    assert [check_file(str(p)) for p in paths] == [None] * 13
