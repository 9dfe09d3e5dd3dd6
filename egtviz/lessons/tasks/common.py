"""What several task kinds share: the ranges their parameters must lie in, the checks that a step's scene has
what a task names (:func:`camera_in`, ...: an :class:`~egtviz.lessons.errors.EntryError` for the author), what
a learner's scene no longer has (:func:`camera_gone`, ...: a sentence for the learner), and how points and
numbers are named in feedback.
"""

from __future__ import annotations

from typing import Any

from ...scene import Scene
from ...scene.limits import COORDINATE, MAX_POINTS, Range
from ..errors import EntryError

__all__ = [
    "ANSWER",
    "DEPTH_ERROR",
    "FRACTION",
    "POINT_INDEX",
    "SAMPSON_PX2",
    "TOLERANCE",
    "WITHIN_DEG",
    "WITHIN_PX",
    "camera_gone",
    "camera_in",
    "fmt",
    "in_pair",
    "pair_gone",
    "point_gone",
    "point_in",
    "point_label",
    "projective_pair",
]

WITHIN_PX = Range(1e-3, 1e4, "px")
WITHIN_DEG = Range(1e-3, 180.0, "deg")
SAMPSON_PX2 = Range(1e-6, 1e6, "px^2")
FRACTION = Range(0.0, 1.0, "")
TOLERANCE = Range(0.0, 1e12, "")
ANSWER = Range(-1e12, 1e12, "")
DEPTH_ERROR = Range(1e-6, COORDINATE.high, "m")
POINT_INDEX = Range(0, MAX_POINTS - 1, "", integer=True)


def point_label(index: int) -> int:
    """The number the viewer shows for point ``index`` (panels, 3D labels, the point list count from 1); prompts
    (``{point}``) and feedback name points by it, lesson files by their index from 0."""
    return index + 1


def fmt(x: float) -> str:
    """A number in feedback: six significant digits (``%.6g``)."""
    return f"{x:.6g}"


def camera_in(scene: Scene, name: str, key: str = "camera") -> Any:
    """The spec of camera ``name`` of the step's scene; an :class:`EntryError` naming ``key`` if it has none."""
    if name not in scene.camera_names:
        raise EntryError(key, f"no camera named {name!r} in the step's scene (have {list(scene.camera_names)})")
    return scene.camera(name)


def point_in(scene: Scene, index: int, key: str = "point") -> None:
    """Refuse a point ``index`` the step's scene does not have (an :class:`EntryError` naming ``key``)."""
    if index >= len(scene.points):
        raise EntryError(key, f"no point {index} in the step's scene (have {len(scene.points)})")


def in_pair(scene: Scene, name: str, key: str = "camera", pinhole_pair: bool = False) -> None:
    """Refuse a camera ``name`` that is not in the step's drawn pair (of pin-holes, with ``pinhole_pair``)."""
    camera_in(scene, name, key)
    pair = scene.drawn_pair
    if pair is None or name not in pair:
        raise EntryError(key, f"camera {name!r} is not in the drawn pair {pair} (add a set_pair change)")
    if pinhole_pair and not projective_pair(scene, pair):
        raise EntryError(key, f"this task needs a drawn pair of pin-hole cameras, got {pair}")


def projective_pair(scene: Scene, pair: tuple[str, str] | None) -> bool:
    """Both cameras of ``pair`` image linearly (pin-holes: they have a K, and F exists between their pixels)."""
    return pair is not None and all(scene.camera(n).camera().projective_calibration is not None for n in pair)


def camera_gone(scene: Scene, *names: str) -> str | None:
    """Which of ``names`` the scene no longer has (the first), as the learner is told."""
    for name in names:
        if name not in scene.camera_names:
            return f"{name} is not in the scene any more"
    return None


def point_gone(scene: Scene, index: int) -> str | None:
    """Why point ``index`` is not in the scene any more, as the learner is told (None: it is)."""
    if index >= len(scene.points):
        return f"point {point_label(index)} is not in the scene any more (it has {len(scene.points)} points)"
    return None


def pair_gone(scene: Scene, camera: str | None = None, *, pinhole: bool = False) -> str | None:
    """Why the drawn pair is not what the task measures: none, without ``camera``, or not two pin-holes."""
    gone = None if camera is None else camera_gone(scene, camera)
    if gone is not None:
        return gone
    pair = scene.drawn_pair
    if pair is None:
        return "the scene has fewer than two cameras: no pair is drawn"
    if camera is not None and camera not in pair:
        return f"{camera} is not in the drawn pair ({pair[0]} & {pair[1]}) any more"
    if pinhole and not projective_pair(scene, pair):
        return f"the drawn pair ({pair[0]} & {pair[1]}) is not two pin-hole cameras any more"
    return None
