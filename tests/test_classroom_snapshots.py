"""Snapshots of a student's scene shown to the room: anonymised, labelled, with cameras and points kept."""

from __future__ import annotations

import dataclasses

import pytest

from egtviz.classroom import Classroom, ClassroomError, SnapshotShown
from egtviz.scene import default_scene
from egtviz.scene.annotations import Annotations, Frame, Label


def _scene_by(name: str):
    base = default_scene()
    notes = Annotations(labels=(Label((0.0, 0.0, 1.0), f"{name.upper()}'s guess"), Label((0.0, 0.0, 2.0), "origin")),
                        frames=(Frame(label=name),), messages=(f"drawn by {name}",))
    return base.replace(title=f"Cameras of {name}", annotations=notes)


def test_a_snapshot_replaces_the_name_and_keeps_the_geometry():
    room = Classroom(task_count=lambda lesson: 0)
    room.join(1, "Ada Lovelace")
    mine = _scene_by("Ada Lovelace")
    room.keep_scene("Ada Lovelace", mine)
    shot = room.snapshot(1)
    assert shot.label == "Student A" and shot.number == 1
    s = shot.scene
    assert s.title == "Cameras of Student A"
    assert [a.text for a in s.annotations.labels] == ["Student A's guess", "origin"]
    assert s.annotations.frames[0].label == "Student A"
    assert s.annotations.messages == ("drawn by Student A",)
    assert s.cameras == mine.cameras and s.camera_names == mine.camera_names
    assert s.points == mine.points and s.pair == mine.pair and s.options == mine.options
    assert "ada" not in repr(dataclasses.asdict(s)).lower()
    assert room.own_scene("Ada Lovelace") is mine  # the student's own scene is untouched


def test_labels_are_stable_per_student_and_snapshots_are_numbered():
    room = Classroom(task_count=lambda lesson: 0)
    for tab, name in ((1, "Ada"), (2, "Ben")):
        room.join(tab, name)
        room.keep_scene(name, default_scene())
    first, second, again = room.snapshot(2), room.snapshot(1), room.snapshot(2)
    assert [(s.label, s.number) for s in (first, second, again)] == [("Student A", 1), ("Student B", 2),
                                                                      ("Student A", 3)]


def test_a_long_title_stays_within_its_limit():
    room = Classroom(task_count=lambda lesson: 0)
    room.join(1, "Al")
    room.keep_scene("Al", default_scene().replace(title="Al " * 66))
    assert len(room.snapshot(1).scene.title) == 200


def test_show_and_hide_a_snapshot():
    room = Classroom(task_count=lambda lesson: 0)
    events = []
    room.subscribe(events.append)
    room.join(1, "Ada")
    room.keep_scene("Ada", default_scene())
    shot = room.snapshot(1)
    room.show_snapshot(shot)
    assert room.shown_snapshot() is shot
    room.show_snapshot(None)
    assert room.shown_snapshot() is None
    assert [e for e in events if isinstance(e, SnapshotShown)] == [SnapshotShown("Student A"), SnapshotShown(None)]


def test_a_snapshot_needs_a_student_with_a_scene():
    room = Classroom(task_count=lambda lesson: 0)
    room.join(1, "Ada")
    with pytest.raises(ClassroomError, match="no scene of their own"):
        room.snapshot(1)
    with pytest.raises(ClassroomError, match="no student"):
        room.snapshot(2)
    with pytest.raises(ClassroomError, match="expected a Snapshot"):
        room.show_snapshot("Ada")  # type: ignore[arg-type]
