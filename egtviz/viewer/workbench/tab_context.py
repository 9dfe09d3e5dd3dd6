"""What a workbench tab's parts share: its client and controller, its lock, its notifier and its event wrappers.

The parts of a tab (:mod:`~egtviz.viewer.workbench.workbench_controls`,
:mod:`~egtviz.viewer.workbench.camera_settings`, :mod:`~egtviz.viewer.workbench.drag_input`,
:mod:`~egtviz.viewer.workbench.panel_dock`) take one :class:`TabContext` rather than the tab's view: they need these
few services, not the view, and a part that imported the view would close a circle of imports with it.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, TypeVar

if TYPE_CHECKING:
    import threading

    import viser

    from ...controllers.workbench import WorkbenchController
    from .lesson_policy import LessonPolicy

__all__ = ["Attach", "TabContext", "TextEvent"]

#: The event a viser handle passes its callbacks (a ``GuiEvent``, a ``TransformControlsEvent``, a camera).
E = TypeVar("E")
#: What a text field sends (its text; a raw client may send another type).
T = TypeVar("T")


class Attach(Protocol):
    """``on(handle.on_update, callback)``: ``callback`` attached to a handle's event, whatever it raises reported."""

    def __call__(self, register: Callable[[Callable[[E], None]], object], callback: Callable[[E], object], /) -> None:
        ...


class TextEvent(Protocol):
    """``text_event(key, apply, text)``: ``apply(text)`` once the user stopped typing (latest text per ``key``)."""

    def __call__(self, key: Hashable, apply: Callable[[T], object], text: T, /) -> None:
        ...


@dataclass(frozen=True)
class TabContext:
    """One browser tab's services, as its view hands them to its parts.

    Attributes:
        client: the tab's :class:`viser.ClientHandle`.
        controller: the tab's :class:`~egtviz.controllers.workbench.WorkbenchController` (its scene model and the
            user's intents).
        lock: the lock every event and render of the tab runs under (re-entrant).
        report: tells the tab what went wrong and puts its fields and gizmos back to the model's values.
        on: ``on(handle.on_update, callback)`` attaches ``callback`` to a handle's event; whatever it raises goes to
            :attr:`report`.
        user_event: ``user_event(action)`` runs a user's action under the lock (ignored while fields are written
            back or once the tab is closed).
        text_event: ``text_event(key, apply, text)`` judges a text field's text once the user stopped typing
            (latest text per ``key`` wins).
        event_started: ``event_started(wall, cpu)`` marks the start of a user event the part runs itself (a gizmo).
        is_closed: whether the tab has left (its events are then ignored).
        redraw_now: draws the controller's scene again; the caller holds the lock.
        policy: what a lesson allows in the tab now (a lesson view may replace it after the parts are built).
    """

    client: viser.ClientHandle
    controller: WorkbenchController
    lock: threading.RLock
    report: Callable[[BaseException], None]
    on: Attach
    user_event: Callable[[Callable[[], object]], None]
    text_event: TextEvent
    event_started: Callable[[float, float], None]
    is_closed: Callable[[], bool]
    redraw_now: Callable[[], None]
    policy: Callable[[], LessonPolicy]
