r"""Tasks a lesson step asks for, from a fixed vocabulary: each kind a frozen record with a ``check``.

Nothing in a lesson file is ever run as code: a ``[[steps.tasks]]`` table names its ``kind`` and the
parameters of that kind, and :meth:`Task.check` measures the scene (through :func:`egtviz.scene.compute_derived`
and the numeric core, never the viewer). Every check returns a :class:`TaskResult` with feedback that says
what was measured; the runner shows the task's ``hint`` after a failed attempt.

Randomised tasks: a parameter written as ``[low, high]`` (whole numbers: a whole number is drawn) is drawn
per learner with ``numpy.random.default_rng(seed)``, the seed derived from (learner, lesson, step, task)
by :func:`task_seed`; the prompt shows the drawn values through ``{name}`` placeholders
(:meth:`Task.prompt_for`).

The kinds, their keys and when they pass are listed in ``docs/lessons.md`` and in each class's docstring
(:data:`TASK_KINDS` maps the names to the classes).

A check on a scene that no longer has what the task names (a camera removed, another scene opened) fails
with what is missing and :data:`RESET_ADVICE` (:meth:`Task.missing`), never an exception; a typed number is
read strictly (:func:`egtviz.lessons.answers.read_number`).

Every task also has ``id`` (unique in its step), ``prompt``, ``hint`` and optional ``solution`` (a list of
changes, as in ``[[steps.changes]]``, that solves it from the step's starting scene).
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import re
import string
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ..geometry import PinholeCamera
from ..geometry.epipolar import epipolar_planes, lines_of_planes
from ..geometry.triangulation import triangulate_linear, triangulate_optimal
from ..scene import Scene, SceneError
from ..scene.derived import Derived, compute_derived
from ..scene.lab import METHODS, LabResult, LabSettings, run_lab
from ..scene.limits import LAB_NOISE_PX, LAB_OUTLIER_PERCENT
from ..scene.lens import LensToggles, LensView, lens_view
from ..scene.limits import COORDINATE, MAX_POINTS, PRINCIPAL_POINT, Range
from . import fields
from .answers import AnswerError, read_number
from .changes import Change, parse_change
from .errors import EntryError
from .markup import MarkupError, render_markdown
from .servo_runs import MEASURES, DemoRun, measure_run

__all__ = ["RESET_ADVICE", "TASK_KINDS", "Task", "TaskContext", "TaskResult", "Uniform", "parse_task", "task_seed"]

WITHIN_PX = Range(1e-3, 1e4, "px")
WITHIN_DEG = Range(1e-3, 180.0, "deg")
SAMPSON_PX2 = Range(1e-6, 1e6, "px^2")
FRACTION = Range(0.0, 1.0, "")
TOLERANCE = Range(0.0, 1e12, "")
ANSWER = Range(-1e12, 1e12, "")
DEPTH_ERROR = Range(1e-6, COORDINATE.high, "m")
_POINT = Range(0, MAX_POINTS - 1, "", integer=True)
_COMPONENT = Range(0, 2, "", integer=True)
_MAX_OPTIONS = 12
_BELOW = {"deg": Range(1e-6, 180.0, "deg"), "cm": Range(1e-6, 100.0 * COORDINATE.high, "cm")}
_TRIANGULATION_DRAWS = 200
#: How a check that finds something missing tells the learner the way back (the lesson panel's step button).
RESET_ADVICE = "press \u201creset step\u201d to start this step again."


@dataclass(frozen=True)
class TaskResult:
    """One attempt's outcome: ``passed`` and the feedback to show."""

    passed: bool
    feedback: str


@dataclass(frozen=True)
class Uniform:
    """A parameter drawn per learner from ``low..high`` (a whole number when ``integer``)."""

    low: float
    high: float
    integer: bool = False

    def draw(self, rng: np.random.Generator) -> float:
        """One value: ``rng.integers(low, high + 1)`` or ``rng.uniform(low, high)`` rounded to 0.01."""
        if self.integer:
            return float(rng.integers(int(self.low), int(self.high) + 1))
        return round(float(rng.uniform(self.low, self.high)), 2)


Param = float | Uniform


@dataclass(frozen=True, eq=False)
class TaskContext:
    """What a check may look at: the scene (and what is drawn of it), the learner's typed answer, the
    estimation lab's settings, the convention lens's toggles and the servo run of the step (its
    ``open_demo``) as the runner holds them."""

    scene: Scene
    derived: Derived | None = None
    answer: str | None = None
    lab: LabSettings = LabSettings()
    lens: LensToggles = LensToggles()
    demo: DemoRun | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    def drawn(self) -> Derived:
        """What is drawn of the scene (``compute_derived``, once)."""
        if self.derived is None:
            self._cache.setdefault("derived", compute_derived(self.scene))
            return self._cache["derived"]
        return self.derived

    def lab_result(self) -> LabResult:
        """The estimation lab on the scene with the runner's lab settings (once)."""
        if "lab" not in self._cache:
            self._cache["lab"] = run_lab(self.scene, self.lab, derived=self.drawn())
        return self._cache["lab"]

    def lens_view(self) -> LensView:
        """The drawn pair through the runner's convention lens (once)."""
        if "lens" not in self._cache:
            self._cache["lens"] = lens_view(self.scene, self.lens, self.drawn())
        return self._cache["lens"]


