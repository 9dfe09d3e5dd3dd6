"""Typed reads of the values of one TOML table, each refusal an :class:`EntryError` naming the key.

Lesson files are TOML, so values arrive as ``str``, ``int``, ``float``, ``bool``, lists, tables and dates;
these helpers accept exactly the type a key needs and the range the shared limits allow.
"""

from __future__ import annotations

import math
from typing import Any

from ..files import printable
from ..scene.limits import Range
from ..scene.specs import has_control_characters
from .errors import EntryError

MAX_TEXT = 20_000
"""Characters of a step's text (a screen or two of Markdown)."""
MAX_LINE_TEXT = 400
"""Characters of a title, prompt, hint, option or name."""


def short(value: Any) -> str:
    """A printable, length-limited ``repr`` for messages."""
    text = printable(repr(value))
    return text if len(text) <= 40 else text[:37] + "..."


def refuse_unknown(table: dict, allowed: tuple[str, ...] | frozenset[str], what: str) -> None:
    """Refuse any key of ``table`` outside ``allowed`` (a typo must not be silently ignored)."""
    for key in table:
        if key not in allowed:
            raise EntryError(key, f"unknown key for {what} (allowed: {', '.join(sorted(allowed))})")


def text(table: dict, key: str, *, required: bool = True, default: str = "", limit: int = MAX_LINE_TEXT,
         multiline: bool = False) -> str:
    """A string of at most ``limit`` characters; control characters refused (newlines and tabs allowed only in
    ``multiline`` text)."""
    if key not in table:
        if required:
            raise EntryError(key, "missing (expected text)")
        return default
    value = table[key]
    if type(value) is not str:
        raise EntryError(key, f"expected text, got {short(value)}")
    if len(value) > limit:
        raise EntryError(key, f"expected at most {limit} characters, got {len(value)}")
    checked = value.replace("\n", "").replace("\t", "") if multiline else value
    if has_control_characters(checked):
        raise EntryError(key, "control characters are not allowed")
    return value


def number(table: dict, key: str, limit: Range, *, required: bool = True, default: float | None = None) -> float:
    """A finite number inside ``limit`` (a whole number if ``limit.integer``); booleans refused."""
    if key not in table:
        if required:
            raise EntryError(key, f"missing (expected a number in {limit.describe()})")
        return default  # type: ignore[return-value]
    return as_number(table[key], key, limit)


def as_number(value: Any, key: str, limit: Range) -> float:
    """``value`` as a float inside ``limit``, or an :class:`EntryError` naming ``key``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise EntryError(key, f"expected a number in {limit.describe()}, got {short(value)}")
    try:
        x = float(value)
    except OverflowError:
        raise EntryError(key, f"expected a number in {limit.describe()}, got a huge integer") from None
    if not math.isfinite(x) or x not in limit or (limit.integer and not x.is_integer()):
        kind = "a whole number" if limit.integer else "a number"
        raise EntryError(key, f"expected {kind} in {limit.describe()}, got {short(value)}")
    return x


def numbers(table: dict, key: str, n: int, limit: Range, *, required: bool = True) -> tuple[float, ...] | None:
    """A list of exactly ``n`` numbers, each inside ``limit``."""
    if key not in table:
        if required:
            raise EntryError(key, f"missing (expected {n} numbers)")
        return None
    value = table[key]
    if not isinstance(value, list) or len(value) != n:
        raise EntryError(key, f"expected a list of {n} numbers, got {short(value)}")
    return tuple(as_number(v, key, limit) for v in value)


def name_list(table: dict, key: str, *, required: bool = True, limit: int = 64) -> tuple[str, ...]:
    """A list of at most ``limit`` short strings."""
    if key not in table:
        if required:
            raise EntryError(key, "missing (expected a list of names)")
        return ()
    value = table[key]
    if not isinstance(value, list) or len(value) > limit:
        raise EntryError(key, f"expected a list of at most {limit} names, got {short(value)}")
    for v in value:
        if type(v) is not str or not v or len(v) > MAX_LINE_TEXT or has_control_characters(v):
            raise EntryError(key, f"expected names (non-empty text), got {short(v)}")
    return tuple(value)


def boolean(table: dict, key: str, *, default: bool = False) -> bool:
    """``true`` or ``false`` (numbers and strings refused)."""
    if key not in table:
        return default
    value = table[key]
    if type(value) is not bool:
        raise EntryError(key, f"expected true or false, got {short(value)}")
    return value


def whole(table: dict, key: str, limit: Range, *, required: bool = True, default: int | None = None) -> int:
    """A whole number inside ``limit``."""
    x = number(table, key, Range(limit.low, limit.high, limit.unit, integer=True), required=required,
               default=default)
    return x if x is None else int(x)  # type: ignore[return-value]
