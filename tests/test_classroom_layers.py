"""The classroom package is headless: it imports neither viser nor the viewer (layer 3)."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import egtviz.classroom

from _subprocesses import run

PACKAGE = Path(egtviz.classroom.__file__).parent


def test_no_module_imports_viser_or_the_viewer():
    found = []
    for path in sorted(PACKAGE.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            for name in names:
                if name.split(".")[0] in ("viser", "trimesh") or "viewer" in name or name.startswith("..bench"):
                    found.append(f"{path.name}: {name}")
    assert found == []


def test_importing_it_loads_no_viser():
    code = "import sys, egtviz.classroom; print('viser' in sys.modules, 'egtviz.viewer' in sys.modules)"
    out = run([sys.executable, "-c", code], "a Python that imports egtviz.classroom to exit", check=True).stdout
    assert out.split() == ["False", "False"]