def task_seed(learner: str, lesson: str, step: int, task: str) -> int:
    """A 63-bit seed from (learner, lesson, step index, task id): the same learner always gets the same draw."""
    digest = hashlib.sha256("\x1f".join((learner, lesson, str(step), task)).encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") >> 1


class _Shown(float):
    """A drawn value in a prompt: ``{u}`` shows it with ``g`` (106, not 106.0), ``{u:.1f}`` as asked."""

    def __format__(self, spec: str) -> str:
        return format(float(self), spec or "g")


class _SafeValues(dict):
    """``format_map`` values: a placeholder without a value stays as written."""

    def __missing__(self, key: str) -> str:
        return "{" + key + "}"


@dataclass(frozen=True, kw_only=True)
class Task:
    """Fields every task has; subclasses add their kind's parameters and ``check``."""

    id: str
    prompt: str
    hint: str = ""
    solution: tuple[Change, ...] = ()
    """Changes that solve the task from the step's starting scene (for the tests and the docs)."""

    kind: ClassVar[str] = ""
    question: ClassVar[bool] = False
    """Answered by typing (number, choice) rather than by acting in the scene."""

    def params(self) -> dict[str, Param]:
        """The parameters that may be drawn per learner, by the names the prompt and the check use."""
        return {}

    def resolve(self, seed: int) -> dict[str, float]:
        """The parameters with every :class:`Uniform` drawn from ``default_rng(seed)`` (in name order)."""
        rng = np.random.default_rng(seed)
        return {k: (v.draw(rng) if isinstance(v, Uniform) else float(v)) for k, v in sorted(self.params().items())}

    def prompt_for(self, params: dict[str, float]) -> str:
        """The prompt with its ``{name}`` placeholders replaced by the drawn values."""
        return self.prompt.format_map(_SafeValues({k: _Shown(v) for k, v in params.items()}))

    def check(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        """Measure the goal in ``ctx`` with the drawn ``params``: passed, and feedback saying what was measured.

        A scene that no longer has what the task measures (a camera removed, another scene opened) fails with
        what is missing and the way back (the step's *reset step*), never an exception.
        """
        gone = self.missing(ctx.scene)
        if gone is None:
            try:
                return self.judge(ctx, params)
            except SceneError as exc:  # e.g. the lab or the lens cannot be computed on this scene
                gone = str(exc)
        return TaskResult(False, f"{gone}: {RESET_ADVICE}")

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:  # pragma: no cover - abstract
        """The check on a scene that has what the task names (:meth:`missing` found nothing)."""
        raise NotImplementedError

    def missing(self, scene: Scene) -> str | None:
        """What the task measures that ``scene`` does not have, e.g. ``"cam2 is not in the scene any more"``."""
        return None

    def validate(self, scene: Scene) -> None:
        """Refuse a task that names what the step's scene does not have (an :class:`EntryError` naming the key)."""


# -- helpers ---------------------------------------------------------------------------------------------


def _camera_in(scene: Scene, name: str, key: str = "camera") -> Any:
    if name not in scene.camera_names:
        raise EntryError(key, f"no camera named {name!r} in the step's scene (have {list(scene.camera_names)})")
    return scene.camera(name)


def _point_in(scene: Scene, index: int, key: str = "point") -> None:
    if index >= len(scene.points):
        raise EntryError(key, f"no point {index} in the step's scene (have {len(scene.points)})")


def _in_pair(scene: Scene, name: str, key: str = "camera", pinhole_pair: bool = False) -> None:
    _camera_in(scene, name, key)
    pair = scene.drawn_pair
    if pair is None or name not in pair:
        raise EntryError(key, f"camera {name!r} is not in the drawn pair {pair} (add a set_pair change)")
    if pinhole_pair and not _projective_pair(scene, pair):
        raise EntryError(key, f"this task needs a drawn pair of pin-hole cameras, got {pair}")


def _projective_pair(scene: Scene, pair: tuple[str, str] | None) -> bool:
    """Both cameras of ``pair`` image linearly (pin-holes: they have a K, and F exists between their pixels)."""
    return pair is not None and all(scene.camera(n).camera().projective_calibration is not None for n in pair)


def _camera_gone(scene: Scene, *names: str) -> str | None:
    """Which of ``names`` the scene no longer has (the first), as the learner is told."""
    for name in names:
        if name not in scene.camera_names:
            return f"{name} is not in the scene any more"
    return None


def _point_gone(scene: Scene, index: int) -> str | None:
    if index >= len(scene.points):
        return f"point {point_label(index)} is not in the scene any more (it has {len(scene.points)} points)"
    return None


def _pair_gone(scene: Scene, camera: str | None = None, *, pinhole: bool = False) -> str | None:
    """Why the drawn pair is not what the task measures: none, without ``camera``, or not two pin-holes."""
    gone = None if camera is None else _camera_gone(scene, camera)
    if gone is not None:
        return gone
    pair = scene.drawn_pair
    if pair is None:
        return "the scene has fewer than two cameras: no pair is drawn"
    if camera is not None and camera not in pair:
        return f"{camera} is not in the drawn pair ({pair[0]} & {pair[1]}) any more"
    if pinhole and not _projective_pair(scene, pair):
        return f"the drawn pair ({pair[0]} & {pair[1]}) is not two pin-hole cameras any more"
    return None


def point_label(index: int) -> int:
    """The number the viewer shows for point ``index`` (panels, 3D labels, the point list count from 1); prompts
    (``{point}``) and feedback name points by it, lesson files by their index from 0."""
    return index + 1


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def _lab_constraints(ctx: TaskContext, min_noise: float, min_outliers: float) -> TaskResult | None:
    if ctx.lab.noise_px < min_noise:
        return TaskResult(False, f"Keep the noise at {min_noise:g} px or more (it is {ctx.lab.noise_px:g} px).")
    if ctx.lab.outlier_percent < min_outliers:
        return TaskResult(
            False, f"Keep the outliers at {min_outliers:g} % or more (they are {ctx.lab.outlier_percent:g} %)."
        )
    return None


# -- questions ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class NumberTask(Task):
    """A numeric answer within ``tolerance`` of ``answer``: one number, optionally followed by ``unit``."""

    answer: float
    tolerance: float = 0.0
    unit: str = ""

    kind: ClassVar[str] = "number"
    question: ClassVar[bool] = True

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        return _compare_number(ctx.answer, self.answer, self.tolerance, self.unit)


def _compare_number(typed: str | None, answer: float, tolerance: float, unit: str) -> TaskResult:
    """The typed number (:func:`~egtviz.lessons.answers.read_number`: one number, then optionally ``unit``)
    against ``answer`` within ``tolerance``."""
    try:
        x = read_number(typed, unit)
    except AnswerError as exc:
        return TaskResult(False, str(exc))
    shown = f" {unit}" if unit else ""
    if abs(x - answer) <= tolerance:
        return TaskResult(True, f"Right: {_fmt(x)}{shown}.")
    return TaskResult(False, f"{_fmt(x)}{shown} is too {'high' if x > answer else 'low'}.")


@dataclass(frozen=True, kw_only=True)
class ServoNumberTask(Task):
    """A number read off the step's servo run (its ``open_demo``): ``measure`` (with ``below`` for the
    ``*_below_time`` measures) within ``tolerance``. The answer is computed by simulating the run headless,
    as the demo does (:mod:`egtviz.lessons.servo_runs`); the unit is the measure's."""

    measure: str
    below: float | None = None
    tolerance: float = 0.0

    kind: ClassVar[str] = "servo_number"
    question: ClassVar[bool] = True

    @property
    def unit(self) -> str:
        """The measure's unit (s, steps, deg, cm)."""
        return MEASURES[self.measure].unit

    def params(self) -> dict[str, Param]:
        return {"tolerance": self.tolerance, **({"below": self.below} if self.below is not None else {})}

    def answer_for(self, run: DemoRun) -> float:
        """The right answer for ``run`` (NaN: the run never gets there)."""
        return measure_run(run, self.measure, math.nan if self.below is None else self.below)

    def validate_run(self, run: DemoRun | None) -> None:
        """Refuse a task without a servo run in its step, a measure the demo does not have, or a run that never
        gets where the measure asks (an :class:`EntryError` naming the key)."""
        if run is None:
            raise EntryError(None, "a servo_number task needs an open_demo change in its step or an earlier one")
        if run.demo not in MEASURES[self.measure].demos:
            raise EntryError("measure", f"the {run.demo} demo has no {self.measure!r}")
        if not math.isfinite(self.answer_for(run)):
            raise EntryError("below" if self.below is not None else "measure",
                             f"the {run.demo} run ({run.describe() or 'its defaults'}) never gets there")

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        if ctx.demo is None:
            return TaskResult(False, "This step opens no servo demo to read the answer from.")
        return _compare_number(ctx.answer, self.answer_for(ctx.demo), params["tolerance"], self.unit)


@dataclass(frozen=True, kw_only=True)
class ChoiceTask(Task):
    """One of ``options``; the learner types the option or its number (1, 2, ...)."""

    options: tuple[str, ...]
    answer: str

    kind: ClassVar[str] = "choice"
    question: ClassVar[bool] = True

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        given = (ctx.answer or "").strip()
        if given.isdigit() and 1 <= int(given) <= len(self.options):
            given = self.options[int(given) - 1]
        if given not in self.options:
            return TaskResult(False, "Pick one of the options.")
        if given == self.answer:
            return TaskResult(True, f"Right: {given}.")
        return TaskResult(False, f"Not {given!r}.")


# -- scene goals ------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class EpipoleNearTask(Task):
    """The epipole of ``camera`` (in the drawn pair) lies within ``within_px`` of ``(u, v)``."""

    camera: str
    u: Param
    v: Param
    within_px: float

    kind: ClassVar[str] = "epipole_near"

    def params(self) -> dict[str, Param]:
        return {"u": self.u, "v": self.v, "within_px": self.within_px}

    def validate(self, scene: Scene) -> None:
        _in_pair(scene, self.camera)

    def missing(self, scene: Scene) -> str | None:
        return _camera_gone(scene, self.camera)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        u, v, within = params["u"], params["v"], params["within_px"]
        plane = ctx.drawn().image_planes.get(self.camera)
        if plane is None or not plane.in_pair:
            return TaskResult(False, f"Camera {self.camera!r} is not in the drawn pair.")
        finite = [e for e in plane.epipoles if e.xy is not None]
        if not finite:
            return TaskResult(
                False, f"The epipole of {self.camera} is at infinity: turn the camera towards the other one."
            )
        best = min(finite, key=lambda e: math.hypot(e.xy[0] - u, e.xy[1] - v))
        d = math.hypot(best.xy[0] - u, best.xy[1] - v)
        where = f"{best.label} is at ({best.xy[0]:.1f}, {best.xy[1]:.1f}), {d:.1f} px from ({u:g}, {v:g})"
        if d <= within:
            return TaskResult(True, f"Done: {where}.")
        return TaskResult(False, f"Not yet: {where}; it must be within {within:g} px.")


def rotation_angle_deg(Ra: np.ndarray, Rb: np.ndarray) -> float:
    r"""Angle of the rotation :math:`R_a^T R_b`: :math:`\arccos((\operatorname{tr}(R_a^T R_b) - 1) / 2)`, degrees."""
    c = (float(np.trace(Ra.T @ Rb)) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


@dataclass(frozen=True, kw_only=True)
class SameOrientationTask(Task):
    """Cameras A and B have the same orientation (frames) within ``within_deg``."""

    cameras: tuple[str, str]
    within_deg: float

    kind: ClassVar[str] = "same_orientation"

    def params(self) -> dict[str, Param]:
        return {"within_deg": self.within_deg}

    def validate(self, scene: Scene) -> None:
        a, b = (_camera_in(scene, n, "cameras") for n in self.cameras)
        if a.model_kind != b.model_kind:
            raise EntryError("cameras", f"expected two cameras of one kind, got {a.model_kind} and {b.model_kind}")

    def missing(self, scene: Scene) -> str | None:
        return _camera_gone(scene, *self.cameras)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        a, b = (ctx.scene.camera(n) for n in self.cameras)
        angle = rotation_angle_deg(a.pose.R, b.pose.R)
        msg = f"{self.cameras[0]} and {self.cameras[1]} differ by a rotation of {angle:.1f} degrees"
        if angle <= params["within_deg"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['within_deg']:g} allowed.")


def direction_spread_deg(lines: np.ndarray) -> float:
    """The smallest angle (degrees) that contains the directions of all ``lines`` (N, 3), as undirected lines.

    Each line's direction angle is doubled (so opposite directions coincide) and the spread is half the
    smallest arc of the circle holding them all: ``(2 pi - largest gap) / 2``.
    """
    phi = np.sort(np.mod(2.0 * np.arctan2(lines[:, 0], -lines[:, 1]), 2.0 * np.pi))
    if len(phi) < 2:
        return 0.0
    gaps = np.diff(np.concatenate([phi, [phi[0] + 2.0 * np.pi]]))
    return math.degrees((2.0 * np.pi - float(gaps.max())) / 2.0)


@dataclass(frozen=True, kw_only=True)
class LinesParallelTask(Task):
    """The epipolar lines in ``camera``'s image are parallel within ``within_deg`` (its epipole at infinity)."""

    camera: str
    within_deg: float

    kind: ClassVar[str] = "lines_parallel"

    def params(self) -> dict[str, Param]:
        return {"within_deg": self.within_deg}

    def validate(self, scene: Scene) -> None:
        _in_pair(scene, self.camera, pinhole_pair=True)
        if len(scene.points) < 2:
            raise EntryError(None, "lines_parallel needs at least two points in the scene")

    def missing(self, scene: Scene) -> str | None:
        return _pair_gone(scene, self.camera, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        scene = ctx.scene
        n1, n2 = scene.drawn_pair  # type: ignore[misc]
        c1, c2 = scene.camera(n1).camera(), scene.camera(n2).camera()
        planes = epipolar_planes(c1.center, c2.center, scene.points_array())
        normals = planes[~np.isnan(planes).any(axis=1), :3]  # points on the baseline have no plane
        if len(normals) < 2:
            return TaskResult(False, "Fewer than two points off the baseline: no lines to compare.")
        lines = lines_of_planes(scene.camera(self.camera).camera(), normals)
        spread = direction_spread_deg(lines)
        msg = f"the epipolar lines of {self.camera} spread over {spread:.2f} degrees"
        if spread <= params["within_deg"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['within_deg']:g} allowed.")


@dataclass(frozen=True, kw_only=True)
class PointOnLineTask(Task):
    """The image of point ``point`` lies within ``within_px`` of its epipolar line computed from the ``F`` the
    panels show (through the convention lens)."""

    point: int
    camera: str
    within_px: float

    kind: ClassVar[str] = "point_on_line"

    def params(self) -> dict[str, Param]:
        return {"point": float(point_label(self.point)), "within_px": self.within_px}

    def validate(self, scene: Scene) -> None:
        _point_in(scene, self.point)
        _in_pair(scene, self.camera, pinhole_pair=True)

    def missing(self, scene: Scene) -> str | None:
        return _point_gone(scene, self.point) or _pair_gone(scene, self.camera, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        view = ctx.lens_view()
        d = (view.distances1_px if self.camera == view.names[0] else view.distances2_px)[self.point]
        if not math.isfinite(d):
            return TaskResult(False, f"Point {point_label(self.point)} has no image in both cameras.")
        msg = f"point {point_label(self.point)} is {d:.2f} px from its epipolar line in {self.camera}"
        if d <= params["within_px"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['within_px']:g} px allowed.")


@dataclass(frozen=True, kw_only=True)
class SampsonBelowTask(Task):
    """The lab's ``method`` has a mean Sampson error below ``below_px2`` (``against`` the true or the measured
    pixels of the true inliers), with the lab's noise and outliers at least the given minimum."""

    method: str
    below_px2: float
    against: str = "true"
    min_noise_px: float = 0.0
    min_outlier_percent: float = 0.0

    kind: ClassVar[str] = "sampson_below"

    def params(self) -> dict[str, Param]:
        return {"below_px2": self.below_px2}

    def validate(self, scene: Scene) -> None:
        _lab_scene(scene)

    def missing(self, scene: Scene) -> str | None:
        return _pair_gone(scene, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        refused = _lab_constraints(ctx, self.min_noise_px, self.min_outlier_percent)
        if refused is not None:
            return refused
        fit = ctx.lab_result().fit(self.method)
        if fit.F is None:
            return TaskResult(False, f"{fit.title} failed: {fit.message}")
        err = fit.sampson_true if self.against == "true" else fit.sampson_noisy
        msg = f"{fit.title}'s mean Sampson error is {err:.3g} px^2"
        if err < params["below_px2"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; it must be below {params['below_px2']:g} px^2.")


@dataclass(frozen=True, kw_only=True)
class InliersRecallTask(Task):
    """The lab's robust ``method`` marks at least ``at_least`` of the true inliers as inliers."""

    method: str
    at_least: float
    min_noise_px: float = 0.0
    min_outlier_percent: float = 0.0

    kind: ClassVar[str] = "inliers_recall"

    def params(self) -> dict[str, Param]:
        return {"at_least": self.at_least, "at_least_percent": 100.0 * self.at_least}

    def validate(self, scene: Scene) -> None:
        _lab_scene(scene)

    def missing(self, scene: Scene) -> str | None:
        return _pair_gone(scene, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        refused = _lab_constraints(ctx, self.min_noise_px, self.min_outlier_percent)
        if refused is not None:
            return refused
        fit = ctx.lab_result().fit(self.method)
        if fit.F is None:
            return TaskResult(False, f"{fit.title} failed: {fit.message}")
        msg = f"{fit.title} marks {100 * fit.inlier_recall:.0f} % of the true inliers as inliers"
        if fit.inlier_recall >= params["at_least"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at least {100 * params['at_least']:g} % needed.")


def _lab_scene(scene: Scene) -> None:
    pair = scene.drawn_pair
    if not _projective_pair(scene, pair):
        raise EntryError(None, f"the estimation lab needs a drawn pair of pin-hole cameras, got {pair}")


@dataclass(frozen=True, kw_only=True)
class PointInImageTask(Task):
    """Point ``point`` is seen inside ``camera``'s image."""

    point: int
    camera: str

    kind: ClassVar[str] = "point_in_image"

    def params(self) -> dict[str, Param]:
        return {"point": float(point_label(self.point))}

    def validate(self, scene: Scene) -> None:
        _point_in(scene, self.point)
        _camera_in(scene, self.camera)

    def missing(self, scene: Scene) -> str | None:
        return _camera_gone(scene, self.camera) or _point_gone(scene, self.point)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        plane = ctx.drawn().image_planes[self.camera]
        i, label = self.point, point_label(self.point)
        if plane.in_image[i]:
            u, v = plane.points[i]
            return TaskResult(True, f"Done: point {label} is at ({u:.4g}, {v:.4g}) in {self.camera}'s image.")
        if not plane.visible[i]:
            return TaskResult(False, f"Not yet: point {label} has no image in {self.camera} (behind it, or blind).")
        u, v = plane.points[i]
        return TaskResult(False, f"Not yet: point {label} projects to ({u:.4g}, {v:.4g}), outside the "
                                 f"{plane.width} x {plane.height} image.")


@dataclass(frozen=True, kw_only=True)
class CameraFieldTask(Task):
    """A numeric field of a camera spec (component ``component`` of a vector field) lies in ``low..high``."""

    camera: str
    field: str
    low: float
    high: float
    component: int | None = None

    kind: ClassVar[str] = "camera_field"

    def params(self) -> dict[str, Param]:
        return {"low": self.low, "high": self.high}

    def validate(self, scene: Scene) -> None:
        spec = _camera_in(scene, self.camera)
        if self.field not in {f.name for f in dataclasses.fields(spec)}:
            raise EntryError("field", f"camera {self.camera!r} ({spec.kind}) has no field {self.field!r}")
        value = getattr(spec, self.field)
        if isinstance(value, tuple) != (self.component is not None):
            raise EntryError("component", f"give a component (0..{len(value) - 1}) exactly for a vector field"
                             if isinstance(value, tuple) else f"{self.field!r} is a single number: no component")
        if isinstance(value, tuple) and self.component >= len(value):  # type: ignore[operator]
            raise EntryError("component", f"{self.field!r} has {len(value)} components")
        if isinstance(value, str):
            raise EntryError("field", f"{self.field!r} is not a number")

    def missing(self, scene: Scene) -> str | None:
        gone = _camera_gone(scene, self.camera)
        if gone is not None:
            return gone
        value = getattr(scene.camera(self.camera), self.field, None)
        shape_ok = (isinstance(value, tuple) and self.component is not None and self.component < len(value)
                    or isinstance(value, (int, float)) and self.component is None)
        if not shape_ok:
            return f"{self.camera} has no {self.field.replace('_', ' ')} any more (another kind of camera?)"
        return None

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        value = getattr(ctx.scene.camera(self.camera), self.field)
        x = float(value[self.component] if self.component is not None else value)
        name = self.field + (f"[{self.component}]" if self.component is not None else "")
        if params["low"] <= x <= params["high"]:
            return TaskResult(True, f"Done: {self.camera}'s {name} is {_fmt(x)}.")
        return TaskResult(False, f"Not yet: {self.camera}'s {name} is {_fmt(x)}; "
                                 f"it must be in {params['low']:g}..{params['high']:g}.")


def camera_xi(spec: Any) -> float:
    r"""The unified-sphere :math:`\xi` of a camera: its own ``xi``, its mirror's, or 0 for a pin-hole."""
    camera = spec.camera()
    if hasattr(camera, "xi"):
        return float(camera.xi)
    mirror = getattr(camera, "mirror", None)
    return 0.0 if mirror is None else float(mirror.xi)


@dataclass(frozen=True, kw_only=True)
class XiBetweenTask(Task):
    r"""The unified-sphere parameter :math:`\xi` of ``camera`` lies in ``low..high``."""

    camera: str
    low: float
    high: float

    kind: ClassVar[str] = "xi_between"

    def params(self) -> dict[str, Param]:
        return {"low": self.low, "high": self.high}

    def validate(self, scene: Scene) -> None:
        _camera_in(scene, self.camera)

    def missing(self, scene: Scene) -> str | None:
        return _camera_gone(scene, self.camera)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        xi = camera_xi(ctx.scene.camera(self.camera))
        if params["low"] <= xi <= params["high"]:
            return TaskResult(True, f"Done: xi = {xi:.3f}.")
        return TaskResult(False, f"Not yet: xi = {xi:.3f}; it must be in {params['low']:g}..{params['high']:g}.")


@dataclass(frozen=True, kw_only=True)
class TriangulationErrorTask(Task):
    r"""Triangulating point ``point`` from its two images, each pixel perturbed by Gaussian noise of
    ``noise_px``, gives an RMS position error of at most ``at_most`` metres (200 fixed draws):

    .. math:: \varepsilon = \sqrt{\tfrac{1}{K} \textstyle\sum_k \|\hat X_k - X\|^2} .
    """

    point: int
    noise_px: float
    at_most: float
    method: str = "linear"

    kind: ClassVar[str] = "triangulation_error"

    def params(self) -> dict[str, Param]:
        return {"point": float(point_label(self.point)), "noise_px": self.noise_px, "at_most": self.at_most}

    def validate(self, scene: Scene) -> None:
        _point_in(scene, self.point)
        pair = scene.drawn_pair
        if not _projective_pair(scene, pair):
            raise EntryError(None, f"triangulation needs a drawn pair of pin-hole cameras, got {pair}")

    def missing(self, scene: Scene) -> str | None:
        return _point_gone(scene, self.point) or _pair_gone(scene, pinhole=True)

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        err = triangulation_rms(ctx.scene, self.point, params["noise_px"], self.method)
        if not math.isfinite(err):
            return TaskResult(False, f"Point {point_label(self.point)} is not seen by both cameras.")
        msg = f"the RMS triangulation error of point {point_label(self.point)} is {err:.3g} m"
        if err <= params["at_most"]:
            return TaskResult(True, f"Done: {msg}.")
        return TaskResult(False, f"Not yet: {msg}; at most {params['at_most']:g} m allowed.")


def triangulation_rms(scene: Scene, point: int, noise_px: float, method: str = "linear", seed: int = 0) -> float:
    """RMS error (metres) of triangulating ``point`` of the drawn pin-hole pair under pixel noise (NaN if unseen)."""
    n1, n2 = scene.drawn_pair  # type: ignore[misc]
    c1, c2 = scene.camera(n1).camera(), scene.camera(n2).camera()
    if not (isinstance(c1, PinholeCamera) and isinstance(c2, PinholeCamera)):
        return math.nan
    X = scene.points_array()[point]
    p1, p2 = c1.project(X), c2.project(X)
    if not (p1.in_front[0] and p2.in_front[0]):
        return math.nan
    rng = np.random.default_rng(seed)
    u1 = p1.pixels[0] + rng.normal(0.0, noise_px, (_TRIANGULATION_DRAWS, 2))
    u2 = p2.pixels[0] + rng.normal(0.0, noise_px, (_TRIANGULATION_DRAWS, 2))
    solve = triangulate_optimal if method == "optimal" else triangulate_linear
    Xh = solve(c1.P, c2.P, u1, u2)
    return float(np.sqrt(np.mean(np.sum((Xh - X) ** 2, axis=1))))


TASK_KINDS: dict[str, type[Task]] = {
    cls.kind: cls
    for cls in (NumberTask, ChoiceTask, EpipoleNearTask, SameOrientationTask, LinesParallelTask, PointOnLineTask,
                SampsonBelowTask, InliersRecallTask, PointInImageTask, CameraFieldTask, XiBetweenTask,
                TriangulationErrorTask, ServoNumberTask)
}
"""Every task kind by its ``kind`` name."""

# -- parsing -----------------------------------------------------------------------------------------------

_COMMON = ("kind", "id", "prompt", "hint", "solution")
_KEYS: dict[str, tuple[str, ...]] = {
    "number": ("answer", "tolerance", "unit"),
    "choice": ("options", "answer"),
    "epipole_near": ("camera", "target", "within_px"),
    "same_orientation": ("cameras", "within_deg"),
    "lines_parallel": ("camera", "within_deg"),
    "point_on_line": ("point", "camera", "within_px"),
    "sampson_below": ("method", "below_px2", "against", "min_noise_px", "min_outlier_percent"),
    "inliers_recall": ("method", "at_least", "min_noise_px", "min_outlier_percent"),
    "point_in_image": ("point", "camera"),
    "camera_field": ("camera", "field", "component", "low", "high"),
    "xi_between": ("camera", "low", "high"),
    "triangulation_error": ("point", "noise_px", "at_most", "method"),
    "servo_number": ("measure", "below", "tolerance"),
}
_ID = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,39}")
# A placeholder may round its value ({u:.1f}); nothing that could build a huge string.
_FORMAT_SPEC = re.compile(r"\.\d?[fg]")


def _param(value: Any, key: str, limit: Range) -> Param:
    """``value`` as a number in ``limit``, or ``[low, high]`` inside it (a :class:`Uniform` drawn per learner);
    errors name ``key``."""
    if isinstance(value, list):
        if len(value) != 2:
            raise EntryError(key, f"expected a number or [low, high], got {fields.short(value)}")
        low, high = (fields.as_number(x, key, limit) for x in value)
        if not low < high:
            raise EntryError(key, f"expected low < high, got {fields.short(value)}")
        return Uniform(low, high, integer=all(type(x) is int for x in value))
    return fields.as_number(value, key, limit)


def _method(table: dict, robust: bool) -> str:
    method = fields.text(table, "method")
    allowed = [m for m in METHODS if not robust or m in ("ransac", "lmeds", "mestimator")]
    if method not in allowed:
        raise EntryError("method", f"expected one of {', '.join(allowed)}, got {fields.short(method)}")
    return method


def _check_prompt(prompt: str, names: set[str]) -> None:
    try:
        parsed = list(string.Formatter().parse(prompt))
    except ValueError as exc:
        raise EntryError("prompt", f"bad placeholder ({exc}); write {{{{ and }}}} for braces") from None
    for _, name, spec, conversion in parsed:
        if name is None:
            continue
        if name not in names:
            raise EntryError("prompt", f"placeholder {{{name}}}: expected one of "
                                       f"{', '.join('{' + n + '}' for n in sorted(names)) or 'none'}")
        if conversion or (spec and not _FORMAT_SPEC.fullmatch(spec)):
            raise EntryError("prompt", f"placeholder {{{name}}}: only {{{name}}} or a rounding such as "
                                       f"{{{name}:.1f}} is allowed")


def parse_task(table: Any, default_id: str) -> Task:
    """One ``[[steps.tasks]]`` table as a :class:`Task` (types and ranges checked; the names of cameras and
    points are checked against the step's scene by :meth:`Task.validate`).

    Raises:
        EntryError: naming the offending key.
    """
    if not isinstance(table, dict):
        raise EntryError(None, f"expected a table, got {fields.short(table)}")
    kind = table.get("kind")
    if type(kind) is not str or kind not in TASK_KINDS:
        raise EntryError("kind", f"unknown task kind {fields.short(kind)} (expected one of {', '.join(TASK_KINDS)})")
    fields.refuse_unknown(table, _COMMON + _KEYS[kind], f"a {kind!r} task")
    task_id = fields.text(table, "id", required=False, default=default_id)
    if not _ID.fullmatch(task_id):
        raise EntryError(
            "id", f"expected a letter then letters, digits, '_' or '-' (at most 40), got {fields.short(task_id)}"
        )
    common: dict[str, Any] = {
        "id": task_id,
        "prompt": fields.text(table, "prompt", limit=fields.MAX_TEXT, multiline=True),
        "hint": fields.text(table, "hint", required=False, limit=fields.MAX_TEXT, multiline=True),
    }
    solution = table.get("solution", [])
    if not isinstance(solution, list):
        raise EntryError("solution", f"expected a list of changes, got {fields.short(solution)}")
    try:
        common["solution"] = tuple(parse_change(c) for c in solution)
    except EntryError as exc:
        raise EntryError("solution", f"change: {exc}") from None
    task = _parse_kind(kind, table, common)
    _check_prompt(task.prompt, set(task.params()))
    for key in ("prompt", "hint"):
        try:
            render_markdown(getattr(task, key))
        except MarkupError as exc:
            raise EntryError(key, str(exc)) from None
    return task


def _parse_kind(kind: str, t: dict, common: dict[str, Any]) -> Task:
    if kind == "number":
        return NumberTask(**common, answer=fields.number(t, "answer", ANSWER),
                          tolerance=fields.number(t, "tolerance", TOLERANCE, required=False, default=0.0),
                          unit=fields.text(t, "unit", required=False))
    if kind == "choice":
        options = fields.name_list(t, "options", limit=_MAX_OPTIONS)
        if len(options) < 2 or len(set(options)) != len(options):
            raise EntryError("options", "expected at least two different options")
        answer = fields.text(t, "answer")
        if answer not in options:
            raise EntryError("answer", f"expected one of the options, got {fields.short(answer)}")
        return ChoiceTask(**common, options=options, answer=answer)
    if kind == "epipole_near":
        target = t.get("target")
        if not isinstance(target, dict) or set(target) != {"u", "v"}:
            raise EntryError(
                "target", f"expected {{ u = ..., v = ... }} (numbers or [low, high]), got {fields.short(target)}"
            )
        return EpipoleNearTask(**common, camera=fields.text(t, "camera"),
                               u=_param(target["u"], "target", PRINCIPAL_POINT),
                               v=_param(target["v"], "target", PRINCIPAL_POINT),
                               within_px=fields.number(t, "within_px", WITHIN_PX))
    if kind == "same_orientation":
        cams = fields.name_list(t, "cameras")
        if len(cams) != 2 or cams[0] == cams[1]:
            raise EntryError("cameras", f"expected two different camera names, got {fields.short(list(cams))}")
        return SameOrientationTask(**common, cameras=cams, within_deg=fields.number(t, "within_deg", WITHIN_DEG))  # type: ignore[arg-type]
    if kind == "lines_parallel":
        return LinesParallelTask(**common, camera=fields.text(t, "camera"),
                                 within_deg=fields.number(t, "within_deg", WITHIN_DEG))
    if kind == "point_on_line":
        return PointOnLineTask(**common, point=fields.whole(t, "point", _POINT), camera=fields.text(t, "camera"),
                               within_px=fields.number(t, "within_px", WITHIN_PX))
    if kind in ("sampson_below", "inliers_recall"):
        extra = dict(
            min_noise_px=fields.number(t, "min_noise_px", LAB_NOISE_PX, required=False, default=0.0),
            min_outlier_percent=fields.number(t, "min_outlier_percent", LAB_OUTLIER_PERCENT, required=False,
                                              default=0.0),
        )
        if kind == "sampson_below":
            against = fields.text(t, "against", required=False, default="true")
            if against not in ("true", "measured"):
                raise EntryError("against", f"expected 'true' or 'measured', got {fields.short(against)}")
            return SampsonBelowTask(**common, **extra, method=_method(t, robust=False), against=against,
                                    below_px2=fields.number(t, "below_px2", SAMPSON_PX2))
        return InliersRecallTask(**common, **extra, method=_method(t, robust=True),
                                 at_least=fields.number(t, "at_least", FRACTION))
    if kind == "point_in_image":
        return PointInImageTask(**common, point=fields.whole(t, "point", _POINT), camera=fields.text(t, "camera"))
    if kind == "camera_field":
        low = fields.number(t, "low", ANSWER)
        high = fields.number(t, "high", ANSWER)
        if not low <= high:
            raise EntryError("high", f"expected high >= low ({low:g}), got {high:g}")
        component = fields.whole(t, "component", _COMPONENT, required=False)
        return CameraFieldTask(**common, camera=fields.text(t, "camera"), field=fields.text(t, "field"),
                               low=low, high=high, component=component)
    if kind == "xi_between":
        low = fields.number(t, "low", FRACTION)
        high = fields.number(t, "high", FRACTION)
        if not low <= high:
            raise EntryError("high", f"expected high >= low ({low:g}), got {high:g}")
        return XiBetweenTask(**common, camera=fields.text(t, "camera"), low=low, high=high)
    if kind == "servo_number":
        measure = fields.text(t, "measure")
        if measure not in MEASURES:
            raise EntryError("measure", f"expected one of {', '.join(MEASURES)}, got {fields.short(measure)}")
        below_unit = MEASURES[measure].below_unit
        if bool(below_unit) != ("below" in t):
            raise EntryError("below", f"{measure!r} needs 'below' (in {below_unit})" if below_unit
                             else f"{measure!r} takes no 'below'")
        below = fields.number(t, "below", _BELOW[below_unit]) if below_unit else None
        return ServoNumberTask(**common, measure=measure, below=below,
                               tolerance=fields.number(t, "tolerance", TOLERANCE, required=False, default=0.0))
    method = fields.text(t, "method", required=False, default="linear")
    if method not in ("linear", "optimal"):
        raise EntryError("method", f"expected 'linear' or 'optimal', got {fields.short(method)}")
    return TriangulationErrorTask(**common, point=fields.whole(t, "point", _POINT),
                                  noise_px=fields.number(t, "noise_px", LAB_NOISE_PX),
                                  at_most=fields.number(t, "at_most", DEPTH_ERROR), method=method)
