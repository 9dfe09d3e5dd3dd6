"""``egtviz serve --workers N``: one port served by N processes, a dead worker restarted, a class shared.

Raw websocket tabs (:mod:`egtviz.bench.ws_client`'s protocol) are opened until one lands on each worker; which
worker holds a connection is read from ``/proc`` (the server side of the connection is a socket of that process).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import signal
import time
from collections.abc import Callable
from pathlib import Path

import msgspec.msgpack
import pytest
import viser
import websockets.asyncio.client
from websockets.typing import Subprotocol

from egtviz.bench.ws_client import CAMERA, decode_frame
from egtviz.scene import default_scene
from egtviz.viewer.server.workers import Supervisor, WorkerOptions, reserve_port, worker_of_connection

from _threads import joined
from _waiting import PATIENCE, wait_for

pytestmark = pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux's /proc")

_PANEL = re.compile(r'data-egtviz="image-plane" data-camera="([^"]*)"')
CAMERAS = len(default_scene().cameras)
"""Panels of the scene the class starts on."""


class Tab:
    """A raw tab that answers the local-storage question with ``name`` and keeps every panel SVG it is sent."""

    def __init__(self, ws, name: str | None) -> None:
        self.ws, self.name = ws, name
        self.panels: dict[str, str] = {}
        self.types: set[str] = set()
        self.gizmo: dict | None = None
        self.pose: dict = {}

    async def send(self, message: dict) -> None:
        await self.ws.send(msgspec.msgpack.encode(message))

    def _take(self, message: dict) -> list[dict]:
        replies = []
        self.types.add(message["type"])
        if message["type"] == "LocalStorageGetItemRequestMessage":
            replies.append({"type": "LocalStorageGetItemResponseMessage", "value": self.name, "error": None,
                            "request_uuid": message["request_uuid"]})
        if message.get("name") == "/egt/cam_0":
            if message["type"] == "TransformControlsMessage":
                self.gizmo = message
            elif message["type"] == "SetPositionMessage":
                self.pose["position"] = message["position"]
            elif message["type"] == "SetOrientationMessage":
                self.pose["wxyz"] = message["wxyz"]
        stack = [message]
        while stack:
            item = stack.pop()
            if isinstance(item, dict):
                stack.extend(item.values())
            elif isinstance(item, (list, tuple)):
                stack.extend(item)
            elif isinstance(item, str) and 'data-egtviz="image-plane"' in item:
                self.panels[_PANEL.search(item).group(1)] = item
        return replies

    async def read(self, seconds: float) -> None:
        """Read (answering as a browser's tab does) for ``seconds``: a pause between a drag's moves, or one slice of
        :func:`read_until`."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            try:
                frame = await asyncio.wait_for(self.ws.recv(decode=False), min(left, 0.2))
            except TimeoutError:
                continue
            for message in decode_frame(frame):
                for reply in self._take(message):
                    await self.send(reply)

    async def read_until(self, done: Callable[[], object], what: str) -> None:
        """Read until ``done()``; fail naming ``what`` if it is not within :data:`PATIENCE`."""
        await read_until([self], done, what)


async def read_until(tabs: list[Tab], done: Callable[[], object], what: str) -> None:
    """Read every one of ``tabs`` at once until ``done()``.

    Raises:
        AssertionError: not done within :data:`PATIENCE`, naming ``what`` was awaited.
    """
    deadline = time.monotonic() + PATIENCE
    while not done():
        if time.monotonic() > deadline:
            raise AssertionError(f"waited {PATIENCE:.0f} s for {what}")
        await asyncio.gather(*(tab.read(0.2) for tab in tabs))


@contextlib.asynccontextmanager
async def open_tab(port: int, path: str = "", name: str | None = None):
    async with websockets.asyncio.client.connect(
            f"ws://127.0.0.1:{port}{path}", subprotocols=[Subprotocol(f"viser-v{viser.__version__}")],
            max_size=None, open_timeout=PATIENCE) as ws:
        tab = Tab(ws, name)
        await tab.send({**CAMERA, "image_width": 1366, "image_height": 768})
        yield tab


async def tabs_on_each_worker(stack: contextlib.AsyncExitStack, sup: Supervisor, name: str | None = None,
                              tries: int = 24) -> dict[int, Tab]:
    """Open tabs until one is on each worker (the extra ones are closed again)."""
    pids = [p for p in sup.pids() if p is not None]
    found: dict[int, Tab] = {}
    for i in range(tries):
        inner = contextlib.AsyncExitStack()
        tab = await inner.enter_async_context(open_tab(sup.port, name=None if name is None else f"{name} {i}"))
        pid = worker_of_connection(sup.port, tab.ws.local_address[1], pids)
        if pid is not None and pid not in found:
            found[pid] = tab
            stack.push_async_callback(inner.aclose)
            if len(found) == len(pids):
                return found
        else:
            await inner.aclose()
    raise AssertionError(f"{tries} tabs never reached every worker: {sorted(found)} of {pids}")


def test_a_reserved_port_is_busy_for_others_and_a_listened_port_is_passed_over() -> None:
    import socket

    port, held = reserve_port("127.0.0.1", 0)
    try:
        with socket.socket() as other, pytest.raises(OSError):  # as an asyncio server binds
            other.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            other.bind(("127.0.0.1", port))
        again, others = reserve_port("127.0.0.1", port)
        for s in others:
            s.close()
        assert again != port
    finally:
        for s in held:
            s.close()
    with socket.socket() as listening:
        listening.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listening.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)  # a stranger's reuseport server
        listening.bind(("127.0.0.1", 0))
        listening.listen()
        busy = listening.getsockname()[1]
        chosen, socks = reserve_port("127.0.0.1", busy)
        for s in socks:
            s.close()
        assert chosen != busy  # the workers never join someone else's listening port


