"""Scene changes a lesson step makes: a fixed vocabulary of small frozen records.

Each ``[[steps.changes]]`` table names its kind with ``do`` and is parsed by :func:`parse_change`. The changes
that alter the scene are applied to a :class:`~egtviz.scene.SceneModel` by :func:`apply` (through the model's
own validated API, so the scene layer's checks and limits hold); :class:`SetRange`, :class:`SetLab`,
:class:`SetLens` and :class:`OpenDemo` are records for the runner and the GUI (a field's slider range, the
estimation lab's settings, the convention lens's toggles, the servo demo the step opens), which
:func:`apply` returns untouched.

The kinds (``do = ...``) and their keys are listed in ``docs/lessons.md``; :func:`parse_change` reads them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from ..scene import SceneError, SceneModel
from ..scene.lab import LabSettings
from ..scene.lens import LensToggles
from ..scene.limits import (
    ANGLE_DEG,
    COORDINATE,
    FOCAL_LENGTH,
    IMAGE_SIZE,
    MAX_POINTS,
    MIRROR_PARAMETER,
    PANORAMIC_FOCAL_PIXELS,
    PIXELS_PER_METRE,
    PRINCIPAL_POINT,
    SKEW,
    Range,
)
from . import fields
from .errors import EntryError
from .servo_runs import DEMOS, RUN_FIELDS, DemoRun, parse_run_fields

DISPLAY_OPTIONS = ("rays", "planes", "frames", "labels", "surfaces")
"""What ``show`` / ``hide`` switch (the ``show_<what>`` fields of :class:`~egtviz.scene.DisplayOptions`)."""

RANGED_FIELDS: dict[str, Range] = {
    "position": COORDINATE,
    "ypr_deg": ANGLE_DEG,
    "focal_length": FOCAL_LENGTH,
    "pixels_per_metre": PIXELS_PER_METRE,
    "principal_point": PRINCIPAL_POINT,
    "skew": SKEW,
    "width": IMAGE_SIZE,
    "height": IMAGE_SIZE,
    "a": MIRROR_PARAMETER,
    "b": MIRROR_PARAMETER,
    "focal_pixels": PANORAMIC_FOCAL_PIXELS,
}
"""Camera fields a ``set_range`` may narrow, with the shared limit the range must lie in."""

_POINT_INDEX = Range(0, MAX_POINTS - 1, "", integer=True)
_SEED = Range(0, 2**31 - 1, "", integer=True)
_EXTENT = Range(1e-3, COORDINATE.high, "m")
_COUNT = Range(8, MAX_POINTS, "", integer=True)


@dataclass(frozen=True)
class Show:
    """Switch a display option on (``show``) or off (``hide``)."""

    what: str
    on: bool = True

    do: ClassVar[str] = "show"

    def _apply(self, model: SceneModel) -> None:
        model.set_option(f"show_{self.what}", self.on)


@dataclass(frozen=True)
class MoveCamera:
    """Place a camera: new ``position`` and/or ``ypr_deg`` (the spec's own angle convention)."""

    camera: str
    position: tuple[float, float, float] | None = None
    ypr_deg: tuple[float, float, float] | None = None

    do: ClassVar[str] = "move"

    def _apply(self, model: SceneModel) -> None:
        values = {k: v for k, v in (("position", self.position), ("ypr_deg", self.ypr_deg)) if v is not None}
        model.update_camera(self.camera, **values)


@dataclass(frozen=True)
class MovePoint:
    """Move point ``point`` to ``to``."""

    point: int
    to: tuple[float, float, float]

    do: ClassVar[str] = "move"

    def _apply(self, model: SceneModel) -> None:
        model.set_point(self.point, self.to)


@dataclass(frozen=True)
class Highlight:
    """Draw attention to these cameras and ``"point:<i>"`` (replaces the previous highlight)."""

    names: tuple[str, ...]

    do: ClassVar[str] = "highlight"

    def _apply(self, model: SceneModel) -> None:
        model.highlight(list(self.names))


@dataclass(frozen=True)
class Lock:
    """Lock (``locked=True``) or unlock these gizmos: camera names and ``"point:<i>"``."""

    names: tuple[str, ...]
    locked: bool = True

    do: ClassVar[str] = "lock"

    def _apply(self, model: SceneModel) -> None:
        scene = model.scene
        for n in self.names:  # unlocking an unknown name would otherwise pass silently
            if n.startswith("point:"):
                if not n[6:].isdigit() or int(n[6:]) >= len(scene.points):
                    raise SceneError(f"names: no point {n!r} (have {len(scene.points)} points)")
            else:
                scene.camera(n)
        with model.batch("lock"):  # all or nothing
            for n in self.names:
                model.lock(n, self.locked)


@dataclass(frozen=True)
class Select:
    """Select a point (its epipolar plane is drawn), or clear the selection (``point=None``)."""

    point: int | None

    do: ClassVar[str] = "select"

    def _apply(self, model: SceneModel) -> None:
        model.select_point(self.point)


@dataclass(frozen=True)
class SetPair:
    """Choose the two cameras whose epipolar geometry is drawn."""

    cameras: tuple[str, str]

    do: ClassVar[str] = "set_pair"

    def _apply(self, model: SceneModel) -> None:
        model.set_pair(*self.cameras)


@dataclass(frozen=True)
class SetField:
    """Set one field of a camera spec (``focal_length``, ``principal_point``, ``mirror``, ...)."""

    camera: str
    field: str
    value: Any

    do: ClassVar[str] = "set_field"

    def _apply(self, model: SceneModel) -> None:
        model.update_camera(self.camera, **{self.field: self.value})


@dataclass(frozen=True)
class SetPoints:
    """Replace every point."""

    points: tuple[tuple[float, float, float], ...]

    do: ClassVar[str] = "set_points"

    def _apply(self, model: SceneModel) -> None:
        model.set_points(list(self.points))


@dataclass(frozen=True)
class RandomPoints:
    """``n`` points drawn uniformly in the cube of half-side ``extent`` round ``center`` (seeded)."""

    n: int
    seed: int = 0
    center: tuple[float, float, float] = (0.0, 0.0, 1.0)
    extent: float = 2.0

    do: ClassVar[str] = "random_points"

    def _apply(self, model: SceneModel) -> None:
        model.randomize_points(self.n, self.seed, center=self.center, extent=self.extent)


@dataclass(frozen=True)
class SetRange:
    """Record: the GUI offers only ``low..high`` for ``camera``'s ``field`` (each component of a vector field)."""

    camera: str
    field: str
    low: float
    high: float

    do: ClassVar[str] = "set_range"

    def _apply(self, model: SceneModel) -> SetRange:
        spec = model.scene.camera(self.camera)  # SceneError: no such camera
        if self.field not in spec.field_names():
            raise EntryError("field", f"camera {self.camera!r} ({spec.kind}) has no field {self.field!r}")
        return self


@dataclass(frozen=True)
class SetLab:
    """Record: new values for some of the estimation lab's settings (:class:`~egtviz.scene.lab.LabSettings`)."""

    values: tuple[tuple[str, Any], ...]

    do: ClassVar[str] = "set_lab"

    def _apply(self, model: SceneModel) -> SetLab:
        return self

    def applied_to(self, settings: LabSettings) -> LabSettings:
        """``settings`` with this record's values (checked by :class:`LabSettings`)."""
        return dataclasses.replace(settings, **dict(self.values))


@dataclass(frozen=True)
class SetLens:
    """Record: new values for some of the convention lens's toggles (:class:`~egtviz.scene.lens.LensToggles`)."""

    values: tuple[tuple[str, bool], ...]

    do: ClassVar[str] = "set_lens"

    def _apply(self, model: SceneModel) -> SetLens:
        return self

    def applied_to(self, toggles: LensToggles) -> LensToggles:
        """``toggles`` with this record's values."""
        return dataclasses.replace(toggles, **dict(self.values))


@dataclass(frozen=True)
class OpenDemo(DemoRun):
    """Record: the step offers a button that opens servo demo ``demo`` with these run fields
    (:class:`~egtviz.lessons.servo_runs.DemoRun`); its ``servo_number`` tasks measure that run."""

    do: ClassVar[str] = "open_demo"

    def _apply(self, model: SceneModel) -> OpenDemo:
        return self


def _drawn(rng: Any, low: float, high: float, digits: int = 2) -> float:
    """One value drawn uniformly in ``[low, high]`` and rounded to ``digits`` decimals (the fields show what the
    core uses); ``low`` itself for an empty range."""
    return round(float(rng.uniform(low, high)), digits) if low < high else low


@dataclass(frozen=True)
class RandomiseCamera:
    """Place camera ``camera`` (and set its focal length and principal point) at values drawn per learner.

    Each component is a ``(low, high)`` range, drawn uniformly and rounded to 0.01 (so the value the camera's
    fields show is the value the core uses), in a fixed order: position x, y, z, yaw, pitch, roll, focal
    length, u0, v0. ``seed`` is bound by the lesson runner from (learner, lesson, step, camera); unbound (a
    lesson being validated), the draw of seed 0 is used.
    """

    camera: str
    position: tuple[tuple[float, float], ...] | None = None
    ypr_deg: tuple[tuple[float, float], ...] | None = None
    focal_length: tuple[float, float] | None = None
    principal_point: tuple[tuple[float, float], ...] | None = None
    seed: int | None = None

    do: ClassVar[str] = "randomise_camera"

    def seeded(self, seed: int) -> RandomiseCamera:
        """This change with its draw bound to ``seed``."""
        return dataclasses.replace(self, seed=seed)

    def values(self) -> dict[str, Any]:
        """The drawn fields (``position``, ``ypr_deg``, ``focal_length``, ``principal_point``), by this seed."""
        import numpy as np

        rng = np.random.default_rng(0 if self.seed is None else self.seed)
        out: dict[str, Any] = {}
        for key in ("position", "ypr_deg", "focal_length", "principal_point"):
            ranges = getattr(self, key)
            if ranges is None:
                continue
            if key == "focal_length":
                low, high = ranges
                out[key] = _drawn(rng, low, high, digits=5)
            else:
                out[key] = tuple(_drawn(rng, low, high) for low, high in ranges)
        return out

    @property
    def seed_key(self) -> str:
        """What the runner's per-learner seed is drawn for (with the learner, lesson and step)."""
        return f"randomise:{self.camera}"

    def _apply(self, model: SceneModel) -> None:
        model.update_camera(self.camera, **self.values())


@dataclass(frozen=True)
class RandomisePoint:
    """Move point ``point`` to a position drawn per learner: each coordinate a ``(low, high)`` range, drawn
    uniformly and rounded to 0.01 (the point list shows what the core uses). ``seed`` is bound by the lesson runner
    from (learner, lesson, step, point), as for :class:`RandomiseCamera`; unbound, the draw of seed 0."""

    point: int
    position: tuple[tuple[float, float], ...]
    seed: int | None = None

    do: ClassVar[str] = "randomise_point"

    def seeded(self, seed: int) -> RandomisePoint:
        """This change with its draw bound to ``seed``."""
        return dataclasses.replace(self, seed=seed)

    @property
    def seed_key(self) -> str:
        """What the runner's per-learner seed is drawn for (with the learner, lesson and step)."""
        return f"randomise:point:{self.point}"

    def value(self) -> tuple[float, float, float]:
        """The drawn position, by this seed."""
        import numpy as np

        rng = np.random.default_rng(0 if self.seed is None else self.seed)
        x, y, z = (_drawn(rng, low, high) for low, high in self.position)
        return x, y, z

    def _apply(self, model: SceneModel) -> None:
        model.set_point(self.point, self.value())


Change = (
    Show | MoveCamera | MovePoint | Highlight | Lock | Select | SetPair | SetField | SetPoints | RandomPoints
    | SetRange | SetLab | SetLens | OpenDemo | RandomiseCamera | RandomisePoint
)
Record = SetRange | SetLab | SetLens | OpenDemo


def apply(model: SceneModel, change: Change) -> Record | None:
    """Apply ``change`` to ``model``; a record (:data:`Record`) is returned for the runner instead.

    Raises:
        SceneError: the scene layer refused the change (a missing camera or point, a value out of range);
            the model is unchanged.
        EntryError: a ``set_range`` naming a field the camera does not have.
    """
    return change._apply(model)


# -- parsing -------------------------------------------------------------------------------------------

_SETTABLE = frozenset(
    {"focal_length", "pixels_per_metre", "principal_point", "skew", "width", "height", "mirror", "a", "b",
     "focal_pixels", "position", "ypr_deg", "xi"}
)


def _show(table: dict, do: str) -> Show:
    what = fields.text(table, "what")
    if what not in DISPLAY_OPTIONS:
        raise EntryError("what", f"expected one of {', '.join(DISPLAY_OPTIONS)}, got {fields.short(what)}")
    return Show(what, do == "show")


def _move(table: dict, do: str) -> MoveCamera | MovePoint:
    if "point" in table:
        for key in ("camera", "position", "ypr_deg"):
            if key in table:
                raise EntryError(key, "a move names a camera (position, ypr_deg) or a point (to), not both")
        return MovePoint(fields.whole(table, "point", _POINT_INDEX),
                         fields.numbers(table, "to", 3, COORDINATE))  # type: ignore[arg-type]
    if "to" in table:
        raise EntryError("to", "'to' moves a point: name it with 'point'")
    camera = fields.text(table, "camera")
    position = fields.numbers(table, "position", 3, COORDINATE, required=False)
    ypr = fields.numbers(table, "ypr_deg", 3, ANGLE_DEG, required=False)
    if position is None and ypr is None:
        raise EntryError(None, "a camera move needs 'position', 'ypr_deg' or both")
    return MoveCamera(camera, position, ypr)  # type: ignore[arg-type]


def _set_pair(table: dict, do: str) -> SetPair:
    names = fields.name_list(table, "cameras")
    if len(names) != 2 or names[0] == names[1]:
        raise EntryError("cameras", f"expected two different camera names, got {fields.short(list(names))}")
    return SetPair(names)  # type: ignore[arg-type]


def _set_field(table: dict, do: str) -> SetField:
    camera = fields.text(table, "camera")
    field = fields.text(table, "field")
    if field not in _SETTABLE:
        raise EntryError("field", f"expected one of {', '.join(sorted(_SETTABLE))}, got {fields.short(field)}")
    if "value" not in table:
        raise EntryError("value", "missing")
    value = table["value"]
    if isinstance(value, list):
        value = tuple(value)
    if isinstance(value, dict) or not isinstance(value, (int, float, str, tuple)) or isinstance(value, bool):
        raise EntryError("value", f"expected a number, a list of numbers or text, got {fields.short(value)}")
    return SetField(camera, field, value)


def _set_points(table: dict, do: str) -> SetPoints:
    pts = table.get("points")
    if not isinstance(pts, list) or len(pts) > MAX_POINTS:
        raise EntryError("points", f"expected a list of at most {MAX_POINTS} [x, y, z], got {fields.short(pts)}")
    return SetPoints(tuple(fields.numbers({"points": p}, "points", 3, COORDINATE) for p in pts))  # type: ignore[misc]


def _random_points(table: dict, do: str) -> RandomPoints:
    return RandomPoints(
        fields.whole(table, "n", _COUNT),
        fields.whole(table, "seed", _SEED, required=False, default=0),
        fields.numbers(table, "center", 3, COORDINATE, required=False) or (0.0, 0.0, 1.0),  # type: ignore[arg-type]
        fields.number(table, "extent", _EXTENT, required=False, default=2.0),
    )


def _set_range(table: dict, do: str) -> SetRange:
    camera = fields.text(table, "camera")
    field = fields.text(table, "field")
    if field not in RANGED_FIELDS:
        raise EntryError("field", f"expected one of {', '.join(RANGED_FIELDS)}, got {fields.short(field)}")
    limit = RANGED_FIELDS[field]
    low = fields.number(table, "low", limit)
    high = fields.number(table, "high", limit)
    if not low < high:
        raise EntryError("high", f"expected high > low ({low:g}), got {high:g}")
    return SetRange(camera, field, low, high)


def _set_lab(table: dict, do: str) -> SetLab:
    values = {k: v for k, v in table.items() if k != "do"}
    try:
        LabSettings(**values)
    except (ValueError, TypeError) as exc:
        raise EntryError(_named_key(str(exc), values), str(exc)) from None
    return SetLab(tuple(sorted(values.items())))


def _set_lens(table: dict, do: str) -> SetLens:
    values = {k: v for k, v in table.items() if k != "do"}
    for k, v in values.items():
        if type(v) is not bool:
            raise EntryError(k, f"expected true or false, got {fields.short(v)}")
    return SetLens(tuple(sorted(values.items())))


def _open_demo(table: dict, do: str) -> OpenDemo:
    demo = fields.text(table, "demo")
    if demo not in DEMOS:
        raise EntryError("demo", f"expected one of {', '.join(DEMOS)}, got {fields.short(demo)}")
    fields.refuse_unknown(table, ("do", "demo", *RUN_FIELDS[demo]), f"an 'open_demo' change of the {demo} demo")
    return OpenDemo(demo, parse_run_fields(table, demo))


def _ranges(table: dict, key: str, n: int, limit: Range) -> tuple[tuple[float, float], ...] | None:
    """``n`` components, each a number (fixed) or ``[low, high]`` inside ``limit``."""
    if key not in table:
        return None
    value = table[key]
    if not isinstance(value, list) or len(value) != n:
        raise EntryError(key, f"expected a list of {n} numbers or [low, high] pairs, got {fields.short(value)}")
    out = []
    for item in value:
        pair = item if isinstance(item, list) else [item, item]
        if len(pair) != 2:
            raise EntryError(key, f"expected a number or [low, high], got {fields.short(item)}")
        low, high = (fields.as_number(x, key, limit) for x in pair)
        if low > high:
            raise EntryError(key, f"expected low <= high, got {fields.short(item)}")
        out.append((low, high))
    return tuple(out)


def _randomise_camera(table: dict, do: str) -> RandomiseCamera:
    focal = _ranges({"focal_length": [table["focal_length"]]} if "focal_length" in table else {}, "focal_length",
                    1, FOCAL_LENGTH)
    ranges = {k: _ranges(table, k, n, limit) for k, n, limit in
              (("position", 3, COORDINATE), ("ypr_deg", 3, ANGLE_DEG), ("principal_point", 2, PRINCIPAL_POINT))}
    if focal is None and all(v is None for v in ranges.values()):
        raise EntryError("position", "expected at least one of position, ypr_deg, focal_length, principal_point")
    return RandomiseCamera(fields.text(table, "camera"), focal_length=None if focal is None else focal[0],
                           position=ranges["position"], ypr_deg=ranges["ypr_deg"],
                           principal_point=ranges["principal_point"])


def _randomise_point(table: dict, do: str) -> RandomisePoint:
    position = _ranges(table, "position", 3, COORDINATE)
    if position is None:
        raise EntryError("position", "missing")
    return RandomisePoint(fields.whole(table, "point", _POINT_INDEX), position)


def _highlight(table: dict, do: str) -> Highlight:
    return Highlight(fields.name_list(table, "names"))


def _lock(table: dict, do: str) -> Lock:
    return Lock(fields.name_list(table, "names"), do == "lock")


def _select(table: dict, do: str) -> Select:
    return Select(fields.whole(table, "point", _POINT_INDEX) if "point" in table else None)


_KINDS: dict[str, tuple[tuple[str, ...], Callable[[dict, str], Change]]] = {
    "show": (("do", "what"), _show),
    "hide": (("do", "what"), _show),
    "move": (("do", "camera", "position", "ypr_deg", "point", "to"), _move),
    "highlight": (("do", "names"), _highlight),
    "lock": (("do", "names"), _lock),
    "unlock": (("do", "names"), _lock),
    "select": (("do", "point"), _select),
    "set_pair": (("do", "cameras"), _set_pair),
    "set_field": (("do", "camera", "field", "value"), _set_field),
    "set_points": (("do", "points"), _set_points),
    "random_points": (("do", "n", "seed", "center", "extent"), _random_points),
    "set_range": (("do", "camera", "field", "low", "high"), _set_range),
    "set_lab": (("do", *(f.name for f in dataclasses.fields(LabSettings))), _set_lab),
    "set_lens": (("do", *(f.name for f in dataclasses.fields(LensToggles))), _set_lens),
    "open_demo": (("do", "demo", *RUN_FIELDS["pinhole"]), _open_demo),
    "randomise_camera": (("do", "camera", "position", "ypr_deg", "focal_length", "principal_point"),
                         _randomise_camera),
    "randomise_point": (("do", "point", "position"), _randomise_point),
}
"""Every change kind (``do``): the keys its table may have and the function that reads it (given ``do``)."""
CHANGE_KINDS = tuple(_KINDS)
"""The values ``do`` accepts."""


def parse_change(table: Any) -> Change:
    """One ``[[steps.changes]]`` table as a change record (types and ranges checked here; names of cameras
    and points are checked when the change is applied to the step's scene).

    Raises:
        EntryError: naming the offending key.
    """
    if not isinstance(table, dict):
        raise EntryError(None, f"expected a table, got {fields.short(table)}")
    do = table.get("do")
    if type(do) is not str or do not in _KINDS:
        raise EntryError("do", f"expected one of {', '.join(CHANGE_KINDS)}, got {fields.short(do)}")
    keys, parse = _KINDS[do]
    fields.refuse_unknown(table, keys, f"a {do!r} change")
    return parse(table, do)


def _named_key(message: str, values: dict) -> str | None:
    """The key of ``values`` a message starts with, if any."""
    for k in values:
        if message.startswith(k):
            return k
    return None
