"""MATLAB's colour/line/marker style strings (``'b:'``, ``'r*'``, ``'g--o'``) as what egtviz draws with."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: MATLAB's colour letters; pure green and yellow are darkened and white becomes light grey (they would not
#: read on the viewer's white background).
MATLAB_COLOURS = {
    "r": "#e00000",
    "g": "#00a000",
    "b": "#0000e0",
    "c": "#00a0a0",
    "m": "#c000c0",
    "y": "#b0a000",
    "k": "#000000",
    "w": "#bbbbbb",
}
_LINES = ("--", "-.", "-", ":")
_MARKERS = set("+o*.xsd^v<>ph")


@dataclass(frozen=True)
class Style:
    """One MATLAB style string, parsed."""

    colour: str
    """``"#rrggbb"``."""
    line: str | None
    """``"-"``, ``"--"``, ``":"``, ``"-."`` or None (markers only)."""
    marker: str | None


def parse_style(style: Any, default_colour: str = "#333333") -> Style:
    """A MATLAB style string as a :class:`Style`; anything that is not a string gives the defaults.

    Unknown characters are ignored (MATLAB would raise; a figure never fails a student's script).
    """
    text = style if isinstance(style, str) else ""
    colour = next((MATLAB_COLOURS[c] for c in text if c in MATLAB_COLOURS), default_colour)
    line = next((ls for ls in _LINES if ls in text), None)
    marker = next((c for c in text if c in _MARKERS), None)
    return Style(colour, line, marker)
