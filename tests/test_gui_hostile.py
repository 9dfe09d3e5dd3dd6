"""The GUI in front of a clumsy or hostile user: every bad value is refused with a message, the tab carries on.

A real viser server runs in-process with the app; ``FakeTab`` is a websocket
client. Most tests set a handle's value (its callbacks run at once: the app is
started with ``field_delay=0``); the forged-message tests send raw viser
messages over the websocket, as a hand-written client could, and wait for the
notification the server sends back.
"""

from __future__ import annotations

import json
import math
import threading
import time
import types

import numpy as np
import pytest
import viser
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.scene import SCENES, SceneError, default_scene, limits, scene_from_bytes
from egtviz.controllers.workbench_fields import FieldError, NumberRule, format_number, format_numbers, parse_numbers
from egtviz.viewer.workbench.fields import Debouncer, safe_callback
from egtviz.viewer.server.headless import start_headless

from _threads import joined  # noqa: E402
from _waiting import wait_for  # noqa: E402

FOCAL = NumberRule("focal length", "mm", 0.1, 10_000.0)


def record_notes(view):
    view.notes = []
    view.client.add_notification = lambda title, body, v=view, **kw: v.notes.append((title, body))
    return view


@pytest.fixture
def tab():
    server, app, fakes, views = start_headless(default_scene())
    yield app, fakes[0], record_notes(views[0])
    for f in fakes:
        f.close()
    server.stop()


def fire(handle, view, value) -> None:
    """What viser does for an incoming value: store it unconverted and call the handle's callbacks."""
    handle._impl.value = value
    for cb in handle._impl.update_cb:
        cb(types.SimpleNamespace(target=handle, client=view.client, client_id=None))


# -- parsing the raw text of a field ---------------------------------------------------------------


@pytest.mark.parametrize(
    "text, reason",
    [
        ("nan", "expected a number, got 'nan'"),
        ("abc", "expected a number, got 'abc'"),
        ("inf", "expected a number"),
        ("1e400", "too large to be a number"),
        ("", "expected a number, got ''"),
        ("1_0", "expected a number"),  # Python's float() would read 10
        ("0x10", "expected a number"),
        ("12, 3", "expected a number, got '12, 3'"),
        ("0", "must be between 0.1 mm and 10000 mm, got 0 mm"),
        ("-5", "got -5 mm"),
        ("1e5", "got 100000 mm"),
    ],
)
def test_a_number_field_refuses_text_that_is_not_a_valid_number(text, reason):
    with pytest.raises(FieldError) as info:
        parse_numbers(text, (FOCAL,), owner="cam1")
    assert str(info.value).startswith("cam1: focal length")
    assert reason in str(info.value)


def test_a_number_field_reads_decimal_text():
    assert parse_numbers(" 12.5 ", (FOCAL,)) == (12.5,)
    assert parse_numbers("1e1", (FOCAL,)) == (10.0,)
    assert parse_numbers(".5", (FOCAL,)) == (0.5,)
    size = NumberRule("image size width", "px", 1, 8192, integer=True)
    assert parse_numbers("640, 480.0", (size, size)) == (640.0, 480.0)
    with pytest.raises(FieldError, match=r"must be a whole number, got 640.5 px"):
        parse_numbers("640.5, 480", (size, size))  # refused, never rounded


def test_a_field_text_is_quoted_short_and_printable():
    with pytest.raises(FieldError) as info:
        parse_numbers("\x1b[31m" + "x" * 5000, (FOCAL,))
    assert "\x1b" not in str(info.value) and len(str(info.value)) < 150


def test_a_vector_field_shows_rounding_as_zero():
    # A gizmo's turn about a vertical axis comes back from the rotation matrix with a roll of ~4e-15 degrees.
    assert format_numbers((20.556, -3.34916, 3.98412e-15)) == "20.556, -3.34916, 0"
    assert format_numbers((-2.7, -8.0, 1.5)) == "-2.7, -8, 1.5"
    # Small is not rounding when nothing larger stands beside it, nor at 1e-12 of the largest and above.
    assert format_numbers((1e-13, 0.0)) == "1e-13, 0"
    assert format_numbers((1.0, 2e-12)) == "1, 2e-12"
    assert format_numbers((5.0, -4e-13)) == "5, 0"


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=-1e4, max_value=1e4, allow_nan=False))
def test_format_then_parse_gives_the_value_to_six_digits(x):
    rule = NumberRule("x", "m", -1e4, 1e4)
    (back,) = parse_numbers(format_number(x), (rule,))
    assert back == pytest.approx(x, rel=5e-6, abs=1e-300)


