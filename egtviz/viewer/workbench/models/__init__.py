"""How each camera model is drawn in the 3D view: one drawing module per model, named by the model's spec class.

A drawing owns the nodes of one camera's body (a frustum, a mirror over its CCD, a sphere, a lens) under the camera's
gizmo node ``root`` (so they move with the gizmo, in the model frame) and any world-level nodes it needs. It draws
only what the core model and the scene layer computed (``egtviz.scene.Derived``): the geometry comes from the
camera model's public methods, never from a formula here.

There is no registry here: each spec class of ``egtviz.scene.specs`` (the scene's one entry per camera spec) names
the drawing and short label of every model it builds (``DRAWINGS``), and :data:`DRAWINGS` and :data:`SHORT_LABELS`
are read from them. ``scene3d.Scene3D`` looks a camera's drawing up by its model's ``kind`` (:func:`drawing_class`);
no kind is tested anywhere else. How to add a model: ``docs/camera_models.md``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np

from ....geometry.camera_model import CAMERA_MODELS
from ....scene.specs import SPEC_CLASSES

if TYPE_CHECKING:
    from ....geometry.camera_model import CameraModel
    from ....scene.derived import ImagePlane

__all__ = ["DRAWINGS", "SHORT_LABELS", "CameraDrawing", "DrawContext", "drawing_class"]


@dataclass(frozen=True, eq=False)
class DrawContext:
    """What a drawing may need beyond its camera and its panel's content."""

    points: np.ndarray
    """(N, 3) the scene's points."""
    line_rows: tuple[int, ...] | None
    """The points whose lines (rays, epipolar lines) are drawn; None: all."""
    selected_point: int | None
    selected_normal: np.ndarray | None
    """(3,) unit world normal of the selected point's epipolar plane in the drawn pair, or None."""
    in_pair: bool
    """The camera is one of the drawn pair."""


#: The camera model a drawing draws (each drawing module draws the models of one core class).
ModelT = TypeVar("ModelT", bound="CameraModel")


class CameraDrawing(Generic[ModelT]):
    """The 3D body of one camera (base class: nothing but the interface).

    Args:
        api: the client's ``viser.SceneApi``.
        root: the scene path of the camera's gizmo (children move with it, in the model frame).
        k: the camera's number (for world-level node names).
        colour: the camera's colour (RGB).
    """

    def __init__(self, api: Any, root: str, k: int, colour: tuple[int, int, int]) -> None:
        self.api = api
        self.root = root
        self.k = k
        self.colour = colour

    @property
    def body(self) -> Any:
        """The node that takes the camera's colour (orange when a lesson highlights it)."""
        raise NotImplementedError

    def named_nodes(self) -> dict[str, Any]:
        """The nodes made when the drawing was built, by name (``frustum``, ``ccd``, ``sphere``, ...)."""
        return {}

    def update(self, camera: ModelT, plane: ImagePlane, ctx: DrawContext) -> None:
        """Bring the nodes up to date with ``camera`` (its core model) and ``plane`` (its ``ImagePlane``)."""
        raise NotImplementedError

    def remove(self) -> None:
        """Remove the world-level nodes (the children of ``root`` go with the gizmo)."""


def _drawings() -> tuple[dict[str, str], dict[str, str]]:
    """The drawing and short label of each registered model, in the registry's order, from the scene's spec classes
    (each names the drawings of the models it builds)."""
    found = {kind: entry for cls in SPEC_CLASSES for kind, entry in cls.DRAWINGS.items()}
    order = [kind for kind in CAMERA_MODELS if kind in found]
    return {k: found[k][0] for k in order}, {k: found[k][1] for k in order}


DRAWINGS, SHORT_LABELS = _drawings()
"""``"module:Class"`` of the drawing of each registered camera model kind, and a few words naming each model in the
GUI (a camera's folder: ``cam1 (pin-hole)``); both read from the spec classes (``egtviz.scene.specs``)."""


def drawing_class(kind: str) -> type[CameraDrawing]:
    """The drawing class of the camera model ``kind``.

    Raises:
        KeyError: naming the kind, when no drawing is registered for it.
    """
    target = DRAWINGS.get(kind)
    if target is None:
        raise KeyError(f"kind: no drawing registered for camera model {kind!r} (have {sorted(DRAWINGS)})")
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)
