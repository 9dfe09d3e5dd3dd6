"""The class's camera lock on a released student's own scene: held by the scene model against every edit in place,
lifted on unlock without lifting a lesson step's locks, and applied on every worker that adopts the lock."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from egtviz.classroom import CamerasLocked, Classroom
from egtviz.scene import SceneError, SceneModel
from egtviz.viewer.classroom.camera_lock import CameraLock
from egtviz.viewer.classroom.scene_lock import LOCKED_TITLE, SceneLocks
from egtviz.viewer.server import class_bus
from egtviz.viewer.server.class_bus import ClassHub, ClassroomBus

from _waiting import PATIENCE, wait_for


class _Flag:
    def __init__(self) -> None:
        self.on = False

    def __call__(self) -> bool:
        return self.on


def _position(model: SceneModel, name: str) -> tuple[float, ...]:
    return tuple(model.scene.camera(name).position)


def test_the_class_lock_refuses_every_edit_of_a_pose_and_unlock_keeps_the_lessons_lock() -> None:
    model = SceneModel()
    names = model.scene.camera_names
    assert len(names) >= 2
    first, second = names[0], names[1]
    with model.lesson_step("the step locks one camera"):
        model.lock(second)
    flag = _Flag()
    locks = SceneLocks(flag)
    locks.watch(model)
    assert model.scene.locked == {second}  # not locked by the class yet
    flag.on = True
    locks.set_locked(True)
    assert model.scene.locked == set(names)
    assert locks.class_locks(model) == set(names) - {second}
    before = _position(model, first)
    rotation = model.scene.camera(first).camera().pose.R
    with pytest.raises(SceneError, match="locked"):
        model.update_camera(first, position=(1.0, 2.0, 3.0))  # a typed field
    with pytest.raises(SceneError, match="locked"):
        model.set_camera_pose(first, (0.5, 0.5, 0.5), rotation, drag_id=1)  # a gizmo drag or a raw message
    assert _position(model, first) == before
    assert not model.can_undo  # the class's lock is no step the student can undo
    # The student keeps their scene without the class's locks (a reconnect, another worker).
    assert locks.without_class_locks(model, model.scene).locked == {second}
    flag.on = False
    locks.set_locked(False)
    assert model.scene.locked == {second}  # the lesson's lock stays
    assert locks.class_locks(model) == frozenset()
    model.update_camera(first, position=(1.0, 2.0, 3.0))
    assert _position(model, first) == (1.0, 2.0, 3.0)
    with pytest.raises(SceneError, match="locked"):
        model.update_camera(second, position=(1.0, 2.0, 3.0))


def test_a_camera_unlocked_by_a_loaded_scene_or_added_while_locked_is_locked_again() -> None:
    model = SceneModel()
    model.update_camera(model.scene.camera_names[0], focal_length=0.02)
    flag = _Flag()
    flag.on = True
    locks = SceneLocks(flag)
    locks.watch(model)  # a student released while the class locks: locked at once
    assert model.scene.locked == set(model.scene.camera_names)
    assert not model.undo()  # the lock ended the student's history (see the test below)
    model.load_scene(model.scene.replace(locked=frozenset()))  # an uploaded scene file has no locks
    wait_for(lambda: model.scene.locked == set(model.scene.camera_names), "the loaded scene's cameras locked again")
    name = model.add_camera()
    wait_for(lambda: name in model.scene.locked, "the added camera locked")
    with pytest.raises(SceneError, match="locked"):
        model.update_camera(name, position=(0.0, 0.0, -4.0))


def _released_view(model: SceneModel):
    told: list[str] = []
    client = SimpleNamespace(client_id=1, add_notification=lambda title, body, **kw: told.append(title))
    return SimpleNamespace(model=model, client=client), told


def test_the_lock_adopted_from_another_worker_locks_this_workers_released_students(monkeypatch) -> None:
    monkeypatch.setattr(class_bus, "SYNC_S", 0.01)
    hub = ClassHub()
    buses = []
    try:
        rooms = []
        for i in range(2):
            room = Classroom(None, token="t" * 20, task_count=lambda name: 1)
            bus = ClassroomBus(hub.address, hub.authkey, i)
            bus.attach(SimpleNamespace(room=room, sender=SimpleNamespace(post=lambda f: None, latest=None)))
            assert bus.wait_welcomed(PATIENCE), f"waited {PATIENCE:.0f} s for the hub to welcome worker {i}"
            rooms.append(room)
            buses.append(bus)
        a, b = rooms
        model = SceneModel()
        view, told = _released_view(model)
        cameras = CameraLock(b, dict, released=lambda: ({1: "student"}, {1: view}))
        cameras.released(view, shown=True)  # released while the class does not lock: nothing said
        b.subscribe(lambda e: isinstance(e, CamerasLocked) and cameras.class_changed())
        a.lock_cameras(True)  # the instructor is on the other worker
        wait_for(lambda: model.scene.locked == set(model.scene.camera_names) and told == [LOCKED_TITLE],
                 "the lock from worker a to lock worker b's released student, with a note")
        name = model.scene.camera_names[0]
        before = np.array(model.scene.camera(name).position)
        with pytest.raises(SceneError, match="locked"):
            model.update_camera(name, position=tuple(before + 1.0))
        a.lock_cameras(False)
        wait_for(lambda: not model.scene.locked and len(told) == 2, "the unlock from worker a to reach the student")
        assert told[1] != LOCKED_TITLE
        model.update_camera(name, position=tuple(before + 1.0))
        assert np.allclose(model.scene.camera(name).position, before + 1.0)
    finally:
        for bus in buses:
            bus.close()
        hub.close()


def test_undo_cannot_put_a_camera_back_where_it_was_before_the_class_locked_it() -> None:
    model = SceneModel()
    first = model.scene.camera_names[0]
    model.update_camera(first, position=(1.0, 2.0, 3.0))  # the student's own move, undoable until the lock
    assert model.can_undo
    flag = _Flag()
    locks = SceneLocks(flag)
    locks.watch(model)
    flag.on = True
    locks.set_locked(True)
    assert not model.undo()  # undo swaps whole scenes: before the lock it would have moved the camera back
    assert _position(model, first) == (1.0, 2.0, 3.0)
    model.set_point(0, (0.1, 0.2, 3.0))  # what a locked class may still change stays undoable
    assert model.undo() and _position(model, first) == (1.0, 2.0, 3.0)