@settings(max_examples=200, deadline=None)
@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(min_value=0.0, max_value=1e6))
def test_a_rule_accepts_exactly_its_range(x, hi):
    rule = NumberRule("v", "u", 0.0, hi)
    if math.isfinite(x) and 0.0 <= x <= hi:
        assert rule.check(x) == x
    else:
        with pytest.raises(FieldError):
            rule.check(x)


def test_debouncer_runs_only_the_text_the_user_stopped_at():
    seen = []
    typing = Debouncer(1.0)  # keystrokes 0.02 s apart: well inside the delay even when a busy machine stretches them
    for text in ("0", "0.", "0.5"):
        typing.submit("focal", lambda t=text: seen.append(t))
        time.sleep(0.02)
    wait_for(lambda: seen, "the debounced text to run")
    assert seen == ["0.5"] and not typing.pending()
    # A later text, typed after the user stopped: by the time it runs, a replaced text that had been left to run
    # would have run too (it was due earlier).
    typing.submit("focal", lambda: seen.append("0.7"))
    wait_for(lambda: len(seen) >= 2, "the later text to run")
    assert seen == ["0.5", "0.7"] and not typing.pending()


def test_safe_callback_reports_instead_of_raising():
    got = []
    safe_callback(lambda e: 1 / 0, got.append)(None)
    assert len(got) == 1 and isinstance(got[0], ZeroDivisionError)


# -- fields of the workbench -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "key, text, message",
    [
        ("focal", "nan", "cam1: focal length: expected a number, got 'nan'"),
        ("focal", "abc", "cam1: focal length: expected a number, got 'abc'"),
        ("focal", "1e400", "cam1: focal length: '1e400' is too large to be a number"),
        ("focal", "0", "cam1: focal length must be between 0.1 mm and 10000 mm, got 0 mm"),
        ("size", "640.5, 480", "cam1: image size width must be a whole number, got 640.5 px"),
        ("size", "0, 480", "cam1: image size width must be between 1 px and 8192 px, got 0 px"),
        ("pixel", "10, 0", "cam1: pixel size y must be between 0.1 µm and 1000000 µm, got 0 µm"),
        ("position", "1, 2", "cam1: position: expected 3 numbers separated by commas, got '1, 2'"),
        ("position", "0, 0, 1e5", "cam1: position z must be between -10000 m and 10000 m, got 100000 m"),
        ("ypr", "1, nan, 0", "cam1: angle pitch: expected a number, got 'nan'"),
    ],
)
def test_bad_field_text_is_refused_in_the_fields_units_and_reverted(tab, key, text, message):
    app, fake, view = tab
    field = view.cameras["cam1"].fields[key]
    shown, scene, rev = field.value, view.model.scene, view.revision
    field.value = text
    assert view.model.scene is scene and view.revision == rev
    assert field.value == shown  # back to the last valid value
    assert view.notes[-1] == ("Value refused", message)


def test_a_panoramic_field_names_its_camera(tab):
    app, fake, view = tab
    view.controls.add_buttons["hyperbolic"].value = True
    f = view.cameras["pano1"].fields
    f["b"].value = "0"
    assert view.notes[-1] == ("Value refused", "pano1: b must be between 0.001 m and 100 m, got 0 m")
    assert f["b"].value == "1"
    fire(f["mirror"], view, "elliptic")  # a drop-down value no browser offers
    assert view.notes[-1][1] == "pano1: mirror must be one of hyperbolic, parabolic, got 'elliptic'"
    assert f["mirror"].value == "hyperbolic" and view.model.scene.camera("pano1").mirror == "hyperbolic"


