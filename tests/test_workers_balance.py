"""``egtviz serve --workers N`` hands each connection to the worker holding the fewest, not to the kernel's hash."""

from __future__ import annotations

import socket
from collections import Counter
from pathlib import Path

import pytest

from egtviz.viewer.server.balance import CLOSED, Dispatcher
from egtviz.viewer.server.workers import Supervisor, WorkerOptions, worker_of_connection

from _waiting import PATIENCE, wait_for

pytestmark = pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux's /proc")


def _where(sup: Supervisor, conns: list[socket.socket]) -> list[int | None]:
    pids = [p for p in sup.pids() if p is not None]
    out: list[int | None] = []
    for conn in conns:
        port = conn.getsockname()[1]
        # The worker adopts a handed connection a moment after the supervisor accepted it.
        wait_for(lambda: worker_of_connection(sup.port, port, pids) is not None,
                 f"a worker to adopt the connection from port {port}")
        out.append(worker_of_connection(sup.port, port, pids))
    return out


def _settle(sup: Supervisor, want: dict[int, int]) -> None:
    assert sup.dispatcher is not None
    wait_for(lambda: sup.dispatcher.open_connections() == want,
             f"the dispatcher to count {want} open connections")


def test_connections_are_split_evenly_and_fill_the_emptier_worker():
    sup = Supervisor(2, 0, WorkerOptions())
    conns: list[socket.socket] = []
    try:
        sup.start(timeout=PATIENCE)
        conns = [socket.create_connection(("127.0.0.1", sup.port)) for _ in range(8)]
        where = _where(sup, conns)
        assert None not in where
        counts = Counter(where)
        assert sorted(counts.values()) == [4, 4]  # the kernel's hash split 30 tabs 9 / 21 in one bench run
        emptied = where[0]
        for conn, pid in zip(conns, where):
            if pid == emptied:
                conn.close()
        conns = [c for c, pid in zip(conns, where) if pid != emptied]
        _settle(sup, {i: (4 if sup.slots[i].pid != emptied else 0) for i in range(2)})
        fresh = [socket.create_connection(("127.0.0.1", sup.port)) for _ in range(4)]
        conns += fresh
        assert _where(sup, fresh) == [emptied] * 4  # the worker whose tabs left takes the next ones
    finally:
        for conn in conns:
            conn.close()
        sup.stop()


def test_a_dead_worker_is_passed_over():
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    dispatcher = Dispatcher([listener])
    try:
        gone = dispatcher.channel_for(0)
        gone.close()  # the worker died with its end of the channel
        alive = dispatcher.channel_for(1)
        dispatcher.mark_ready(0)
        dispatcher.mark_ready(1)
        wait_for(lambda: 0 not in dispatcher.open_connections(), "the dispatcher to hear the closed channel")
        client = socket.create_connection(listener.getsockname())
        msg, fds, _flags, _addr = socket.recv_fds(alive, 16, 4)
        assert len(fds) == 1
        # Counted by the dispatcher's thread once the send returned.
        wait_for(lambda: dispatcher.handed, "the dispatcher to count the connection it handed")
        assert dispatcher.handed == {1: 1}
        with socket.socket(fileno=fds[0]) as handed:
            assert handed.getpeername() == client.getsockname()  # the browser's own connection
        alive.sendall(CLOSED)
        wait_for(lambda: dispatcher.open_connections() == {1: 0}, "the dispatcher to hear the connection closed")
        client.close()
        alive.close()
    finally:
        dispatcher.close()
        listener.close()
