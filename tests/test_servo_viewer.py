"""Headless tests of the servo demos (egtviz.viewer.servo.servo_demo and its per-demo classes) on a real viser server.

A websocket stand-in (egtviz.viewer.server.headless.FakeTab) is the browser tab; GUI
handle values are set directly (their callbacks run synchronously).
"""

from __future__ import annotations

import re
import time
import types

import numpy as np
import pytest
import viser

from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.servo.servo_demo import SERVO_DEMOS, ServoDemo, make_servo_demo
from egtviz.viewer.servo.servo_panoramic_demo import PanoramicServoDemo
from egtviz.viewer.servo.servo_pinhole_demo import PinholeServoDemo
from egtviz.viewer.render.servo_svg import ServoImage, servo_image_svg

from _waiting import PATIENCE, wait_for


@pytest.fixture(scope="module")
def client():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    clients = []
    server.on_client_connect(clients.append)
    tab = FakeTab(server.get_port())
    wait_for(lambda: clients, "the headless tab to connect")
    yield clients[0]
    tab.close()
    server.stop()


def _kinds(svg: str) -> dict[str, int]:
    out: dict[str, int] = {}
    for k in re.findall(r'data-kind="([a-z-]+)"', svg):
        out[k] = out.get(k, 0) + 1
    return out


def _point_xy(svg: str, i: int) -> tuple[float, float]:
    m = re.search(rf'data-kind="point" data-index="{i}" cx="([-\d.e]+)" cy="([-\d.e]+)"', svg)
    assert m, svg[:400]
    return float(m.group(1)), float(m.group(2))


def _trail_len(svg: str, i: int) -> int:
    m = re.search(rf'data-kind="trail" data-index="{i}" points="([^"]*)"', svg)
    return 0 if m is None else len(m.group(1).split())


def test_pinhole_demo_steps_and_scrubs(client):
    demo = make_servo_demo(client, "pinhole", steps=60, autoplay=False)
    try:
        assert demo.wait(PATIENCE) and demo.error == ""
        r = demo.result
        assert r is not None and r.n_samples == 61
        assert demo.frame == 0 and 'data-egtviz="servo-image"' in demo.svg
        s0 = demo.svg
        k0 = _kinds(s0)
        n = len(r.desired_features)
        assert k0["point"] == n and k0["desired"] == n
        assert k0["epipolar-line"] >= n - 1 and k0["epipole"] == 1
        assert "trail" not in k0  # one sample: no trail yet
        p0 = _point_xy(s0, 0)
        demo.clock.btn_step.value = None  # a "click": viser runs the button's callbacks on assignment
        assert demo.frame == 1
        demo.step(4)
        assert demo.frame == 5
        s5 = demo.svg
        assert _point_xy(s5, 0) != p0  # features move
        assert _kinds(s5)["trail"] == n and _trail_len(s5, 0) == 6
        demo.step(10)
        assert _trail_len(demo.svg, 0) == 16  # trails grow
        demo.step(-3)
        assert demo.frame == 12
        # The scrubber sets the frame (its callback runs synchronously).
        demo.clock.slider.value = float(r.time[40])
        assert demo.frame == 40 and 'data-frame="40"' in demo.svg
        assert abs(demo.clock.slider.value - r.time[40]) < 1e-9
        # Plots are revealed up to the current time.
        assert len(demo.display.plot_controls.data[0]) == 41 and len(demo.display.plot_controls.data) == 7
        assert len(demo.display.plot_errors.data[0]) == 41
        assert "rotation error" in demo.display.readout.content
        # Not converged in 60 steps: the status says why, no traceback.
        assert not r.converged and "not converged" in demo.form.status.content
    finally:
        demo.close()
    assert demo.closed


def test_pinhole_play_pause(client):
    demo = make_servo_demo(client, "pinhole", steps=200, autoplay=False, speed="4x")
    try:
        assert demo.wait(PATIENCE)
        demo.play()
        assert demo.playing and demo.clock.btn_play.label == "Pause"
        wait_for(lambda: demo.frame > 5, "the playback to move past frame 5")
        demo.pause()
        k = demo.frame
        assert k > 5 and not demo.playing and demo.clock.btn_play.label == "Play"
        # Paused: the playback loop stops (its thread ends), and the frame is where the pause left it.
        wait_for(lambda: not demo._play_thread.is_alive(), "the playback thread to end after the pause")
        assert demo.frame == k
    finally:
        demo.close()


