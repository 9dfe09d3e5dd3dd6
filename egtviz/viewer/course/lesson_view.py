"""The lesson runner in a tab: the step's text, its tasks with their answers and checks, and the way through.

A :class:`LessonPanel` sits at the top of a workbench tab's control panel and is the skin of a
:class:`~egtviz.controllers.lesson.LessonController`, which owns the :class:`~egtviz.lessons.LessonRun` on the
tab's own :class:`~egtviz.scene.SceneModel`: the panel maps its widgets to the controller's intents (check a
task, go to a step, a learner's name) and draws the controller's state. The workbench below it (gizmos, fields,
panels) is the learner's instrument, and the run's checks read the same scene. It shows

* the lesson's title, "step k of n" and a progress bar;
* "previous", "reset step" and "next" (entering a step applies its scene changes through the run);
* the step's text (Markdown with the formulas as MathML);
* each task: its prompt, the answer widget it declares (:attr:`~egtviz.lessons.tasks.Task.needs`, built by its
  skin in :mod:`egtviz.viewer.course.answers`), a "Check" button, the feedback on each attempt and the hint
  after a failed one;
* the learner's name: progress (the step, the tasks passed) is kept under it in the
  :class:`~egtviz.lessons.ProgressStore`, so a reload, a new tab or a restarted server resumes there;
* the estimation lab (:mod:`egtviz.viewer.course.lab_view`) or the convention lens (:mod:`egtviz.viewer.course.lens_view`)
  when the lesson uses them (:attr:`~egtviz.controllers.lesson.LessonController.needs`); they draw the panels
  through the tab's lesson policy's ``panel_filter``;
* when the step has a servo run (an ``open_demo`` change), its settings and a button that opens that demo
  with them in this tab (the demo's *Back* button returns to the lesson, at the same step).

A ``set_range`` change of a step limits a camera field. The rule is the scene's
(:class:`~egtviz.scene.constraints.CameraRanges`, worded as the GUI fields by
:mod:`egtviz.controllers.lesson_rules`): the
controller puts it on the model, which holds it for every edit, the tab's lesson policy (``field_guard``) asks
it so that a typed value outside is refused with the range in the field's own unit (the field reverts), the
panel lists the ranges, and a task is not checked while the scene breaks them (a script
may still move a camera out of a range). A gizmo drag is not refused but stopped, by the model, once per update:
a ``position`` range stops the camera at its edge, each coordinate clamped like a mechanical stop; under a
``ypr_deg`` range the camera keeps the last orientation that respected it. The gizmo follows the pointer while
it is held and shows the applied pose when the drag ends. The browser's own gizmo limits (viser's
``translation_limits``, ``rotation_limits``) are not used: they bound the offset along each of the gizmo's own,
rotated, axes accumulated since the gizmo was drawn, not the camera centre's world coordinates, and a pose the
server sets does not reset them.

A lock is the scene model's (it refuses every edit of a locked pose); a check also fails, with *reset step*
as the way back, when a camera locked at the step's start has gone or moved because the scene was replaced
(:func:`egtviz.controllers.lesson_rules.lock_refusal`).

Every callback is attached through :func:`egtviz.viewer.workbench.fields.on_event`, so an error becomes a
notification in this tab.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager
from html import escape
from typing import Protocol, TypeVar

import viser

from ...controllers.lesson import LessonController, StepGate, typed_learner_key
from ...controllers.workbench_fields import FieldError
from ...lessons import LessonRun, ProgressStore
from ...lessons.changes import OpenDemo
from ...lessons.runner import Attempt, ResolvedTask
from ...scene import SceneError, SceneModel
from ..workbench.fields import Debouncer, on_event
from .answers import answer_widget
from .answers.choice import CHOOSE
from .lab_view import LabPanel
from .lens_view import LensPanel
from .progress_notice import progress_notice_html, show_name_in_use
from ..workbench.lesson_policy import LessonPolicy

__all__ = [
    "CHOOSE", "HELD_NAME_HINT", "LessonPanel", "LessonTab", "StepNav", "TaskRow", "refuse_held_name",
]

#: The step buttons, in their group's order.
STEP_BUTTONS = ("previous", "reset step", "next")
#: Where the lesson's folders sit in the control panel (viser puts smaller orders first; the workbench's own
#: folders take increasing positive orders).
LESSON_ORDER = -100.0
LAB_ORDER = -90.0
LENS_ORDER = -80.0
MATH_CSS = ('<style>math[display="block"]{max-width:100%;overflow-x:auto;overflow-y:hidden;'
            "font-size:0.92em;padding:0.35em 0 0.2em}</style>")
DEMO_TITLES = {"pinhole": "the pin-hole demo (Puma 560)", "panoramic": "the panoramic demo (mobile robot)"}

#: The event a viser handle passes the callbacks :meth:`LessonPanel._on` attaches.
_Event = TypeVar("_Event")


class LessonTab(Protocol):
    """What a lesson panel uses of the workbench tab it sits in: a :class:`~egtviz.viewer.workbench.app.ClientView`
    (named by what it offers: the workbench's app builds the course, so the course cannot import it)."""

    #: The tab's lesson policy: the panel sets what the panels draw through and what a typed field must respect.
    policy: LessonPolicy

    @property
    def client(self) -> viser.ClientHandle: ...

    @property
    def model(self) -> SceneModel: ...

    @property
    def lock(self) -> AbstractContextManager[object]: ...

    @property
    def closed(self) -> bool: ...

    @property
    def open_demo(self) -> Callable[..., object] | None: ...

    def redraw(self) -> None: ...

    def report(self, exc: BaseException) -> None: ...


#: The *your name* field's hint for a class student (the field is read-only).
HELD_NAME_HINT = "In the class your progress is kept under the name you joined with."


def refuse_held_name(field: viser.GuiTextHandle, held: str, text: object) -> None:
    """A class student's *your name* ``field`` was sent ``text``: nothing if it is ``held``, the name they joined
    with (the field showing it again); else the field shows ``held`` again and the change is refused (their progress
    never goes under another name, perhaps another student's).

    Raises:
        FieldError: ``text`` is not ``held``.
    """
    if text == held:
        return
    show_name_in_use(field, held)
    raise FieldError(f"your name: in the class your progress is kept under the name you joined with, {held}")


def _feedback_markdown(passed: bool, feedback: str, hint: str | None, *, unread: bool = False) -> str:
    """One attempt as shown: the verdict, the check's feedback (plain text), the hints shown so far (Markdown, each
    labelled by the runner) after a failure. An answer that could not be read (``unread``) gets no verdict: it was
    not judged."""
    text = escape(feedback, quote=False).replace("*", "\\*").replace("_", "\\_")
    if passed:
        return f"**\u2713 Passed.** {text}"
    out = f"**Answer not read.** {text}" if unread else f"**\u2717 Not yet.** {text}"
    if hint:
        out += f"\n\n{hint}"
    return out


class TaskRow:
    """One task of the step in the panel: prompt, the answer widget the task declares, Check button, feedback."""

    def __init__(self, gui: viser.GuiApi, number: int, resolved: ResolvedTask, *, passed_before: bool) -> None:
        self.task_id = resolved.task.id
        self.number = number
        self.prompt = gui.add_markdown(f"**Task {number}.** {resolved.prompt_html}")
        self.widget = answer_widget(gui, f"answer {number}", resolved.task.needs.answer)
        #: The GUI handle the learner answers in (None: the task is done in the scene).
        self.answer: viser.GuiInputHandle[str] | None = self.widget.field
        self.button = gui.add_button(f"Check task {number}")
        self.feedback = gui.add_markdown("\u2713 passed before." if passed_before else "")

    def answer_text(self) -> str | None:
        """The learner's answer, checked for what the page can send (None: the task asks no question)."""
        return self.widget.text()


class StepNav:
    """The step's header: title, "step k of n", the progress bar and the step buttons."""

    def __init__(self, gui: viser.GuiApi) -> None:
        self.head = gui.add_html("")
        self.bar = gui.add_progress_bar(0.0, color="teal")
        self.buttons = gui.add_button_group("step", STEP_BUTTONS)


class LessonPanel:
    """A lesson in a workbench tab: the skin of a :class:`~egtviz.controllers.lesson.LessonController`.

    Args:
        view: the tab's :class:`~egtviz.viewer.workbench.app.ClientView`; its model must be ``run.model``.
        run: the lesson run (already at the learner's remembered step).
        progress: where progress is kept when the learner types a name here.
        on_back: opens the course's start page in this tab (None: no such button).
        on_learner: told the learner's name whenever it changes (the course remembers it for the tab).
        field_delay: seconds the name field must stay unchanged before the name is taken (the field sends
            every keystroke: "Ada" must not make learners "A" and "Ad"); 0: at once.
    """

    def __init__(self, view: LessonTab, run: LessonRun, *, progress: ProgressStore | None = None,
                 on_back: Callable[[], object] | None = None, on_learner: Callable[[str], None] | None = None,
                 field_delay: float = 0.0) -> None:
        if view.model is not run.model:
            raise SceneError("the lesson's scene could not be drawn in this tab")
        self.view = view
        self._on_learner = on_learner
        #: In a class, the name the student joined with: the name field shows it read-only (None: free).
        self.held_name: str | None = None
        self._typing = Debouncer(field_delay)
        self.rows: list[TaskRow] = []
        #: The lesson's summary under the last step's tasks (None on the other steps).
        self.summary: viser.GuiMarkdownHandle | None = None
        self.lab: LabPanel | None = None
        self.lens: LensPanel | None = None
        #: The button that opens the step's servo run (None: the step has none).
        self.demo_button: viser.GuiButtonHandle | None = None
        client = view.client
        gui = client.gui
        with view.lock, client.atomic():
            #: The lesson itself: the run, its intents and its state; this panel draws it.
            self.controller = LessonController(run, progress=progress)
            # A displayed formula wider than the control panel scrolls instead of running past its edge.
            gui.add_html(MATH_CSS, order=LESSON_ORDER - 1)
            # A long title in the folder's legend would wrap over the folder's first line: it goes in the head.
            self.folder = gui.add_folder("Lesson", order=LESSON_ORDER, expand_by_default=True)
            with self.folder:
                self.nav = StepNav(gui)
                self._notice = self.controller.progress_problem
                self.notice = gui.add_html(progress_notice_html(self._notice))
                self.text = gui.add_markdown("")
                self.tasks_folder = gui.add_folder(None)
                self.ranges = gui.add_html("")
                self.learner = gui.add_text("your name", run.learner,
                                            hint="Your progress is kept under this name: type it again in any tab, "
                                                 "or after a restart, to resume where you were.")
                self.btn_back = gui.add_button("Back to the course") if on_back is not None else None
            needs = self.controller.needs
            panel_filter = None
            if needs.lab:
                self.lab = LabPanel(client, run, redraw=view.redraw, report=view.report, order=LAB_ORDER,
                                    drawn=needs.lab_draws)
                panel_filter = self.lab.panel_filter
            elif needs.lens:
                self.lens = LensPanel(gui, run, redraw=view.redraw, report=view.report, order=LENS_ORDER)
                panel_filter = self.lens.panel_filter
            # A typed field asks the ranges first (the policy's field_guard) so that its refusal says the range and
            # nothing else; the model holds them for every other route.
            view.policy = LessonPolicy(panel_filter=panel_filter, field_guard=self.controller.constraints.refusal,
                                       display=lambda: self.run.step.display)
            self._show_step()
            view.redraw()
        self._on(self.nav.buttons.on_click, lambda e: self._navigate(e.target.value))
        self._on(self.learner.on_update, lambda e: self._name_typed(e.target.value))
        if self.btn_back is not None and on_back is not None:
            self._on(self.btn_back.on_click, lambda _: on_back())

    @property
    def run(self) -> LessonRun:
        """The controller's lesson run (a new one when the learner changes)."""
        return self.controller.run

    @property
    def may_enter(self) -> StepGate | None:
        """``may_enter(lesson, step)``: whether "next" may open that step (a class's pacing); None: always."""
        return self.controller.may_enter

    @may_enter.setter
    def may_enter(self, gate: StepGate | None) -> None:
        self.controller.may_enter = gate

    @property
    def attempts(self) -> dict[str, Attempt]:
        """The last attempt per task id in this step (tests read it; the page shows it)."""
        return self.controller.attempts

    def _on(self, register: Callable[[Callable[[_Event], None]], object], callback: Callable[[_Event], object]) -> None:
        """Attach ``callback`` safely; it runs under the tab's lock, and not after the tab closed."""

        def locked(event: _Event) -> None:
            with self.view.lock:
                if self.view.closed:
                    return
                try:
                    callback(event)
                finally:
                    self._show_notice()

        on_event(register, locked, self.view.report)

    def _show_notice(self) -> None:
        """Once progress stops being kept (the store fell back to memory), say so in this tab, once."""
        problem = self.controller.progress_problem
        if problem == self._notice:
            return
        self._notice = problem
        self.notice.content = progress_notice_html(problem)
        if problem:
            try:
                self.view.client.add_notification("Progress is not being kept", problem, color="yellow",
                                                  auto_close_seconds=15.0)
            except Exception:  # noqa: BLE001 - the tab may be gone; the notice stays in the panel
                pass

    def _name_typed(self, text: object) -> None:
        """The name field changed: take the name once the typing stops (latest text wins); a class student's
        name is refused at once."""
        if self.held_name is not None:
            refuse_held_name(self.learner, self.held_name, text)
            return
        self._typing.submit("learner", lambda: self._later(lambda: self._set_learner(text)))

    def _later(self, action: Callable[[], None]) -> None:
        """Run a debounced action (from a timer thread: no callback wrapper above it) under the tab's lock."""
        try:
            with self.view.lock:
                if not self.view.closed:
                    try:
                        action()
                    finally:
                        self._show_notice()
        except Exception as exc:  # noqa: BLE001 - every failure must reach the tab
            self.view.report(exc)

    # -- the step ----------------------------------------------------------------------------

    def _show_step(self) -> None:
        """Show the controller's current step: header, text, tasks (with what was passed before), ranges,
        instruments."""
        state = self.controller.step_state()
        gui = self.view.client.gui
        self.nav.head.content = (
            f'<div style="font-size:0.9em" data-egtviz="lesson-head" data-step="{state.index}">'
            f'<div style="color:#555">{escape(state.lesson_title)}</div>'
            f"<b>Step {state.index + 1} of {state.count}: {escape(state.title)}</b></div>"
        )
        # viser's value setter sits apart from its getter: mypy takes the property as read-only.
        self.nav.bar.value = state.percent  # type: ignore[misc]
        self.text.content = state.html
        self.tasks_folder.remove()
        self.rows = []
        self.demo_button = None
        with self.folder:
            self.tasks_folder = gui.add_folder(None, order=self.text.order + 0.5)
        with self.tasks_folder:
            if state.demo is not None:
                self._add_demo_row(state.demo)
            for task in state.tasks:
                row = TaskRow(gui, task.number, task.resolved, passed_before=task.passed_before)
                self._on(row.button.on_click, self._checker(row))
                self.rows.append(row)
            # The lesson's end: what the learner did in it and what comes next, kept current by each check.
            self.summary = gui.add_markdown(state.summary) if state.summary is not None else None
        limits = [f"{escape(r.camera)}: {escape(r.label)} {escape(r.shown)}" for r in state.ranges]
        self.ranges.content = ('<div style="font-size:0.8em">In this step: ' + "; ".join(limits) + "</div>"
                               if limits else "")
        for instrument in (self.lab, self.lens):
            if instrument is not None:
                instrument.sync()

    def _add_demo_row(self, demo: OpenDemo) -> None:
        """The step's servo run: what it is, and a button that opens the demo with its run fields."""
        gui = self.view.client.gui
        settings = demo.describe() or "its default settings"
        opener = self.view.open_demo
        how = ("" if opener is not None else
               f" Open it with <code>egtviz --demo {escape(demo.demo)}</code> and set those fields.")
        self.demo_info = gui.add_html(
            f'<div style="font-size:0.85em;padding:0 0.75em" data-egtviz="lesson-demo" data-demo="{escape(demo.demo)}">'
            f"This step's run: {escape(DEMO_TITLES[demo.demo])} with {escape(settings)}.{how}</div>")
        if opener is not None:
            self.demo_button = gui.add_button("Open the demo with these settings")
            on_event(self.demo_button.on_click,
                     lambda _: None if self.view.closed else opener(demo.demo, **demo.options()), self.view.report)

    def _navigate(self, action: object) -> None:
        if action not in STEP_BUTTONS:  # a raw client can send any string
            raise FieldError(f"step: no button {str(action)[:40]!r}")
        with self.view.client.atomic():
            if action == "next":
                self.controller.next()
            elif action == "previous":
                self.controller.previous()
            else:
                self.controller.reset_step()
            self._show_step()
            self.view.redraw()

    def hold_learner(self, name: str) -> None:
        """A class student's lesson: the learner is ``name``, the one they joined with, shown read-only."""
        with self.view.lock:
            self.held_name = name
            self.learner.disabled = True
            self.learner.hint = HELD_NAME_HINT

    def hold_back(self, step: int) -> bool:
        """Go back to ``step`` if the run is past it (a class's pacing tightened). False: it is not, or the tab
        closed."""
        with self.view.lock:
            if self.view.closed or self.run.step_index <= step:
                return False
            with self.view.client.atomic():
                self.controller.hold_back(step)
                self._show_step()
                self.view.redraw()
        return True

    def go_to(self, index: int) -> None:
        """Start step ``index`` (tests; the page uses the step buttons)."""
        with self.view.lock, self.view.client.atomic():
            self.controller.go_to(index)
            self._show_step()
            self.view.redraw()

    # -- tasks --------------------------------------------------------------------------------

    def _checker(self, row: TaskRow) -> Callable[[viser.GuiEvent[viser.GuiButtonHandle]], None]:
        """The click callback of ``row``'s check button."""
        return lambda _event: self._check(row)

    def _check(self, row: TaskRow) -> None:
        outcome = self.controller.check(row.task_id, row.answer_text())
        row.feedback.content = _feedback_markdown(outcome.passed, outcome.feedback, outcome.hint,
                                                  unread=outcome.unread)
        if self.summary is not None and outcome.summary is not None:
            self.summary.content = outcome.summary

    def row(self, task_id: str) -> TaskRow:
        """The task row of ``task_id`` in the current step."""
        for row in self.rows:
            if row.task_id == task_id:
                return row
        raise KeyError(f"task: no task {task_id!r} in this step")

    # -- the learner ------------------------------------------------------------------------------

    def _set_learner(self, name: object) -> None:
        """A name typed: the run is keyed by it from now on, and resumes where that learner was. A refused name
        is not left in the field: it shows the name in use again, and the notification says why."""
        try:
            key = typed_learner_key(name)
        except FieldError:
            show_name_in_use(self.learner, self.run.learner)
            raise
        if key == self.run.learner:
            return
        with self.view.client.atomic():
            self.controller.set_learner(key)
            for instrument in (self.lab, self.lens):
                if instrument is not None:
                    instrument.run = self.run
            self._show_step()
            self.view.redraw()
        if self._on_learner is not None:
            self._on_learner(key)
