"""What ``egtviz check``, ``egtviz lesson`` and the lesson loader say: every refusal has a reason, sizes are
exact, names are shown with their control characters written out, and a ``.TOML`` file is a lesson."""

from __future__ import annotations

import pytest

from egtviz.cli import main
from egtviz.lessons import LessonError, load_lesson, parse_lesson
from egtviz.lessons.catalog import load
from egtviz.lessons.cli import check_file
from egtviz.lessons.markup import MarkupError, render_markdown
from egtviz.scene.limits import MAX_LESSON_FILE_BYTES

GOOD = """\
title = "A lesson"
summary = "For the tests."
scene = "default"

[[steps]]
title = "First"
text = '''
The constraint $m_2^T F m_1 = 0$,
and then FORMULA here.
'''
"""


def lesson_with(formula: str) -> str:
    return GOOD.replace("FORMULA", formula)


def test_a_lesson_name_is_printed_with_its_escape_sequences_written_out(capsys):
    assert main(["lesson", "\x1b[31mred\x07", "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\x07" not in err
    assert err.startswith("egtviz: cannot open the lesson: \\x1b[31mred\\x07:1: no lesson of that name (have: ")
    with pytest.raises(LessonError) as info:
        load("\x9b2J")  # a C1 control (CSI) too
    assert info.value.file == "\\x9b2J"


@pytest.mark.parametrize(("formula", "reason"), [
    (r"\begin{matrix} 1 & 2", r"a \begin{...} without its matching \end{...}"),
    (r"\begin{pmatrix} 1 \end{bmatrix}", r"a \begin{...} without its matching \end{...}"),
    (r"\left( x", r"a \left without its \right, or a \right without its \left"),
    (r"x \right)", r"a \left without its \right, or a \right without its \left"),
    ("x^", "a ^ or _ with nothing after it"),
    (r"\sqrt", r"a command is missing its argument (e.g. \sqrt or \frac at the end)"),
    (r"x_a_b", "two subscripts on one symbol (write x_{ab}, not x_a_b)"),
    (r"\frac{1}{2", "the '{' at character 9 is never closed"),
    ("}}}}", "the '}' at character 1 closes no '{'"),
    (r"a_{b", "the '{' at character 3 is never closed"),
    (r"\text{ab", "the '{' at character 6 is never closed"),
    (r"\frac{1}", r"a fraction needs a numerator and a denominator (\frac{a}{b})"),
])
def test_every_formula_refusal_says_why(formula, reason):
    with pytest.raises(MarkupError) as info:
        render_markdown(f"see ${formula}$")
    assert str(info.value) == f"cannot render the formula '{formula}': {reason}"
    assert info.value.offset == 4


def test_escaped_braces_are_characters_not_groups():
    assert "<mo stretchy=\"false\">{</mo>" in render_markdown(r"$\{x\}$")


@pytest.mark.parametrize(("formula", "line"), [(r"$\frac{1}{2$", 9), ("$}}}}$", 9), (r"$\begin{matrix} 1 & 2$", 9)])
def test_egtviz_check_refuses_a_bad_formula_at_its_own_line(tmp_path, formula, line):
    path = tmp_path / "01-formula.toml"
    path.write_text(lesson_with(formula))
    message = check_file(str(path))
    assert message is not None and message.startswith(f"{path}:{line}: steps[0].text: cannot render the formula ")
    assert not message.endswith(": ")


def test_a_formula_in_a_one_line_text_is_refused_at_the_key(tmp_path):
    path = tmp_path / "01-formula.toml"
    path.write_text(GOOD.replace("text = '''\nThe constraint $m_2^T F m_1 = 0$,\nand then FORMULA here.\n'''",
                                 'text = "See $}}$."'))
    assert check_file(str(path)) == (f"{path}:7: steps[0].text: cannot render the formula '}}}}': the '}}' at "
                                     "character 1 closes no '{'")


def test_file_sizes_are_exact_in_bytes(tmp_path):
    over = GOOD.encode() + b"#" * (MAX_LESSON_FILE_BYTES + 1 - len(GOOD.encode()))
    assert len(over) == 1_000_001
    path = tmp_path / "01-big.toml"
    path.write_bytes(over)
    reason = "1,000,001 bytes, more than the 1,000,000-byte limit"
    assert check_file(str(path)) == f"{path}:1: {reason}"
    with pytest.raises(LessonError, match=f"^t.toml:1: {reason}$"):
        parse_lesson(over, source="t.toml", name="01-big")
    with pytest.raises(LessonError, match=f"^t.toml:1: {reason}$"):  # the same text as a str
        parse_lesson(over.decode(), source="t.toml", name="01-big")
    path.write_bytes(over[:-1])  # exactly at the limit: accepted
    assert load_lesson(path).title == "A lesson"


@pytest.mark.parametrize("suffix", [".TOML", ".Toml"])
def test_a_lesson_suffix_in_any_case_is_checked_as_a_lesson(tmp_path, suffix):
    path = tmp_path / f"01-upper{suffix}"
    path.write_text(lesson_with("$x$"))
    assert check_file(str(path)) is None
    path.write_text(lesson_with("$}$"))
    message = check_file(str(path))
    assert message is not None and "cannot render the formula" in message and "JSON" not in message
