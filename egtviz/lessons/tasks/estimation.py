"""Tasks about estimating from noisy pixels: the estimation lab's fits (:class:`SampsonBelowTask`,
:class:`InliersRecallTask`) and triangulation under pixel noise (:class:`TriangulationErrorTask`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, TypedDict, cast

import numpy as np

from ...geometry import PinholeCamera
from ...geometry.error_metrics import sampson_distance
from ...geometry.triangulation import triangulate_linear, triangulate_optimal
from ...scene import Scene
from ...scene.lab import METHODS, FitResult, LabResult
from ...scene.limits import LAB_NOISE_PX, LAB_OUTLIER_PERCENT
from .. import fields
from ..errors import EntryError
from .base import Param, Task, TaskContext, TaskResult
from .common import (
    DEPTH_ERROR,
    FRACTION,
    POINT_INDEX,
    SAMPSON_PX2,
    pair_gone,
    point_gone,
    point_in,
    point_label,
    projective_pair,
)
from .needs import LabNeeds, TaskNeeds

__all__ = ["DEFAULT_MIN_PRECISION", "InliersRecallTask", "SampsonBelowTask", "TriangulationErrorTask",
           "default_max_sampson_px2", "held_out_correspondences", "triangulation_rms"]

_TRIANGULATION_DRAWS = 200
DEFAULT_MIN_PRECISION = 0.9
"""Share of a recall task's marked inliers that must be true inliers, unless its ``min_precision`` says."""
_LAB_KEYS = ("min_noise_px", "min_outlier_percent")
_HELD_OUT_GRID = (7, 5)
"""Columns and rows of the held-out pixels in image 1, from 10 % to 90 % of its width and height."""
_HELD_OUT_DEPTHS = (0.5, 1.0, 2.0)
"""Depths of the held-out points along each pixel's ray, as multiples of the median depth of the lab's points."""


class _LabMinimums(TypedDict):
    min_noise_px: float
    min_outlier_percent: float


def _lab_minimums(table: dict) -> _LabMinimums:
    """The lab settings the learner must keep at least (``min_noise_px``, ``min_outlier_percent``; 0 if absent)."""
    return _LabMinimums(
        min_noise_px=fields.number(table, "min_noise_px", LAB_NOISE_PX, required=False, default=0.0),
        min_outlier_percent=fields.number(table, "min_outlier_percent", LAB_OUTLIER_PERCENT, required=False,
                                          default=0.0),
    )


def _method(table: dict, robust: bool) -> str:
    method = fields.text(table, "method")
    allowed = [m for m in METHODS if not robust or m in ("ransac", "lmeds", "mestimator")]
    if method not in allowed:
        raise EntryError("method", f"expected one of {', '.join(allowed)}, got {fields.short(method)}")
    return method


def _lab_scene(scene: Scene) -> None:
    pair = scene.drawn_pair
    if not projective_pair(scene, pair):
        raise EntryError(None, f"the estimation lab needs a drawn pair of pin-hole cameras, got {pair}")


def _lab_constraints(ctx: TaskContext, min_noise: float, min_outliers: float) -> TaskResult | None:
    if ctx.lab.noise_px < min_noise:
        return TaskResult(False, f"Keep the noise at {min_noise:g} px or more (it is {ctx.lab.noise_px:g} px).")
    if ctx.lab.outlier_percent < min_outliers:
        return TaskResult(
            False, f"Keep the outliers at {min_outliers:g} % or more (they are {ctx.lab.outlier_percent:g} %)."
        )
    return None


class _LabFitJudged:
    """What a task judged on the lab's fit by ``method`` shares, once the lab has the noise and outliers it asks for
    (a mixin before :class:`Task`: the fields are the task's)."""

    method: str
    min_noise_px: float
    min_outlier_percent: float

    def validate(self, scene: Scene) -> None:
        _lab_scene(scene)

    def missing(self, scene: Scene) -> str | None:
        return pair_gone(scene, pinhole=True)

    def _fit(self, ctx: TaskContext) -> tuple[LabResult, FitResult] | TaskResult:
        """The lab's result and its fit by ``method``, or the result that refuses the check (the lab lacks noise or
        outliers, or the fit failed)."""
        refused = _lab_constraints(ctx, self.min_noise_px, self.min_outlier_percent)
        if refused is not None:
            return refused
        lab = ctx.lab_result()
        fit = lab.fit(self.method)
        if fit.F is None:
            return TaskResult(False, f"{fit.title} failed: {fit.message}")
        return lab, fit