def test_panoramic_demo_biconics(client):
    demo = make_servo_demo(client, "panoramic", steps=80, autoplay=False)
    try:
        assert demo.wait(PATIENCE) and demo.error == ""
        s0 = _kinds(demo.svg)
        n = len(demo.result.desired_features)
        assert s0["point"] == n and s0["desired"] == n and s0["rim"] == 1
        assert s0["epipolar-conic"] >= n  # one bi-conic (or more pieces) per feature
        demo.seek(30)
        k = _kinds(demo.svg)
        assert k["trail"] == n and k["epipolar-conic"] >= n
        assert "step 1: rotation" in demo.svg or "step 2: translation" in demo.svg
        assert len(demo.display.plot_controls.data) == 4  # t, v_x, v_y, omega
        demo.seek_time(1.0)
        assert demo.frame == 20
    finally:
        demo.close()


@pytest.fixture
def notes(client, monkeypatch):
    got: list[tuple[str, str]] = []
    monkeypatch.setattr(client, "add_notification", lambda title, body, **kw: got.append((title, body)))
    return got


def _fire(handle, client, value) -> None:
    """What viser does for an incoming value: store it and call the handle's callbacks."""
    handle._impl.value = value
    for cb in handle._impl.update_cb:
        cb(types.SimpleNamespace(target=handle, client=client, client_id=None))


@pytest.mark.parametrize(
    "field, text, message",
    [
        ("beta", "-1", "beta must be between 0 and 100, got -1"),
        ("steps", "0", "max steps must be between 1 and 10000, got 0"),
        ("steps", "1e9", "max steps must be between 1 and 10000, got 1000000000"),
        ("noise_px", "-3", "noise must be between 0 px and 50 px, got -3 px"),
        ("seed", "1.5", "seed must be a whole number, got 1.5"),
        ("seed", "abc", "seed: expected a number, got 'abc'"),
        ("noise_px", "nan", "noise: expected a number, got 'nan'"),
    ],
)
def test_bad_run_fields_are_refused_with_a_notification(client, notes, field, text, message):
    demo = make_servo_demo(client, "pinhole", steps=20, autorun=False, autoplay=False, field_delay=0)
    try:
        handle = demo.fields[field]
        shown, params = handle.value, demo.params()
        handle.value = text
        assert notes[-1] == ("Value refused", message)
        assert handle.value == shown and demo.params() == params  # the run uses the last valid values
        handle.value = "2"  # a good value afterwards is taken
        assert notes[-1] == ("Value refused", message) and len(notes) == 1
    finally:
        demo.close()


def test_run_fields_are_judged_once_the_user_stops_typing(client, notes):
    # Keystrokes 0.02 s apart, well inside the fields' delay even when a busy machine stretches them.
    demo = make_servo_demo(client, "panoramic", steps=20, autorun=False, autoplay=False, field_delay=1.0)
    try:
        for text in ("0", "0.", "0.5"):  # keystrokes; "0." alone is not a number
            demo.fields["noise_px"].value = text
            time.sleep(0.02)
        wait_for(lambda: demo.params()["noise_px"] == 0.5, "the last text typed, 0.5, to be taken")
        assert notes == []
    finally:
        demo.close()


def test_set_params_refuses_bad_values_and_changes_nothing(client):
    demo = make_servo_demo(client, "pinhole", steps=20, autorun=False, autoplay=False, field_delay=0)
    try:
        before = demo.params()
        for bad in ({"beta": -1.0}, {"steps": 0}, {"noise_px": -3.0}, {"seed": 1.5}, {"seed": True},
                    {"estimator": "magic"}, {"speed": "9x"}, {"steps": 10, "beta": float("nan")}):
            with pytest.raises(ValueError):
                demo.set_params(**bad)
            assert demo.params() == before
        with pytest.raises(ValueError, match="wheels: not a parameter of the pinhole demo"):
            demo.set_params(wheels=2)
        demo.set_params(beta=0.5, steps=30, seed="4294967295")
        assert demo.params() == {**before, "beta": 0.5, "steps": 30, "seed": 4294967295}
        f = demo.fields
        assert f["beta"].value == "0.5" and f["steps"].value == "30" and f["seed"].value == "4294967295"
    finally:
        demo.close()
    with pytest.raises(ValueError, match="beta"):
        make_servo_demo(client, "pinhole", beta=-1.0, autorun=False)


def test_forged_drop_downs_and_slider_are_refused(client, notes):
    demo = make_servo_demo(client, "pinhole", steps=20, autorun=False, autoplay=False, field_delay=0)
    try:
        assert demo.run(wait=True, timeout=PATIENCE) and demo.result is not None
        _fire(demo.fields["estimator"], client, "magic")
        assert notes[-1] == ("Value refused", "F estimator: expected one of true, linear, normalized, sampson, got 'magic'")
        assert demo.fields["estimator"].value == "true" and demo.params()["f_algorithm"] is None
        _fire(demo.fields["speed"], client, "1000x")
        assert "speed" in notes[-1][1] and demo.fields["speed"].value == "1x"
        _fire(demo.clock.slider, client, "abc")
        assert notes[-1] == ("Value refused", "time: expected a number of seconds, got 'abc'")
        demo.step(3)  # still working
        assert demo.frame == 3
    finally:
        demo.close()


