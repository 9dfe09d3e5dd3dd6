"""The lesson runner in a tab: the step's text, its tasks with their answers and checks, and the way through.

A :class:`LessonPanel` sits at the top of a workbench tab's control panel and drives one
:class:`~egtviz.lessons.LessonRun` on the tab's own :class:`~egtviz.scene.SceneModel`: the workbench below
it (gizmos, fields, panels) is the learner's instrument, and the run's checks read the same scene. It shows

* the lesson's title, "step k of n" and a progress bar;
* "previous", "reset step" and "next" (entering a step applies its scene changes through the run);
* the step's text (Markdown with the formulas as MathML);
* each task: its prompt, the answer widget it declares (:attr:`~egtviz.lessons.tasks.Task.needs`, built by its
  skin in :mod:`egtviz.viewer.course.answers`), a "Check" button, the feedback on each attempt and the hint
  after a failed one;
* the learner's name: progress (the step, the tasks passed) is kept under it in the
  :class:`~egtviz.lessons.ProgressStore`, so a reload, a new tab or a restarted server resumes there;
* the estimation lab (:mod:`egtviz.viewer.course.lab_view`) or the convention lens (:mod:`egtviz.viewer.course.lens_view`)
  when the lesson uses them (:func:`egtviz.lessons.instruments.lesson_needs`); they draw the panels through the
  tab's lesson policy's ``panel_filter``;
* when the step has a servo run (an ``open_demo`` change), its settings and a button that opens that demo
  with them in this tab (the demo's *Back* button returns to the lesson, at the same step).

A ``set_range`` change of a step limits a camera field. The rule is the scene's
(:class:`~egtviz.scene.constraints.CameraRanges`, :func:`lesson_ranges` words it as the GUI fields): the model
holds it for every edit, the tab's lesson policy (``field_guard``) asks it so that a typed value outside is
refused with the range in the field's own unit (the field reverts), the panel lists the ranges, and a task is
not checked while the scene breaks them (:func:`range_refusal`: a script may still move a camera out of a
range). A gizmo drag is not refused but stopped, by the model, once per update: a ``position`` range stops the
camera at its edge, each coordinate clamped like a mechanical stop; under a ``ypr_deg`` range the camera keeps
the last orientation that respected it. The gizmo follows the pointer while it is held and shows the applied
pose when the drag ends. The browser's own gizmo limits (viser's ``translation_limits``, ``rotation_limits``)
are not used: they bound the offset along each of the gizmo's own, rotated, axes accumulated since the gizmo
was drawn, not the camera centre's world coordinates, and a pose the server sets does not reset them.

A lock is the scene model's (it refuses every edit of a locked pose); a check also fails, with *reset step*
as the way back, when a camera locked at the step's start (the model's undo barrier) has gone or moved
because the scene was replaced (:func:`lock_refusal`).

Every callback is attached through :func:`egtviz.viewer.workbench.fields.on_event`, so an error becomes a
notification in this tab.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import dataclass
from html import escape
from typing import Protocol, TypeVar

import numpy as np
import viser

from ...lessons import Lesson, LessonRun, ProgressStore
from ...lessons.changes import RANGED_FIELDS
from ...lessons.instruments import lesson_needs
from ...lessons.progress import LearnerNameError, learner_key
from ...lessons.runner import Attempt, ResolvedTask
from ...lessons.tasks import RESET_ADVICE
from ...scene import SceneError, SceneModel
from ...scene.constraints import CameraRanges
from ..workbench.camera_fields import field_of_spec
from ..workbench.fields import Debouncer, FieldError, NumberRule, format_number, on_event
from .answers import answer_widget
from .answers.choice import CHOOSE
from .lab_view import LabPanel
from .lens_view import LensPanel
from .progress_notice import progress_notice_html, show_name_in_use
from ..workbench.lesson_policy import LessonPolicy

__all__ = [
    "CHOOSE", "HELD_NAME_HINT", "LessonPanel", "LessonTab", "StepNav", "TaskRow", "lesson_instruments",
    "lesson_ranges", "lock_refusal", "pose_within_ranges", "range_refusal", "refuse_held_name", "typed_learner_key",
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


def lesson_instruments(lesson: Lesson) -> tuple[bool, bool]:
    """``(lab, lens)``: whether the lesson uses the estimation lab, the convention lens (its changes or tasks)."""
    needs = lesson_needs(lesson)
    return needs.lab, needs.lens


def range_refusal(run: LessonRun) -> str | None:
    """Why the scene breaks the step's ``set_range`` limits (a camera field outside its range), or None."""
    refusal = lesson_ranges(lambda: run).scene_refusal(run.model.scene)
    return None if refusal is None else refusal + "; bring it back into that range and check again."