@dataclass(frozen=True, kw_only=True)
class SampsonBelowTask(_LabFitJudged, Task):
    """The lab's ``method`` has a mean Sampson error below ``below_px2`` (``against`` the true or the measured
    pixels of the true inliers), with the lab's noise and outliers at least the given minimum."""

    method: str
    below_px2: float
    against: str = "true"
    min_noise_px: float = 0.0
    min_outlier_percent: float = 0.0
    held_out_below_px2: float | None = None
    """Also required: the fit's mean Sampson error on :func:`held_out_correspondences` (None: not judged)."""

    kind: ClassVar[str] = "sampson_below"
    table_keys: ClassVar[tuple[str, ...]] = ("method", "below_px2", "against", "held_out_below_px2", *_LAB_KEYS)

    @property
    def needs(self) -> TaskNeeds:
        return TaskNeeds(lab=LabNeeds())

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> SampsonBelowTask:
        minimums = _lab_minimums(table)
        against = fields.text(table, "against", required=False, default="true")
        if against not in ("true", "measured"):
            raise EntryError("against", f"expected 'true' or 'measured', got {fields.short(against)}")
        return cls(**common, **minimums, method=_method(table, robust=False), against=against,
                   below_px2=fields.number(table, "below_px2", SAMPSON_PX2),
                   held_out_below_px2=fields.number(table, "held_out_below_px2", SAMPSON_PX2, required=False))

    def params(self) -> dict[str, Param]:
        if self.held_out_below_px2 is None:
            return {"below_px2": self.below_px2}
        return {"below_px2": self.below_px2, "held_out_below_px2": self.held_out_below_px2}

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        got = self._fit(ctx)
        if isinstance(got, TaskResult):
            return got
        _, fit = got
        err = fit.sampson_true if self.against == "true" else fit.sampson_noisy
        msg = f"{fit.title}'s mean Sampson error is {err:.3g} px^2"
        if not err < params["below_px2"]:
            return TaskResult(False, f"Not yet: {msg}; it must be below {params['below_px2']:g} px^2.")
        if self.held_out_below_px2 is None:
            return TaskResult(True, f"Done: {msg}.")
        u1, u2 = held_out_correspondences(ctx.scene, ctx.lab_result())
        held = float(np.mean(sampson_distance(cast(np.ndarray, fit.F), u1, u2))) if len(u1) else math.inf
        where = f"on {len(u1)} held-out true correspondences spread over both images"
        if held < params["held_out_below_px2"]:
            return TaskResult(True, f"Done: {msg} on your points and {held:.3g} px^2 {where}.")
        return TaskResult(False, f"Not yet: {msg} on your points, but {held:.3g} px^2 {where} (it must be below "
                                 f"{params['held_out_below_px2']:g} px^2). A fit is only as good as the spread of "
                                 "its data: points that cover little of the images and of the depths pin F down "
                                 "only there.")


@dataclass(frozen=True, kw_only=True)
class InliersRecallTask(_LabFitJudged, Task):
    """The lab's robust ``method`` marks at least ``at_least`` of the true inliers as inliers, and its fit is not
    ruined: at most ``1 - min_precision`` of what it marks are outliers, and the mean Sampson error of its ``F``
    against the true pixels is at most ``max_sampson_px2`` (default :func:`default_max_sampson_px2` of the
    lab's noise). A loose threshold keeps every inlier and lets the outliers vote: recall alone would pass it."""

    method: str
    at_least: float
    min_noise_px: float = 0.0
    min_outlier_percent: float = 0.0
    min_precision: float = DEFAULT_MIN_PRECISION
    max_sampson_px2: float | None = None
    """None: :func:`default_max_sampson_px2` of the lab's noise at the check."""

    kind: ClassVar[str] = "inliers_recall"
    table_keys: ClassVar[tuple[str, ...]] = ("method", "at_least", "min_precision", "max_sampson_px2", *_LAB_KEYS)

    @property
    def needs(self) -> TaskNeeds:
        # RANSAC whichever robust fit the task judges: the lab's threshold slider is RANSAC's tau.
        return TaskNeeds(lab=LabNeeds(draws="ransac"))

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> InliersRecallTask:
        minimums = _lab_minimums(table)
        return cls(**common, **minimums, method=_method(table, robust=True),
                   at_least=fields.number(table, "at_least", FRACTION),
                   min_precision=fields.number(table, "min_precision", FRACTION, required=False,
                                               default=DEFAULT_MIN_PRECISION),
                   max_sampson_px2=fields.number(table, "max_sampson_px2", SAMPSON_PX2, required=False))

    def params(self) -> dict[str, Param]:
        return {"at_least": self.at_least, "at_least_percent": 100.0 * self.at_least}

    def judge(self, ctx: TaskContext, params: dict[str, float]) -> TaskResult:
        got = self._fit(ctx)
        if isinstance(got, TaskResult):
            return got
        lab, fit = got
        msg = f"{fit.title} marks {100 * fit.inlier_recall:.0f} % of the true inliers as inliers"
        if fit.inlier_recall < params["at_least"]:
            return TaskResult(False, f"Not yet: {msg}; at least {100 * params['at_least']:g} % needed.")
        inliers = cast(np.ndarray, fit.inliers)  # the task's method is robust: its fit has an inlier mask
        marked = int(np.count_nonzero(inliers))
        wrong = int(np.count_nonzero(inliers & lab.data.outlier))
        precision = 1.0 - wrong / marked if marked else 0.0
        if precision < self.min_precision:
            return TaskResult(False, f"Not yet: {msg}, but {wrong} of the {marked} it marks are outliers "
                                     f"({100 * (1 - precision):.0f} %; at most {100 * (1 - self.min_precision):g} %): "
                                     "the threshold lets mismatches vote.")
        bound = self.max_sampson_px2 if self.max_sampson_px2 is not None else default_max_sampson_px2(ctx.lab.noise_px)
        if not fit.sampson_true <= bound:
            return TaskResult(False, f"Not yet: {msg}, but its F is ruined: mean Sampson error {fit.sampson_true:.3g} "
                                     f"px^2 against the true points (at most {bound:.3g} px^2).")
        return TaskResult(True, f"Done: {msg}, {100 * precision:.0f} % of its inliers are true ones and its mean "
                                f"Sampson error is {fit.sampson_true:.3g} px^2.")


