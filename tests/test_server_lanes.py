"""The fair executor's redraw lane: gizmo drags' pose updates of all tabs run one at a time, tabs taking turns."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import viser

from egtviz.viewer.server import guard
from egtviz.viewer.server.guard import FairExecutor

from _waiting import PATIENCE

BLOCKED_S = 2 * PATIENCE
"""How long a redraw held at a gate waits at most: longer than any wait of the test that holds it."""


class _Target:
    """A gizmo handle stand-in."""


def _value_event(tab: int, target: _Target) -> viser.TransformControlsEvent:
    """A gizmo drag's pose update (latest wins; a redraw)."""
    return viser.TransformControlsEvent(client=None, client_id=tab, target=target,  # type: ignore[arg-type]
                                        phase="update")


def test_only_a_drags_pose_takes_a_lane():
    fair, pool = _fair(stall_s=BLOCKED_S)  # the held redraw never stalls out of its lane here
    gate = threading.Event()
    ran = threading.Event()
    try:
        first = fair.submit(lambda event: gate.wait(BLOCKED_S), _value_event(0, _Target()))
        value = viser.GuiEvent(client=None, client_id=1, target=_Target())  # type: ignore[arg-type]
        field = fair.submit(lambda event: ran.set(), value)
        # A field's value (the follow-me checkbox, say) is not held behind a drag: it runs while the drag is held.
        assert ran.wait(PATIENCE), "the field's job waited for the held redraw"
    finally:
        gate.set()
    first.result(timeout=PATIENCE)
    field.result(timeout=PATIENCE)
    pool.shutdown()


class _Event:
    def __init__(self, client_id: int) -> None:
        self.client_id = client_id


def _fair(**kwargs) -> tuple[FairExecutor, ThreadPoolExecutor]:
    pool = ThreadPoolExecutor(max_workers=8)
    return FairExecutor(pool, max_pending=100, stats=guard.GuardStats(), **kwargs), pool


def test_redraws_of_different_tabs_run_one_at_a_time_in_turn():
    fair, pool = _fair(stall_s=BLOCKED_S)  # no redraw stalls out of its lane, however slow the machine
    lock = threading.Lock()
    running, peak, order = [0], [0], []

    def redraw(event: viser.GuiEvent, label: str) -> None:
        with lock:
            running[0] += 1
            peak[0] = max(peak[0], running[0])
        time.sleep(0.03)
        with lock:
            running[0] -= 1
            order.append(label)

    a, b, c = _Target(), _Target(), _Target()
    futures = [fair.submit(redraw, _value_event(0, a), "tab0-a"), fair.submit(redraw, _value_event(0, b), "tab0-b"),
               fair.submit(redraw, _value_event(1, c), "tab1"), fair.submit(redraw, _value_event(2, c), "tab2")]
    for f in futures:
        f.result(timeout=PATIENCE)
    pool.shutdown()
    assert peak[0] == 1  # side by side they all finish late; one after the other each finishes in its time
    assert order == ["tab0-a", "tab1", "tab2", "tab0-b"]  # tab 0's second redraw waits for the others' turn


def test_other_jobs_are_not_held_by_a_running_redraw():
    fair, pool = _fair(stall_s=BLOCKED_S)  # the held redraw never stalls out of its lane here
    gate = threading.Event()
    ran = threading.Event()
    try:
        first = fair.submit(lambda event: gate.wait(BLOCKED_S), _value_event(0, _Target()))
        other = fair.submit(lambda event: ran.set(), _Event(1))  # a button, a connection's set-up: not a redraw
        assert ran.wait(PATIENCE), "the other job waited for the held redraw"
    finally:
        gate.set()
    first.result(timeout=PATIENCE)
    other.result(timeout=PATIENCE)
    pool.shutdown()


def test_a_redraw_that_stalls_frees_its_lane():
    fair, pool = _fair(stall_s=0.1)
    gate = threading.Event()
    ran = threading.Event()
    try:
        stuck = fair.submit(lambda event: gate.wait(BLOCKED_S), _value_event(0, _Target()))
        t0 = time.monotonic()
        nxt = fair.submit(lambda event: ran.set(), _value_event(1, _Target()))
        # Started once the stuck redraw had held the lane for its time (a lower bound: a busy machine only adds),
        # not when it ended (it is held until the test lets it go).
        assert ran.wait(PATIENCE), "the next redraw waited for the stuck one to end"
        assert time.monotonic() - t0 >= 0.09
    finally:
        gate.set()
    stuck.result(timeout=PATIENCE)
    nxt.result(timeout=PATIENCE)
    fair.shutdown()
    pool.shutdown()
