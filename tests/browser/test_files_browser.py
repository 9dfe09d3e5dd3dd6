"""Real-browser tests of the scene file buttons: Save downloads the tab's scene, Load uploads one.

Headless Debian Chromium (playwright) against an in-process egtviz server. No
path on the server is named anywhere: the file goes through the browser.
"""

from __future__ import annotations

import dataclasses

import pytest

from _waiting import wait_for
from egtviz.scene import default_scene, scene_from_bytes, scene_to_bytes
from egtviz.viewer.server.browser import open_viewer

pytestmark = pytest.mark.browser



@pytest.fixture(scope="module")
def served(browser):
    import viser

    from egtviz.viewer.tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, default_scene())
    yield app, browser, f"http://127.0.0.1:{server.get_port()}"
    server.stop()


def _open_scene_folder(page) -> None:
    page.get_by_text("Scene", exact=True).first.click()
    page.get_by_text("Save (download)").first.wait_for()


def _the_view(app, before: set[int]):
    new: list[int] = []
    wait_for(lambda: new.extend(set(app.views) - before) or new, "the page's tab to connect")
    return app.views[new[0]]


def test_save_downloads_the_scene_file(served, tmp_path):
    app, browser, url = served
    before = set(app.views)
    page = open_viewer(browser, url)
    try:
        view = _the_view(app, before)
        view.model.update_camera("cam1", focal_length=0.0135)  # something to tell the file from the default
        _open_scene_folder(page)
        with page.expect_download() as info:
            page.get_by_text("Save (download)").first.click()
        download = info.value
        assert download.suggested_filename.endswith(".json") and "/" not in download.suggested_filename
        path = tmp_path / "saved.json"
        download.save_as(path)
        scene = scene_from_bytes(path.read_bytes(), "saved.json")
        assert scene == view.model.scene
        assert scene.camera("cam1").focal_length == pytest.approx(0.0135)
    finally:
        page.close()


def test_load_uploads_a_scene_file_and_the_scene_changes(served, tmp_path):
    app, browser, url = served
    before = set(app.views)
    page = open_viewer(browser, url)
    try:
        view = _the_view(app, before)
        base = default_scene()
        wanted = base.replace(title="Uploaded", cameras=tuple(
            dataclasses.replace(c, position=(4.0, -6.0, 2.0)) if c.name == "cam2" else c for c in base.cameras))
        path = tmp_path / "mine.json"
        path.write_bytes(scene_to_bytes(wanted))
        _open_scene_folder(page)
        page.locator('input[type="file"]').first.set_input_files(str(path))
        wait_for(lambda: view.model.scene.title == "Uploaded", "the uploaded scene in the tab's model")
        assert view.model.scene == wanted
        # the page shows the new scene: its title and cam2's position field
        page.get_by_text("Uploaded").first.wait_for()
        assert view.cameras["cam2"].fields["position"].value == "4, -6, 2"
    finally:
        page.close()


def test_a_bad_upload_shows_the_reason_in_the_page(served, tmp_path):
    app, browser, url = served
    before = set(app.views)
    page = open_viewer(browser, url)
    try:
        view = _the_view(app, before)
        scene = view.model.scene
        path = tmp_path / "broken.json"
        path.write_text('{"cameras": [{"kind": "pinhole", "name": "c", "focal_length": "0.008"}]}')
        _open_scene_folder(page)
        page.locator('input[type="file"]').first.set_input_files(str(path))
        page.get_by_text("Could not load the scene").first.wait_for()
        assert page.get_by_text("broken.json").count() >= 1
        assert view.model.scene is scene
    finally:
        page.close()
