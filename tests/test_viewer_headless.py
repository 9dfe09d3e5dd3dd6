"""The viewer's update path on a real viser server, with a websocket stand-in for the browser.

Setting a GUI handle's ``.value`` runs its callbacks synchronously (and the
app judges text fields at once with ``field_delay=0``), so a test can edit a
field and then read the model and the SVG the panel received. Number fields are
text fields: a test types the text a user would.
"""

from __future__ import annotations

import json
import threading
import time
import types
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from egtviz.scene import default_scene, scene_from_bytes
from egtviz.viewer.server.headless import start_headless

from _threads import joined
from _waiting import wait_for


def kinds(svg: str, kind: str) -> list[ET.Element]:
    return [el for el in ET.fromstring(svg).iter() if el.get("data-kind") == kind]


def line_coords(svg: str) -> np.ndarray:
    return np.array([[float(e.get(k)) for k in ("x1", "y1", "x2", "y2")] for e in kinds(svg, "epipolar-line")])


@pytest.fixture
def tabs(request):
    n = getattr(request, "param", 1)
    server, app, fakes, views = start_headless(default_scene(), tabs=n)
    for v in views:
        v.notes = []
        v.client.add_notification = (  # record instead of sending
            lambda title, body, v=v, **kw: v.notes.append((title, body))
        )
    yield app, views
    for f in fakes:
        f.close()
    server.stop()


def view_of(tabs):
    return tabs[1][0]


def test_initial_panels_match_the_scene(tabs):
    view = view_of(tabs)
    assert set(view.svgs) == {"cam1", "cam2"}
    for name, svg in view.svgs.items():
        root = ET.fromstring(svg)
        assert root.get("data-camera") == name
        assert len(kinds(svg, "point")) == 8
        assert len(kinds(svg, "epipolar-line")) == 8
        assert len(kinds(svg, "epipole")) == 1
    assert "rank 2" in view.readout


def test_editing_focal_length_changes_model_and_lines(tabs):
    view = view_of(tabs)
    before1, before2 = line_coords(view.svgs["cam1"]), line_coords(view.svgs["cam2"])
    before_rev = view.revision
    view.cameras["cam1"].fields["focal"].value = "12"
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.012)
    assert view.revision == before_rev + 1  # one change -> one update
    # Image 1 is magnified, so its epipolar lines move; in image 2, l2 = F m1 = K2^-T E x1 does not
    # depend on K1, so those lines stay put.
    assert not np.allclose(line_coords(view.svgs["cam1"]), before1, atol=0.5)
    assert np.allclose(line_coords(view.svgs["cam2"]), before2, atol=0.2)


def test_moving_a_camera_changes_the_other_image_lines(tabs):
    view = view_of(tabs)
    before = line_coords(view.svgs["cam2"])
    view.cameras["cam1"].fields["position"].value = "-4, -8, 1.5"
    assert view.model.scene.camera("cam1").position == (-4.0, -8.0, 1.5)
    after = line_coords(view.svgs["cam2"])
    assert before.shape == after.shape and not np.allclose(before, after, atol=0.5)
    # the gizmo follows the field
    gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
    assert np.allclose(gizmo.position, (-4.0, -8.0, 1.5))


@pytest.mark.parametrize("bad", ["-5", "0", "nan"])
def test_invalid_focal_length_is_refused_and_reverted(tabs, bad):
    view = view_of(tabs)
    field = view.cameras["cam1"].fields["focal"]
    good = field.value
    assert good == "8"
    rev = view.revision
    field.value = bad
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.008)
    assert field.value == good  # the field shows the last valid value again
    assert view.revision == rev
    assert view.notes and view.notes[-1][0] == "Value refused"


def test_invalid_mirror_parameter_is_refused(tabs):
    view = view_of(tabs)
    view.controls.add_buttons["hyperbolic"].value = True
    name = [c.name for c in view.model.scene.cameras if c.kind == "panoramic"][0]
    field = view.cameras[name].fields["a"]
    field.value = "-1"
    assert view.model.scene.camera(name).a == 3.0
    assert field.value == "3"
    assert view.notes


