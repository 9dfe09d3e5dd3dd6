"""The events that take a listener from one class state to another (a process that adopts a state another
process wrote tells its panels what changed, as if the changes had been made here)."""

from __future__ import annotations

from .events import (
    AnswersChanged, CamerasLocked, Event, FollowChanged, ModeChanged, NamesShown, PacingChanged, PauseChanged,
    QuestionAsked, RosterChanged, SharedChanged, SnapshotShown,
)
from .state import ClassState

__all__ = ["changes_between"]


def changes_between(old: ClassState, new: ClassState) -> list[Event]:
    """The events a listener of ``old`` needs to show ``new``, in the order the classroom sends them."""
    events: list[Event] = []
    if new.shared.version != old.shared.version or new.shared.scene != old.shared.scene:
        events.append(SharedChanged(new.shared.version))
    if new.mode is not old.mode:
        events.append(ModeChanged(new.mode))
    for tab, t in new.tabs.items():
        before = old.tabs.get(tab)
        if t.name is not None and (before is None or before.following != t.following or before.name != t.name):
            events.append(FollowChanged(tab, t.following))
    if new.cameras_locked != old.cameras_locked:
        events.append(CamerasLocked(new.cameras_locked))
    if new.pause != old.pause:
        events.append(PauseChanged(new.pause))
    if new.paced != old.paced or new.allowed != old.allowed:
        events.append(PacingChanged())
    if new.question != old.question:
        events.append(QuestionAsked(new.question))
    versions = {q: e["version"] for q, e in old.answers.to_dict().items()}
    events.extend(AnswersChanged(q) for q, e in new.answers.to_dict().items() if versions.get(q) != e["version"])
    if new.shown != old.shown:
        events.append(SnapshotShown(None if new.shown is None else new.shown.label))
    if new.names_shown != old.names_shown:
        events.append(NamesShown(new.names_shown))
    if new.students != old.students or _places(new) != _places(old):
        events.append(RosterChanged())
    return events


def _places(state: ClassState) -> dict[int, tuple]:
    return {tab: (t.name, t.following, t.lesson, t.step) for tab, t in state.tabs.items()}
