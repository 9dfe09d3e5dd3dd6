"""The class shared between workers: two classrooms joined through a hub (in one process, no server)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from egtviz.classroom import Classroom, Mode
from egtviz.viewer.server import class_bus
from egtviz.viewer.server.class_bus import ClassHub, ClassroomBus
from egtviz.viewer.server.class_patch import TAB_SPAN, apply_patch, diff, global_tab, normal

from _waiting import PATIENCE, wait_for


class _Sender:
    def __init__(self) -> None:
        self.frames: list = []
        self.latest = None
        self._n = 0

    def post(self, frame) -> None:
        self.frames.append(frame)

    def next_number(self) -> int:
        self._n += 1
        return self._n


@pytest.fixture
def pair(monkeypatch):
    monkeypatch.setattr(class_bus, "SYNC_S", 0.01)
    hub = ClassHub()
    rooms, buses = [], []
    for i in range(2):
        room = Classroom(None, token="t" * 20, task_count=lambda name: 1)
        bus = ClassroomBus(hub.address, hub.authkey, i)
        bus.attach(SimpleNamespace(room=room, sender=_Sender()))
        assert bus.wait_welcomed(PATIENCE), f"waited {PATIENCE:.0f} s for the hub to welcome worker {i}"
        rooms.append(room)
        buses.append(bus)
    yield hub, rooms, buses
    for bus in buses:
        bus.close()
    hub.close()


def test_changes_made_at_once_in_two_workers_are_both_kept(pair) -> None:
    hub, (a, b), _ = pair
    a.instructor_join(0)
    a.join(1, "Ada")
    b.join(1, "Bob")  # the same tab id in another worker: another tab
    b.join(2, "Cy")
    a.ask("How far apart are the epipoles?")
    wait_for(lambda: len(a.student_tabs()) == 3 and len(b.student_tabs()) == 3, "both workers to see the 3 tabs")
    assert a.student_tabs() == {1: "Ada", global_tab(1, 1): "Bob", global_tab(1, 2): "Cy"}
    assert b.student_tabs() == {1: "Bob", 2: "Cy", global_tab(0, 1): "Ada"}
    wait_for(lambda: b.asked() == "How far apart are the epipoles?", "worker b to see the question")
    b.record_answer(1, "How far apart are the epipoles?", 2.5)
    a.record_answer(1, "How far apart are the epipoles?", 3.5)
    wait_for(lambda: a.histogram("How far apart are the epipoles?").n == 2
             and b.histogram("How far apart are the epipoles?").n == 2, "both workers to count both answers")
    assert sorted(a.answers("How far apart are the epipoles?").values()) == [2.5, 3.5]
    assert [r.name for r in a.roster()] == [r.name for r in b.roster()] == ["Ada", "Bob", "Cy"]


def test_the_instructors_mode_releases_the_students_of_every_worker(pair) -> None:
    _, (a, b), _ = pair
    a.instructor_join(0)
    b.join(1, "Bob")
    wait_for(lambda: global_tab(1, 1) in a.student_tabs(), "worker a to see Bob's tab")
    assert b.is_following(1)
    a.set_mode(Mode.EXPLORE)
    wait_for(lambda: not b.is_following(1), "worker b to release Bob")
    assert b.mode is Mode.EXPLORE
    a.pause("Eyes to the front")
    wait_for(lambda: b.paused() == "Eyes to the front", "worker b to see the pause")
    b.follow(1, True)  # the student rejoins follow on their own
    wait_for(lambda: a.is_following(global_tab(1, 1)), "worker a to see Bob follow again")


def test_a_worker_that_goes_takes_its_tabs_out_of_the_class(pair) -> None:
    hub, (a, b), (bus_a, bus_b) = pair
    b.join(3, "Bob")
    wait_for(lambda: global_tab(1, 3) in a.student_tabs(), "worker a to see Bob's tab")
    bus_b.close()
    wait_for(lambda: global_tab(1, 3) not in a.student_tabs(), "worker a to see Bob's tab gone with its worker")
    assert "Bob" in [r.name for r in a.roster()]  # the student stays in the roster (they may reconnect)
    assert "Bob" in hub.state()["students"]


def test_a_patch_carries_only_what_changed_and_applies_back() -> None:
    room = Classroom(None, token="t" * 20)
    before = normal(room.to_json())
    room.join(4, "Ada")
    room.pause(None)
    after = normal(room.to_json())
    patch = diff(before, after)
    assert set(patch["set"]) == set()
    assert patch["keys"] == {"students": {"set": {"Ada": None}, "del": []}}
    assert patch["tabs"]["set"] == {"4": ["Ada", True, None, None]}
    assert apply_patch(before, patch) == after
    after["tabs"][str(TAB_SPAN + 4)] = ["Bob", True, None, None]  # another worker's tab: not this one's to send
    assert str(TAB_SPAN + 4) not in diff(before, after)["tabs"]["set"]


def test_update_replaces_the_state_at_once_and_says_what_changed() -> None:
    import dataclasses

    from egtviz.classroom import ClassroomError, PauseChanged

    room = Classroom(None, token="t" * 20)
    heard = []
    room.subscribe(heard.append)
    room.update(lambda old: dataclasses.replace(old, pause="Eyes to the front"))
    assert room.paused() == "Eyes to the front"
    assert heard == [PauseChanged("Eyes to the front")]
    with pytest.raises(ClassroomError, match="expected a ClassState"):
        room.update(lambda old: None)
    assert room.paused() == "Eyes to the front"
