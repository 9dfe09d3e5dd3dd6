"""The shape of the numeric core and the scene layer, read from the source with ``ast``.

- no import cycle among the modules of ``egtviz.geometry``, nor among those of ``egtviz.scene``, counting every
  import statement (inside functions too: a lazy import that hides a cycle is still a cycle);
- no module of ``egtviz/geometry``, ``egtviz/scene`` or ``egtviz/egt`` imports an underscore name from another
  module (public names of a private module, such as ``._validate``, are fine);
- no file of ``egtviz/geometry`` over ``MAX_LINES`` lines;
- every module of ``egtviz.geometry`` declares ``__all__``, and every name in it exists;
- ``egtviz/py.typed`` (PEP 561: the package's root marks every subpackage typed) exists and the wheel ships it.
"""

from __future__ import annotations

import ast
import fnmatch
import importlib
import tomllib
from pathlib import Path

import pytest

from _graphs import circles

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "egtviz"
MAX_LINES = 600


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _imports(name: str) -> list[tuple[str, str, int]]:
    """``(module imported from, name imported, line)`` for every import statement of module ``name``, anywhere in
    it; ``import a.b`` gives ``(a.b, "", line)``."""
    path = MODULES[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            out.extend((source, alias.name, node.lineno) for alias in node.names)
        elif isinstance(node, ast.Import):
            out.extend((alias.name, "", node.lineno) for alias in node.names)
    return out


def _edges(name: str) -> set[str]:
    """The modules of egtviz that module ``name`` imports (``from pkg import mod`` counts as importing ``mod``)."""
    out = set()
    for source, imported, _ in _imports(name):
        if f"{source}.{imported}" in MODULES:
            out.add(f"{source}.{imported}")
        elif source in MODULES:
            out.add(source)
    out.discard(name)
    return out


def _cycles(package: str) -> list[list[str]]:
    """The strongly connected components of more than one module among the modules of ``package`` (Tarjan)."""
    nodes = sorted(m for m in MODULES if m.startswith(package + "."))
    return circles({m: sorted(e for e in _edges(m) if e in nodes) for m in nodes})


def test_the_cycle_finder_sees_a_cycle_through_a_function_level_import(tmp_path, monkeypatch):
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("from . import b\n")
    b.write_text("def f():\n    from .a import g\n")
    monkeypatch.setitem(MODULES, "egtviz.fake.a", a)
    monkeypatch.setitem(MODULES, "egtviz.fake.b", b)
    assert _cycles("egtviz.fake") == [["egtviz.fake.a", "egtviz.fake.b"]]


@pytest.mark.parametrize("package", ["egtviz.geometry", "egtviz.scene"])
def test_no_import_cycle(package):
    assert _cycles(package) == []


@pytest.mark.parametrize("folder", ["geometry", "scene", "egt"])
def test_no_module_imports_a_private_name_of_another(folder):
    bad = []
    for name, path in MODULES.items():
        if not name.startswith(f"egtviz.{folder}."):
            continue
        for source, imported, line in _imports(name):
            if imported.startswith("_") and source.startswith("egtviz") and f"{source}.{imported}" not in MODULES:
                bad.append(f"{path.relative_to(ROOT)}:{line}: from {source} import {imported}")
    assert not bad, "\n".join(bad)


def test_no_geometry_file_is_over_the_line_limit():
    long = {str(p.relative_to(ROOT)): n for p in (PACKAGE / "geometry").glob("*.py")
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"over {MAX_LINES} lines: {long}"


GEOMETRY = sorted(m for m in MODULES if m == "egtviz.geometry" or m.startswith("egtviz.geometry."))


@pytest.mark.parametrize("name", GEOMETRY)
def test_every_geometry_module_declares_all_and_every_name_exists(name):
    module = importlib.import_module(name)
    names = getattr(module, "__all__", None)
    assert isinstance(names, list | tuple) and names, f"{name}: no __all__"
    assert all(isinstance(n, str) for n in names)
    missing = [n for n in names if not hasattr(module, n)]
    assert not missing, f"{name}.__all__ names what the module does not define: {missing}"
    assert len(set(names)) == len(names), f"{name}.__all__ lists a name twice"


def test_the_package_root_ships_py_typed():
    marker = PACKAGE / "py.typed"
    assert marker.is_file()
    wheel = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["hatch"]["build"]["targets"]["wheel"]
    # Hatch puts every file of a listed package in the wheel unless an exclude (or an only-include) leaves it out.
    assert "egtviz" in wheel.get("packages", [])
    relative = str(marker.relative_to(ROOT))
    for key in ("exclude", "only-include"):
        patterns = wheel.get(key, [])
        hit = any(fnmatch.fnmatch(relative, p) or relative.startswith(p.rstrip("/") + "/") for p in patterns)
        assert not hit if key == "exclude" else (not patterns or hit), f"{key} {patterns} leaves out {relative}"
    ignored = [line.strip() for line in (ROOT / ".gitignore").read_text().splitlines()] if (
        ROOT / ".gitignore").is_file() else []
    assert not any(p and not p.startswith("#") and fnmatch.fnmatch(marker.name, p) for p in ignored)