def lock_refusal(run: LessonRun) -> str | None:
    """Why the scene breaks the step's locks, or None: a camera (or point) locked at the step's start (the model's
    undo barrier) that is gone or no longer where the step put it, whatever moved it (another scene opened,
    a script). The model refuses every edit of a locked pose; this catches what replaced the scene."""
    start = run.model.barrier_scene
    if start is None:
        return None
    scene = run.model.scene
    # A mirror's virtual camera is locked by its scene and follows the camera it reflects: it moves lawfully.
    derived = {m.virtual for m in start.annotations.mirrors} | {m.virtual for m in scene.annotations.mirrors}
    for name in sorted(start.locked - derived):
        if name.startswith("point:"):
            i = int(name[6:])
            if i >= len(scene.points):
                return f"Point {i + 1} is not in the scene any more: {RESET_ADVICE}"
            if scene.points[i] != start.points[i]:
                return f"Point {i + 1} must stay where this step put it (it is locked): {RESET_ADVICE}"
        elif name in start.camera_names:
            if name not in scene.camera_names:
                return f"{name} is not in the scene any more: {RESET_ADVICE}"
            a, b = start.camera(name), scene.camera(name)
            if a.position != b.position or a.ypr_deg != b.ypr_deg:
                return f"{name} must stay where this step put it (it is locked): {RESET_ADVICE}"
    return None


@dataclass(frozen=True)
class _RangeTerms:
    """A ranged spec field in the words and unit of its GUI field."""

    label: str
    rule: NumberRule
    """The rule of the range as shown, ``lo`` to ``hi``."""
    convert: Callable[[float], float]
    """Stored value -> shown value."""
    lo: float
    hi: float


def _range_terms(run: LessonRun, camera: str, field: str) -> _RangeTerms:
    """A ranged spec field in the words and unit of its GUI field, and its range as shown."""
    scene = run.model.scene
    limit = run.ranges[(camera, field)]
    convert: Callable[[float], float]
    if camera in scene.camera_names:
        shown = field_of_spec(scene.camera(camera), field)
        label, unit, convert = shown.label, shown.unit, shown.shown_number
    else:
        label, unit, convert = field.replace("_", " "), "", float
    unit = unit or (RANGED_FIELDS[field].unit if field in RANGED_FIELDS else "")
    lo, hi = sorted((convert(limit.low), convert(limit.high)))  # a reciprocal (pixel size) swaps the bounds
    return _RangeTerms(label, NumberRule(label, unit, lo, hi), convert, lo, hi)


def _range_words(run: LessonRun, camera: str, fields: dict[str, object]) -> str:
    """A breach of the step's ``set_range`` limit of ``camera``'s field (``fields``: that field and its value) in
    the GUI field's words and unit (the focal length in mm, the pixel size in µm), as the learner types it."""
    ((field, value),) = fields.items()
    terms = _range_terms(run, camera, field)
    rule = terms.rule
    values = value if isinstance(value, tuple) else (value,)
    shown = ", ".join(rule.with_units(terms.convert(float(v))) for v in values if isinstance(v, (int, float)))
    return (f"In this step {camera}'s {terms.label} must stay between {rule.with_units(terms.lo)} and "
            f"{rule.with_units(terms.hi)} (it is {shown})")


def lesson_ranges(run: Callable[[], LessonRun]) -> CameraRanges:
    """The step's ``set_range`` limits as the scene's constraints, worded as the GUI fields (``run()``: the run
    whose current step holds them)."""
    return CameraRanges(lambda: run().ranges, lambda camera, fields: _range_words(run(), camera, fields))


