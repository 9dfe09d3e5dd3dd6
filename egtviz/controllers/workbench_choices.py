"""What the workbench's drop-downs offer, and the name of a saved scene's file: pure functions of the scene.

Every drop-down value a tab sends is looked up in these options, since a hand-written client can send any string:
only what is listed exists (``mesh: /any/path`` is no surface).
"""

from __future__ import annotations

import itertools
from typing import Literal

from ..scene import Scene, mesh_names

__all__ = ["SURFACE_KINDS", "SurfaceChoice", "file_name", "pair_choices", "point_choices", "surface_choices"]

SURFACE_KINDS: tuple[Literal["plane", "sphere"], ...] = ("plane", "sphere")
#: A surface the "surface" drop-down offers: its kind and, for a mesh, the package's mesh name.
SurfaceChoice = tuple[Literal["plane", "sphere", "mesh"], str]


def pair_choices(scene: Scene) -> dict[str, tuple[str, str]]:
    """The "drawn pair" drop-down's options: every pair of the scene's cameras, and the drawn pair whatever it is."""
    pairs = {f"{a} & {b}": (a, b) for a, b in itertools.combinations(scene.camera_names, 2)}
    drawn = scene.drawn_pair
    if drawn is not None and f"{drawn[0]} & {drawn[1]}" not in pairs:
        pairs[f"{drawn[0]} & {drawn[1]}"] = drawn
    return pairs


def point_choices(n: int) -> dict[str, int | None]:
    """The "selected point" drop-down's options for ``n`` points: ``none``, then ``point 1`` .. ``point n``."""
    return {"none": None} | {f"point {i + 1}": i for i in range(n)}


def surface_choices() -> dict[str, SurfaceChoice]:
    """The "surface" drop-down's options: a plane, a sphere, and each mesh of the package's own."""
    options: dict[str, SurfaceChoice] = {k: (k, "") for k in SURFACE_KINDS}
    options.update({f"mesh: {m}": ("mesh", m) for m in mesh_names()})
    return options


def file_name(title: str) -> str:
    """The download's file name: the scene title reduced to letters, digits, ``-`` and ``_``."""
    stem = "".join(c if c.isascii() and (c.isalnum() or c in "-_") else "_" for c in title.strip())[:40].strip("_")
    return f"{stem or 'scene'}.json"
