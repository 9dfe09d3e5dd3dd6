"""A student's controls in a class: the name they join under, their bar (follow or not, the question asked,
their answer) and the paused screen.

The bar is a skin over a :class:`~egtviz.controllers.class_member.StudentController`: its buttons become the
controller's intents and it draws the controller's state. It sits at the top of whatever the tab shows (a
following view, their own workbench, a lesson); it is built again whenever the tab is cleared. Every callback's
failure is shown in the tab (:func:`egtviz.viewer.workbench.fields.on_event`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol
import viser

from ...controllers.class_member import StudentController
from ...controllers.class_state import StudentState
from ...controllers.class_text import as_refusal
from ..render.palette import PRESENT_GUI_CSS
from ..workbench.fields import notify_error, on_event
from .room_html import pause_html, student_status_html

__all__ = ["BAR_ORDER", "JoinPage", "StudentBar", "notify_refusal", "stored_name"]

#: GUI order of the bar: above everything a workbench or a lesson adds.
BAR_ORDER = -1000.0
#: The join page's width and margin (CSS pixels).
JOIN_WIDTH_PX = 480
JOIN_MARGIN_PX = 16


class _Modal(Protocol):
    """The paused screen's modal (viser exports no name for its handle): entered to fill it, closed to go."""

    def __enter__(self) -> object: ...

    def __exit__(self, *args: object) -> None: ...

    def close(self) -> None: ...


def stored_name(client: viser.ClientHandle, key: str, timeout: float) -> str | None:
    """The name the tab's browser keeps under ``key`` (a student back after a reconnect); None if it keeps none,
    or does not answer within ``timeout`` seconds."""
    try:
        value = client.local_storage.get_item(key, timeout=timeout)
    except Exception:  # noqa: BLE001 - no storage, or no answer in time: the student types their name
        return None
    return value if isinstance(value, str) and value.strip() else None


class JoinPage:
    """The first thing a student sees: a name field and a button to join the class.

    Args:
        client: the tab.
        on_join: called with the typed name (it raises what is wrong with it).
        report: shows an exception in the tab.
        present: presentation mode (large type).
    """

    def __init__(self, client: viser.ClientHandle, on_join: Callable[[str], None],
                 report: Callable[[BaseException], None], *, present: bool = False) -> None:
        gui = client.gui
        with client.atomic():
            gui.configure_theme(dark_mode=False, show_logo=False)
            try:  # a page of its own: floating at the top left, as the course's start page is
                gui.main_panel.float(x=JOIN_MARGIN_PX, y=JOIN_MARGIN_PX, width=JOIN_WIDTH_PX)
            except Exception:  # noqa: BLE001 - placement is cosmetic
                pass
            if present:
                gui.add_html(PRESENT_GUI_CSS)
            self.title = gui.add_html('<div data-egtviz="join" style="padding:0 0.6em"><h2 style="margin:0.3em 0">'
                                      "Join the class</h2>Type your name: your work and progress are kept under "
                                      "it, and come back if you reconnect.</div>")
            self.name = gui.add_text("your name", "")
            self.button = gui.add_button("Join", color="teal", icon=viser.Icon.ARROW_RIGHT)
        on_event(self.button.on_click, lambda _: on_join(self.name.value), report)


def notify_refusal(client: viser.ClientHandle, exc: BaseException) -> None:
    """:func:`~egtviz.viewer.workbench.fields.notify_error`, with the class's refusals (a name the course does not
    take, a question or an answer it cannot keep) shown as the refusal they are, in their own words
    (:func:`egtviz.controllers.class_text.as_refusal`)."""
    notify_error(client, as_refusal(exc))


class StudentBar:
    """The bar of a student who joined: status, follow / leave follow, and the question, if one is asked.

    Args:
        client: the tab.
        student: the student's controller (what the buttons do, what the bar shows).
        report: shows an exception in the tab.
    """

    def __init__(self, client: viser.ClientHandle, student: StudentController, *,
                 report: Callable[[BaseException], None]) -> None:
        self.client = client
        self.student = student
        self.following = False
        self.question: str | None = None
        self._modal: _Modal | None = None
        gui = client.gui
        with client.atomic():
            self.status = gui.add_html("", order=BAR_ORDER)
            self.btn_follow = gui.add_button("Follow the instructor", order=BAR_ORDER + 0.1,
                                             icon=viser.Icon.PLAYER_PLAY)
            self.answer = gui.add_text("your answer", "", order=BAR_ORDER + 0.2, visible=False)
            self.btn_answer = gui.add_button("Send my answer", order=BAR_ORDER + 0.3, visible=False)
        on_event(self.btn_follow.on_click, lambda _: student.follow(not self.following), report)
        on_event(self.btn_answer.on_click, lambda _: self._send(), report)

    def _send(self) -> None:
        self.student.answer(self.question, self.answer.value)  # the question the student reads
        self.client.add_notification("Answer sent", "The instructor sees it (without your name).", color="green",
                                     auto_close_seconds=3.0)

    def show(self, state: StudentState) -> None:
        """Show whether the tab follows the instructor, and the question asked (the pause is :meth:`set_paused`'s:
        it is drawn only when it changes)."""
        self.following, self.question = state.following, state.question
        with self.client.atomic():
            self.status.content = student_status_html(state.name, state.following, state.question)
            self.btn_follow.label = "Leave follow (my own scene)" if state.following else "Follow the instructor"
            self.answer.visible = self.btn_answer.visible = state.question is not None

    def set_paused(self, message: str | None) -> None:
        """Cover the screen with the instructor's message (None: take it away)."""
        if self._modal is not None:
            try:
                self._modal.close()
            except Exception:  # noqa: BLE001 - gone with a cleared tab
                pass
            self._modal = None
        if message is not None:
            self._modal = self.client.gui.add_modal("The class is paused")
            with self._modal:
                self.client.gui.add_html(pause_html(message))
