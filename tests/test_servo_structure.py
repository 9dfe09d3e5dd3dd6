"""Structure rules of the headless servo simulations: no function over 80 lines, no class over 400 lines.

A function counts from its ``def`` line to the last line of its body (docstring included, decorators not);
nested functions and methods count on their own as well as inside what holds them.
"""

from __future__ import annotations

import ast
import textwrap
from pathlib import Path

import pytest

import egtviz.servo

MAX_FUNCTION_LINES = 80
MAX_CLASS_LINES = 400
SERVO_DIR = Path(egtviz.servo.__file__).parent


def oversized(source: str) -> list[tuple[str, str, int]]:
    """``(kind, name, lines)`` of every function over :data:`MAX_FUNCTION_LINES` and class over
    :data:`MAX_CLASS_LINES` in ``source``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            lines = node.end_lineno - node.lineno + 1
            is_class = isinstance(node, ast.ClassDef)
            if lines > (MAX_CLASS_LINES if is_class else MAX_FUNCTION_LINES):
                found.append(("class" if is_class else "function", node.name, lines))
    return found


def test_the_counter_counts_from_def_to_the_last_body_line():
    body = "\n".join(f"    x{i} = {i}" for i in range(79))
    at_limit = f"@decorator\ndef f():\n{body}\n"  # def + 79 body lines = 80
    assert oversized(at_limit) == []
    assert oversized(at_limit + "    x = 0\n") == [("function", "f", 81)]
    # class line, decorator, def, 80 body lines, 320 more lines of the class: 403
    nested = "class C:\n" + textwrap.indent(at_limit + "    x = 0\n", "    ") + "    y = 0\n" * 320
    assert sorted(oversized(nested)) == [("class", "C", 403), ("function", "f", 81)]
    assert oversized(nested.rsplit("    y = 0\n", 3)[0]) == [("function", "f", 81)]  # class of 400 lines


@pytest.mark.parametrize("path", sorted(SERVO_DIR.glob("*.py")), ids=lambda p: p.name)
def test_no_servo_function_or_class_is_over_the_limits(path):
    assert oversized(path.read_text(encoding="utf-8")) == []
