"""Connections handed to the worker that holds the fewest (``egtviz serve --workers N``).

With ``SO_REUSEPORT`` alone the kernel picks a worker for each new connection by a hash of its addresses: a room of
30 tabs split 9 / 21 in one run, and the busier worker's tabs waited twice as long. Here the supervising process
listens on the one port itself, accepts each connection and passes its socket (``SCM_RIGHTS`` over a Unix socket
pair) to the worker with the fewest open connections; the worker hands it to its websockets server as if it had
accepted it (:meth:`asyncio.loop.connect_accepted_socket` with the server's own protocol factory) and says when it
closes. A tab's websocket then lives on that worker, as before, and its peer address is the browser's.

:class:`Dispatcher` is the supervising process's side, :func:`adopt_connections` a worker's. The private names used
(websockets' ``serve`` keeps its asyncio server in ``Server.server``; asyncio's server keeps its protocol factory in
``_protocol_factory``) are checked by :func:`missing_internals`.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import threading
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from websockets.asyncio.server import Server

__all__ = ["CLOSED", "Dispatcher", "adopt_connections", "capture_serve", "missing_internals", "served"]

_log = logging.getLogger(__name__)

#: What a worker sends back on its channel when a connection it was handed has closed.
CLOSED = b"-"
_HANDED = b"c"

_served: list[Server] = []


def served() -> list[Server]:
    """The websockets servers started in this process since :func:`capture_serve` (newest last)."""
    return list(_served)


def capture_serve(*, reuse_port: bool) -> None:
    """Make every websockets server this process starts known to :func:`served` (and, with ``reuse_port``, bind
    with ``SO_REUSEPORT``: the kernel-balanced workers). viser 1.1.1 starts its server with
    ``websockets.asyncio.server.serve(handler, host, port, ...)``, which hands unknown keywords to asyncio's
    ``create_server``. Process-wide: called only in a worker process."""
    import websockets.asyncio.server as ws_server

    base = ws_server.serve
    while (replaced := getattr(base, "egtviz_base", None)) is not None:
        base = replaced

    class serve(base):  # type: ignore[valid-type,misc]  # noqa: N801 - it replaces websockets' ``serve``
        egtviz_base = base
        egtviz_reuse_port = reuse_port

        def __init__(self, *args: object, **kwargs: object) -> None:
            if reuse_port:
                kwargs.setdefault("reuse_port", True)
            super().__init__(*args, **kwargs)

        async def __await_impl__(self) -> Server:
            server = await super().__await_impl__()
            _served.append(server)
            return server

    ws_server.serve = serve  # type: ignore[misc]


def missing_internals(server: object) -> list[str]:
    """What ``server`` (a websockets server from :func:`served`) lacks of the private names used here."""
    inner = getattr(server, "server", None)
    if inner is None:
        return ["websockets Server.server"]
    if not callable(getattr(inner, "_protocol_factory", None)):
        return ["asyncio Server._protocol_factory"]
    return []


def adopt_connections(channel: socket.socket, server: Server, loop: asyncio.AbstractEventLoop) -> threading.Thread:
    """In a worker: serve every connection the supervising process passes on ``channel`` with ``server`` (a
    websockets server running on ``loop``), and write :data:`CLOSED` on ``channel`` as each one closes. Returns the
    receiving thread (it ends when the channel closes).

    Raises:
        RuntimeError: ``server`` lacks a private name this relies on (:func:`missing_internals`).
    """
    missing = missing_internals(server)
    if missing:
        raise RuntimeError(f"egtviz workers cannot be handed connections: {', '.join(missing)} not found")
    # asyncio's private name, which typeshed does not declare (found above by missing_internals).
    factory = getattr(server.server, "_protocol_factory")  # noqa: B009
    send_lock = threading.Lock()

    def closed() -> None:
        try:
            with send_lock:
                channel.sendall(CLOSED)
        except OSError:
            pass  # the supervising process is going: nobody counts any more

    async def adopt(sock: socket.socket) -> None:
        try:
            _transport, connection = await loop.connect_accepted_socket(factory, sock)
        except OSError:
            sock.close()
            closed()
            return
        try:
            await connection.wait_closed()
        finally:
            closed()

    def receive() -> None:
        while True:
            try:
                data, fds, _flags, _addr = socket.recv_fds(channel, 64, 16)
            except OSError:
                return
            if not data and not fds:
                return  # the supervising process closed the channel
            for fd in fds:
                sock = socket.socket(fileno=fd)
                sock.setblocking(False)
                try:
                    asyncio.run_coroutine_threadsafe(adopt(sock), loop)
                except RuntimeError:  # the server stopped
                    sock.close()

    thread = threading.Thread(target=receive, name="egtviz-adopt", daemon=True)
    thread.start()
    return thread


class _Channel:
    """The supervising process's end of one worker's channel, and the connections that worker holds."""

    def __init__(self, index: int, sock: socket.socket) -> None:
        self.index = index
        self.sock = sock
        self.open = 0
        self.alive = True
        self.ready = False


class Dispatcher:
    """Accepts on ``listeners`` (bound sockets, made to listen here) and passes each connection to the worker with
    the fewest open ones (ties: the lowest index). :meth:`channel_for` makes a worker's channel when it (re)starts.

    Args:
        listeners: the port's sockets (one per address of the host).
        backlog: the listen backlog.
    """

    def __init__(self, listeners: list[socket.socket], backlog: int = 256) -> None:
        self._listeners = listeners
        self._lock = threading.Lock()
        self._channels: dict[int, _Channel] = {}
        self._closed = False
        #: Connections handed to each worker index since the start (tests and benchmarks read it).
        self.handed: dict[int, int] = {}
        for sock in listeners:
            sock.listen(backlog)
            threading.Thread(target=self._accept, args=(sock,), name="egtviz-dispatch", daemon=True).start()

    def channel_for(self, index: int) -> socket.socket:
        """A new channel for worker ``index`` (its previous one, if any, is dropped); returns the worker's end,
        to be passed to the worker process and closed here once it started."""
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        channel = _Channel(index, mine)
        with self._lock:
            old = self._channels.pop(index, None)
            self._channels[index] = channel
        if old is not None:
            self._drop(old)
        threading.Thread(target=self._count_closed, args=(channel,), name="egtviz-dispatch-count",
                         daemon=True).start()
        return theirs

    def mark_ready(self, index: int) -> None:
        """Worker ``index`` serves: connections go to it (one that is still starting gets them only when no
        worker serves)."""
        with self._lock:
            channel = self._channels.get(index)
            if channel is not None:
                channel.ready = True

    def open_connections(self) -> dict[int, int]:
        """Open connections each live worker holds, as far as this process knows."""
        with self._lock:
            return {i: c.open for i, c in self._channels.items() if c.alive}

    def _count_closed(self, channel: _Channel) -> None:
        while True:
            try:
                data = channel.sock.recv(256)
            except OSError:
                data = b""
            if not data:
                with self._lock:
                    channel.alive = False
                return
            with self._lock:
                channel.open = max(0, channel.open - data.count(CLOSED))

    def _pick(self) -> _Channel | None:
        with self._lock:
            live = [c for c in self._channels.values() if c.alive]
            if not live:
                return None
            live = [c for c in live if c.ready] or live
            best = min(live, key=lambda c: (c.open, c.index))
            best.open += 1
            return best

    def _accept(self, listener: socket.socket) -> None:
        while not self._closed:
            try:
                conn, _addr = listener.accept()
            except OSError:
                if self._closed:
                    return
                continue
            self._hand(conn)

    def _hand(self, conn: socket.socket) -> None:
        try:
            for _ in range(len(self._channels) + 1):
                channel = self._pick()
                if channel is None:
                    return  # no worker to take it: the browser retries
                try:
                    socket.send_fds(channel.sock, [_HANDED], [conn.fileno()])
                except OSError:
                    self._drop(channel)
                    continue
                with self._lock:
                    self.handed[channel.index] = self.handed.get(channel.index, 0) + 1
                return
        finally:
            conn.close()  # the worker holds its own copy now (or nobody does and the connection ends)

    def _drop(self, channel: _Channel) -> None:
        with self._lock:
            channel.alive = False
        try:
            channel.sock.close()
        except OSError:
            pass

    def close(self) -> None:
        """Stop accepting (the listening sockets are the caller's to close) and drop every channel."""
        self._closed = True
        for sock in self._listeners:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        with self._lock:
            channels = list(self._channels.values())
            self._channels.clear()
        for channel in channels:
            self._drop(channel)

