"""The class on the course's own pages, for students' tabs:

* **Pacing.** The start page shows the lessons the instructor has not opened as not yet open (their buttons
  disabled, and a click forged by a raw message refused), and a lesson opened from it starts at a step the pacing
  allows, its "next" held by the pacing too. When the instructor tightens the pacing, a student already past it goes
  back to the last open step (to the start page if their lesson closed), with a note saying so; the progress
  database keeps the furthest step they reached.
* **Their name.** A student's name is the one they joined with: the name fields of the start page and of the lesson
  panel show it read-only, and a name sent to them anyway is refused.
* **Their own scene.** The workbench the start page opens is the student's own scene, the one the class keeps for
  them, not a new one.

The instructor's tabs, and a course served without a class, are left alone. The course asks the gate
(:attr:`egtviz.viewer.course.start_page.Course.gate`); the gate asks the classroom.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

from ...classroom import Classroom, Event, PacingChanged
from ..course.lesson_view import LessonPanel
from ..course.start_page import StartPage

if TYPE_CHECKING:
    from ...lessons import LessonRun
    from ...scene import SceneModel
    from ..course.start_page import Course

__all__ = ["NOT_OPEN", "PACED_TITLE", "CourseGate"]

#: Why a student cannot open a lesson the pacing keeps closed.
NOT_OPEN = "the instructor has not opened this lesson yet"
#: The title of the note a student's tab shows when the pacing moved it back.
PACED_TITLE = "Paced by the instructor"


class CourseGate:
    """Which lessons, and which steps of them, a student's tab may open under the class's pacing, and which scene
    their workbench shows.

    Args:
        room: the class.
        course: the course that asks the gate (it becomes the course's ``gate``), and whose start pages are shown
            again when the pacing changes; None: no course.
        own_model: the scene model of a student's own scene, by name (None: a new workbench for everyone).
    """

    def __init__(self, room: Classroom, course: Course | None = None, *,
                 own_model: Callable[[str], SceneModel] | None = None) -> None:
        self.room = room
        self.course = course
        self._own_model = own_model
        # Tabs are moved off the instructor's thread (a class of redraws must not hold up the pacing form), in order.
        self._mover = ThreadPoolExecutor(max_workers=1, thread_name_prefix="egtviz-class-pacing")
        self._unsubscribe: Callable[[], None] = room.subscribe(self._on_event)
        if course is not None:
            course.gate = self

    def _paced(self, tab: int) -> bool:
        """Students' tabs are paced; the instructor's, and a tab that has not joined, are not."""
        return self.room.name_of(tab) is not None and not self.room.is_instructor(tab)

    def student_name(self, tab: int) -> str | None:
        """The name the student on ``tab`` joined with, which their tab cannot change; None: the instructor's tab
        or a tab that has not joined (it names its own learner)."""
        return self.room.name_of(tab) if self._paced(tab) else None

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

    def paced_run(self, tab: int, run: LessonRun) -> Callable[[str, int], bool] | None:
        """A lesson run (:class:`~egtviz.lessons.LessonRun`) opened in the tab, before it is drawn: a student who
        was further on resumes at the last step open. Returns what the lesson panel's "next" asks (None: the tab is
        not paced)."""
        if not self._paced(tab):
            return None
        run.keep_furthest = True  # the pacing moves the tab, not how far the learner got
        last = self.last_open(run.lesson.name, run.step_index)
        if last != run.step_index:
            run.go_to(last)
        return self.room.may_open

    def workbench_model(self, tab: int) -> SceneModel | None:
        """The scene model the workbench opened in the tab shows: a student's own; None: a new one."""
        name = self.room.name_of(tab) if self._paced(tab) else None
        return self._own_model(name) if name is not None and self._own_model is not None else None

    def _on_event(self, event: Event) -> None:
        if not isinstance(event, PacingChanged) or self.course is None:
            return
        try:
            self._mover.submit(self._follow_pacing)
        except RuntimeError:  # closed: the server is stopping
            pass

    def _follow_pacing(self) -> None:
        """Each student's tab as the new pacing says: start pages shown again, a lesson past it moved back."""
        course = self.course
        if course is None:
            return
        for tab, page in list(course.tabs.items()):
            if not self._paced(tab):
                continue
            try:
                if isinstance(page, StartPage):
                    page.show_pacing()
                elif isinstance(page, LessonPanel) and page.run is not None:
                    self._hold_back(course, page)
            except Exception:  # noqa: BLE001 - a tab that left meanwhile; the other tabs still follow
                logging.getLogger(__name__).debug("tab %s not paced", tab, exc_info=True)

    def _hold_back(self, course: Course, panel: LessonPanel) -> None:
        """A student's lesson panel past the pacing goes back to the last open step, or to the start page if their
        lesson is closed, with a note in the tab."""
        lesson = panel.run.lesson
        client = panel.view.client
        if not self.room.may_open(lesson.name, 0):
            with panel.view.lock:
                if panel.view.closed or course.tabs.get(client.client_id) is not panel:
                    return
            course.show_start(client)
            said = f"{lesson.title} is closed for now: you are back on the course's page."
        else:
            last = self.last_open(lesson.name, panel.run.step_index)
            if not panel.hold_back(last):
                return
            said = f"{lesson.title} is open up to step {last + 1} for now: you are back on that step."
        client.add_notification(PACED_TITLE, said, color="blue", auto_close_seconds=8.0)

    def close(self) -> None:
        """Stop listening to the class; the course is no longer paced."""
        self._unsubscribe()
        self._mover.shutdown(wait=False, cancel_futures=True)
        if self.course is not None and self.course.gate is self:
            self.course.gate = None