def fake_drag(gizmo, position, wxyz, phase="update", stamp=None):
    gizmo._impl.position = np.asarray(position, float)
    gizmo._impl.wxyz = np.asarray(wxyz, float)
    gizmo._impl_aux.last_updated = time.time() if stamp is None else stamp
    return types.SimpleNamespace(target=gizmo, phase=phase, client=None, client_id=None)


def test_camera_gizmo_drag_updates_model_and_fields(tabs):
    view = view_of(tabs)
    gizmo = view.scene3d.camera_nodes("cam2")["gizmo"]
    wxyz = np.array(gizmo.wxyz)
    view.drag.camera_event("cam2", fake_drag(gizmo, (2.0, -7.0, 2.0), wxyz))
    spec = view.model.scene.camera("cam2")
    assert spec.position == pytest.approx((2.0, -7.0, 2.0))
    assert view.cameras["cam2"].fields["position"].value == "2, -7, 2"
    # the yaw/pitch/roll field shows the same orientation as before
    shown = [float(x) for x in view.cameras["cam2"].fields["ypr"].value.split(",")]
    assert shown == pytest.approx(default_scene().camera("cam2").ypr_deg, abs=1e-4)


def test_late_gizmo_event_does_not_overwrite_a_newer_one(tabs):
    view = view_of(tabs)
    gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
    wxyz = np.array(gizmo.wxyz)
    now = time.time()
    view.drag.camera_event("cam1", fake_drag(gizmo, (-2.0, -8.0, 1.5), wxyz, stamp=now))
    old = types.SimpleNamespace(target=types.SimpleNamespace(position=np.array([9.0, 9.0, 9.0]), wxyz=wxyz,
                                                             update_timestamp=now - 1.0), phase="update")
    view.drag.camera_event("cam1", old)
    assert view.model.scene.camera("cam1").position == pytest.approx((-2.0, -8.0, 1.5))


def test_point_gizmo_moves_and_selects_the_point(tabs):
    view = view_of(tabs)
    g = view.scene3d._point_gizmos[2]
    view.drag.point_event(2, fake_drag(g, g.position, (1, 0, 0, 0), phase="start"))
    assert view.model.scene.selected_point == 2
    assert view.controls.point_dropdown.value == "point 3"
    view.drag.point_event(2, fake_drag(g, (0.5, 0.5, 0.5), (1, 0, 0, 0)))
    assert view.model.scene.points[2] == pytest.approx((0.5, 0.5, 0.5))
    rings = [el for el in ET.fromstring(view.svgs["cam1"]).iter() if el.get("data-selected") == "true"]
    assert len(rings) == 1
    assert view.scene3d.epiplane.visible


def test_buttons_add_and_remove_cameras_and_panels(tabs):
    view = view_of(tabs)
    view.controls.add_buttons["pinhole"].value = True
    names = view.model.scene.camera_names
    assert len(names) == 3 and set(view.dock.html) == set(names)
    assert len(view.controls.pair_dropdown.options) == 3
    view.controls.pair_dropdown.value = f"cam1 & {names[2]}"
    assert view.model.scene.drawn_pair == ("cam1", names[2])
    assert len(kinds(view.svgs["cam2"], "epipolar-line")) == 0  # not in the drawn pair
    assert len(kinds(view.svgs[names[2]], "epipole")) == 1
    view.controls.btn_undo.value = True
    assert view.model.scene.drawn_pair == ("cam1", "cam2")
    view.controls.btn_undo.value = True
    assert len(view.model.scene.cameras) == 2 and set(view.dock.html) == {"cam1", "cam2"}


