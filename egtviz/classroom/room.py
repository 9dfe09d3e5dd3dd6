"""The classroom: one instructor (on one or more tabs), a room of students, and what the instructor controls.

Headless (no viser): the viewer calls these methods from its callbacks and redraws on the events. Every
method takes the one lock briefly and is cheap (the roster reads the progress database after releasing it);
listeners are called after the lock is released, in the calling thread.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

from ..lessons.progress import ProgressStore, learner_key
from ..scene import Scene
from .changes import changes_between
from .events import (
    CamerasLocked, FollowChanged, Mode, ModeChanged, PacingChanged, PauseChanged, RosterChanged, SharedChanged,
)
from .projector import ProjectorControls
from .roster import RosterRow, StudentPlace, build_roster, roster_csv, shipped_task_count
from .state import ClassState, SharedState, TabState
from .text import ClassroomError, lesson_name, plain_text, step_number, tab_id
from .tokens import RedactingFilter, TokenGuard

__all__ = ["MAX_PAUSE_MESSAGE", "MAX_STUDENTS", "Classroom"]

MAX_STUDENTS = 1000
"""Students a class keeps (a join past it is refused)."""
MAX_PAUSE_MESSAGE = 200
DEFAULT_PAUSE = "The class is paused."


class Classroom(ProjectorControls):
    """The state of one class and the instructor's controls over it.

    Args:
        progress: the course's progress database (the roster's tasks and steps); None: no progress in the roster.
        token: the instructor's secret (default: a random one, :attr:`instructor_token`).
        clock: monotonic seconds (for the rate limits; a test passes a fake one).
        task_count: tasks in a lesson by name (default: the shipped lessons').
        state: a class to resume (:meth:`to_json` of another process's classroom).
    """

    def __init__(self, progress: ProgressStore | None = None, *, token: str | None = None,
                 clock: Callable[[], float] = time.monotonic, task_count: Callable[[str], int] | None = None,
                 state: ClassState | None = None) -> None:
        super().__init__(state, clock)
        self._progress = progress
        self._guard = TokenGuard(token, clock=clock)
        self._task_count = task_count or shipped_task_count

    # -- tokens ------------------------------------------------------------------------------------------

    @property
    def instructor_token(self) -> str:
        return self._guard.token

    def check_token(self, candidate: str | None, peer: str) -> bool:
        """Whether ``candidate`` is the instructor token (``peer``: the client's address, for the rate limit)."""
        return self._guard.check(candidate, peer)

    def redact(self, text: str) -> str:
        """``text`` with the token shortened to its first four characters and ``…``."""
        return self._guard.redact(text)

    def redact_url(self, url: str) -> str:
        """``url`` with the token (or any ``token=`` value) shortened, for a log."""
        return self._guard.redact_url(url)

    def log_filter(self) -> RedactingFilter:
        """A logging filter that shortens the token in every record (install it on the server's handlers)."""
        return self._guard.log_filter()

    # -- who is here -------------------------------------------------------------------------------------

    def join(self, tab: int, name: str) -> None:
        """The student ``name`` opened ``tab`` (a name that joined before is the same student again).

        Raises:
            LearnerNameError: a name :func:`~egtviz.lessons.progress.learner_key` refuses.
            ClassroomError: the class is full (:data:`MAX_STUDENTS`).
        """
        tab = tab_id(tab)
        key = learner_key(name)
        with self._lock:
            s = self._state
            before = s.tabs.get(tab)
            if before is not None and before.name == key:
                return
            if key not in s.students and len(s.students) >= MAX_STUDENTS:
                raise ClassroomError(f"the class is full ({MAX_STUDENTS} students)")
            s.students[key] = None
            following = s.mode is Mode.FOLLOW
            s.tabs[tab] = TabState(key, following)
            if before is not None and before.name is not None:
                self._forget_if_empty(before.name)
        self._emit([RosterChanged(), FollowChanged(tab, following)])

    def _forget_if_empty(self, name: str) -> None:
        """Drop ``name`` from the class if nothing of theirs is kept (a tab that renamed itself before doing
        anything), so one tab trying many names cannot fill the class."""
        s = self._state
        if name in s.scenes or name in s.labels or s.answers.has_answered(name):
            return
        if any(t.name == name for t in s.tabs.values()):
            return
        s.students.pop(name, None)

    def leave(self, tab: int) -> None:
        """``tab`` closed (a student's or an instructor's); their scene and progress are kept."""
        with self._lock:
            gone = self._state.tabs.pop(tab_id(tab), None)
        if gone is not None:
            self._emit([RosterChanged()])

    def instructor_join(self, tab: int) -> None:
        """``tab`` is the instructor's (its token was checked); the class is as the instructor left it."""
        tab = tab_id(tab)
        with self._lock:
            self._state.tabs[tab] = TabState(None)
        self._emit([RosterChanged()])

    def instructor_leave(self, tab: int) -> None:
        """The instructor's ``tab`` closed; the class (mode, pacing, pause, shared scene) carries on."""
        tab = tab_id(tab)
        with self._lock:
            t = self._state.tabs.get(tab)
            if t is None or not t.instructor:
                return
            del self._state.tabs[tab]
        self._emit([RosterChanged()])

    def is_instructor(self, tab: int) -> bool:
        with self._lock:
            t = self._state.tabs.get(tab_id(tab))
            return t is not None and t.instructor

    def instructor_present(self) -> bool:
        """Whether an instructor tab is open."""
        with self._lock:
            return any(t.instructor for t in self._state.tabs.values())

    def name_of(self, tab: int) -> str | None:
        """The student on ``tab`` (None: an instructor's tab or no tab)."""
        with self._lock:
            t = self._state.tabs.get(tab_id(tab))
            return None if t is None else t.name

    def own_scene(self, name: str) -> Scene | None:
        """The scene the student ``name`` last kept (their own, given back when they reconnect); None if none."""
        key = learner_key(name)
        with self._lock:
            return self._state.scenes.get(key)

    def keep_scene(self, name: str, scene: Scene) -> None:
        """Remember ``scene`` as the student ``name``'s own (a student who joined)."""
        key = learner_key(name)
        if not isinstance(scene, Scene):
            raise ClassroomError(f"scene: expected a Scene, got {type(scene).__name__}")
        with self._lock:
            if key not in self._state.students:
                raise ClassroomError("scene: that student has not joined the class")
            self._state.scenes[key] = scene

    def report_step(self, tab: int, lesson: str | None, step: int | None) -> None:
        """The student on ``tab`` is at ``step`` of ``lesson`` (None: on no lesson), for the roster."""
        lesson = None if lesson is None else lesson_name(lesson)
        step = step_number(step)
        with self._lock:
            t = self._student_tab(tab)
            if (t.lesson, t.step) == (lesson, step):
                return
            t.lesson, t.step = lesson, step
        self._emit([RosterChanged()])

    # -- follow me -----------------------------------------------------------------------------------------

    def publish(self, scene: Scene, *, lesson: str | None = None, step: int | None = None) -> int:
        """Make ``scene`` (of ``lesson`` at ``step``) the one every follower shows; returns its version. The same
        scene object published again with the same lesson and step keeps the version (nothing is sent)."""
        if not isinstance(scene, Scene):
            raise ClassroomError(f"scene: expected a Scene, got {type(scene).__name__}")
        lesson = None if lesson is None else lesson_name(lesson)
        step = step_number(step)
        with self._lock:
            old = self._state.shared
            if old.scene is scene and (old.lesson, old.step) == (lesson, step):
                return old.version
            self._state.shared = new = SharedState(old.version + 1, scene, lesson, step)
        self._emit([SharedChanged(new.version)])
        return new.version

    def shared(self) -> SharedState:
        with self._lock:
            return self._state.shared

    def follow(self, tab: int, on: bool) -> None:
        """The student on ``tab`` follows the instructor (True) or goes back to their own scene."""
        on = bool(on)
        with self._lock:
            t = self._student_tab(tab)
            if t.following == on:
                return
            t.following = on
        self._emit([FollowChanged(tab, on), RosterChanged()])

    def is_following(self, tab: int) -> bool:
        with self._lock:
            t = self._state.tabs.get(tab_id(tab))
            return t is not None and t.following

    def followers(self) -> list[int]:
        """The student tabs that follow the instructor (the ones a new shared scene is sent to), in join order."""
        with self._lock:
            return [tab for tab, t in self._state.tabs.items() if t.following]

    def student_tabs(self) -> dict[int, str]:
        """Every open student tab and the student on it."""
        with self._lock:
            return {tab: t.name for tab, t in self._state.tabs.items() if t.name is not None}

    # -- modes, pause, pacing ----------------------------------------------------------------------------

    @property
    def mode(self) -> Mode:
        with self._lock:
            return self._state.mode

    def set_mode(self, mode: Mode) -> None:
        """FOLLOW: every student tab follows the instructor; EXPLORE and TASKS release them to their own scene."""
        mode = Mode(mode)
        following = mode is Mode.FOLLOW
        with self._lock:
            if mode is self._state.mode and all(t.following == following
                                                for t in self._state.tabs.values() if not t.instructor):
                return
            self._state.mode = mode
            changed = [tab for tab, t in self._state.tabs.items() if not t.instructor and t.following != following]
            for tab in changed:
                self._state.tabs[tab].following = following
        self._emit([ModeChanged(mode), *(FollowChanged(tab, following) for tab in changed), RosterChanged()])

    @property
    def cameras_locked(self) -> bool:
        with self._lock:
            return self._state.cameras_locked

    def lock_cameras(self, locked: bool) -> None:
        """Lock (True) or unlock students' view cameras."""
        locked = bool(locked)
        with self._lock:
            if self._state.cameras_locked == locked:
                return
            self._state.cameras_locked = locked
        self._emit([CamerasLocked(locked)])

    def pause(self, message: str | None) -> None:
        """Pause every student's screen showing ``message`` (plain text; empty: a default); None resumes."""
        if message is not None:
            message = plain_text(message, "message", MAX_PAUSE_MESSAGE, empty=True) or DEFAULT_PAUSE
        with self._lock:
            if self._state.pause == message:
                return
            self._state.pause = message
        self._emit([PauseChanged(message)])

    def paused(self) -> str | None:
        """The pause message, None while the class is not paused."""
        with self._lock:
            return self._state.pause

    def pace(self, lesson: str, max_step: int | None) -> None:
        """Students may open ``lesson`` up to step ``max_step`` (0-based); None: every step."""
        lesson = lesson_name(lesson)
        max_step = step_number(max_step, "max_step")
        with self._lock:
            paced = self._state.paced
            if paced.get(lesson, None) == max_step and (max_step is not None or lesson not in paced):
                return
            if max_step is None:
                paced.pop(lesson, None)
            else:
                paced[lesson] = max_step
        self._emit([PacingChanged()])

    def allow_lessons(self, names: Iterable[str] | None) -> None:
        """Students may open only these lessons; None: every lesson."""
        allowed = None if names is None else frozenset(lesson_name(n) for n in names)
        with self._lock:
            if self._state.allowed == allowed:
                return
            self._state.allowed = allowed
        self._emit([PacingChanged()])

    def may_open(self, lesson: str, step: int) -> bool:
        """Whether a student may open ``step`` (0-based) of ``lesson`` under the instructor's pacing."""
        with self._lock:
            allowed = self._state.allowed
            if allowed is not None and lesson not in allowed:
                return False
            limit = self._state.paced.get(lesson)
        return limit is None or (isinstance(step, int) and step <= limit)

    def pacing(self) -> tuple[frozenset[str] | None, dict[str, int]]:
        """``(lessons allowed or None, {lesson: last step allowed})``."""
        with self._lock:
            return self._state.allowed, {k: v for k, v in self._state.paced.items() if v is not None}

    # -- roster, answers, snapshots ----------------------------------------------------------------------

    def _places(self) -> list[StudentPlace]:
        s = self._state
        live: dict[str, list[TabState]] = {}
        for t in s.tabs.values():
            if t.name is not None:
                live.setdefault(t.name, []).append(t)
        places = []
        for name in s.students:
            tabs = live.get(name, [])
            where = next((t for t in reversed(tabs) if t.lesson is not None), None)
            places.append(StudentPlace(name, bool(tabs), any(t.following for t in tabs),
                                       None if where is None else where.lesson, None if where is None else where.step))
        return places

    def roster(self) -> list[RosterRow]:
        """Every student who joined, sorted by name, with their progress from the database."""
        with self._lock:
            places = self._places()
        return build_roster(places, self._progress, self._task_count)

    def roster_csv(self) -> str:
        """The roster and every question's answers as CSV text (a cell starting a formula gets a ``'``)."""
        rows = self.roster()
        with self._lock:
            book = self._state.answers
            answers = {q: book.answers(q) for q in book.questions()}
        return roster_csv(rows, answers)

    # -- sharing between processes -----------------------------------------------------------------------

    def to_json(self) -> str:
        """The class's state as JSON (no token, no listeners): :meth:`from_json` in another process resumes it."""
        with self._lock:
            return self._state.to_json()

    def adopt(self, state: ClassState) -> None:
        """Make ``state`` (read from another process's :meth:`to_json`) this class's, and tell the listeners
        what changed. The state replaces this one whole, tabs included: a process that shares a class with
        others merges their tabs before it adopts."""
        if not isinstance(state, ClassState):
            raise ClassroomError(f"state: expected a ClassState, got {type(state).__name__}")
        with self._lock:
            old, self._state = self._state, state
        self._emit(changes_between(old, state))

    def update(self, change: Callable[[ClassState], ClassState]) -> None:
        """Replace the state with ``change(state)`` under the lock, and tell the listeners what changed.

        Another process's changes are merged this way without losing one made here meanwhile (:meth:`adopt`
        would). ``change`` must be quick and build a new state, leaving the one it is given as it was.
        """
        with self._lock:
            old = self._state
            new = change(old)
            if not isinstance(new, ClassState):
                raise ClassroomError(f"state: expected a ClassState, got {type(new).__name__}")
            self._state = new
        self._emit(changes_between(old, new))

    @classmethod
    def from_json(cls, text: str | bytes, progress: ProgressStore | None = None, **kwargs: Any) -> Classroom:
        """A classroom holding the state :meth:`to_json` wrote (``kwargs``: as for the constructor)."""
        return cls(progress, state=ClassState.from_json(text), **kwargs)
