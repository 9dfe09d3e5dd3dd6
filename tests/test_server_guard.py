"""The server guards (egtviz.viewer.server.guard) against raw websocket clients on a real server.

Each test starts a viser server on a free loopback port with the guards installed, speaks viser's
wire protocol itself (msgpack messages up, zstd-framed msgpack down, as ``viser/infra/_infra.py``
does; the client is :mod:`egtviz.bench.ws_client`) and stops the server. The app served is a small one made here (a slider, a gizmo and an
upload button per tab, callbacks that cost a few milliseconds) so the figures measure the guards,
not the workbench's drawing code.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import statistics
import threading
import time
from pathlib import Path

import msgspec.msgpack
import numpy as np
import pytest
import viser
import websockets.asyncio.client
import websockets.asyncio.server
import websockets.exceptions
from websockets.typing import Origin, Subprotocol

from egtviz.bench import ws_client
from egtviz.bench.ws_client import CAMERA
from egtviz.viewer.server import guard
from egtviz.viewer.server.guard import FairExecutor, GuardLimits, install_guards, origin_allowed

from _subprocesses import Printed
from _waiting import PATIENCE, wait_for

CALLBACK_SECONDS = 0.003
BLOCKED_S = 2 * PATIENCE
"""How long a job held at a gate waits at most: longer than any wait of the test that holds it."""


def _busy(seconds: float) -> None:
    """CPU work holding the GIL, like a redraw (a sleep would let everything else run)."""
    end = time.perf_counter() + seconds
    a = np.ones((64, 64))
    while time.perf_counter() < end:
        a = a @ a * 1e-3


class TabApp:
    """Per tab: a slider, a gizmo and an upload button whose callbacks record when they ran."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.lock = threading.Lock()
        self.slider_runs: dict[int, list[tuple[float, float]]] = {}
        self.gizmo_runs: dict[int, int] = {}
        self.callbacks: list[tuple[int, float]] = []  # (tab, when) of every slider and gizmo callback, in order
        self.uploads: list[bytes] = []
        self.ready: set[int] = set()
        server.on_client_connect(self._connect)

    def _connect(self, client: viser.ClientHandle) -> None:
        cid = client.client_id
        slider = client.gui.add_slider("x", min=0.0, max=1000.0, step=1.0, initial_value=0.0)
        upload = client.gui.add_upload_button("scene file")
        gizmo = client.scene.add_transform_controls("/gizmo")

        @slider.on_update
        def _(event: viser.GuiEvent) -> None:
            _busy(CALLBACK_SECONDS)
            with self.lock:
                now = time.perf_counter()
                self.slider_runs.setdefault(cid, []).append((now, event.target.value))
                self.callbacks.append((cid, now))

        @gizmo.on_update
        def _(event: viser.TransformControlsEvent) -> None:
            _busy(CALLBACK_SECONDS)
            with self.lock:
                self.gizmo_runs[cid] = self.gizmo_runs.get(cid, 0) + 1
                self.callbacks.append((cid, time.perf_counter()))

        @upload.on_upload
        def _(event: viser.GuiEvent) -> None:
            with self.lock:
                self.uploads.append(event.target.value.content)

        with self.lock:
            self.ready.add(cid)


@contextlib.contextmanager
def guarded_server(limits: GuardLimits | None = None):
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        guards = install_guards(server, limits)
        app = TabApp(server)
        yield server, app, guards
    finally:
        server.stop()


class RawClient(ws_client.RawClient):
    """The shared raw client, joining this module's small app, as patient as the tests."""

    @classmethod
    @contextlib.asynccontextmanager
    async def connect(cls, port: int, *, origin: str | None = None):
        async with websockets.asyncio.client.connect(
            f"ws://127.0.0.1:{port}", subprotocols=[Subprotocol(f"viser-v{viser.__version__}")],
            origin=None if origin is None else Origin(origin), max_size=None, open_timeout=PATIENCE,
        ) as ws:
            yield cls(ws)

    async def join(self, app: TabApp) -> int:
        """Send the first camera (viser then runs the connect callbacks) and wait for the tab's widgets."""
        await self.wait_for(("GuiSliderMessage", "TransformControlsMessage", "GuiUploadButtonMessage"),
                            timeout=PATIENCE)
        return int(self.find("TransformControlsMessage")["owner"])