def test_points_buttons_and_toggles(tabs):
    view = view_of(tabs)
    view.controls.n_points.value = "40"
    view.controls.btn_random.value = True
    assert len(view.model.scene.points) == 40
    assert len(view.scene3d._point_gizmos) == 0  # many points: only the selected one gets a gizmo
    view.controls.point_dropdown.value = "point 5"
    assert view.model.scene.selected_point == 4 and list(view.scene3d._point_gizmos) == [4]
    view.controls.btn_remove_point.value = True
    assert len(view.model.scene.points) == 39 and view.model.scene.selected_point is None
    view.controls.toggles["show_rays"].value = False
    assert view.model.scene.options.show_rays is False
    assert not any(r.visible for r in view.scene3d._rays.values())
    view.controls.btn_surface.value = True
    assert len(view.model.scene.surfaces) == 1 and view.scene3d.surfaces.visible
    view.controls.btn_reset.value = True
    assert len(view.model.scene.points) == 8


def test_centres_coinciding_shows_the_message(tabs):
    view = view_of(tabs)
    view.cameras["cam2"].fields["position"].value = "-3, -8, 1.5"  # cam1's centre
    for name in ("cam1", "cam2"):
        msgs = kinds(view.svgs[name], "message")
        assert msgs and "centres coincide" in msgs[0].text
    assert "centres coincide" in view.readout


def test_save_downloads_and_load_uploads(tabs):
    view = view_of(tabs)
    sent = []
    view.client.send_file_download = lambda name, data, **kw: sent.append((name, data))
    view.cameras["cam1"].fields["focal"].value = "10"
    view.controls.btn_save.value = True
    (name, data), = sent
    assert name.endswith(".json") and "/" not in name
    assert scene_from_bytes(data, "download").camera("cam1").focal_length == pytest.approx(0.010)
    view.controls.btn_reset.value = True
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.008)
    upload(view, "mine.json", data)
    assert view.model.scene.camera("cam1").focal_length == pytest.approx(0.010)
    assert view.cameras["cam1"].fields["focal"].value == "10"


def upload(view, name: str, content: bytes) -> None:
    """What viser does when an upload completes: store the file as the button's value, call its callbacks."""
    from viser import UploadedFile

    impl = view.controls.btn_load._impl
    impl.value = UploadedFile(name, content)
    for cb in impl.update_cb:
        cb(types.SimpleNamespace(target=view.controls.btn_load, client=view.client, client_id=None))


def test_malformed_upload_notifies_and_keeps_the_scene(tabs):
    view = view_of(tabs)
    bad = json.dumps({"cameras": [{"kind": "pinhole", "name": "x", "focal_length": -1}]}).encode()
    before = view.model.scene
    upload(view, "bad.json", bad)
    assert view.model.scene is before
    title, body = view.notes[-1]
    assert title == "Could not load the scene" and "bad.json" in body and "cameras[0]" in body
    upload(view, "garbage.json", b"{not json")
    assert view.model.scene is before and len(view.notes) == 2


@pytest.mark.parametrize("tabs", [2], indirect=True)
def test_two_tabs_have_separate_scenes(tabs):
    app, (a, b) = tabs
    assert a.model is not b.model
    b_svg = b.svgs["cam2"]
    a.cameras["cam1"].fields["position"].value = "-5, -8, 1.5"
    assert a.model.scene.camera("cam1").position == (-5.0, -8.0, 1.5)
    assert b.model.scene.camera("cam1").position == (-3.0, -8.0, 1.5)
    assert b.svgs["cam2"] == b_svg


def test_disconnect_drops_the_view():
    server, app, fakes, views = start_headless(default_scene())
    try:
        view = views[0]
        fakes[0].close()
        wait_for(lambda: not app.views, "the server to drop the closed tab's view")
        assert view.closed
        # a late gizmo event after the tab left changes nothing
        gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
        scene = view.model.scene
        view.drag.camera_event("cam1", types.SimpleNamespace(target=gizmo, phase="update"))
        assert view.model.scene is scene
        assert not view.model._listeners
    finally:
        server.stop()