def test_a_limit_across_fields_is_reported_in_the_fields_terms(tab):
    """Each field in range, but focal length / pixel size = 10 m / 0.1 um is 1e8 px, over the scene's limit."""
    app, fake, view = tab
    f = view.cameras["cam1"].fields
    f["focal"].value = "10000"
    f["pixel"].value = "0.1, 0.1"
    assert view.notes[-1] == ("Value refused", "cam1: focal length in pixels (focal length / pixel size) must be "
                                               "between 1 px and 1000000 px, got 100000000 px")
    assert f["pixel"].value == "10, 10" and view.model.scene.camera("cam1").pixels_per_metre == (1e5, 1e5)
    view.controls.add_buttons["hyperbolic"].value = True
    view.cameras["pano1"].fields["b"].value = "0.01"  # a = 3: b / a = 0.0033
    assert view.notes[-1] == ("Value refused", "pano1: b / a must be between 0.01 and 100, got 0.00333333")
    assert view.cameras["pano1"].fields["b"].value == "1"


def test_a_value_the_model_refuses_at_commit_reverts_the_field(tab, monkeypatch):
    """In range for the field, but the scene cannot be drawn: the model refuses it before commit."""
    import egtviz.scene.model as model_module

    app, fake, view = tab
    real = model_module.compute_derived

    def undrawable_at_9mm(scene):
        if any(c.kind == "pinhole" and abs(c.focal_length - 0.009) < 1e-12 for c in scene.cameras):
            raise SceneError("the scene cannot be drawn: image plane degenerate")
        return real(scene)

    monkeypatch.setattr(model_module, "compute_derived", undrawable_at_9mm)
    field = view.cameras["cam1"].fields["focal"]
    field.value = "9"
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.008)
    assert field.value == "8"
    title, body = view.notes[-1]
    assert title == "Value refused" and body.startswith("cam1: ") and "cannot be drawn" in body
    field.value = "11"  # the tab carries on
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.011)


def test_numbers_left_as_shown_keep_their_full_precision(tab):
    app, fake, view = tab
    before = view.model.scene.camera("cam1").ypr_deg
    field = view.cameras["cam1"].fields["ypr"]
    yaw, pitch, _ = field.value.split(", ")
    assert float(yaw) != before[0]  # the field shows six digits of 20.556045...
    field.value = f"{yaw}, {pitch}, 5"
    assert view.model.scene.camera("cam1").ypr_deg == (before[0], before[1], 5.0)
    n_undo = len(view.model._undo)
    field.value = f"{yaw}, {pitch}, 5"  # the same text again: no change, no undo step
    assert len(view.model._undo) == n_undo


def test_typing_partial_text_commits_only_the_final_value():
    # Keystrokes 0.02 s apart, well inside the field's delay even when a busy machine stretches them.
    server, app, fakes, views = start_headless(default_scene(), field_delay=1.0)
    try:
        view = record_notes(views[0])
        field = view.cameras["cam1"].fields["focal"]
        for text in ("0", "0.", "0.5"):  # keystrokes of "0.5": "0" alone would be refused
            field.value = text
            time.sleep(0.02)
        wait_for(lambda: view.model.scene.camera("cam1").focal_length == pytest.approx(0.0005),
                 "the field's last text, 0.5, to be committed")
        assert view.notes == [] and field.value == "0.5"
        field.value = "-"  # left as is: judged once the user stops
        # Its refusal is the first note: "0", due before it, was not judged (it would have been refused first).
        wait_for(lambda: view.notes, "the refusal of '-'")
        assert view.notes[0][1] == "cam1: focal length: expected a number, got '-'" and field.value == "0.5"
        assert len(view.notes) == 1
    finally:
        fakes[0].close()
        server.stop()


# -- limits the page shows are the server's --------------------------------------------------------


def test_points_count_is_enforced_by_the_server(tab):
    app, fake, view = tab
    view.controls.n_points.value = str(limits.MAX_POINTS + 1)
    assert view.notes[-1][1] == f"how many points must be between 0 and {limits.MAX_POINTS}, got {limits.MAX_POINTS + 1}"
    assert view.controls.n_points.value == "8"
    view.controls.n_points.value = "2.5"
    assert "whole number" in view.notes[-1][1] and view.controls.n_points.value == "8"
    fire(view.controls.n_points, view, "100000")  # straight into the handle, as if no field check had run
    view.controls.btn_random.value = True
    assert len(view.model.scene.points) == 8 and "100000" in view.notes[-1][1]


