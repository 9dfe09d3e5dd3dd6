"""Checks of the values a scene holds: numbers in a range, triples, short quotes of bad values, the scene errors.

Shared by the specs, the scene, the annotations, the file reader and the model (each imports these public names;
the module is private to :mod:`egtviz.scene`).
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import numpy as np

from .limits import COORDINATE, Range

__all__ = [
    "NUMBER_TYPES",
    "OutOfRangeError",
    "SceneError",
    "as_number",
    "as_numbers",
    "as_pair",
    "as_ranged",
    "as_triple",
    "has_control_characters",
    "required_fields",
    "short_text",
]

_isfinite = math.isfinite


class SceneError(ValueError):
    """A change to a scene that cannot be applied (the scene is left unchanged)."""


class OutOfRangeError(SceneError):
    """A number outside its plausible range (``egtviz.scene.limits``).

    The attributes let a GUI restate the refusal in its own units.
    """

    def __init__(self, camera: str | None, field: str, value: float, limit: Range) -> None:
        self.camera = camera
        """Name of the camera the value belongs to, or None (a point, a surface)."""
        self.field = field
        """The spec field (``"focal_length"``, ``"position"``, ...)."""
        self.value = value
        self.limit = limit
        owner = f"camera {camera!r}: " if camera is not None else ""
        kind = "a whole number in " if limit.integer else ""
        super().__init__(f"{owner}{field}: expected {kind}{limit.describe()}, got {short_text(value)}")


def short_text(value: Any) -> str:
    """``repr(value)`` cut to a short prefix (a bad value may be a huge string or integer)."""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**30:
        return "an integer with more than 30 digits"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


NUMBER_TYPES = (int, float, np.integer, np.floating)


def as_number(value: Any, name: str, owner: str = "") -> float:
    """``value`` as a finite float; strings, booleans, None and containers are refused."""
    if type(value) is float:
        x = value
    elif isinstance(value, (bool, np.bool_)) or not isinstance(value, NUMBER_TYPES):
        raise SceneError(f"{owner}{name}: expected a number, got {short_text(value)}")
    else:
        try:
            x = float(value)
        except OverflowError:
            raise SceneError(f"{owner}{name}: expected a finite number, got {short_text(value)}") from None
    if not _isfinite(x):
        raise SceneError(f"{owner}{name}: expected a finite number, got {short_text(value)}")
    return x


def as_ranged(value: Any, limit: Range, name: str, camera: str | None = None) -> float:
    """``value`` as a float inside ``limit`` (a whole number if ``limit.integer``), or an error naming it."""
    owner = f"camera {camera!r}: " if camera is not None else ""
    x = as_number(value, name, owner)
    if x not in limit or (limit.integer and not x.is_integer()):
        raise OutOfRangeError(camera, name, x, limit)
    return x


def as_numbers(value: Any, name: str, n: int, limit: Range = COORDINATE, camera: str | None = None) -> tuple[float, ...]:
    """``value`` as ``n`` floats inside ``limit``, or a SceneError naming ``name``."""
    lo, hi = limit.low, limit.high
    if type(value) is tuple and len(value) == n and all(type(v) is float for v in value):
        if all(lo <= v <= hi for v in value):  # the usual case (every drag): nothing to convert
            return value
        x = value
    else:
        owner = f"camera {camera!r}: " if camera is not None else ""
        if isinstance(value, np.ndarray):
            if value.ndim != 1:
                raise SceneError(f"{owner}{name}: expected {_COUNT[n]} numbers, got an array of shape {value.shape}")
            value = value.tolist()
        if not isinstance(value, (tuple, list)):
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} numbers, got {short_text(value)}")
        if len(value) != n:
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} finite numbers, got {len(value)}")
        for v in value:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, NUMBER_TYPES):
                raise SceneError(f"{owner}{name}: expected {_COUNT[n]} numbers, got {short_text(v)}")
        try:
            x = tuple(float(v) for v in value)
        except OverflowError:
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} finite numbers, got {short_text(value)}") from None
    for v in x:
        if not _isfinite(v):
            owner = f"camera {camera!r}: " if camera is not None else ""
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} finite numbers, got {short_text(v)}")
        if not lo <= v <= hi:
            raise OutOfRangeError(camera, name, v, limit)
    return x


_COUNT = {2: "two", 3: "three"}


def as_triple(value: Any, name: str, limit: Range = COORDINATE, camera: str | None = None) -> tuple[float, float, float]:
    return as_numbers(value, name, 3, limit, camera)  # type: ignore[return-value]


def as_pair(value: Any, name: str, limit: Range, camera: str | None = None) -> tuple[float, float]:
    return as_numbers(value, name, 2, limit, camera)  # type: ignore[return-value]


def has_control_characters(text: str) -> bool:
    """True if ``text`` holds a control character (C0, DEL, C1): refused in names and titles."""
    return _CONTROL.search(text) is not None


_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")


def required_fields(cls: type) -> tuple[str, ...]:
    """The fields of the dataclass ``cls`` that have no default (an entry of a scene file must give them: the
    constructor would raise a ``TypeError`` instead of an error naming the entry)."""
    return tuple(
        f.name for f in dataclasses.fields(cls)
        if f.init and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    )
