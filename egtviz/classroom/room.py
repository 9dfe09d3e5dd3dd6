"""The classroom: one instructor (on one or more tabs), a room of students, and what the instructor controls.

Headless (no viser): the viewer calls these methods from its callbacks and redraws on the events. Every
method takes the one lock briefly and is cheap (the roster reads the progress database after releasing it);
listeners are called after the lock is released, in the calling thread.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from typing import Any

from ..lessons.progress import ProgressStore, learner_key
from ..scene import Scene
from .answers import Histogram
from .events import (
    AnswersChanged, Broadcaster, CamerasLocked, FollowChanged, Mode, ModeChanged, NamesShown, PacingChanged,
    PauseChanged, RosterChanged, SharedChanged, SnapshotShown,
)
from .roster import RosterRow, StudentPlace, build_roster, roster_csv, shipped_task_count
from .snapshots import Snapshot, anonymise, label_for
from .state import ClassState, SharedState, TabState
from .text import ClassroomError, plain_text
from .tokens import RedactingFilter, TokenGuard

__all__ = ["MAX_PAUSE_MESSAGE", "MAX_STUDENTS", "Classroom"]

MAX_STUDENTS = 1000
"""Students a class keeps (a join past it is refused)."""
MAX_PAUSE_MESSAGE = 200
MAX_LESSON_NAME = 120
DEFAULT_PAUSE = "The class is paused."


def _tab_id(tab: object) -> int:
    if isinstance(tab, bool) or not isinstance(tab, int) or tab < 0:
        raise ClassroomError(f"tab: expected a whole number 0 or more, got {tab!r}")
    return tab


def _step(step: object, what: str = "step") -> int | None:
    if step is None:
        return None
    if isinstance(step, bool) or not isinstance(step, int) or not 0 <= step < 10_000:
        raise ClassroomError(f"{what}: expected a whole number 0 to 9999 or none, got {step!r}")
    return step


def _lesson(lesson: object) -> str:
    return plain_text(lesson, "lesson", MAX_LESSON_NAME)


class Classroom(Broadcaster):
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
        self._lock = threading.RLock()
        super().__init__(self._lock)
        self._progress = progress
        self._clock = clock
        self._guard = TokenGuard(token, clock=clock)
        self._task_count = task_count or shipped_task_count
        self._state = state if state is not None else ClassState()

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
        tab = _tab_id(tab)
        key = learner_key(name)
        with self._lock:
            s = self._state
            if key not in s.students and len(s.students) >= MAX_STUDENTS:
                raise ClassroomError(f"the class is full ({MAX_STUDENTS} students)")
            s.students[key] = None
            following = s.mode is Mode.FOLLOW
            s.tabs[tab] = TabState(key, following)
        self._emit([RosterChanged(), FollowChanged(tab, following)])

    def leave(self, tab: int) -> None:
        """``tab`` closed (a student's or an instructor's); their scene and progress are kept."""
        with self._lock:
            gone = self._state.tabs.pop(_tab_id(tab), None)
        if gone is not None:
            self._emit([RosterChanged()])

    def instructor_join(self, tab: int) -> None:
        """``tab`` is the instructor's (its token was checked); the class is as the instructor left it."""
        tab = _tab_id(tab)
        with self._lock:
            self._state.tabs[tab] = TabState(None)
        self._emit([RosterChanged()])

    def instructor_leave(self, tab: int) -> None:
        """The instructor's ``tab`` closed; the class (mode, pacing, pause, shared scene) carries on."""
        tab = _tab_id(tab)
        with self._lock:
            t = self._state.tabs.get(tab)
            if t is None or not t.instructor:
                return
            del self._state.tabs[tab]
        self._emit([RosterChanged()])

    def is_instructor(self, tab: int) -> bool:
        with self._lock:
            t = self._state.tabs.get(_tab_id(tab))
            return t is not None and t.instructor

    def instructor_present(self) -> bool:
        """Whether an instructor tab is open."""
        with self._lock:
            return any(t.instructor for t in self._state.tabs.values())

    def name_of(self, tab: int) -> str | None:
        """The student on ``tab`` (None: an instructor's tab or no tab)."""
        with self._lock:
            t = self._state.tabs.get(_tab_id(tab))
            return None if t is None else t.name

    def _student_tab(self, tab: int) -> TabState:
        t = self._state.tabs.get(_tab_id(tab))
        if t is None or t.instructor:
            raise ClassroomError(f"tab {tab}: no student has joined on it")
        return t

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
        lesson = None if lesson is None else _lesson(lesson)
        step = _step(step)
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
        lesson = None if lesson is None else _lesson(lesson)
        step = _step(step)
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
            t = self._state.tabs.get(_tab_id(tab))
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
        lesson = _lesson(lesson)
        max_step = _step(max_step, "max_step")
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
        allowed = None if names is None else frozenset(_lesson(n) for n in names)
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

    def record_answer(self, tab: int, question: str, value: float | str) -> None:
        """The student on ``tab`` answers ``question`` (their latest answer counts); O(1).

        Raises:
            ClassroomError: no student on ``tab``, or a question or answer that cannot be kept.
        """
        now = self._clock()
        with self._lock:
            t = self._student_tab(tab)
            question, due = self._state.answers.record(t.name or "", question, value, now)
        if due:
            self._emit([AnswersChanged(question)])

    def histogram(self, question: str, bins: int = 10) -> Histogram:
        """The answers to ``question`` counted; no names."""
        with self._lock:
            return self._state.answers.histogram(question, bins)

    def questions(self) -> list[str]:
        with self._lock:
            return self._state.answers.questions()

    def snapshot(self, tab: int) -> Snapshot:
        """An anonymised copy of the own scene of the student on ``tab``, labelled ``Student A``, ...

        Raises:
            ClassroomError: no student on ``tab``, or they have no scene of their own yet.
        """
        with self._lock:
            s = self._state
            name = self._student_tab(tab).name or ""
            scene = s.scenes.get(name)
            if scene is None:
                raise ClassroomError(f"tab {tab}: that student has no scene of their own yet")
            label = s.labels.get(name)
            if label is None:
                label = s.labels[name] = label_for(len(s.labels))
            s.snapshots_taken += 1
            number = s.snapshots_taken
        return Snapshot(label, anonymise(scene, name, label), number)

    def show_snapshot(self, snapshot: Snapshot | None) -> None:
        """Show ``snapshot`` to the room beside each student's own scene; None: show none."""
        if snapshot is not None and not isinstance(snapshot, Snapshot):
            raise ClassroomError(f"snapshot: expected a Snapshot, got {type(snapshot).__name__}")
        with self._lock:
            if self._state.shown is snapshot:
                return
            self._state.shown = snapshot
        self._emit([SnapshotShown(None if snapshot is None else snapshot.label)])

    def shown_snapshot(self) -> Snapshot | None:
        with self._lock:
            return self._state.shown

    def show_names(self, shown: bool) -> None:
        """Show students' names on the projector (True) or hide them (the default)."""
        shown = bool(shown)
        with self._lock:
            if self._state.names_shown == shown:
                return
            self._state.names_shown = shown
        self._emit([NamesShown(shown)])

    def names_shown(self) -> bool:
        with self._lock:
            return self._state.names_shown

    # -- sharing between processes -----------------------------------------------------------------------

    def to_json(self) -> str:
        """The class's state as JSON (no token, no listeners): :meth:`from_json` in another process resumes it."""
        with self._lock:
            return self._state.to_json()

    @classmethod
    def from_json(cls, text: str | bytes, progress: ProgressStore | None = None, **kwargs: Any) -> Classroom:
        """A classroom holding the state :meth:`to_json` wrote (``kwargs``: as for the constructor)."""
        return cls(progress, state=ClassState.from_json(text), **kwargs)