def _run(coro) -> None:
    """Run a scenario (its own waits are bounded and say what they waited for; this bound is the last resort)."""
    asyncio.run(asyncio.wait_for(coro, 3 * PATIENCE))


async def _until(check, what: str) -> None:
    """Poll ``check`` from the event loop until it is true (an upload arrived, a flood reached the server)."""
    deadline = time.monotonic() + PATIENCE
    while not check():
        assert time.monotonic() < deadline, f"waited {PATIENCE:.0f} s for {what}"
        await asyncio.sleep(0.01)


def _rss_bytes() -> int:
    return int(Path("/proc/self/statm").read_text().split()[1]) * 4096


# -- the private names the guards rely on ----------------------------------------------------------------------


def test_viser_internals_are_the_ones_the_guards_patch():
    # Fails loudly on a viser or websockets upgrade that renames what guard.py hooks into.
    assert viser.__version__ in guard.TESTED_VISER_VERSIONS
    import viser.infra._infra as infra

    assert "serve_future" in inspect.getsource(infra.WebsockServer._background_worker)
    assert "await websocket.recv()" in inspect.getsource(infra._message_consumer)
    assert list(inspect.signature(websockets.asyncio.server.ServerConnection.recv).parameters) == ["self", "decode"]
    with guarded_server() as (server, _app, guards):
        guard.check_viser_internals(server)
        assert isinstance(server._thread_executor, FairExecutor)
        assert server.scene._thread_executor is server._thread_executor
        assert server.gui._thread_executor is server._thread_executor
        ws_server = guard._websockets_server(server)
        assert ws_server.handler.__name__ == "guarded_handler"
        assert ws_server.process_request.__name__ == "process_request"
        assert guards.limits.max_upload_bytes == guard._default_upload_bytes()


def test_check_viser_internals_names_what_is_missing(monkeypatch):
    async def recv(self, timeout):  # a websockets release that changed recv
        return b""

    monkeypatch.setattr(websockets.asyncio.server.ServerConnection, "recv", recv)
    with pytest.raises(RuntimeError, match=r"ServerConnection\.recv signature changed: \['self', 'timeout'\]"):
        guard.check_viser_internals()
    monkeypatch.undo()
    guard.check_viser_internals()


def test_guard_limits_name_the_bad_argument():
    with pytest.raises(ValueError, match="max_upload_bytes: expected a positive integer"):
        GuardLimits(max_upload_bytes=0)
    with pytest.raises(ValueError, match="max_pending_events"):
        GuardLimits(max_pending_events=True)
    with pytest.raises(ValueError, match="allowed_hosts"):
        GuardLimits(allowed_hosts=["x"])  # type: ignore[arg-type]


# -- Origin ---------------------------------------------------------------------------------------------------

OWN = frozenset({"laptop", "laptop.local"})


@pytest.mark.parametrize(("origin", "host", "allowed"), [
    (None, "127.0.0.1:8080", True),  # not a browser
    ("http://127.0.0.1:8080", "127.0.0.1:8080", True),
    ("http://localhost:8080", "127.0.0.1:8080", True),  # loopback aliases are one host
    ("http://[::1]:8080", "localhost:8080", True),
    ("http://192.168.1.20:8080", "192.168.1.20:8080", True),  # a student on the LAN
    ("http://LAPTOP.local:8080", "laptop.local:8080", True),  # the machine's own name
    ("https://192.168.1.20", "192.168.1.20:443", True),  # default ports
    ("http://evil.example", "127.0.0.1:8080", False),
    ("http://evil.example:8080", "evil.example:8080", False),  # DNS rebinding: names agree, not ours
    ("http://127.0.0.1:9999", "127.0.0.1:8080", False),  # another local app
    ("http://192.168.1.21:8080", "192.168.1.20:8080", False),
    ("null", "127.0.0.1:8080", False),  # sandboxed frames, file:// pages
    ("file://", "127.0.0.1:8080", False),
    ("http://127.0.0.1:8080", None, False),
    ("http://127.0.0.1:99999", "127.0.0.1:8080", False),  # unparsable port
])
def test_origin_allowed(origin, host, allowed):
    assert origin_allowed(origin, host, own_names=OWN) is allowed