@pytest.fixture(scope="module")
def sup():
    """Two workers teaching a class (one start for the tests below: a worker takes seconds to start)."""
    sup = Supervisor(2, 0, WorkerOptions(classroom=True))
    sup.start(timeout=PATIENCE)
    yield sup
    sup.stop()


def test_a_follower_on_each_worker_sees_the_instructors_scene(sup: Supervisor) -> None:

    async def scenario() -> None:
        async with contextlib.AsyncExitStack() as stack:
            teacher = await stack.enter_async_context(
                open_tab(sup.port, path=f"/egtviz-instructor/{sup.token}"))
            await teacher.read_until(lambda: teacher.gizmo is not None and {"position", "wxyz"} <= set(teacher.pose)
                                     and len(teacher.panels) == CAMERAS,
                                     "the instructor's workbench: its gizmo, pose and panels")
            students = await tabs_on_each_worker(stack, sup, name="student")
            await read_until([teacher, *students.values()],
                             lambda: all(len(tab.panels) == CAMERAS for tab in students.values()),
                             "each worker's follower to show the room's panels")
            assert teacher.gizmo is not None
            x, y, z = [float(v) for v in teacher.pose["position"]]
            base = {"name": "/egt/cam_0", "owner": teacher.gizmo["owner"]}
            before = dict(teacher.panels)
            await teacher.send({"type": "TransformControlsDragStartMessage", **base})
            for k in range(5):
                await teacher.send({"type": "TransformControlsUpdateMessage", **base, "wxyz": teacher.pose["wxyz"],
                                    "position": [x + 0.05 * (k + 1), y + 0.02, z]})
                await teacher.read(0.1)
            await teacher.send({"type": "TransformControlsDragEndMessage", **base})
            # The instructor's tab and the followers are read together until they agree on panels the drag redrew
            # (a loaded machine may take a while): each follower shows what the instructor's tab shows.
            await read_until([teacher, *students.values()],
                             lambda: teacher.panels != before
                             and all(tab.panels == teacher.panels for tab in students.values()),
                             "each worker's follower to show the instructor's panels after the drag")

    asyncio.run(asyncio.wait_for(scenario(), 3 * PATIENCE))


