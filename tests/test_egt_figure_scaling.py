"""EGT's figures at scale: drawings over the limit are refused before any work per item, the duplicate check is
the one of before on small inputs, and draw calls with tabs open only record the figure (one background thread
pushes the latest state to the tabs, a burst as a few pushes).

"Work per item" is counted as Python lines executed during the drawing (``sys.settrace``): a check that goes
point by point runs at least one line per point; the refusal at the limit runs a fixed number.
"""

from __future__ import annotations

import sys
import threading
import time
import types

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import egtviz.egt_figure as ef
from egtviz.egt import eye, f_3Dframe, f_epipline, f_epipole, f_panproj, f_perspproj, f_Rt2H, f_scenepnt, rotoz
from egtviz.egt_figure import _builder
from egtviz.egt_figure._publisher import COALESCE_SECONDS, Publisher
from egtviz.egt_figure._server import FigureServer, on_cell_end
from egtviz.scene.annotations import Annotations
from egtviz.scene.limits import MAX_PLOT_ITEMS

from _waiting import PATIENCE

K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])
H = f_Rt2H(eye(3), [0.0, -5.0, 0.0])


@pytest.fixture(autouse=True)
def headless_figures(monkeypatch):
    monkeypatch.setenv("EGTVIZ_FIGURE", "off")
    ef.reset()
    yield
    ef.stop_server()
    ef.reset()


def _points_in_front(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    P = rng.uniform(-1.0, 1.0, (3, n))
    P[1] += 5.0  # in front of the camera at y = -5 looking along +y
    return P


def _python_lines(fn, *args) -> int:
    """Python lines executed while ``fn(*args)`` runs (a loop over the points runs at least one per point)."""
    lines = 0

    def trace(frame, event, arg):
        nonlocal lines
        if event == "line":
            lines += 1
        return trace

    sys.settrace(trace)
    try:
        fn(*args)
    finally:
        sys.settrace(None)
    return lines


# -- item 1: the drawing limit before any work per item ------------------------------------------------------


@pytest.mark.parametrize("n", [5000, 1_000_000])
def test_f_perspproj_plot_over_the_limit_is_refused_without_work_per_point(n):
    P = _points_in_front(n, seed=1)
    with pytest.warns(RuntimeWarning, match=rf"image_points: not drawn \(plot points: expected 0 to 2000 entries, "
                                            rf"got {n}\)"):
        lines = _python_lines(f_perspproj, P, H, K, 1)
    assert lines < 2000  # far fewer than one per point
    scene = ef.current_figure().scene()
    assert [len(p.points) for p in scene.annotations.plots] == []  # the figure is as it was


def test_a_plot_at_the_limit_is_drawn_and_one_more_point_is_refused():
    P = _points_in_front(MAX_PLOT_ITEMS, seed=2)
    U = f_perspproj(P, H, K, 1)
    (plot,) = ef.current_figure().scene().annotations.plots
    np.testing.assert_array_equal(np.array(plot.points), U.T)
    f_perspproj(P, H, K, 1)  # the same points again: nothing new, still within the limit
    assert len(ef.current_figure().scene().annotations.plots[0].points) == MAX_PLOT_ITEMS
    with pytest.warns(RuntimeWarning, match="got 2001"):
        f_perspproj(_points_in_front(1, seed=3), H, K, 1)
    assert len(ef.current_figure().scene().annotations.plots[0].points) == MAX_PLOT_ITEMS


def test_points_drawn_many_times_over_count_once_against_the_limit():
    P = np.tile(_points_in_front(10, seed=4), 500)  # 5000 columns, 10 different points
    U = f_perspproj(P, H, K, 1)
    (plot,) = ef.current_figure().scene().annotations.plots
    np.testing.assert_array_equal(np.array(plot.points), U[:, :10].T)


def test_f_epipline_plot_over_the_limit_is_refused_without_work_per_line():
    H1, H2 = f_Rt2H(rotoz(0.3), [-1.0, -5.0, 0.0]), f_Rt2H(eye(3), [0.0, -5.0, 0.0])
    P = _points_in_front(6000, seed=5)
    U1, U2 = f_perspproj(P, H1, K), f_perspproj(P, H2, K)
    _, _, F = f_epipole(H1, H2, K, K)
    with pytest.warns(RuntimeWarning, match=r"epipolar_lines: not drawn \(plot points: expected 0 to 2000"):
        lines = _python_lines(f_epipline, U1, U2, F, 1, 1, 2)
    assert lines < 3000
    assert ef.current_figure().scene().annotations.plots == ()


def test_scene_points_and_panoramic_points_over_the_limit_are_refused_without_work_per_point():
    P = np.random.default_rng(6).uniform(-3.0, 3.0, (3, 200_000))
    with pytest.warns(RuntimeWarning, match=r"world_points: not drawn \(points: at most 2000, got 200000\)"):
        assert _python_lines(f_scenepnt, P) < 2000
    with pytest.warns(RuntimeWarning, match=r"panoramic_points: not drawn \(point set points: expected 1 to 2000"):
        assert _python_lines(f_panproj, P + np.array([[0.0], [0.0], [5.0]]), np.eye(4), None, 3, 1, 1, "r") < 4000
    assert ef.current_figure().scene().points == ()


@pytest.mark.parametrize("kind, data, message", [
    ("projection_rays", dict(points=np.ones((3, 50_000)), centre=np.zeros(3)), "polylines: expected 0 to 2000"),
    ("scene_points", dict(points=np.ones((3, 50_000))), "point set points: expected 1 to 2000"),
    ("numbered_points", dict(points=np.ones((3, 50_000))), "point set points: expected 1 to 2000"),
    ("line3d", dict(points=np.ones((3, 50_000))), "polyline points: expected 2 to 2000"),
    ("sphere_model", dict(H=np.eye(4), ell=1.0, m=1.0, points=np.ones((3, 50_000)),
                          sphere_points=np.ones((3, 50_000))), "point set points: expected 1 to 2000"),
    ("surface", dict(x=np.ones((300, 300)), y=np.ones((300, 300)), z=np.ones((300, 300))),
     "meshes: at most 20000 vertices in all, got 90000"),
])
def test_every_kind_over_its_limit_is_refused_without_work_per_item(kind, data, message):
    with pytest.warns(RuntimeWarning, match=rf"{kind}: not drawn \({message}"):
        assert _python_lines(lambda: ef.draw(kind, **data)) < 1500
    scene = ef.current_figure().scene()
    assert scene.points == () and scene.annotations == Annotations(messages=scene.annotations.messages)


def _add_points_before(points: list, P: np.ndarray) -> None:
    """The duplicate check of before (quadratic), kept as the oracle of what a plot draws."""
    have = np.array(points).reshape(-1, 2)
    for p in P:
        if not len(have) or not np.any(np.all(np.abs(have - p) <= 1e-9 * (1.0 + np.abs(p)), axis=1)):
            points.append((float(p[0]), float(p[1])))
            have = np.array(points).reshape(-1, 2)


_coordinate = st.sampled_from([0.0, -0.0, 1.0, 3.5, -2.25, 1e-12, 640.0, 1e6, -1e9])
_nudge = st.sampled_from([0.0, 1e-10, -1e-10, 5e-10, 1e-9, 2e-9, 1e-6])


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(_coordinate, _coordinate, _nudge, _nudge), max_size=40),
       st.integers(min_value=0, max_value=40))
