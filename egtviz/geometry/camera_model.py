r"""Central camera models as one unit: the interface every model implements, and the registry of models.

A *central* camera has a single viewpoint, its centre: every pixel is the image of one ray from the
centre, and a plane through the centre images to one curve (a line for the pin-hole, a conic for the
sphere models). Everything the rest of egtviz needs from a camera goes through :class:`CameraModel`:

- ``project(X_world)``: pixels (N, 2), NaN where a point has no image, and the masks ``visible`` (the
  point has an image) and ``in_image`` (visible and inside ``[0, width] x [0, height]``);
- ``back_project(pixels)``: the unit world rays (N, 3) that image at the pixels;
- ``baseline_images(direction)``: the images of the line through the centre with that world direction
  (one point for the pin-hole, the two rays :math:`\pm d` for sphere models), with visibility flags; for
  the line towards another camera's centre these are the epipoles;
- ``plane_image_conics(normals)`` / ``plane_image_lines(normals)``: the exact image of each plane
  :math:`n \cdot (X - c) = 0` through the centre, a symmetric conic :math:`m^T C m = 0` (the double line
  :math:`l l^T` for the pin-hole; None when the model does not image planes to conics) and a line
  :math:`l \cdot m = 0` (None when the model does not image planes to lines);
- ``light_paths(X_world)``: the light's way from each point to the sensor, as world polylines (3D drawing);
- ``projective_calibration``: :math:`K` when the model images linearly (a pin-hole), else None;
- ``no_image``: where the points without an image are, in a few words;
- ``plane_image_arcs(normals, n_samples)``: the same images sampled as polylines, only the arcs the camera
  really shows, inside its drawn image region;
- ``rim(n)``: the boundary of that region as a closed polyline;
- ``PARAMETERS``, ``parameters()``, ``from_parameters(pose, **values)``: the model's scalar parameters with
  their ranges; ``pose``, ``centre``, ``moved(pose)``, ``width``, ``height``.

The methods a drag calls (``project``, ``light_paths``, ``baseline_images``, ``plane_image_conics``,
``plane_image_lines``, ``plane_image_arcs``) take a keyword ``check`` (default True): ``check=False`` skips the
conversion and checks of arguments the caller has checked once (float64 arrays of the documented shapes, finite;
normals finite or all NaN), with the same arithmetic; anything else gives an undefined result
(``docs/conventions.md``, "Checked at the edge, fast inside").

:data:`CAMERA_MODELS` maps each kind name to a :class:`CameraModelInfo` (its class, label and parameter
ranges), one registration line per model. How to add a model: ``docs/camera_models.md``.

The models are :class:`~egtviz.geometry.pinhole.PinholeCamera`, :class:`~egtviz.geometry.catadioptric.CatadioptricCamera`
(two kinds, ``hyperbolic`` and ``parabolic``, one per mirror shape), :class:`~egtviz.geometry.unified.UnifiedCamera`
and every model registered below.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, TypeVar, cast, runtime_checkable

import numpy as np
import numpy.typing as npt

from ._validate import (
    GeometryError,
    to_float64,
    as_count,
    as_scalar,
    as_vector,
    short_repr,
)
from .poses import Pose

CameraT = TypeVar("CameraT")

__all__ = [
    "CAMERA_MODELS",
    "IMAGE_SIZE_PARAMETERS",
    "PRINCIPAL_POINT_PARAMETERS",
    "CameraModel",
    "CameraModelInfo",
    "CameraProjection",
    "DirectionImages",
    "ParameterSpec",
    "Projection",
    "arc_normals",
    "as_direction",
    "as_normals",
    "camera_from_parameters",
    "camera_model_info",
    "check_parameters",
    "check_pose",
    "check_sample_count",
    "double_line_conics",
    "finite_nonzero_rows",
    "normals_with_planes",
    "parameter_values",
    "parameters_from_specs",
    "rectangle_rim",
    "unchecked_normals",
]


@dataclass(frozen=True)
class ParameterSpec:
    """One scalar parameter of a camera model: its name, unit and accepted range.

    Raises:
        GeometryError: if the range is empty or the default lies outside it.
    """

    name: str
    """Keyword of ``from_parameters`` and key of ``parameters()``."""
    label: str
    """Short human-readable name (for a UI field)."""
    unit: str
    """Unit of the value (``""`` for a pure number)."""
    min: float
    """Smallest accepted value (inclusive)."""
    max: float
    """Largest accepted value (inclusive)."""
    default: float
    """Value used when none is given."""
    integer: bool = False
    """The value is a whole number (image sizes)."""

    def __post_init__(self) -> None:
        if not self.name:
            raise GeometryError("name: expected a non-empty parameter name")
        if not (math.isfinite(self.min) and math.isfinite(self.max) and self.min <= self.max):
            raise GeometryError(f"{self.name}: expected a finite range min <= max, got [{self.min:g}, {self.max:g}]")
        if not self.min <= self.default <= self.max:
            raise GeometryError(f"{self.name}: default {self.default:g} outside [{self.min:g}, {self.max:g}]")

    def check(self, value: object) -> float | int:
        """``value`` as a float (an int for integer parameters) inside ``[min, max]``, or a GeometryError naming it."""
        unit = f" {self.unit}" if self.unit else ""
        expected = f"{'a whole number' if self.integer else 'a number'} in [{self.min:g}, {self.max:g}]{unit}"
        try:
            x = as_scalar(value, self.name, max_abs=None)  # refuses booleans, strings, None, NaN, inf
        except GeometryError as exc:
            raise GeometryError(f"{self.name}: expected {expected}, got {short_repr(value)}") from exc
        if not (self.min <= x <= self.max) or (self.integer and x != int(x)):
            raise GeometryError(f"{self.name}: expected {expected}, got {short_repr(value)}")
        return int(x) if self.integer else x


def parameters_from_specs(specs: tuple[ParameterSpec, ...], values: Mapping[str, object]) -> dict[str, float | int]:
    """Every parameter of ``specs``, checked: the given ``values`` and the defaults for the rest.

    Raises:
        GeometryError: on an unknown name or a value outside its range.
    """
    known = {s.name for s in specs}
    unknown = sorted(set(values) - known)
    if unknown:
        raise GeometryError(f"{unknown[0]}: unknown parameter, expected one of {sorted(known)}")
    return {s.name: s.check(values.get(s.name, s.default)) for s in specs}


@dataclass(frozen=True, eq=False)
class CameraProjection:
    """Result of projecting N world points into a camera model."""

    pixels: np.ndarray
    """(N, 2) pixels; NaN where not ``visible``."""
    visible: np.ndarray
    """(N,) bool: the point has an image."""
    in_image: np.ndarray
    """(N,) bool: ``visible`` and inside ``[0, width] x [0, height]``."""


@dataclass(frozen=True, eq=False)
class DirectionImages:
    """Images of the line through a camera's centre along one world direction (the epipoles of a baseline)."""

    points: np.ndarray
    """(k, 3) homogeneous pixels (last coordinate 1, or unit norm with last coordinate 0 at infinity); row 0 is the
    image of the ray towards ``+d``. A sphere model has two rows (``+d`` and ``-d``), given even where the camera
    does not show them (every image of a plane containing the line passes through them); a pin-hole has one."""
    visible: np.ndarray
    """(k,) bool: the camera really shows that image (the ray is in front / seen by the mirror)."""


