"""The classroom's follow / release / lock / pause machine against a plain model, driven by hypothesis: after
any sequence of calls the classroom agrees with the model, and a listener that only hears the events knows
the same following state for every tab."""

from __future__ import annotations

from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, precondition, rule

from egtviz.classroom import (
    CamerasLocked, Classroom, FollowChanged, Mode, ModeChanged, PauseChanged, RosterChanged,
)

TABS = st.integers(0, 5)
NAMES = st.sampled_from(["Ada", "Ben", "Cy", "Dee"])


class ClassMachine(RuleBasedStateMachine):
    def __init__(self) -> None:
        super().__init__()
        self.room = Classroom(token="k" * 32, task_count=lambda lesson: 0)
        self.heard_following: dict[int, bool] = {}
        self.heard_mode = Mode.FOLLOW
        self.heard_pause: str | None = None
        self.heard_locked = False
        self.room.subscribe(self._hear)
        # the model
        self.mode = Mode.FOLLOW
        self.tabs: dict[int, tuple[str | None, bool]] = {}  # tab -> (student name or None, following)
        self.locked = False
        self.pause: str | None = None

    def _hear(self, event) -> None:
        if isinstance(event, FollowChanged):
            self.heard_following[event.tab] = event.following
        elif isinstance(event, ModeChanged):
            self.heard_mode = event.mode
        elif isinstance(event, PauseChanged):
            self.heard_pause = event.message
        elif isinstance(event, CamerasLocked):
            self.heard_locked = event.locked
        else:
            assert isinstance(event, RosterChanged)

    @rule(tab=TABS, name=NAMES)
    def join(self, tab, name):
        self.room.join(tab, name)
        before = self.tabs.get(tab)
        if before is None or before[0] != name:
            self.tabs[tab] = (name, self.mode is Mode.FOLLOW)

    @rule(tab=TABS)
    def instructor_join(self, tab):
        self.room.instructor_join(tab)
        self.tabs[tab] = (None, False)
        self.heard_following.pop(tab, None)

    @rule(tab=TABS)
    def leave(self, tab):
        self.room.leave(tab)
        self.tabs.pop(tab, None)
        self.heard_following.pop(tab, None)

    @precondition(lambda self: any(name is not None for name, _ in self.tabs.values()))
    @rule(data=st.data(), on=st.booleans())
    def follow(self, data, on):
        tab = data.draw(st.sampled_from(sorted(t for t, (name, _) in self.tabs.items() if name is not None)))
        self.room.follow(tab, on)
        self.tabs[tab] = (self.tabs[tab][0], on)

    @rule(mode=st.sampled_from(list(Mode)))
    def set_mode(self, mode):
        self.room.set_mode(mode)
        self.mode = mode
        self.tabs = {t: (name, name is not None and mode is Mode.FOLLOW) for t, (name, _) in self.tabs.items()}

    @rule(locked=st.booleans())
    def lock(self, locked):
        self.room.lock_cameras(locked)
        self.locked = locked

    @rule(message=st.one_of(st.none(), st.sampled_from(["Look up", "Stop", ""])))
    def pause(self, message):
        self.room.pause(message)
        self.pause = None if message is None else (message or "The class is paused.")

    @invariant()
    def agrees_with_the_model(self):
        room = self.room
        assert room.mode is self.mode and room.cameras_locked == self.locked and room.paused() == self.pause
        for tab, (name, following) in self.tabs.items():
            assert room.name_of(tab) == name
            assert room.is_following(tab) == following
            assert room.is_instructor(tab) == (name is None)
        assert room.followers() == [t for t, (_, following) in self.tabs.items() if following]
        connected = {name for name, _ in self.tabs.values() if name is not None}
        assert {r.name for r in room.roster() if r.connected} == connected

    @invariant()
    def a_listener_knows_the_same(self):
        assert self.heard_following == {t: f for t, (name, f) in self.tabs.items() if name is not None}
        assert self.heard_mode is self.mode
        assert self.heard_pause == self.pause
        assert self.heard_locked == self.locked


ClassMachine.TestCase.settings = settings(max_examples=60, stateful_step_count=30, deadline=None)
test_class_machine = ClassMachine.TestCase
