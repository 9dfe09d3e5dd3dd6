"""Malformed and out-of-range scene files: refused everywhere with the file, the entry and the reason.

Every case goes through ``egtviz scene check`` (exit 2, no traceback), ``egtviz serve --scene`` (refused
before a server starts) and ``scene_from_bytes`` (what the browser's Load uses). A file that passes is
drawn: ``check`` passes if and only if ``compute_derived`` works on the loaded scene.
"""

import copy
import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, reject, settings
from hypothesis import strategies as st

from egtviz.cli import main
from egtviz.scene import (
    PanoramicSpec,
    PinholeSpec,
    Scene,
    SceneError,
    SceneFileError,
    SceneModel,
    compute_derived,
    default_scene,
    limits,
    scene_from_bytes,
)

BASE = default_scene().to_dict()

PANORAMIC_CAMERA = {
    "kind": "panoramic", "name": "pano", "position": [0.0, -6.0, 0.5], "ypr_deg": [0.0, 0.0, 0.0],
    "mirror": "hyperbolic", "a": 0.3, "b": 0.1, "focal_pixels": 1100.0, "principal_point": [320.0, 240.0],
    "width": 640, "height": 480,
}  # fmt: skip


def mutated(change):
    data = copy.deepcopy(BASE)
    change(data)
    return json.dumps(data, allow_nan=True).encode()


def cam(field, value, index=0):
    return lambda d: d["cameras"][index].__setitem__(field, value)


def pano(field, value):
    def change(d):
        entry = dict(PANORAMIC_CAMERA)
        entry[field] = value
        d["cameras"][1] = entry

    return change


def surface(**fields):
    def change(d):
        entry = {"kind": "plane", "center": [0.0, 0.0, 0.0], "size": 2.0, "normal": [0.0, 0.0, 1.0],
                 "samples": 100, "path": ""}
        entry.update(fields)
        d["surfaces"] = [entry]

    return change


def top(key, value):
    return lambda d: d.__setitem__(key, value)


def raw(text):
    return text.encode("utf-8") if isinstance(text, str) else text


DEEP = "[" * 100_000 + "]" * 100_000

