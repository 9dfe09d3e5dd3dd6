"""The viewer's seams, read from the source with ``ast``: typed, and made of small parts.

- ``Any`` is named at most :data:`ANY_BUDGET` times in ``egtviz/viewer`` (annotations, casts and aliases alike;
  the word in a docstring is not counted): a parameter typed ``Any`` lets any object in unchecked, so a change to
  what a part hands another is seen by nobody until the page breaks;
- no class assigns more than :data:`MAX_ATTRIBUTES` attributes of its own (``self.x = ...`` anywhere in its body):
  a class holding more is several things, to be split into parts with names.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VIEWER = ROOT / "egtviz" / "viewer"
#: The most ``Any`` the viewer may name.
ANY_BUDGET = 40
#: The most attributes a class of egtviz may assign.
MAX_ATTRIBUTES = 25


def any_uses(path: Path) -> list[int]:
    """The lines on which ``path`` names ``Any`` (``Any`` or ``typing.Any``, also inside string annotations),
    import statements left out."""
    lines: list[int] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Name) and node.id == "Any":
            lines.append(node.lineno)
        elif isinstance(node, ast.Attribute) and node.attr == "Any" and isinstance(node.value, ast.Name) \
                and node.value.id == "typing":
            lines.append(node.lineno)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and _is_annotation_text(node.value):
            lines.append(node.lineno)
    return lines


def _is_annotation_text(text: str) -> bool:
    """A string that parses as a type expression naming ``Any`` (a quoted annotation), not prose."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        return False
    return any(isinstance(n, ast.Name) and n.id == "Any" for n in ast.walk(tree))


def own_attributes(cls: ast.ClassDef) -> set[str]:
    """Names ``x`` assigned as ``self.x`` (``=``, ``:`` or an augmented assignment) anywhere in ``cls``, and the
    instance attributes its body declares (``x: T``, not ``ClassVar``)."""
    names: set[str] = {node.target.id for node in cls.body if isinstance(node, ast.AnnAssign)
                       and isinstance(node.target, ast.Name) and "ClassVar" not in ast.unparse(node.annotation)}
    for node in ast.walk(cls):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
            targets = [node.target]
        for target in targets:
            for part in ast.walk(target):
                if isinstance(part, ast.Attribute) and isinstance(part.value, ast.Name) and part.value.id == "self":
                    names.add(part.attr)
    return names


def test_the_viewer_names_any_at_most_its_budget():
    uses = {path.relative_to(ROOT).as_posix(): lines for path in sorted(VIEWER.rglob("*.py"))
            if (lines := any_uses(path))}
    total = sum(len(lines) for lines in uses.values())
    by_file = ", ".join(f"{name}: {len(lines)}" for name, lines in sorted(uses.items(), key=lambda kv: -len(kv[1])))
    assert total <= ANY_BUDGET, f"{total} uses of Any in egtviz/viewer (at most {ANY_BUDGET}): {by_file}"


def test_no_class_assigns_more_than_its_share_of_attributes():
    big = []
    for path in sorted((ROOT / "egtviz").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.ClassDef) and len(names := own_attributes(node)) > MAX_ATTRIBUTES:
                big.append(f"{path.relative_to(ROOT).as_posix()}:{node.name} ({len(names)})")
    assert not big, f"classes with more than {MAX_ATTRIBUTES} attributes: {', '.join(big)}"


def test_the_counters_count_what_they_claim(tmp_path):
    source = ('from typing import Any\nimport typing\n"""Any prose."""\n'
              'def f(a: Any, b: "list[Any]", c: typing.Any) -> "Any": ...\n'
              'class C:\n    K: typing.ClassVar[int] = 1\n    w: int\n    def __init__(self):\n        self.a = 1\n        self.b: int = 2\n        self.a += 1\n'
              '        self.c, self.d = 3, 4\n        other.e = 5\n')
    path = tmp_path / "sample.py"
    path.write_text(source, encoding="utf-8")
    assert any_uses(path) == [4, 4, 4, 4]
    (cls,) = [n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.ClassDef)]
    assert own_attributes(cls) == {"w", "a", "b", "c", "d"}
