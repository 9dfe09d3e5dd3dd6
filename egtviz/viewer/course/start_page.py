"""The course in the viewer: a start page in each tab, the lessons it opens, and the workbench one click away.

``egtviz`` with no arguments serves the course (:class:`Course`, ``EgtvizApp(course=True)``). A new tab
shows the :class:`StartPage`: the learner's name, one line per lesson (its number and title, its summary, and
"done", "step k of n" or "not started" for that name), a button to open each lesson and one to open the
workbench. A lesson opens as the workbench with the lesson's panel on top
(:class:`~egtviz.viewer.course.lesson_view.LessonPanel`); "Back to the course" returns to the start page, and the
workbench has the same button. ``egtviz lesson NAME`` opens that lesson in every new tab instead.

The lessons are read once, when the server starts: a lesson file edited later is read on the next start.
One render of the page reads the learner's progress in one indexed query (:meth:`ProgressStore.lessons_of`),
and the name field is taken once the typing stops. When progress is not being kept (the database cannot be
used, :attr:`ProgressStore.problem`), the page says so under its title, naming the file.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from html import escape
from typing import Protocol, TypeVar

import viser

from ...lessons import Lesson, LessonRun, ProgressStore, list_lessons, load
from ...lessons.progress import LessonProgress
from ...lessons.records import records_csv
from ...scene import Scene, SceneModel
from ...controllers.workbench_fields import FieldError
from ..workbench.fields import Debouncer, notify_error, on_event
from ...controllers.lesson import typed_learner_key
from .lesson_view import HELD_NAME_HINT, LESSON_ORDER, LessonPanel, LessonTab, refuse_held_name
from ..render.palette import PRESENT_GUI_CSS
from ..render.panels import DEFAULT_WINDOW, WindowSize, window_from_canvas
from .start_preview import start_preview_html
from .progress_notice import progress_notice_html, show_name_in_use

__all__ = ["ClassGate", "Course", "CourseApp", "LessonStatus", "StartPage", "course_statuses", "lesson_status"]

#: The start page's control panel is wider than the workbench's: it is the page.
START_PAGE_WIDTH_PX = 560
START_PAGE_MARGIN_PX = 16
#: In presentation mode the column is this much wider (its type is 1.25 times larger).
PRESENT_WIDTH_SCALE = 1.25

#: The event a viser handle passes the callbacks :meth:`StartPage._on` attaches.
_Event = TypeVar("_Event")
#: What :meth:`Course.wait_for_tab` waits for.
_Shown = TypeVar("_Shown")


class CourseApp(Protocol):
    """What the course uses of the app that serves it: an :class:`~egtviz.viewer.tabs.EgtvizApp` (named
    by what it offers: the app builds the course, so the course cannot import it)."""

    @property
    def field_delay(self) -> float: ...

    @property
    def initial_scene(self) -> Scene: ...

    def show_workbench(self, client: viser.ClientHandle, model: SceneModel | None = None) -> LessonTab | None: ...

    def clear_tab(self, client: viser.ClientHandle) -> None: ...


class ClassGate(Protocol):
    """What the course asks a class on its pages: a :class:`egtviz.viewer.classroom.course_gate.CourseGate` (named
    by what it offers: the gate shows the course's start pages again, so the course cannot import it)."""

    def refusal(self, tab: int, lesson: str) -> str | None: ...

    def note(self, tab: int, lesson: str, steps: int) -> str: ...

    def paced_run(self, tab: int, run: LessonRun) -> Callable[[str, int], bool] | None: ...

    def workbench_model(self, tab: int) -> SceneModel | None: ...

    def student_name(self, tab: int) -> str | None: ...


class LessonStatus:
    """How far a learner got in a lesson, as the start page says it."""

    NOT_STARTED = "not started"
    DONE = "done"


def lesson_status(record: LessonProgress | None, lesson: Lesson) -> str:
    """``"done"`` (every task passed; a lesson without tasks: its last step reached), ``"step k of n"``, or
    ``"not started"`` (``record`` None: the learner never started it, or is anonymous and nothing is kept)."""
    if record is None:
        return LessonStatus.NOT_STARTED
    tasks = {(i, t.id) for i, step in enumerate(lesson.steps) for t in step.tasks}
    if (tasks and tasks <= record.passed) or (not tasks and record.step == len(lesson.steps) - 1):
        return LessonStatus.DONE
    return f"step {record.step + 1} of {len(lesson.steps)}"


def course_statuses(progress: ProgressStore, learner: str, lessons: dict[str, Lesson]) -> dict[str, str]:
    """:func:`lesson_status` of each lesson for ``learner`` (``""``: anonymous), from one query of ``progress``."""
    records = progress.lessons_of(learner) if learner else {}
    return {name: lesson_status(records.get(name), lesson) for name, lesson in lessons.items()}


class StartPage:
    """The course's start page in one tab.

    Args:
        client: the tab's viser client.
        course: the course (its lessons, progress, and what the buttons open).
        learner: the name to show (the tab's last one; a class student's is the name they joined with).
    """

    def __init__(self, client: viser.ClientHandle, course: Course, learner: str = "") -> None:
        self.client = client
        self.course = course
        #: In a class, the name the student joined with: the name field shows it read-only (None: free).
        self.held_name: str | None = course.held_name(client.client_id)
        self.learner = learner if self.held_name is None else self.held_name
        self.closed = False
        self._lock = threading.RLock()
        self._typing = Debouncer(course.app.field_delay)
        gui = client.gui
        present = bool(getattr(course.app, "present", False))
        width = START_PAGE_WIDTH_PX * (PRESENT_WIDTH_SCALE if present else 1.0)
        with client.atomic():
            gui.configure_theme(dark_mode=False, show_logo=False)
            try:
                # Floating, not docked: the 3D canvas keeps the whole window, and the workbench a lesson opens
                # plans its panels from the canvas size the tab reports (the window's, before anything docks).
                gui.main_panel.float(x=START_PAGE_MARGIN_PX, y=START_PAGE_MARGIN_PX, width=width,
                                     height=self._height())
            except Exception:  # noqa: BLE001 - placement is cosmetic
                pass
            if present:
                gui.add_html(PRESENT_GUI_CSS)
            self.preview = gui.add_html(self._preview(width, present))
            gui.add_html(
                '<div style="padding:0 0.6em" data-egtviz="start-page"><h2 style="margin:0.3em 0">'
                f"Two-view geometry: a course</h2>{len(course.lessons)} lessons, from camera poses to visual "
                "servoing. Each lesson is a workbench with a panel of steps; its tasks are checked as you go. "
                "Type your name to keep your progress.</div>")
            self.notice = gui.add_html("")
            self.name = gui.add_text("your name", self.learner, disabled=self.held_name is not None,
                                     hint=HELD_NAME_HINT if self.held_name is not None else
                                     "Your progress is kept under this name: type it again in any tab, or after a "
                                     "restart, to resume where you were.")
            self.btn_workbench = gui.add_button(
                "Open the workbench", color="teal", icon=viser.Icon.ARROW_RIGHT,
                hint="Cameras, points and image planes without a lesson; this page is one click away from it.")
            self.btn_record = gui.add_button(
                "Download my record", icon=viser.Icon.DOWNLOAD,
                hint="A CSV file of your tasks: passed, attempts, hints used, last attempt.")
            self.buttons: dict[str, viser.GuiButtonHandle] = {}
            self.status: dict[str, viser.GuiHtmlHandle] = {}
            with gui.add_folder("Lessons", expand_by_default=True):
                for k, lesson in enumerate(course.lessons.values(), start=1):
                    self.buttons[lesson.name] = gui.add_button(f"{k}. {lesson.title}")
                    self.status[lesson.name] = gui.add_html("")
            self._show_status()
        for name, button in self.buttons.items():
            self._on(button.on_click, self._opener(name))
        self._on(self.btn_workbench.on_click, lambda _: self.course.open_workbench(self.client))
        self._on(self.btn_record.on_click, lambda _: self.download_record())
        self._on(self.name.on_update, lambda e: self._name_typed(e.target.value))

    def _opener(self, name: str) -> Callable[[viser.GuiEvent[viser.GuiButtonHandle]], object]:
        """The click callback of lesson ``name``'s button."""
        return lambda _: self.course.open_lesson(self.client, name, self.learner)

    def _window(self) -> WindowSize:
        """The tab's window, as it reported its canvas (nothing is docked on the start page)."""
        try:
            return window_from_canvas(self.client.camera.image_width, self.client.camera.image_height)
        except (AssertionError, AttributeError):  # no camera message yet
            return DEFAULT_WINDOW

    def _height(self) -> float:
        """The page's height: the window's less the margins."""
        return max(self._window().height - 2 * START_PAGE_MARGIN_PX, 300.0)

    def _preview(self, width: float, present: bool) -> str:
        """The workbench's scene drawn beside the page's column (:mod:`egtviz.viewer.course.start_preview`)."""
        try:
            return start_preview_html(self.course.app.initial_scene, self._window(),
                                      left_px=START_PAGE_MARGIN_PX + width, margin_px=START_PAGE_MARGIN_PX,
                                      present=present)
        except Exception:  # noqa: BLE001 - a preview that cannot be drawn leaves the page as it was
            return ""

    def report(self, exc: BaseException) -> None:
        """Show what went wrong in this tab."""
        notify_error(self.client, exc)

    def _on(self, register: Callable[[Callable[[_Event], None]], object], callback: Callable[[_Event], object]) -> None:
        def guarded(event: _Event) -> None:
            with self._lock:
                if self.closed:
                    return
                callback(event)

        on_event(register, guarded, self.report)

    def _name_typed(self, text: object) -> None:
        """The name field changed: take the name once the typing stops (each keystroke is not a learner); a class
        student's name is refused at once."""
        if self.held_name is not None:
            refuse_held_name(self.name, self.held_name, text)
            return
        self._typing.submit("learner", lambda: self._later(lambda: self._set_name(text)))

    def _later(self, action: Callable[[], None]) -> None:
        """Run a debounced action (from a timer thread: no callback wrapper above it) under the page's lock."""
        try:
            with self._lock:
                if not self.closed:
                    action()
        except Exception as exc:  # noqa: BLE001 - every failure must reach the tab
            self.report(exc)

    def _set_name(self, name: object) -> None:
        try:
            key = typed_learner_key(name)
        except FieldError:
            show_name_in_use(self.name, self.learner)
            raise
        if key != self.learner:
            self.learner = key
            self.course.remember(self.client.client_id, key)
            self._show_status()

    def download_record(self) -> None:
        """Send this learner's record to the browser as a CSV download (the server writes no file)."""
        if not self.learner:
            raise FieldError("download my record: type your name first (your record is kept under it)")
        text = records_csv(self.course.progress.task_records(self.learner))
        self.client.send_file_download("egtviz-record.csv", text.encode("utf-8"), save_immediately=True)

    def _show_status(self) -> None:
        """Each lesson's summary and how far this learner got in it; whether progress is kept; in a class, the
        lessons the pacing keeps closed (their buttons disabled) and how far the open ones go."""
        statuses = course_statuses(self.course.progress, self.learner, self.course.lessons)
        self.notice.content = progress_notice_html(self.course.progress.problem)
        gate, tab = self.course.gate, self.client.client_id
        for name, lesson in self.course.lessons.items():
            status = statuses[name]
            colour = "#117733" if status == LessonStatus.DONE else "#555"
            mark = "\u2713 " if status == LessonStatus.DONE else ""
            closed = gate.refusal(tab, name) if gate is not None else None
            paced = gate.note(tab, name, len(lesson.steps)) if gate is not None and closed is None else ""
            pacing = (f' · <b data-egtviz="not-open">not yet open</b>: {escape(closed)}' if closed is not None
                      else f" · {escape(paced)}" if paced else "")
            self.buttons[name].disabled = closed is not None
            self.status[name].content = (
                f'<div style="font-size:0.85em;padding:0 0.6em 0.4em" data-lesson="{escape(name)}" '
                f'data-status="{escape(status)}" data-open="{str(closed is None).lower()}">{escape(lesson.summary)} '
                f'<b style="color:{colour}">{mark}{escape(status)}</b>{pacing}</div>'
            )

    def show_pacing(self) -> None:
        """Show the lines again: the class's pacing changed."""
        with self._lock:
            if not self.closed:
                with self.client.atomic():
                    self._show_status()

    def close(self) -> None:
        self._typing.close()
        with self._lock:
            self.closed = True


class Course:
    """The course served by an :class:`~egtviz.viewer.tabs.EgtvizApp`: what each tab shows, and its learner.

    Args:
        app: the app (its ``show_workbench`` and ``clear_tab`` build and clear a tab).
        lesson: open this lesson in every new tab instead of the start page.
        progress: where progress is kept (default: :class:`ProgressStore` in the user's data folder).

    Raises:
        LessonError: ``lesson`` is not a shipped lesson, or a shipped lesson is invalid.
    """

    def __init__(self, app: CourseApp, *, lesson: str | None = None, progress: ProgressStore | None = None) -> None:
        self.app = app
        self.progress = progress if progress is not None else ProgressStore()
        #: Every shipped lesson, in course order.
        self.lessons: dict[str, Lesson] = {info.name: load(info.name) for info in list_lessons()}
        if lesson is not None and lesson not in self.lessons:
            load(lesson)  # raises the LessonError naming the lessons there are
        self.lesson = lesson
        self._lock = threading.Lock()
        #: A class on the course's pages (:class:`egtviz.viewer.classroom.course_gate.CourseGate`):
        #: ``refusal(tab, lesson)`` says why a tab may not open a lesson, ``paced_run(tab, run)`` puts a run opened
        #: there at a step the pacing allows and gives what "next" asks (None: anything), ``workbench_model(tab)``
        #: the scene a tab's workbench shows (None: a new one), ``student_name(tab)`` the name a class student joined
        #: with (None: the tab names its learner); None: no class.
        self.gate: ClassGate | None = None
        #: What each tab shows: a :class:`StartPage`, a :class:`LessonPanel`, or a workbench view.
        self.tabs: dict[int, StartPage | LessonPanel | LessonTab] = {}
        self._learners: dict[int, str] = {}

    def open(self, client: viser.ClientHandle) -> None:
        """A new tab: the lesson of ``egtviz lesson NAME``, else the start page."""
        if self.lesson is not None:
            self.open_lesson(client, self.lesson, "")
        else:
            self.show_start(client)

    def held_name(self, client_id: int) -> str | None:
        """The name a class student joined with, which their tab cannot change (None: the tab types its own)."""
        return self.gate.student_name(client_id) if self.gate is not None else None

    def remember(self, client_id: int, learner: str) -> None:
        """The tab's learner, kept while the tab lives (the start page and the lessons it opens show it)."""
        with self._lock:
            self._learners[client_id] = learner

    def _set_tab(self, client: viser.ClientHandle, what: StartPage | LessonPanel | LessonTab) -> None:
        with self._lock:
            old = self.tabs.get(client.client_id)
            self.tabs[client.client_id] = what
        if isinstance(old, StartPage):
            old.close()

    def show_start(self, client: viser.ClientHandle) -> StartPage:
        """Show the start page in this tab."""
        self._close_tab(client)
        self.app.clear_tab(client)
        with self._lock:
            learner = self._learners.get(client.client_id, "")
        page = StartPage(client, self, learner)
        self._set_tab(client, page)
        return page

    def _close_tab(self, client: viser.ClientHandle) -> None:
        with self._lock:
            old = self.tabs.pop(client.client_id, None)
        if isinstance(old, StartPage):
            old.close()

    def open_lesson(self, client: viser.ClientHandle, name: str, learner: str) -> LessonPanel | None:
        """Open lesson ``name`` for ``learner`` in this tab (at the step they were at); None if the tab left."""
        lesson = self.lessons.get(name)
        if lesson is None:
            raise FieldError(f"lesson: no lesson {str(name)[:40]!r}")
        closed = self.gate.refusal(client.client_id, name) if self.gate is not None else None
        if closed is not None:  # a disabled button clicked by a raw message, say
            raise FieldError(f"{lesson.title}: {closed}")
        held = self.held_name(client.client_id)
        self._close_tab(client)
        run = LessonRun(lesson, learner if held is None else held, model=SceneModel(lesson.scene),
                        progress=self.progress)
        # Paced: at a step the class allows, before anything is drawn; "next" asks the pacing.
        may_enter = self.gate.paced_run(client.client_id, run) if self.gate is not None else None
        view = self.app.show_workbench(client, run.model)
        if view is None:
            return None
        panel = self._lesson_panel(client, view, run, may_enter)
        self.remember(client.client_id, run.learner)
        self._set_tab(client, panel)
        return panel

    def _lesson_panel(self, client: viser.ClientHandle, view: LessonTab, run: LessonRun,
                      may_enter: Callable[[str, int], bool] | None) -> LessonPanel:
        """The lesson's panel on ``view``; a class student's name in it is the one they joined with."""
        panel = LessonPanel(view, run, progress=self.progress, on_back=lambda: self.show_start(client),
                            on_learner=lambda key: self.remember(client.client_id, key),
                            field_delay=self.app.field_delay)
        panel.may_enter = may_enter
        held = self.held_name(client.client_id)
        if held is not None:
            panel.hold_learner(held)
        return panel

    def open_workbench(self, client: viser.ClientHandle, model: SceneModel | None = None) -> LessonTab | None:
        """Open the workbench in this tab (on ``model``, default a new one or, in a class, the student's own), with a
        button back to the course."""
        if model is None and self.gate is not None:
            model = self.gate.workbench_model(client.client_id)
        self._close_tab(client)
        view = self.app.show_workbench(client, model)
        if view is None:
            return None
        self._add_back_button(client, view)
        self._set_tab(client, view)
        return view

    def restore(self, client: viser.ClientHandle, view: LessonTab) -> None:
        """The tab is back from a servo demo on ``view``: its lesson's panel (same run) or its way back to the
        course comes back with it."""
        with self._lock:
            was = self.tabs.get(client.client_id)
        if isinstance(was, LessonPanel) and was.run.model is view.model:
            if self.gate is not None:  # the pacing may have tightened while the demo was open
                self.gate.paced_run(client.client_id, was.run)
            self._set_tab(client, self._lesson_panel(client, view, was.run, was.may_enter))
        else:
            self._add_back_button(client, view)
            self._set_tab(client, view)

    def _add_back_button(self, client: viser.ClientHandle, view: LessonTab) -> None:
        with view.lock, client.atomic():
            back = client.gui.add_button("Back to the course", order=LESSON_ORDER)
        on_event(back.on_click, lambda _: self.show_start(client), view.report)

    def forget(self, client_id: int) -> None:
        """The tab left."""
        with self._lock:
            old = self.tabs.pop(client_id, None)
            self._learners.pop(client_id, None)
        if isinstance(old, StartPage):
            old.close()

    def wait_for_tab(self, kind: type[_Shown], timeout: float = 10.0, count: int = 1) -> list[_Shown]:
        """Block until ``count`` tabs show a ``kind`` (:class:`StartPage`, :class:`LessonPanel`; tests)."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self._lock:
                found: list[_Shown] = [t for t in self.tabs.values() if isinstance(t, kind)]
            if len(found) >= count:
                return found
            time.sleep(0.02)
        raise TimeoutError(f"fewer than {count} tabs show a {kind.__name__} after {timeout} s")
