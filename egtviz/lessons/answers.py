"""A learner's typed number, read strictly: one number, optionally followed by the task's unit, or a message.

A lenient reading would mark answers right that the learner did not give: ``14.85.3``, ``14.85 is my answer``
or ``14.85`` then ``7`` on a second line are not 14.85, ``1,5`` is not 1 and ``14_85`` is not 14 (nor 1485,
as Python's ``float`` reads it). :func:`read_number` accepts exactly

* surrounding whitespace,
* one decimal number: an optional sign, digits with an optional decimal point (or a point then digits), an
  optional exponent (``8e2``, ``1.5E-3``),
* then, optionally, the task's own unit (``800 px``, ``800px``; any case), when the task has one,

and refuses everything else with a message that says what was expected.
"""

from __future__ import annotations

import math
import re

__all__ = ["AnswerError", "EXAMPLE", "read_number"]

#: The number a refusal shows as an example (not any task's answer: an example must not give one away).
EXAMPLE = "2.5"

_NUMBER = r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_DECIMAL_COMMA = re.compile(r"\s*([+-]?[0-9]+),([0-9]+)\s*(?P<unit>\S.*?)?\s*")
_SHOWN = 40


class AnswerError(ValueError):
    """A typed answer that is not one number (in the task's unit); the message is for the learner."""


def _expected(unit: str) -> str:
    """What a refusal asks for, e.g. ``type one number, e.g. 2.5 (in px: 2.5 or 2.5 px)``."""
    if not unit:
        return f"Type one number, e.g. {EXAMPLE}"
    return f"Type one number, e.g. {EXAMPLE} (in {unit}: {EXAMPLE} or {EXAMPLE} {unit})"


def _shown(text: str) -> str:
    """The learner's text quoted in a message: printable characters only, at most 40 of them."""
    clean = "".join(c if c.isprintable() else " " for c in text.strip())
    return repr(clean if len(clean) <= _SHOWN else clean[:_SHOWN] + "...")


def read_number(text: str | None, unit: str = "") -> float:
    """The one number typed in ``text``, optionally followed by ``unit`` (the task's; empty: no unit allowed).

    Args:
        text: what the learner typed (None: nothing).
        unit: the task's unit, e.g. ``"px"``; matched whole and in any case.

    Returns:
        The number, finite.

    Raises:
        AnswerError: ``text`` is not exactly one number (and the unit); the message says what was expected
            and, for a decimal comma (``1,5``), suggests the decimal point.
    """
    if text is None or not text.strip():
        raise AnswerError(f"{_expected(unit)}.")
    unit_part = rf"(?:\s*{re.escape(unit)})?" if unit else ""
    m = re.fullmatch(rf"\s*({_NUMBER}){unit_part}\s*", text, flags=re.IGNORECASE)
    if m is None:
        comma = _DECIMAL_COMMA.fullmatch(text)
        if comma is not None and (comma["unit"] is None or comma["unit"].lower() == unit.lower()):
            a, b = comma.group(1), comma.group(2)
            raise AnswerError(f"Write the decimals after a point: {a}.{b}, not {a},{b}.")
        raise AnswerError(f"{_expected(unit)}; got {_shown(text)}.")
    x = float(m.group(1))
    if not math.isfinite(x):  # decimal text too large for a float, e.g. 1e400
        raise AnswerError(f"{_expected(unit)}; {_shown(m.group(1))} is too large.")
    return x