def test_origin_allowed_hosts_adds_a_proxy_name():
    assert not origin_allowed("https://egt.school.example", "egt.school.example", own_names=OWN)
    assert origin_allowed("https://egt.school.example", "egt.school.example", own_names=OWN,
                          allowed_hosts=("egt.school.example",))


def test_cross_origin_websocket_is_refused_and_same_origin_served():
    with guarded_server() as (server, app, guards):
        port = server.get_port()

        async def scenario() -> None:
            with pytest.raises(websockets.exceptions.InvalidStatus, match="403"):
                async with RawClient.connect(port, origin="http://evil.example"):
                    pass
            async with RawClient.connect(port, origin=f"http://localhost:{port}") as same:
                await same.join(app)
            async with RawClient.connect(port) as no_origin:  # a program, not a browser
                await no_origin.join(app)

        _run(scenario())
        assert guards.stats.refused_origins == 1
        assert len(app.ready) == 2  # the refused one never became a tab


# -- uploads --------------------------------------------------------------------------------------------------


def _upload_start(button: str, tid: str, size: int, parts: int) -> dict:
    return {"type": "FileTransferStartUpload", "source_component_uuid": button, "transfer_uuid": tid,
            "filename": "scene.json", "mime_type": "application/json", "part_count": parts, "size_bytes": size}


def _upload_part(button: str, tid: str, index: int, content: bytes) -> dict:
    return {"type": "FileTransferPart", "source_component_uuid": button, "transfer_uuid": tid,
            "part_index": index, "content": content}


def test_a_legitimate_upload_arrives_whole():
    with guarded_server() as (server, app, guards):
        async def scenario() -> None:
            async with RawClient.connect(server.get_port()) as c:
                await c.join(app)
                button = c.find("GuiUploadButtonMessage")["uuid"]
                data = bytes(range(256)) * 3000  # 768 000 B: two parts of 512 KiB as the browser sends them
                await c.send(_upload_start(button, "t1", len(data), 2))
                await c.send(_upload_part(button, "t1", 0, data[:524288]))
                await c.send(_upload_part(button, "t1", 1, data[524288:]))
                await _until(lambda: app.uploads, "the upload to arrive")
                assert app.uploads == [data]

        _run(scenario())
        assert guards.stats.refused_uploads == 0 and guards.stats.dropped_parts == 0