# (case id, file bytes, regex the message must match after the file name: the entry and the reason)
REFUSED = [
    # -- not UTF-8 / not JSON / JSON that is refused while parsed
    ("latin1", raw(b'{"title": "caf\xe9"}'), r"byte 14: not UTF-8"),
    ("binary", raw(b"\xff\xfe\x00\x01"), r"not UTF-8"),
    ("not-json", raw("{ not json"), r"line 1, column 3: not valid JSON"),
    ("empty", raw(""), r"line 1, column 1: not valid JSON"),
    ("truncated", raw('{"cameras": [{"kind": "pinhole"'), r"not valid JSON"),
    ("duplicate-top", raw('{"title": "a", "title": "b"}'), r"duplicate key 'title'"),
    ("duplicate-camera-key", raw('{"cameras": [{"kind": "pinhole", "name": "a", "name": "b"}]}'), r"duplicate key 'name'"),
    ("huge-int", raw('{"selected_point": 1' + "0" * 400 + "}"), r"integer with more than 15 digits"),
    ("huge-int-focal", mutated(cam("focal_length", 10**300)), r"integer with more than 15 digits"),
    ("float-overflow", raw('{"points": [[1e400, 0, 0]]}'), r"1e400 is too large"),
    ("nan", raw('{"points": [[NaN, 0, 0]]}'), r"NaN is not a JSON number"),
    ("infinity", raw('{"points": [[Infinity, 0, 0]]}'), r"Infinity is not a JSON number"),
    ("minus-infinity", raw('{"points": [[-Infinity, 0, 0]]}'), r"-Infinity is not a JSON number"),
    ("deep-nesting", raw(DEEP), r"nested more than 8 levels"),
    ("nested-points", raw('{"points": [[[[[[[[[[1]]]]]]]]]]}'), r"nested more than 8 levels"),
    ("top-list", raw("[]"), r"top level: expected a JSON object"),
    ("top-string", raw('"scene"'), r"top level: expected a JSON object"),
    ("top-null", raw("null"), r"top level: expected a JSON object"),
    ("top-number", raw("3"), r"top level: expected a JSON object"),
    # -- top-level entries
    ("unknown-entry", mutated(top("script", "rm -rf")), r"script: unknown entry"),
    ("format", mutated(top("format", "other")), r"format: expected 'egtviz-scene'"),
    ("version-2", mutated(top("version", 2)), r"version: this egtviz reads version 1"),
    ("version-string", mutated(top("version", "1")), r"version: this egtviz reads version 1"),
    ("version-bool", mutated(top("version", True)), r"version: this egtviz reads version 1"),
    ("title-number", mutated(top("title", 5)), r"title: expected text"),
    ("title-list", mutated(top("title", ["a"])), r"title: expected text"),
    ("title-long", mutated(top("title", "x" * 1000)), r"title: expected text of at most 200"),
    ("title-escape", mutated(top("title", "\x1b]0;pwned\x07")), r"title: .*without control characters"),
    ("selected-float", mutated(top("selected_point", 1.5)), r"selected_point: expected null or a whole number below 8"),
    ("selected-true", mutated(top("selected_point", True)), r"selected_point: expected null or a whole number"),
    ("selected-string", mutated(top("selected_point", "0")), r"selected_point: expected null or a whole number"),
    ("selected-negative", mutated(top("selected_point", -1)), r"selected_point: expected null or a whole number"),
    ("selected-past-end", mutated(top("selected_point", 8)), r"selected_point: expected null or a whole number below 8"),
    ("highlight-abc", mutated(top("highlighted", ["point:abc"])), r"highlighted: expected camera names"),
    ("highlight-past-end", mutated(top("highlighted", ["point:99"])), r"highlighted: .*got 'point:99'"),
    ("highlight-negative", mutated(top("highlighted", ["point:-1"])), r"highlighted: .*got 'point:-1'"),
    ("highlight-leading-zero", mutated(top("highlighted", ["point:01"])), r"highlighted: .*got 'point:01'"),
    ("highlight-ghost", mutated(top("highlighted", ["ghost"])), r"highlighted: .*got 'ghost'"),
    ("highlight-string", mutated(top("highlighted", "cam1")), r"highlighted: expected a list of names"),
    ("highlight-number", mutated(top("highlighted", [5])), r"highlighted: expected a list of names"),
    ("highlight-nested", mutated(top("highlighted", [["cam1"]])), r"highlighted: expected a list of names"),
    ("locked-abc", mutated(top("locked", ["point:abc"])), r"locked: expected camera names"),
    ("locked-object", mutated(top("locked", {"cam1": True})), r"locked: expected a list of names"),
    ("pair-one", mutated(top("pair", ["cam1"])), r"pair: expected two different camera names"),
    ("pair-same", mutated(top("pair", ["cam1", "cam1"])), r"pair: expected two different camera names"),
    ("pair-ghost", mutated(top("pair", ["cam1", "ghost"])), r"pair: expected two different camera names"),
    ("pair-string", mutated(top("pair", "cam1,cam2")), r"pair: expected two different camera names"),
    ("pair-numbers", mutated(top("pair", [1, 2])), r"pair: expected two different camera names"),
    ("options-string", mutated(top("options", {"show_rays": "yes"})), r"options: show_rays: expected true or false"),
    ("options-number", mutated(top("options", {"show_rays": 1})), r"options: show_rays: expected true or false"),
    ("options-unknown", mutated(top("options", {"zoom": True})), r"options\.zoom: unknown field"),
    ("options-list", mutated(top("options", [])), r"options: expected an object"),
    # -- cameras
    ("cameras-object", mutated(top("cameras", {"cam1": {}})), r"cameras: expected a list"),
    ("cameras-string", mutated(top("cameras", "cam1")), r"cameras: expected a list"),
    ("too-many-cameras", mutated(lambda d: d.__setitem__("cameras", [
        dict(d["cameras"][0], name=f"c{i}") for i in range(9)])), r"cameras: at most 8 entries, got 9"),
    ("camera-list", mutated(lambda d: d["cameras"].__setitem__(0, ["pinhole"])), r"cameras\[0\]\.kind: expected one of"),
    ("camera-null", mutated(lambda d: d["cameras"].__setitem__(0, None)), r"cameras\[0\]\.kind: expected one of"),
    ("kind-orthographic", mutated(cam("kind", "orthographic")), r"cameras\[0\]\.kind: expected one of \['fisheye', 'hyperbolic', 'panoramic', 'parabolic', 'pinhole', 'unified'\]"),
    ("kind-list", mutated(cam("kind", ["pinhole"])), r"cameras\[0\]\.kind: expected one of"),
    ("kind-missing", mutated(lambda d: d["cameras"][0].pop("kind")), r"cameras\[0\]\.kind: expected one of"),
    ("unknown-camera-field", mutated(cam("zoom", 2)), r"cameras\[0\]\.zoom: unknown field for a pinhole camera"),
    ("duplicate-names", mutated(cam("name", "cam2")), r"cameras: names must be unique"),
    ("name-missing", mutated(lambda d: d["cameras"][0].pop("name")), r"cameras\[0\]: name: missing; expected a non-empty string"),
    ("name-missing-panoramic", mutated(lambda d: d["cameras"].__setitem__(1, {"kind": "panoramic"})), r"cameras\[1\]: name: missing"),
    ("name-missing-unified", mutated(lambda d: d["cameras"].__setitem__(0, {"kind": "unified", "xi": 0.5})), r"cameras\[0\]: name: missing"),
    ("name-number", mutated(cam("name", 5)), r"cameras\[0\]: name: expected a non-empty string"),
    ("name-list", mutated(cam("name", ["cam"])), r"cameras\[0\]: name: expected a non-empty string"),
    ("name-empty", mutated(cam("name", "  ")), r"cameras\[0\]: name: expected a non-empty string"),
    ("name-long", mutated(cam("name", "c" * 1000)), r"cameras\[0\]: name: expected at most 40 characters"),
    ("name-escape", mutated(cam("name", "a\x1b[2J")), r"cameras\[0\]: name: .*no control characters"),
    ("name-point-prefix", mutated(cam("name", "point:3")), r"cameras\[0\]: name: .*no 'point:' prefix"),
    ("focal-string", mutated(cam("focal_length", "0.008")), r"cameras\[0\]: camera 'cam1': focal_length: expected a number, got '0.008'"),
    ("focal-true", mutated(cam("focal_length", True)), r"cameras\[0\]: .*focal_length: expected a number, got True"),
    ("focal-null", mutated(cam("focal_length", None)), r"cameras\[0\]: .*focal_length: expected a number, got None"),
    ("focal-list", mutated(cam("focal_length", [0.008])), r"cameras\[0\]: .*focal_length: expected a number"),
    ("focal-tiny", mutated(cam("focal_length", 1e-300)), r"cameras\[0\]: .*focal_length: expected 0.0001..10 m, got 1e-300"),
    ("focal-huge", mutated(cam("focal_length", 1e308)), r"cameras\[0\]: .*focal_length: expected 0.0001..10 m, got 1e\+308"),
    ("focal-zero", mutated(cam("focal_length", 0)), r"cameras\[0\]: .*focal_length: expected 0.0001..10 m, got 0"),
    ("focal-negative", mutated(cam("focal_length", -1)), r"cameras\[0\]: .*focal_length: expected 0.0001..10 m, got -1"),
    ("pixel-size-tiny", mutated(cam("pixels_per_metre", [1e300, 1e300])), r"cameras\[0\]: .*pixels_per_metre: expected 1..1e\+07 px/m, got 1e\+300"),
    ("pixel-size-string", mutated(cam("pixels_per_metre", "100000")), r"cameras\[0\]: .*pixels_per_metre: expected two numbers, got '100000'"),
    ("pixel-size-strings", mutated(cam("pixels_per_metre", ["1e5", "1e5"])), r"cameras\[0\]: .*pixels_per_metre: expected two numbers, got '1e5'"),
    ("pixel-size-three", mutated(cam("pixels_per_metre", [1, 2, 3])), r"cameras\[0\]: .*pixels_per_metre: expected two finite numbers, got 3"),
    ("pixel-size-scalar", mutated(cam("pixels_per_metre", 5)), r"cameras\[0\]: .*pixels_per_metre: expected two numbers, got 5"),
    ("principal-huge", mutated(cam("principal_point", [1e308, 0])), r"cameras\[0\]: .*principal_point: expected -100000..100000 px"),
    ("principal-strings", mutated(cam("principal_point", ["320", "240"])), r"cameras\[0\]: .*principal_point: expected two numbers"),
    ("skew-huge", mutated(cam("skew", 1e308)), r"cameras\[0\]: .*skew: expected -100000..100000 px, got 1e\+308"),
    ("skew-over-focal", mutated(cam("skew", 801.0)), r"cameras\[0\]: .*skew / \(focal_length \* pixels_per_metre\[0\]\): expected -1..1, got 1.00125"),
    ("focal-pixels-low", mutated(lambda d: d["cameras"][0].update(focal_length=1e-4, pixels_per_metre=[1e3, 1e3])), r"cameras\[0\]: .*focal_length \* pixels_per_metre: expected 1..1e\+06 px, got 0.1"),
    ("skew-string", mutated(cam("skew", "0")), r"cameras\[0\]: .*skew: expected a number"),
    ("width-fraction", mutated(cam("width", 640.5)), r"cameras\[0\]: .*width: expected a whole number in 1..8192 px, got 640.5"),
    ("width-string", mutated(cam("width", "640")), r"cameras\[0\]: .*width: expected a number"),
    ("width-true", mutated(cam("width", True)), r"cameras\[0\]: .*width: expected a number, got True"),
    ("width-zero", mutated(cam("width", 0)), r"cameras\[0\]: .*width: expected a whole number in 1..8192"),
    ("width-huge", mutated(cam("width", 100_000)), r"cameras\[0\]: .*width: expected a whole number in 1..8192"),
    ("height-negative", mutated(cam("height", -3)), r"cameras\[0\]: .*height: expected a whole number in 1..8192"),
    ("height-1e9", mutated(cam("height", 1e9)), r"cameras\[0\]: .*height: expected a whole number in 1..8192"),
    ("position-far", mutated(cam("position", [1e200, 0, 0])), r"cameras\[0\]: .*position: expected -10000..10000 m, got 1e\+200"),
    ("position-strings", mutated(cam("position", ["0", "0", "0"])), r"cameras\[0\]: .*position: expected three numbers, got '0'"),
    ("position-two", mutated(cam("position", [0, 0])), r"cameras\[0\]: .*position: expected three finite numbers, got 2"),
    ("position-object", mutated(cam("position", {"x": 0})), r"cameras\[0\]: .*position: expected three numbers, got \{'x': 0\}"),
    ("position-string", mutated(cam("position", "0,0,0")), r"cameras\[0\]: .*position: expected three numbers, got '0,0,0'"),
    ("position-bool", mutated(cam("position", [True, 0, 0])), r"cameras\[0\]: .*position: expected three numbers, got True"),
    ("position-null", mutated(cam("position", [None, 0, 0])), r"cameras\[0\]: .*position: expected three numbers, got None"),
    ("ypr-huge", mutated(cam("ypr_deg", [1e300, 0, 0])), r"cameras\[0\]: .*ypr_deg: expected -3600..3600 deg"),
    ("ypr-string", mutated(cam("ypr_deg", ["a", 0, 0])), r"cameras\[0\]: .*ypr_deg: expected three numbers"),
    # -- panoramic cameras
    ("mirror-b-tiny", mutated(pano("b", 1e-200)), r"cameras\[1\]: camera 'pano': b: expected 0.001..100 m, got 1e-200"),
    ("mirror-a-huge", mutated(pano("a", 1e308)), r"cameras\[1\]: .*a: expected 0.001..100 m"),
    ("mirror-a-zero", mutated(pano("a", 0)), r"cameras\[1\]: .*a: expected 0.001..100 m"),
    ("mirror-a-string", mutated(pano("a", "0.3")), r"cameras\[1\]: .*a: expected a number"),
    ("mirror-ratio", mutated(pano("b", 50.0)), r"cameras\[1\]: .*b/a: expected 0.01..100"),
    ("mirror-kind", mutated(pano("mirror", "elliptic")), r"cameras\[1\]: .*mirror: expected 'hyperbolic' or 'parabolic'"),
    ("mirror-kind-list", mutated(pano("mirror", ["hyperbolic"])), r"cameras\[1\]: .*mirror: expected 'hyperbolic'"),
    ("pano-focal-tiny", mutated(pano("focal_pixels", 1e-300)), r"cameras\[1\]: .*focal_pixels: expected 1..1e\+06 px"),
    ("pano-focal-string", mutated(pano("focal_pixels", "1000")), r"cameras\[1\]: .*focal_pixels: expected a number"),
    ("pano-width-fraction", mutated(pano("width", 10.5)), r"cameras\[1\]: .*width: expected a whole number"),
    ("pano-skew", mutated(pano("skew", 0.0)), r"cameras\[1\]\.skew: unknown field for a panoramic camera"),
    # -- points
    ("points-object", mutated(top("points", {"0": [0, 0, 0]})), r"points: expected a list"),
    ("points-string", mutated(top("points", "abc")), r"points: expected a list"),
    ("too-many-points", mutated(top("points", [[0, 0, 0]] * 2001)), r"points: at most 2000 entries, got 2001"),
    ("million-points", mutated(top("points", [[0, 0, 0]] * 10**6)), r"bytes, more than the 2,000,000-byte limit"),
    ("point-string", mutated(lambda d: d["points"].__setitem__(3, "1,2,3")), r"points\[3\]: expected three numbers, got '1,2,3'"),
    ("point-mixed", mutated(lambda d: d["points"].append([1, "x", 2])), r"points\[8\]: expected three numbers, got 'x'"),
    ("point-two", mutated(lambda d: d["points"].append([1, 2])), r"points\[8\]: expected three finite numbers, got 2"),
    ("point-four", mutated(lambda d: d["points"].append([1, 2, 3, 4])), r"points\[8\]: expected three finite numbers, got 4"),
    ("point-bool", mutated(lambda d: d["points"].append([True, 0, 0])), r"points\[8\]: expected three numbers, got True"),
    ("point-far", mutated(lambda d: d["points"].append([1e200, 0, 0])), r"points\[8\]: expected -10000..10000 m"),
    ("point-null", mutated(lambda d: d["points"].append(None)), r"points\[8\]: expected three numbers, got None"),
    ("point-object", mutated(lambda d: d["points"].append({"x": 1})), r"points\[8\]: expected three numbers"),
    # -- surfaces
    ("surfaces-object", mutated(top("surfaces", {})), r"surfaces: expected a list"),
    ("surface-list", mutated(top("surfaces", [[1, 2]])), r"surfaces\[0\]: expected an object"),
    ("surface-billion", mutated(surface(samples=10**9)), r"surfaces\[0\]: samples: expected a whole number in 1..10000"),
    ("surface-fraction", mutated(surface(samples=1.5)), r"surfaces\[0\]: samples: expected a whole number"),
    ("surface-samples-string", mutated(surface(samples="100")), r"surfaces\[0\]: samples: expected a number"),
    ("surface-samples-true", mutated(surface(samples=True)), r"surfaces\[0\]: samples: expected a number"),
    ("surface-samples-zero", mutated(surface(samples=0)), r"surfaces\[0\]: samples: expected a whole number in 1..10000"),
    ("surface-kind", mutated(surface(kind="torus")), r"surfaces\[0\]: surface kind: expected plane, sphere or mesh"),
    ("surface-kind-list", mutated(surface(kind=["plane"])), r"surfaces\[0\]: surface kind: expected plane"),
    ("surface-size-huge", mutated(surface(size=1e308)), r"surfaces\[0\]: size: expected 0.001..1000 m"),
    ("surface-size-zero", mutated(surface(size=0)), r"surfaces\[0\]: size: expected 0.001..1000 m"),
    ("surface-size-string", mutated(surface(size="2")), r"surfaces\[0\]: size: expected a number"),
    ("surface-normal-zero", mutated(surface(normal=[0, 0, 0])), r"surfaces\[0\]: surface normal: must not be"),
    ("surface-normal-huge", mutated(surface(normal=[1e300, 0, 0])), r"surfaces\[0\]: normal: expected -10000..10000"),
    ("surface-center-far", mutated(surface(center=[1e200, 0, 0])), r"surfaces\[0\]: center: expected -10000..10000"),
    ("surface-unknown-field", mutated(surface(colour="red")), r"surfaces\[0\]\.colour: unknown field for a surface"),
    ("surface-plane-path", mutated(surface(path="house.obj")), r"surfaces\[0\]: surface path: only a mesh surface"),
    ("mesh-absolute", mutated(surface(kind="mesh", path="/etc/passwd")), r"surfaces\[0\]: surface path: expected the name of a mesh in the assets \(house.obj\)"),
    ("mesh-dotdot", mutated(surface(kind="mesh", path="../assets/house.obj")), r"surfaces\[0\]: surface path: expected the name of a mesh"),
    ("mesh-subfolder", mutated(surface(kind="mesh", path="sub/house.obj")), r"surfaces\[0\]: surface path: expected the name"),
    ("mesh-backslash", mutated(surface(kind="mesh", path="..\\house.obj")), r"surfaces\[0\]: surface path: expected the name"),
    ("mesh-nul", mutated(surface(kind="mesh", path="house.obj\x00")), r"surfaces\[0\]: surface path: expected the name"),
    ("mesh-missing", mutated(surface(kind="mesh", path="missing.obj")), r"surfaces\[0\]: surface path: no mesh named 'missing.obj'"),
    ("mesh-not-a-mesh", mutated(surface(kind="mesh", path="screenshot-default.png")), r"surfaces\[0\]: surface path: expected the name"),
    ("mesh-empty", mutated(surface(kind="mesh", path="")), r"surfaces\[0\]: surface path: expected the name"),
    ("mesh-path-number", mutated(surface(kind="mesh", path=5)), r"surfaces\[0\]: surface path: expected a mesh name"),
    ("mesh-forged-dropdown", mutated(surface(kind="mesh", path="mesh: /any/path")), r"surfaces\[0\]: surface path: expected the name"),
    ("too-many-surfaces", mutated(lambda d: d.__setitem__("surfaces", [
        {"kind": "sphere", "samples": 10} for _ in range(9)])), r"surfaces: at most 8 entries, got 9"),
    ("too-many-samples", mutated(lambda d: d.__setitem__("surfaces", [
        {"kind": "sphere", "samples": 10_000} for _ in range(3)])), r"surfaces: at most 20000 samples in all, got 30000"),
]

