"""Constraints the scene model enforces on every edit in place of a camera: a lesson step's ranges of its fields.

A range holds whatever sent the edit (a GUI field, a gizmo drag, a raw client message, a script), because the
model judges the edit itself (:meth:`~egtviz.scene.SceneModel.set_constraints`); a lesson step's own changes are
not judged (the model's lesson authority), and a field that an edit leaves as it was is not judged either (the
scene may start outside a range).

- A typed value outside its range is refused: a :class:`~egtviz.scene.SceneError` with the range, in the words
  and unit of the field the learner typed in when the lesson gives them (``refusal``).
- A drag (only the pose fields change) is not refused: under a ``position`` range each coordinate is clamped to
  the range, like a mechanical stop (the camera stops at the box's edge and still slides along it); under a
  ``ypr_deg`` range the camera keeps its orientation when the new one leaves the range. Clamping each angle on
  its own would not stop it: an angle wraps at 180 degrees, so a yaw dragged past 180 in a range -30..30 would
  jump from 30 to -30.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from ._values import SceneError

__all__ = ["RANGE_SLACK", "CameraRanges", "within"]

RANGE_SLACK = 1e-9
"""A value this far outside a range (relative to the range's largest bound, at least 1) is inside: rounding of a
value converted for display and back."""


def within(low: float, high: float, value: float) -> bool:
    """Whether ``value`` is in ``low..high``, up to :data:`RANGE_SLACK`."""
    slack = RANGE_SLACK * max(1.0, abs(low), abs(high))
    return low - slack <= value <= high + slack


@dataclass(frozen=True, eq=False)
class CameraRanges:
    """Ranges of camera fields, read afresh at every edit (a lesson's ranges change from step to step).

    Args:
        ranges: returns the current ranges, ``(camera, field) -> range`` with ``low`` and ``high`` (each component
            of a vector field).
        refusal: ``refusal(camera, fields)``: why these new field values break the ranges, in the GUI's words
            (None: they do not); without it the message names the spec field and the range.
    """

    ranges: Callable[[], Mapping[tuple[str, str], Any]]
    refusal: Callable[[str, dict[str, Any]], str | None] | None = None

    def judge(self, old: Any, new: Any, *, drag: bool) -> Any:
        """``new`` (a camera spec replacing ``old``) as the ranges allow it: the same spec, a clamped one (a drag),
        or a SceneError (a typed value outside its range)."""
        clamped: dict[str, Any] = {}
        for (camera, field), limit in self.ranges().items():
            if camera != old.name or not hasattr(new, field):
                continue
            value = getattr(new, field)
            if value == getattr(old, field):
                continue
            values = value if isinstance(value, tuple) else (value,)
            if all(within(limit.low, limit.high, float(v)) for v in values):
                continue
            if drag and field == "position":
                clamped[field] = tuple(min(max(float(v), limit.low), limit.high) for v in values)
            elif drag and field in new.POSE_FIELDS:
                clamped[field] = getattr(old, field)
            else:
                raise SceneError(self._message(old.name, field, value, limit))
        return new.with_pose(**clamped) if clamped else new

    def _message(self, camera: str, field: str, value: Any, limit: Any) -> str:
        text = self.refusal(camera, {field: value}) if self.refusal is not None else None
        if text is None:
            shown = ", ".join(f"{float(v):g}" for v in (value if isinstance(value, tuple) else (value,)))
            text = f"In this step {camera}'s {field} must stay between {limit.low:g} and {limit.high:g} (it is {shown})"
        return text
