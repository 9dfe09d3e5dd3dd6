"""Server-side guards viser has no option for: the websocket's Origin, upload caps, event floods.

:func:`install_guards` is called on a freshly made :class:`viser.ViserServer` (``egtviz serve`` does it
in :func:`egtviz.viewer.server.launch.start`). It adds three things, all described in ``docs/server.md``:

* **Origin.** A websocket handshake whose ``Origin`` header is not the page's own origin is answered
  with HTTP 403: a page on another site (or a DNS-rebinding name) cannot drive the app. A handshake
  without ``Origin`` is accepted: browsers always send it, so only non-browser programs omit it, and
  those could forge any value anyway. Names a proxy reaches the app under (a JupyterHub's) are
  allowed by :func:`allowed_hosts` (``egtviz serve --allow-host NAME``, ``EGTVIZ_ALLOWED_HOSTS``).
* **Uploads.** viser's file-transfer messages are checked before viser buffers them: a transfer
  declaring more than ``max_upload_bytes``, an implausible number of parts, more transfers in flight
  than ``max_uploads_in_flight`` per tab, parts beyond the declared size and any message over
  ``max_message_bytes`` are refused, so a forged upload cannot pin memory.
* **Floods.** Callbacks run on viser's thread pool through a per-tab queue: one job per tab at a
  time, tabs served round-robin, and a new event for a handle that already has one waiting replaces
  it (latest wins). A tab sending thousands of gizmo or field updates then delays the other tabs by
  at most one callback, and itself only does the work of the last value.

viser exposes none of these hooks, so this module (and only this one) uses viser's and websockets'
private names; :func:`check_viser_internals` says which, and fails loudly when an upgrade changes them.
"""

from __future__ import annotations

import asyncio
import collections
import dataclasses
import http
import inspect
import ipaddress
import logging
import math
import socket
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Awaitable, Callable, ParamSpec, TypeGuard, TypeVar
from urllib.parse import urlsplit

import msgspec.msgpack
import viser
import websockets.asyncio.server
from websockets.asyncio.server import ServerConnection
from websockets.http11 import Request, Response
from websockets.typing import Data

from ...hosts import ALLOWED_HOSTS_ENV, allowed_host, allowed_hosts

__all__ = [
    "ALLOWED_HOSTS_ENV",
    "GuardLimits",
    "GuardStats",
    "Guards",
    "allowed_host",
    "allowed_hosts",
    "Handshake",
    "check_viser_internals",
    "handshake_of",
    "install_guards",
    "origin_allowed",
    "serve_page_under",
]

_log = logging.getLogger(__name__)
_P = ParamSpec("_P")
_T = TypeVar("_T")

#: The viser releases whose internals this module was written and tested against (``pyproject.toml`` pins them).
TESTED_VISER_VERSIONS = ("1.1.1",)
#: viser's browser client sends uploads in parts of this size; a forged transfer may use smaller parts
#: only down to :data:`MIN_UPLOAD_PART_BYTES`, which bounds the part count of an allowed size.
MIN_UPLOAD_PART_BYTES = 16 * 1024
#: Used when ``egtviz.scene.limits`` does not state the scene file limit.
FALLBACK_UPLOAD_BYTES = 2 * 1024 * 1024
#: At most this many buffered messages of one tab are looked at (and thinned) together.
_DRAIN_BATCH = 64


def _default_upload_bytes() -> int:
    """The scene file size limit, shared with the CLI's reads when ``egtviz.scene.limits`` states it."""
    try:
        from ...scene import limits
    except ImportError:
        return FALLBACK_UPLOAD_BYTES
    value = getattr(limits, "MAX_SCENE_FILE_BYTES", None)
    return int(value) if isinstance(value, int) and value > 0 else FALLBACK_UPLOAD_BYTES


