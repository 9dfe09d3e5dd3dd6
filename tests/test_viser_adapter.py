"""The viser adapter: the one place that uses viser's private handle internals. These tests fail when the installed
viser changes them (a name goes, or the fast path no longer sends what viser's own assignment sends)."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from egtviz.viewer.server import viser_adapter
from egtviz.viewer.server.viser_adapter import (
    PRIVATE_NAMES,
    assign,
    assign_array,
    missing_internals,
)


@pytest.fixture
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def test_the_installed_viser_has_every_private_name_the_adapter_uses(server):
    api = server.scene
    handles = [
        api.add_line_segments("/a", np.zeros((1, 2, 3), np.float32), (0, 0, 0)),
        api.add_point_cloud("/b", np.zeros((1, 3), np.float32), (0, 0, 0), point_size=0.1),
        api.add_mesh_simple("/c", np.zeros((3, 3), np.float32), np.array([[0, 1, 2]], np.uint32)),
    ]
    for h in handles:
        assert missing_internals(h) == [], f"viser {viser.__version__} changed: {missing_internals(h)}"
    assert viser_adapter.FAST_PATH
    # A handle without them is reported name by name (what a changed viser would look like).
    assert missing_internals(object()) == list(PRIVATE_NAMES)


class CountingHandle:
    """Stands for a handle: counts the assignments that reach it."""

    def __init__(self) -> None:
        self.__dict__["sent"] = []

    def __setattr__(self, name, value):
        self.sent.append(name)
        self.__dict__[name] = value


def test_assign_skips_equal_values_and_sends_changed_ones():
    h = CountingHandle()
    assign(h, "visible", False)
    assign(h, "visible", False)
    assign(h, "position", np.array([1.0, 2.0, 3.0]))
    assign(h, "position", np.array([1.0, 2.0, 3.0]))
    assign(h, "position", np.array([1.0, 2.0, 4.0]))
    assert h.sent == ["visible", "position", "position"]
    assert h.visible is False and np.array_equal(h.position, (1.0, 2.0, 4.0))


def test_array_assignment_matches_viser_own(server):
    api = server.scene
    rng = np.random.default_rng(0)
    for kind in ("segments", "cloud"):
        if kind == "segments":
            make = lambda name: api.add_line_segments(name, np.zeros((1, 2, 3), np.float32), (0, 0, 0))
            pts = rng.normal(size=(7, 2, 3)).astype(np.float32)
        else:
            make = lambda name: api.add_point_cloud(name, np.zeros((1, 3), np.float32), (0, 0, 0), point_size=0.1)
            pts = rng.normal(size=(7, 3)).astype(np.float32)
        ours, theirs = make(f"/ours_{kind}"), make(f"/theirs_{kind}")
        queued: dict = {"ours": [], "theirs": []}
        for key, h in (("ours", ours), ("theirs", theirs)):
            original = h._queue_update
            h._queue_update = lambda name, value, key=key, original=original, queued=queued: (
                queued[key].append((name, value)), original(name, value))
        cols = rng.integers(0, 255, size=pts.shape, dtype=np.uint8)
        for value in (pts, pts, pts * 2):  # the second is unchanged: nothing queued
            for prop, v in (("points", value), ("colors", cols)):
                theirs.__setattr__(prop, v)
                assign_array(ours, prop, v)
        assert [n for n, _ in queued["ours"]] == [n for n, _ in queued["theirs"]]
        for (_, a), (_, b) in zip(queued["ours"], queued["theirs"]):
            assert a.dtype == b.dtype and np.array_equal(a, b)
        for prop in ("points", "colors"):
            a, b = getattr(ours._impl.props, prop), getattr(theirs._impl.props, prop)
            assert a.dtype == b.dtype and np.array_equal(a, b)
            assert not any(a is v for _, v in queued["ours"])  # the node's array is not the queued one
        pts[:] = 0  # the caller's array is not kept either
        assert not np.array_equal(ours._impl.props.points, pts.reshape(ours._impl.props.points.shape))
    ours.remove()
    with pytest.raises(RuntimeError, match="removed"):
        assign_array(ours, "points", np.ones((2, 3), np.float32))




def test_the_installed_viser_has_the_server_and_gizmo_internals_the_benchmarks_use(server):
    assert viser_adapter.missing_server_internals(server) == []
    assert viser_adapter.event_loop(server).is_running()
    assert hasattr(viser_adapter.callback_pool(server), "submit")
    gizmo = server.scene.add_transform_controls("/g")
    assert viser_adapter.missing_gizmo_internals(gizmo) == []
    viser_adapter.gizmo_moved_by_client(gizmo, np.array([1.0, 2.0, 3.0]))
    assert np.allclose(gizmo.position, (1.0, 2.0, 3.0))
    box = server.gui.add_checkbox("box", False)
    seen = []
    box.on_update(lambda e: seen.append(e.target.value))
    assert viser_adapter.missing_input_internals(box) == []
    (callback,) = viser_adapter.value_sent_by_client(box, True)
    assert box.value is True and seen == []  # the value taken, the callback not yet run
    # Objects without them are reported name by name (what a changed viser would look like).
    assert viser_adapter.missing_server_internals(object()) == list(viser_adapter.SERVER_PRIVATE_NAMES)
    assert viser_adapter.missing_gizmo_internals(object()) == list(viser_adapter.GIZMO_PRIVATE_NAMES)
    assert viser_adapter.missing_input_internals(object()) == list(viser_adapter.INPUT_PRIVATE_NAMES)