def test_a_forged_gui_message_over_the_websocket_is_refused(tab):
    app, fake, view = tab
    fake.send("GuiUpdateMessage", uuid=view.controls.n_points._impl.uuid, updates={"value": 100000})
    wait_for(lambda: view.notes, "the refusal of 100000 points")
    assert view.notes[-1] == ("Value refused", f"how many points must be between 0 and {limits.MAX_POINTS}, got 100000")
    wait_for(lambda: view.controls.n_points.value == "8", "the field to show 8 points again")
    points = view.model.scene.points
    fake.send("GuiUpdateMessage", uuid=view.controls.btn_random._impl.uuid, updates={"value": True})
    wait_for(lambda: view.model.scene.points != points, "the click on 'Randomise points' to run")
    assert len(view.model.scene.points) == 8  # the count the server kept, not the forged one
    fake.send("GuiUpdateMessage", uuid=view.controls.surface_kind._impl.uuid, updates={"value": "mesh: /etc/passwd"})
    fake.send("GuiUpdateMessage", uuid=view.controls.btn_surface._impl.uuid, updates={"value": True})
    wait_for(lambda: len(view.notes) >= 2, "the refusal of the forged surface")
    assert view.notes[-1] == ("Value refused", "surface: no surface 'mesh: /etc/passwd'")
    assert view.model.scene.surfaces == ()


def test_forged_gizmo_messages_are_refused_and_the_gizmo_goes_back(tab):
    app, fake, view = tab
    gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
    owner = view.client.scene._owner_id
    before = view.model.scene.camera("cam1")
    for wxyz, position in (((0.0, 0.0, 0.0, 0.0), (1.0, 2.0, 3.0)), ((1.0, 0.0, 0.0, 0.0), (math.nan, 0.0, 0.0)),
                           ((math.inf, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0))):
        n = len(view.notes)
        fake.send("TransformControlsUpdateMessage", name=gizmo.name, wxyz=wxyz, position=position, owner=owner)
        wait_for(lambda: len(view.notes) > n, f"the refusal of the forged gizmo pose {wxyz} {position}")
        assert view.model.scene.camera("cam1") == before
        wait_for(lambda: np.allclose(gizmo.position, before.position), "the gizmo to go back")
    assert all(title == "Value refused" for title, _ in view.notes), view.notes
    g = view.scene3d._point_gizmos[0]
    fake.send("TransformControlsUpdateMessage", name=g.name, wxyz=(1.0, 0.0, 0.0, 0.0),
              position=(math.nan, 1.0, 1.0), owner=owner)
    wait_for(lambda: len(view.notes) == 4, "the refusal of the forged point gizmo pose")
    assert "point 1" in view.notes[-1][1] and view.model.scene.points[0] == default_scene().points[0]
    # the tab still works
    view.cameras["cam1"].fields["focal"].value = "12"
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.012)


@pytest.mark.parametrize(
    "handle, value, message",
    [
        ("pair_dropdown", "cam1 & nobody", "drawn pair: no pair 'cam1 & nobody'"),
        ("point_dropdown", "point 99999", "selected point: no 'point 99999' (have 8 points)"),
        ("builtin", "../../etc/passwd", "built-in scene: no scene '../../etc/passwd'"),
    ],
)
def test_forged_drop_down_values_are_refused(tab, handle, value, message):
    app, fake, view = tab
    h = getattr(view.controls, handle)
    shown = h.value
    fire(h, view, value)
    if handle == "builtin":
        view.controls.btn_open.value = True
    assert view.notes[-1][0] == "Value refused" and view.notes[-1][1].startswith(message)
    assert view.model.scene is not None and len(view.model.scene.cameras) == 2
    if handle != "builtin":
        assert h.value == shown


def test_the_surface_drop_down_lists_the_package_meshes_by_name(tab):
    from egtviz.scene import mesh_names

    app, fake, view = tab
    names = mesh_names()
    assert names  # the package ships at least one mesh
    assert set(view.controls.surface_kind.options) == {"plane", "sphere"} | {f"mesh: {m}" for m in names}
    view.controls.surface_kind.value = f"mesh: {names[0]}"
    view.controls.btn_surface.value = True
    (surface,) = view.model.scene.surfaces
    assert surface.kind == "mesh" and surface.path == names[0]


def test_an_exception_in_any_callback_reaches_the_tab(tab, monkeypatch):
    app, fake, view = tab
    monkeypatch.setattr(view.model, "add_point", lambda xyz: (_ for _ in ()).throw(RuntimeError("/secret/path")))
    view.controls.btn_add_point.value = True
    title, body = view.notes[-1]
    assert title == "Something went wrong" and "RuntimeError" in body and "/secret" not in body
    view.cameras["cam1"].fields["focal"].value = "12"  # still working
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.012)