@dataclasses.dataclass(frozen=True)
class GuardLimits:
    """What one browser tab may send.

    Attributes:
        max_upload_bytes: largest declared size of an upload (default: the scene file limit).
        max_uploads_in_flight: uploads one tab may have started and not finished.
        max_message_bytes: largest websocket message the server reads from a tab; viser's own
            upload parts are 512 KiB, every other message a few hundred bytes.
        max_pending_events: callbacks one tab may have waiting; more are dropped (a button pressed
            this many times faster than the app can answer).
        allowed_hosts: host names, besides loopback, IP literals and this machine's names, under
            which the page may be reached (a reverse proxy's name, say).
    """

    max_upload_bytes: int = dataclasses.field(default_factory=_default_upload_bytes)
    max_uploads_in_flight: int = 2
    max_message_bytes: int = 1024 * 1024
    max_pending_events: int = 256
    allowed_hosts: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name in ("max_upload_bytes", "max_uploads_in_flight", "max_message_bytes", "max_pending_events"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name}: expected a positive integer, got {value!r}")
        if not isinstance(self.allowed_hosts, tuple) or not all(isinstance(h, str) for h in self.allowed_hosts):
            raise ValueError(f"allowed_hosts: expected a tuple of host names, got {self.allowed_hosts!r}")
        for host in self.allowed_hosts:
            allowed_host(host, what="allowed_hosts")  # a wildcard or an origin-like "https://x" would open the app


@dataclasses.dataclass
class GuardStats:
    """Counters of what the guards refused or merged since the server started (thread-safe enough
    for reporting: each is only ever incremented)."""

    refused_origins: int = 0
    refused_uploads: int = 0
    dropped_parts: int = 0
    coalesced_messages: int = 0
    coalesced_events: int = 0
    dropped_events: int = 0


@dataclasses.dataclass(frozen=True)
class Guards:
    """What :func:`install_guards` returns: the limits in force and the live counters."""

    limits: GuardLimits
    stats: GuardStats


# -- private names of viser / websockets used below ------------------------------------------------


def check_viser_internals(server: viser.ViserServer | None = None) -> None:
    """Fail loudly if the installed viser/websockets lack the private names the guards rely on.

    Checked: ``ViserServer._websock_server`` (its ``_background_event_loop``, ``_live_connections``),
    the ``start_server`` coroutine of ``WebsockServer._background_worker`` holding the websockets
    server in its local ``serve_future``, ``websockets.asyncio.server.Server.handler`` /
    ``.process_request``, ``ServerConnection.recv`` / ``.recv_messages.frames`` /
    ``.protocol.max_message_size``, and the ``_thread_executor`` of the server, its ``scene`` and ``gui``.

    Raises:
        RuntimeError: naming what is missing and the viser version installed.
    """
    problems: list[str] = []
    if viser.__version__ not in TESTED_VISER_VERSIONS:
        # The names below are what matters; an untested release that has them is used, with a warning.
        _log.warning("viser %s is not one of the versions the server guards were tested with %s",
                     viser.__version__, TESTED_VISER_VERSIONS)
    import viser.infra._infra as infra

    worker_src = inspect.getsource(infra.WebsockServer._background_worker)
    for needle in ("async def start_server", "as serve_future", "process_request=", "_message_consumer(connection"):
        if needle not in worker_src:
            problems.append(f"WebsockServer._background_worker no longer contains {needle!r}")
    consumer_src = inspect.getsource(infra._message_consumer)
    if "await websocket.recv()" not in consumer_src:
        problems.append("_message_consumer no longer reads with websocket.recv()")
    recv_params = list(inspect.signature(websockets.asyncio.server.ServerConnection.recv).parameters)
    if recv_params[:2] != ["self", "decode"]:
        problems.append(f"ServerConnection.recv signature changed: {recv_params}")
    server_init = list(inspect.signature(websockets.asyncio.server.Server.__init__).parameters)
    if "process_request" not in server_init or "handler" not in server_init:
        problems.append(f"websockets Server.__init__ parameters changed: {server_init}")
    if server is not None:
        ws = getattr(server, "_websock_server", None)
        for owner, attr in ((ws, "_background_event_loop"), (ws, "_live_connections"), (server, "_thread_executor"),
                            (server.scene, "_thread_executor"), (server.gui, "_thread_executor")):
            if not hasattr(owner, attr):
                problems.append(f"{type(owner).__name__} has no {attr}")
    if problems:
        raise RuntimeError("egtviz's server guards cannot be installed: " + "; ".join(problems))


