"""Issue 15's messages, by routes the first fixes did not cover: what a user typed is shown with its control
characters written out (a host name cannot move the terminal's cursor or change its colours)."""

from __future__ import annotations

import pytest

from egtviz.cli import main
from egtviz.viewer.server.launch import ServeAddressError, check_bind

from _waiting import PATIENCE

ESCAPES = "\x1b[31mX\x07"
SHOWN = "'\\x1b[31mX\\x07': expected a host name or an IP address"


@pytest.mark.parametrize("argv", [
    ["serve", "--port", "0"],
    ["serve", "--port", "0", "--workers", "2"],
    ["lesson", "03-intrinsics", "--port", "0"],
], ids=["serve", "workers", "lesson"])
def test_a_host_with_escape_sequences_is_refused_with_them_written_out(capsys, argv):
    assert main([*argv, "--host", ESCAPES]) in (1, 2)
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\x07" not in err
    assert f"argument --host: {SHOWN}" in err


def test_check_bind_refuses_a_host_with_control_characters_before_resolving_it():
    with pytest.raises(ServeAddressError) as info:
        check_bind(ESCAPES, 0)
    assert str(info.value) == f"cannot use --host {SHOWN}"


@pytest.mark.parametrize(("argv", "shown"), [
    (["serve", "--port", "0", "--allow-host", ESCAPES], "'\\x1b[31mX\\x07' is not a host name"),
    (["scene", "save", ESCAPES, "/nonexistent-egtviz/o.json"], "no built-in scene '\\x1b[31mX\\x07'"),
], ids=["allow-host", "scene-save"])
def test_a_name_is_written_out_once_not_escaped_twice(capsys, argv, shown):
    assert main(argv) in (1, 2)
    err = capsys.readouterr().err
    assert "\x1b" not in err and shown in err and "\\\\x1b" not in err


# -- a set_range refusal in the unit of the field the learner types in ------------------------------------------


@pytest.fixture
def zoom_step_tab(tmp_path):
    """Lesson 3's step 2 in one tab (cam1 at 30 mm, its focal length limited to 2..50 mm); ``(panel, told)``."""
    import viser

    from egtviz.lessons import ProgressStore
    from egtviz.viewer.course.lesson_view import LessonPanel
    from egtviz.viewer.server.headless import FakeTab
    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tab = None
    try:
        app = EgtvizApp(server, field_delay=0.0, course=True, progress=ProgressStore(tmp_path / "p.sqlite3"),
                        lesson="03-intrinsics")
        tab = FakeTab(server.get_port())
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        panel.go_to(1)
        told: list[tuple[str, str]] = []
        panel.view.client.add_notification = lambda title, body, **_: told.append((title, body))
        yield panel, told
    finally:
        if tab is not None:
            tab.close()
        server.stop()


@pytest.mark.parametrize(("typed", "shown"), [("60", "60 mm"), ("1", "1 mm")])
def test_a_typed_focal_length_outside_the_steps_range_is_refused_in_mm(zoom_step_tab, typed, shown):
    panel, told = zoom_step_tab
    before = panel.view.model.scene.camera("cam1").focal_length
    panel.view.cameras["cam1"].fields["focal"].value = typed
    assert panel.view.model.scene.camera("cam1").focal_length == before
    assert told == [("Value refused", f"In this step cam1's focal length must stay between 2 mm and 50 mm (it is "
                                      f"{shown})")]


def test_a_pixel_size_range_is_said_in_micrometres_with_its_bounds_in_order(zoom_step_tab):
    from egtviz.lessons.changes import SetRange
    from egtviz.scene import SceneError

    panel, told = zoom_step_tab
    panel.run.apply(SetRange("cam1", "pixels_per_metre", 50_000.0, 200_000.0))  # pixels of 5 to 20 µm
    before = panel.view.model.scene.camera("cam1").pixels_per_metre
    panel.view.cameras["cam1"].fields["pixel"].value = "1, 1"
    expected = "In this step cam1's pixel size must stay between 5 µm and 20 µm (it is 1 µm, 1 µm)"
    assert told == [("Value refused", expected)]
    with pytest.raises(SceneError) as info:  # a raw edit (a script, a client message) hears the same words
        panel.view.model.update_camera("cam1", pixels_per_metre=(1e6, 1e6))
    assert str(info.value) == expected
    assert panel.view.model.scene.camera("cam1").pixels_per_metre == before
    panel.view.cameras["cam1"].fields["pixel"].value = "8, 8"  # inside the range: taken
    assert panel.view.model.scene.camera("cam1").pixels_per_metre == pytest.approx((125_000.0, 125_000.0))
