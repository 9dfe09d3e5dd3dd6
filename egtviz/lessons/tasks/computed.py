"""A question whose answer is computed from the learner's own scene (:class:`ComputedTask`): "where does point 3
land in cam1?", "the epipole of your pair", "F of your pair, up to scale".

The step randomises the scene per learner (``do = "randomise_camera"``), so two learners get two answers; the
answer is computed by the core (:data:`~egtviz.lessons.mistakes.QUANTITIES`) from the scene the learner sees,
and a wrong answer that matches a classic mistake (:data:`~egtviz.lessons.mistakes.MISTAKES`) is named with why
it is wrong.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ...geometry import GeometryError
from ...scene import Scene, SceneError
from .. import fields
from ..answers import EXAMPLE, AnswerError, read_matrix, read_number, read_vector
from ..errors import EntryError
from ..mistakes import QUANTITIES, Mistake, Quantity, Where
from .base import Task, TaskContext, TaskResult
from .common import POINT_INDEX, TOLERANCE, camera_gone, camera_in, fmt, point_gone, point_in, point_label
from .needs import NUMBER, TEXT, AnswerNeeds, TaskNeeds

__all__ = ["LINE_SPAN_PX", "ComputedTask", "distance", "typed_text"]

LINE_SPAN_PX = 1000.0
"""How far from the image origin two lines are compared (about an image's diagonal), in pixels."""


def distance(a: np.ndarray, b: np.ndarray, up_to_scale: bool | str) -> float:
    """How far ``a`` is from ``b``: the Euclidean norm of the difference; ``up_to_scale``, of the difference of
    the two scaled to unit norm with the sign that brings them closest; ``"line"``, for image lines
    ``[a, b, c]``, in pixels: each scaled so that ``(a, b)`` is a unit normal (``c`` is then the line's offset in
    pixels) and the normals' difference weighed by :data:`LINE_SPAN_PX` (a turn by that angle moves the line so
    far at that distance); ``"pixels"``, for a 3 x 3 matrix between pixels (F), as unit-norm vectors after
    scaling pixels by :data:`LINE_SPAN_PX` (``T F T``, ``T = diag(s, s, 1)``)."""
    m, n = a, b = np.asarray(a, dtype=float).ravel(), np.asarray(b, dtype=float).ravel()
    if not up_to_scale:
        return float(np.linalg.norm(a - b))
    if up_to_scale == "line":
        na, nb = np.hypot(a[0], a[1]), np.hypot(b[0], b[1])
        if na == 0.0 or nb == 0.0:
            return float("inf")
        a, b = a / na, b / nb
        return float(min(max(LINE_SPAN_PX * np.linalg.norm(a[:2] - s * b[:2]), abs(a[2] - s * b[2]))
                         for s in (1.0, -1.0)))
    if up_to_scale == "pixels":  # a matrix between pixels: balanced so that no entry's scale hides another's
        t = np.array([LINE_SPAN_PX, LINE_SPAN_PX, 1.0])
        a, b = (np.outer(t, t) * m.reshape(3, 3)).ravel(), (np.outer(t, t) * n.reshape(3, 3)).ravel()
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0.0 or nb == 0.0:
        return float("inf")
    a, b = a / na, b / nb
    return float(min(np.linalg.norm(a - b), np.linalg.norm(a + b)))


def typed_text(value: np.ndarray, unit: str = "") -> str:
    """``value`` as a learner types it: ``1.5``, ``[1.5, -2]``, ``[[...], [...], [...]]`` (``%.9g``), then the unit."""
    v = np.asarray(value, dtype=float)
    if v.ndim == 0:
        text = f"{float(v):.9g}"
    elif v.ndim == 1:
        text = "[" + ", ".join(f"{x:.9g}" for x in v) + "]"
    else:
        text = "[" + ", ".join("[" + ", ".join(f"{x:.9g}" for x in row) + "]" for row in v) + "]"
    return f"{text} {unit}" if unit else text


@dataclass(frozen=True, kw_only=True)
class ComputedTask(Task):
    """The ``quantity`` of ``camera`` (with ``other``, of ``point``) in the learner's scene, within ``tolerance``
    (in the quantity's unit; for a quantity defined up to scale, of the unit-norm vectors)."""

    quantity: str
    camera: str
    other: str | None = None
    point: int | None = None
    tolerance: float

    kind: ClassVar[str] = "computed"
    table_keys: ClassVar[tuple[str, ...]] = ("quantity", "camera", "other", "point", "tolerance")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> ComputedTask:
        name = fields.text(table, "quantity")
        if name not in QUANTITIES:
            raise EntryError("quantity", f"expected one of {', '.join(QUANTITIES)}, got {fields.short(name)}")
        q = QUANTITIES[name]
        other = fields.text(table, "other") if q.needs_other else None
        if not q.needs_other and "other" in table:
            raise EntryError("other", f"the quantity {name!r} is about one camera: no 'other'")
        point = int(fields.number(table, "point", POINT_INDEX)) if q.needs_point else None
        if not q.needs_point and "point" in table:
            raise EntryError("point", f"the quantity {name!r} is about no point: no 'point'")
        tolerance = fields.number(table, "tolerance", TOLERANCE, required=False, default=q.default_tolerance)
        if tolerance <= 0:
            raise EntryError("tolerance", "expected a tolerance above 0")
        return cls(**common, quantity=name, camera=fields.text(table, "camera"), other=other, point=point,
                   tolerance=tolerance)

    @property
    def spec(self) -> Quantity:
        """What the task asks for."""
        return QUANTITIES[self.quantity]

    @property
    def unit(self) -> str:
        """The answer's unit (what the answer field's label shows)."""
        return self.spec.unit

    @property
    def answer_format(self) -> str:
        """How to type the answer, for the answer field's hint."""
        shape, unit = self.spec.shape, self.spec.unit
        tail = f", in {unit} (the unit may follow it)" if unit else ""
        scale = "; any scale" if self.spec.up_to_scale else ""
        if shape == ():
            return f"One number, e.g. {EXAMPLE}{tail}."
        if len(shape) == 1:
            return f"{shape[0]} numbers in brackets, e.g. [{', '.join([EXAMPLE] * shape[0])}]{tail}{scale}."
        return f"A {shape[0]} x {shape[1]} matrix row by row, e.g. [a, b, c; d, e, f; g, h, i]{scale}."

    @property
    def needs(self) -> TaskNeeds:
        widget = NUMBER if self.spec.shape == () else TEXT
        return TaskNeeds(AnswerNeeds(widget, unit=self.unit, hint=self.answer_format))

    @property
    def where(self) -> Where:
        """The cameras and point the quantity is about."""
        return Where(self.camera, self.other, self.point)

    def validate(self, scene: Scene) -> None:
        spec = camera_in(scene, self.camera)
        if self.other is not None:
            camera_in(scene, self.other, "other")
            if self.other == self.camera:
                raise EntryError("other", "expected a camera other than 'camera'")
        if self.point is not None:
            point_in(scene, self.point)
        if self.spec.pinhole_only and spec.kind != "pinhole":
            raise EntryError("camera", f"the quantity {self.quantity!r} needs a pin-hole camera, got {spec.kind}")
        self.value(scene)  # the step's scene must have an answer (a point in front, a finite epipole)

    def missing(self, scene: Scene) -> str | None:
        gone = camera_gone(scene, *(n for n in (self.camera, self.other) if n is not None))
        if gone is None and self.point is not None:
            gone = point_gone(scene, self.point)
        return gone

    def value(self, scene: Scene) -> np.ndarray:
        """The right answer in ``scene`` (the same function the check uses)."""
        try:
            return np.asarray(self.spec.value(scene, self.where), dtype=float)
        except GeometryError as exc:
            raise SceneError(str(exc)) from None

    def answer_text(self, scene: Scene) -> str:
        """The right answer in ``scene``, as a learner would type it."""
        return typed_text(self.value(scene), self.unit)

    def mistake_value(self, name: str, scene: Scene) -> np.ndarray:
        """What a learner who made mistake ``name`` would type in ``scene``.

        Raises:
            KeyError: the quantity has no mistake of that name.
        """
        for mistake in self.spec.mistakes:
            if mistake.name == name:
                return np.asarray(mistake.value(scene, self.where), dtype=float)
        raise KeyError(f"mistake: {self.quantity!r} has no mistake {name!r} (have "
                       f"{', '.join(m.name for m in self.spec.mistakes) or 'none'})")

    def mistake_text(self, name: str, scene: Scene) -> str:
        """:meth:`mistake_value` as typed (a counter-example types it)."""
        return typed_text(self.mistake_value(name, scene), self.unit)

    def read(self, typed: str | None) -> np.ndarray:
        """The learner's answer in the quantity's shape (:mod:`~egtviz.lessons.answers`, strictly).

        Raises:
            AnswerError: the text is not that; the message says what was expected.
        """
        shape, unit = self.spec.shape, self.spec.unit
        if shape == ():
            return np.array(read_number(typed, unit))
        if len(shape) == 1:
            return np.array(read_vector(typed, shape[0], unit))
        return np.array(read_matrix(typed, *shape))

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        try:
            x = self.read(ctx.answer)
        except AnswerError as exc:
            return TaskResult(False, str(exc), unread=True)
        right = self.value(ctx.scene)
        scale = self.spec.up_to_scale
        shown = typed_text(x, self.unit)
        if distance(x, right, scale) <= self.tolerance:
            return TaskResult(True, f"Right: {shown}" + (" (up to scale)." if scale else "."))
        mistake = self.diagnose(x, right, ctx.scene)
        if mistake is not None:
            return TaskResult(False, f"{shown} is {mistake.title}: {mistake.why}.")
        what = "of the answer (up to scale)" if scale else "of the answer"
        unit = "px" if scale == "line" else self.unit
        return TaskResult(False, f"{shown} is not within {fmt(self.tolerance)}{' ' + unit if unit else ''} {what}.")

    def diagnose(self, typed: np.ndarray, right: np.ndarray, scene: Scene) -> Mistake | None:
        """The classic mistake whose value ``typed`` matches within the tolerance (and the right answer does not)."""
        scale = self.spec.up_to_scale
        for mistake in self.spec.mistakes:
            try:
                wrong = np.asarray(mistake.value(scene, self.where), dtype=float)
            except (SceneError, GeometryError, AttributeError):  # the mistake does not apply to this camera
                continue
            if wrong.shape != right.shape or not np.all(np.isfinite(wrong)):
                continue
            if distance(typed, wrong, scale) <= self.tolerance < distance(wrong, right, scale):
                return mistake
        return None

    def point_named(self) -> str:
        """The point as prompts name it (``point 3``), or empty."""
        return "" if self.point is None else f"point {point_label(self.point)}"
