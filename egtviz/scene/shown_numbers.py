"""One rule for every number the user reads: panel labels, the read-out, plot ticks, fields and exported figures.

A vector's component below ``ZERO_FRACTION`` (1e-12) of its largest finite component is rounding of a zero
(an epipole on the image's centre row comes out at ``v = -1.5e-16``) and is shown as ``0``; a number that
rounds to zero in its format is written without a sign, never ``-0`` or ``-0.0``.
"""

from __future__ import annotations

import math
from typing import Any

from .derived import ZERO_FRACTION

__all__ = ["ZERO_FRACTION", "format_value", "format_vector", "shown_components"]


def shown_components(values: Any) -> tuple[float, ...]:
    """The components as shown: those below ``ZERO_FRACTION`` of the largest finite one become 0.0.

    A lone small number stays (``(1e-13, 0)`` is not rounding: nothing larger stands beside it), and so do
    non-finite ones; ``-0.0`` becomes ``0.0``.
    """
    numbers = [float(v) for v in values]
    largest = max((abs(v) for v in numbers if math.isfinite(v)), default=0.0)
    return tuple(0.0 if abs(v) < ZERO_FRACTION * largest else v + 0.0 for v in numbers)


def format_value(value: float, spec: str = ".4g") -> str:
    """``value`` formatted by ``spec`` (a format specification such as ``.4g``, ``.1f``, `` .4e``), never with
    a minus sign on a zero: ``-0.04`` at ``.1f`` is ``0.0``, ``-0.0`` is ``0``."""
    text = format(float(value) + 0.0, spec)
    stripped = text.lstrip()
    if stripped.startswith("-"):
        try:
            if float(stripped) == 0.0:
                text = text.replace("-", " " if spec.startswith(" ") else "", 1)
        except ValueError:  # "-inf"
            pass
    return text


def format_vector(values: Any, spec: str = ".4g", sep: str = ", ") -> str:
    """A vector's components by :func:`shown_components` and :func:`format_value`: ``"5.667, 0"``."""
    return sep.join(format_value(v, spec) for v in shown_components(values))