def _websockets_server(server: viser.ViserServer) -> websockets.asyncio.server.Server:
    """The websockets server viser runs, found in the frame of its ``start_server`` coroutine."""
    ws = server._websock_server
    loop = ws._background_event_loop
    if loop is None:  # viser sets it when its server thread starts, before ViserServer() returns
        raise RuntimeError("egtviz's server guards: viser's event loop is not running")

    async def find() -> object:
        for task in asyncio.all_tasks():
            coro = task.get_coro()
            frame = getattr(coro, "cr_frame", None)
            if frame is not None and getattr(coro, "__name__", "") == "start_server":
                return frame.f_locals.get("serve_future")
        return None

    found = asyncio.run_coroutine_threadsafe(find(), loop).result(timeout=5.0)
    if not isinstance(found, websockets.asyncio.server.Server):
        raise RuntimeError(f"egtviz's server guards: viser's websockets server not found (got {type(found).__name__})")
    return found


# -- Origin ------------------------------------------------------------------------------------------------

_LOOPBACK_NAMES = frozenset({"localhost", "localhost.localdomain", "ip6-localhost"})


def _split_host(host_port: str, default_port: int | None) -> tuple[str, int | None] | None:
    """``("example.org", 8080)`` from ``"example.org:8080"`` (brackets of IPv6 literals removed)."""
    try:
        parts = urlsplit("//" + host_port)
        host, port = parts.hostname, parts.port
    except ValueError:
        return None
    if not host:
        return None
    return host.lower().rstrip("."), port if port is not None else default_port


def _is_loopback(host: str) -> bool:
    if host in _LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _own_names() -> frozenset[str]:
    """This machine's own names (what a student types to reach the laptop), lower-case."""
    names = {socket.gethostname().lower()}
    try:
        names.add(socket.getfqdn().lower())
    except OSError:
        pass
    names |= {n + ".local" for n in list(names) if "." not in n}
    return frozenset(n.rstrip(".") for n in names if n)


def origin_allowed(origin: str | None, host_header: str | None, *, allowed_hosts: tuple[str, ...] = (),
                   own_names: frozenset[str] | None = None) -> bool:
    """Whether a websocket handshake with these ``Origin`` and ``Host`` headers is the page's own.

    Allowed: no ``Origin`` (not a browser), or an ``http``/``https`` origin whose host and port equal
    those of ``Host`` (loopback names such as ``localhost`` and ``127.0.0.1`` count as one), where
    ``Host`` names this machine: loopback, an IP literal, this machine's host name, or one of
    ``allowed_hosts``. The last rule defeats DNS rebinding, where a foreign name is made to point at
    this machine and origin and host agree.

    Args:
        origin: the ``Origin`` header, or None when absent.
        host_header: the ``Host`` header, or None when absent.
        allowed_hosts: extra host names the page may be reached under.
        own_names: this machine's names (default: from :mod:`socket`).
    """
    if origin is None:
        return True
    try:
        parts = urlsplit(origin.strip())
        origin_port = parts.port
    except ValueError:
        return False
    if parts.scheme not in ("http", "https") or not parts.hostname or host_header is None:
        return False
    default_port = 443 if parts.scheme == "https" else 80
    origin_host = parts.hostname.lower().rstrip(".")
    origin_port = origin_port if origin_port is not None else default_port
    host = _split_host(host_header.strip(), default_port)
    if host is None:
        return False
    host_name, host_port = host
    if origin_port != host_port:
        return False
    if _is_loopback(origin_host) and _is_loopback(host_name):
        return True
    if origin_host != host_name:
        return False
    try:
        ipaddress.ip_address(host_name)
        return True
    except ValueError:
        pass
    names = own_names if own_names is not None else _own_names()
    return host_name in names or host_name in {h.lower().rstrip(".") for h in allowed_hosts}


