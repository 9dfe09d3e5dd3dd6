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
  :math:`n \cdot (X - c) = 0` through the centre, a symmetric conic :math:`m^T C m = 0` (None when the model has
  no conic) and a line :math:`l \cdot m = 0` (None when the model does not image planes to lines);
- ``plane_image_arcs(normals, n_samples)``: the same images sampled as polylines, only the arcs the camera
  really shows, inside its drawn image region;
- ``rim(n)``: the boundary of that region as a closed polyline;
- ``PARAMETERS``, ``parameters()``, ``from_parameters(pose, **values)``: the model's scalar parameters with
  their ranges; ``pose``, ``centre``, ``moved(pose)``, ``width``, ``height``.

:data:`CAMERA_MODELS` maps each kind name to a :class:`CameraModelInfo` (its class, label and parameter
ranges), one registration line per model. How to add a model: ``docs/camera_models.md``.

This module also adapts the pin-hole and catadioptric cameras to the interface (:class:`PinholeModel`,
:class:`CatadioptricModel`) through their public API only.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_vector
from .catadioptric import UNIFIED_FLIP, CatadioptricCamera
from .epipolar import lines_of_planes
from .homogeneous import clip_lines_to_rect, normalize_homogeneous
from .mirrors import HyperbolicMirror, ParabolicMirror
from .panoramic_epipolar import conic_from_plane, sample_plane_conics
from .pinhole import Intrinsics, PinholeCamera
from .poses import Pose

__all__ = [
    "CAMERA_MODELS",
    "CameraModel",
    "CameraModelInfo",
    "CameraProjection",
    "CatadioptricModel",
    "DirectionImages",
    "HyperbolicModel",
    "ParabolicModel",
    "ParameterSpec",
    "PinholeModel",
    "Projection",
    "double_line_conics",
    "as_camera_model",
    "as_direction",
    "as_normals",
    "check_sample_count",
    "finite_nonzero_rows",
    "parameters_from_specs",
    "rectangle_rim",
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

    def check(self, value: Any) -> float | int:
        """``value`` as a float (an int for integer parameters) inside ``[min, max]``, or a GeometryError naming it."""
        unit = f" {self.unit}" if self.unit else ""
        expected = f"{'a whole number' if self.integer else 'a number'} in [{self.min:g}, {self.max:g}]{unit}"
        if isinstance(value, bool):
            raise GeometryError(f"{self.name}: expected {expected}, got {value!r}")
        try:
            x = float(value)
        except (TypeError, ValueError) as exc:
            raise GeometryError(f"{self.name}: expected {expected}, got {value!r}") from exc
        if not (math.isfinite(x) and self.min <= x <= self.max) or (self.integer and x != int(x)):
            raise GeometryError(f"{self.name}: expected {expected}, got {value!r}")
        return int(x) if self.integer else x


def parameters_from_specs(specs: tuple[ParameterSpec, ...], values: dict[str, Any]) -> dict[str, float | int]:
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
    """What ``CameraModel.project`` returns: pixels and the two masks."""

    pixels: np.ndarray
    visible: np.ndarray
    in_image: np.ndarray


@runtime_checkable
class CameraModel(Protocol):
    """A central camera model (see the module docstring). Instances are immutable: moving returns a new one."""

    kind: ClassVar[str]
    """The registry key of the model."""
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]]
    """The model's scalar parameters and their accepted ranges."""
    pose: Pose
    width: int
    height: int

    @property
    def centre(self) -> np.ndarray:
        """(3,) the single viewpoint in world coordinates."""
        ...

    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> CameraModel:
        """The model at ``pose`` with the given parameters (defaults for the others)."""
        ...

    def parameters(self) -> dict[str, float | int]:
        """Current value of every parameter in ``PARAMETERS``."""
        ...

    def moved(self, pose: Pose) -> CameraModel:
        """The same camera at another pose."""
        ...

    def project(self, X_world: npt.ArrayLike) -> Projection:
        """Project world points (N, 3)."""
        ...

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        """Unit world rays (N, 3) of pixels (N, 2); NaN rows for pixels that are no ray's image."""
        ...

    def baseline_images(self, direction_world: npt.ArrayLike) -> DirectionImages:
        """Images of the line through the centre along ``direction_world`` (3,)."""
        ...

    def plane_image_conics(self, normals_world: npt.ArrayLike) -> np.ndarray | None:
        """Exact image conics (N, 3, 3) of planes through the centre, unit Frobenius norm; NaN rows for zero or
        NaN normals; None if the model's plane images are not conics."""
        ...

    def plane_image_lines(self, normals_world: npt.ArrayLike) -> np.ndarray | None:
        """Exact image lines (N, 3) of planes through the centre; None if the model does not image planes to
        lines."""
        ...

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96) -> list[list[np.ndarray]]:
        """Per normal, the visible arcs (k, 2) of the plane's image inside the drawn region (empty: none)."""
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


