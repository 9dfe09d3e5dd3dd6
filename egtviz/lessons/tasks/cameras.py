r"""Tasks about the cameras' own fields: two orientations alike (:class:`SameOrientationTask`), a field in a
range (:class:`CameraFieldTask`), the unified-sphere :math:`\xi` in a range (:class:`XiBetweenTask`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...scene import Scene
from ...scene.limits import Range
from .. import fields
from ..errors import EntryError
from .base import Param, Task, TaskContext, TaskResult
from .common import ANSWER, FRACTION, WITHIN_DEG, camera_gone, camera_in, fmt

__all__ = ["CameraFieldTask", "SameOrientationTask", "XiBetweenTask", "camera_xi", "rotation_angle_deg"]

_COMPONENT = Range(0, 2, "", integer=True)


def rotation_angle_deg(Ra: np.ndarray, Rb: np.ndarray) -> float:
    r"""Angle of the rotation :math:`R_a^T R_b`: :math:`\arccos((\operatorname{tr}(R_a^T R_b) - 1) / 2)`, degrees."""
    c = (float(np.trace(Ra.T @ Rb)) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


@dataclass(frozen=True, kw_only=True)
class SameOrientationTask(Task):
    """Cameras A and B have the same orientation (frames) within ``within_deg``."""

    cameras: tuple[str, str]
    within_deg: float

    kind: ClassVar[str] = "same_orientation"
    table_keys: ClassVar[tuple[str, ...]] = ("cameras", "within_deg")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> SameOrientationTask:
        cams = fields.name_list(table, "cameras")
        if len(cams) != 2 or cams[0] == cams[1]:
            raise EntryError("cameras", f"expected two different camera names, got {fields.short(list(cams))}")
        return cls(**common, cameras=cams, within_deg=fields.number(table, "within_deg", WITHIN_DEG))  # type: ignore[arg-type]

    def params(self) -> dict[str, Param]:
        return {"within_deg": self.within_deg}

    def validate(self, scene: Scene) -> None:
        a, b = (camera_in(scene, n, "cameras") for n in self.cameras)
        if a.model_kind != b.model_kind:
            raise EntryError("cameras", f"expected two cameras of one kind, got {a.model_kind} and {b.model_kind}")

    def missing(self, scene: Scene) -> str | None:
        return camera_gone(scene, *self.cameras)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        a, b = (ctx.scene.camera(n) for n in self.cameras)
        angle = rotation_angle_deg(a.pose.R, b.pose.R)
        msg = f"{self.cameras[0]} and {self.cameras[1]} differ by a rotation of {angle:.1f} degrees"
        if angle <= params["within_deg"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['within_deg']:g} allowed.")


def _low_high(table: dict, limit: Range) -> tuple[float, float]:
    """The table's ``low`` and ``high`` in ``limit``, ``low <= high``."""
    low = fields.number(table, "low", limit)
    high = fields.number(table, "high", limit)
    if not low <= high:
        raise EntryError("high", f"expected high >= low ({low:g}), got {high:g}")
    return low, high


@dataclass(frozen=True, kw_only=True)
class CameraFieldTask(Task):
    """A numeric field of a camera spec (component ``component`` of a vector field) lies in ``low..high``."""

    camera: str
    field: str
    low: float
    high: float
    component: int | None = None

    kind: ClassVar[str] = "camera_field"
    table_keys: ClassVar[tuple[str, ...]] = ("camera", "field", "component", "low", "high")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> CameraFieldTask:
        low, high = _low_high(table, ANSWER)
        component = fields.whole(table, "component", _COMPONENT, required=False)
        return cls(**common, camera=fields.text(table, "camera"), field=fields.text(table, "field"),
                   low=low, high=high, component=component)

    def params(self) -> dict[str, Param]:
        return {"low": self.low, "high": self.high}

    def validate(self, scene: Scene) -> None:
        spec = camera_in(scene, self.camera)
        if self.field not in spec.field_names():
            raise EntryError("field", f"camera {self.camera!r} ({spec.kind}) has no field {self.field!r}")
        value = getattr(spec, self.field)
        if isinstance(value, tuple) != (self.component is not None):
            raise EntryError("component", f"give a component (0..{len(value) - 1}) exactly for a vector field"
                             if isinstance(value, tuple) else f"{self.field!r} is a single number: no component")
        if isinstance(value, tuple) and self.component >= len(value):  # type: ignore[operator]
            raise EntryError("component", f"{self.field!r} has {len(value)} components")
        if isinstance(value, str):
            raise EntryError("field", f"{self.field!r} is not a number")

    def missing(self, scene: Scene) -> str | None:
        gone = camera_gone(scene, self.camera)
        if gone is not None:
            return gone
        value = getattr(scene.camera(self.camera), self.field, None)
        shape_ok = (isinstance(value, tuple) and self.component is not None and self.component < len(value)
                    or isinstance(value, (int, float)) and self.component is None)
        if not shape_ok:
            return f"{self.camera} has no {self.field.replace('_', ' ')} any more (another kind of camera?)"
        return None

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        value = getattr(ctx.scene.camera(self.camera), self.field)
        x = float(value[self.component] if self.component is not None else value)
        name = self.field + (f"[{self.component}]" if self.component is not None else "")
        if params["low"] <= x <= params["high"]:
            return TaskResult(True, f"Done: {self.camera}'s {name} is {fmt(x)}.")
        return TaskResult(False, f"Not yet: {self.camera}'s {name} is {fmt(x)}; "
                                 f"it must be in {params['low']:g}..{params['high']:g}.")


def camera_xi(spec: Any) -> float:
    r"""The unified-sphere :math:`\xi` of a camera: its own ``xi``, its mirror's, or 0 for a pin-hole."""
    camera = spec.camera()
    if hasattr(camera, "xi"):
        return float(camera.xi)
    mirror = getattr(camera, "mirror", None)
    return 0.0 if mirror is None else float(mirror.xi)


@dataclass(frozen=True, kw_only=True)
class XiBetweenTask(Task):
    r"""The unified-sphere parameter :math:`\xi` of ``camera`` lies in ``low..high``."""

    camera: str
    low: float
    high: float

    kind: ClassVar[str] = "xi_between"
    table_keys: ClassVar[tuple[str, ...]] = ("camera", "low", "high")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> XiBetweenTask:
        low, high = _low_high(table, FRACTION)
        return cls(**common, camera=fields.text(table, "camera"), low=low, high=high)

    def params(self) -> dict[str, Param]:
        return {"low": self.low, "high": self.high}

    def validate(self, scene: Scene) -> None:
        camera_in(scene, self.camera)

    def missing(self, scene: Scene) -> str | None:
        return camera_gone(scene, self.camera)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        xi = camera_xi(ctx.scene.camera(self.camera))
        if params["low"] <= xi <= params["high"]:
            return TaskResult(True, f"Done: xi = {xi:.3f}.")
        return TaskResult(False, f"Not yet: xi = {xi:.3f}; it must be in {params['low']:g}..{params['high']:g}.")
