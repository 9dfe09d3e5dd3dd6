"""The state of a scene (immutable) and its file format."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .specs import (
    CAMERA_KINDS,
    CameraSpec,
    DisplayOptions,
    SceneError,
    SurfaceSpec,
    _triple,
    spec_to_dict,
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
    """Gizmos the user cannot drag: camera names and ``"point:<i>"``."""
    highlighted: frozenset[str] = frozenset()
    """Camera names and ``"point:<i>"`` a lesson draws attention to."""
    title: str = ""

    def __post_init__(self) -> None:
        names = [c.name for c in self.cameras]
        if len(set(names)) != len(names):
            raise SceneError(f"cameras: names must be unique, got {names}")
        if type(self.points) is not _Points:  # a camera change keeps the previous scene's checked points
            object.__setattr__(self, "points", _points_tuple(self.points))
        if self.pair is not None:
            pair = tuple(self.pair)
            if len(pair) != 2 or pair[0] == pair[1] or any(n not in names for n in pair):
                raise SceneError(f"pair: expected two different camera names from {names}, got {self.pair!r}")
            object.__setattr__(self, "pair", pair)
        if self.selected_point is not None and not 0 <= self.selected_point < len(self.points):
            raise SceneError(f"selected_point: expected an index below {len(self.points)}, got {self.selected_point}")
        object.__setattr__(self, "locked", frozenset(self.locked))
        object.__setattr__(self, "highlighted", frozenset(self.highlighted))

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
        p = _triple(xyz, f"point {index}")
        arr = points.array.copy()  # type: ignore[attr-defined]
        arr[index] = p
        new = list(points)
        new[index] = p
        return self.replace(points=_Points.trusted(new, arr))

    def surface_points(self) -> tuple[np.ndarray, np.ndarray]:
        """All surfaces sampled: ``(points (M, 3), normals (M, 3))``."""
        from .surfaces import sample_surface

        if not self.surfaces:
            return np.zeros((0, 3)), np.zeros((0, 3))
        pts, nrm = zip(*(sample_surface(s) for s in self.surfaces))
        return np.concatenate(pts), np.concatenate(nrm)

    def replace(self, **changes: Any) -> Scene:
        """``dataclasses.replace(self, **changes)`` (a new, checked scene)."""
        if type(self) is not Scene:
            return dataclasses.replace(self, **changes)
        return Scene(**{**{name: getattr(self, name) for name in _SCENE_FIELDS}, **changes})

    # -- file format ---------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": FILE_FORMAT,
            "version": FILE_VERSION,
            "title": self.title,
            "cameras": [spec_to_dict(c) for c in self.cameras],
            "points": [list(p) for p in self.points],
            "surfaces": [spec_to_dict(s) for s in self.surfaces],
            "pair": list(self.pair) if self.pair else None,
            "selected_point": self.selected_point,
            "options": dataclasses.asdict(self.options),
            "locked": sorted(self.locked),
            "highlighted": sorted(self.highlighted),
        }

    @classmethod
    def from_dict(cls, data: Any, source: str = "scene") -> Scene:
        """Build a scene from :meth:`to_dict` data; errors name ``source`` and the entry."""

        def fail(entry: str, why: str) -> SceneFileError:
            return SceneFileError(f"{source}: {entry}: {why}")

        if not isinstance(data, dict):
            raise fail("top level", "expected a JSON object")
        if data.get("format", FILE_FORMAT) != FILE_FORMAT:
            raise fail("format", f"expected {FILE_FORMAT!r}, got {data.get('format')!r}")
        if data.get("version", FILE_VERSION) != FILE_VERSION:
            raise fail("version", f"this egtviz reads version {FILE_VERSION}, got {data.get('version')!r}")
        unknown = set(data) - {
            "format", "version", "title", "cameras", "points", "surfaces", "pair",
            "selected_point", "options", "locked", "highlighted",
        }
        if unknown:
            raise fail(sorted(unknown)[0], "unknown entry")

        cameras = []
        for i, entry in enumerate(data.get("cameras", [])):
            where = f"cameras[{i}]"
            if not isinstance(entry, dict):
                raise fail(where, "expected an object")
            entry = dict(entry)
            kind = entry.pop("kind", None)
            if kind not in CAMERA_KINDS:
                raise fail(f"{where}.kind", f"expected one of {sorted(CAMERA_KINDS)}, got {kind!r}")
            spec_cls = CAMERA_KINDS[kind]
            known = {f.name for f in dataclasses.fields(spec_cls)}
            for key in entry:
                if key not in known:
                    raise fail(f"{where}.{key}", f"unknown field for a {kind} camera")
            try:
                cameras.append(spec_cls(**{k: _from_json(v) for k, v in entry.items()}))
            except (SceneError, TypeError, ValueError) as exc:
                raise fail(where, str(exc)) from exc

        points = []
        for i, p in enumerate(data.get("points", [])):
            try:
                points.append(_triple(p, f"points[{i}]"))
            except SceneError as exc:
                raise fail(f"points[{i}]", "expected [x, y, z] with finite numbers") from exc

        surfaces = []
        for i, entry in enumerate(data.get("surfaces", [])):
            try:
                surfaces.append(SurfaceSpec(**{k: _from_json(v) for k, v in entry.items() if k != "kind"}, kind=entry.get("kind", "plane")))
            except (SceneError, TypeError, ValueError, AttributeError) as exc:
                raise fail(f"surfaces[{i}]", str(exc)) from exc

        try:
            options = DisplayOptions(**data.get("options", {}))
        except TypeError as exc:
            raise fail("options", str(exc)) from exc
        pair = data.get("pair")
        try:
            return cls(
                cameras=tuple(cameras),
                points=tuple(points),
                surfaces=tuple(surfaces),
                pair=tuple(pair) if pair else None,
                selected_point=data.get("selected_point"),
                options=options,
                locked=frozenset(data.get("locked", ())),
                highlighted=frozenset(data.get("highlighted", ())),
                title=str(data.get("title", "")),
            )
        except SceneError as exc:
            raise fail(str(exc).split(":")[0], str(exc).split(":", 1)[-1].strip()) from exc

    def save(self, path: str | Path) -> None:
        """Write the scene as indented JSON (atomically: a crash never leaves half a file)."""
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(self.to_dict(), indent=2) + "\n", encoding="utf-8")
        tmp.replace(path)

    @classmethod
    def load(cls, path: str | Path) -> Scene:
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise SceneFileError(f"{path}: cannot read: {exc.strerror or exc}") from exc
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise SceneFileError(f"{path}: line {exc.lineno}, column {exc.colno}: not valid JSON ({exc.msg})") from exc
        return cls.from_dict(data, source=str(path))


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
    """Points as a tuple of float triples, checked in one vectorised pass."""
    try:
        seq = points if isinstance(points, (tuple, list)) else list(points)
        if all(type(p) is tuple and len(p) == 3 for p in seq):
            arr = np.array(seq, dtype=np.float64).reshape(-1, 3)
            if np.isfinite(arr).all():
                if all(type(c) is float for p in seq for c in p):
                    return _Points.trusted(seq, arr)
                return _Points.trusted(map(tuple, arr.tolist()), arr)
    except (TypeError, ValueError):
        pass
    for i, p in enumerate(points):
        _triple(p, f"points[{i}]")
    arr = np.array(points, dtype=np.float64).reshape(-1, 3)
    return _Points.trusted(map(tuple, arr.tolist()), arr)


def _from_json(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value