def test_the_duplicate_check_draws_what_it_drew_before(rows, split):
    """Near-equal pixels (within, at and beyond the 1e-9 relative tolerance) merge exactly as before."""
    P = np.array([(x * (1 + dx) + dx, y * (1 + dy) + dy) for x, y, dx, dy in rows], dtype=float).reshape(-1, 2)
    first, second = P[:split], P[split:]
    expected: list = []
    _add_points_before(expected, first)
    _add_points_before(expected, second)
    plot = _builder._PlotState(1)
    plot.add_points(first)
    plot.add_points(second)
    assert plot.points == expected
    for part in (first, second):
        have = np.array(expected).reshape(-1, 2)
        before = bool(len(have)) and bool(len(part)) and all(
            np.any(np.all(np.abs(have - p) <= 1e-9 * (1.0 + np.abs(p)), axis=1)) for p in part)
        assert plot.holds(part) == before


# -- item 2: draw calls record, one thread pushes ------------------------------------------------------------


class _CountingServer:
    """A figure server with ``tabs`` fake tabs: each push costs ``cost`` seconds per tab and is recorded."""

    tabs = 3
    cost = 0.03
    made: list[_CountingServer] = []

    def __init__(self, port=None) -> None:
        self.url = "http://127.0.0.1:1"
        self.shown: list[list] = [[] for _ in range(self.tabs)]
        self.threads: set[str] = set()
        _CountingServer.made.append(self)

    def show(self, scene) -> None:
        self.threads.add(threading.current_thread().name)
        for tab in self.shown:
            time.sleep(self.cost)
            tab.append(scene)

    def catch_up(self) -> None:
        pass

    def stop(self) -> None:
        pass


