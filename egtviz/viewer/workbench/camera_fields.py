"""A camera's GUI fields, from its model's entry (``egtviz.scene.cameras``) and its parameters (``ParameterSpec``).

Each field shows one parameter, or a pair that reads as one quantity (the principal point, the image size, the
pixel size), in the units a person thinks in: a parameter the model's entry presents (the focal length in mm, the
pixel size in µm, ``xi`` as a slider) is shown that way, every other one as its ``ParameterSpec`` says, with its unit
in the label. A field's accepted range is the parameter's, converted to the field's unit: what the page offers is
what the model accepts.
"""

from __future__ import annotations

from ...scene import CameraSpec
from ...scene.camera_entry import AXES, CameraField
from ...scene.cameras import camera_entry
from .fields import NumberRule

__all__ = ["CameraField", "camera_fields", "field_of_spec", "field_rules"]


def camera_fields(model_kind: str) -> tuple[CameraField, ...]:
    """The fields of the registered model ``model_kind``, in its parameters' order."""
    return camera_entry(model_kind).camera_fields()


def field_rules(field: CameraField, model_kind: str) -> tuple[NumberRule, ...]:
    """What each number of ``field`` of a ``model_kind`` camera accepts, in the field's unit."""
    specs = {p.name: p for p in camera_entry(model_kind).parameters}
    return tuple(NumberRule(r.label, r.unit, r.lo, r.hi, integer=r.integer) for r in field.ranges(specs))


#: The pose views every camera spec has, as the GUI shows them.
_POSE = {"position": CameraField("position", "position", "m", ("position",)),
         "ypr_deg": CameraField("ypr", "angle", "deg", ("ypr_deg",))}


def field_of_spec(spec: CameraSpec, field: str) -> CameraField:
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
    for shown in camera_fields(spec.model_kind):
        if stored and set(stored) <= set(shown.parameters):
            if len(stored) == 1 and len(shown.parameters) > 1:
                return CameraField(shown.key, f"{shown.label} {AXES.get(stored[0], stored[0])}", shown.unit, stored,
                                   scale=shown.scale, reciprocal=shown.reciprocal)
            return shown
    return CameraField(field, field.replace("_", " "), "", (field,))