def test_a_killed_worker_is_restarted_and_a_tab_reconnects_to_a_live_worker(sup: Supervisor) -> None:

    async def scenario() -> None:
        async with contextlib.AsyncExitStack() as stack:
            tabs = await tabs_on_each_worker(stack, sup, name="restart")
            await read_until(list(tabs.values()), lambda: all(tab.panels for tab in tabs.values()),
                             "each worker to show the room's frame")
            victim = sorted(tabs)[0]
            os.kill(victim, signal.SIGKILL)
            with pytest.raises(websockets.exceptions.ConnectionClosed):
                for _ in range(100):
                    await tabs[victim].ws.recv()
            # The tab reconnects, retrying as viser's client does (a connection made while the dead worker's
            # listening socket was still being closed is refused): a live worker takes it.
            deadline = time.monotonic() + PATIENCE
            while True:
                try:
                    async with open_tab(sup.port, name="restart again") as again:
                        await again.read_until(lambda: again.panels, "the reconnected tab to be served")
                    break
                except (OSError, websockets.exceptions.InvalidMessage, websockets.exceptions.ConnectionClosed) as exc:
                    assert time.monotonic() < deadline, f"waited {PATIENCE:.0f} s for a live worker to take a " \
                                                        f"reconnecting tab (last: {exc!r})"
                    await asyncio.sleep(0.25)
            # (In a thread: the tabs' connections keep answering the server's pings meanwhile.)
            assert await asyncio.to_thread(sup.wait_ready, PATIENCE), \
                f"waited {PATIENCE:.0f} s for the killed worker to be restarted"
            pids = sup.pids()
            assert victim not in pids and None not in pids and len(set(pids)) == 2
            assert sum(s.restarts for s in sup.slots) == 1
            # The restarted worker is in the class: its followers show the room's frame, as the other's do.
            fresh = await tabs_on_each_worker(stack, sup, name="after restart")
            first, second = fresh.values()
            await read_until([first, second], lambda: len(first.panels) == CAMERAS and first.panels == second.panels,
                             "the followers on the restarted worker and on the other to show the same room's frame")

    asyncio.run(asyncio.wait_for(scenario(), 3 * PATIENCE))


def test_options_a_worker_would_refuse_are_refused_before_any_worker_starts(capsys) -> None:
    from egtviz.viewer.server.workers import serve_workers

    assert serve_workers(2, 0, WorkerOptions(scene="/nonexistent/scene.json")) == 2
    assert serve_workers(2, 0, WorkerOptions(lesson="no-such-lesson")) == 2
    assert serve_workers(2, 0, WorkerOptions(allow_hosts=("http://bad:1",))) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 3
    assert err[0].startswith("egtviz: cannot read the scene file: ") and "/nonexistent/scene.json" in err[0]
    assert err[1].startswith("egtviz: cannot open the lesson: ")
    assert err[2].startswith("egtviz: cannot use ")


def test_a_worker_that_cannot_start_stops_the_start_with_its_status() -> None:
    sup = Supervisor(2, 0, WorkerOptions(), worker_module="egtviz.no_such_worker_module")
    with pytest.raises(RuntimeError, match=r"worker 0 did not start \(it ended with status 1\)"):
        sup.start(timeout=PATIENCE)
    assert all(s.proc is not None and s.proc.poll() is not None for s in sup.slots)  # none left running


def test_the_installed_viser_starts_its_server_the_way_the_workers_share_a_port() -> None:
    import inspect

    import viser.infra._infra as infra

    # enable_reuse_port relies on this call (it passes reuse_port through serve's keywords to asyncio).
    assert "websockets.asyncio.server.serve(" in inspect.getsource(infra.WebsockServer._background_worker)


def test_serve_workers_says_where_it_serves_and_stops_its_workers(capsys) -> None:
    import socket
    import threading

    from egtviz.viewer.server.workers import serve_workers

    stop = threading.Event()
    status: list[int] = []
    out = err = ""
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        runner = threading.Thread(target=lambda: status.append(
            serve_workers(1, port, WorkerOptions(classroom=True), stop_event=stop)))
        runner.start()

        def printed_the_instructors_url() -> bool:
            nonlocal out, err
            more = capsys.readouterr()
            out, err = out + more.out, err + more.err
            assert runner.is_alive() or "instructor (keep this secret)" in out, (out, err, status)
            return "instructor (keep this secret)" in out

        wait_for(printed_the_instructors_url, "serve_workers to print the instructor's URL")
        stop.set()
        joined(runner, "serve_workers to stop its workers")
    assert status == [0]
    assert f"egtviz: port {port} is busy on 127.0.0.1; using " in err
    served = re.search(r"egtviz running at http://127\.0\.0\.1:(\d+) \(1 worker\)", out)
    assert served and int(served.group(1)) != port
    assert out.count("/egtviz-instructor/") == 1  # the token is printed once, on loopback
