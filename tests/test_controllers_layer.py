"""The controllers are headless and typed: no module of ``egtviz/controllers`` imports viser, trimesh or the viewer,
importing them loads neither, and none names ``Any`` (their intents and state are the viewer's contract)."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import egtviz.controllers

from _subprocesses import run
from test_viewer_seams import any_uses

PACKAGE = Path(egtviz.controllers.__file__).parent


def _imports(path: Path) -> list[str]:
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            out.append(("." * node.level) + (node.module or ""))
    return out


def test_no_controller_imports_viser_or_the_viewer():
    found = [f"{path.name}: {name}" for path in sorted(PACKAGE.rglob("*.py")) for name in _imports(path)
             if name.split(".")[0] in ("viser", "trimesh", "playwright") or "viewer" in name
             or "bench" in name.split(".")]  # egtviz.bench; the workbench's modules are controllers
    assert found == []


def test_importing_every_controller_loads_no_viser():
    modules = sorted(f"egtviz.controllers.{p.stem}" for p in PACKAGE.glob("*.py") if p.stem != "__init__")
    code = (f"import sys; import egtviz.controllers; [__import__(m) for m in {modules!r}]; "
            "print('viser' in sys.modules, 'egtviz.viewer' in sys.modules)")
    out = run([sys.executable, "-c", code], "a Python that imports every controller to exit", check=True).stdout
    assert out.split() == ["False", "False"]


def test_no_controller_names_any():
    uses = {path.name: lines for path in sorted(PACKAGE.rglob("*.py")) if (lines := any_uses(path))}
    assert uses == {}
