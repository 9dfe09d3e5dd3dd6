"""Colours shared by the 3D view and the image-plane panels.

Okabe & Ito's colour-blind-safe palette (without black and yellow, which do not
read on white): point ``i`` gets ``POINT_COLOURS[i % 6]`` in the 3D scene and in
every image plane, and its number is written next to it, so nothing depends on
telling two hues apart.
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
EPIPOLE_COLOUR = "#222222"
BASELINE_COLOUR = "#444444"
RIM_COLOUR = "#777777"
CAMERA_COLOURS: tuple[str, ...] = ("#1b1b1b", "#5a3e8c", "#2f6d3a", "#8c4a1e")


def hex_to_rgb(colour: str) -> tuple[int, int, int]:
    """``"#RRGGBB"`` as an ``(r, g, b)`` tuple of ints."""
    c = colour.lstrip("#")
    return int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16)


def point_colour(i: int) -> str:
    """Hex colour of scene point ``i`` (0-based)."""
    return POINT_COLOURS[i % len(POINT_COLOURS)]


def point_rgb(i: int) -> tuple[int, int, int]:
    return hex_to_rgb(point_colour(i))