def test_forged_uploads_are_refused_without_pinning_memory():
    with guarded_server() as (server, app, guards):
        cap = guards.limits.max_upload_bytes

        async def scenario() -> None:
            async with RawClient.connect(server.get_port()) as c:
                await c.join(app)
                button = c.find("GuiUploadButtonMessage")["uuid"]
                rss0 = _rss_bytes()
                # A billion parts of a terabyte, then 200 MB of parts for it.
                await c.send(_upload_start(button, "huge", 10**12, 10**9))
                # Within the size cap but with far more parts than its size allows.
                await c.send(_upload_start(button, "confetti", cap, 10**6))
                chunk = b"\0" * (512 * 1024)
                for i in range(400):
                    await c.send(_upload_part(button, "huge", i, chunk))
                    await c.send(_upload_part(button, "confetti", i, chunk[:1]))
                # Two honest-looking transfers fill the in-flight slots; a third is refused.
                await c.send(_upload_start(button, "a", 100_000, 1))
                await c.send(_upload_start(button, "b", 100_000, 1))
                await c.send(_upload_start(button, "c", 100_000, 1))
                # Parts beyond a transfer's declared size are dropped, whatever source they name.
                await c.send(_upload_part(button, "a", 0, b"x" * 200_000))
                await c.send({**_upload_part(button, "b", 0, b"x" * 200_000), "source_component_uuid": None})

                def notes() -> list[dict]:
                    return [m for m in c.messages if m["type"] == "NotificationShowMessage"]

                def handled() -> bool:  # every message above handled, the refusals told to the tab
                    bodies = [n["props"]["body"] for n in notes()]
                    return (guards.stats.refused_uploads == 3 and guards.stats.dropped_parts == 802
                            and any("larger than" in b for b in bodies) and any("uploads at once" in b for b in bodies))

                deadline = time.monotonic() + PATIENCE
                while not handled():
                    assert time.monotonic() < deadline, (f"waited {PATIENCE:.0f} s for the forged uploads to be "
                                                         f"refused and the tab told: {guards.stats}, {notes()}")
                    await c.read_until_quiet(0.1, limit=1.0)
                grown = _rss_bytes() - rss0
                assert grown < 20 * 2**20, f"memory grew by {grown / 2**20:.1f} MB"
                # The refusals reached the tab as notifications (awaited above).

        _run(scenario())
        assert guards.stats.refused_uploads == 3  # huge, confetti, c
        assert guards.stats.dropped_parts == 802  # 400 + 400 + the two oversized parts
        assert app.uploads == []


def test_a_message_over_the_size_limit_closes_only_that_connection():
    with guarded_server(GuardLimits(max_message_bytes=64 * 1024)) as (server, app, _guards):
        async def scenario() -> None:
            async with RawClient.connect(server.get_port()) as other:
                await other.join(app)
                async with RawClient.connect(server.get_port()) as c:
                    await c.join(app)
                    button = c.find("GuiUploadButtonMessage")["uuid"]
                    await c.send(_upload_part(button, "t", 0, b"\0" * 200_000))
                    with pytest.raises(websockets.exceptions.ConnectionClosed) as closed:
                        for _ in range(100):
                            await c.ws.recv()
                    assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009  # message too big
                await _slider_latency(other, app, n=3)  # the other tab is still served

        _run(scenario())


# -- floods and disconnects --------------------------------------------------------------------------------------


async def _slider_probes(c: RawClient, app: TabApp, *, n: int, spacing: float = 0.05) -> list[tuple[float, float]]:
    """``n`` times: when a slider value was sent and when its callback had run (``time.perf_counter``)."""
    uuid = c.find("GuiSliderMessage")["uuid"]
    cid = int(c.find("TransformControlsMessage")["owner"])
    out = []
    for k in range(n):
        value = float(1 + k % 500)
        t0 = time.perf_counter()
        await c.send({"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": value}})
        while True:
            with app.lock:
                runs = list(app.slider_runs.get(cid, ()))
            done = next((t for t, v in runs if v == value and t >= t0), None)
            if done is not None:
                out.append((t0, done))
                break
            assert time.perf_counter() - t0 < PATIENCE, f"waited {PATIENCE:.0f} s for the tab's slider callback"
            await asyncio.sleep(0.0005)
        await asyncio.sleep(spacing)
    return out


async def _slider_latency(c: RawClient, app: TabApp, *, n: int, spacing: float = 0.05) -> list[float]:
    """Seconds from sending a slider value to its callback having run, ``n`` times."""
    return [done - t0 for t0, done in await _slider_probes(c, app, n=n, spacing=spacing)]


async def _flood(c: RawClient, count: int) -> None:
    owner = c.find("TransformControlsMessage")["owner"]
    slider = c.find("GuiSliderMessage")["uuid"]
    for i in range(count):
        await c.send({"type": "TransformControlsUpdateMessage", "name": "/gizmo", "wxyz": [1.0, 0.0, 0.0, 0.0],
                      "position": [i * 1e-3, 0.0, 0.0], "owner": owner})
        await c.send({"type": "GuiUpdateMessage", "uuid": slider, "updates": {"value": float(i % 1000)}})
        if i % 50 == 0:
            await asyncio.sleep(0)  # let the latency probe run between the flood's writes


