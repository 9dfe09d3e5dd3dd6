"""Figures of the image-plane panels: SVG and PNG files, and the ``egtviz figure`` command's errors."""

from __future__ import annotations

import argparse
import io
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PIL import Image

from egtviz.scene import SCENES
from egtviz.viewer.render.figure_export import add_arguments, panel_svg, run, svg_to_png
from egtviz.viewer.render.svg import NORMAL, PRESENT

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def figure(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="egtviz figure")
    add_arguments(parser)
    return run(parser.parse_args(argv))


def test_panel_svg_is_a_sized_standalone_document():
    svg = panel_svg(SCENES["default"](), "cam2")
    root = ET.fromstring(svg.encode())
    assert root.get("data-camera") == "cam2" and root.get("data-style") == "normal"
    assert float(root.get("width")) == NORMAL.panel_px
    # Height follows the view box's aspect ratio.
    _, _, vw, vh = map(float, root.get("viewBox").split())
    assert float(root.get("height")) == pytest.approx(NORMAL.panel_px * vh / vw, rel=1e-4)
    # Fitted: the view reaches the epipole e2 at u = -1683 (left of the image).
    u0 = float(root.get("data-view").split()[0])
    assert u0 < -1683
    present = ET.fromstring(panel_svg(SCENES["default"](), "cam2", present=True, fit=False).encode())
    assert present.get("data-style") == "present" and float(present.get("width")) == PRESENT.panel_px
    assert present.get("data-view") == "0 0 640 480"


def test_panel_svg_refuses_an_unknown_camera_listing_the_names():
    with pytest.raises(KeyError, match="no camera 'nope'.*cam1, cam2"):
        panel_svg(SCENES["default"](), "nope")


def decode(png: bytes) -> np.ndarray:
    assert png[:8] == PNG_SIGNATURE
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=float)


@pytest.mark.parametrize("name, camera", [("default", "cam1"), ("example3", "cam1")])
def test_png_has_the_scaled_size_and_shows_the_drawing(name, camera):
    svg = panel_svg(SCENES[name](), camera)
    root = ET.fromstring(svg.encode())
    w, h = float(root.get("width")), float(root.get("height"))
    img = decode(svg_to_png(svg, scale=2.0))
    assert img.shape[1] == round(2 * w) and abs(img.shape[0] - 2 * h) <= 1
    assert img.std() > 20  # not blank
    # The first point's colour is drawn (the blue of point 1, hollow when outside the image).
    blue = np.array([0x00, 0x72, 0xB2], float)
    assert (np.abs(img - blue).sum(axis=2) < 30).sum() > 20
    # Text is drawn: dark pixels beyond the frame's lines (tick labels, numbers).
    assert (img.sum(axis=2) < 200).sum() > 500


def test_png_scale_is_checked():
    with pytest.raises(ValueError, match="scale"):
        svg_to_png(panel_svg(SCENES["default"](), "cam1"), scale=0)


def test_cli_writes_svg_and_png(tmp_path, capsys):
    svg_path, png_path = tmp_path / "fig.svg", tmp_path / "fig.png"
    assert figure(["example3", "--camera", "cam2", "--out", str(svg_path)]) == 0
    root = ET.parse(svg_path).getroot()
    assert root.get("data-egtviz") == "image-plane" and root.get("data-camera") == "cam2"
    assert figure(["default", "--camera", "cam1", "--out", str(png_path), "--present", "--scale", "1"]) == 0
    img = decode(png_path.read_bytes())
    assert img.shape[1] == round(PRESENT.panel_px) and img.std() > 20
    # From a scene file too.
    scene_file = tmp_path / "s.json"
    SCENES["example1"]().save(scene_file)
    assert figure(["--scene", str(scene_file), "--camera", "cam", "--out", str(svg_path), "--no-fit"]) == 0
    assert ET.parse(svg_path).getroot().get("data-view") == "0 0 2 2"
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["default", "--camera", "nope", "--out", "{tmp}/f.svg"], "no camera 'nope' in the scene (cameras: cam1, cam2)"),
    (["default", "--camera", "cam1", "--out", "{tmp}/f.jpg"], "unknown extension .jpg; use .svg or .png"),
    (["default", "--camera", "cam1", "--out", "{tmp}/no/such/dir/f.png"], "does not exist"),
    (["default", "--camera", "cam1", "--out", "{tmp}/adir.svg"], "adir.svg"),
    (["nosuch", "--camera", "cam1", "--out", "{tmp}/f.svg"], "no built-in scene 'nosuch'"),
    (["--scene", "{tmp}/missing.json", "--camera", "cam1", "--out", "{tmp}/f.svg"], "missing.json"),
])
def test_cli_refuses_with_one_line_and_exit_2(tmp_path, capsys, argv, message):
    (tmp_path / "adir.svg").mkdir()
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert figure(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("egtviz figure: ") and message in err
    assert not (tmp_path / "f.svg").exists() and not (tmp_path / "f.jpg").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir.svg"]  # nothing half-written left behind