def check_sample_count(n: int, name: str, minimum: int) -> int:
    """``n`` as an int of at least ``minimum``, or a GeometryError naming ``name``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < minimum:
        raise GeometryError(f"{name}: expected an integer >= {minimum}, got {n!r}")
    return int(n)


def finite_nonzero_rows(normals: np.ndarray) -> np.ndarray:
    """Indices of the rows that are finite and non-zero."""
    return np.flatnonzero(np.all(np.isfinite(normals), axis=1) & np.any(normals != 0.0, axis=1))


def _check_pose(pose: Any) -> Pose:
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
    """Plane normals as (N, 3) float64 rows (a (3,) normal is N = 1); NaN rows are allowed (points on a baseline
    have no epipolar plane) and give NaN conics and lines and no arcs; inf is an error."""
    try:
        n = np.asarray(normals_world, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"normals_world: expected a numeric array, got {type(normals_world).__name__}") from exc
    if n.ndim == 1 and n.shape[0] == 3:
        n = n[None, :]
    if n.ndim != 2 or n.shape[1] != 3:
        raise GeometryError(f"normals_world: expected shape (N, 3), got {n.shape}")
    if np.isinf(n).any():
        raise GeometryError("normals_world: contains inf")
    return n



_IMAGE_SIZE = (
    ParameterSpec("width", "width", "px", 1, 100_000, 640, integer=True),
    ParameterSpec("height", "height", "px", 1, 100_000, 480, integer=True),
)
_PRINCIPAL_POINT = (
    ParameterSpec("u0", "principal point u0", "px", -100_000.0, 100_000.0, 320.0),
    ParameterSpec("v0", "principal point v0", "px", -100_000.0, 100_000.0, 240.0),
)


# ------------------------------------------------------------------------------------------------ pin-hole
@dataclass(frozen=True, eq=False)
class PinholeModel:
    r"""A :class:`~egtviz.geometry.pinhole.PinholeCamera` seen through :class:`CameraModel`.

    A plane through the centre with world normal :math:`n` images to the line :math:`l = K^{-T} R^T n`
    (its conic is the double line :math:`l l^T`); its arc is the line clipped to the image rectangle,
    which is the drawn region. The baseline direction :math:`d` has one image :math:`K R^T d`, visible
    when the other centre is in front (:math:`(R^T d)_z > 0`).
    """

    camera: PinholeCamera = field(default_factory=PinholeCamera)

    kind: ClassVar[str] = "pinhole"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = (
        ParameterSpec("focal_length", "focal length", "m", 1e-5, 100.0, 0.008),
        ParameterSpec("ku", "pixels per metre along u", "px/m", 1.0, 1e9, 100_000.0),
        ParameterSpec("kv", "pixels per metre along v", "px/m", 1.0, 1e9, 100_000.0),
        *_PRINCIPAL_POINT,
        ParameterSpec("skew", "skew", "px", -100_000.0, 100_000.0, 0.0),
        *_IMAGE_SIZE,
    )

    def __post_init__(self) -> None:
        if not isinstance(self.camera, PinholeCamera):
            raise GeometryError(f"camera: expected a PinholeCamera, got {type(self.camera).__name__}")

    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> PinholeModel:
        p = parameters_from_specs(cls.PARAMETERS, values)
        intr = Intrinsics(p["focal_length"], (p["ku"], p["kv"]), (p["u0"], p["v0"]), p["skew"], p["width"],
                          p["height"])
        return cls(PinholeCamera(_check_pose(pose), intr))

    def parameters(self) -> dict[str, float | int]:
        i = self.camera.intrinsics
        (ku, kv), (u0, v0) = i.pixels_per_metre, i.principal_point
        return {"focal_length": i.focal_length, "ku": ku, "kv": kv, "u0": u0, "v0": v0, "skew": i.skew,
                "width": i.width, "height": i.height}

    @property
    def pose(self) -> Pose:
        return self.camera.pose

    @property
    def width(self) -> int:
        return self.camera.intrinsics.width

    @property
    def height(self) -> int:
        return self.camera.intrinsics.height

    @property
    def centre(self) -> np.ndarray:
        return self.camera.pose.t

    def moved(self, pose: Pose) -> PinholeModel:
        return PinholeModel(self.camera.moved(_check_pose(pose)))

    def project(self, X_world: npt.ArrayLike) -> CameraProjection:
        p = self.camera.project(X_world)
        return CameraProjection(p.pixels, p.in_front, p.in_image)

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        return self.camera.back_project(pixels)

    def baseline_images(self, direction_world: npt.ArrayLike) -> DirectionImages:
        d = as_direction(direction_world)
        m = self.camera.K @ (self.camera.pose.R.T @ d)
        return DirectionImages(normalize_homogeneous(m)[None, :], np.array([m[2] > 0]))

    def plane_image_lines(self, normals_world: npt.ArrayLike) -> np.ndarray:
        n = as_normals(normals_world)
        lines = np.full((len(n), 3), np.nan)
        good = finite_nonzero_rows(n)
        if len(good):
            lines[good] = lines_of_planes(self.camera, n[good])
        return lines

    def plane_image_conics(self, normals_world: npt.ArrayLike) -> np.ndarray:
        return double_line_conics(self.plane_image_lines(normals_world))

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96) -> list[list[np.ndarray]]:
        check_sample_count(n_samples, "n_samples", 2)
        lines = self.plane_image_lines(normals_world)
        out: list[list[np.ndarray]] = [[] for _ in range(len(lines))]
        good = finite_nonzero_rows(lines)
        if len(good):
            seg, hit = clip_lines_to_rect(lines[good], self.width, self.height)
            for k, s, h in zip(good.tolist(), seg, hit.tolist(), strict=True):
                if h:
                    out[k] = [s]
        return out

    def rim(self, n: int = 128) -> np.ndarray:
        return rectangle_rim(self.width, self.height)


# ------------------------------------------------------------------------------------------------ catadioptric
@dataclass(frozen=True, eq=False)
class CatadioptricModel:
    r"""A :class:`~egtviz.geometry.catadioptric.CatadioptricCamera` seen through :class:`CameraModel`.

    A plane through the focus with world normal :math:`n` images to the conic of its mirror-frame normal
    :math:`R^T n` (``conic_from_plane``), drawn as its arcs that meet the mirror inside the rim
    (``sample_plane_conics``); the drawn region is the rim's image. The baseline direction :math:`d` has the
    two images of :math:`\pm R^T d` by the unified model,
    :math:`K_g (F \hat d + (0, 0, \xi))` with :math:`\hat d = d / |d|`, visible where the mirror shows the ray.

    Its kind is the mirror's (``hyperbolic`` or ``parabolic``); :class:`HyperbolicModel` and
    :class:`ParabolicModel` carry each one's parameters.
    """

    camera: CatadioptricCamera = field(default_factory=CatadioptricCamera)

    kind: ClassVar[str] = "catadioptric"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.camera, CatadioptricCamera):
            raise GeometryError(f"camera: expected a CatadioptricCamera, got {type(self.camera).__name__}")

    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> CatadioptricModel:
        raise GeometryError(f"{cls.__name__}: build a HyperbolicModel or a ParabolicModel")

    def parameters(self) -> dict[str, float | int]:
        K = self.camera.K
        return {"focal_pixels": float(K[0, 0]), "u0": float(K[0, 2]), "v0": float(K[1, 2]),
                "width": self.camera.width, "height": self.camera.height}

    @property
    def pose(self) -> Pose:
        return self.camera.pose

    @property
    def width(self) -> int:
        return self.camera.width

    @property
    def height(self) -> int:
        return self.camera.height

    @property
    def centre(self) -> np.ndarray:
        return self.camera.pose.t

    def moved(self, pose: Pose) -> CatadioptricModel:
        return type(self)(self.camera.moved(_check_pose(pose)))

    def project(self, X_world: npt.ArrayLike) -> Projection:
        return self.camera.project(X_world)

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        return self.camera.back_project(pixels)

    def baseline_images(self, direction_world: npt.ArrayLike) -> DirectionImages:
        d = self.camera.pose.R.T @ as_direction(direction_world)
        dirs = np.stack([d, -d])
        s = (dirs / np.linalg.norm(d)) @ UNIFIED_FLIP.T
        s[:, 2] += self.camera.mirror.xi
        m = s @ self.camera.unified_calibration.T
        return DirectionImages(normalize_homogeneous(m), self.camera.project_directions(dirs).visible)

    def plane_image_lines(self, normals_world: npt.ArrayLike) -> None:
        return None

    def plane_image_conics(self, normals_world: npt.ArrayLike) -> np.ndarray:
        n = as_normals(normals_world)
        C = np.full((len(n), 3, 3), np.nan)
        good = finite_nonzero_rows(n)
        if len(good):
            C[good] = conic_from_plane(self.camera, n[good] @ self.camera.pose.R)
        return C

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96) -> list[list[np.ndarray]]:
        n_samples = check_sample_count(n_samples, "n_samples", 3)
        n = as_normals(normals_world)
        out: list[list[np.ndarray]] = [[] for _ in range(len(n))]
        good = finite_nonzero_rows(n)
        if len(good):
            for k, arcs in zip(good.tolist(), sample_plane_conics(self.camera, n[good] @ self.camera.pose.R,
                                                                   n_samples), strict=True):
                out[k] = arcs
        return out

    def rim(self, n: int = 128) -> np.ndarray:
        r = self.camera.rim_image(check_sample_count(n, "n", 3))
        return np.vstack([r, r[:1]])


_CCD = (ParameterSpec("focal_pixels", "CCD focal length", "px", 1.0, 1e7, 1000.0), *_PRINCIPAL_POINT, *_IMAGE_SIZE)


def _ccd(p: dict[str, float | int]) -> dict[str, Any]:
    u0, v0, f = p["u0"], p["v0"], p["focal_pixels"]
    return {"K": np.array([[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]]), "width": p["width"],
            "height": p["height"]}


@dataclass(frozen=True, eq=False)
class HyperbolicModel(CatadioptricModel):
    """A catadioptric camera with a hyperbolic mirror (parameters ``a``, ``b`` and the CCD's)."""

    kind: ClassVar[str] = "hyperbolic"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = (
        ParameterSpec("a", "mirror a", "m", 1e-3, 1e3, 3.0),
        ParameterSpec("b", "mirror b", "m", 1e-3, 1e3, 1.0),
        *_CCD,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.camera.mirror, HyperbolicMirror):
            raise GeometryError("camera: expected a camera with a HyperbolicMirror")

    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> HyperbolicModel:
        p = parameters_from_specs(cls.PARAMETERS, values)
        return cls(CatadioptricCamera(_check_pose(pose), HyperbolicMirror(p["a"], p["b"]), **_ccd(p)))

    def parameters(self) -> dict[str, float | int]:
        m = self.camera.mirror
        return {"a": m.a, "b": m.b, **super().parameters()}


@dataclass(frozen=True, eq=False)
class ParabolicModel(CatadioptricModel):
    """A catadioptric camera with a parabolic mirror (parameter ``h`` and the CCD's)."""

    kind: ClassVar[str] = "parabolic"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = (
        ParameterSpec("h", "mirror h", "m", 1e-3, 1e3, 1.0),
        *_CCD,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.camera.mirror, ParabolicMirror):
            raise GeometryError("camera: expected a camera with a ParabolicMirror")

    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> ParabolicModel:
        p = parameters_from_specs(cls.PARAMETERS, values)
        return cls(CatadioptricCamera(_check_pose(pose), ParabolicMirror(p["h"]), **_ccd(p)))

    def parameters(self) -> dict[str, float | int]:
        return {"h": self.camera.mirror.h, **super().parameters()}


def as_camera_model(camera: Any, name: str = "camera") -> CameraModel:
    """``camera`` as a :class:`CameraModel`: a model is returned as it is, a ``PinholeCamera`` or ``CatadioptricCamera``
    wrapped in its adapter (:class:`PinholeModel`, :class:`HyperbolicModel`, :class:`ParabolicModel`).

    Raises:
        GeometryError: naming ``name``, for anything else.
    """
    if isinstance(camera, PinholeCamera):
        return PinholeModel(camera)
    if isinstance(camera, CatadioptricCamera):
        return HyperbolicModel(camera) if isinstance(camera.mirror, HyperbolicMirror) else ParabolicModel(camera)
    if isinstance(camera, CameraModel):
        return camera
    raise GeometryError(f"{name}: expected a camera model or a pin-hole or catadioptric camera, "
                        f"got {type(camera).__name__}")


# ------------------------------------------------------------------------------------------------ registry
@dataclass(frozen=True)
class CameraModelInfo:
    """One registered camera model: its kind, label and class (imported on first use)."""

    kind: str
    """Registry key, the class's ``kind``."""
    label: str
    """Name shown to people."""
    target: str
    """``"package.module:ClassName"`` of the class implementing :class:`CameraModel`."""

    @property
    def cls(self) -> type:
        """The model's class (imported lazily, so that model modules may import this one)."""
        module, _, name = self.target.partition(":")
        cls = getattr(importlib.import_module(module), name)
        if getattr(cls, "kind", None) != self.kind:
            raise GeometryError(f"{self.target}: its kind {getattr(cls, 'kind', None)!r} is not {self.kind!r}")
        return cls

    @property
    def parameters(self) -> tuple[ParameterSpec, ...]:
        """The model's parameter specs (``cls.PARAMETERS``)."""
        return self.cls.PARAMETERS

    def build(self, pose: Pose, **values: float) -> CameraModel:
        """``cls.from_parameters(pose, **values)``."""
        return self.cls.from_parameters(pose, **values)


CAMERA_MODELS: dict[str, CameraModelInfo] = {}
"""Every camera model by kind name; one :func:`_register` line per model below."""


def _register(kind: str, label: str, target: str) -> None:
    if kind in CAMERA_MODELS:
        raise GeometryError(f"kind: {kind!r} is registered twice")
    CAMERA_MODELS[kind] = CameraModelInfo(kind, label, target)


_register("pinhole", "Pin-hole camera", "egtviz.geometry.camera_model:PinholeModel")
_register("hyperbolic", "Hyperbolic mirror (catadioptric)", "egtviz.geometry.camera_model:HyperbolicModel")
_register("parabolic", "Parabolic mirror (catadioptric)", "egtviz.geometry.camera_model:ParabolicModel")
_register("unified", "Unified sphere camera", "egtviz.geometry.unified:UnifiedCamera")
