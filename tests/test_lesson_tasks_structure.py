"""The shape of the lessons code: one registry entry per task kind, each kind's keys as documented, small
functions and classes, small task modules, and no module built on another module's private names."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import egtviz.lessons
from egtviz.lessons import tasks
from egtviz.lessons.changes import CHANGE_KINDS, parse_change
from egtviz.lessons.errors import EntryError

LESSONS_CODE = Path(egtviz.lessons.__file__).parent
DOCS = Path(__file__).resolve().parents[1] / "docs" / "lessons.md"


def _modules() -> list[Path]:
    return sorted(LESSONS_CODE.rglob("*.py"))


def _doc_table(heading: str) -> dict[str, set[str]]:
    """The first column (each backticked name) of the table under ``heading`` in docs/lessons.md, with the
    key names (a backticked name's leading word) of its second column."""
    lines = DOCS.read_text(encoding="utf-8").split(heading, 1)[1].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    end = next(i for i in range(start, len(lines)) if not lines[i].startswith("|"))
    rows = lines[start + 2:end]
    out: dict[str, set[str]] = {}
    for row in rows:
        first, second = row.split("|")[1:3]
        keys = {m.group(0) for m in (re.match(r"\w+", k) for k in re.findall(r"`([^`]*)`", second)) if m}
        for name in re.findall(r"`(\w+)`", first):
            out[name] = keys
    return out


def test_every_task_kind_is_one_registry_entry_of_its_own_class():
    kinds = [cls.kind for cls in tasks.TASK_KINDS.values()]
    assert kinds == list(tasks.TASK_KINDS) and len(set(kinds)) == len(kinds)
    subclasses = set()
    pending = [tasks.Task]
    while pending:
        for sub in pending.pop().__subclasses__():
            subclasses.add(sub)
            pending.append(sub)
    assert subclasses == set(tasks.TASK_KINDS.values())


def test_each_task_kind_reads_the_keys_docs_list_for_it():
    documented = _doc_table("### Tasks (`[[steps.tasks]]`)")
    assert set(documented) == set(tasks.TASK_KINDS)
    for kind, cls in tasks.TASK_KINDS.items():
        assert set(cls.table_keys) == documented[kind], kind


def test_every_change_kind_is_documented_and_parsed_from_its_table():
    assert set(_doc_table("### Scene changes (`[[steps.changes]]`)")) == set(CHANGE_KINDS)
    for do in CHANGE_KINDS:
        with pytest.raises(EntryError, match=rf"^bogus: unknown key for an? '?{do}'? change"):
            parse_change({"do": do, "bogus": 1, **({"demo": "pinhole"} if do == "open_demo" else {})})


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(LESSONS_CODE)))
def test_no_function_over_80_lines_no_class_over_400(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            limit = 400 if isinstance(node, ast.ClassDef) else 80
            assert node.end_lineno - node.lineno + 1 <= limit, f"{node.name} has over {limit} lines"


def test_task_modules_have_at_most_400_lines():
    for path in sorted((LESSONS_CODE / "tasks").glob("*.py")):
        assert len(path.read_text(encoding="utf-8").splitlines()) <= 400, path.name
    assert not (LESSONS_CODE / "tasks.py").exists()


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(LESSONS_CODE)))
def test_no_module_imports_another_modules_private_names(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module != "__future__":
            private = [a.name for a in node.names if a.name.startswith("_")]
            assert not private, f"imports {private} from {node.module}"
