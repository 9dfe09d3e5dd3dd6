"""The whole package keeps the structure rules: no function over 80 lines, no class over 400 (decorators excluded,
from the ``def``/``class`` line to the last line of its body)."""

from __future__ import annotations

import ast
from pathlib import Path

import egtviz

PACKAGE = Path(egtviz.__file__).parent


def _too_long() -> list[str]:
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            limit = 80 if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) else (
                400 if isinstance(node, ast.ClassDef) else None)
            if limit is not None and node.end_lineno - node.lineno + 1 > limit:
                found.append(f"{path.relative_to(PACKAGE)}: {node.name} ({node.end_lineno - node.lineno + 1} lines)")
    return found


def test_no_function_over_80_lines_and_no_class_over_400():
    assert _too_long() == []


def test_the_scan_sees_a_long_function(tmp_path, monkeypatch):
    body = "\n".join(f"    x{i} = {i}" for i in range(80))
    (tmp_path / "long.py").write_text(f"def f():\n{body}\n", encoding="utf-8")
    monkeypatch.setattr(__import__(__name__), "PACKAGE", tmp_path)
    assert _too_long() == ["long.py: f (81 lines)"]