def flooder_main(port: int, count: int) -> None:
    """Run in a separate process (as a hostile client would be): join, wait for "go" on stdin, flood."""
    import sys

    async def main() -> None:
        async with RawClient.connect(port) as c:
            await c.send(CAMERA)
            deadline = time.monotonic() + PATIENCE
            while not (c.find("GuiSliderMessage") and c.find("TransformControlsMessage")):
                assert time.monotonic() < deadline, f"waited {PATIENCE:.0f} s for the flooder's tab to join"
                await c.read_until_quiet(0.2)
            print("joined", c.find("TransformControlsMessage")["owner"], flush=True)
            await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)
            t0 = time.perf_counter()
            await _flood(c, count)
            print(f"sent {2 * count} in {time.perf_counter() - t0:.2f} s", flush=True)
            await c.read_until_quiet(1.0, limit=PATIENCE)

    asyncio.run(asyncio.wait_for(main(), 3 * PATIENCE))


@contextlib.contextmanager
def flooder(port: int, count: int):
    """A flooding tab in its own process; yields (its client id, a function that starts the flood)."""
    import subprocess
    import sys

    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); "
            f"import test_server_guard as t; t.flooder_main({port}, {count})")
    proc = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    printed = Printed(proc)
    try:
        line = printed.wait_line("joined", "the flooding tab to join")

        def go() -> None:
            proc.stdin.write("go\n")
            proc.stdin.flush()

        yield int(line.split()[1]), go
        proc.stdin.close()
        printed.finish("the flooding tab's process to end")
    finally:
        printed.kill()


MAX_AHEAD = 10
"""The most of the flooder's callbacks that may run while one of the victim's values waits for its own."""


def measure_flood(app: TabApp, port: int, count: int = 5000) -> dict[str, list[float]]:
    """The victim tab's slider latency idle and while another process floods; the flooder's callback counts: in
    all, and while each of the victim's values waited for its callback (``ahead``)."""
    result: dict[str, list[float]] = {}
    with flooder(port, count) as (flood_id, go):
        def flood_callbacks() -> list[float]:
            with app.lock:
                return [t for cid, t in app.callbacks if cid == flood_id]

        async def scenario() -> None:
            async with RawClient.connect(port) as victim:
                await victim.join(app)
                result["idle"] = await _slider_latency(victim, app, n=10)
                go()
                await _until(flood_callbacks, "the flood to reach the server")
                probes = await _slider_probes(victim, app, n=30)
                result["flooded"] = [done - t0 for t0, done in probes]
                ran = flood_callbacks()
                result["ahead"] = [float(sum(t0 < t < done for t in ran)) for t0, done in probes]

        _run(scenario())
    with app.lock:
        result["flood_runs"] = [len(app.slider_runs.get(flood_id, ())) + app.gizmo_runs.get(flood_id, 0)]
    return result


def test_a_flooding_tab_does_not_delay_another():
    with guarded_server() as (server, app, guards):
        result = measure_flood(app, server.get_port())
    flooded = sorted(result["flooded"])
    p95 = flooded[int(0.95 * (len(flooded) - 1))]
    idle = statistics.median(result["idle"])
    print(f"\nvictim slider latency: idle median {1e3 * idle:.1f} ms; "
          f"under a 10 000-message flood median {1e3 * statistics.median(flooded):.1f} ms, "
          f"p95 {1e3 * p95:.1f} ms, max {1e3 * flooded[-1]:.1f} ms; the flooder's callbacks ran "
          f"{result['flood_runs'][0]} times for 10 000 messages, at most {max(result['ahead']):.0f} of them while "
          f"one of the victim's values waited")
    # Against this run's own figures, not a number of milliseconds a shared machine may overrun: the victim's
    # values are answered about as fast as before the flood, and while one waits, the flooder's callbacks do not
    # run ahead of it (a queue that serves the flood first runs tens of them; taking turns, a few: those already
    # running, and the flood's messages read before the victim's).
    assert statistics.median(flooded) < 10 * idle, (result["flooded"], result["idle"])
    assert max(result["ahead"]) <= MAX_AHEAD, result["ahead"]
    # Latest wins: the flooder's 5 000 + 5 000 events were merged into far fewer callbacks.
    assert result["flood_runs"][0] < 5000
    assert guards.stats.coalesced_events + guards.stats.coalesced_messages > 5000


