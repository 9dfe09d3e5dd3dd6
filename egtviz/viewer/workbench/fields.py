"""GUI input: the raw text of a field parsed and checked in the user's units; every callback made safe.

viser's number and vector inputs parse what the user types in the browser and
send nothing for text they cannot read (``nan`` and ``abc`` leave the field
empty) or send something else (``1e400`` arrives as 1400, and a vector with
step 1 rounds 3.5 to 3). The viewer therefore uses text fields and parses
their raw text here, so that every value the user typed reaches the server
and is either accepted or refused with a message.

A number is plain decimal text, ``[+-] digits [. digits] [e [+-] digits]``;
a vector is such numbers separated by commas. A refusal names the owner (a
camera) and the field, in the field's own units::

    cam1: focal length must be between 0.1 mm and 1000 mm, got 0 mm
"""

from __future__ import annotations

import math
import os
import re
import sys
import threading
import traceback
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

from ...scene import SceneError
from ...scene.shown_numbers import shown_components

if TYPE_CHECKING:
    import viser

__all__ = [
    "FieldError",
    "NumberRule",
    "Debouncer",
    "format_number",
    "format_numbers",
    "parse_numbers",
    "safe_callback",
    "on_event",
    "describe_error",
]

#: The event a viser handle passes its callbacks (a ``GuiEvent``, a ``TransformControlsEvent``, a camera).
E = TypeVar("E")

#: Longest field text the server reads (anything longer is refused unread).
MAX_FIELD_CHARS = 200

_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


class FieldError(SceneError):
    """A GUI field's text that is not a valid value for that field (the message is for the user)."""


@dataclass(frozen=True)
class NumberRule:
    """What one GUI field accepts, in the field's own units.

    A value ``x`` is accepted when it is finite, ``lo <= x <= hi`` (a bound of
    ``None`` is open), and ``x`` is a whole number when ``integer``.
    """

    label: str
    """The field as the message names it, e.g. ``"focal length"``."""
    unit: str = ""
    """The field's unit as shown to the user, e.g. ``"mm"`` (empty: none)."""
    lo: float | None = None
    """Smallest accepted value (inclusive)."""
    hi: float | None = None
    """Largest accepted value (inclusive)."""
    integer: bool = False
    """Only whole numbers (``640`` or ``640.0``; ``640.5`` is refused, never rounded)."""

    def with_units(self, value: float) -> str:
        """``value`` written with the field's unit, e.g. ``"0 mm"``."""
        return f"{format_number(value)} {self.unit}".rstrip()

    def range_text(self) -> str:
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            return f"between {self.with_units(lo)} and {self.with_units(hi)}"
        if lo is not None:
            return f"at least {self.with_units(lo)}"
        if hi is not None:
            return f"at most {self.with_units(hi)}"
        return "a finite number"

    def check(self, value: float, owner: str = "") -> float:
        """``value`` if this field accepts it, else :class:`FieldError` naming ``owner`` and the field."""
        where = f"{owner}: " if owner else ""
        if not math.isfinite(value):
            raise FieldError(f"{where}{self.label} must be a finite number, got {format_number(value)}")
        if (self.lo is not None and value < self.lo) or (self.hi is not None and value > self.hi):
            raise FieldError(f"{where}{self.label} must be {self.range_text()}, got {self.with_units(value)}")
        if self.integer and value != math.floor(value):
            raise FieldError(f"{where}{self.label} must be a whole number, got {self.with_units(value)}")
        return value


def format_number(value: float) -> str:
    """A number as a field shows it: a whole number below 10^10 in full (a seed, a size), else six
    significant digits; never ``-0``."""
    value = float(value)
    if not math.isfinite(value):
        return str(value)
    if value.is_integer() and abs(value) < 1e10:
        return str(int(value))
    return f"{value + 0.0:.6g}"


def format_numbers(values: Iterable[float]) -> str:
    """A vector as a field shows it: ``"1.5, -4, 1.2"``. A component below ``ZERO_FRACTION`` of the vector's
    largest is rounding and is shown as 0, as in the read-out (a gizmo's turn gives a roll of 4e-15 degrees)."""
    return ", ".join(format_number(v) for v in shown_components(values))


def _show(text: str) -> str:
    """The user's text quoted in a message: printable characters only, at most 40 of them."""
    clean = "".join(c if c.isprintable() else "?" for c in text)
    return repr(clean if len(clean) <= 40 else clean[:40] + "...")


def parse_numbers(text: object, rules: tuple[NumberRule, ...], owner: str = "") -> tuple[float, ...]:
    """Parse a field's raw text into ``len(rules)`` numbers, each checked by its rule.

    Args:
        text: the field's text, e.g. ``"12.5"`` or ``"1.5, -4, 1.2"``.
        rules: one :class:`NumberRule` per number expected.
        owner: who the field belongs to (a camera name), for the message.

    Returns:
        The numbers, as floats (whole numbers when the rule says ``integer``).

    Raises:
        FieldError: the text is not ``len(rules)`` plain decimal numbers, or a number is refused by its rule.
    """
    where = f"{owner}: " if owner else ""
    # A vector's rules are "position x", "position y" ...: the field is named by what they share.
    label = os.path.commonprefix([r.label for r in rules]).strip() or rules[0].label
    if not isinstance(text, str):
        raise FieldError(f"{where}{label}: expected text, got {type(text).__name__}")
    if len(text) > MAX_FIELD_CHARS:
        raise FieldError(f"{where}{label}: expected at most {MAX_FIELD_CHARS} characters, got {len(text)}")
    tokens = [t.strip() for t in text.split(",")] if text.strip() else []
    n = len(rules)
    if len(tokens) != n:
        what = "a number" if n == 1 else f"{n} numbers separated by commas"
        raise FieldError(f"{where}{label}: expected {what}, got {_show(text)}")
    values = []
    for token, rule in zip(tokens, rules):
        if _NUMBER.fullmatch(token) is None:
            raise FieldError(f"{where}{rule.label}: expected a number, got {_show(token)}")
        value = float(token)
        if not math.isfinite(value):  # e.g. 1e400: decimal text too large for a float
            raise FieldError(f"{where}{rule.label}: {_show(token)} is too large to be a number")
        values.append(rule.check(value, owner))
    return tuple(values)


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