PASSING = [
    ("base", mutated(lambda d: None)),
    ("bom", b"\xef\xbb\xbf" + mutated(lambda d: None)),
    ("empty-object", raw("{}")),
    ("integral-float-width", mutated(cam("width", 640.0))),
    ("limits-low", mutated(lambda d: d["cameras"][0].update(focal_length=1e-4, pixels_per_metre=[1e7, 1e7], width=1, height=1))),
    ("limits-high", mutated(lambda d: d["cameras"][0].update(focal_length=10.0, pixels_per_metre=[1.0, 1.0], width=8192, height=8192,
                                                             principal_point=[1e5, -1e5], skew=-10.0))),
    ("edge-of-world", mutated(lambda d: d["cameras"][0].update(position=[1e4, -1e4, 1e4]))),
    ("coincident-centres", mutated(lambda d: d["cameras"][1].update(position=d["cameras"][0]["position"]))),
    ("point-on-centre", mutated(lambda d: d["points"].append(d["cameras"][0]["position"]))),
    ("highlight-and-lock", mutated(lambda d: d.update(highlighted=["cam1", "point:7"], locked=["point:0"], selected_point=7))),
    ("mesh-by-name", mutated(surface(kind="mesh", path="house.obj", samples=50))),
    ("max-points", mutated(top("points", [[float(i % 7), float(i % 11), float(i % 13)] for i in range(2000)]))),
    ("panoramic-pair", mutated(pano("a", 0.3))),
    ("parabolic", mutated(pano("mirror", "parabolic"))),
    ("mirror-ratio-edges", mutated(lambda d: d["cameras"].__setitem__(1, dict(PANORAMIC_CAMERA, a=1.0, b=0.01)))),
]