def _origin_checker(original: Callable | None, limits: GuardLimits, stats: GuardStats) -> Callable:
    own = _own_names()

    def process_request(connection: ServerConnection,
                        request: Request) -> Awaitable[Response | None] | Response | None:
        headers = request.headers
        if headers.get("Upgrade", "").lower() == "websocket" and not origin_allowed(
            headers.get("Origin"), headers.get("Host"), allowed_hosts=limits.allowed_hosts, own_names=own
        ):
            stats.refused_origins += 1
            # Names are printed, never the whole header: a proxy's name is what the operator needs to allow.
            _log.warning("refused a websocket connection from origin %.80r to host %.80r (if this is a proxy's "
                         "name: egtviz serve --allow-host NAME)", headers.get("Origin"), headers.get("Host"))
            return connection.respond(http.HTTPStatus.FORBIDDEN, "egtviz: this page's origin may not connect.\n")
        return original(connection, request) if original is not None else None

    return process_request


# -- inbound messages: upload caps, gizmo/camera coalescing -------------------------------------------------

#: Messages that carry a whole state (a pose, a camera): of several buffered ones only the last matters.
_STATE_MESSAGES = {
    "TransformControlsUpdateMessage": ("name", "owner"),
    "ViewerCameraMessage": (),
}
_DRAG_BOUNDARIES = frozenset({"TransformControlsDragStartMessage", "TransformControlsDragEndMessage"})


def _is_value_update(msg: dict) -> bool:
    """A field's new value (not a button press, which sends ``True``, nor a checkbox, whose every
    toggle is kept): several of these for one field, buffered together, need only the last."""
    updates = msg.get("updates")
    return isinstance(updates, dict) and list(updates) == ["value"] and not isinstance(updates["value"], bool)


def _is_count(value: object) -> TypeGuard[int]:
    """An int from the browser (msgpack booleans decode to bool, a subclass of int, and are refused)."""
    return isinstance(value, int) and not isinstance(value, bool)


@dataclasses.dataclass
class _Transfer:
    size: int
    part_count: int
    received: int = 0
    parts: set[int] = dataclasses.field(default_factory=set)