def held_out_correspondences(scene: Scene, lab: LabResult) -> tuple[np.ndarray, np.ndarray]:
    """True correspondences the lab's fits never see, spread over both images: a grid of pixels of image 1
    (:data:`_HELD_OUT_GRID`) each at the depths :data:`_HELD_OUT_DEPTHS`, projected into image 2 and kept where
    in front of both cameras and inside image 2.

    Returns:
        ``(u1, u2)``, each ``(N, 2)`` pixels (N may be 0).
    """
    c1, c2 = (scene.camera(n).camera() for n in lab.names)
    if not (isinstance(c1, PinholeCamera) and isinstance(c2, PinholeCamera)):  # the lab runs on pin-hole pairs only
        return np.zeros((0, 2)), np.zeros((0, 2))
    cols, rows = _HELD_OUT_GRID
    u, v = np.meshgrid(np.linspace(0.1, 0.9, cols) * c1.width, np.linspace(0.1, 0.9, rows) * c1.height)
    m = np.column_stack([u.ravel(), v.ravel(), np.ones(u.size)])
    M = c1.P[:, :3]
    # Rows of inv(M) m: the ray of each pixel scaled to depth 1 (third row of M is the optical axis).
    rays = np.linalg.solve(M, m.T).T
    rays /= (rays @ M[2])[:, None]
    depth = float(np.median((scene.points_array()[lab.data.point_indices] - c1.centre) @ M[2]))
    X = np.concatenate([c1.centre + k * depth * rays for k in _HELD_OUT_DEPTHS])
    p1, p2 = c1.project(X), c2.project(X)
    inside = (p2.pixels[:, 0] >= 0) & (p2.pixels[:, 0] <= c2.width) & (p2.pixels[:, 1] >= 0) \
        & (p2.pixels[:, 1] <= c2.height)
    keep = p1.in_front & p2.in_front & inside
    return p1.pixels[keep], p2.pixels[keep]


def default_max_sampson_px2(noise_px: float) -> float:
    """The worst mean Sampson error (px^2, against the true pixels) a recall task accepts by default: four times
    the noise variance, and at least 0.1 px^2 (a fit from noisy pixels is never exact)."""
    return max(4.0 * noise_px**2, 0.1)


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
    table_keys: ClassVar[tuple[str, ...]] = ("point", "noise_px", "at_most", "method")

    @classmethod
    def from_table(cls, table: dict, common: dict[str, Any]) -> TriangulationErrorTask:
        method = fields.text(table, "method", required=False, default="linear")
        if method not in ("linear", "optimal"):
            raise EntryError("method", f"expected 'linear' or 'optimal', got {fields.short(method)}")
        return cls(**common, point=fields.whole(table, "point", POINT_INDEX),
                   noise_px=fields.number(table, "noise_px", LAB_NOISE_PX),
                   at_most=fields.number(table, "at_most", DEPTH_ERROR), method=method)

    def params(self) -> dict[str, Param]:
        return {"point": float(point_label(self.point)), "noise_px": self.noise_px, "at_most": self.at_most}

    def validate(self, scene: Scene) -> None:
        point_in(scene, self.point)
        pair = scene.drawn_pair
        if not projective_pair(scene, pair):
            raise EntryError(None, f"triangulation needs a drawn pair of pin-hole cameras, got {pair}")

    def missing(self, scene: Scene) -> str | None:
        return point_gone(scene, self.point) or pair_gone(scene, pinhole=True)

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
