"""Constraints the scene model enforces on every edit in place of a camera: a lesson step's ranges of its fields.

The one range rule is :meth:`CameraRanges.breaches`; everything that asks whether a camera field is inside its
range goes through it: the model judging an edit (:meth:`CameraRanges.judge`, whatever sent the edit: a GUI
field, a gizmo drag, a raw client message, a script, :meth:`~egtviz.scene.SceneModel.set_constraints`), a GUI
field refusing a typed value before the model sees it (:meth:`CameraRanges.refusal`) and a lesson's check
refusing a scene that left its ranges some other way (:meth:`CameraRanges.scene_refusal`). A lesson step's own
changes are not judged (the model's lesson authority), and a field that an edit leaves as it was is not judged
either (the scene may start outside a range).

- A typed value outside its range is refused: a :class:`~egtviz.scene.SceneError` with the range, in the words
  and unit of the field the learner typed in when the lesson gives them (``words``).
- A drag (only the pose fields change) is not refused: under a ``position`` range each coordinate is clamped to
  the range, like a mechanical stop (the camera stops at the box's edge and still slides along it); under a
  ``ypr_deg`` range the camera keeps its rotation, exactly, when the new one leaves the range. Clamping each
  angle on its own would not stop it: an angle wraps at 180 degrees, so a yaw dragged past 180 in a range
  -30..30 would jump from 30 to -30.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ._values import SceneError

if TYPE_CHECKING:
    from .scene import Scene

__all__ = ["RANGE_SLACK", "Breach", "CameraRanges", "within"]

RANGE_SLACK = 1e-9
"""A value this far outside a range (relative to the range's largest bound, at least 1) is inside: rounding of a
value converted for display and back, or of angles read back from a rotation (yaw 30 reads 30.000000000000004)."""


def within(low: float, high: float, value: float) -> bool:
    """Whether ``value`` is in ``low..high``, up to :data:`RANGE_SLACK`."""
    slack = RANGE_SLACK * max(1.0, abs(low), abs(high))
    return low - slack <= value <= high + slack


def _inside(limit: Any, value: Any) -> bool:
    """Whether ``value`` (each component of a vector field) is a number within ``limit``."""
    values = value if isinstance(value, tuple) else (value,)
    return all(isinstance(v, (int, float)) and within(limit.low, limit.high, float(v)) for v in values)


@dataclass(frozen=True)
class Breach:
    """A camera field whose value is outside its range."""

    camera: str
    field: str
    value: Any
    limit: Any
    """The range, with ``low`` and ``high``."""


@dataclass(frozen=True, eq=False)
class CameraRanges:
    """Ranges of camera fields, read afresh at every question (a lesson's ranges change from step to step).

    Args:
        ranges: returns the current ranges, ``(camera, field) -> range`` with ``low`` and ``high`` (each component
            of a vector field).
        words: ``words(camera, {field: value})``: a breach of that field's range in the GUI's words (None: the
            plain words); without it the message names the spec field and the range.
    """

    ranges: Callable[[], Mapping[tuple[str, str], Any]]
    words: Callable[[str, dict[str, Any]], str | None] | None = None

    def breaches(self, camera: str, fields: Mapping[str, Any]) -> list[Breach]:
        """The range rule: the values among ``fields`` (``camera``'s field -> value) outside their ranges, in the
        fields' name order."""
        ranges = self.ranges()
        return [Breach(camera, field, value, ranges[(camera, field)]) for field, value in sorted(fields.items())
                if (camera, field) in ranges and not _inside(ranges[(camera, field)], value)]

    def refusal(self, camera: str, fields: Mapping[str, Any]) -> str | None:
        """Why these new values of ``camera``'s fields break the ranges (the first breach, in words), or None."""
        found = self.breaches(camera, fields)
        return self._message(found[0]) if found else None

    def scene_refusal(self, scene: Scene) -> str | None:
        """Why ``scene`` breaks the ranges (a camera field outside its range, whatever put it there), or None."""
        ranged = list(self.ranges())
        for camera in scene.camera_names:
            spec = scene.camera(camera)
            refusal = self.refusal(camera, {f: getattr(spec, f, None) for c, f in ranged if c == camera})
            if refusal is not None:
                return refusal
        return None

    def judge(self, old: Any, new: Any, *, drag: bool) -> Any:
        """``new`` (a camera spec replacing ``old``) as the ranges allow it: the same spec, one stopped at the
        ranges (a drag), or a SceneError (a typed value outside its range)."""
        changed = {field: getattr(new, field) for camera, field in self.ranges()
                   if camera == old.name and hasattr(new, field) and getattr(new, field) != getattr(old, field)}
        found = self.breaches(old.name, changed)
        if not found:
            return new
        if not drag or any(b.field not in new.POSE_FIELDS for b in found):
            raise SceneError(self._message(found[0]))
        return _stopped(old, new, found)

    def _message(self, breach: Breach) -> str:
        text = self.words(breach.camera, {breach.field: breach.value}) if self.words is not None else None
        if text is None:
            value, limit = breach.value, breach.limit
            shown = ", ".join(f"{float(v):g}" for v in (value if isinstance(value, tuple) else (value,))
                              if isinstance(v, (int, float)))
            text = (f"In this step {breach.camera}'s {breach.field} must stay between {limit.low:g} and "
                    f"{limit.high:g} (it is {shown})")
        return text


def _stopped(old: Any, new: Any, found: list[Breach]) -> Any:
    """``new``, a dragged pose of ``old`` that breaks ``found``, stopped at the ranges: its centre clamped into
    the ``position`` range; when the orientation left its range, ``old``'s very rotation (one rebuilt from its
    angles differs by rounding: the stop would still turn the camera a hair)."""
    limits = {b.field: b.limit for b in found}
    position = new.position
    if "position" in limits:
        low, high = limits["position"].low, limits["position"].high
        position = tuple(min(max(float(v), low), high) for v in position)
    if any(field != "position" for field in limits):
        return old if position == old.position else old.with_pose(position=position)
    return new.with_pose(position=position)