class _InboundFilter:
    """Replaces one connection's ``recv``: reads what is buffered, refuses bad uploads, thins pose floods.

    ``transfers`` holds the uploads this tab started and has not finished (id -> declared size and
    part count, bytes and part indices received).
    """

    def __init__(self, connection: ServerConnection, limits: GuardLimits, stats: GuardStats,
                 notify: Callable[[ServerConnection, str], None]):
        self._connection = connection
        self._recv = connection.recv
        self._frames = connection.recv_messages.frames
        self._limits = limits
        self._stats = stats
        self._notify = notify
        self._ready: collections.deque[Data] = collections.deque()
        self.transfers: dict[str, _Transfer] = {}

    async def recv(self, decode: bool | None = None) -> Data:
        if self._ready:
            # One event-loop turn per message: another tab's message, read by the loop meanwhile, is
            # dispatched after at most one of this tab's instead of after a whole buffered batch.
            await asyncio.sleep(0)
        while not self._ready:
            batch = [await self._recv(decode)]
            # Only what is already buffered: never wait for more to arrive.
            while len(batch) < _DRAIN_BATCH and len(self._frames) > 0:
                batch.append(await self._recv(decode))
            self._ready.extend(self._thin(batch))
        return self._ready.popleft()

    def _thin(self, batch: list[Data]) -> list[Data]:
        decoded: list[dict | None] = []
        for raw in batch:
            try:  # a text frame is no msgpack: None, as msgspec's TypeError for it gave
                msg = msgspec.msgpack.decode(raw) if not isinstance(raw, str) else None
            except (msgspec.DecodeError, TypeError):
                msg = None  # viser's own decoder reports it
            decoded.append(msg if isinstance(msg, dict) else None)
        kinds = [msg.get("type") if msg is not None and isinstance(msg.get("type"), str) else None for msg in decoded]
        last: dict[tuple, int] = {}
        drag = 0
        for i, (kind, msg) in enumerate(zip(kinds, decoded)):
            if msg is None:
                continue  # kind is None too: nothing to supersede
            if kind in _DRAG_BOUNDARIES:
                drag += 1  # a pose before a drag's start or end is not superseded by one after it
            elif kind in _STATE_MESSAGES:
                last[(drag, kind, *(str(msg.get(k)) for k in _STATE_MESSAGES[kind]))] = i
            elif kind == "GuiUpdateMessage" and _is_value_update(msg):
                last[("gui", str(msg.get("uuid")))] = i
        keep_state = set(last.values())
        out = []
        for i, (raw, msg, kind) in enumerate(zip(batch, decoded, kinds)):
            if (kind in _STATE_MESSAGES or kind == "GuiUpdateMessage" and msg is not None and _is_value_update(msg)) \
                    and i not in keep_state:
                self._stats.coalesced_messages += 1
                continue
            # A message with a kind decoded to a dict: msg is None only when kind is None.
            if msg is not None and kind == "FileTransferStartUpload" and not self._start_upload(msg):
                continue
            if msg is not None and kind == "FileTransferPart" and not self._accept_part(msg):
                continue
            out.append(raw)
        return out

    def _start_upload(self, msg: dict) -> bool:
        lim = self._limits
        size, parts, tid = msg.get("size_bytes"), msg.get("part_count"), msg.get("transfer_uuid")
        if not (_is_count(size) and _is_count(parts) and isinstance(tid, str)) or size < 0 or parts < 0:
            return self._refuse_upload("the upload announced no valid size")
        reason = None
        if size > lim.max_upload_bytes:
            reason = f"the file is larger than {lim.max_upload_bytes / 1e6:g} MB"
        elif (parts != 0) if size == 0 else not 1 <= parts <= math.ceil(size / MIN_UPLOAD_PART_BYTES):
            reason = "the upload announced an implausible number of parts"
        elif tid in self.transfers:
            reason = "the upload repeated a transfer id"
        elif len(self.transfers) >= lim.max_uploads_in_flight:
            reason = f"more than {lim.max_uploads_in_flight} uploads at once"
        if reason is not None:
            return self._refuse_upload(reason)
        if parts > 0:
            self.transfers[tid] = _Transfer(size, parts)
        return True

    def _refuse_upload(self, reason: str) -> bool:
        """Count, log and tell the tab why its upload was refused; False, for ``_start_upload`` to return."""
        self._stats.refused_uploads += 1
        _log.warning("refused an upload: %s", reason)
        self._notify(self._connection, f"Upload refused: {reason}.")
        return False

    def _accept_part(self, msg: dict) -> bool:
        # Every part from a browser belongs to an upload: viser files it by transfer id alone, so a
        # part is counted against its transfer whatever its source_component_uuid says.
        tid = msg.get("transfer_uuid")
        transfer = self.transfers.get(tid) if isinstance(tid, str) else None
        index, content = msg.get("part_index"), msg.get("content")
        if (transfer is None or not isinstance(tid, str) or not isinstance(index, int) or isinstance(index, bool)
                or not 0 <= index < transfer.part_count or index in transfer.parts
                or not isinstance(content, bytes) or transfer.received + len(content) > transfer.size):
            self._stats.dropped_parts += 1
            return False
        transfer.parts.add(index)
        transfer.received += len(content)
        if len(transfer.parts) == transfer.part_count:
            del self.transfers[tid]
        return True


# -- callbacks: per-tab queues, round-robin, latest wins ----------------------------------------------------


@dataclasses.dataclass
class _Job:
    fn: Callable
    args: tuple
    kwargs: dict
    future: Future
    key: tuple | None


