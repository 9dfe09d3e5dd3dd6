"""PNG downloads of a panel: rendered in a worker process, latest click wins per tab, tabs take turns, refused
above the limits with the reason, and a failed render is a notification in the tab that asked."""

from __future__ import annotations

import dataclasses
import io
import os
import signal
import threading
import types

import numpy as np
import pytest
from PIL import Image

from egtviz.scene import default_scene, limits
from egtviz.viewer.render.figure_export import panel_svg, png_pixels, png_refusal, svg_to_png
from egtviz.viewer.server.headless import start_headless
from egtviz.viewer.render.png_worker import PngDownloads, PngJob, PngRenderer, PngRenderError, WorkerProcess
from egtviz.viewer.render.svg import NORMAL

from _waiting import PATIENCE, wait_for  # noqa: E402

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_width(png: bytes) -> int:
    assert png[:8] == PNG_SIGNATURE
    return int.from_bytes(png[16:20], "big")


class HeldWorker:
    """A worker whose renders wait until the test lets them go; it records what it rendered."""

    def __init__(self, timeout: float = 0.0) -> None:
        self.gate = threading.Event()
        self.rendered: list[str] = []
        self.pid = None

    def render(self, svg: str, scale: float) -> bytes:
        assert self.gate.wait(timeout=PATIENCE), "the test never let the held render go"
        self.rendered.append(svg)
        return svg.encode()

    def close(self) -> None:
        pass


class Note:
    def __init__(self, log: list, title: str, body: str, kw: dict) -> None:
        self.log, self.title, self.body, self.kw, self.removed = log, title, body, kw, False

    def remove(self) -> None:
        self.removed = True


class RecordingClient:
    """What a tab's PngDownloads uses of a viser client: notifications and file downloads, recorded."""

    def __init__(self) -> None:
        self.notes: list[Note] = []
        self.files: list[tuple[str, bytes]] = []

    def add_notification(self, title: str, body: str, **kw) -> Note:
        note = Note(self.notes, title, body, kw)
        self.notes.append(note)
        return note

    def send_file_download(self, name: str, data: bytes, **kw) -> None:
        self.files.append((name, data))


def held_renderer(workers: int = 1) -> tuple[PngRenderer, list[HeldWorker]]:
    made: list[HeldWorker] = []

    def factory(timeout: float) -> HeldWorker:
        made.append(HeldWorker(timeout))
        return made[-1]

    return PngRenderer(workers, worker_factory=factory), made


def tiny_svg(label: str, width: int = 10) -> str:
    return f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="10"><desc>{label}</desc></svg>'


def heavy_svg() -> str:
    """4,000 long lines on a 1000 x 400 figure: seconds of rendering at scale 2, inside the limits."""
    lines = "".join(f'<line x1="0" y1="{k % 400}" x2="1000" y2="{(7 * k) % 400}" stroke="#000"/>' for k in range(4000))
    return f'<svg xmlns="http://www.w3.org/2000/svg" width="1000" height="400">{lines}</svg>'


# -- the queue: latest wins per tab, tabs take turns -------------------------------------------------------


def test_twenty_rapid_requests_from_one_tab_render_twice_the_first_and_the_last():
    renderer, workers = held_renderer()
    client = RecordingClient()
    tab = PngDownloads(client, renderer)
    try:
        assert tab.request("click0.png", tiny_svg("click 0"))
        wait_for(lambda: renderer.renders == 1, "the first click's render to run (held by the test)")
        for k in range(1, 20):
            assert tab.request(f"click{k}.png", tiny_svg(f"click {k}"))
        workers[0].gate.set()
        wait_for(renderer.idle_now, "the renderer to finish every job")
        assert renderer.renders == 2
        assert [name for name, _ in client.files] == ["click0.png", "click19.png"]
        assert b"click 19" in client.files[1][1]
        # One progress notification, updated to the latest click, gone once nothing is left to render.
        progress = [n for n in client.notes if n.title == "Rendering PNG..."]
        assert len(progress) == 1 and progress[0].kw["loading"] is True
        assert progress[0].body.startswith("click19.png") and progress[0].removed
    finally:
        workers[0].gate.set()
        renderer.close()


def test_a_flooding_tab_does_not_delay_another_tab_by_more_than_one_render():
    renderer, workers = held_renderer()
    flood, other = RecordingClient(), RecordingClient()
    a, b = PngDownloads(flood, renderer), PngDownloads(other, renderer)
    try:
        a.request("a0.png", tiny_svg("a0"))
        wait_for(lambda: renderer.renders == 1, "a's first render to run (held by the test)")
        for k in range(1, 20):
            a.request(f"a{k}.png", tiny_svg(f"a{k}"))
        b.request("b.png", tiny_svg("b"))
        workers[0].gate.set()
        wait_for(renderer.idle_now, "the renderer to finish every job")
        # a's first render, then b (which waited during it), then a's latest click.
        assert list(renderer.started) == [id(a), id(b), id(a)]
        assert [n for n, _ in flood.files] == ["a0.png", "a19.png"] and [n for n, _ in other.files] == ["b.png"]
    finally:
        workers[0].gate.set()
        renderer.close()


