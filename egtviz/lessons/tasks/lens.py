"""Tasks read through the convention lens (the F the panels show, with the learner's mistake toggles):
:class:`PointOnLineTask`, whether a point's image lies on its epipolar line."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from ...scene import Scene
from .. import fields
from .base import Param, Task, TaskContext, TaskResult
from .common import POINT_INDEX, WITHIN_PX, in_pair, pair_gone, point_gone, point_in, point_label
from .needs import TaskNeeds

__all__ = ["PointOnLineTask"]


@dataclass(frozen=True, kw_only=True)
class PointOnLineTask(Task):
    """The image of point ``point`` lies within ``within_px`` of its epipolar line computed from the ``F`` the
    panels show (through the convention lens)."""

    point: int
    camera: str
    within_px: float

    kind: ClassVar[str] = "point_on_line"
    table_keys: ClassVar[tuple[str, ...]] = ("point", "camera", "within_px")

    @property
    def needs(self) -> TaskNeeds:
        return TaskNeeds(lens=True)

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> PointOnLineTask:
        return cls(**common, point=fields.whole(table, "point", POINT_INDEX), camera=fields.text(table, "camera"),
                   within_px=fields.number(table, "within_px", WITHIN_PX))

    def params(self) -> dict[str, Param]:
        return {"point": float(point_label(self.point)), "within_px": self.within_px}

    def validate(self, scene: Scene) -> None:
        point_in(scene, self.point)
        in_pair(scene, self.camera, pinhole_pair=True)

    def missing(self, scene: Scene) -> str | None:
        return point_gone(scene, self.point) or pair_gone(scene, self.camera, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        view = ctx.lens_view()
        d = (view.distances1_px if self.camera == view.names[0] else view.distances2_px)[self.point]
        if not math.isfinite(d):
            return TaskResult(False, f"Point {point_label(self.point)} has no image in both cameras.")
        msg = f"point {point_label(self.point)} is {d:.2f} px from its epipolar line in {self.camera}"
        if d <= params["within_px"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['within_px']:g} px allowed.")