@dataclasses.dataclass
class _TabQueue:
    jobs: collections.deque[_Job] = dataclasses.field(default_factory=collections.deque)
    waiting: dict[tuple, _Job] = dataclasses.field(default_factory=dict)  # key -> _Job not yet started
    scheduled: bool = False


def _tab_of(args: tuple) -> int | None:
    """The client id an event (or a ClientHandle, or a CameraHandle) belongs to."""
    if not args:
        return None
    first = args[0]
    cid = getattr(first, "client_id", None)
    if cid is None and isinstance(first, viser.CameraHandle):
        cid = getattr(first.client, "client_id", None)
    return cid if isinstance(cid, int) and not isinstance(cid, bool) else None


def _latest_wins_key(fn: Callable, args: tuple) -> tuple | None:
    """A key for events whose callback only needs the newest one (a value, a pose, a camera)."""
    event = args[0]
    if isinstance(event, viser.CameraHandle):
        return (fn, "camera")
    if isinstance(event, viser.GuiEvent):
        if isinstance(event.target, (viser.GuiButtonHandle, viser.GuiUploadButtonHandle)):
            return None  # every press and every file counts
        return (fn, "gui", id(event.target))
    if isinstance(event, (viser.TransformControlsEvent, viser.SceneNodeDragEvent)) and event.phase == "update":
        return (fn, type(event).__name__, id(event.target))
    return None


#: Drag redraws (a gizmo drag's pose updates) that run at once across all tabs. Under the GIL, thirty redraws
#: run side by side each finish near the end of the round (and starve the event loop that receives and sends);
#: run one after the other, each finishes in its own time. Other events (a field's value, a view camera) keep
#: the pool: with them in the lane too, a classroom browser test's follow-me came back too late to its tabs.
REDRAW_LANES = 1
#: A redraw running longer than this (seconds) no longer holds its lane: one that waits must not stop the room.
LANE_STALL_S = 0.25


def _is_redraw(key: tuple | None) -> bool:
    """A job that takes a lane: a gizmo drag's pose (what a dragging room sends twenty times a second)."""
    return key is not None and key[1] in ("TransformControlsEvent", "SceneNodeDragEvent")