def test_a_failing_run_is_shown_not_raised(client, notes, monkeypatch):
    from egtviz.controllers import servo_demos

    def refuse(**kw):
        raise ValueError("beta: the simulation refused it")

    monkeypatch.setattr(servo_demos, "simulate_pinhole", refuse)
    demo = make_servo_demo(client, "pinhole", steps=20, autorun=False, autoplay=False, field_delay=0)
    try:
        assert demo.run(wait=True, timeout=PATIENCE)
        assert demo.result is None
        assert "beta" in demo.error and "Bad parameters" in demo.form.status.content
        assert 'data-level="error"' in demo.form.status.content
        assert 'data-kind="message"' in demo.svg and "beta" in demo.svg
        assert notes[-1][0] == "Servo run failed"
        # A good run afterwards clears the error.
        monkeypatch.undo()
        demo.set_params(beta=1.0, steps=10)
        assert demo.run(wait=True, timeout=PATIENCE) and demo.error == "" and demo.result.n_samples == 11
    finally:
        demo.close()


def test_rerun_while_running_is_refused_and_close_stops(client):
    demo = make_servo_demo(client, "panoramic", steps=400, autorun=False, autoplay=True)
    try:
        assert demo.run()
        assert not demo.run()  # one run at a time
        assert demo.wait(PATIENCE)
        wait_for(lambda: demo.playing, "the finished run to start playing")
    finally:
        demo.close()
    assert not demo.playing
    wait_for(lambda: demo._play_thread is None or not demo._play_thread.is_alive(),
             "the playback thread to end once the demo closed")


def test_app_opens_demo_and_goes_back():
    from egtviz.viewer.server.headless import start_headless

    server, app, fakes, views = start_headless()
    try:
        client = views[0].client
        views[0].controls.servo_buttons["panoramic"].value = None  # click "Visual servoing > Panoramic ..."
        demo = app.demos[client.client_id]
        assert demo.kind == "panoramic" and not app.views
        assert views[0].closed
        demo.wait(PATIENCE)
        # The demo's docked panels narrow the 3D canvas the tab reports.
        fakes[0].send("ViewerCameraMessage", wxyz=[1.0, 0.0, 0.0, 0.0], position=[0.0, -10.0, 3.0], fov=1.0,
                      near=0.01, far=1000.0, image_height=768, image_width=558, look_at=[0.0, 0.0, 0.0],
                      up_direction=[0.0, 0.0, 1.0])
        wait_for(lambda: client.camera.image_width == 558, "the tab's narrowed canvas to reach the server")
        demo.btn_back.value = None  # click "Back to the epipolar workbench"
        view = app.views.get(client.client_id)
        assert demo.closed and view is not None and app.views[client.client_id] is view
        assert not app.demos
        # The workbench comes back laid out for the window it had, not for the demo's narrowed canvas.
        assert view.window == views[0].window and view.grid == views[0].grid
    finally:
        for f in fakes:
            f.close()
        server.stop()


def test_app_demo_mode_and_cli():
    from egtviz.viewer.server.launch import start

    server, app = start("127.0.0.1", 0, demo="pinhole")
    try:
        tab = FakeTab(server.get_port())
        demo = app.wait_for_demo(timeout=PATIENCE)[0]
        assert demo.kind == "pinhole"
        tab.close()
        wait_for(lambda: not app.demos, "the disconnected tab's demo to close")
        assert demo.closed  # disconnect closes the demo
    finally:
        server.stop()


def test_servo_svg_pure():
    n = 3
    cur = np.array([[10.0, 10.0], [50.0, 60.0], [np.nan, np.nan]])
    img = ServoImage(demo="pinhole", width=640, height=480, frame=2, current=cur, desired=cur + 5,
                     trails=np.stack([cur, cur + 1, cur + 2]), lines=np.full((n, 2, 2), np.nan),
                     epipoles=[("e", np.array([100.0, 100.0]))], caption="t = 0.10 s", message="hi <b>")
    svg = servo_image_svg(img, revision=7)
    k = _kinds(svg)
    assert k["point"] == 2 and k["desired"] == 2 and k["trail"] == 2 and k["epipole"] == 1
    assert "epipolar-line" not in k and 'data-rev="7"' in svg and "hi &lt;b&gt;" in svg


