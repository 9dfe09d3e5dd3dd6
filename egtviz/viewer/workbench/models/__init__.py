"""How each camera model is drawn in the 3D view: the drawing its entry names (``egtviz.scene.cameras``).

A drawing owns the nodes of one camera's body (a frustum, a mirror over its CCD, a sphere, a lens) under the camera's
gizmo node ``root`` (so they move with the gizmo, in the model frame) and any world-level nodes it needs. It draws
only what the core model and the scene layer computed (``egtviz.scene.Derived``): the geometry comes from the
camera model's public methods, never from a formula here.

There is no registry here: each model's entry (``egtviz.scene.cameras.CAMERA_ENTRIES``) names its drawing, a
``"module:Class"`` of this package (a body with its own behaviour: the pin-hole's image plane, the mirror, the
sphere) or a :class:`~egtviz.scene.camera_entry.MeshBody` that :class:`MeshDrawing` draws (a model file of the scene
layer then needs nothing here). ``scene3d.Scene3D`` looks a camera's drawing up by its model's ``kind``
(:func:`drawing_class`); no kind is tested anywhere else. How to add a model: ``docs/camera_models.md``.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

from ....scene.camera_entry import MeshBody
from ....scene.cameras import CAMERA_ENTRIES

if TYPE_CHECKING:
    import viser

    from ....geometry.camera_model import CameraModel
    from ....scene.derived import ImagePlane

__all__ = ["DRAWINGS", "SHORT_LABELS", "CameraDrawing", "DrawContext", "MeshDrawing", "drawing_class"]


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

    def __init__(self, api: viser.SceneApi, root: str, k: int, colour: tuple[int, int, int]) -> None:
        self.api = api
        self.root = root
        self.k = k
        self.colour = colour

    @property
    def body(self) -> viser.SceneNodeHandle:
        """The node that takes the camera's colour (orange when a lesson highlights it)."""
        raise NotImplementedError

    def named_nodes(self) -> dict[str, viser.SceneNodeHandle]:
        """The nodes made when the drawing was built, by name (``frustum``, ``ccd``, ``sphere``, ...)."""
        return {}

    def update(self, camera: ModelT, plane: ImagePlane, ctx: DrawContext) -> None:
        """Bring the nodes up to date with ``camera`` (its core model) and ``plane`` (its ``ImagePlane``)."""
        raise NotImplementedError

    def remove(self) -> None:
        """Remove the world-level nodes (the children of ``root`` go with the gizmo)."""


class MeshDrawing(CameraDrawing["CameraModel"]):
    """A body given by its model's entry as a translucent mesh in the model frame (:class:`MeshBody`): built at
    the model's default parameters, sent again only when the camera's parameters give another mesh."""

    def __init__(self, api: viser.SceneApi, root: str, k: int, colour: tuple[int, int, int], *, kind: str,
                 body: MeshBody) -> None:
        super().__init__(api, root, k, colour)
        self._body = body
        values = {p.name: p.default for p in CAMERA_ENTRIES[kind].parameters}
        self.mesh = self._add_mesh(values, colour, None)
        self._key = tuple(values.items())

    def _add_mesh(self, values: Mapping[str, float], colour: tuple[int, int, int],
                  old: viser.MeshHandle | None) -> viser.MeshHandle:
        """The mesh of these parameter values, in place of ``old`` (removed only once the new mesh is made)."""
        vertices, faces = self._body.mesh(values)
        if old is not None:
            old.remove()
        return self.api.add_mesh_simple(f"{self.root}/{self._body.name}", vertices, faces, color=colour,
                                        opacity=self._body.opacity, side="double", cast_shadow=False,
                                        receive_shadow=False)

    def _draw(self, values: Mapping[str, float], colour: tuple[int, int, int]) -> None:
        key = tuple(values.items())
        if key == self._key:
            return
        self.mesh = self._add_mesh(values, colour, self.mesh)
        self._key = key

    def named_nodes(self) -> dict[str, viser.SceneNodeHandle]:
        return {self._body.name: self.mesh}

    @property
    def body(self) -> viser.MeshHandle:
        return self.mesh

    def update(self, camera: CameraModel, plane: ImagePlane, ctx: DrawContext) -> None:
        """The mesh of the camera's parameters (a new one keeps the colour the old one had: a highlight)."""
        self._draw(camera.parameters(), self.mesh.color)


DRAWINGS: dict[str, str | MeshBody] = {kind: entry.drawing for kind, entry in CAMERA_ENTRIES.items()}
"""The drawing of each registered camera model kind (``"module:Class"`` or a mesh body), from its entry."""
SHORT_LABELS: dict[str, str] = {kind: entry.short_label for kind, entry in CAMERA_ENTRIES.items()}
"""A few words naming each model in the GUI (a camera's folder: ``cam1 (pin-hole)``), from its entry."""


def drawing_class(kind: str) -> Callable[[viser.SceneApi, str, int, tuple[int, int, int]], CameraDrawing]:
    """What builds the drawing of the camera model ``kind``: ``factory(api, root, k, colour)``.

    Raises:
        KeyError: naming the kind, when no drawing is registered for it.
    """
    target = DRAWINGS.get(kind)
    if target is None:
        raise KeyError(f"kind: no drawing registered for camera model {kind!r} (have {sorted(DRAWINGS)})")
    if isinstance(target, MeshBody):
        return functools.partial(MeshDrawing, kind=kind, body=target)
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)