def test_disconnect_mid_drag_leaves_the_server_serving():
    with guarded_server() as (server, app, _guards):
        async def scenario() -> None:
            port = server.get_port()
            async with RawClient.connect(port) as other:
                await other.join(app)
                async with RawClient.connect(port) as dragger:
                    owner = (await dragger.join(app), dragger.find("TransformControlsMessage")["owner"])[1]
                    await dragger.send({"type": "TransformControlsDragStartMessage", "name": "/gizmo", "owner": owner})
                    for i in range(200):
                        await dragger.send({"type": "TransformControlsUpdateMessage", "name": "/gizmo",
                                            "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [i * 0.01, 0.0, 0.0],
                                            "owner": owner})
                    dragger.ws.transport.abort()  # the tab vanishes: no drag end, no close frame
                assert len(await _slider_latency(other, app, n=5)) == 5
                async with RawClient.connect(port) as newcomer:
                    await newcomer.join(app)
                    assert len(await _slider_latency(newcomer, app, n=2)) == 2

        _run(scenario())


# -- the executor alone --------------------------------------------------------------------------------------------


class _Event:
    def __init__(self, client_id: int) -> None:
        self.client_id = client_id


def test_fair_executor_runs_one_job_per_tab_and_round_robin():
    from concurrent.futures import ThreadPoolExecutor

    stats = guard.GuardStats()
    pool = ThreadPoolExecutor(max_workers=4)
    fair = FairExecutor(pool, max_pending=3, stats=stats)
    gate = threading.Event()
    order: list[tuple[int, int]] = []
    running = {0: 0, 1: 0}
    peak = {0: 0, 1: 0}
    lock = threading.Lock()

    def job(event: _Event, k: int) -> None:
        with lock:
            running[event.client_id] += 1
            peak[event.client_id] = max(peak[event.client_id], running[event.client_id])
        gate.wait(BLOCKED_S)
        with lock:
            running[event.client_id] -= 1
            order.append((event.client_id, k))

    def wait_running(tab: int) -> None:
        def started() -> bool:
            with lock:
                return bool(running[tab])

        wait_for(started, f"tab {tab}'s first job to run")

    try:
        futures = [fair.submit(job, _Event(0), 0)]
        wait_running(0)  # so that exactly 1, 2, 3 wait and 4, 5 are dropped
        futures += [fair.submit(job, _Event(0), k) for k in range(1, 6)]
        futures += [fair.submit(job, _Event(1), k) for k in range(2)]
        wait_running(1)
        assert fair.pending() == 4  # 1, 2, 3 of tab 0 and 1 of tab 1 (tab 1's first job is running)
    finally:
        gate.set()
    for f in futures:
        f.result(timeout=PATIENCE)
    pool.shutdown()
    assert peak == {0: 1, 1: 1}  # one job per tab at a time
    assert stats.dropped_events == 2
    for tab in (0, 1):  # within a tab in order of arrival (tabs interleave in any order)
        ks = [k for c, k in order if c == tab]
        assert ks == sorted(ks)
    assert sorted(order) == [(0, 0), (0, 1), (0, 2), (0, 3), (1, 0), (1, 1)]
    assert fair.pending() == 0