def test_every_callback_of_the_viewer_is_registered_safely():
    """No bare ``on_update``/``on_click``/``on_upload`` call: each goes through ``fields.on_event``."""
    import importlib
    import inspect
    import pkgutil
    import re

    import egtviz.viewer

    names = [m.name for m in pkgutil.walk_packages(egtviz.viewer.__path__, "egtviz.viewer.")]
    assert {"egtviz.viewer.workbench.app", "egtviz.viewer.workbench.scene3d",
            "egtviz.viewer.servo.servo_player"} <= set(names)
    for name in names:
        module = importlib.import_module(name)
        src = inspect.getsource(module)
        bare = re.findall(r"\.on_(?:update|click|upload)\(", src)
        assert bare == [], f"{module.__name__}: {len(bare)} callbacks registered without fields.on_event"


# -- uploads, downloads, built-in scenes -----------------------------------------------------------


def upload(view, name: str, content) -> None:
    from viser import UploadedFile

    fire(view.controls.btn_load, view, UploadedFile(name, content))


def test_an_oversized_upload_is_refused_before_parsing(tab, monkeypatch):
    import egtviz.controllers.workbench as app_module

    app, fake, view = tab
    parsed = []
    monkeypatch.setattr(app_module, "scene_from_bytes", lambda *a, **k: parsed.append(a))
    before = view.model.scene
    upload(view, "big.json", b" " * (limits.MAX_SCENE_FILE_BYTES + 1))
    assert parsed == [] and view.model.scene is before
    title, body = view.notes[-1]
    assert title == "Could not load the scene"
    assert body == f"big.json: the file has {limits.MAX_SCENE_FILE_BYTES + 1} bytes; a scene file has at most " \
                   f"{limits.MAX_SCENE_FILE_BYTES} bytes"


@pytest.mark.parametrize(
    "content, expected",
    [
        (b"\xff\xfe", "not UTF-8"),
        (b"[]", "x.json"),
        (json.dumps({"cameras": [{"kind": "pinhole", "name": "c", "focal_length": "0.008"}]}).encode(), "x.json"),
        (json.dumps({"points": [[0, 0, 1e200]]}).encode(), "x.json"),
        (json.dumps({"surfaces": [{"kind": "mesh", "path": "/etc/passwd"}]}).encode(), "x.json"),
    ],
)
def test_a_bad_upload_notifies_and_keeps_the_scene(tab, content, expected):
    app, fake, view = tab
    before = view.model.scene
    upload(view, "x.json", content)
    assert view.model.scene is before
    title, body = view.notes[-1]
    assert title == "Could not load the scene" and expected in body
    assert "Traceback" not in body


def test_an_upload_with_a_hostile_name_is_named_as_text(tab):
    app, fake, view = tab
    upload(view, "<img src=x onerror=alert(1)>\x1b[2J.json", b"{")
    body = view.notes[-1][1]
    assert "\x1b" not in body and body.startswith("<img src=x onerror=alert(1)>?[2J.json: ")


def test_a_forged_upload_value_that_is_no_file_is_refused(tab):
    app, fake, view = tab
    fire(view.controls.btn_load, view, "not a file")
    assert view.notes[-1] == ("Could not load the scene", "the upload: the upload holds no file")


def test_save_downloads_what_load_reads_back(tab):
    app, fake, view = tab
    sent = []
    view.client.send_file_download = lambda name, data, **kw: sent.append((name, data, kw))
    view.model.update_camera("cam1", focal_length=0.0125)
    view.model.highlight(["cam2"])
    view.controls.btn_save.value = True
    (name, data, kw), = sent
    assert name == "Two_pin-hole_cameras_looking_at_a_cube.json" or name.endswith(".json")
    assert "/" not in name and "\\" not in name
    back = scene_from_bytes(data, name)
    assert back == view.model.scene


def test_built_in_scenes_open_from_the_drop_down(tab):
    app, fake, view = tab
    assert tuple(view.controls.builtin.options) == tuple(SCENES)
    view.controls.builtin.value = "panoramic"
    view.controls.btn_open.value = True
    assert view.model.scene == SCENES["panoramic"]()
    assert {c.kind for c in view.model.scene.cameras} == {"panoramic"}
    view.controls.btn_undo.value = True
    assert view.model.scene.camera_names == ("cam1", "cam2")


