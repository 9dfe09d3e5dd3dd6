"""The state of a scene (immutable) and how it is written to a file (``egtviz.scene.io`` reads files)."""

from __future__ import annotations

import dataclasses
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..files import write_atomic
from .annotations import Annotations, annotations_to_dict, resolve_reflections
from .surfaces import sample_surface
from .limits import (
    COORDINATE,
    MAX_CAMERAS,
    MAX_POINTS,
    MAX_SURFACES,
    MAX_TITLE_LENGTH,
    MAX_TOTAL_SURFACE_SAMPLES,
)
from ._values import SceneError, as_triple, has_control_characters, short_text
from .cameras import SPEC_CLASSES
from .specs import CameraSpec, DisplayOptions, SurfaceSpec, spec_to_dict

_CAMERA_TYPES = SPEC_CLASSES
_POINT_MARK = re.compile(r"point:(0|[1-9][0-9]{0,8})")


def _sequence(value: Any, name: str, limit: int) -> tuple:
    """A list or tuple of at most ``limit`` items as a tuple (counted before anything is converted)."""
    if not isinstance(value, (tuple, list)):
        raise SceneError(f"{name}: expected a list, got {short_text(value)}")
    if len(value) > limit:
        raise SceneError(f"{name}: at most {limit}, got {len(value)}")
    return tuple(value)


def _marks(value: Any, name: str) -> frozenset[str]:
    """``locked`` / ``highlighted`` as a frozenset of strings."""
    if isinstance(value, (str, bytes)) or not isinstance(value, (tuple, list, set, frozenset)):
        raise SceneError(f"{name}: expected a list of camera names and 'point:<i>', got {short_text(value)}")
    if len(value) > MAX_CAMERAS + MAX_POINTS:
        raise SceneError(f"{name}: at most {MAX_CAMERAS + MAX_POINTS} entries, got {len(value)}")
    try:
        return frozenset(value)
    except TypeError:
        raise SceneError(f"{name}: expected a list of camera names and 'point:<i>', got {short_text(value)}") from None


def _check_mark(mark: Any, name: str, cameras: list[str], n_points: int) -> None:
    """A camera name of the scene or ``"point:<i>"`` with ``i`` below the number of points."""
    if type(mark) is str:
        m = _POINT_MARK.fullmatch(mark)
        if m is not None and int(m.group(1)) < n_points:
            return
        if m is None and mark in cameras:
            return
    raise SceneError(
        f"{name}: expected camera names of the scene and 'point:<i>' with i below {n_points}, got {short_text(mark)}"
    )

FILE_FORMAT = "egtviz-scene"
FILE_VERSION = 1


class SceneFileError(SceneError):
    """A scene file that cannot be read; the message names the file and the offending entry."""


