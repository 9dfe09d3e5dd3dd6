"""A field's raw text parsed and checked in the user's units: what every number a user types must be.

The viewer's number fields are text fields (viser's own number boxes drop ``nan`` and ``abc`` in the browser, turn
``1e400`` into 1400 and round ``3.5`` to 3), so every value the user typed reaches the server and is accepted or
refused here, with a message.

A number is plain decimal text, ``[+-] digits [. digits] [e [+-] digits]``;
a vector is such numbers separated by commas. A refusal names the owner (a
camera) and the field, in the field's own units::

    cam1: focal length must be between 0.1 mm and 1000 mm, got 0 mm
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass

from ..scene import SceneError
from ..scene.shown_numbers import shown_components

__all__ = ["MAX_FIELD_CHARS", "FieldError", "NumberRule", "format_number", "format_numbers", "parse_numbers", "plain"]

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


def plain(text: str, limit: int = 80) -> str:
    """Text from a file or a browser, safe to show: printable characters only, at most ``limit`` of them."""
    clean = "".join(c if c.isprintable() else "?" for c in str(text))
    return clean if len(clean) <= limit else clean[:limit] + "..."
