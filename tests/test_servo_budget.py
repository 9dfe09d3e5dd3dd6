"""The server's budget of servo-run frames (egtviz.controllers.servo_budget) and the demos that reserve from it.

Demos run on a real viser server with websocket stand-ins (FakeTab) as tabs; a small budget stands for the
server's (the same code, fewer frames), so runs of a few dozen steps fill it.
"""

from __future__ import annotations

import gc
import re
import threading

import pytest
import viser

from egtviz.scene.limits import SERVO_DEMO_STEPS, SERVO_SERVER_FRAMES
from egtviz.viewer.server.headless import FakeTab
from egtviz.controllers.servo_budget import SERVER_BUDGET, ServoBudget, ServoBusy
from egtviz.viewer.servo.servo_demo import make_servo_demo

from _threads import joined
from _waiting import PATIENCE, wait_for

STEPS = 40
"""Steps of the test runs: too few for the pin-hole demo to converge, so each run has STEPS + 1 frames."""


@pytest.fixture(scope="module")
def clients():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    got = []
    server.on_client_connect(got.append)
    tabs = [FakeTab(server.get_port()) for _ in range(3)]
    wait_for(lambda: len(got) == 3, "the 3 headless tabs to connect")
    yield got
    for tab in tabs:
        tab.close()
    server.stop()


@pytest.fixture
def notes(clients, monkeypatch):
    got: dict[int, list[tuple[str, str]]] = {i: [] for i in range(len(clients))}
    for i, client in enumerate(clients):
        monkeypatch.setattr(client, "add_notification",
                            lambda title, body, _i=i, **kw: got[_i].append((title, body)))
    return got


def test_the_budget_refuses_what_does_not_fit_and_frees_on_release():
    budget = ServoBudget(frames=100, queue_seconds=0.0)
    a, b, c = object.__new__(type("A", (), {})), object.__new__(type("B", (), {})), object.__new__(type("C", (), {}))
    budget.reserve(a, 60)
    budget.reserve(b, 40)
    with pytest.raises(ServoBusy, match=r"^The server is busy with 2 other servo runs \(100 of its 100 frames\); "
                                        r"this run needs up to 1\. Try again in a moment, or with fewer max steps\.$"):
        budget.reserve(c, 1)
    assert budget.held(c) == 0 and budget.held() == 100  # a refusal changes nothing
    budget.reserve(a, 30)  # a's next run replaces its last one
    budget.reserve(c, 30)
    with pytest.raises(ServoBusy, match="busy with 2 other servo runs"):
        budget.reserve(b, 41)  # b's own 40 count as free for its next run, a's and c's 60 do not
    budget.shrink(b, 10)
    budget.shrink(b, 99)  # never grows
    assert budget.held(b) == 10 and budget.held() == 70
    budget.release(a)
    budget.release(a)
    assert budget.held() == 40
    del c
    gc.collect()
    assert budget.held() == 10  # an owner that is garbage holds nothing


def test_the_server_budget_is_the_named_limit():
    assert SERVER_BUDGET.frames == SERVO_SERVER_FRAMES == 2 * (SERVO_DEMO_STEPS.high + 1)  # two runs at the bound


def test_a_run_that_does_not_fit_waits_for_frames_and_is_told_why():
    budget = ServoBudget(frames=100, queue_seconds=30.0)
    a, b = object.__new__(type("A", (), {})), object.__new__(type("B", (), {}))
    budget.reserve(a, 100)
    told: list[str] = []
    got = threading.Event()

    def wait_for_frames():
        budget.reserve(b, 60, waiting=told.append)
        got.set()

    thread = threading.Thread(target=wait_for_frames)
    thread.start()
    wait_for(lambda: told, "the waiting run to be told why it waits")
    assert told == ["The server is busy with 1 other servo run (100 of its 100 frames); this "
                    "run needs up to 60; it waits up to 30 s for them."]
    assert not got.is_set() and budget.held(b) == 0  # it waits: nothing reserved for it yet
    budget.shrink(a, 40)  # a's run converged early: the waiting run fits
    assert got.wait(PATIENCE) and budget.held(b) == 60
    joined(thread, "the waiting run's thread")
    closed = threading.Event()
    errors = []

    def cancelled_wait():
        try:
            budget.reserve(object.__new__(type("C", (), {})), 60, cancelled=closed.is_set)
        except ServoBusy as exc:
            errors.append(str(exc))

    thread = threading.Thread(target=cancelled_wait)
    thread.start()
    closed.set()  # its tab closed
    joined(thread, "the cancelled wait to end")
    assert "busy with 2 other servo runs" in errors[0]


