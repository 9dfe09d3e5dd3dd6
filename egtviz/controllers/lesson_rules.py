"""What a lesson step holds the scene to, headless: its ``set_range`` limits as the scene's constraints, and the
refusals of a check while the scene breaks its ranges or its locks.

The rule of a range is the scene's (:class:`~egtviz.scene.constraints.CameraRanges`): the model holds it for
every edit, a typed field asks it first, and a check asks it of the whole scene (:func:`range_refusal`: a
script may still move a camera out of a range). A breach is worded as the GUI field the learner types in: its
label and its unit (:func:`range_words`; the focal length in mm, the pixel size in µm).

A lock is the scene model's (it refuses every edit of a locked pose); a check also fails, with *reset step* as
the way back, when a camera locked at the step's start (the model's undo barrier) has gone or moved because the
scene was replaced (:func:`lock_refusal`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..lessons import LessonRun
from ..lessons.changes import RANGED_FIELDS
from ..lessons.tasks import RESET_ADVICE
from ..scene.constraints import CameraRanges
from .workbench_cameras import field_of_spec
from .workbench_fields import NumberRule, format_number

__all__ = ["RANGE_ADVICE", "RangeLimit", "RangeTerms", "lesson_constraints", "lock_refusal", "pose_within_ranges",
           "range_limit", "range_refusal", "range_terms", "range_words"]

#: What a check refused for a breached range says after the breach.
RANGE_ADVICE = "; bring it back into that range and check again."


@dataclass(frozen=True)
class RangeTerms:
    """A ranged spec field in the words and unit of its GUI field."""

    label: str
    rule: NumberRule
    """The rule of the range as shown, ``lo`` to ``hi``."""
    convert: Callable[[float], float]
    """Stored value -> shown value."""
    lo: float
    hi: float


@dataclass(frozen=True)
class RangeLimit:
    """A ``set_range`` limit in force, as the lesson panel lists it."""

    camera: str
    label: str
    """The field's label, e.g. ``focal length``."""
    shown: str
    """The range in the field's unit, e.g. ``4 to 12 mm``."""


def range_terms(run: LessonRun, camera: str, field: str) -> RangeTerms:
    """A ranged spec field in the words and unit of its GUI field, and its range as shown."""
    scene = run.model.scene
    limit = run.ranges[(camera, field)]
    convert: Callable[[float], float]
    if camera in scene.camera_names:
        shown = field_of_spec(scene.camera(camera), field)
        label, unit, convert = shown.label, shown.unit, shown.shown_number
    else:
        label, unit, convert = field.replace("_", " "), "", float
    unit = unit or (RANGED_FIELDS[field].unit if field in RANGED_FIELDS else "")
    lo, hi = sorted((convert(limit.low), convert(limit.high)))  # a reciprocal (pixel size) swaps the bounds
    return RangeTerms(label, NumberRule(label, unit, lo, hi), convert, lo, hi)


def range_limit(run: LessonRun, camera: str, field: str) -> RangeLimit:
    """The step's range of ``camera``'s ``field`` as the panel lists it, in the GUI field's words and unit."""
    terms = range_terms(run, camera, field)
    return RangeLimit(camera, terms.label, f"{format_number(terms.lo)} to {terms.rule.with_units(terms.hi)}")


def range_words(run: LessonRun, camera: str, fields: dict[str, object]) -> str:
    """A breach of the step's ``set_range`` limit of ``camera``'s field (``fields``: that field and its value) in
    the GUI field's words and unit (the focal length in mm, the pixel size in µm), as the learner types it."""
    ((field, value),) = fields.items()
    terms = range_terms(run, camera, field)
    rule = terms.rule
    values = value if isinstance(value, tuple) else (value,)
    shown = ", ".join(rule.with_units(terms.convert(float(v))) for v in values if isinstance(v, (int, float)))
    return (f"In this step {camera}'s {terms.label} must stay between {rule.with_units(terms.lo)} and "
            f"{rule.with_units(terms.hi)} (it is {shown})")


def lesson_constraints(run: Callable[[], LessonRun]) -> CameraRanges:
    """The step's ``set_range`` limits as the scene's constraints, worded as the GUI fields (``run()``: the run
    whose current step holds them, read afresh at every question)."""
    return CameraRanges(lambda: run().ranges, lambda camera, fields: range_words(run(), camera, fields))


def range_refusal(run: LessonRun) -> str | None:
    """Why the scene breaks the step's ``set_range`` limits (a camera field outside its range), with the way back,
    or None."""
    refusal = lesson_constraints(lambda: run).scene_refusal(run.model.scene)
    return None if refusal is None else refusal + RANGE_ADVICE


def pose_within_ranges(run: LessonRun, camera: str, position: np.ndarray,
                       R_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pose the scene's constraints give ``camera`` when a gizmo sends ``(position, R_world)`` under the
    step's ``set_range`` limits: what the model applies to that drag (:meth:`CameraRanges.judge`), as a pose.

    Returns:
        ``(position, R_world)``: the centre clamped into a ``position`` range (the nearest point of the box); the
        sent rotation itself, or the camera's current one when the sent one leaves a ``ypr_deg`` range.
    """
    spec = run.model.scene.camera(camera)
    sent = spec.with_world_pose(tuple(np.asarray(position, float).tolist()), R_world)
    allowed = lesson_constraints(lambda: run).judge(spec, sent, drag=True)
    kept = np.array_equal(allowed.pose.R, sent.pose.R)
    return np.array(allowed.position), R_world if kept else allowed.pose.R


def lock_refusal(run: LessonRun) -> str | None:
    """Why the scene breaks the step's locks, or None: a camera (or point) locked at the step's start (the model's
    undo barrier) that is gone or no longer where the step put it, whatever moved it (another scene opened,
    a script). The model refuses every edit of a locked pose; this catches what replaced the scene."""
    start = run.model.barrier_scene
    if start is None:
        return None
    scene = run.model.scene
    # A mirror's virtual camera is locked by its scene and follows the camera it reflects: it moves lawfully.
    derived = {m.virtual for m in start.annotations.mirrors} | {m.virtual for m in scene.annotations.mirrors}
    for name in sorted(start.locked - derived):
        if name.startswith("point:"):
            i = int(name[6:])
            if i >= len(scene.points):
                return f"Point {i + 1} is not in the scene any more: {RESET_ADVICE}"
            if scene.points[i] != start.points[i]:
                return f"Point {i + 1} must stay where this step put it (it is locked): {RESET_ADVICE}"
        elif name in start.camera_names:
            if name not in scene.camera_names:
                return f"{name} is not in the scene any more: {RESET_ADVICE}"
            a, b = start.camera(name), scene.camera(name)
            if a.position != b.position or a.ypr_deg != b.ypr_deg:
                return f"{name} must stay where this step put it (it is locked): {RESET_ADVICE}"
    return None