class FairExecutor:
    """Stands in for viser's thread pool: one job per tab at a time, tabs round-robin, latest wins.

    Drag redraws (a gizmo's pose updates) of all tabs take turns in ``lanes`` lanes, tabs in the order they
    became ready; other jobs of a tab (a field, a button, a connection's set-up, which may wait) go to the pool
    at once. Jobs that belong to no tab go straight to the pool.
    """

    def __init__(self, pool: ThreadPoolExecutor, *, max_pending: int, stats: GuardStats, lanes: int = REDRAW_LANES,
                 stall_s: float = LANE_STALL_S) -> None:
        self._pool = pool
        self._max_pending = max_pending
        self._stats = stats
        self._lock = threading.Lock()
        self._tabs: dict[int, _TabQueue] = {}
        self._lanes = lanes
        self._stall_s = stall_s
        self._line: collections.deque[int] = collections.deque()  # tabs whose next job is a redraw, in turn
        self._started: dict[int, float] = {}  # tab -> when its redraw was handed to the pool
        self._timer: threading.Timer | None = None

    def _schedule(self, tab: int, queue: _TabQueue, *, start: bool = True) -> None:
        """Put the tab in line for its next job (the lock is held; ``start``: start the line's next redraws)."""
        queue.scheduled = True
        if self._lanes > 0 and _is_redraw(queue.jobs[0].key):
            self._line.append(tab)
            if start:
                self._start_lanes()
        else:
            self._pool.submit(self._run_one, tab)

    def _start_lanes(self) -> None:
        """Hand the next redraws in line to the pool while a lane is free (the lock is held)."""
        if not self._line:
            return
        now = time.monotonic()
        running = [t0 for t0 in self._started.values() if now - t0 < self._stall_s]
        while self._line and len(running) < self._lanes:
            tab = self._line.popleft()
            self._started[tab] = now
            running.append(now)
            self._pool.submit(self._run_one, tab)
        if self._line and self._timer is None:  # look again when the oldest running redraw stalls
            self._timer = threading.Timer(max(0.0, min(running) + self._stall_s - now), self._on_stall)
            self._timer.daemon = True
            self._timer.start()

    def _on_stall(self) -> None:
        with self._lock:
            self._timer = None
            self._start_lanes()

    def submit(self, fn: Callable[_P, _T], /, *args: _P.args, **kwargs: _P.kwargs) -> Future[_T]:
        """Queue ``fn(*args, **kwargs)`` behind the other jobs of the tab ``args[0]`` belongs to.

        Returns:
            The job's future; an already finished one (result None) when the call was merged into a
            waiting job of the same handle or dropped because the tab has too many waiting.
        """
        tab = _tab_of(args)
        if tab is None:
            return self._pool.submit(fn, *args, **kwargs)
        key = _latest_wins_key(fn, args)
        with self._lock:
            queue = self._tabs.setdefault(tab, _TabQueue())
            waiting = queue.waiting.get(key) if key is not None else None
            if waiting is not None:
                waiting.args, waiting.kwargs = args, kwargs  # the newer event replaces the one not yet run
                self._stats.coalesced_events += 1
                return _done_future()
            if len(queue.jobs) >= self._max_pending:
                self._stats.dropped_events += 1
                if self._stats.dropped_events == 1 or self._stats.dropped_events % 1000 == 0:
                    _log.warning("a tab sent events faster than they can be handled; dropped %d so far",
                                 self._stats.dropped_events)
                return _done_future()
            job = _Job(fn, args, kwargs, Future(), key)
            queue.jobs.append(job)
            if key is not None:
                queue.waiting[key] = job
            if not queue.scheduled:
                self._schedule(tab, queue)
            else:
                self._start_lanes()  # a redraw that stalls past its time frees its lane here
        return job.future

    def _run_one(self, tab: int | None) -> None:
        """On a pool thread: run the tab's oldest job, then put the tab back in line. A thread that ran a redraw
        goes on with the next redraw in line itself (no hand-over to another pool thread between two)."""
        while tab is not None:
            tab = self._run_job(tab)

    def _run_job(self, tab: int) -> int | None:
        """Run ``tab``'s oldest job; returns the tab whose redraw this thread runs next (None: none)."""
        with self._lock:
            queue = self._tabs[tab]
            job = queue.jobs.popleft()
            if job.key is not None and queue.waiting.get(job.key) is job:
                del queue.waiting[job.key]
        nxt = None
        try:
            if job.future.set_running_or_notify_cancel():
                try:
                    result = job.fn(*job.args, **job.kwargs)
                except BaseException as exc:  # noqa: BLE001 - handed to the future, reported by viser
                    job.future.set_exception(exc)
                else:
                    job.future.set_result(result)
        finally:
            with self._lock:
                lane = self._started.pop(tab, None) is not None
                if queue.jobs:
                    # Back of the line: the other tabs' jobs go first (round-robin).
                    self._schedule(tab, queue, start=False)
                else:
                    queue.scheduled = False
                    del self._tabs[tab]
                if lane and self._line:
                    nxt = self._line.popleft()
                    self._started[nxt] = time.monotonic()
                self._start_lanes()
        return nxt

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Shut the underlying pool down (viser does when the server stops)."""
        with self._lock:
            self._line.clear()
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
        self._pool.shutdown(wait=wait, cancel_futures=cancel_futures)

    def pending(self) -> int:
        """Jobs waiting in all tabs' queues."""
        with self._lock:
            return sum(len(q.jobs) for q in self._tabs.values())


def _done_future() -> Future:
    f: Future = Future()
    f.set_result(None)
    return f


# -- installing ---------------------------------------------------------------------------------------------


