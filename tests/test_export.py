"""``egtviz export``: the page's text, the recorded scene, and bad input refused in one line with exit status 2."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from egtviz.lessons.markup import render_markdown
from egtviz.viewer.export import MARKER, ExportError, export_lesson, export_scene
from egtviz.viewer.export.page import markdown_to_html

from _subprocesses import run

EGTVIZ = [sys.executable, "-m", "egtviz.cli"]


def test_markdown_blocks_and_emphasis_become_html_and_formulas_stay_mathml():
    text = render_markdown("Intro with **bold** and *it* and $a*b$.\n\n* one\n* two\n  continued\n\n"
                           "1. first\n2. second\n\n## Sub\n\n$$x^2$$")
    html = markdown_to_html(text)
    assert "<p>Intro with <strong>bold</strong> and <em>it</em> and <math" in html
    assert "<ul><li>one</li><li>two\ncontinued</li></ul>" in html
    assert "<ol><li>first</li><li>second</li></ol>" in html
    assert "<h3>Sub</h3>" in html
    assert html.count("<math") == 2 and "<em>" not in html.split("<math", 1)[1].split("</math>")[0]


def test_markup_in_a_lesson_text_stays_text():
    html = markdown_to_html(render_markdown("<script>alert(1)</script> <img src=x onerror=y> [link](http://e.x)"))
    assert "<script" not in html and "<img" not in html and "<a " not in html
    assert "&lt;script&gt;" in html


def _run(*args: str) -> subprocess.CompletedProcess:
    return run([*EGTVIZ, "export", *args], f"egtviz export {' '.join(args)} to exit",
               env={**os.environ, "PYTHONUNBUFFERED": "1"})


@pytest.mark.parametrize(("args", "message"), [
    (["--lesson", "99-no-such-lesson"], "egtviz export: --lesson: "),
    (["--lesson", "06-pinhole-epipolar", "--step", "0"], "--step 0: lesson 06-pinhole-epipolar has steps 1 to 3"),
    (["--lesson", "06-pinhole-epipolar", "--step", "4"], "--step 4: lesson 06-pinhole-epipolar has steps 1 to 3"),
    (["--scene", "default", "--step", "2"], "--step: only with --lesson"),
    (["--scene", "no-such-scene.json"], "egtviz export: --scene: "),
])
def test_bad_input_is_one_line_and_exit_2_and_writes_nothing(tmp_path, args, message):
    out = tmp_path / "out"
    done = _run(*args, "--out", str(out))
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert len(done.stderr.strip().splitlines()) == 1 and message in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""
    assert not out.exists()


def test_a_folder_that_is_not_an_export_is_refused_and_left_alone(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    done = _run("--lesson", "06-pinhole-epipolar", "--out", str(tmp_path))
    assert done.returncode == 2
    assert done.stderr.strip() == (f"egtviz export: --out {tmp_path}: not empty and not an egtviz export "
                                   f"(no {MARKER}); give a new or empty folder")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]
    a_file = tmp_path / "notes.txt"
    done = _run("--scene", "default", "--out", str(a_file))
    assert done.returncode == 2 and done.stderr.strip().endswith("not a folder") and a_file.read_text() == "mine"


def test_a_step_is_exported_and_an_export_may_be_replaced(tmp_path):
    out = tmp_path / "lesson"
    page = export_lesson("06-pinhole-epipolar", 2, out)
    assert page == out / "index.html"
    assert sorted(p.name for p in out.iterdir()) == ["egtviz-export.json", "index.html", "scene.html"]
    html = page.read_text(encoding="utf-8")
    assert "<h1>Step 2 of 3: Steer the epipole</h1>" in html and "Pin-hole epipolar geometry" in html
    assert "Turn cam1 so that its epipole e1 lands" in html  # the step's task, as a prompt
    assert '<iframe src="scene.html"' in html
    scene = (out / "scene.html").read_text(encoding="utf-8")
    assert "window.__VISER_EMBED_DATA__=" in scene and "<script src=" not in scene
    assert json.loads((out / MARKER).read_text()) == {
        "egtviz": json.loads((out / MARKER).read_text())["egtviz"], "kind": "lesson",
        "lesson": "06-pinhole-epipolar", "step": 2}
    export_scene("example3", out)  # the folder is an export: its files are replaced
    assert json.loads((out / MARKER).read_text())["kind"] == "scene"
    assert "<h1>" in (out / "index.html").read_text() and "Step 2 of 3" not in (out / "index.html").read_text()


def test_the_recording_holds_the_scene_and_a_picture_of_each_panel(tmp_path):
    import base64
    import re

    import msgspec
    import zstandard

    export_lesson("06-pinhole-epipolar", 1, tmp_path)
    scene = (tmp_path / "scene.html").read_text(encoding="utf-8")
    data = base64.b64decode(re.search(r'__VISER_EMBED_DATA__="([^"]+)"', scene).group(1))
    inner = zstandard.ZstdDecompressor().decompress(data[8:], max_output_size=int.from_bytes(data[:8], "little"))
    recording = msgspec.msgpack.decode(inner[8:8 + int.from_bytes(inner[:8], "little")])
    names = [m[1].get("name") for m in recording["messages"]]
    kinds = [m[1]["type"] for m in recording["messages"]]
    assert {"/egt/panel_0", "/egt/panel_1", "/egt/points", "/egt/baseline"} <= set(names)
    assert "ImageMessage" in kinds and "SetCameraPositionMessage" in kinds
    assert not any(k.startswith("Gui") for k in kinds)


def test_export_errors_name_the_argument():
    with pytest.raises(ExportError, match=r"--step 5: lesson 06-pinhole-epipolar has steps 1 to 3"):
        export_lesson("06-pinhole-epipolar", 5, "/nonexistent/never")
    with pytest.raises(ExportError, match="--lesson"):
        export_lesson("no-such", 1, "/nonexistent/never")


def test_an_export_that_cannot_be_written_is_one_line_and_exit_1():
    done = _run("--scene", "default", "--out", "/proc/egtviz-export-test")
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert len(done.stderr.strip().splitlines()) == 1
    assert done.stderr.startswith("egtviz export: --out /proc/egtviz-export-test: ") and "Traceback" not in done.stderr


def test_a_missing_client_page_is_an_export_failure_not_a_traceback(tmp_path, monkeypatch):
    from viser.infra import StateSerializer

    from egtviz.viewer.export import ExportFailed

    def missing(self, dark_mode=False):
        raise FileNotFoundError(2, "No such file or directory", "client/build/index.html")

    monkeypatch.setattr(StateSerializer, "as_html", missing)
    with pytest.raises(ExportFailed, match="cannot record the 3D scene: .*client/build/index.html"):
        export_scene("default", tmp_path / "out")
    assert not (tmp_path / "out").exists()
