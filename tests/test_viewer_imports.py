"""The viewer's import graph, read from the source with ``ast``.

- no circle of imports among the modules of ``egtviz/viewer``, counting every import statement: under
  ``if TYPE_CHECKING:`` and inside functions too (two modules that name each other, even for a type checker or
  lazily, cannot be read or changed apart);
- the workbench's tab view (:class:`egtviz.viewer.workbench.app.ClientView`) forwards no name by ``__getattr__``: a
  name read through the view is one the view has, or the part that has it is named.

The allow-list names the circles that remain outside the workbench; each is to be broken by its own change and then
taken off the list (an entry no longer found fails the test, so the list only shrinks).
"""

from __future__ import annotations

import ast
from pathlib import Path

from _graphs import circles

ROOT = Path(__file__).resolve().parents[1]
VIEWER = ROOT / "egtviz" / "viewer"

#: Circles outside the workbench, as sorted module names: each to be broken, then removed from here.
KNOWN_CYCLES: set[tuple[str, ...]] = set()


def module_names(package: Path) -> dict[str, Path]:
    """Every module under the folder ``package`` by dotted name (a package by its ``__init__.py``)."""
    top = package
    while (top.parent / "__init__.py").exists():
        top = top.parent
    root = top.parent
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def imported_modules(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The modules of ``modules`` that module ``name`` imports, by any import statement anywhere in it."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            for alias in node.names:
                # ``from pkg import mod`` imports the module ``mod``; ``from mod import name`` the module ``mod``.
                target = f"{source}.{alias.name}" if f"{source}.{alias.name}" in modules else source
                if target in modules:
                    out.add(target)
        elif isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names if alias.name in modules)
    out.discard(name)
    return out


def import_cycles(package: Path) -> set[tuple[str, ...]]:
    """The circles of imports under ``package``: each strongly connected set of more than one module (Tarjan)."""
    modules = module_names(package)
    return {tuple(c) for c in circles({m: sorted(imported_modules(m, p, modules)) for m, p in modules.items()})}


def test_the_cycle_finder_sees_type_checking_and_function_level_imports(tmp_path):
    viewer = tmp_path / "egtviz" / "viewer"
    viewer.mkdir(parents=True)
    (viewer.parent / "__init__.py").write_text("")
    (viewer / "__init__.py").write_text("")
    (viewer / "a.py").write_text("from . import b\n")
    (viewer / "b.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import A\n")
    (viewer / "c.py").write_text("from .d import D\n")
    (viewer / "d.py").write_text("def f():\n    from .c import C\n")
    (viewer / "e.py").write_text("from .a import A\n")  # imports into a circle: not part of it
    assert import_cycles(viewer) == {("egtviz.viewer.a", "egtviz.viewer.b"), ("egtviz.viewer.c", "egtviz.viewer.d")}


def test_the_workbench_is_in_no_import_cycle():
    assert [c for c in import_cycles(VIEWER) if any(m.startswith("egtviz.viewer.workbench") for m in c)] == []


def test_no_import_cycle_in_the_viewer_but_the_known_ones():
    assert import_cycles(VIEWER) == KNOWN_CYCLES


def test_the_tab_view_forwards_no_name():
    from egtviz.viewer.workbench.app import ClientView

    tree = ast.parse((VIEWER / "workbench" / "app.py").read_text(encoding="utf-8"))
    (cls,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "ClientView"]
    defined = {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
    assert not defined & {"__getattr__", "__getattribute__"}
    assert "__getattr__" not in vars(ClientView)
