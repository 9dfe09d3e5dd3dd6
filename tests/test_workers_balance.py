"""``egtviz serve --workers N`` hands each connection to the worker holding the fewest, not to the kernel's hash."""

from __future__ import annotations

import socket
import time
from collections import Counter
from pathlib import Path

import pytest

from egtviz.viewer.server.balance import CLOSED, Dispatcher
from egtviz.viewer.server.workers import Supervisor, WorkerOptions, worker_of_connection

pytestmark = pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux's /proc")


def _where(sup: Supervisor, conns: list[socket.socket]) -> list[int | None]:
    pids = [p for p in sup.pids() if p is not None]
    out: list[int | None] = []
    for conn in conns:
        pid = None
        for _ in range(100):  # the worker adopts a handed connection a moment after the supervisor accepted it
            pid = worker_of_connection(sup.port, conn.getsockname()[1], pids)
            if pid is not None:
                break
            time.sleep(0.02)
        out.append(pid)
    return out


def _settle(sup: Supervisor, want: dict[int, int]) -> None:
    assert sup.dispatcher is not None
    for _ in range(200):
        if sup.dispatcher.open_connections() == want:
            return
        time.sleep(0.02)
    assert sup.dispatcher.open_connections() == want


def test_connections_are_split_evenly_and_fill_the_emptier_worker():
    sup = Supervisor(2, 0, WorkerOptions())
    conns: list[socket.socket] = []
    try:
        sup.start()
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
        for _ in range(100):  # the dispatcher hears the closed channel
            if 0 not in dispatcher.open_connections():
                break
            time.sleep(0.01)
        client = socket.create_connection(listener.getsockname())
        msg, fds, _flags, _addr = socket.recv_fds(alive, 16, 4)
        assert len(fds) == 1
        for _ in range(100):  # counted by the dispatcher's thread once the send returned
            if dispatcher.handed:
                break
            time.sleep(0.01)
        assert dispatcher.handed == {1: 1}
        with socket.socket(fileno=fds[0]) as handed:
            assert handed.getpeername() == client.getsockname()  # the browser's own connection
        alive.sendall(CLOSED)
        for _ in range(100):
            if dispatcher.open_connections() == {1: 0}:
                break
            time.sleep(0.01)
        assert dispatcher.open_connections() == {1: 0}
        client.close()
        alive.close()
    finally:
        dispatcher.close()
        listener.close()