def pose_within_ranges(run: LessonRun, camera: str, position: np.ndarray,
                       R_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pose the scene's constraints give ``camera`` when a gizmo sends ``(position, R_world)`` under the
    step's ``set_range`` limits: what the model applies to that drag (:meth:`CameraRanges.judge`), as a pose.

    Returns:
        ``(position, R_world)``: the centre clamped into a ``position`` range (the nearest point of the box); the
        sent rotation itself, or the camera's current one when the sent one leaves a ``ypr_deg`` range.
    """
    spec = run.model.scene.camera(camera)
    sent = spec.with_world_pose(tuple(np.asarray(position, float).tolist()), R_world)
    allowed = lesson_ranges(lambda: run).judge(spec, sent, drag=True)
    kept = np.array_equal(allowed.pose.R, sent.pose.R)
    return np.array(allowed.position), R_world if kept else allowed.pose.R


def typed_learner_key(name: object) -> str:
    """The progress key of the name typed in a *your name* field; ``""`` for a blank field (no learner yet).

    Raises:
        FieldError: the name cannot be used (the field reverts, with the reason).
    """
    if not isinstance(name, str):
        raise FieldError(f"your name: expected text, got {type(name).__name__}")
    if not name.strip():
        return ""
    try:
        return learner_key(name)
    except LearnerNameError as exc:
        raise FieldError(str(exc)) from exc


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
    """A lesson in a workbench tab.

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
        self.run = run
        #: The step's ranges as the scene's constraints: the model and the typed fields ask them.
        self.constraints = lesson_ranges(lambda: self.run)
        self.progress = progress
        self._on_learner = on_learner
        #: ``may_enter(lesson, step)``: whether "next" may open that step (a class's pacing); None: always.
        self.may_enter: Callable[[str, int], bool] | None = None
        #: In a class, the name the student joined with: the name field shows it read-only (None: free).
        self.held_name: str | None = None
        self._typing = Debouncer(field_delay)
        self.rows: list[TaskRow] = []
        #: The lesson's summary under the last step's tasks (None on the other steps).
        self.summary: viser.GuiMarkdownHandle | None = None
        #: The last attempt per task id in this step (tests read it; the page shows it).
        self.attempts: dict[str, Attempt] = {}
        self.lab: LabPanel | None = None
        self.lens: LensPanel | None = None
        #: The button that opens the step's servo run (None: the step has none).
        self.demo_button: viser.GuiButtonHandle | None = None
        client = view.client
        gui = client.gui
        lesson = run.lesson
        with view.lock, client.atomic():
            # A displayed formula wider than the control panel scrolls instead of running past its edge.
            gui.add_html(MATH_CSS, order=LESSON_ORDER - 1)
            # A long title in the folder's legend would wrap over the folder's first line: it goes in the head.
            self.folder = gui.add_folder("Lesson", order=LESSON_ORDER, expand_by_default=True)
            with self.folder:
                self.nav = StepNav(gui)
                store = progress if progress is not None else run.progress
                self._notice = store.problem if store is not None else None
                self.notice = gui.add_html(progress_notice_html(self._notice))
                self.text = gui.add_markdown("")
                self.tasks_folder = gui.add_folder(None)
                self.ranges = gui.add_html("")
                self.learner = gui.add_text("your name", run.learner,
                                            hint="Your progress is kept under this name: type it again in any tab, "
                                                 "or after a restart, to resume where you were.")
                self.btn_back = gui.add_button("Back to the course") if on_back is not None else None
            needs = lesson_needs(lesson)
            panel_filter = None
            if needs.lab:
                self.lab = LabPanel(client, run, redraw=view.redraw, report=view.report, order=LAB_ORDER,
                                    drawn=needs.lab_draws)
                panel_filter = self.lab.panel_filter
            elif needs.lens:
                self.lens = LensPanel(gui, run, redraw=view.redraw, report=view.report, order=LENS_ORDER)
                panel_filter = self.lens.panel_filter
            # The model holds the ranges, for every route into it (a gizmo, a raw client message, a script); a typed
            # field asks them first (the policy's field_guard) so that its refusal says the range and nothing else.
            view.model.set_constraints(self.constraints)
            view.policy = LessonPolicy(panel_filter=panel_filter, field_guard=self.constraints.refusal,
                                       display=lambda: self.run.step.display)
            self._show_step()
            view.redraw()
        self._on(self.nav.buttons.on_click, lambda e: self._navigate(e.target.value))
        self._on(self.learner.on_update, lambda e: self._name_typed(e.target.value))
        if self.btn_back is not None and on_back is not None:
            self._on(self.btn_back.on_click, lambda _: on_back())

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
        store = self.progress if self.progress is not None else self.run.progress
        problem = store.problem if store is not None else None
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
        """Show the run's current step: header, text, tasks (with what was passed before), ranges, instruments."""
        run = self.run
        gui = self.view.client.gui
        n = len(run.lesson.steps)
        i = run.step_index
        self.nav.head.content = (
            f'<div style="font-size:0.9em" data-egtviz="lesson-head" data-step="{i}">'
            f'<div style="color:#555">{escape(run.lesson.title)}</div>'
            f"<b>Step {i + 1} of {n}: {escape(run.step.title)}</b></div>"
        )
        # viser's value setter sits apart from its getter: mypy takes the property as read-only.
        self.nav.bar.value = 100.0 * (i + 1) / n  # type: ignore[misc]
        self.text.content = run.step.html
        passed = run.progress.passed_tasks(run.learner, run.lesson.name) if run.progress is not None else frozenset()
        self.tasks_folder.remove()
        self.attempts = {}
        self.rows = []
        self.demo_button = None
        with self.folder:
            self.tasks_folder = gui.add_folder(None, order=self.text.order + 0.5)
        with self.tasks_folder:
            if run.demo is not None:
                self._add_demo_row(run)
            for k, resolved in enumerate(run.tasks(), start=1):
                row = TaskRow(gui, k, resolved, passed_before=(i, resolved.task.id) in passed)
                self._on(row.button.on_click, self._checker(row))
                self.rows.append(row)
            # The lesson's end: what the learner did in it and what comes next, kept current by each check.
            self.summary = gui.add_markdown(run.summary().markdown()) if run.on_last_step else None
        limits = []
        for c, f in sorted(run.ranges):
            terms = _range_terms(run, c, f)
            shown = f"{format_number(terms.lo)} to {terms.rule.with_units(terms.hi)}"
            limits.append(f"{escape(c)}: {escape(terms.label)} {escape(shown)}")
        self.ranges.content = ('<div style="font-size:0.8em">In this step: ' + "; ".join(limits) + "</div>"
                               if limits else "")
        for instrument in (self.lab, self.lens):
            if instrument is not None:
                instrument.sync()

    def _add_demo_row(self, run: LessonRun) -> None:
        """The step's servo run: what it is, and a button that opens the demo with its run fields."""
        demo = run.demo
        assert demo is not None
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
                ahead = self.run.step_index + 1
                if (self.may_enter is not None and ahead < len(self.run.lesson.steps)
                        and not self.may_enter(self.run.lesson.name, ahead)):
                    raise FieldError(f"step {ahead + 1}: the instructor has not opened it yet")
                self.run.next()
            elif action == "previous":
                self.run.previous()
            else:
                self.run.reset_step()
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
                self.run.go_to(step)
                self._show_step()
                self.view.redraw()
        return True

    def go_to(self, index: int) -> None:
        """Start step ``index`` (tests; the page uses the step buttons)."""
        with self.view.lock, self.view.client.atomic():
            self.run.go_to(index)
            self._show_step()
            self.view.redraw()

    # -- tasks --------------------------------------------------------------------------------

    def _checker(self, row: TaskRow) -> Callable[[viser.GuiEvent[viser.GuiButtonHandle]], None]:
        """The click callback of ``row``'s check button."""
        return lambda _event: self._check(row)

    def _check(self, row: TaskRow) -> None:
        answer = row.answer_text()
        refusal = lock_refusal(self.run) or range_refusal(self.run)
        if refusal is not None:
            row.feedback.content = _feedback_markdown(False, refusal, None)
            return
        attempt = self.run.check(row.task_id, answer)
        self.attempts[row.task_id] = attempt
        row.feedback.content = _feedback_markdown(attempt.result.passed, attempt.result.feedback, attempt.hint,
                                                  unread=attempt.result.unread)
        if self.summary is not None:
            self.summary.content = self.run.summary().markdown()

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
            self.run = LessonRun(self.run.lesson, key, model=self.view.model, progress=self.progress)
            for instrument in (self.lab, self.lens):
                if instrument is not None:
                    instrument.run = self.run
            self._show_step()
            self.view.redraw()
        if self._on_learner is not None:
            self._on_learner(key)