def _most_pushes(drawing_s: float, push_s: float) -> float:
    """The most pushes a burst of drawings that took ``drawing_s`` seconds can cost when each push takes at least
    ``push_s`` seconds: one push at a time, each after the coalescing wait (the rest after a push only adds to
    that), and the flush at the end pushes once more. Figures of this run, not a constant that a busy machine,
    slower at drawing than at pushing, might overrun; without coalescing there would be a push per drawing."""
    return 2 + drawing_s / (COALESCE_SECONDS + push_s)


def test_a_burst_of_draw_calls_is_a_few_pushes_per_tab_and_the_tabs_end_with_the_last_state(monkeypatch):
    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    monkeypatch.setattr(ef, "FigureServer", _CountingServer)
    _CountingServer.made.clear()
    t0 = time.monotonic()
    for k in range(300):
        f_3Dframe(f_Rt2H(rotoz(0.01 * k), [0.01 * k, 0.0, 0.0]), "r", 0.5)
    drawing_s = time.monotonic() - t0
    assert ef.flush(PATIENCE)
    (server,) = _CountingServer.made
    final = ef.current_figure().scene()
    assert len(final.annotations.frames) == 300
    for tab in server.shown:
        # 300 drawings, far fewer pushes: a push takes 90 ms (three tabs), however long the 300 calls took here.
        assert 1 <= len(tab) <= _most_pushes(drawing_s, _CountingServer.tabs * _CountingServer.cost), (
            len(tab), drawing_s)
        assert tab[-1] == final
    assert server.threads == {"egtviz-figure-publisher"}  # never in the script's thread


def test_figure_switches_and_show_leave_the_tabs_on_the_current_figure(monkeypatch):
    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    monkeypatch.setattr(ef, "FigureServer", _CountingServer)
    _CountingServer.made.clear()
    f_scenepnt(np.array([[0.0, 0.0, 1.0]]).T)
    ef.figure(2)
    f_scenepnt(np.array([[1.0, 2.0, 3.0]]).T)
    ef.show(wait=False)  # the end of a script: the tabs are current when it returns
    (server,) = _CountingServer.made
    assert all(tab[-1].title == "Figure 2" and tab[-1].points == ((1.0, 2.0, 3.0),) for tab in server.shown)


def test_in_a_notebook_the_inline_page_opens_on_the_figure_and_cells_end_with_a_flush(monkeypatch):
    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    monkeypatch.setattr(ef, "FigureServer", _CountingServer)
    monkeypatch.setattr(ef, "in_jupyter", lambda: True)
    cell_end = []
    monkeypatch.setattr(ef, "on_cell_end", cell_end.append)
    inline = []
    monkeypatch.setattr(ef, "show_inline",
                        lambda url: inline.append((url, [tab[-1] for tab in _CountingServer.made[0].shown])))
    _CountingServer.made.clear()
    f_scenepnt(np.array([[0.0, 0.0, 1.0]]).T)
    (server,) = _CountingServer.made
    first = ef.current_figure().scene()
    f_scenepnt(np.array([[1.0, 0.0, 1.0]]).T)
    assert inline == [("http://127.0.0.1:1", [first] * 3)]  # once, when every tab already shows the figure
    (flush_at_cell_end,) = cell_end
    flush_at_cell_end(None)  # IPython's post_run_cell passes the cell's result
    assert all(tab[-1] == ef.current_figure().scene() for tab in server.shown)


def test_the_publisher_pushes_the_latest_state_and_flush_waits_for_it():
    shown: list[int] = []
    pushing = threading.Event()
    gate = threading.Event()

    def show(state):
        pushing.set()
        assert gate.wait(PATIENCE), "the test never opened the gate"
        shown.append(state)

    publisher = Publisher(show, coalesce=0.0)
    try:
        publisher.submit(1)
        assert pushing.wait(PATIENCE), "the publisher never began the first push"  # held at the gate
        for k in range(2, 101):
            publisher.submit(k)
        gate.set()
        assert publisher.flush(PATIENCE)
        assert shown == [1, 100]  # states 2..99 were replaced before they were pushed
    finally:
        publisher.close()


