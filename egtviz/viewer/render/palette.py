"""Colours shared by the 3D view and the image-plane panels, and presentation mode's type for every page.

Okabe & Ito's colour-blind-safe palette (without black and yellow, which do not
read on white): point ``i`` gets ``POINT_COLOURS[i % 6]`` in the 3D scene and in
every image plane, and its number is written next to it, so nothing depends on
telling two hues apart (from the seventh point on, colours repeat).

``PRESENT_POINT_COLOURS`` are the same six hues darkened for a projector: each
has a contrast ratio of at least 4.5 : 1 on white (the WCAG level for text),
``contrast_ratio(c, "#ffffff") = (L_white + 0.05) / (L_c + 0.05)`` with ``L``
the relative luminance.
"""

from __future__ import annotations

POINT_COLOURS: tuple[str, ...] = (
    "#0072B2",  # blue
    "#D55E00",  # vermillion
    "#009E73",  # bluish green
    "#CC79A7",  # reddish purple
    "#E69F00",  # orange
    "#56B4E9",  # sky blue
)
PRESENT_POINT_COLOURS: tuple[str, ...] = (
    "#004C7A",  # blue
    "#B34700",  # vermillion
    "#007A5A",  # bluish green
    "#A3457F",  # reddish purple
    "#A35F00",  # orange
    "#1F6FA8",  # sky blue
)
EPIPOLE_COLOUR = "#222222"
BASELINE_COLOUR = "#444444"
RIM_COLOUR = "#777777"
CAMERA_COLOURS: tuple[str, ...] = ("#1b1b1b", "#5a3e8c", "#2f6d3a", "#8c4a1e")

#: Smallest text of a page in presentation mode, CSS pixels (what a projector's back row reads; the panels'
#: :data:`egtviz.viewer.render.svg.PRESENT` sizes meet it too).
PRESENT_MIN_TEXT_PX = 16.0
#: Presentation mode's GUI type, for every page (workbench, start page, servo demos): Mantine (viser's GUI toolkit)
#: scales its rem-based sizes by ``--mantine-scale``; the pages' own smaller notes (an inline ``font-size:0.8em``)
#: and Mantine's small controls are raised to :data:`PRESENT_MIN_TEXT_PX` (``max``: larger text stays larger).
PRESENT_GUI_CSS = (
    "<style>:root:root{--mantine-scale:1.25}"
    f'small,[style*="font-size:0."],[style*="font-size: 0."]{{font-size:max({PRESENT_MIN_TEXT_PX:g}px,0.85em)!important}}'
    ".mantine-Button-label,.mantine-SegmentedControl-label,.mantine-InputWrapper-label,.u-legend,.u-title,"
    f".mantine-InputWrapper-description,.mantine-Tabs-tabLabel{{font-size:max({PRESENT_MIN_TEXT_PX:g}px,1em)!important}}"
    "</style>"
)


def hex_to_rgb(colour: str) -> tuple[int, int, int]:
    """``"#RRGGBB"`` as an ``(r, g, b)`` tuple of ints."""
    c = colour.lstrip("#")
    return int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16)


def point_colour(i: int) -> str:
    """Hex colour of scene point ``i`` (0-based)."""
    return POINT_COLOURS[i % len(POINT_COLOURS)]


def point_rgb(i: int) -> tuple[int, int, int]:
    """``(r, g, b)`` of scene point ``i`` (0-based)."""
    return hex_to_rgb(point_colour(i))


def relative_luminance(colour: str) -> float:
    """Relative luminance of an sRGB colour: ``L = 0.2126 R + 0.7152 G + 0.0722 B`` on linearised channels."""

    def linear(c8: int) -> float:
        c = c8 / 255.0
        return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4

    r, g, b = hex_to_rgb(colour)
    return 0.2126 * linear(r) + 0.7152 * linear(g) + 0.0722 * linear(b)


def contrast_ratio(a: str, b: str) -> float:
    """WCAG contrast ratio ``(L_light + 0.05) / (L_dark + 0.05)`` of two colours (1 to 21)."""
    la, lb = sorted((relative_luminance(a), relative_luminance(b)))
    return (lb + 0.05) / (la + 0.05)
