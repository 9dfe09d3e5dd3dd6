"""Scene tasks about what a camera's image shows: where an epipole is (:class:`EpipoleNearTask`), whether the
epipolar lines are parallel (:class:`LinesParallelTask`) and whether a point is inside the image
(:class:`PointInImageTask`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, cast

import numpy as np

from ...geometry.epipolar import epipolar_planes, lines_of_planes
from ...geometry.pinhole import PinholeCamera
from ...scene import Scene
from ...scene.limits import PRINCIPAL_POINT
from .. import fields
from ..errors import EntryError
from .base import Param, Task, TaskContext, TaskResult, read_param
from .common import (
    POINT_INDEX,
    WITHIN_DEG,
    WITHIN_PX,
    camera_gone,
    camera_in,
    in_pair,
    pair_gone,
    point_gone,
    point_in,
    point_label,
)

__all__ = ["EpipoleNearTask", "LinesParallelTask", "PointInImageTask", "direction_spread_deg"]


@dataclass(frozen=True, kw_only=True)
class EpipoleNearTask(Task):
    """The epipole of ``camera`` (in the drawn pair) lies within ``within_px`` of ``(u, v)``."""

    camera: str
    u: Param
    v: Param
    within_px: float

    kind: ClassVar[str] = "epipole_near"
    table_keys: ClassVar[tuple[str, ...]] = ("camera", "target", "within_px")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> EpipoleNearTask:
        target = table.get("target")
        if not isinstance(target, dict) or set(target) != {"u", "v"}:
            raise EntryError(
                "target", f"expected {{ u = ..., v = ... }} (numbers or [low, high]), got {fields.short(target)}"
            )
        return cls(**common, camera=fields.text(table, "camera"),
                   u=read_param(target["u"], "target", PRINCIPAL_POINT),
                   v=read_param(target["v"], "target", PRINCIPAL_POINT),
                   within_px=fields.number(table, "within_px", WITHIN_PX))

    def params(self) -> dict[str, Param]:
        return {"u": self.u, "v": self.v, "within_px": self.within_px}

    def validate(self, scene: Scene) -> None:
        in_pair(scene, self.camera)

    def missing(self, scene: Scene) -> str | None:
        return camera_gone(scene, self.camera)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        u, v, within = params["u"], params["v"], params["within_px"]
        plane = ctx.drawn().image_planes.get(self.camera)
        if plane is None or not plane.in_pair:
            return TaskResult(False, f"Camera {self.camera!r} is not in the drawn pair.")
        finite = [(e, e.xy) for e in plane.epipoles if e.xy is not None]
        if not finite:
            return TaskResult(
                False, f"The epipole of {self.camera} is at infinity: turn the camera towards the other one."
            )
        best, xy = min(finite, key=lambda exy: math.hypot(exy[1][0] - u, exy[1][1] - v))
        d = math.hypot(xy[0] - u, xy[1] - v)
        where = f"{best.label} is at ({xy[0]:.1f}, {xy[1]:.1f}), {d:.1f} px from ({u:g}, {v:g})"
        if d <= within:
            return TaskResult(True, f"Done: {where}.")
        return TaskResult(False, f"Not yet: {where}; it must be within {within:g} px.")


def direction_spread_deg(lines: np.ndarray) -> float:
    """The smallest angle (degrees) that contains the directions of all ``lines`` (N, 3), as undirected lines.

    Each line's direction angle is doubled (so opposite directions coincide) and the spread is half the
    smallest arc of the circle holding them all: ``(2 pi - largest gap) / 2``.
    """
    phi = np.sort(np.mod(2.0 * np.arctan2(lines[:, 0], -lines[:, 1]), 2.0 * np.pi))
    if len(phi) < 2:
        return 0.0
    gaps = np.diff(np.concatenate([phi, [phi[0] + 2.0 * np.pi]]))
    return math.degrees((2.0 * np.pi - float(gaps.max())) / 2.0)


@dataclass(frozen=True, kw_only=True)
class LinesParallelTask(Task):
    """The epipolar lines in ``camera``'s image are parallel within ``within_deg`` (its epipole at infinity)."""

    camera: str
    within_deg: float

    kind: ClassVar[str] = "lines_parallel"
    table_keys: ClassVar[tuple[str, ...]] = ("camera", "within_deg")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> LinesParallelTask:
        return cls(**common, camera=fields.text(table, "camera"),
                   within_deg=fields.number(table, "within_deg", WITHIN_DEG))

    def params(self) -> dict[str, Param]:
        return {"within_deg": self.within_deg}

    def validate(self, scene: Scene) -> None:
        in_pair(scene, self.camera, pinhole_pair=True)
        if len(scene.points) < 2:
            raise EntryError(None, "lines_parallel needs at least two points in the scene")

    def missing(self, scene: Scene) -> str | None:
        return pair_gone(scene, self.camera, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        scene = ctx.scene
        n1, n2 = scene.drawn_pair  # type: ignore[misc]
        c1, c2 = scene.camera(n1).camera(), scene.camera(n2).camera()
        planes = epipolar_planes(c1.centre, c2.centre, scene.points_array())
        normals = planes[~np.isnan(planes).any(axis=1), :3]  # points on the baseline have no plane
        if len(normals) < 2:
            return TaskResult(False, "Fewer than two points off the baseline: no lines to compare.")
        # missing() stops the task unless the drawn pair is two pin-hole cameras.
        lines = lines_of_planes(cast(PinholeCamera, scene.camera(self.camera).camera()), normals)
        spread = direction_spread_deg(lines)
        msg = f"the epipolar lines of {self.camera} spread over {spread:.2f} degrees"
        if spread <= params["within_deg"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['within_deg']:g} allowed.")


@dataclass(frozen=True, kw_only=True)
class PointInImageTask(Task):
    """Point ``point`` is seen inside ``camera``'s image."""

    point: int
    camera: str

    kind: ClassVar[str] = "point_in_image"
    table_keys: ClassVar[tuple[str, ...]] = ("point", "camera")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> PointInImageTask:
        return cls(**common, point=fields.whole(table, "point", POINT_INDEX), camera=fields.text(table, "camera"))

    def params(self) -> dict[str, Param]:
        return {"point": float(point_label(self.point))}

    def validate(self, scene: Scene) -> None:
        point_in(scene, self.point)
        camera_in(scene, self.camera)

    def missing(self, scene: Scene) -> str | None:
        return camera_gone(scene, self.camera) or point_gone(scene, self.point)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        plane = ctx.drawn().image_planes[self.camera]
        i, label = self.point, point_label(self.point)
        if plane.in_image[i]:
            u, v = plane.points[i]
            return TaskResult(True, f"Done: point {label} is at ({u:.4g}, {v:.4g}) in {self.camera}'s image.")
        if not plane.visible[i]:
            return TaskResult(False, f"Not yet: point {label} has no image in {self.camera} (behind it, or blind).")
        u, v = plane.points[i]
        return TaskResult(False, f"Not yet: point {label} projects to ({u:.4g}, {v:.4g}), outside the "
                                 f"{plane.width} x {plane.height} image.")
