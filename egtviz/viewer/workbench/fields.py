"""GUI input of the viewer: the typing delay of a text field, and every callback made safe.

What a field's text means (its parsing and its number rules) is headless:
:mod:`egtviz.controllers.workbench_fields`. This module holds what only a page needs: judging a field once the user
stopped typing (:class:`Debouncer`), and attaching every callback so that whatever it raises reaches the tab as a
notification (:func:`on_event`, :func:`describe_error`).
"""

from __future__ import annotations

import math
import sys
import threading
import traceback
from collections.abc import Callable, Hashable
from typing import TYPE_CHECKING, TypeVar

from ...scene import SceneError

if TYPE_CHECKING:
    import viser

__all__ = [
    "Debouncer",
    "safe_callback",
    "on_event",
    "describe_error",
    "notify_error",
]

#: The event a viser handle passes its callbacks (a ``GuiEvent``, a ``TransformControlsEvent``, a camera).
E = TypeVar("E")


class Debouncer:
    """Run the latest action given for a key once no newer one arrived for ``delay`` seconds.

    A text field sends its text on every keystroke; ``0.5`` arrives as ``0``,
    ``0.``, ``0.5``. Judging only the text the user stopped at keeps a refusal
    of ``0`` from reverting the field under their fingers. ``delay = 0`` runs
    each action at once, in the caller's thread.
    """

    def __init__(self, delay: float) -> None:
        if not (isinstance(delay, (int, float)) and math.isfinite(delay) and delay >= 0):
            raise ValueError(f"delay: expected a finite number of seconds >= 0, got {delay!r}")
        self.delay = float(delay)
        self._lock = threading.Lock()
        self._timers: dict[Hashable, threading.Timer] = {}
        self._closed = False

    def submit(self, key: Hashable, action: Callable[[], None]) -> None:
        """Schedule ``action`` for ``key``, replacing the one not yet run."""
        if self.delay == 0:
            action()
            return
        timer = threading.Timer(self.delay, self._fire, args=(key, action))
        timer.daemon = True
        with self._lock:
            if self._closed:
                return
            old = self._timers.pop(key, None)
            self._timers[key] = timer
        if old is not None:
            old.cancel()
        timer.start()

    def _fire(self, key: Hashable, action: Callable[[], None]) -> None:
        with self._lock:
            if self._timers.get(key) is not threading.current_thread():
                return  # replaced by a newer action after this timer had already started
            del self._timers[key]
        action()

    def pending(self) -> bool:
        with self._lock:
            return bool(self._timers)

    def close(self) -> None:
        """Drop every pending action."""
        with self._lock:
            self._closed = True
            timers, self._timers = list(self._timers.values()), {}
        for t in timers:
            t.cancel()


def describe_error(exc: BaseException) -> tuple[str, str]:
    """``(title, message)`` of the notification a tab gets for ``exc``.

    Refusals (:class:`SceneError`, which includes scene-file errors) carry
    messages written for the user. Anything else is a fault of the program:
    the tab gets its type only, since its text can hold server paths; the
    details go to the server's log.
    """
    from ...scene import SceneFileError

    if isinstance(exc, SceneFileError):
        return "Could not load the scene", _short(str(exc))
    if isinstance(exc, SceneError):
        return "Value refused", _short(str(exc))
    return "Something went wrong", f"{type(exc).__name__} (the details are in the server's log); the tab carries on."


def notify_error(client: viser.ClientHandle, exc: BaseException, *, title: str | None = None) -> None:
    """Show ``exc`` in ``client``'s tab as a red notification (:func:`describe_error`; ``title`` replaces its
    title). A tab that is already gone is left alone."""
    default_title, body = describe_error(exc)
    try:
        client.add_notification(title or default_title, body, color="red", auto_close_seconds=8.0)
    except Exception:  # noqa: BLE001 - the client may be gone
        pass


def _short(message: str, limit: int = 500) -> str:
    clean = "".join(c if c.isprintable() or c == "\n" else "?" for c in message)
    return clean if len(clean) <= limit else clean[:limit] + " ..."


def safe_callback(callback: Callable[[E], object], report: Callable[[BaseException], None]) -> Callable[[E], None]:
    """``callback`` wrapped so that any exception it raises goes to ``report`` instead of viser's thread pool."""

    def run(event: E) -> None:
        try:
            callback(event)
        except Exception as exc:  # noqa: BLE001 - every failure must reach the tab, none may escape
            if not isinstance(exc, SceneError):
                traceback.print_exception(exc, file=sys.stderr)
            try:
                report(exc)
            except Exception as inner:  # noqa: BLE001 - the tab may be gone; the server carries on
                traceback.print_exception(inner, file=sys.stderr)

    return run


def on_event(register: Callable[[Callable[[E], None]], object], callback: Callable[[E], object],
             report: Callable[[BaseException], None]) -> None:
    """Register ``callback`` through ``register`` (``handle.on_update``, ``on_click``, ``on_upload``) safely.

    The one way the viewer attaches a callback to a viser handle: see :func:`safe_callback`.
    """
    register(safe_callback(callback, report))
