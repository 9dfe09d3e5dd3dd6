"""The `egtviz` command line: scenes, version, and bad files."""

import json

import pytest

from egtviz import __version__
from egtviz.cli import main
from egtviz.scene import load_scene_file
from egtviz.scene import scene_from_argument


def test_version(capsys):
    assert main(["version"]) == 0
    assert capsys.readouterr().out.strip() == f"egtviz {__version__}"


def test_scene_save_then_check_round_trip(tmp_path, capsys):
    path = tmp_path / "pano.json"
    assert main(["scene", "save", "panoramic", str(path)]) == 0
    assert load_scene_file(path).camera_names == ("pano1", "pano2")
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
    assert scene_from_argument(name).cameras[0].name == first


# -- hardening: targets, reads, help, refused options ------------------------------------------------------

import os  # noqa: E402
import sys  # noqa: E402
import types  # noqa: E402

from egtviz.cli import build_parser  # noqa: E402
from egtviz.scene import SCENES, SceneFileError, scene_from_argument  # noqa: E402

from _threads import returns  # noqa: E402


def test_top_level_help_shows_the_serve_options(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for option in ("--host HOST", "--port PORT", "--scene", "--demo {pinhole,panoramic}"):
        assert option in out
    for command in ("serve", "scene", "servo", "figure", "bench", "version"):
        assert command in out


def _parsers(parser, prefix=()):
    yield prefix, parser
    for action in parser._actions:
        if action.choices and isinstance(action.choices, dict):  # sub-commands
            for name, sub in action.choices.items():
                yield from _parsers(sub, prefix + (name,))


def test_every_subcommand_describes_its_arguments():
    seen = set()
    for path, parser in _parsers(build_parser("figure")):
        seen.add(path)
        if path:
            assert parser.description, path
        for action in parser._actions:
            assert action.help, (path, action.dest)
    assert {("serve",), ("scene", "save"), ("scene", "check"), ("servo",), ("bench",), ("figure",)} <= seen


@pytest.mark.parametrize("argv, message", [
    (["servo", "pinhole", "--steps", "1e9"], "--steps: expected a whole number in 1..100000, got '1e9'"),
    (["servo", "pinhole", "--steps", "1000000000"], "--steps: expected a whole number in 1..100000, got 1000000000"),
    (["servo", "pinhole", "--steps", "0"], "--steps: expected a whole number in 1..100000"),
    (["servo", "pinhole", "--seed", "1.5"], "--seed: expected a whole number"),
    (["servo", "pinhole", "--seed", "-1"], "--seed: expected a whole number in 0.."),
    (["servo", "pinhole", "--beta", "-1"], "--beta: expected a number in 0..1000, got -1"),
    (["servo", "pinhole", "--noise", "-3"], "--noise: expected a number in 0..100 px"),
    (["servo", "pinhole", "--noise", "nan"], "--noise: expected a number in 0..100 px, got nan"),
    (["servo", "pinhole", "--noise", "1e400"], "--noise: expected a number in 0..100 px, got inf"),
    (["servo", "pinhole", "--noise", "abc"], "argument --noise: invalid float value: 'abc'"),
    (["servo", "panoramic", "--beta", "2"], "--beta is a pin-hole option; the panoramic demo does not use it"),
    (["servo", "panoramic", "--estimator", "linear"], "--estimator is a pin-hole option"),
    (["servo", "pinhole", "--plot", "run.txt"], "--plot writes a PNG: expected a file name ending in .png"),
    (["servo", "pinhole", "--json", "/dev/null"], "cannot write the output: /dev/null: will not replace a device"),
    (["servo", "pinhole", "--json", "/no/such/folder/run.json"], "the folder /no/such/folder does not exist"),
    (["bench", "--repeats", "1e3"], "--repeats: expected a whole number in 1..10000"),
    (["scene", "check"], "the following arguments are required: file"),
])
def test_bad_arguments_are_refused_up_front_without_a_traceback(argv, message, capsys, monkeypatch):
    import egtviz.cli as cli
    import egtviz.servo.cli as servo_cli

    # Up front: refused before the work starts (the order of events, not a number of seconds).
    monkeypatch.setattr(servo_cli, "_simulate", lambda *a: pytest.fail("the simulation must not start"))
    monkeypatch.setattr(cli, "_run_bench", lambda *a: pytest.fail("the benchmark must not start"))
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_servo_writes_its_outputs_atomically(tmp_path, capsys):
    run_json, run_png = tmp_path / "run.json", tmp_path / "run.png"
    run_json.write_text("old")
    status = main(["servo", "panoramic", "--steps", "3", "--json", str(run_json), "--plot", str(run_png)])
    assert status == 1  # three steps do not converge
    data = json.loads(run_json.read_text())
    assert data["demo"] == "panoramic" and len(data["time"]) == 4
    assert run_png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.json", "run.png"]


def test_servo_output_that_fails_to_write_is_reported(tmp_path, capsys, monkeypatch):
    import egtviz.servo.cli as servo_cli
    from egtviz.files import FileSafetyError

    def full_disk(path, data, **kw):
        raise FileSafetyError(f"{path}: cannot write: No space left on device")

    monkeypatch.setattr(servo_cli, "write_atomic", full_disk)
    assert main(["servo", "panoramic", "--steps", "2", "--json", str(tmp_path / "r.json")]) == 1
    err = capsys.readouterr().err
    assert "cannot write the output" in err and "No space left" in err and "Traceback" not in err


def test_scene_save_refuses_non_regular_targets(tmp_path, capsys):
    real = tmp_path / "real.json"
    real.write_text("keep")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for target, why in ((link, "will not replace a symbolic link"), (fifo, "will not replace a FIFO"),
                        (tmp_path, "will not replace a directory"), ("/dev/null", "will not replace a device"),
                        (tmp_path / "no" / "x.json", "does not exist")):
        assert main(["scene", "save", "default", str(target)]) == 2
        err = capsys.readouterr().err
        assert why in err and "Traceback" not in err, err
    assert real.read_text() == "keep"
    assert main(["scene", "save", "default", str(real)]) == 0  # a regular file is replaced
    assert load_scene_file(real).camera_names == ("cam1", "cam2")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo.json", "link.json", "real.json"]


def test_scene_check_refuses_devices_fifos_and_big_files_at_once(tmp_path, capsys):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    big = tmp_path / "big.json"
    with open(big, "wb") as fh:
        fh.truncate(50_000_000)
    for path, why in (("/dev/zero", "not a regular file (a device)"), (fifo, "not a regular file (a FIFO"),
                      (big, "50,000,000 bytes, more than the 2,000,000-byte limit"),
                      (tmp_path, "not a regular file (a directory)"),
                      (tmp_path / "missing.json", "no such file")):
        # In a thread of its own: reading /dev/zero or opening the FIFO nobody writes to would never return.
        assert returns(lambda: main(["scene", "check", str(path)]), f"egtviz scene check {path} to refuse it") == 2
        err = capsys.readouterr().err
        assert why in err and "Traceback" not in err, err


def test_unknown_scene_name_lists_the_built_in_names(capsys):
    assert main(["--port", "0", "--scene", "nosuch"]) == 2
    err = capsys.readouterr().err
    names = ", ".join(SCENES)
    assert "default, panoramic, example1" in names
    assert f"nosuch: no such file and not a built-in scene (built-in: {names})" in err
    with pytest.raises(SceneFileError, match=f"built-in: {names}"):
        scene_from_argument("defualt")
    assert main(["scene", "save", "nonsense", "x.json"]) == 2
    assert f"(built-in: {names})" in capsys.readouterr().err


def test_scene_argument_is_a_built_in_name_or_a_file(tmp_path):
    for name, make in SCENES.items():
        assert scene_from_argument(name).to_dict() == make().to_dict()
    path = tmp_path / "mine.json"
    path.write_bytes(b'{"title": "mine"}')
    assert scene_from_argument(str(path)).title == "mine"


def test_figure_runs_the_export_module_with_its_own_arguments(monkeypatch, capsys):
    fake = types.ModuleType("egtviz.viewer.render.figure_export")
    calls = []
    fake.add_arguments = lambda p: p.add_argument("output", help="the figure file")
    fake.run = lambda args: calls.append(args.output) or 0
    monkeypatch.setitem(sys.modules, "egtviz.viewer.render.figure_export", fake)
    import egtviz.viewer.render

    monkeypatch.setattr(egtviz.viewer.render, "figure_export", fake, raising=False)
    assert main(["figure", "out.svg"]) == 0 and calls == ["out.svg"]


def test_figure_without_the_export_module_says_so(monkeypatch, capsys):
    import egtviz.viewer.render

    monkeypatch.setitem(sys.modules, "egtviz.viewer.render.figure_export", None)  # import fails
    monkeypatch.delattr(egtviz.viewer.render, "figure_export", raising=False)
    assert main(["figure"]) == 1
    err = capsys.readouterr().err
    assert "egtviz figure: not available" in err and "Traceback" not in err