@runtime_checkable
class Projection(Protocol):
    """What ``CameraModel.project`` returns: pixels and the two masks (read-only: results are frozen)."""

    @property
    def pixels(self) -> np.ndarray:
        """(N, 2) pixels; NaN where not ``visible``."""
        ...

    @property
    def visible(self) -> np.ndarray:
        """(N,) bool: the point has an image."""
        ...

    @property
    def in_image(self) -> np.ndarray:
        """(N,) bool: ``visible`` and inside the image."""
        ...


@runtime_checkable
class CameraModel(Protocol):
    """A central camera model (see the module docstring). Instances are immutable: moving returns a new one.

    ``kind`` and ``PARAMETERS`` are class attributes for a model class with one kind (pin-hole, unified) and
    properties of the instance for one with several (the catadioptric camera: its mirror decides).
    """

    # Read-only members (properties here): a model is a frozen dataclass, and a class attribute or a property of the
    # instance satisfies each of them alike.
    @property
    def kind(self) -> str:
        """The registry key of the model."""
        ...

    @property
    def PARAMETERS(self) -> tuple[ParameterSpec, ...]:  # noqa: N802 - the models' class attribute
        """The model's scalar parameters and their accepted ranges."""
        ...

    @property
    def no_image(self) -> str:
        """Where the points lie that have no image, in a few words (``"behind the camera"``)."""
        ...

    @property
    def pose(self) -> Pose:
        """The camera's pose in the world."""
        ...

    @property
    def width(self) -> int:
        """Image width in pixels."""
        ...

    @property
    def height(self) -> int:
        """Image height in pixels."""
        ...

    @property
    def centre(self) -> np.ndarray:
        """(3,) the single viewpoint in world coordinates."""
        ...

    @property
    def projective_calibration(self) -> np.ndarray | None:
        r"""(3, 3) :math:`K` when every visible point images at :math:`m \sim K R^T (X - c)` (a pin-hole camera: then
        pixels of two such cameras obey :math:`m_2^T F m_1 = 0`), else None."""
        ...

    def from_parameters(self, pose: Pose, **values: float) -> CameraModel:
        """A model of this kind at ``pose`` with the given parameters (defaults for the others)."""
        ...

    def parameters(self) -> dict[str, float | int]:
        """Current value of every parameter in ``PARAMETERS``."""
        ...

    def moved(self, pose: Pose) -> CameraModel:
        """The same camera at another pose: the fast path for a drag (only the pose is new and checked)."""
        ...

    def project(self, X_world: npt.ArrayLike, *, check: bool = True) -> Projection:
        """Project world points (N, 3)."""
        ...

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        """Unit world rays (N, 3) of pixels (N, 2); NaN rows for pixels that are no ray's image."""
        ...

    def light_paths(self, X_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        """(N, k, 3) world polylines of the light from each point to the sensor (point, ..., sensor end); NaN
        rows for points that have no image."""
        ...

    def baseline_images(self, direction_world: npt.ArrayLike, *, check: bool = True) -> DirectionImages:
        """Images of the line through the centre along ``direction_world`` (3,)."""
        ...

    def plane_image_conics(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray | None:
        """Exact image conics (N, 3, 3) of planes through the centre, unit Frobenius norm; NaN rows for zero or
        NaN normals; None if the model does not image planes to conics (its arcs are sampled)."""
        ...

    def plane_image_lines(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray | None:
        """Exact image lines (N, 3) of planes through the centre; None if the model does not image planes to
        lines."""
        ...

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96, *,
                         check: bool = True) -> Sequence[Sequence[np.ndarray]]:
        """Per normal, a sequence (list or tuple) of the visible arcs (k, 2) of the plane's image inside the drawn
        region (empty: none)."""
        ...

    def rim(self, n: int = 128) -> np.ndarray:
        """Closed polyline (M, 2) (first point repeated) bounding the region the arcs are drawn in."""
        ...


def double_line_conics(lines: np.ndarray) -> np.ndarray:
    r"""Degenerate conics :math:`C = l l^T / |l|^2` (N, 3, 3) of lines (N, 3): the line counted twice.

    :math:`m^T C m = (l \cdot m)^2 / |l|^2`, so the conic vanishes exactly on the line; it is the
    :math:`\xi \to 0` limit of the sphere models' plane conics. NaN rows stay NaN.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = lines / np.linalg.norm(lines, axis=1, keepdims=True)
    return unit[:, :, None] * unit[:, None, :]


def rectangle_rim(width: int, height: int) -> np.ndarray:
    """The closed polyline (5, 2) of the image rectangle ``[0, width] x [0, height]``."""
    w, h = float(width), float(height)
    return np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h], [0.0, 0.0]])


MAX_SAMPLES = 100_000
"""Most samples of one curve or rim."""


def check_sample_count(n: int, name: str, minimum: int) -> int:
    """``n`` as an int in ``minimum..MAX_SAMPLES``, or a GeometryError naming ``name``."""
    try:
        return as_count(n, name, minimum=minimum, maximum=MAX_SAMPLES)
    except GeometryError as exc:
        raise GeometryError(f"{name}: expected an integer >= {minimum} and <= {MAX_SAMPLES}, got "
                            f"{short_repr(n)}") from exc


def finite_nonzero_rows(normals: np.ndarray) -> np.ndarray:
    """Indices of the rows that are finite and non-zero."""
    return np.flatnonzero(np.all(np.isfinite(normals), axis=1) & np.any(normals != 0.0, axis=1))


def check_pose(pose: object) -> Pose:
    """``pose`` if it is a :class:`Pose`, else a GeometryError naming ``pose``."""
    if not isinstance(pose, Pose):
        raise GeometryError(f"pose: expected a Pose, got {type(pose).__name__}")
    return pose


def as_direction(direction_world: npt.ArrayLike) -> np.ndarray:
    """A finite non-zero (3,) direction, or a GeometryError naming ``direction_world``."""
    d = as_vector(direction_world, "direction_world", 3)
    if not np.linalg.norm(d) > 0:
        raise GeometryError("direction_world: a zero vector has no direction")
    return d


def as_normals(normals_world: npt.ArrayLike) -> np.ndarray:
    """Plane normals, defined up to scale, as (N, 3) float64 rows (a (3,) normal is N = 1), each finite row divided
    by its largest absolute entry (so any finite magnitude works).

    A row with a NaN entry is allowed and stays all NaN: a point on a baseline has no epipolar plane, and its
    conic, line and arcs are then NaN or empty. A zero row likewise has no plane. Everything else that is not
    real numbers (booleans, strings, None, inf, a wrong shape) is a GeometryError naming ``normals_world``.
    """
    return normals_with_planes(normals_world)[0]


def normals_with_planes(normals_world: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """:func:`as_normals`, and the indices of the rows that define a plane (finite and non-zero)."""
    n = to_float64(normals_world, "normals_world")
    if n.ndim == 1 and n.shape[0] == 3:
        n = n[None, :]
    if n.ndim != 2 or n.shape[1] != 3:
        raise GeometryError(f"normals_world: expected shape (N, 3) or (3,), got {n.shape}")
    with np.errstate(invalid="ignore"):
        top = np.abs(n).max(axis=1) if n.size else np.ones(0)
    if np.isinf(top).any():
        raise GeometryError("normals_world: contains inf")
    good = top > 0  # False for NaN rows and zero rows
    if good.all():
        return n / top[:, None], np.arange(len(n))
    nan_rows = np.isnan(top)
    top[~good] = 1.0
    out = n / top[:, None]
    out[nan_rows] = np.nan
    return out, np.flatnonzero(good)


def arc_normals(normals_world: npt.ArrayLike, n_samples: int, check: bool) -> tuple[np.ndarray, int]:
    """The normals and sample count of a model's ``plane_image_arcs``: checked (:func:`as_normals`,
    :func:`check_sample_count` in ``3..MAX_SAMPLES``), or with ``check=False`` taken as promised
    (:func:`unchecked_normals`)."""
    if check:
        n_samples = check_sample_count(n_samples, "n_samples", 3)
        return as_normals(normals_world), n_samples
    return unchecked_normals(cast(np.ndarray, normals_world)), n_samples


def check_parameters(camera: object, names: Sequence[str]) -> None:
    """Check a frozen camera's fields ``names`` and its ``principal_point`` against its ``PARAMETERS``, setting each
    to its checked value; a GeometryError names the first field outside its range."""
    specs = {s.name: s for s in getattr(camera, "PARAMETERS")}
    for name in names:
        object.__setattr__(camera, name, specs[name].check(getattr(camera, name)))
    point = getattr(camera, "principal_point")
    try:
        u0, v0 = point
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"principal_point: expected (u0, v0), got {point!r}") from exc
    object.__setattr__(camera, "principal_point", (specs["u0"].check(u0), specs["v0"].check(v0)))


def parameter_values(camera: object) -> dict[str, float | int]:
    """A camera's parameters in the order of its ``PARAMETERS``, ``u0`` and ``v0`` read from its
    ``principal_point``."""
    u0, v0 = getattr(camera, "principal_point")
    point = {"u0": u0, "v0": v0}
    return {s.name: point[s.name] if s.name in point else getattr(camera, s.name)
            for s in getattr(camera, "PARAMETERS")}


def camera_from_parameters(cls: Callable[..., CameraT], specs: tuple[ParameterSpec, ...], pose: Pose,
                           values: Mapping[str, object]) -> CameraT:
    """A camera built by ``cls`` at ``pose`` from parameter ``values`` checked against ``specs``: each parameter a
    field of its name, but ``u0``, ``v0`` (the ``principal_point``) and whole-pixel ``width``, ``height``."""
    p = parameters_from_specs(specs, values)
    fields = {s.name: p[s.name] for s in specs if s.name not in ("u0", "v0", "width", "height")}
    return cls(pose, **fields, principal_point=(p["u0"], p["v0"]), width=int(p["width"]), height=int(p["height"]))


def unchecked_normals(normals_world: np.ndarray) -> np.ndarray:
    """:func:`as_normals` of a float64 (N, 3) array whose rows are finite or all NaN, unchecked: each row divided by
    its largest absolute entry (the same arithmetic), zero and NaN rows NaN. The ``check=False`` path of the
    models' plane images."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return normals_world / np.maximum.reduce(np.abs(normals_world), axis=1, keepdims=True)


IMAGE_SIZE_PARAMETERS = (
    ParameterSpec("width", "width", "px", 1, 8192, 640, integer=True),
    ParameterSpec("height", "height", "px", 1, 8192, 480, integer=True),
)
"""Image width and height, whole pixels, shared by every model."""
PRINCIPAL_POINT_PARAMETERS = (
    ParameterSpec("u0", "principal point u0", "px", -100_000.0, 100_000.0, 320.0),
    ParameterSpec("v0", "principal point v0", "px", -100_000.0, 100_000.0, 240.0),
)
"""The principal point (u0, v0), shared by every model."""


# ------------------------------------------------------------------------------------------------ registry
@dataclass(frozen=True)
class CameraModelInfo:
    """One registered camera model: its kind, label and model type (imported on first use)."""

    kind: str
    """Registry key, the model's ``kind``."""
    label: str
    """Name shown to people."""
    target: str
    """``"package.module:name"`` of the model type: a class implementing :class:`CameraModel`, or an object with its
    ``kind``, ``PARAMETERS`` and ``from_parameters`` (the catadioptric kinds, one per mirror shape)."""

    @property
    def cls(self) -> Any:
        """The model type (imported on first use, so that model modules may import this one; then remembered)."""
        found = _TYPES.get(self)
        if found is None:
            module, _, name = self.target.partition(":")
            found = getattr(importlib.import_module(module), name)
            if getattr(found, "kind", None) != self.kind:
                raise GeometryError(f"{self.target}: its kind {getattr(found, 'kind', None)!r} is not {self.kind!r}")
            _TYPES[self] = found
        return found

    @property
    def parameters(self) -> tuple[ParameterSpec, ...]:
        """The model's parameter specs (``cls.PARAMETERS``)."""
        return self.cls.PARAMETERS

    def parameter(self, name: str) -> ParameterSpec:
        """The spec of parameter ``name``, or a GeometryError naming it."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise GeometryError(f"{name}: not a parameter of the {self.kind} model")

    def build(self, pose: Pose, **values: float) -> CameraModel:
        """``cls.from_parameters(pose, **values)``."""
        return self.cls.from_parameters(pose, **values)


CAMERA_MODELS: dict[str, CameraModelInfo] = {}
"""Every camera model by kind name; one :func:`_register` line per model below."""
_TYPES: dict[CameraModelInfo, Any] = {}
"""The imported model type of each registry entry."""


def camera_model_info(camera: CameraModel) -> CameraModelInfo:
    """The registry entry of ``camera`` (by its ``kind``), or a GeometryError."""
    info = CAMERA_MODELS.get(getattr(camera, "kind", None))  # type: ignore[arg-type]
    if info is None:
        raise GeometryError(f"camera: expected a registered camera model, got {type(camera).__name__}")
    return info


def _register(kind: str, label: str, target: str) -> None:
    if kind in CAMERA_MODELS:
        raise GeometryError(f"kind: {kind!r} is registered twice")
    CAMERA_MODELS[kind] = CameraModelInfo(kind, label, target)


_register("pinhole", "Pin-hole camera", "egtviz.geometry.pinhole:PinholeCamera")
_register("hyperbolic", "Hyperbolic mirror (catadioptric)", "egtviz.geometry.catadioptric:HYPERBOLIC")
_register("parabolic", "Parabolic mirror (catadioptric)", "egtviz.geometry.catadioptric:PARABOLIC")
_register("unified", "Unified sphere camera", "egtviz.geometry.unified:UnifiedCamera")
_register("fisheye", "Equidistant fisheye camera", "egtviz.geometry.fisheye:FisheyeCamera")