def test_a_tab_never_has_two_renders_at_once_even_with_two_workers():
    renderer, workers = held_renderer(workers=2)
    client, other_client = RecordingClient(), RecordingClient()
    tab, other = PngDownloads(client, renderer), PngDownloads(other_client, renderer)
    try:
        tab.request("first.png", tiny_svg("first"))
        wait_for(lambda: renderer.renders == 1, "the tab's first render to run (held by the test)")
        tab.request("second.png", tiny_svg("second"))
        # A free second worker must not take the tab's waiting job: it takes the job of another tab, asked later.
        other.request("other.png", tiny_svg("other"))
        wait_for(lambda: renderer.renders == 2, "the free worker to take a job")
        assert list(renderer.started) == [id(tab), id(other)] and renderer.busy(tab)
        for w in workers:
            w.gate.set()
        wait_for(renderer.idle_now, "the renderer to finish every job")
        assert [n for n, _ in client.files] == ["first.png", "second.png"]
        assert [n for n, _ in other_client.files] == ["other.png"]
    finally:
        for w in workers:
            w.gate.set()
        renderer.close()


def test_a_closed_tab_gets_nothing_and_its_waiting_job_is_dropped():
    renderer, workers = held_renderer()
    client = RecordingClient()
    tab = PngDownloads(client, renderer)
    try:
        tab.request("running.png", tiny_svg("running"))
        wait_for(lambda: renderer.renders == 1, "the tab's first render to run (held by the test)")
        tab.request("waiting.png", tiny_svg("waiting"))
        tab.close()
        workers[0].gate.set()
        wait_for(renderer.idle_now, "the renderer to finish every job")
        assert renderer.renders == 1 and client.files == []
        assert tab.request("after.png", tiny_svg("after")) is False
    finally:
        workers[0].gate.set()
        renderer.close()


def click(group, view, value: str) -> None:
    """What viser does for a click on a button group: store the value, call the callbacks."""
    group._impl.value = value
    for cb in group._impl.update_cb:
        cb(types.SimpleNamespace(target=group, client=view.client, client_id=None))


def test_twenty_png_clicks_in_the_viewer_send_two_files_and_svg_stays_immediate():
    server, _app, fakes, (view,) = start_headless(default_scene())
    renderer, workers = held_renderer()
    try:
        sent = []
        view.client.send_file_download = lambda name, data, **kw: sent.append(name)
        view.png = PngDownloads(view.client, renderer)
        group = view.panel_buttons["cam1"]["download panel"]
        click(group, view, "PNG")
        wait_for(lambda: renderer.renders == 1, "the first click's render to run (held by the test)")
        for _ in range(19):
            click(group, view, "PNG")
        click(view.panel_buttons["cam2"]["download panel"], view, "PNG")  # the latest click: cam2's panel
        click(group, view, "SVG")  # not queued: sent at once
        assert sent == ["cam1-image-plane.svg"]
        workers[0].gate.set()
        wait_for(renderer.idle_now, "the renderer to finish every job")
        assert renderer.renders == 2
        assert sent == ["cam1-image-plane.svg", "cam1-image-plane.png", "cam2-image-plane.png"]
        assert b'data-camera="cam2"' in workers[0].rendered[1].encode()
    finally:
        workers[0].gate.set()
        renderer.close()
        for f in fakes:
            f.close()
        server.stop()


# -- the limits ---------------------------------------------------------------------------------------------


def tall_camera_svg() -> str:
    """The panel of a 1 x 8192-pixel image: the figure is 480 CSS pixels wide and millions tall."""
    scene = default_scene()
    cam = dataclasses.replace(scene.camera("cam1"), width=1, height=8192)
    return panel_svg(scene.replace(cameras=(cam, *scene.cameras[1:])), "cam1", fit=False)


def test_refusal_names_the_pixel_limit_of_a_tall_panel():
    svg = tall_camera_svg()
    w, h = png_pixels(svg)
    assert w == 2 * int(NORMAL.panel_px) and h > 1_000_000
    why = png_refusal(svg)
    assert why is not None
    assert f"{w:,} x {h:,} pixels" in why and f"at most {limits.MAX_PNG_PIXELS:,} pixels" in why
    assert "Download the SVG instead" in why


def test_refusal_names_the_element_and_byte_limits():
    svg = panel_svg(default_scene(), "cam1")
    assert png_refusal(svg) is None
    n = limits.MAX_PNG_SVG_ELEMENTS + 1
    many = svg.replace("</svg>", "<g/>" * n + "</svg>")
    why = png_refusal(many)
    assert why is not None and f"at most {limits.MAX_PNG_SVG_ELEMENTS:,}" in why and "draw fewer points" in why
    big = svg.replace("</svg>", "<!--" + "x" * limits.MAX_PNG_SVG_BYTES + "--></svg>")
    why = png_refusal(big)
    assert why is not None and f"at most {limits.MAX_PNG_SVG_BYTES / 1e6:g} MB" in why
    assert png_refusal('<svg xmlns="http://www.w3.org/2000/svg" width="100%"/>') == \
        "the figure has no width and height in pixels, so no PNG is made. Download the SVG instead."


