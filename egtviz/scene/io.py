"""Scene files: bytes to a checked, drawable :class:`Scene` and back; safe reads and atomic writes.

One validation for every way a scene file arrives (``egtviz scene check``, ``serve --scene``, a browser
upload, lesson files): strict UTF-8, JSON with no duplicate keys and bounded nesting and integers, every
entry type-checked against the limits of :mod:`egtviz.scene.limits`, then drawn once
(:func:`egtviz.scene.compute_derived`). A file passes if and only if the viewer can draw it. Every
refusal is a :class:`SceneFileError` naming the source, the entry and the reason.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..files import FileSafetyError, printable, read_limited, too_large, write_atomic
from ..geometry.camera_model import CAMERA_MODELS
from .limits import (
    MAX_CAMERAS,
    MAX_JSON_DEPTH,
    MAX_JSON_INT_DIGITS,
    MAX_POINTS,
    MAX_SCENE_FILE_BYTES,
    MAX_SURFACES,
)
from .annotations import annotations_from_dict
from .scene import FILE_FORMAT, FILE_VERSION, Scene, SceneFileError, scene_to_bytes, scene_to_dict
from ._values import SceneError, required_fields, short_text
from .cameras import CAMERA_KINDS, spec_for_model
from .specs import DisplayOptions, SurfaceSpec
from .surfaces import check_surface

__all__ = [
    "load_scene_file",
    "save_scene_file",
    "scene_from_argument",
    "scene_from_bytes",
    "scene_from_dict",
    "scene_to_bytes",
    "scene_to_dict",
]

_TOP_LEVEL = (
    "format", "version", "title", "cameras", "points", "surfaces", "pair",
    "selected_point", "options", "locked", "highlighted", "annotations",
)  # fmt: skip


class _Refused(ValueError):
    """A JSON text refused while it is parsed (duplicate key, huge integer, NaN)."""


def _object_without_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _Refused(f"duplicate key {short_text(key)}")
        out[key] = value
    return out


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_JSON_INT_DIGITS:
        raise _Refused(f"an integer with more than {MAX_JSON_INT_DIGITS} digits ({text[:12]}...)")
    return int(text)


def _finite_float(text: str) -> float:
    x = float(text)
    if not np.isfinite(x):
        raise _Refused(f"the number {text[:20]} is too large for a float")
    return x


def _no_constant(text: str) -> Any:
    raise _Refused(f"{text} is not a JSON number")


def _nesting_depth(value: Any) -> int:
    """How deeply lists and objects nest in parsed JSON (1 for a flat list), counted without recursion."""
    deepest = 0
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, (list, dict)):
            deepest = max(deepest, depth)
            stack.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict) else item))
    return deepest


def _too_deep(data: bytes) -> int | None:
    """The line where a JSON text first nests lists or objects more than ``MAX_JSON_DEPTH`` deep, or None.

    Read from the bytes before the text is parsed, in a few array operations (linear in the size, whatever the
    text): brackets inside strings, between quotes that no odd run of backslashes escapes, do not count.
    """
    if data.count(b"[") + data.count(b"{") <= MAX_JSON_DEPTH:
        return None
    b = np.frombuffer(data, dtype=np.uint8)
    index = np.arange(b.size, dtype=np.int32)
    last_other = np.maximum.accumulate(np.where(b == ord("\\"), np.int32(-1), index))
    quote = b == ord('"')
    quote[1:] &= (index[:-1] - last_other[:-1]) % 2 == 0  # an even run of backslashes (or none) before it
    outside = np.cumsum(quote, dtype=np.int32) % 2 == 0
    step = (((b == ord("[")) | (b == ord("{"))) & outside).astype(np.int8)
    step -= (((b == ord("]")) | (b == ord("}"))) & outside).astype(np.int8)
    deeper = np.flatnonzero(np.cumsum(step, dtype=np.int32) > MAX_JSON_DEPTH)
    return data.count(b"\n", 0, int(deeper[0])) + 1 if deeper.size else None


def scene_from_bytes(data: bytes, source: str) -> Scene:
    """A scene from the bytes of a scene file, checked completely (what an upload and the CLI use).

    Args:
        data: the file's content (UTF-8 JSON).
        source: what to call the file in messages (a path or an upload's name).

    Raises:
        SceneFileError: ``"<source>: <entry>: <reason>"``.
    """
    source = printable(source)
    if not isinstance(data, (bytes, bytearray)):
        raise SceneFileError(f"{source}: expected the bytes of a file, got {type(data).__name__}")
    if len(data) > MAX_SCENE_FILE_BYTES:
        raise SceneFileError(f"{source}: {too_large(len(data), MAX_SCENE_FILE_BYTES)}")
    deep = _too_deep(bytes(data))
    if deep is not None:
        raise SceneFileError(f"{source}: line {deep}: lists or objects nested more than {MAX_JSON_DEPTH} levels deep")
    try:
        text = bytes(data).decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SceneFileError(f"{source}: byte {exc.start}: not UTF-8 text") from None
    text = text.removeprefix("\ufeff")
    try:
        parsed = json.loads(
            text,
            object_pairs_hook=_object_without_duplicates,
            parse_int=_bounded_int,
            parse_float=_finite_float,
            parse_constant=_no_constant,
        )
    except json.JSONDecodeError as exc:
        raise SceneFileError(f"{source}: line {exc.lineno}, column {exc.colno}: not valid JSON ({exc.msg})") from None
    except _Refused as exc:
        raise SceneFileError(f"{source}: {exc}") from None
    except RecursionError:  # the parser's own guard against deep nesting
        raise SceneFileError(f"{source}: lists or objects nested more than {MAX_JSON_DEPTH} levels deep") from None
    if _nesting_depth(parsed) > MAX_JSON_DEPTH:
        raise SceneFileError(f"{source}: lists or objects nested more than {MAX_JSON_DEPTH} levels deep")
    return scene_from_dict(parsed, source)


def _entry(source: str, where: str, exc: Exception) -> SceneFileError:
    return SceneFileError(f"{source}: {where}: {exc}")


def _list(data: dict, key: str, source: str, limit: int) -> list:
    value = data.get(key, [])
    if not isinstance(value, list):
        raise SceneFileError(f"{source}: {key}: expected a list, got {short_text(value)}")
    if len(value) > limit:
        raise SceneFileError(f"{source}: {key}: at most {limit} entries, got {len(value)}")
    return value


#: What a missing required field holds, for the message.
_REQUIRED_WHAT = {"name": "a non-empty string"}


def _fields(entry: Any, where: str, source: str, cls: type, what: str) -> dict[str, Any]:
    """A JSON object's entries as keyword arguments of ``cls`` (lists become tuples); unknown keys refused (a camera
    spec's are its ``field_names()``: its pose as ``position`` and ``ypr_deg``)."""
    if not isinstance(entry, dict):
        raise SceneFileError(f"{source}: {where}: expected an object, got {short_text(entry)}")
    names = getattr(cls, "field_names", None)
    known = set(names()) if names is not None else {f.name for f in dataclasses.fields(cls)}
    for key in entry:
        if key not in known:
            raise SceneFileError(f"{source}: {where}.{printable(key)}: unknown field for {what}")
    for name in required_fields(cls):
        if name not in entry:
            # Caught here: the constructor would raise a TypeError, not an error naming the entry.
            raise SceneFileError(f"{source}: {where}: {name}: missing; expected {_REQUIRED_WHAT.get(name, 'a value')}")
    return {k: tuple(v) if isinstance(v, list) else v for k, v in entry.items()}


def _camera(entry: Any, where: str, source: str) -> Any:
    """The camera spec of a scene file's entry ``where``: its ``kind`` is a spec's (``"panoramic"``) or a registered
    model's (``"parabolic"``, which selects it in its spec)."""
    kind = entry.get("kind") if isinstance(entry, dict) else None
    if type(kind) is not str or not (kind in CAMERA_KINDS or kind in CAMERA_MODELS):
        raise SceneFileError(f"{source}: {where}.kind: expected one of {sorted(set(CAMERA_KINDS) | set(CAMERA_MODELS))}, "
                             f"got {short_text(kind)}")
    entry = {k: v for k, v in entry.items() if k != "kind"}
    spec_cls, selection = (CAMERA_KINDS[kind], {}) if kind in CAMERA_KINDS else spec_for_model(kind)
    for field, value in selection.items():  # a field that says otherwise than the kind is an error
        if entry.setdefault(field, value) != value:
            raise SceneFileError(f"{source}: {where}.{field}: a {kind} camera has {field} {value!r}, got "
                                 f"{short_text(entry[field])}")
    try:
        return spec_cls(**_fields(entry, where, source, spec_cls, f"a {kind} camera"))
    except SceneError as exc:
        if isinstance(exc, SceneFileError):
            raise
        raise _entry(source, where, exc) from None


def scene_from_dict(data: Any, source: str = "scene") -> Scene:
    """A scene from parsed JSON data: every entry type-checked, then the scene drawn once.

    Raises:
        SceneFileError: ``"<source>: <entry>: <reason>"``.
    """
    source = printable(source)
    if not isinstance(data, dict):
        raise SceneFileError(f"{source}: top level: expected a JSON object, got {short_text(data)}")
    for key in data:
        if key not in _TOP_LEVEL:
            raise SceneFileError(f"{source}: {printable(key)}: unknown entry")
    if "format" in data and data["format"] != FILE_FORMAT:
        raise SceneFileError(f"{source}: format: expected {FILE_FORMAT!r}, got {short_text(data['format'])}")
    if "version" in data and (type(data["version"]) is not int or data["version"] != FILE_VERSION):
        raise SceneFileError(f"{source}: version: this egtviz reads version {FILE_VERSION}, got {short_text(data['version'])}")

    cameras = [_camera(entry, f"cameras[{i}]", source)
               for i, entry in enumerate(_list(data, "cameras", source, MAX_CAMERAS))]

    points = _list(data, "points", source, MAX_POINTS)
    points = [tuple(p) if isinstance(p, list) else p for p in points]

    surfaces = []
    for i, entry in enumerate(_list(data, "surfaces", source, MAX_SURFACES)):
        where = f"surfaces[{i}]"
        try:
            surfaces.append(check_surface(SurfaceSpec(**_fields(entry, where, source, SurfaceSpec, "a surface"))))
        except SceneError as exc:
            if isinstance(exc, SceneFileError):
                raise
            raise _entry(source, where, exc) from None

    options = data.get("options", {})
    try:
        options = DisplayOptions(**_fields(options, "options", source, DisplayOptions, "the display options"))
    except SceneError as exc:
        if isinstance(exc, SceneFileError):
            raise
        raise SceneFileError(f"{source}: {exc}") from None
    pair = data.get("pair")
    marks = {}
    for key in ("locked", "highlighted"):
        value = data.get(key, [])
        if not isinstance(value, list) or not all(type(v) is str for v in value):
            raise SceneFileError(f"{source}: {key}: expected a list of names, got {short_text(value)}")
        marks[key] = frozenset(value)
    try:
        annotations = annotations_from_dict(data.get("annotations", {}))
    except SceneError as exc:
        raise SceneFileError(f"{source}: {exc}") from None
    try:
        scene = Scene(
            cameras=tuple(cameras),
            points=tuple(points),
            surfaces=tuple(surfaces),
            pair=tuple(pair) if isinstance(pair, list) else pair,
            selected_point=data.get("selected_point"),
            options=options,
            title=data.get("title", ""),
            annotations=annotations,
            **marks,
        )
    except SceneError as exc:  # messages start with the entry ("points[3]: ...", "pair: ...")
        raise SceneFileError(f"{source}: {exc}") from None
    from .derived import compute_derived

    try:
        compute_derived(scene)
    except SceneError as exc:
        raise SceneFileError(f"{source}: scene: {exc}") from None
    return scene


def load_scene_file(path: str | os.PathLike) -> Scene:
    """Read a scene file: a regular file of at most ``MAX_SCENE_FILE_BYTES``, checked like any scene file.

    Raises:
        SceneFileError: the file is refused (not a regular file, too large, unreadable) or malformed.
    """
    try:
        data = read_limited(path, MAX_SCENE_FILE_BYTES)
    except FileSafetyError as exc:
        raise SceneFileError(str(exc)) from None
    return scene_from_bytes(data, os.fspath(path))


def save_scene_file(scene: Scene, path: str | os.PathLike, *, overwrite: bool = True) -> None:
    """Write a scene file atomically (``egtviz.files.write_atomic``: never a device, FIFO, folder or link).

    Raises:
        FileSafetyError: the target is refused or the write failed.
    """
    write_atomic(path, scene_to_bytes(scene), overwrite=overwrite)


def scene_from_argument(value: str) -> Scene:
    """A built-in scene by name (unless a file of that name exists), or a scene file.

    Raises:
        SceneFileError: the file is refused or malformed; for a name that is neither, the message lists the
            built-in names.
    """
    from .examples import SCENES

    value = os.fspath(value)
    if value in SCENES and not os.path.lexists(value):
        return SCENES[value]()
    if not os.path.lexists(value):
        raise SceneFileError(
            f"{printable(value)}: no such file and not a built-in scene (built-in: {', '.join(SCENES)})"
        )
    return load_scene_file(Path(value))
