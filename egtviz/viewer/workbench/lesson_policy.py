"""What a lesson allows in a workbench tab: one policy object instead of three loose hooks.

A lesson view supplies a :class:`LessonPolicy` (its convention lens or estimation lab's panel filter, the refusal
of a typed value outside the step's ranges, what the step's panels show); the plain workbench uses
:data:`ALLOW_ALL`, which draws the model's geometry and allows every edit the scene model accepts. A gizmo's pose
has no hook here: the scene model's constraints decide where a dragged camera goes (:mod:`egtviz.scene.constraints`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

from ...controllers.workbench import FieldGuard
from ...lessons.display import PanelDisplay, thin_lines
from ...scene import Scene
from ...scene.derived import Derived
from ..render.panel_view import ViewBox
from ..render.panels import PanelView

__all__ = ["ALLOW_ALL", "LessonPolicy", "PanelFilter"]

#: ``panel_filter(scene, derived) -> (derived for the panels, point indices to ring)``.
PanelFilter = Callable[[Scene, Derived], tuple[Derived, frozenset[int]]]


@dataclass(frozen=True)
class LessonPolicy:
    """A lesson's say over a workbench tab; every hook left None allows what the scene model allows.

    Attributes:
        panel_filter: what the image-plane panels draw instead of the model's derived quantities (a lesson's
            convention lens or estimation lab). The 3D view and the read-out always show the model's.
        field_guard: asked before a camera field's new value is committed (the tab's controller asks it:
            :class:`~egtviz.controllers.workbench.WorkbenchController`); a refusal reverts the field with that message.
        display: the current step's :class:`~egtviz.lessons.display.PanelDisplay` (how many epipolar lines,
            which point numbers, which view per camera).
    """

    panel_filter: PanelFilter | None = None
    field_guard: FieldGuard | None = None
    #: ``display() -> PanelDisplay``: what the current step lets the panels show (lines, numbers, views).
    display: Callable[[], PanelDisplay] | None = None

    def panels(self, scene: Scene, derived: Derived) -> tuple[Derived, frozenset[int]]:
        """What the panels draw, and the points they ring (the model's geometry and none without a filter); the
        step's ``max_lines`` thins each panel's epipolar lines. The filter's rings are drawn without numbers unless
        the panel numbers every point."""
        drawn, ringed = (derived, frozenset()) if self.panel_filter is None else self.panel_filter(scene, derived)
        shown = self.shown()
        if shown.max_lines is not None:
            planes = {name: thin_lines(plane, shown.max_lines, scene.selected_point)
                      for name, plane in drawn.image_planes.items()}
            drawn = dataclasses.replace(drawn, image_planes=planes)
        return drawn, ringed

    def shown(self) -> PanelDisplay:
        """What the current step lets the panels show (everything without a lesson)."""
        return PanelDisplay() if self.display is None else self.display()

    def step_view(self, camera: str) -> tuple[int, PanelView] | None:
        """The view the current step gives ``camera``'s panel, keyed by the step's display (the panel applies it
        once per step), or None when the step leaves the panel's view alone."""
        shown = self.shown()
        view = shown.view_of(camera)
        if view is None:
            return None
        if view in ("fit", "image"):
            return id(shown), PanelView(view)
        u0, u1, v0, v1 = view
        return id(shown), PanelView("custom", ViewBox(u0, v0, u1 - u0, v1 - v0))

    def refusal(self, camera: str, fields: dict[str, object]) -> str | None:
        """Why ``camera`` may not take ``fields`` now, or None when it may."""
        return None if self.field_guard is None else self.field_guard(camera, fields)


#: The plain workbench's policy: the model's geometry in the panels, every edit the model accepts.
ALLOW_ALL = LessonPolicy()
