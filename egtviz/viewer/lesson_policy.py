"""What a lesson allows in a workbench tab: one policy object instead of three loose hooks.

A lesson view supplies a :class:`LessonPolicy` (its convention lens or estimation lab's panel filter, its narrower
field ranges, its gizmo pose ranges); the plain workbench uses :data:`ALLOW_ALL`, which draws the model's geometry
and allows every edit the scene model accepts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..scene import Scene

__all__ = ["ALLOW_ALL", "FieldGuard", "LessonPolicy", "PanelFilter", "PoseGuard"]

#: ``panel_filter(scene, derived) -> (derived for the panels, point indices to ring)``.
PanelFilter = Callable[[Scene, Any], tuple[Any, frozenset[int]]]
#: ``field_guard(camera, spec_fields) -> refusal message or None``.
FieldGuard = Callable[[str, dict[str, Any]], str | None]
#: ``pose_guard(camera, position, R_world) -> (position, R_world)``.
PoseGuard = Callable[[str, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class LessonPolicy:
    """A lesson's say over a workbench tab; every hook left None allows what the scene model allows.

    Attributes:
        panel_filter: what the image-plane panels draw instead of the model's derived quantities (a lesson's
            convention lens or estimation lab). The 3D view and the read-out always show the model's.
        field_guard: asked before a camera field's new value is committed; a refusal reverts the field with
            that message.
        pose_guard: turns the pose a gizmo sent into the pose to apply (one inside the lesson's ranges); the
            gizmo shows the applied pose when the drag ends.
    """

    panel_filter: PanelFilter | None = None
    field_guard: FieldGuard | None = None
    pose_guard: PoseGuard | None = None

    def panels(self, scene: Scene, derived: Any) -> tuple[Any, frozenset[int]]:
        """What the panels draw, and the points they ring (the model's geometry and none without a filter)."""
        if self.panel_filter is None:
            return derived, frozenset()
        return self.panel_filter(scene, derived)

    def refusal(self, camera: str, fields: dict[str, Any]) -> str | None:
        """Why ``camera`` may not take ``fields`` now, or None when it may."""
        return None if self.field_guard is None else self.field_guard(camera, fields)

    def pose(self, camera: str, position: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pose to apply when a gizmo sent ``(position, R)`` for ``camera``."""
        return (position, R) if self.pose_guard is None else self.pose_guard(camera, position, R)


#: The plain workbench's policy: the model's geometry in the panels, every edit the model accepts.
ALLOW_ALL = LessonPolicy()