def install_guards(server: viser.ViserServer, limits: GuardLimits | None = None) -> Guards:
    """Add the Origin check, the upload caps and the flood handling to a running viser server.

    Call it right after making the server (before any tab can have connected).

    Args:
        server: the viser server.
        limits: what a tab may send (default :class:`GuardLimits`).

    Returns:
        The limits in force and counters of what was refused.

    Raises:
        RuntimeError: the installed viser lacks a private name used here (see :func:`check_viser_internals`).
    """
    limits = limits if limits is not None else GuardLimits()
    if not isinstance(limits, GuardLimits):
        raise TypeError(f"limits: expected a GuardLimits, got {type(limits).__name__}")
    check_viser_internals(server)
    stats = GuardStats()
    ws_server = _websockets_server(server)
    live = server._websock_server._live_connections

    def notify(connection: ServerConnection, text: str) -> None:
        cid = next((k for k, c in list(live.items()) if c is connection), None)
        client = server.get_clients().get(cid) if cid is not None else None
        if client is not None:
            client.add_notification("Refused", text, color="red", auto_close_seconds=8.0)

    ws_server.process_request = _origin_checker(ws_server.process_request, limits, stats)
    handler = ws_server.handler

    async def guarded_handler(connection: ServerConnection) -> None:
        connection.protocol.max_message_size = limits.max_message_bytes
        # websockets reads through the attribute: the filter stands in for this connection's own recv (a method to
        # mypy, and an overloaded one).
        inbound = _InboundFilter(connection, limits, stats, notify)
        connection.recv = inbound.recv  # type: ignore[method-assign,assignment]
        await handler(connection)

    ws_server.handler = guarded_handler
    fair = FairExecutor(server._thread_executor, max_pending=limits.max_pending_events, stats=stats)
    # Client handles made later copy the server's pool, so swapping these three covers every callback.
    server._thread_executor = fair  # type: ignore[assignment]
    server.scene._thread_executor = fair  # type: ignore[assignment]
    server.gui._thread_executor = fair  # type: ignore[assignment]
    return Guards(limits, stats)


# -- a page under a path prefix, and what a tab's handshake asked for (the classroom's instructor link) ------------


@dataclasses.dataclass(frozen=True)
class Handshake:
    """What a connected tab's websocket handshake asked for.

    Attributes:
        path: the request path (the page's path: viser's client connects to the page's own URL, query dropped).
        peer: the peer's address (an IP literal; ``""`` when unknown).
    """

    path: str
    peer: str


def handshake_of(server: viser.ViserServer, client_id: int) -> Handshake | None:
    """The handshake of the connected tab ``client_id``; None once it left (or before viser listed it)."""
    connection = server._websock_server._live_connections.get(client_id)
    request = getattr(connection, "request", None)
    if connection is None or request is None:
        return None
    try:
        peer = str(connection.remote_address[0])
    except (TypeError, IndexError, OSError):
        peer = ""
    return Handshake(str(request.path), peer)


def serve_page_under(server: viser.ViserServer, prefix: str) -> None:
    """Serve viser's page at every path ``prefix/<one segment>`` too, as at ``/`` (its websocket then arrives
    with that path, which :func:`handshake_of` reports). Call it after :func:`install_guards`.

    Args:
        prefix: a path such as ``/egtviz-instructor`` (starts with ``/``, no trailing ``/``).
    """
    if not prefix.startswith("/") or prefix.endswith("/") or len(prefix) < 2:
        raise ValueError(f"prefix: expected a path such as '/name', got {prefix!r}")
    ws_server = _websockets_server(server)
    original = ws_server.process_request

    def process_request(connection: ServerConnection,
                        request: Request) -> Awaitable[Response | None] | Response | None:
        path, sep, query = request.path.partition("?")
        if request.headers.get("Upgrade", "").lower() != "websocket" and path.startswith(prefix + "/"):
            rest = path[len(prefix) + 1:].split("/", 1)
            page = "/" + (rest[1] if len(rest) > 1 else "")
            request = dataclasses.replace(request, path=page + sep + query)
        return original(connection, request) if original is not None else None

    ws_server.process_request = process_request
