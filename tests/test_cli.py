"""The `egtviz` command line: scenes, version, and bad files."""

import json

import pytest

from egtviz import __version__
from egtviz.cli import main
from egtviz.scene import Scene
from egtviz.viewer.cli import load_scene_argument


def test_version(capsys):
    assert main(["version"]) == 0
    assert capsys.readouterr().out.strip() == f"egtviz {__version__}"


def test_scene_save_then_check_round_trip(tmp_path, capsys):
    path = tmp_path / "pano.json"
    assert main(["scene", "save", "panoramic", str(path)]) == 0
    assert Scene.load(path).camera_names == ("pano1", "pano2")
    assert main(["scene", "check", str(path)]) == 0
    assert "pano1 (panoramic), pano2 (panoramic); 8 points" in capsys.readouterr().out


def test_scene_check_reports_the_offending_entry(tmp_path, capsys):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"cameras": [{"kind": "pinhole", "name": "a", "width": 0}]}))
    assert main(["scene", "check", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "cameras[0]" in err and "width" in err
    assert main(["scene", "save", "nonsense", str(tmp_path / "x.json")]) == 2


def test_serve_refuses_a_malformed_scene_file(tmp_path, capsys):
    path = tmp_path / "broken.json"
    path.write_text("{ not json")
    assert main(["serve", "--port", "0", "--scene", str(path)]) == 2
    assert "broken.json: line 1" in capsys.readouterr().err


@pytest.mark.parametrize("name, first", [("default", "cam1"), ("panoramic", "pano1"), ("example3", "cam1")])
def test_built_in_scene_names(name, first):
    assert load_scene_argument(name).cameras[0].name == first