def test_one_class_per_demo_and_the_factory(client):
    assert SERVO_DEMOS == {"pinhole": PinholeServoDemo, "panoramic": PanoramicServoDemo}
    with pytest.raises(ValueError, match="kind: expected one of 'pinhole', 'panoramic', got 'stereo'"):
        make_servo_demo(client, "stereo")
    for bad in ({"beta": 1.0}, {"estimator": "linear"}):  # pin-hole parameters: the panoramic demo has none
        with pytest.raises(ValueError, match=f"{next(iter(bad))}: not a parameter of the panoramic demo"):
            make_servo_demo(client, "panoramic", autorun=False, **bad)
    demo = make_servo_demo(client, "panoramic", steps=20, autorun=False, autoplay=False, show_panel=False)
    try:
        assert type(demo) is PanoramicServoDemo and isinstance(demo, ServoDemo)
        assert set(demo.fields) == {"seed", "noise_px", "steps", "speed"}
        assert demo.params() == {"seed": 0, "noise_px": 0.0, "steps": 20}
        # No panel: plays all the same.
        assert demo.run(wait=True, timeout=PATIENCE) and demo.error == "" and demo.display.panel is None
        demo.step(5)
        assert demo.frame == 5 and 'data-frame="5"' in demo.svg
    finally:
        demo.close()
    demo = PinholeServoDemo(client, beta=0.25, estimator="sampson", autorun=False, autoplay=False)
    try:
        assert set(demo.fields) == {"seed", "beta", "estimator", "noise_px", "steps", "speed"}
        assert demo.params() == {"seed": 0, "noise_px": 0.0, "steps": 1000, "beta": 0.25, "f_algorithm": 3}
    finally:
        demo.close()


def test_the_viewer_modules_branch_on_no_kind_and_register_callbacks_safely():
    import inspect

    from egtviz.viewer.servo import (
        servo_demo,
        servo_panoramic_demo,
        servo_pinhole_demo,
        servo_player,
    )

    for module in (servo_demo, servo_player, servo_pinhole_demo, servo_panoramic_demo):
        src = inspect.getsource(module)
        assert re.findall(r"kind\s*[!=]=", src) == [], module.__name__
        assert re.findall(r"\.on_(?:update|click|upload)\(", src) == [], module.__name__


def _line_ends(svg: str) -> dict[int, np.ndarray]:
    out = {}
    for m in re.finditer(r'data-kind="epipolar-line" data-index="(\d+)" x1="([-\d.e]+)" y1="([-\d.e]+)" '
                         r'x2="([-\d.e]+)" y2="([-\d.e]+)"', svg):
        out[int(m.group(1))] = np.array([float(v) for v in m.groups()[1:]]).reshape(2, 2)
    return out


def test_the_viewer_draws_the_frames_geometry(client):
    """The image plane and the 3D nodes show the run's ServoFrames (the viewer computes no geometry)."""
    demo = make_servo_demo(client, "pinhole", steps=30, autoplay=False)
    try:
        assert demo.wait(PATIENCE) and demo.error == ""
        demo.seek(17)
        g, frames = demo.frames.at(17), demo.frames
        drawn = _line_ends(demo.svg)
        assert sorted(drawn) == [i for i in range(len(g.lines)) if np.all(np.isfinite(g.lines[i]))]
        for i, seg in drawn.items():
            assert np.abs(seg - g.lines[i]).max() < 0.01
        assert np.allclose(demo.nodes.body.position, frames.body_poses[17][:3, 3])
        joints = frames.links[17, :, :3, 3]  # the arm: link meshes, or the stick figure without rtb-data's meshes
        shown = [h.position for h in demo.arm.links] if demo.arm.links else demo.arm.joints.points
        assert np.allclose(np.asarray(shown, float), joints, atol=1e-6)
        segs, _ = frames.ray_segments(17, demo.model.points)
        assert np.allclose(demo.nodes.rays.points, segs, atol=1e-6)
    finally:
        demo.close()


@pytest.mark.parametrize("kind", ["pinhole", "panoramic"])
def test_the_two_axes_of_the_controls_plot_share_their_zero(client, kind):
    demo = make_servo_demo(client, kind, steps=40, autoplay=False)
    try:
        assert demo.wait(PATIENCE) and demo.error == ""
        scales = demo.display.plot_controls.scales
        (lv, hv), (lw, hw) = scales["v"]["range"], scales["w"]["range"]
        assert lv <= 0 <= hv and lw <= 0 <= hw and hv > lv and hw > lw
        assert -lv / (hv - lv) == pytest.approx(-lw / (hw - lw), abs=1e-12)  # zero at the same height
        u = demo.result.controls[demo.CONTROL_KEY]
        for j, (_, _, axis) in enumerate(demo.CONTROL_SERIES):  # every sample inside its axis
            lo, hi = scales[axis]["range"]
            assert lo <= u[:, j].min() and u[:, j].max() <= hi
    finally:
        demo.close()