def test_a_third_run_over_the_budget_is_refused_in_its_tab_and_runs_once_another_closes(clients, notes):
    budget = ServoBudget(frames=2 * (STEPS + 1), queue_seconds=0.0)
    demos = []
    try:
        for client in clients[:2]:
            demo = make_servo_demo(client, "pinhole", steps=STEPS, autoplay=False, budget=budget)
            demos.append(demo)
            assert demo.wait(PATIENCE) and demo.result is not None and demo.result.n_samples == STEPS + 1
        third = make_servo_demo(clients[2], "pinhole", steps=STEPS, autoplay=False, budget=budget)
        demos.append(third)
        assert third.wait(PATIENCE) and not third.running and third.result is None  # refused: nothing simulated
        assert not third.form.btn_run.disabled
        assert notes[2] == [("Server busy", notes[2][0][1])]
        assert re.search(r"busy with 2 other servo runs .*Try again in a moment", notes[2][0][1])
        assert "busy with 2 other servo runs" in third.form.status.content
        assert notes[0] == notes[1] == []  # the other tabs are not told anything
        assert budget.held() == 2 * (STEPS + 1)
        demos[0].close()  # a tab closes: its frames are free
        assert budget.held() == STEPS + 1
        assert third.run(wait=True, timeout=PATIENCE) and third.result is not None and third.result.n_samples == STEPS + 1
        assert budget.held() == 2 * (STEPS + 1)
    finally:
        for demo in demos:
            demo.close()
    assert budget.held() == 0


def test_a_run_replaced_by_a_shorter_one_or_failing_frees_its_frames(clients, notes, monkeypatch):
    from egtviz.controllers import servo_demos

    budget = ServoBudget(frames=STEPS + 1)
    demo = make_servo_demo(clients[0], "pinhole", steps=STEPS, autoplay=False, budget=budget)
    try:
        assert demo.wait(PATIENCE) and budget.held(demo) == STEPS + 1
        demo.set_params(steps=10)
        assert demo.run(wait=True, timeout=PATIENCE) and budget.held(demo) == 11  # the new run replaced the old one's frames

        def refuse(**kw):
            raise ValueError("the simulation refused it")

        monkeypatch.setattr(servo_demos, "simulate_pinhole", refuse)
        assert demo.run(wait=True, timeout=PATIENCE) and demo.result is None and budget.held(demo) == 0
    finally:
        demo.close()


def test_a_converged_run_keeps_only_the_frames_it_has(clients):
    budget = ServoBudget(frames=SERVO_DEMO_STEPS.high + 1)
    demo = make_servo_demo(clients[0], "pinhole", steps=SERVO_DEMO_STEPS.high, autoplay=False, budget=budget)
    try:
        assert demo.wait(PATIENCE) and demo.result is not None and demo.result.converged
        assert budget.held(demo) == demo.result.n_samples < SERVO_DEMO_STEPS.high
    finally:
        demo.close()


def test_the_lessons_measured_runs_are_cached_within_the_frame_budget(monkeypatch):
    from egtviz.lessons import servo_runs

    simulated = []
    real = servo_runs.simulate_pinhole
    monkeypatch.setattr(servo_runs, "simulate_pinhole", lambda **kw: simulated.append(kw["seed"]) or real(**kw))
    monkeypatch.setattr(servo_runs, "_RUNS", servo_runs._RunCache(samples=2 * (STEPS + 1)))
    runs = [servo_runs.DemoRun("pinhole", (("seed", seed), ("steps", STEPS))) for seed in range(3)]
    first = servo_runs.simulate(runs[0])
    assert servo_runs.simulate(runs[0]) is first and simulated == [0]  # cached
    servo_runs.simulate(runs[1])
    servo_runs.simulate(runs[2])  # three runs do not fit: the oldest is dropped
    assert simulated == [0, 1, 2]
    again = servo_runs.simulate(runs[0])
    assert simulated == [0, 1, 2, 0] and again is not first
    assert again.time.tolist() == first.time.tolist()  # simulated again, the same run
    servo_runs.simulate(runs[2])
    assert simulated == [0, 1, 2, 0]  # the newest are kept


def test_a_queued_run_says_so_and_runs_when_another_tab_closes(clients, notes):
    budget = ServoBudget(frames=2 * (STEPS + 1) - 1, queue_seconds=30.0)
    first = make_servo_demo(clients[0], "pinhole", steps=STEPS, autoplay=False, budget=budget)
    second = None
    try:
        assert first.wait(PATIENCE) and first.result is not None
        second = make_servo_demo(clients[1], "pinhole", steps=STEPS, autoplay=False, budget=budget)
        wait_for(lambda: "Queued" in second.form.status.content, "the second run to say it is queued")
        assert "Queued: The server is busy with 1 other servo run" in second.form.status.content
        assert second.running and second.result is None
        first.close()
        assert second.wait(PATIENCE) and second.result is not None and second.result.n_samples == STEPS + 1
        assert notes[1] == []  # queued, not refused
    finally:
        first.close()
        if second is not None:
            second.close()
    assert budget.held() == 0