def test_a_tab_asking_for_a_too_large_png_is_told_the_limit_and_nothing_renders():
    renderer, workers = held_renderer()
    client = RecordingClient()
    tab = PngDownloads(client, renderer)
    try:
        assert tab.request("cam1-image-plane.png", tall_camera_svg()) is False
        (note,) = client.notes
        assert note.title == "PNG not made: the figure is too large" and note.kw["color"] == "red"
        assert note.body.startswith("cam1-image-plane.png: the PNG would be 960 x ")
        assert f"at most {limits.MAX_PNG_PIXELS:,} pixels" in note.body
        assert renderer.renders == 0 and client.files == []
    finally:
        renderer.close()


def test_the_viewer_refuses_the_png_of_a_tall_image_in_that_tab():
    server, _app, fakes, (view,) = start_headless(default_scene())
    try:
        notes, sent = [], []
        view.client.add_notification = lambda title, body, **kw: notes.append((title, body))
        view.client.send_file_download = lambda name, data, **kw: sent.append(name)
        view.model.update_camera("cam1", width=1, height=8192)
        click(view.panel_buttons["cam1"]["download panel"], view, "PNG")
        wait_for(lambda: notes, "the tab to be told the PNG is too large")
        title, body = notes[0]
        assert title == "PNG not made: the figure is too large"
        assert body.startswith("cam1-image-plane.png: the PNG would be 960 x ")
        assert f"at most {limits.MAX_PNG_PIXELS:,} pixels" in body and sent == []
    finally:
        for f in fakes:
            f.close()
        server.stop()


# -- the worker process -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def worker():
    w = WorkerProcess(timeout=PATIENCE)  # the first render starts the process, on a busy machine slowly
    yield w
    w.close()


def test_the_worker_renders_what_svg_to_png_renders_in_process(worker):
    svg = panel_svg(default_scene(), "cam1")
    there, here = worker.render(svg, 2.0), svg_to_png(svg, scale=2.0)
    a = np.asarray(Image.open(io.BytesIO(there)).convert("RGB"))
    b = np.asarray(Image.open(io.BytesIO(here)).convert("RGB"))
    assert a.shape == b.shape and a.shape[1] == 2 * int(NORMAL.panel_px)
    assert np.array_equal(a, b)
    assert worker.pid is not None and worker.pid != os.getpid()


def test_an_svg_the_renderer_cannot_read_is_reported_and_the_worker_carries_on(worker):
    with pytest.raises(PngRenderError, match="could not draw the figure"):
        worker.render("<svg this is not xml", 1.0)
    pid = worker.pid
    assert png_width(worker.render(tiny_svg("ok", width=20), 1.0)) == 20 and worker.pid == pid


def test_a_render_over_the_timeout_is_stopped():
    slow = WorkerProcess(timeout=PATIENCE)
    try:
        slow.render(tiny_svg("warm"), 1.0)  # started and imported: what follows is the render alone
        slow.timeout = 0.3
        with pytest.raises(PngRenderError, match="longer than 0.3 s"):
            slow.render(heavy_svg(), 2.0)
        assert slow.pid is None
        slow.timeout = PATIENCE
        assert png_width(slow.render(tiny_svg("again", width=30), 1.0)) == 30  # a new worker
    finally:
        slow.close()


def test_a_worker_that_dies_becomes_a_notification_and_the_next_png_works():
    renderer = PngRenderer(1, timeout=PATIENCE)
    client = RecordingClient()
    tab = PngDownloads(client, renderer)
    try:
        tab.request("warm.png", tiny_svg("warm", width=12))
        wait_for(lambda: len(client.files) == 1, "the first PNG (the worker process started)")
        (pid,) = renderer.worker_pids()
        assert png_refusal(heavy_svg()) is None
        tab.request("heavy.png", heavy_svg())
        wait_for(lambda: renderer.renders == 2, "the heavy render to start")
        os.kill(pid, signal.SIGKILL)
        wait_for(lambda: any(n.title == "Could not make the PNG" for n in client.notes),
                 "the tab to be told the renderer stopped")
        failed = next(n for n in client.notes if n.title == "Could not make the PNG")
        assert failed.body == ("heavy.png: the PNG renderer stopped unexpectedly; try again. "
                               "The SVG download still works.")
        assert all(n.removed for n in client.notes if n.title == "Rendering PNG...")
        tab.request("next.png", tiny_svg("next", width=14))
        wait_for(lambda: len(client.files) == 2, "the next PNG, from a new worker")
        assert client.files[1][0] == "next.png" and png_width(client.files[1][1]) == 2 * 14  # scale 2
        assert renderer.worker_pids() != [pid]
    finally:
        renderer.close()
    assert renderer.worker_pids() == []


def test_a_job_is_a_frozen_value():
    job = PngJob("<svg/>", 2.0, lambda png, err: None)
    with pytest.raises(AttributeError):
        job.scale = 3.0  # type: ignore[misc]
