"""The instructor's controls, at the top of the instructor's tab: follow me, release, lock cameras, pause,
pacing, the roster, the question and its live histogram, snapshots, the roster as CSV and the student URL's QR
code.

The panel is a skin over an :class:`~egtviz.controllers.class_member.InstructorController`: its widgets become the
controller's intents and it draws the controller's state. What each control does to the students' tabs is the
:class:`~egtviz.viewer.classroom.host.ClassroomHost`'s job (the panel knows it as a :class:`PanelHost`: the host
builds the panels, so the panel cannot name the host's class). Names, questions and messages are shown as text.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from html import escape
from typing import Protocol

import viser

from ...classroom import Classroom, Mode
from ...controllers.class_member import RELEASE_TO, InstructorController
from ...controllers.class_text import ClassRefusal
from ..workbench.fields import on_event
from .links import qr_svg
from .room_html import histogram_html, pacing_html, roster_html, status_html

__all__ = ["ALL_STEPS", "InstructorPanel", "PanelHost", "SnapshotPicker"]

#: The pacing field's text for "every step".
ALL_STEPS = ""
#: The snapshot buttons' choices.
SHOW_SNAPSHOT, HIDE_SNAPSHOT = "show to the room", "hide"
_NO_STUDENT = "(nobody)"


class PanelHost(Protocol):
    """What the panel reads of the class's host and calls on it (the host is
    :class:`~egtviz.viewer.classroom.host.ClassroomHost`)."""

    @property
    def room(self) -> Classroom: ...

    @property
    def student_url(self) -> str: ...

    def lesson_steps(self) -> dict[str, int]: ...

    def student_tabs(self) -> dict[str, int]: ...

    def publish(self, client: viser.ClientHandle) -> None: ...


class SnapshotPicker:
    """The panel's "Snapshot" folder: the connected student whose scene to show the room, and the buttons.

    Args:
        gui: the instructor tab's GUI (the folder is added where the caller's ``with`` puts it).
    """

    def __init__(self, gui: viser.GuiApi) -> None:
        self._tabs: dict[str, int] = {}
        with gui.add_folder("Snapshot", expand_by_default=False):
            self.student = gui.add_dropdown("student", (_NO_STUDENT,), initial_value=_NO_STUDENT)
            self.buttons = gui.add_button_group("snapshot", (SHOW_SNAPSHOT, HIDE_SNAPSHOT))

    def offer(self, tabs: dict[str, int]) -> None:
        """The students to choose from now: their names and one tab of each."""
        self._tabs = tabs
        options = tuple(tabs) or (_NO_STUDENT,)
        if tuple(self.student.options) != options:
            self.student.options = options

    def chosen_tab(self) -> int | None:
        """The chosen student's tab (None: nobody, or a student no longer connected)."""
        return self._tabs.get(self.student.value)