def test_a_push_that_fails_does_not_stop_later_pushes(capsys):
    shown = []

    def show(state):
        if state == "bad":
            raise RuntimeError("tab gone")
        shown.append(state)

    publisher = Publisher(show, coalesce=0.0)
    try:
        publisher.submit("bad")
        assert publisher.flush(PATIENCE)
        publisher.submit("good")
        assert publisher.flush(PATIENCE)
    finally:
        publisher.close()
    assert shown == ["good"]
    assert "tabs were not updated (RuntimeError: tab gone)" in capsys.readouterr().err


def test_notebook_cells_flush_at_their_end():
    registered = []
    events = types.SimpleNamespace(register=lambda name, cb: registered.append((name, cb)))
    shell = types.SimpleNamespace(kernel=object(), events=events)
    callback = lambda *_: None  # noqa: E731
    assert on_cell_end(callback, {"IPython": types.SimpleNamespace(get_ipython=lambda: shell)}) is True
    assert registered == [("post_run_cell", callback)]
    assert on_cell_end(callback, {}) is False


class _FakeView:
    def __init__(self, scene) -> None:
        self.model = types.SimpleNamespace(scene=scene, load_scene=self.load)
        self.loads = 0

    def load(self, scene) -> None:
        self.model.scene = scene
        self.loads += 1


def test_a_tab_that_opens_during_a_push_is_brought_up_to_date():
    late: list[_FakeView] = []

    def show_scene(scene):
        for view in list(app.views.values()):
            view.load(scene)
        # A tab built on the scene before this push, registered after the loop above listed the tabs.
        app.views[2] = late_view = _FakeView("old")
        late.append(late_view)

    app = types.SimpleNamespace(views={1: _FakeView("old")}, show_scene=show_scene)
    server = FigureServer(viewer=(types.SimpleNamespace(get_port=lambda: 1), app))
    server.show("new")
    assert app.views[1].model.scene == "new" and late[0].model.scene == "old"
    server.catch_up()
    assert late[0].model.scene == "new" and late[0].loads == 1
    server.catch_up()
    assert app.views[1].loads == 1 and late[0].loads == 1  # each tab is given the scene once


def test_the_publisher_settles_a_while_after_the_last_push():
    settled = threading.Event()
    publisher = Publisher(lambda state: None, coalesce=0.0, settle=settled.set)
    try:
        assert not settled.wait(0.2)  # nothing pushed yet: nothing to settle (a time only a wrong settle can fail)
        publisher.submit(1)
        assert settled.wait(PATIENCE)
    finally:
        publisher.close()


def test_real_tabs_get_few_pushes_and_end_with_the_last_state(monkeypatch):
    from egtviz.egt_figure import _server
    from egtviz.viewer.server.headless import FakeTab

    monkeypatch.setenv("EGTVIZ_FIGURE", "on")
    monkeypatch.setattr(_server, "FIRST_PORT", 0)
    ef.figure(1)
    server = ef.figure_server()
    tabs = [FakeTab(server.server.get_port()) for _ in range(2)]
    try:
        views = server.app.wait_for_view(count=2, timeout=PATIENCE)
        assert ef.flush(PATIENCE)
        publisher = ef._publisher
        push_s: list[float] = []
        show = publisher._show

        def timed(scene):
            t = time.perf_counter()
            show(scene)
            push_s.append(time.perf_counter() - t)

        monkeypatch.setattr(publisher, "_show", timed)  # the time of each push to the real tabs, on this machine
        loads = {id(v): 0 for v in views}
        for v in views:
            original = v.model.load_scene

            def counted(scene, _v=v, _original=original):
                loads[id(_v)] += 1
                return _original(scene)

            monkeypatch.setattr(v.model, "load_scene", counted)
        t0 = time.monotonic()
        for k in range(100):
            f_3Dframe(f_Rt2H(rotoz(0.01 * k), [0.01 * k, 0.0, 0.0]), "r", 0.5)
        drawing_s = time.monotonic() - t0
        assert ef.flush(PATIENCE)
        final = ef.current_figure().scene()
        for v in views:
            # 100 drawings, far fewer pushes: as many as the pushes' own time and rests allow while they were drawn.
            assert 1 <= loads[id(v)] <= _most_pushes(drawing_s, min(push_s)), (loads[id(v)], drawing_s, push_s)
            assert v.model.scene.annotations.frames == final.annotations.frames
    finally:
        for tab in tabs:
            tab.close()
