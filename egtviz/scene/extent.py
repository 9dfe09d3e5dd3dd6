"""How big a scene is: what a 3D view must frame, and the size its glyphs (gizmos, axes) are drawn at.

A scene may be a room (the tutorial's cameras 10 m apart) or a table top (two panoramic mirrors 0.4 m wide,
1.5 m apart); a view framed on the camera centres alone with a metre of room cuts off a 4 m mirror that stands
6 m above its CCD, and a 1 m gizmo hides a 0.4 m mirror. The viewer asks this module; it computes nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .derived import Derived
from .scene import Scene

__all__ = ["GLYPH_FRACTION", "GLYPH_RANGE", "SceneExtent", "scene_extent"]

#: A glyph (a camera's gizmo, its axes, the world axes) is this fraction of the scene's bounding-box diagonal ...
GLYPH_FRACTION = 1.0 / 15.0
#: ... within these bounds (metres): the default scene's gizmos stay near 1 m, the tutorial's 25 m scenes get
#: 1.6 m ones (a 1 m gizmo is a speck there), a table top of 0.4 m mirrors 0.4 m ones.
GLYPH_RANGE = (0.1, 2.0)
#: Samples of a mirror's surface (rings, around) taken as its extent.
_MIRROR_SAMPLES = (4, 12)


@dataclass(frozen=True, eq=False)
class SceneExtent:
    """What a scene occupies in the world."""

    points: np.ndarray
    """(N, 3) points a view must show: camera centres, scene points, mirror surfaces and CCDs (world, metres)."""
    lo: np.ndarray
    """(3,) the bounding box's lower corner."""
    hi: np.ndarray
    """(3,) the bounding box's upper corner."""
    glyph: float
    """The length glyphs are drawn at (metres): ``GLYPH_FRACTION`` of the diagonal, within ``GLYPH_RANGE``."""

    @property
    def diagonal(self) -> float:
        """The bounding box's diagonal (metres)."""
        return float(np.linalg.norm(self.hi - self.lo))


def _body_points(model: object) -> np.ndarray:
    """A camera's drawn body in world coordinates beyond its centre: a mirror's surface and its CCD (a model
    with a ``mirror``); none for the others, whose bodies are drawn at glyph size."""
    mirror = getattr(model, "mirror", None)
    pose = getattr(model, "pose", None)
    if mirror is None or pose is None:
        return np.zeros((0, 3))
    vertices, _faces = mirror.surface(*_MIRROR_SAMPLES)
    local = np.vstack([np.asarray(vertices, float).reshape(-1, 3),
                       [[0.0, 0.0, -float(getattr(mirror, "ccd_offset", 0.0))]]])
    return local @ np.asarray(pose.R, float).T + np.asarray(pose.t, float)


def scene_extent(scene: Scene, derived: Derived) -> SceneExtent:
    """The scene's extent: its cameras (with their mirrors), its points and its bounding box.

    Args:
        scene: the scene.
        derived: its derived quantities (:func:`egtviz.scene.compute_derived`; the camera models).
    """
    parts = [np.asarray(c.position, float).reshape(1, 3) for c in scene.cameras]
    if scene.points:
        parts.append(np.asarray(scene.points_array(), float).reshape(-1, 3))
    parts.extend(_body_points(model) for model in derived.cameras.values())
    P = np.vstack(parts) if parts else np.zeros((1, 3))
    P = P[np.all(np.isfinite(P), axis=1)]
    if len(P) == 0:
        P = np.zeros((1, 3))
    lo, hi = P.min(axis=0), P.max(axis=0)
    glyph = float(np.clip(GLYPH_FRACTION * np.linalg.norm(hi - lo), *GLYPH_RANGE))
    return SceneExtent(P, lo, hi, glyph)
