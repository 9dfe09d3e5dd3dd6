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

__all__ = ["AnswerError", "EXAMPLE", "read_matrix", "read_number", "read_vector"]

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


def _numbers_in(body: str, what: str) -> list[float]:
    """The comma-separated numbers of one bracketed row, each read as :data:`_NUMBER` (nothing else)."""
    items = body.split(",")
    out = []
    for item in items:
        if re.fullmatch(rf"\s*{_NUMBER}\s*", item) is None:
            raise AnswerError(f"{what}: {_shown(item)} is not a number.")
        x = float(item)
        if not math.isfinite(x):
            raise AnswerError(f"{what}: {_shown(item)} is too large.")
        out.append(x)
    return out


def _vector_example(size: int) -> str:
    return "[" + ", ".join(EXAMPLE for _ in range(size)) + "]"


def read_vector(text: str | None, size: int, unit: str = "") -> tuple[float, ...]:
    """A vector typed as ``[a, b]`` (``size`` numbers in brackets, separated by commas), optionally followed by
    ``unit``; read as strictly as :func:`read_number` reads one number.

    Raises:
        AnswerError: anything else (no brackets, another count of numbers, a word among them); the message says
            what was expected.
    """
    example = _vector_example(size)
    expected = f"Type {size} numbers in brackets, e.g. {example}" + (f" (in {unit}: {example} {unit})" if unit else "")
    if text is None or not text.strip():
        raise AnswerError(f"{expected}.")
    unit_part = rf"(?:\s*{re.escape(unit)})?" if unit else ""
    m = re.fullmatch(rf"\s*\[([^\[\]]*)\]{unit_part}\s*", text, flags=re.IGNORECASE)
    if m is None:
        raise AnswerError(f"{expected}; got {_shown(text)}.")
    values = _numbers_in(m.group(1), expected)
    if len(values) != size:
        raise AnswerError(f"{expected}; got {len(values)} number{'s' * (len(values) != 1)}.")
    return tuple(values)


def read_matrix(text: str | None, rows: int, cols: int) -> tuple[tuple[float, ...], ...]:
    """A matrix typed row by row: ``[[a, b, c], [d, e, f], [g, h, i]]`` or ``[a, b, c; d, e, f; g, h, i]``.

    Raises:
        AnswerError: anything else (another shape, a word among the numbers); the message says what was
            expected.
    """
    row = ", ".join(EXAMPLE for _ in range(cols))
    expected = (f"Type a {rows} x {cols} matrix row by row, e.g. [{'; '.join(row for _ in range(rows))}] "
                f"or [[{'], ['.join(row for _ in range(rows))}]]")
    if text is None or not text.strip():
        raise AnswerError(f"{expected}.")
    inner = text.strip()
    if not (inner.startswith("[") and inner.endswith("]")):
        raise AnswerError(f"{expected}; got {_shown(text)}.")
    inner = inner[1:-1]
    if "#" in inner:  # the mark the row scan below uses
        raise AnswerError(f"{expected}; got {_shown(text)}.")
    if "[" in inner or "]" in inner:  # [[...], [...]]: scanned without nested quantifiers (no backtracking)
        bodies = re.findall(r"\[([^\[\]]*)\]", inner)
        if re.fullmatch(r"\s*#(?:\s*,\s*#)*\s*", re.sub(r"\[[^\[\]]*\]", "#", inner)) is None:
            raise AnswerError(f"{expected}; separate the rows by commas.")
    elif ";" in inner:
        bodies = inner.split(";")
    else:
        raise AnswerError(f"{expected}; got {_shown(text)}.")
    if len(bodies) != rows:
        raise AnswerError(f"{expected}; got {len(bodies)} row{'s' * (len(bodies) != 1)}.")
    out = []
    for k, body in enumerate(bodies, start=1):
        values = _numbers_in(body, expected)
        if len(values) != cols:
            raise AnswerError(f"{expected}; row {k} has {len(values)} number{'s' * (len(values) != 1)}.")
        out.append(tuple(values))
    return tuple(out)
