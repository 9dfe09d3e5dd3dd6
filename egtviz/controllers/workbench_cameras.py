"""A camera's fields in the workbench: which there are, what each accepts in its unit, and what a typed value means.

Each field shows one parameter, or a pair that reads as one quantity (the principal point, the image size, the
pixel size), in the units a person thinks in: a parameter the model's entry presents (the focal length in mm, the
pixel size in µm, ``xi`` as a slider) is shown that way, every other one as its ``ParameterSpec`` says, with its unit
in the label. A field's accepted range is the parameter's, converted to the field's unit: what the page offers is
what the model accepts. Every camera also has its pose fields (``position`` in m, ``ypr`` in degrees), whose ranges
are the scene's limits (:mod:`egtviz.scene.limits`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

from ..scene import CameraSpec, limits
from ..scene.camera_entry import AXES, CameraField
from ..scene.cameras import camera_entry
from ..scene.specs import OutOfRangeError
from .workbench_fields import FieldError, NumberRule

__all__ = ["FIELD_RULES", "CameraField", "camera_fields", "field_of_spec", "field_rules", "model_field_rules",
           "model_fields", "restated", "spec_fields", "spec_values"]


def camera_fields(model_kind: str) -> tuple[CameraField, ...]:
    """The fields of the registered model ``model_kind``, in its parameters' order."""
    return camera_entry(model_kind).camera_fields()


def model_field_rules(field: CameraField, model_kind: str) -> tuple[NumberRule, ...]:
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


def _rules(label: str, unit: str, rng: limits.Range, *, scale: float = 1.0,
           axes: Sequence[str] = ("",)) -> tuple[NumberRule, ...]:
    """One field rule per axis from a :mod:`egtviz.scene.limits` range, converted to the field's unit by ``scale``."""
    return tuple(NumberRule(f"{label} {a}".strip(), unit, rng.low * scale, rng.high * scale, integer=rng.integer)
                 for a in axes)


#: What each camera field accepts, in the units the field shows (the scene's limits, converted).
FIELD_RULES: dict[str, tuple[NumberRule, ...]] = {
    "position": _rules("position", "m", limits.COORDINATE, axes="xyz"),
    "ypr": _rules("angle", "deg", limits.ANGLE_DEG, axes=("yaw", "pitch", "roll")),
}
"""The pose fields every camera has; a model's own fields take their rules from its parameters
(:func:`model_field_rules`)."""


def restated(exc: OutOfRangeError, name: str, model_kind: str) -> FieldError:
    """The model's range refusal restated for the user: the camera, the field's words and units (as the model's
    entry words them)."""
    terms = camera_entry(model_kind).terms
    label, unit, scale = terms.get(exc.field, (exc.field.replace("_", " "), exc.limit.unit, 1.0))
    rule = NumberRule(label, unit, exc.limit.low * scale, exc.limit.high * scale, integer=exc.limit.integer)
    try:
        rule.check(float(exc.value) * scale, owner=name)
    except FieldError as refusal:
        return refusal
    except (TypeError, ValueError):  # a value that is no number: keep the model's own words
        pass
    return FieldError(f"{name}: {exc}")


@lru_cache(maxsize=16)
def model_fields(model_kind: str) -> dict[str, CameraField]:
    """A model's GUI fields by key (from its entry)."""
    return {f.key: f for f in camera_fields(model_kind)}


def spec_values(spec: CameraSpec) -> dict[str, tuple[float, ...]]:
    """A camera spec's values as its fields show them (model parameters -> the fields' units)."""
    values: dict[str, tuple[float, ...]] = {"position": tuple(spec.position), "ypr": tuple(spec.ypr_deg)}
    params = spec.model_values()
    for key, field in model_fields(spec.model_kind).items():
        values[key] = field.shown(params)
    return values


def field_rules(spec: CameraSpec, key: str) -> tuple[NumberRule, ...]:
    """What field ``key`` of this camera accepts (its parameters' ranges in the field's units)."""
    if key in FIELD_RULES:
        return FIELD_RULES[key]
    fields = model_fields(spec.model_kind)
    if key not in fields:
        raise FieldError(f"{spec.name}: no field {key!r} on a {spec.model.label.lower()}")
    return model_field_rules(fields[key], spec.model_kind)


def spec_fields(spec: CameraSpec, key: str, v: tuple[float, ...]) -> dict[str, object]:
    """Parsed field values as spec fields (the fields' units -> model parameters -> spec fields)."""
    if key == "position":
        return {"position": v}
    if key == "ypr":
        return {"ypr_deg": v}
    field = model_fields(spec.model_kind).get(key)
    if field is None:
        raise FieldError(f"unknown field {key!r}")
    return spec.fields_for_parameters(**field.parameters_of(v))
