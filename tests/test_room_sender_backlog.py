"""The room's sender passes over a follower whose tab has not been sent its last frame, and comes back to it."""

from __future__ import annotations

import threading
import time

from egtviz.viewer.classroom import room_sender
from egtviz.viewer.classroom.follow_view import RoomFrame
from egtviz.viewer.classroom.room_sender import RoomSender


class _View:
    """A follower stand-in: records the frame numbers it was shown."""

    def __init__(self) -> None:
        self.frame: RoomFrame | None = None
        self.shown: list[int] = []
        self.busy = False

    def show(self, frame: RoomFrame) -> None:
        if self.frame is not None and frame.number <= self.frame.number:
            return
        self.frame = frame
        self.shown.append(frame.number)


def _frame(n: int) -> RoomFrame:
    return RoomFrame(n, n, None, None, (), "", False)  # type: ignore[arg-type]


def _wait(cond, timeout: float = 3.0) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        assert time.monotonic() < deadline
        time.sleep(0.005)


def test_a_busy_follower_is_passed_over_then_shown_the_newest_frame_once_it_drained():
    fast, slow = _View(), _View()
    checks: list[str] = []
    lock = threading.Lock()

    def busy(view: _View) -> bool:
        with lock:
            checks.append("slow" if view is slow else "fast")
            return view.busy

    sender = RoomSender(lambda: [slow, fast], busy=busy)
    try:
        sender.post(_frame(1))
        _wait(lambda: fast.shown == [1] and slow.shown == [1])
        slow.busy = True  # its tab is still being sent frame 1
        sender.post(_frame(2))
        _wait(lambda: fast.shown == [1, 2])
        sender.post(_frame(3))
        _wait(lambda: fast.shown == [1, 2, 3])
        assert slow.shown == [1]  # nothing drawn for a tab that would only have it replaced
        slow.busy = False
        _wait(lambda: slow.shown == [1, 3])  # frame 2 skipped: the newest is shown once the tab drained
        assert fast.shown == [1, 2, 3]
    finally:
        sender.close()


def test_a_follower_that_never_drains_is_shown_the_frame_after_a_while(monkeypatch):
    monkeypatch.setattr(room_sender, "MAX_PASS_OVER_S", 0.1)
    stuck = _View()
    stuck.busy = True
    sender = RoomSender(lambda: [stuck], busy=lambda view: view.busy)
    try:
        t0 = time.monotonic()
        sender.post(_frame(1))
        _wait(lambda: stuck.shown == [1])
        assert time.monotonic() - t0 >= 0.09
    finally:
        sender.close()


def test_the_default_question_reads_a_real_tab(tmp_path):
    import viser

    from egtviz.viewer.server.client_backlog import missing_internals, waiting
    from egtviz.viewer.server.headless import FakeTab

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tab = FakeTab(server.get_port())
    try:
        _wait(lambda: len(server.get_clients()) == 1)
        client = next(iter(server.get_clients().values()))
        assert missing_internals(client) == []
        _wait(lambda: not waiting(client))
        with client.atomic():  # held back: pushed, not sent
            client.gui.add_markdown("x")
            assert waiting(client)
        _wait(lambda: not waiting(client))
    finally:
        tab.close()
        server.stop()