@dataclass(frozen=True)
class Scene:
    """Cameras, points, surfaces and what is drawn: one immutable snapshot."""

    cameras: tuple[CameraSpec, ...] = ()
    points: tuple[tuple[float, float, float], ...] = ()
    surfaces: tuple[SurfaceSpec, ...] = ()
    pair: tuple[str, str] | None = None
    """Names of the two cameras whose epipolar geometry is drawn; None: the first two."""
    selected_point: int | None = None
    options: DisplayOptions = field(default_factory=DisplayOptions)
    locked: frozenset[str] = frozenset()
    """Gizmos the user cannot drag: camera names and ``"point:<i>"`` (``i`` an index of ``points``)."""
    highlighted: frozenset[str] = frozenset()
    """Camera names and ``"point:<i>"`` a lesson draws attention to."""
    title: str = ""
    annotations: Annotations = field(default_factory=Annotations)
    """What a figure draws besides cameras and points: frames, polylines, labels, point sets, meshes,
    plane mirrors (which may keep a reflected camera in ``cameras``) and 2D plots."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        cameras = self.cameras
        if type(cameras) is not tuple:
            cameras = _sequence(cameras, "cameras", MAX_CAMERAS)
            set_(self, "cameras", cameras)
        if len(cameras) > MAX_CAMERAS:
            raise SceneError(f"cameras: at most {MAX_CAMERAS}, got {len(cameras)}")
        for c in cameras:
            if type(c) not in _CAMERA_TYPES:
                raise SceneError(f"cameras: expected camera specs, got {short_text(c)}")
        if type(self.annotations) is not Annotations:
            raise SceneError(f"annotations: expected Annotations, got {short_text(self.annotations)}")
        if self.annotations.mirrors:  # a reflected camera follows the camera it reflects
            cameras = resolve_reflections(cameras, self.annotations)
            if len(cameras) > MAX_CAMERAS:
                raise SceneError(f"cameras: at most {MAX_CAMERAS} (with the mirrors' virtual cameras), got {len(cameras)}")
            set_(self, "cameras", cameras)
        names = [c.name for c in cameras]
        if len(set(names)) != len(names):
            raise SceneError(f"cameras: names must be unique, got {names}")
        if type(self.points) is not _Points:  # a camera change keeps the previous scene's checked points
            set_(self, "points", _points_tuple(self.points))
        n_points = len(self.points)
        surfaces = self.surfaces
        if type(surfaces) is not tuple:
            surfaces = _sequence(surfaces, "surfaces", MAX_SURFACES)
            set_(self, "surfaces", surfaces)
        if surfaces:
            if len(surfaces) > MAX_SURFACES:
                raise SceneError(f"surfaces: at most {MAX_SURFACES}, got {len(surfaces)}")
            if not all(type(s) is SurfaceSpec for s in surfaces):
                raise SceneError("surfaces: expected surface specs")
            total = sum(s.samples for s in surfaces)
            if total > MAX_TOTAL_SURFACE_SAMPLES:
                raise SceneError(f"surfaces: at most {MAX_TOTAL_SURFACE_SAMPLES} samples in all, got {total}")
        if self.pair is not None:
            pair = self.pair
            if not isinstance(pair, (tuple, list)) or len(pair) != 2 or pair[0] == pair[1] or any(
                type(n) is not str or n not in names for n in pair
            ):
                raise SceneError(f"pair: expected two different camera names from {names}, got {short_text(self.pair)}")
            set_(self, "pair", tuple(pair))
        sel = self.selected_point
        if sel is not None:
            if isinstance(sel, (bool, np.bool_)) or not isinstance(sel, (int, np.integer)) or not 0 <= sel < n_points:
                raise SceneError(f"selected_point: expected null or a whole number below {n_points}, got {short_text(sel)}")
            set_(self, "selected_point", int(sel))
        if type(self.options) is not DisplayOptions:
            raise SceneError(f"options: expected DisplayOptions, got {short_text(self.options)}")
        for name in ("locked", "highlighted"):
            value = getattr(self, name)
            if type(value) is not frozenset:
                value = _marks(value, name)
                set_(self, name, value)
            for mark in value:
                _check_mark(mark, name, names, n_points)
        title = self.title
        if type(title) is not str or len(title) > MAX_TITLE_LENGTH or has_control_characters(title):
            raise SceneError(
                f"title: expected text of at most {MAX_TITLE_LENGTH} characters without control characters, "
                f"got {short_text(title)}"
            )

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.cameras)

    def camera(self, name: str) -> CameraSpec:
        for c in self.cameras:
            if c.name == name:
                return c
        raise SceneError(f"camera: no camera named {name!r} (have {list(self.camera_names)})")

    @property
    def drawn_pair(self) -> tuple[str, str] | None:
        """The pair whose epipolar geometry is drawn: ``pair``, or the first two cameras."""
        if self.pair is not None:
            return self.pair
        if len(self.cameras) >= 2:
            return (self.cameras[0].name, self.cameras[1].name)
        return None

    def points_array(self) -> np.ndarray:
        """The points as a read-only (N, 3) float64 array (made once per set of points, shared by the scenes
        that keep them; copy it to change it)."""
        return self.points.array  # type: ignore[attr-defined]

    def with_point(self, index: int, xyz: Any) -> Scene:
        """This scene with point ``index`` moved to ``xyz`` (checked); one row changes, the rest is not re-checked."""
        points = self.points
        if not 0 <= index < len(points):
            raise SceneError(f"index: no point {index} (have {len(points)})")
        p = as_triple(xyz, f"point {index}")
        arr = points.array.copy()  # type: ignore[attr-defined]
        arr[index] = p
        new = list(points)
        new[index] = p
        return self.replace(points=_Points.trusted(new, arr))

    def surface_points(self) -> tuple[np.ndarray, np.ndarray]:
        """All surfaces sampled: ``(points (M, 3), normals (M, 3))``.

        Raises:
            SceneError: a mesh surface names no mesh of the assets (a scene file or the model checks that first).
        """
        if not self.surfaces:
            return np.zeros((0, 3)), np.zeros((0, 3))
        pts, nrm = zip(*(sample_surface(s) for s in self.surfaces))
        return np.concatenate(pts), np.concatenate(nrm)

    def replace(self, **changes: Any) -> Scene:
        """``dataclasses.replace(self, **changes)`` (a new, checked scene)."""
        if type(self) is not Scene:
            return dataclasses.replace(self, **changes)
        return Scene(**{**{name: getattr(self, name) for name in _SCENE_FIELDS}, **changes})

    # -- file format: writing (reading checks a file completely, ``egtviz.scene.io``) --------------------

    def to_dict(self) -> dict[str, Any]:
        """The scene as plain JSON data (the file format, version ``FILE_VERSION``); :func:`scene_to_dict`."""
        return scene_to_dict(self)

    def save(self, path: str | Path) -> None:
        """Write the scene file atomically (``egtviz.files.write_atomic``: never a device, FIFO, folder or link).

        A file is read back with :func:`egtviz.scene.load_scene_file` (which checks it completely).
        """
        write_atomic(path, scene_to_bytes(self))


_SCENE_FIELDS = tuple(f.name for f in dataclasses.fields(Scene))


class _Points(tuple):
    """A scene's checked points: a tuple of float triples that carries them as a read-only (N, 3) array.

    Only :func:`_points_tuple` and :meth:`Scene.with_point` make one, so a :class:`Scene` built with a
    ``_Points`` (every change that leaves the points alone) skips checking them again. The hash is
    remembered too (caches keyed on the points hash them on every update).
    """

    array: np.ndarray

    @classmethod
    def trusted(cls, points: Any, arr: np.ndarray) -> _Points:
        """``points`` (float triples) and the same values as ``arr``, both already checked."""
        out = cls(points)
        arr.setflags(write=False)
        out.array = arr
        return out

    def __hash__(self) -> int:
        h = self.__dict__.get("_hash")
        if h is None:
            h = self.__dict__["_hash"] = tuple.__hash__(self)
        return h

    def __getattr__(self, name: str) -> Any:
        if name == "array":  # a copy made by copy/pickle/asdict: rebuild the array
            arr = np.array(tuple(self), dtype=np.float64).reshape(-1, 3)
            arr.setflags(write=False)
            self.__dict__["array"] = arr
            return arr
        raise AttributeError(name)


def _points_tuple(points: Any) -> _Points:
    """Points as a tuple of float triples, each coordinate a number in ``COORDINATE``; at most ``MAX_POINTS``."""
    if isinstance(points, np.ndarray):
        if points.dtype.kind not in "iuf" or points.ndim != 2 or points.shape[1] != 3:
            raise SceneError(f"points: expected an (N, 3) array of numbers, got {points.dtype} {points.shape}")
        points = points.tolist()
    seq = _sequence(points, "points", MAX_POINTS)
    if all(type(p) is tuple and len(p) == 3 and type(p[0]) is type(p[1]) is type(p[2]) is float for p in seq):
        arr = np.array(seq, dtype=np.float64).reshape(-1, 3)
        if len(arr) == 0 or np.abs(arr).max() <= COORDINATE.high:  # NaN fails this too
            return _Points.trusted(seq, arr)
    checked = [as_triple(p, f"points[{i}]") for i, p in enumerate(seq)]
    return _Points.trusted(checked, np.array(checked, dtype=np.float64).reshape(-1, 3))


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """The scene as plain JSON data (the file format, version ``FILE_VERSION``)."""
    return {
        "format": FILE_FORMAT,
        "version": FILE_VERSION,
        "title": scene.title,
        "cameras": [spec_to_dict(c) for c in scene.cameras],
        "points": [list(p) for p in scene.points],
        "surfaces": [spec_to_dict(s) for s in scene.surfaces],
        "pair": list(scene.pair) if scene.pair else None,
        "selected_point": scene.selected_point,
        "options": dataclasses.asdict(scene.options),
        "locked": sorted(scene.locked),
        "highlighted": sorted(scene.highlighted),
        # Only a figure has annotations: other scene files stay as they were.
        **({} if scene.annotations.empty else {"annotations": annotations_to_dict(scene.annotations)}),
    }


def scene_to_bytes(scene: Scene) -> bytes:
    """The scene file's bytes: indented UTF-8 JSON ending with a newline."""
    return (json.dumps(scene_to_dict(scene), indent=2, allow_nan=False) + "\n").encode("utf-8")