# -- titles are text -------------------------------------------------------------------------------


def test_titles_and_names_from_files_are_shown_as_text():
    scene = default_scene().replace(title="<script>alert(1)</script> **bold** [x](javascript:alert(1))")
    server, app, fakes, views = start_headless(scene)
    try:
        view = views[0]
        html = view.controls.title.content
        assert "<script>" not in html and "&lt;script&gt;alert(1)&lt;/script&gt;" in html
        # shown in HTML, never through markdown: the asterisks and the link stay literal characters
        assert "**bold** [x](javascript:alert(1))" in html
    finally:
        fakes[0].close()
        server.stop()


# -- a tab is never left half-built ----------------------------------------------------------------


def test_a_tab_whose_scene_cannot_be_built_falls_back_to_the_default_scene(monkeypatch):
    import egtviz.viewer.tabs as app_module

    scene = default_scene().replace(title="broken")
    real = app_module.SceneModel

    def model_of(s=None):
        if s is not None and s.title == "broken":
            raise SceneError("broken: the scene cannot be drawn")
        return real(s)

    monkeypatch.setattr(app_module, "SceneModel", model_of)
    notes = []
    # The notification goes out while the tab is built, before a test could reach its client: record them all.
    monkeypatch.setattr(viser.ClientHandle, "add_notification",
                        lambda self, title, body, **kw: notes.append((title, body)))
    server, app, fakes, views = start_headless(scene)
    try:
        (view,) = views
        assert notes == [("Showing the default scene instead",
                          "The scene could not be drawn: broken: the scene cannot be drawn")]
        assert view.model.scene == default_scene()
        assert set(view.svgs) == {"cam1", "cam2"}
        view.cameras["cam1"].fields["focal"].value = "12"
        assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.012)
    finally:
        fakes[0].close()
        server.stop()


def test_a_servo_demo_that_cannot_open_leaves_a_working_workbench(tab, monkeypatch):
    import egtviz.viewer.servo.servo_demo as servo_demo

    app, fake, view = tab

    def broken(self, *a, **k):
        raise RuntimeError("/server/path/to/meshes missing")

    monkeypatch.setattr(servo_demo.ServoDemo, "__init__", broken)
    client = view.client
    view.controls.servo_buttons["pinhole"].value = True
    assert not app.demos and view.closed
    new = app.views[client.client_id]
    assert new is not view and new.model is view.model  # the tab's own scene is back
    title, body = view.notes[-1]
    assert title == "Could not open the demo" and "RuntimeError" in body and "/server" not in body
    new.cameras["cam1"].fields["focal"].value = "12"
    assert new.model.scene.camera("cam1").focal_length == pytest.approx(0.012)


def test_a_render_failure_shows_the_message_and_the_tab_stays_usable(tab, monkeypatch):
    from egtviz.viewer.workbench import panel_dock as app_module

    app, fake, view = tab
    real = app_module.image_plane_svg
    calls = {"n": 0}

    def failing_once(*a, **k):
        calls["n"] += 1
        if calls["n"] == 1:
            raise RuntimeError("boom")
        return real(*a, **k)

    monkeypatch.setattr(app_module, "image_plane_svg", failing_once)
    view.cameras["cam1"].fields["focal"].value = "12"
    assert view.notes[-1][0] == "Something went wrong"
    view.cameras["cam1"].fields["focal"].value = "13"
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.013)
    assert "epipolar-line" in view.svgs["cam1"]


# -- concurrent bad input --------------------------------------------------------------------------


def test_bad_and_good_edits_from_many_threads_end_in_a_valid_state(tab):
    app, fake, view = tab
    field = view.cameras["cam1"].fields["focal"]
    texts = ["nan", "12", "abc", "-1", "14", "1e400", "9"] * 4

    def edit(text):
        fire(field, view, text)

    threads = [threading.Thread(target=edit, args=(t,)) for t in texts]
    for t in threads:
        t.start()
    for t in threads:
        joined(t, "an edit's thread")
    f = view.model.scene.camera("cam1").focal_length
    assert f * 1e3 in (pytest.approx(12.0), pytest.approx(14.0), pytest.approx(9.0))
    view.resync()
    assert float(field.value) == pytest.approx(f * 1e3)
