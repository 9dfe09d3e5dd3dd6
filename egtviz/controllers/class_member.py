"""The class members' tabs without a browser: a student's (:class:`StudentController`) and the instructor's
(:class:`InstructorController`), each over the class's :class:`~egtviz.classroom.Classroom`.

Both take typed intents (the text a member typed, a button's choice, a box ticked) and give the state their tab
draws (:mod:`.class_state`). A refused intent raises :class:`~.class_text.ClassRefusal` in the field's own words
and leaves the class as it was. What an intent does to the other tabs (routing a student to the room's scene,
sending the instructor's frames) is the viewer's: the class's events tell it.
"""

from __future__ import annotations

from collections.abc import Callable

from ..classroom import Classroom, Mode
from .class_state import PanelState, RoomStatus, StudentState, answers_view, pacing_view, roster_lines
from .class_text import ClassRefusal, paced_step, refusals, typed_answer, typed_name

__all__ = ["HISTOGRAM_BINS", "RELEASE_TO", "InstructorController", "StudentController"]

#: The release choices: label -> the mode students are released to.
RELEASE_TO = {"explore": Mode.EXPLORE, "tasks": Mode.TASKS}
#: Bins of the answers' histogram.
HISTOGRAM_BINS = 8


class StudentController:
    """One student's tab: joining, following and answering.

    Args:
        room: the class.
        tab: the tab's id in the class.
    """

    def __init__(self, room: Classroom, tab: int) -> None:
        self.room = room
        self.tab = tab

    def join(self, text: object) -> str:
        """Join the class under the name typed (returned as typed); a name the course does not take, or a full
        class, is refused.

        Raises:
            ClassRefusal: naming what is wrong (``"your name: ..."``).
        """
        name = typed_name(text)
        with refusals():
            self.room.join(self.tab, name)
        return name

    def follow(self, on: bool) -> None:
        """Follow the instructor (True) or leave follow for the student's own scene (False)."""
        self.room.follow(self.tab, on)

    def answer(self, question: str | None, text: object) -> float | str:
        """Answer ``question`` (the one the tab shows; None: none) with the text typed; returns the answer kept.

        Raises:
            ClassRefusal: no question, nothing typed, or an answer the class cannot keep.
        """
        if question is None:
            raise ClassRefusal("your answer: no question is asked at the moment")
        value = typed_answer(text)
        with refusals():
            self.room.record_answer(self.tab, question, value)
        return value

    def state(self) -> StudentState:
        """What the student's bar shows now."""
        return StudentState(self.room.name_of(self.tab) or "", self.room.is_following(self.tab), self.room.asked(),
                            self.room.paused())


class InstructorController:
    """One instructor tab: follow me, release, lock, pause, the question, snapshots, pacing and the roster.

    Args:
        room: the class.
        lesson_steps: the course's lessons, in its order, and how many steps each has (``{}``: no course).
    """

    def __init__(self, room: Classroom, lesson_steps: Callable[[], dict[str, int]]) -> None:
        self.room = room
        self.lesson_steps = lesson_steps

    # -- the buttons ----------------------------------------------------------------------------------------

    def follow_me(self, on: bool) -> bool:
        """Every student follows the instructor (True) or, if they did, is released to explore (False).

        Returns:
            True: the room follows; the tab publishes its scene now.
        """
        if on:
            self.room.set_mode(Mode.FOLLOW)
        elif self.room.mode is Mode.FOLLOW:  # already released (to the tasks, say): stays so
            self.room.set_mode(Mode.EXPLORE)
        return on

    def release(self, label: object) -> Mode:
        """Release the students to one of :data:`RELEASE_TO` (their own scenes, or the lesson step's tasks).

        Raises:
            ClassRefusal: not one of them.
        """
        mode = RELEASE_TO.get(label) if isinstance(label, str) else None
        if mode is None:
            raise ClassRefusal(f"release to: expected one of {sorted(RELEASE_TO)}")
        self.room.set_mode(mode)
        return mode

    def lock_cameras(self, on: bool) -> None:
        """Hold the students' view cameras where the instructor puts them (or let them go)."""
        self.room.lock_cameras(on)

    def toggle_pause(self, message: str) -> None:
        """Pause every screen with ``message``, or resume if the class is paused."""
        if self.room.paused() is None:
            self.pause(message)
        else:
            self.resume()

    def pause(self, message: str) -> None:
        """Cover every student's screen with ``message`` (plain text; empty: "The class is paused.").

        Raises:
            ClassRefusal: a message the class cannot keep.
        """
        with refusals():
            self.room.pause(message)

    def resume(self) -> None:
        """Take the pause away."""
        self.room.pause(None)

    def ask(self, question: str) -> None:
        """Ask every student ``question`` (plain text).

        Raises:
            ClassRefusal: a question the class cannot keep.
        """
        with refusals():
            self.room.ask(question)

    def clear_question(self) -> None:
        """Take the question away."""
        self.room.ask(None)

    def show_names(self, on: bool) -> None:
        """Show the students' names with their answers (off on a projector: counts only)."""
        self.room.show_names(on)

    def show_snapshot(self, tab: int | None) -> None:
        """Show the room a snapshot of the scene of the student on ``tab`` (None: nobody chosen).

        Raises:
            ClassRefusal: no connected student chosen.
        """
        if tab is None:
            raise ClassRefusal("snapshot: choose a connected student first")
        with refusals():
            self.room.show_snapshot(self.room.snapshot(tab))

    def hide_snapshot(self) -> None:
        """Take the snapshot shown away."""
        self.room.show_snapshot(None)

    def pace(self, lesson: object, up_to: object, only: bool) -> None:
        """Students may open ``lesson`` up to the step typed (from 1; blank: every step), and only that lesson if
        ``only``.

        Raises:
            ClassRefusal: no such lesson, or a step it does not have (the pacing is left as it was).
        """
        steps = self.lesson_steps()
        if not isinstance(lesson, str) or lesson not in steps:
            raise ClassRefusal("pacing: no lesson to pace")
        last = paced_step(up_to, lesson, steps.get(lesson, 0))
        with refusals():
            self.room.pace(lesson, last)
            self.room.allow_lessons([lesson] if only else None)

    def roster_csv(self) -> bytes:
        """The roster and every question's answers, as a CSV file's bytes (UTF-8)."""
        return self.room.roster_csv().encode("utf-8")

    # -- the state ------------------------------------------------------------------------------------------

    def state(self) -> PanelState:
        """What the instructor's panel shows now."""
        room = self.room
        rows = room.roster()
        connected = [r for r in rows if r.connected]
        mode, paused = room.mode, room.paused()
        steps = self.lesson_steps()
        question = room.asked()
        answers = None
        if question is not None:
            names = room.answers(question) if room.names_shown() else None
            answers = answers_view(room.histogram(question, HISTOGRAM_BINS), names)
        allowed, paced = room.pacing()
        return PanelState(
            status=RoomStatus(len(connected), sum(r.following for r in connected), mode, paused),
            follow_me=mode is Mode.FOLLOW, cameras_locked=room.cameras_locked, names_shown=room.names_shown(),
            roster=roster_lines(rows, {n: k for k, n in enumerate(steps, 1)}), answers=answers,
            pacing=pacing_view(allowed, paced, steps))