def _ids(cases):
    return [c[0] for c in cases]


@pytest.mark.parametrize("case, data, match", REFUSED, ids=_ids(REFUSED))
def test_check_refuses_with_file_entry_and_reason(tmp_path, capsys, case, data, match):
    path = tmp_path / f"{case}.json"
    path.write_bytes(data)
    assert main(["scene", "check", str(path)]) == 2
    out = capsys.readouterr()
    assert out.out == ""
    assert "Traceback" not in out.err
    assert out.err.startswith(f"egtviz: {path}: ")
    assert len(out.err.strip().splitlines()) == 1
    import re

    assert re.search(match, out.err), out.err


@pytest.mark.parametrize("case, data, match", REFUSED, ids=_ids(REFUSED))
def test_upload_refuses_with_the_same_message(case, data, match):
    with pytest.raises(SceneFileError, match=match) as info:
        scene_from_bytes(data, "upload.json")
    assert str(info.value).startswith("upload.json: ")
    assert "\x1b" not in str(info.value)


@pytest.mark.parametrize("case, data, match", REFUSED[::7], ids=_ids(REFUSED[::7]))
def test_serve_refuses_before_starting(tmp_path, capsys, case, data, match):
    path = tmp_path / f"{case}.json"
    path.write_bytes(data)
    assert main(["serve", "--port", "0", "--scene", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"cannot use --scene: {path}: " in err and "Traceback" not in err


@pytest.mark.parametrize("case, data", PASSING, ids=_ids(PASSING))
def test_passing_files_are_drawn(tmp_path, capsys, case, data):
    path = tmp_path / f"{case}.json"
    path.write_bytes(data)
    assert main(["scene", "check", str(path)]) == 0
    assert capsys.readouterr().out.startswith(f"{path}: ")
    scene = scene_from_bytes(data, "upload.json")
    derived = compute_derived(scene)
    assert set(derived.image_planes) == set(scene.camera_names)
    assert SceneModel(scene).derived.image_planes.keys() == derived.image_planes.keys()


def test_check_passes_iff_the_scene_draws():
    """Every file of both lists: refused by the upload check exactly when it is not drawable."""
    for case, data, _ in REFUSED:
        with pytest.raises(SceneFileError):
            scene_from_bytes(data, case)
    for case, data in PASSING:
        compute_derived(scene_from_bytes(data, case))


def test_title_from_a_file_is_printed_without_control_characters(tmp_path, capsys):
    # A camera name cannot hold control characters; the file name can, and is escaped when printed.
    path = tmp_path / "evil\x1b[2J.json"
    path.write_bytes(mutated(lambda d: None))
    assert main(["scene", "check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "evil\\x1b[2J.json" in out


def test_mesh_symlink_out_of_the_assets_is_refused(tmp_path, monkeypatch):
    from egtviz.scene import SurfaceSpec
    from egtviz.scene import surfaces as surfaces_module

    assets = tmp_path / "assets"
    assets.mkdir()
    outside = tmp_path / "secret.obj"
    outside.write_text((surfaces_module.ASSETS / "house.obj").read_text())
    (assets / "escape.obj").symlink_to(outside)
    (assets / "house.obj").write_text((surfaces_module.ASSETS / "house.obj").read_text())
    (assets / "broken.obj").write_text("v 0 0 0\nf 1 1 1\n")
    monkeypatch.setattr(surfaces_module, "ASSETS", assets)
    surfaces_module._load_mesh.cache_clear()
    surfaces_module.mesh_samples.cache_clear()
    try:
        assert surfaces_module.mesh_names() == ("broken.obj", "house.obj")
        with pytest.raises(SceneError, match="no mesh named 'escape.obj'"):
            surfaces_module.check_surface(SurfaceSpec("mesh", path="escape.obj"))
        with pytest.raises(SceneError, match="mesh 'broken.obj'"):
            surfaces_module.check_surface(SurfaceSpec("mesh", path="broken.obj"))
        assert surfaces_module.check_surface(SurfaceSpec("mesh", path="house.obj", samples=20)).path == "house.obj"
    finally:
        surfaces_module._load_mesh.cache_clear()
        surfaces_module.mesh_samples.cache_clear()


# -- any pin-hole or panoramic scene inside the limits can be drawn ------------------------------------------

def _in(r):
    return st.floats(r.low, r.high, allow_nan=False)


def _log_in(r):
    return st.floats(np.log10(r.low), np.log10(r.high)).map(lambda e: float(np.clip(10.0**e, r.low, r.high)))


coordinate = _in(limits.COORDINATE)
position = st.tuples(coordinate, coordinate, coordinate)
angles = st.tuples(_in(limits.ANGLE_DEG), _in(limits.ANGLE_DEG), _in(limits.ANGLE_DEG))
size = st.integers(int(limits.IMAGE_SIZE.low), int(limits.IMAGE_SIZE.high))
principal = st.tuples(_in(limits.PRINCIPAL_POINT), _in(limits.PRINCIPAL_POINT))


@st.composite
def pinholes(draw, name):
    """Pin-hole specs spread over the whole of every range (log-uniform where the range spans decades)."""
    f = draw(_log_in(limits.FOCAL_LENGTH))
    fpx = draw(_log_in(limits.FOCAL_PIXELS))
    ku = float(np.clip(fpx / f, limits.PIXELS_PER_METRE.low, limits.PIXELS_PER_METRE.high))
    kv = float(np.clip(ku * draw(st.floats(0.5, 2.0)), limits.PIXELS_PER_METRE.low, limits.PIXELS_PER_METRE.high))
    skew = draw(st.floats(-1.0, 1.0)) * min(f * ku, limits.SKEW.high)
    try:
        return PinholeSpec(name, draw(position), draw(angles), f, (ku, kv), draw(principal), skew, draw(size), draw(size))
    except SceneError:  # the clipped ku, kv left the focal length in pixels out of range
        reject()


@st.composite
def panoramics(draw, name):
    a = draw(_log_in(limits.MIRROR_PARAMETER))
    ratio = draw(_log_in(limits.MIRROR_B_OVER_A))
    b = float(np.clip(a * ratio, limits.MIRROR_PARAMETER.low, limits.MIRROR_PARAMETER.high))
    mirror = draw(st.sampled_from(["hyperbolic", "parabolic"]))
    try:
        return PanoramicSpec(name, draw(position), draw(angles), mirror, a, b, draw(_log_in(limits.PANORAMIC_FOCAL_PIXELS)),
                             draw(principal), draw(size), draw(size))
    except SceneError:  # the clipped b left the ratio out of range
        reject()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(a=pinholes("c"), b=st.one_of(pinholes("d"), panoramics("d")), c=panoramics("e"),
       pts=st.lists(position, max_size=20), sel=st.integers(0, 19), pair=st.sampled_from([("c", "d"), ("d", "e"), ("c", "e")]))
def test_every_scene_inside_the_limits_is_drawn(a, b, c, pts, sel, pair):
    scene = Scene(cameras=(a, b, c), points=tuple(pts), pair=pair, selected_point=sel if sel < len(pts) else None)
    derived = compute_derived(scene)
    assert set(derived.image_planes) == {"c", "d", "e"}
    for plane in derived.image_planes.values():
        assert not np.isinf(plane.points).any()
