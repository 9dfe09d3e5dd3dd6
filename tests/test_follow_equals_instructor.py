"""A follower sees exactly what the instructor's tab shows after drags of one camera, then the other, then a
change of the point count: the same SVG strings in its panels and read-out, the same value in every 3D node."""

from __future__ import annotations

import numpy as np
import pytest
import viser

from egtviz.scene import SceneModel, default_scene
from egtviz.scene.extent import scene_extent
from egtviz.viewer.classroom.follow_view import FollowView
from egtviz.viewer.classroom.room_sender import frame_from_scene
from egtviz.viewer.server.headless import FakeTab
from egtviz.viewer.workbench.scene3d import Scene3D

from _waiting import wait_for

FOLLOWERS = 3
_PROPS = ("points", "colors", "vertices", "faces", "position", "wxyz", "visible", "text", "fov", "aspect", "scale")


@pytest.fixture
def clients():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tabs = [FakeTab(server.get_port()) for _ in range(FOLLOWERS + 1)]
    wait_for(lambda: len(server.get_clients()) == len(tabs), f"the {len(tabs)} headless tabs to connect")
    found = [c for _, c in sorted(server.get_clients().items())]
    assert len(found) == len(tabs)
    yield found
    for tab in tabs:
        tab.close()
    server.stop()


def _handles(s3: Scene3D) -> dict[str, object]:
    """Every node a drag or a point count can change, by a name that does not depend on the tab."""
    out: dict[str, object] = {"points": s3.points, "selected": s3.selected, "baseline": s3.baseline,
                              "epiplane": s3.epiplane, "surfaces": s3.surfaces}
    for name, nodes in s3.every_camera_nodes().items():
        for key in ("gizmo", "axes", "label"):
            out[f"{name}/{key}"] = nodes[key]
        for key, handle in nodes.drawing.named_nodes().items():
            out[f"{name}/{key}"] = handle
        out[f"{name}/rays"] = s3._rays[name]
    for i, label in enumerate(s3._point_labels):
        out[f"plabel{i}"] = label
    for i, gizmo in s3._point_gizmos.items():
        out[f"pgizmo{i}"] = gizmo
    return out


def _state(s3: Scene3D) -> dict[str, object]:
    state: dict[str, object] = {}
    for key, handle in _handles(s3).items():
        for prop in _PROPS:
            value = getattr(handle, prop, None) if prop in ("position", "wxyz") else getattr(
                handle._impl.props, prop, None)
            if value is not None:
                state[f"{key}.{prop}"] = np.array(value, copy=True) if isinstance(value, np.ndarray) else value
    return state


def _assert_same(got: dict, want: dict) -> None:
    assert got.keys() == want.keys()
    for key, value in want.items():
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(got[key], value, err_msg=key)
        else:
            assert got[key] == value, key


def test_a_follower_shows_the_instructors_panels_and_nodes_after_each_change(clients):
    model = SceneModel(default_scene())
    model.select_point(1)
    instructor = Scene3D(clients[0].scene, lambda *a: None, lambda *a: None)
    frame = frame_from_scene(model.scene, 1, 1)
    instructor.set_glyph(scene_extent(model.scene, model.derived).glyph)  # as a workbench tab sizes its marks
    instructor.draw(model.scene, model.derived)
    followers = [FollowView(c, frame) for c in clients[1:]]
    first, second = (c.name for c in model.scene.cameras[:2])

    def drag(name: str, step: tuple[float, float, float]) -> None:
        spec = model.scene.camera(name)
        model.set_camera_pose(name, np.add(spec.position, step), spec.pose.R, drag_id=name)

    changes = [lambda: drag(first, (0.3, 0.1, 0.0)), lambda: drag(first, (0.05, -0.2, 0.1)),
               lambda: drag(second, (-0.25, 0.0, 0.15)), lambda: model.add_point((0.2, -0.1, 1.3))]
    shown_panels = []
    for number, change in enumerate(changes, start=2):
        change()
        instructor.draw(model.scene, model.derived)  # as after the browser moved the dragged gizmo
        frame = frame_from_scene(model.scene, number, number)
        for view in followers:
            view.show(frame)
        want = _state(instructor)
        assert want[f"{first}/gizmo.position"].tolist() == pytest.approx(model.derived.poses[first][1])
        for view in followers:
            assert view.frame is frame
            assert {k: h.content for k, h in view._html.items()} == {k: svg for k, _t, svg in frame.panels}
            assert view.readout.content == frame.readout
            _assert_same(_state(view.scene3d), want)
        shown_panels.append(tuple(svg for _k, _t, svg in frame.panels))
    # Each change changed what is shown: the test compares live values, not a first frame kept by mistake.
    assert len(set(shown_panels)) == len(changes)
    assert len(model.scene.points_array()) == sum(k.startswith("plabel") and k.endswith(".text")
                                                  for k in _state(followers[0].scene3d))
