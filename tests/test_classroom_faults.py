"""The class under faults, on a real server with headless websocket tabs: an instructor whose tab goes away and
comes back keeps the class (its panel shows it as it was, and the followers follow the new tab's drags), and a
student who floods answers delays no other student's answer (the server's per-tab queue serves tabs in turn)."""

from __future__ import annotations

import dataclasses
import threading
import types

import msgspec
import numpy as np
import pytest
import viser
from websockets.sync.client import connect
from websockets.typing import Subprotocol

from egtviz.classroom import Mode
from egtviz.lessons import ProgressStore
from egtviz.viewer.classroom import host as host_module
from egtviz.viewer.classroom.host import ClassroomHost
from egtviz.viewer.classroom.links import INSTRUCTOR_PREFIX
from egtviz.viewer.server.guard import install_guards
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.server.viser_adapter import gizmo_moved_by_client, value_sent_by_client
from egtviz.viewer.tabs import EgtvizApp

from _class_course import watch_opened
from _waiting import PATIENCE, wait_for

LESSON = "02-pinhole-projection"
QUESTION = "How many points?"


class InstructorTab(FakeTab):
    """A headless tab on the instructor's URL (the token in the websocket's path, as the page connects)."""

    def __init__(self, port: int, token: str) -> None:  # noqa: D107 - as FakeTab, on another path
        self.ws = connect(f"ws://127.0.0.1:{port}{INSTRUCTOR_PREFIX}/{token}",
                          subprotocols=[Subprotocol(f"viser-v{viser.__version__}")], max_size=None,
                          open_timeout=PATIENCE)
        self.received = 0
        self.ws.send(msgspec.msgpack.encode({
            "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [0.0, -10.0, 3.0], "fov": 1.0,
            "near": 0.01, "far": 1000.0, "image_height": 720, "image_width": 1280, "look_at": [0.0, 0.0, 0.0],
            "up_direction": [0.0, 0.0, 1.0]}))
        self._thread = threading.Thread(target=self._drain, daemon=True)
        self._thread.start()


@pytest.fixture
def served(tmp_path, monkeypatch):
    monkeypatch.setattr(host_module, "NAME_TIMEOUT", 0.05)  # a headless tab keeps no name: ask it at once
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    install_guards(server)
    app = EgtvizApp(server, None, field_delay=0.0, course=True, progress=ProgressStore(tmp_path / "progress.db"))
    host = ClassroomHost(app)
    tabs: list[FakeTab] = []
    opened = watch_opened(host)

    def student(name: str) -> tuple[int, FakeTab]:
        before = set(server.get_clients())
        tabs.append(FakeTab(server.get_port()))
        wait_for(lambda: set(server.get_clients()) - before, f"{name}'s tab to connect")
        (cid,) = set(server.get_clients()) - before
        wait_for(lambda: cid in opened, f"{name}'s tab to be asked for a name it does not keep, then shown the "
                 "join page")
        host.join(server.get_clients()[cid], name)
        wait_for(lambda: cid in host.bars, f"{name} to join and get the student's bar")
        return cid, tabs[-1]

    def instructor() -> tuple[int, InstructorTab]:
        before = set(server.get_clients())
        tabs.append(InstructorTab(server.get_port(), host.room.instructor_token))
        wait_for(lambda: set(server.get_clients()) - before, "the instructor's tab to connect")
        (cid,) = set(server.get_clients()) - before
        wait_for(lambda: cid in host.panels and cid in app.views, "the instructor's panel and workbench")
        return cid, tabs[-1]

    yield types.SimpleNamespace(server=server, app=app, host=host, student=student, instructor=instructor)
    for t in tabs:
        t.close()
    host.close()
    server.stop()


def _drag(view, name: str, dx: float) -> None:
    """Drag camera ``name`` of a workbench view by ``dx`` metres along x, as viser delivers a gizmo message."""
    gizmo = view.scene3d.gizmo(name)
    gizmo_moved_by_client(gizmo, np.array(gizmo.position, float) + np.array([dx, 0.0, 0.0]))
    view.drag.camera_event(name, types.SimpleNamespace(target=gizmo, phase="update", client=None, client_id=None))


def test_an_instructor_who_disconnects_and_reconnects_keeps_the_class(served):
    host, app = served.host, served.app
    first, tab = served.instructor()
    follower_id, _ = served.student("Ada")
    wait_for(lambda: follower_id in host.followers, "Ada to follow the instructor")
    follower = host.followers[follower_id]
    _drag(app.views[first], "cam2", 0.5)
    wait_for(lambda: follower.frame is not None and follower.frame.version == host.room.shared().version,
             "the instructor's drag to reach the follower")
    room = host.room
    room.lock_cameras(True)
    room.pause("Back in five minutes")
    room.pace(LESSON, 1)
    room.ask(QUESTION)
    room.record_answer(follower_id, QUESTION, 8.0)
    shared, version = room.shared().scene, room.shared().version
    tab.close()  # the instructor's laptop drops off the network
    wait_for(lambda: not room.instructor_present() and first not in host.panels,
             "the class to see the instructor's tab gone")
    # The class carries on without them: the student still follows the room's scene, paused, locked, paced.
    assert room.is_following(follower_id) and host.followers.get(follower_id) is follower
    assert (room.mode, room.cameras_locked, room.paused()) == (Mode.FOLLOW, True, "Back in five minutes")
    second, _ = served.instructor()
    assert room.instructor_present() and room.is_instructor(second)
    assert app.views[second].model.scene is shared and room.shared().version == version  # where the room was
    panel = host.panels[second]
    panel.refresh()
    assert panel.lock.value is True and panel.follow_me.value is True
    assert panel.pause.label == "Resume every screen"
    assert f"{LESSON}: up to step 2" in panel.pacing.content
    assert 'data-n="1"' in panel.histogram.content and "1 connected · 1 following" in panel.status.content
    # The followers follow the new tab: its drag reaches them.
    before = follower.frame.version
    _drag(app.views[second], "cam2", -0.3)
    wait_for(lambda: follower.frame.version > before, "the new instructor tab's drag to reach the follower")
    assert np.array_equal(follower.frame.scene.camera("cam2").position,
                          app.views[second].model.scene.camera("cam2").position)


