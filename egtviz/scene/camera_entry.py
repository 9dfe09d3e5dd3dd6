"""What one camera model is above the numeric core: its scene spec, its GUI fields and its 3D drawing, in one entry.

A model's entry (:class:`CameraEntry`) is declared in its model file, ``egtviz/scene/cameras/<module>.py``, next to
its spec class; the registry (:mod:`egtviz.scene.cameras`) collects the entries of every model of the core's
registry ``CAMERA_MODELS``. Nothing here imports the viewer: a drawing is named (``"module:Class"``, imported by the
viewer on first use) or described as a mesh in the model frame (:class:`MeshBody`, drawn by the viewer's generic
mesh drawing).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..geometry.camera_model import CAMERA_MODELS, CameraModelInfo, ParameterSpec

__all__ = ["AXES", "COMMON_FIELDS", "FOCAL_PIXELS_FIELD", "FOCAL_PIXELS_TERMS", "CameraEntry", "CameraField", "FieldRange",
           "MeshBody"]


@dataclass(frozen=True)
class FieldRange:
    """What one number of a GUI field accepts, in the field's unit (a parameter's range converted)."""

    label: str
    unit: str
    lo: float
    hi: float
    integer: bool = False


@dataclass(frozen=True)
class CameraField:
    """One GUI field of a camera: which model parameters it shows, and how."""

    key: str
    """The field's key (stable: tests and the app find the field by it)."""
    label: str
    """The quantity, without its unit."""
    unit: str
    """The unit shown (in the label)."""
    parameters: tuple[str, ...]
    """The model parameters shown, in order (one number each)."""
    scale: float = 1.0
    """Shown value = ``scale * value`` (or ``scale / value`` when ``reciprocal``)."""
    reciprocal: bool = False
    hint: str = ""
    slider: bool = False
    """A slider over the parameter's range (a single parameter)."""

    @property
    def title(self) -> str:
        """The label with its components and unit, e.g. ``"focal length (mm)"``, ``"principal point u, v (px)"``."""
        label = self.label
        if len(self.parameters) > 1:
            label += " " + ", ".join(AXES.get(p, p) for p in self.parameters)
        return f"{label} ({self.unit})" if self.unit else label

    def shown(self, values: Mapping[str, float]) -> tuple[float, ...]:
        """The field's numbers from the model's parameter values."""
        return tuple(self.scale / values[p] if self.reciprocal else values[p] * self.scale for p in self.parameters)

    def parameters_of(self, shown: tuple[float, ...]) -> dict[str, float]:
        """The model's parameter values from the field's numbers."""
        return {p: self.scale / x if self.reciprocal else x / self.scale for p, x in zip(self.parameters, shown)}

    def shown_number(self, value: float) -> float:
        """One stored number in the field's unit (``scale * value``, or ``scale / value`` when ``reciprocal``)."""
        if self.reciprocal:
            return math.inf if value == 0 else self.scale / value
        return value * self.scale

    def ranges(self, specs: Mapping[str, ParameterSpec]) -> tuple[FieldRange, ...]:
        """What each number of the field accepts, in the field's unit: the parameters' ranges converted."""
        out = []
        for p in self.parameters:
            s = specs[p]
            lo, hi = (self.scale / s.max, self.scale / s.min) if self.reciprocal else (s.min * self.scale,
                                                                                        s.max * self.scale)
            name = self.label if len(self.parameters) == 1 else f"{self.label} {AXES.get(p, p)}"
            out.append(FieldRange(name, self.unit, lo, hi, integer=s.integer))
        return tuple(out)


#: How a grouped field names its components.
AXES = {"ku": "x", "kv": "y", "u0": "u", "v0": "v", "width": "width", "height": "height"}

#: The fields every model with a principal point and an image size shows alike.
COMMON_FIELDS: tuple[CameraField, ...] = (
    CameraField("pp", "principal point", "px", ("u0", "v0"), hint="u0, v0"),
    CameraField("size", "image size", "px", ("width", "height"), hint="width, height: whole pixels"),
)

#: A focal length in pixels (``focal_pixels``), as the models that have one show it.
FOCAL_PIXELS_FIELD = CameraField("focal_px", "focal length", "px", ("focal_pixels",))
#: ... and how a refusal of it is restated.
FOCAL_PIXELS_TERMS: Mapping[str, tuple[str, str, float]] = {"focal_pixels": ("focal length", "px", 1.0)}


@dataclass(frozen=True, eq=False)
class MeshBody:
    """A camera's 3D body as one translucent mesh in the model frame (moved by the camera's gizmo).

    ``mesh(parameters)`` gives the vertices (V, 3) and triangles (T, 3) from the model's parameter values; the
    viewer draws it in the camera's colour and sends it again only when those values change.
    """

    mesh: Callable[[Mapping[str, float]], tuple[np.ndarray, np.ndarray]]
    name: str = "body"
    """The node's name under the camera (``lens``)."""
    opacity: float = 0.35


@dataclass(frozen=True, eq=False)
class CameraEntry:
    """One camera model above the core: which spec stores it, how the GUI shows it and how the 3D view draws it.

    The model's parameters and their limits are the core's (:attr:`info`, the registry entry of :attr:`model`).
    """

    model: str
    """The core registry's kind (``egtviz.geometry.CAMERA_MODELS``)."""
    spec: type
    """The spec class that stores a camera of this model (a frozen dataclass of :mod:`egtviz.scene.specs`)."""
    short_label: str
    """A few words naming the model in the GUI (a camera's folder: ``cam1 (pin-hole)``)."""
    drawing: str | MeshBody
    """The 3D body: ``"module:Class"`` of a viewer drawing, or a mesh for the viewer's generic drawing."""
    selection: Mapping[str, Any] = field(default_factory=dict)
    """The spec's field values that select this model (``{"mirror": "parabolic"}``; empty for a spec of one
    model)."""
    fields: tuple[CameraField, ...] = ()
    """How the GUI shows some parameters (a unit, a group, a slider); every other one as its ``ParameterSpec``
    says, the principal point and the image size as :data:`COMMON_FIELDS`."""
    terms: Mapping[str, tuple[str, str, float]] = field(default_factory=dict)
    """A limit across the spec's fields (as ``OutOfRangeError`` names it) in the GUI's words: label, unit and the
    scale to the field's unit."""

    @property
    def info(self) -> CameraModelInfo:
        """The core registry's entry: the model's label, class and parameters with their ranges."""
        return CAMERA_MODELS[self.model]

    @property
    def parameters(self) -> tuple[ParameterSpec, ...]:
        """The model's parameters with their ranges (the core's ``PARAMETERS``)."""
        return self.info.parameters

    def camera_fields(self) -> tuple[CameraField, ...]:
        """The model's GUI fields, in its parameters' order: one per parameter or group of parameters."""
        names = [p.name for p in self.parameters]
        shown = {f.parameters[0]: f for f in (*COMMON_FIELDS, *self.fields)}
        out: list[CameraField] = []
        done: set[str] = set()
        for p in self.parameters:
            if p.name in done:
                continue
            presentation = shown.get(p.name)
            if presentation is None or not set(presentation.parameters) <= set(names):
                presentation = CameraField(p.name, p.label, p.unit, (p.name,))
            out.append(presentation)
            done.update(presentation.parameters)
        return tuple(out)