class InstructorPanel:
    """The "Classroom" folder of one instructor tab.

    Args:
        client: the instructor's tab.
        host: the class's host (the classroom, the student URL, the course's lessons, the students' tabs).
        report: shows an exception in the tab.
    """

    def __init__(self, client: viser.ClientHandle, host: PanelHost,
                 report: Callable[[BaseException], None]) -> None:
        self.client = client
        self.host = host
        #: What the controls do and what the panel shows (its class, ``control.room``, is the host's).
        self.control = InstructorController(host.room, host.lesson_steps)
        self._report = report
        # Per thread: a value written back by refresh() calls its callbacks at once, in the refreshing thread.
        self._syncing = threading.local()
        self._shown: dict[int, bool] = {}  # id(checkbox) -> the class state last written to it
        gui = client.gui
        with client.atomic(), gui.add_folder("Classroom", order=-1000.0, expand_by_default=True):
            self.status = gui.add_html("")
            self.follow_me = gui.add_checkbox("follow me", self.control.room.mode is Mode.FOLLOW,
                                              hint="Every student's tab shows your scene, live.")
            self.release = gui.add_button_group("release to", tuple(RELEASE_TO))
            self.lock = gui.add_checkbox("lock students' cameras", self.control.room.cameras_locked,
                                         hint="Followers see the scene from your viewpoint and cannot turn it.")
            self.pause_text = gui.add_text("pause message", "Eyes on the projector, please.")
            self.pause = gui.add_button("Pause every screen", icon=viser.Icon.PLAYER_PAUSE)
            self._build_join(gui)
            self._build_roster(gui)
            self._build_question(gui)
            self.snapshot = SnapshotPicker(gui)
            self._build_pacing(gui)
        self._wire()
        self.refresh()

    def _build_join(self, gui: viser.GuiApi) -> None:
        with gui.add_folder("Join (student URL)", expand_by_default=False):
            url = self.host.student_url
            self.join = gui.add_html(
                f'<div data-egtviz="join-qr" style="padding:0 0.6em;text-align:center">{qr_svg(url) if url else ""}'
                f'<div style="font-size:1.1em;word-break:break-all">{escape(url)}</div></div>')

    def _build_roster(self, gui: viser.GuiApi) -> None:
        # The button above the list: a roster that grows as students join never moves it under a click.
        with gui.add_folder("Students", expand_by_default=False):
            self.csv = gui.add_button("Download roster (CSV)", icon=viser.Icon.DOWNLOAD)
            self.roster = gui.add_html("")

    def _build_question(self, gui: viser.GuiApi) -> None:
        with gui.add_folder("Question", expand_by_default=True):
            self.question = gui.add_text("question", "")
            self.ask = gui.add_button_group("ask the room", ("ask", "clear"))
            self.show_names = gui.add_checkbox("show names", self.control.room.names_shown(),
                                               hint="Off on a projector: only counts are shown.")
            self.histogram = gui.add_html("")

    def _build_pacing(self, gui: viser.GuiApi) -> None:
        lessons = tuple(self.host.lesson_steps()) or ("(no lessons)",)
        with gui.add_folder("Pacing", expand_by_default=False):
            self.lesson = gui.add_dropdown("lesson", lessons, initial_value=lessons[0])
            self.max_step = gui.add_text("up to step", ALL_STEPS, hint="Blank: every step.")
            self.only = gui.add_checkbox("only this lesson", False)
            self.apply_pacing = gui.add_button("Apply pacing")
            self.pacing = gui.add_html("")

    def _wire(self) -> None:
        control, rep = self.control, self._report
        on_event(self.follow_me.on_update, lambda e: self._unless_syncing(
            lambda: self._follow_me(bool(e.target.value))), rep)
        on_event(self.release.on_click, lambda e: control.release(e.target.value), rep)
        on_event(self.lock.on_update, lambda e: self._unless_syncing(
            lambda: control.lock_cameras(bool(e.target.value))), rep)
        on_event(self.pause.on_click, lambda _: control.toggle_pause(self.pause_text.value), rep)
        on_event(self.csv.on_click, lambda _: self.client.send_file_download(
            "egtviz-roster.csv", control.roster_csv(), save_immediately=True), rep)
        on_event(self.ask.on_click, lambda e: control.ask(self.question.value) if e.target.value == "ask"
                 else control.clear_question(), rep)
        on_event(self.show_names.on_update, lambda e: self._unless_syncing(
            lambda: control.show_names(bool(e.target.value))), rep)
        on_event(self.snapshot.buttons.on_click, lambda e: self._snapshot(e.target.value), rep)
        on_event(self.apply_pacing.on_click, lambda _: control.pace(self.lesson.value, self.max_step.value,
                                                                    self.only.value), rep)

    # -- actions ---------------------------------------------------------------------------------------

    def _unless_syncing(self, action: Callable[[], None]) -> None:
        """Run a checkbox's action, unless the change is :meth:`refresh` writing the class's state back."""
        if not getattr(self._syncing, "on", False):
            action()

    def _follow_me(self, on: bool) -> None:
        if self.control.follow_me(on):
            self.host.publish(self.client)  # the students follow this tab: its scene is the room's now

    def _snapshot(self, action: str) -> None:
        if action == HIDE_SNAPSHOT:
            self.control.hide_snapshot()
        elif action == SHOW_SNAPSHOT:
            self.control.show_snapshot(self.snapshot.chosen_tab())
        else:
            raise ClassRefusal("snapshot: no such action")

    # -- what the panel shows -----------------------------------------------------------------------------

    def refresh(self) -> None:
        """Show the room as it is now: status, roster, students to snapshot, the histogram, the pacing."""
        state = self.control.state()
        with self.client.atomic():
            self.status.content = status_html(state.status)
            self.pause.label = "Resume every screen" if state.status.paused is not None else "Pause every screen"
            self._sync_checkbox(self.follow_me, state.follow_me)
            self._sync_checkbox(self.lock, state.cameras_locked)
            self._sync_checkbox(self.show_names, state.names_shown)
            self.roster.content = roster_html(state.roster)
            self.snapshot.offer(self.host.student_tabs())
            self.histogram.content = histogram_html(state.answers)
            self.pacing.content = pacing_html(state.pacing)

    def _sync_checkbox(self, box: viser.GuiCheckboxHandle, state: bool) -> None:
        """Show the class's ``state`` in ``box`` when that state changed since it was last shown there.

        Only a change of the class is written: a click whose callback has not run yet has already set the box's
        value, and writing the unchanged class state back over it would turn the click around.
        """
        if self._shown.get(id(box)) == state:
            return
        self._shown[id(box)] = state
        if box.value != state:
            self._syncing.on = True
            try:
                # viser's input handle has a value setter (it syncs the box); mypy sees the props' read-only one.
                box.value = state  # type: ignore[misc]
            finally:
                self._syncing.on = False