def test_a_click_whose_callback_waits_is_not_turned_around_by_a_refresh(served):
    """The instructor ticks "lock students' cameras" while a roster change refreshes the panel on another thread:
    viser has taken the box's new value and queued its callback; the refresh runs first. The click still locks."""
    cid, _ = served.instructor()
    host = served.host
    panel = host.panels[cid]
    for box, state in ((panel.lock, lambda: host.room.cameras_locked), (panel.show_names, host.room.names_shown)):
        assert box.value is False and not state()
        callbacks = value_sent_by_client(box, True)
        panel.refresh()  # the class has not changed: the box keeps the click's value
        assert box.value is True
        for callback in callbacks:
            callback(viser.GuiEvent(served.server.get_clients()[cid], cid, box))
        wait_for(state, "the click to reach the class")
        panel.refresh()
        assert box.value is True
    # A change of the class itself is still shown: unlocked from elsewhere, the box is cleared.
    host.room.lock_cameras(False)
    wait_for(lambda: panel.lock.value is False, "the panel to show the class unlocked")


def test_a_frame_sent_while_a_followers_tab_is_built_reaches_it(served, monkeypatch):
    """The instructor's drag makes a frame while a joining student's follow view is being built: the sender shows
    it to the followers it knows, not yet to this one; the new follower is shown it once registered."""
    host = served.host
    served.instructor()
    wait_for(lambda: host.sender.latest is not None, "the instructor's first frame")
    first = host.sender.latest
    built = host_module.FollowView
    posted = []

    def built_while_the_room_moves(*args, **kwargs):
        view = built(*args, **kwargs)
        sent = host.sender.sent
        newer = dataclasses.replace(host.sender.latest, number=host.sender.next_number())
        host.sender.post(newer)
        wait_for(lambda: host.sender.sent > sent, "the sender to send the newer frame to the followers it knows")
        posted.append(newer)
        return view

    monkeypatch.setattr(host_module, "FollowView", built_while_the_room_moves)
    cid, _ = served.student("Ada")
    wait_for(lambda: cid in host.followers, "Ada to follow")
    assert posted[0].number > first.number
    # At least that frame (the instructor's tab may draw again meanwhile on a busy machine: a newer one is shown).
    wait_for(lambda: host.followers[cid].frame.number >= posted[0].number, "the frame posted while Ada's tab was "
             "built to reach Ada")


FLOOD = 3000


def test_a_flood_of_answers_from_one_student_delays_no_other_student(served):
    host = served.host
    host.room.set_mode(Mode.EXPLORE)
    flooder_id, flooder = served.student("Flo")
    other_id, other = served.student("Bo")
    host.room.ask(QUESTION)
    wait_for(lambda: host.bars[flooder_id].question == QUESTION and host.bars[other_id].question == QUESTION,
             "both students' bars to show the question")
    order: list[tuple[int, object]] = []
    record = host.room.record_answer

    def recorded(tab, question, value):
        order.append((tab, value))
        return record(tab, question, value)

    host.room.record_answer = recorded  # the order answers reach the class
    bar = host.bars[flooder_id]
    for k in range(FLOOD):  # as fast as the socket takes them: a text and a click each
        flooder.send("GuiUpdateMessage", uuid=bar.answer._impl.uuid, updates={"value": str(k)})
        flooder.send("GuiUpdateMessage", uuid=bar.btn_answer._impl.uuid, updates={"value": True})
    other_bar = host.bars[other_id]
    before = sum(t == flooder_id for t, _ in order)  # the flood's answers handled while it was being sent
    assert before < FLOOD // 2  # most of the flood is still to be handled when the other student answers
    other.send("GuiUpdateMessage", uuid=other_bar.answer._impl.uuid, updates={"value": "42"})
    other.send("GuiUpdateMessage", uuid=other_bar.btn_answer._impl.uuid, updates={"value": True})
    wait_for(lambda: (other_id, 42.0) in order, "the other student's answer to reach the class")
    ahead = sum(t == flooder_id for t, _ in order[:order.index((other_id, 42.0))]) - before
    # Served in turn: the other student's answer does not wait for the rest of the flood (a first-come queue
    # would run every answer of the flood already read before it).
    assert ahead < (FLOOD - before) // 2, (before, ahead)
    # Latest wins: the flooder's last answer is the one the class keeps, whatever was merged on the way.
    wait_for(lambda: host.room.answers(QUESTION).get("Flo") == float(FLOOD - 1),
             "the flooder's last answer to be the one the class keeps")
    assert host.room.answers(QUESTION)["Bo"] == 42.0
