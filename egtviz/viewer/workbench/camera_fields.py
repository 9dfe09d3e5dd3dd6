"""A camera's GUI fields, built from its model's parameters (``ParameterSpec``: name, label, unit, range).

Each field shows one parameter, or a pair that reads as one quantity (the principal point, the image size, the
pixel size), in the units a person thinks in: a parameter listed in :data:`PRESENTATIONS` is shown that way (the
focal length in mm, the pixel size in µm), every other one as its ``ParameterSpec`` says, with its unit in the label.
A field's accepted range is the parameter's, converted to the field's unit: what the page offers is what the model
accepts. ``xi`` is a slider (it morphs the image live).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ...geometry.camera_model import ParameterSpec
from .fields import NumberRule

__all__ = ["PRESENTATIONS", "CameraField", "camera_fields", "field_of_spec"]


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
            label += " " + ", ".join(_AXES.get(p, p) for p in self.parameters)
        return f"{label} ({self.unit})" if self.unit else label

    def shown(self, values: dict[str, float]) -> tuple[float, ...]:
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

    def rules(self, specs: dict[str, ParameterSpec]) -> tuple[NumberRule, ...]:
        """What each number of the field accepts, in the field's unit: the parameters' ranges converted."""
        out = []
        for p in self.parameters:
            s = specs[p]
            lo, hi = (self.scale / s.max, self.scale / s.min) if self.reciprocal else (s.min * self.scale,
                                                                                        s.max * self.scale)
            name = self.label if len(self.parameters) == 1 else f"{self.label} {_AXES.get(p, p)}"
            out.append(NumberRule(name, self.unit, lo, hi, integer=s.integer))
        return tuple(out)


_AXES = {"ku": "x", "kv": "y", "u0": "u", "v0": "v", "width": "width", "height": "height"}

#: Parameters shown otherwise than as stored, or grouped: the first parameter of each group -> its field.
PRESENTATIONS: dict[str, CameraField] = {f.parameters[0]: f for f in (
    CameraField("focal", "focal length", "mm", ("focal_length",), scale=1e3),
    CameraField("pixel", "pixel size", "µm", ("ku", "kv"), scale=1e6, reciprocal=True, hint="x, y"),
    CameraField("pp", "principal point", "px", ("u0", "v0"), hint="u0, v0"),
    CameraField("size", "image size", "px", ("width", "height"), hint="width, height: whole pixels"),
    CameraField("focal_px", "focal length", "px", ("focal_pixels",)),
    CameraField("xi", "xi", "", ("xi",), slider=True,
                hint="The sphere model's xi: 0 is a pin-hole camera, 1 a parabolic mirror, between a hyperbolic one."),
)}


def camera_fields(parameters: tuple[ParameterSpec, ...]) -> tuple[CameraField, ...]:
    """The fields of a model with these parameters, in the parameters' order."""
    names = [p.name for p in parameters]
    out: list[CameraField] = []
    done: set[str] = set()
    for p in parameters:
        if p.name in done:
            continue
        field = PRESENTATIONS.get(p.name)
        if field is None or not set(field.parameters) <= set(names):
            field = CameraField(p.name, p.label, p.unit, (p.name,))
        out.append(field)
        done.update(field.parameters)
    return tuple(out)


#: The pose fields every camera spec has, as the GUI shows them.
_POSE = {"position": CameraField("position", "position", "m", ("position",)),
         "ypr_deg": CameraField("ypr", "angle", "deg", ("ypr_deg",))}


def field_of_spec(spec: Any, field: str) -> CameraField:
    """How the GUI shows a camera spec's field ``field`` (e.g. ``focal_length``: focal length in mm), so a message
    about a stored value can use the words and unit of the field the user types in.

    Args:
        spec: a camera spec (its ``PARAMETER_FIELDS`` maps the model's parameters to its fields).
        field: a field of the spec, e.g. ``"focal_length"``, ``"pixels_per_metre"``, ``"width"``.

    Returns:
        The field's presentation; its :meth:`CameraField.shown_number` converts a stored number. A spec field
        that holds one parameter of a grouped field (``width`` of the image size) is named with its axis; a field
        no GUI field shows keeps its own name and no unit.
    """
    if field in _POSE:
        return _POSE[field]
    stored = tuple(p for p, (f, _) in getattr(spec, "PARAMETER_FIELDS", {}).items() if f == field)
    for shown in camera_fields(spec.model.parameters):
        if stored and set(stored) <= set(shown.parameters):
            if len(stored) == 1 and len(shown.parameters) > 1:
                return CameraField(shown.key, f"{shown.label} {_AXES.get(stored[0], stored[0])}", shown.unit, stored,
                                   scale=shown.scale, reciprocal=shown.reciprocal)
            return shown
    return CameraField(field, field.replace("_", " "), "", (field,))