def test_fair_executor_latest_event_replaces_the_waiting_one():
    from concurrent.futures import ThreadPoolExecutor

    class _Target:
        pass

    stats = guard.GuardStats()
    pool = ThreadPoolExecutor(max_workers=2)
    fair = FairExecutor(pool, max_pending=100, stats=stats)
    gate = threading.Event()
    seen: list[float] = []
    slider = _Target()

    def blocker(event: _Event) -> None:
        gate.wait(BLOCKED_S)

    def on_value(event: viser.GuiEvent) -> None:
        seen.append(event.client)  # the test's marker of which event this is

    try:
        first = fair.submit(blocker, _Event(7))
        for k in range(50):
            fair.submit(on_value, viser.GuiEvent(client=k, client_id=7, target=slider))  # type: ignore[arg-type]
    finally:
        gate.set()
    first.result(timeout=PATIENCE)
    wait_for(lambda: not fair.pending(), "the tab's waiting job to run")
    pool.shutdown()
    assert seen == [49]  # 50 updates of one handle while the tab was busy: one callback, the newest
    assert stats.coalesced_events == 49


# -- the inbound filter alone ------------------------------------------------------------------------------------


class _FakeConnection:
    """What the filter uses of a websockets connection: ``recv`` and the buffered frame count."""

    def __init__(self, messages: list[dict]) -> None:
        self.raw = [msgspec.msgpack.encode(m) for m in messages]
        self.recv_messages = type("Assembler", (), {})()
        self.recv_messages.frames = self.raw  # len() = messages still buffered

    async def recv(self, decode=None) -> bytes:
        return self.raw.pop(0)


def _filtered(messages: list[dict]) -> list[dict]:
    stats = guard.GuardStats()
    conn = _FakeConnection(messages)
    flt = guard._InboundFilter(conn, GuardLimits(), stats, lambda _c, _t: None)

    async def read_all() -> list[dict]:
        out = [await flt.recv()]
        while flt._ready:
            out.append(await flt.recv())
        return out

    return [msgspec.msgpack.decode(r) for r in asyncio.run(read_all())]


def _pose(x: float, name: str = "/g") -> dict:
    return {"type": "TransformControlsUpdateMessage", "name": name, "wxyz": [1.0, 0, 0, 0], "position": [x, 0, 0],
            "owner": "0"}


def test_inbound_filter_keeps_the_last_pose_between_drag_boundaries():
    start = {"type": "TransformControlsDragStartMessage", "name": "/g", "owner": "0"}
    end = {"type": "TransformControlsDragEndMessage", "name": "/g", "owner": "0"}
    slider = {"type": "GuiUpdateMessage", "uuid": "u", "updates": {"value": 1.0}}
    got = _filtered([start, _pose(1), _pose(2), _pose(9, "/h"), slider, _pose(3), end, _pose(4), _pose(5)])
    # Poses of "/g" 1 and 2 are superseded by 3 (same drag); 4 by 5; other names and GUI messages stay.
    assert [(m["type"][:20], m.get("position", [None])[0]) for m in got] == [
        ("TransformControlsDra", None), ("TransformControlsUpd", 9.0), ("GuiUpdateMessage", None),
        ("TransformControlsUpd", 3.0), ("TransformControlsDra", None), ("TransformControlsUpd", 5.0)]


def test_inbound_filter_passes_malformed_messages_to_viser_untouched():
    # viser's decoder reports these; the filter must neither crash nor drop them silently.
    odd = [{"type": ["not", "a", "string"]}, {"no type": 1},
           {"type": "FileTransferPart", "source_component_uuid": "b", "transfer_uuid": ["x"], "part_index": 0,
            "content": b""}]
    got = _filtered(odd)
    assert got[:2] == odd[:2] and len(got) == 2  # the part of an unknown (unhashable) transfer is dropped


def test_inbound_filter_keeps_the_last_field_value_and_every_press():
    def gui(uuid: str, value) -> dict:
        return {"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": value}}

    got = _filtered([gui("f", 1.0), gui("press", True), gui("f", 2.0), gui("press", True), gui("g", "a"),
                     gui("f", 3.0), gui("box", False), gui("box", True)])
    assert [(m["uuid"], m["updates"]["value"]) for m in got] == [
        ("press", True), ("press", True), ("g", "a"), ("f", 3.0), ("box", False), ("box", True)]