def test_concurrent_events_end_in_the_latest_state(tabs):
    view = view_of(tabs)
    field = view.cameras["cam1"].fields["position"]
    # Events arriving from several threads (viser's thread pool): the final render shows the final model state.
    def edit(k):
        view.user_event(lambda: view.controller.set_field("cam1", "position", f"{-3.0 + 0.01 * k:g}, -8, 1.5"))

    threads = [threading.Thread(target=edit, args=(k,)) for k in range(20)]
    for t in threads:
        t.start()
    for t in threads:
        joined(t, "an edit's thread")
    final = view.model.scene.camera("cam1").position
    assert [float(x) for x in field.value.split(",")] == pytest.approx(final)
    assert np.allclose(view.scene3d.camera_nodes("cam1")["gizmo"].position, final)


def test_cli_serve_reports_the_real_port_and_bad_scene(tmp_path, capsys):
    from egtviz.viewer.server.cli import serve

    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert serve("127.0.0.1", 0, bad) != 0
    err = capsys.readouterr().err
    assert "bad.json" in err
    stop = threading.Event()
    rc = []
    th = threading.Thread(target=lambda: rc.append(serve("127.0.0.1", 0, None, stop_event=stop)))
    th.start()
    printed: list[str] = []

    def running() -> bool:
        printed.append(capsys.readouterr().out)
        return "running at" in "".join(printed) or not th.is_alive()

    wait_for(running, "serve to say it is running")
    stop.set()
    joined(th, "serve to stop")
    assert rc == [0]
    out = "".join(printed)
    port = int(out.split("http://127.0.0.1:")[1].split()[0])
    assert port > 0


def test_highlight_and_lock_from_a_lesson(tabs):
    view = view_of(tabs)
    view.model.highlight(["cam1", "point:2"])
    assert tuple(view.scene3d.camera_nodes("cam1")["frustum"].color) == (230, 159, 0)
    rings = [el for el in ET.fromstring(view.svgs["cam2"]).iter() if el.get("data-selected") == "false"]
    assert len(rings) == 1
    view.model.lock("cam1")
    g = view.scene3d.camera_nodes("cam1")["gizmo"]
    assert g.disable_axes and g.disable_rotations
    view.model.lock("point:1")
    assert view.scene3d._point_gizmos[1].disable_axes


def test_panoramic_and_mixed_pairs(tabs):
    view = view_of(tabs)
    view.controls.add_buttons["hyperbolic"].value = True
    pano = [c.name for c in view.model.scene.cameras if c.kind == "panoramic"][0]
    assert pano in view.svgs and len(kinds(view.svgs[pano], "rim")) == 1
    view.model.add_camera("panoramic")
    panos = [c.name for c in view.model.scene.cameras if c.kind == "panoramic"]
    view.controls.pair_dropdown.value = f"{panos[0]} & {panos[1]}"
    assert view.model.scene.drawn_pair == tuple(panos)
    assert len(view.dock.html) == 4
    for name in panos:
        assert kinds(view.svgs[name], "epipolar-conic")
        assert len(kinds(view.svgs[name], "epipole")) >= 1
    assert 'data-relation="essential"' in view.readout and "No F between pixels" in view.readout
    # a mixed pin-hole / panoramic pair must draw without errors, and says which relation holds
    view.controls.pair_dropdown.value = f"cam1 & {panos[0]}"
    assert view.model.scene.drawn_pair == ("cam1", panos[0])
    assert "d2&#7488; E d1 = 0" in view.readout and "rank" not in view.readout
    assert not kinds(view.svgs["cam1"], "message") or "cannot draw" not in kinds(view.svgs["cam1"], "message")[0].text


def test_gizmo_quaternion_matrix_matches_viser():
    from scipy.spatial.transform import Rotation
    from viser.transforms import SO3

    from egtviz.geometry.poses import matrix_from_quat_wxyz

    rng = np.random.default_rng(3)
    for _ in range(200):
        q = rng.normal(size=4)
        np.testing.assert_allclose(matrix_from_quat_wxyz(q), Rotation.from_quat(q, scalar_first=True).as_matrix(),
                                   atol=1e-12)
        q /= np.linalg.norm(q)
        np.testing.assert_allclose(matrix_from_quat_wxyz(q), SO3(q).as_matrix(), atol=1e-12)
    np.testing.assert_allclose(matrix_from_quat_wxyz((1.0, 0.0, 0.0, 0.0)), np.eye(3))
