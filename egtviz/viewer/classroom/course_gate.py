"""The class on the course's own pages, for students' tabs:

* **Pacing.** The start page shows the lessons the instructor has not opened as not yet open (their buttons
  disabled, and a click forged by a raw message refused), and a lesson opened from it starts at a step the pacing
  allows, its "next" held by the pacing too.
* **Their own scene.** The workbench the start page opens is the student's own scene, the one the class keeps for
  them, not a new one.

The instructor's tabs, and a course served without a class, are left alone. The course asks the gate
(:attr:`egtviz.viewer.course.start_page.Course.gate`); the gate asks the classroom.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from ...classroom import Classroom, PacingChanged
from ..course.start_page import StartPage

__all__ = ["NOT_OPEN", "CourseGate"]

#: Why a student cannot open a lesson the pacing keeps closed.
NOT_OPEN = "the instructor has not opened this lesson yet"


class CourseGate:
    """Which lessons, and which steps of them, a student's tab may open under the class's pacing, and which scene
    their workbench shows.

    Args:
        room: the class.
        course: the course that asks the gate (it becomes the course's ``gate``), and whose start pages are shown
            again when the pacing changes; None: no course.
        own_model: the scene model of a student's own scene, by name (None: a new workbench for everyone).
    """

    def __init__(self, room: Classroom, course: Any = None, *,
                 own_model: Callable[[str], Any] | None = None) -> None:
        self.room = room
        self.course = course
        self._own_model = own_model
        self._unsubscribe: Callable[[], None] = room.subscribe(self._on_event)
        if course is not None:
            course.gate = self

    def _paced(self, tab: int) -> bool:
        """Students' tabs are paced; the instructor's, and a tab that has not joined, are not."""
        return self.room.name_of(tab) is not None and not self.room.is_instructor(tab)

    def refusal(self, tab: int, lesson: str) -> str | None:
        """Why the tab may not open ``lesson`` (None: it may)."""
        if not self._paced(tab) or self.room.may_open(lesson, 0):
            return None
        return NOT_OPEN

    def note(self, tab: int, lesson: str, steps: int) -> str:
        """What the start page says of an open lesson's pacing: ``"open up to step k of n"``, or ``""``."""
        if not self._paced(tab):
            return ""
        last = self.last_open(lesson, steps - 1)
        return "" if last >= steps - 1 else f"open up to step {last + 1} of {steps}"

    def last_open(self, lesson: str, step: int) -> int:
        """The last step at or before ``step`` that the pacing lets students open (0 at the least)."""
        while step > 0 and not self.room.may_open(lesson, step):
            step -= 1
        return step

    def paced_run(self, tab: int, run: Any) -> Callable[[str, int], bool] | None:
        """A lesson run (:class:`~egtviz.lessons.LessonRun`) opened in the tab, before it is drawn: a student who
        was further on resumes at the last step open. Returns what the lesson panel's "next" asks (None: the tab is
        not paced)."""
        if not self._paced(tab):
            return None
        last = self.last_open(run.lesson.name, run.step_index)
        if last != run.step_index:
            run.go_to(last)
        return self.room.may_open

    def workbench_model(self, tab: int) -> Any:
        """The scene model the workbench opened in the tab shows: a student's own; None: a new one."""
        name = self.room.name_of(tab) if self._paced(tab) else None
        return self._own_model(name) if name is not None and self._own_model is not None else None

    def _on_event(self, event: Any) -> None:
        if not isinstance(event, PacingChanged) or self.course is None:
            return
        for tab, page in list(self.course.tabs.items()):
            if isinstance(page, StartPage) and self._paced(tab):
                try:
                    page.show_pacing()
                except Exception:  # noqa: BLE001 - a tab that left meanwhile; the other pages are still shown
                    logging.getLogger(__name__).debug("start page %s not refreshed", tab, exc_info=True)

    def close(self) -> None:
        """Stop listening to the class; the course is no longer paced."""
        self._unsubscribe()
        if self.course is not None and self.course.gate is self:
            self.course.gate = None
