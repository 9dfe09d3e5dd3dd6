"""What a scene holds: camera, surface and display specifications (frozen, serialisable).

A spec stores what a person edits (positions, angles in degrees, focal length
in metres); ``.camera()`` turns it into the numeric core's camera. Rotation
conventions: ``docs/conventions.md``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any, ClassVar, Literal

import numpy as np

from ..geometry import GeometryError, Intrinsics, PinholeCamera, Pose
from ..geometry.camera_model import CAMERA_MODELS, CameraModel, CameraModelInfo
from ..geometry.catadioptric import HYPERBOLIC, PARABOLIC
from ..geometry.fisheye import FisheyeCamera
from ..geometry.poses import EGT_CAMERA_BASE, egt_rotation_from_ypr, rotx, roty, rotz, ypr_from_egt_rotation
from ..geometry.unified import UnifiedCamera
from ._values import (
    NUMBER_TYPES,
    OutOfRangeError,
    SceneError,
    as_numbers,
    as_pair,
    as_ranged,
    as_triple,
    has_control_characters,
    short_text,
)
from .limits import (
    ANGLE_DEG,
    COORDINATE,
    FOCAL_PIXELS,
    MAX_NAME_LENGTH,
    MIRROR_B_OVER_A,
    MIRROR_PARAMETER,
    PANORAMIC_FOCAL_PIXELS,
    SKEW_OVER_FOCAL,
    SURFACE_SAMPLES,
    SURFACE_SIZE,
    Range,
    parameter_range,
)

_isfinite = math.isfinite
_BASE_T = EGT_CAMERA_BASE.T.tolist()


def _is_rotation(m: list[list[float]], tol: float = 1e-6) -> bool:
    """``R^T R = I`` within ``tol`` and ``det R > 0`` (what ``as_rotation`` checks), in plain floats."""
    (a, b, c), (d, e, f), (g, h, i) = m
    if (
        abs(a * a + d * d + g * g - 1.0) > tol
        or abs(b * b + e * e + h * h - 1.0) > tol
        or abs(c * c + f * f + i * i - 1.0) > tol
        or abs(a * b + d * e + g * h) > tol
        or abs(a * c + d * f + g * i) > tol
        or abs(b * c + e * f + h * i) > tol
    ):
        return False
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) > 0


def _check_name(name: Any) -> str:
    if not isinstance(name, str) or not name.strip():
        raise SceneError(f"name: expected a non-empty string, got {short_text(name)}")
    name = name.strip()
    if len(name) > MAX_NAME_LENGTH or has_control_characters(name) or name.startswith("point:"):
        raise SceneError(
            f"name: expected at most {MAX_NAME_LENGTH} characters, no control characters and no 'point:' prefix, "
            f"got {short_text(name)}"
        )
    return name


def _parameter(value: Any, kind: str, parameter: str, field: str, camera: str) -> float:
    """``value`` checked against the range of ``parameter`` of the registered model ``kind`` (a SceneError naming
    ``field``: the spec's own name for it)."""
    return as_ranged(value, parameter_range(kind, parameter), field, camera)


def _parameter_pair(value: Any, kind: str, parameters: tuple[str, str], field: str, camera: str) -> tuple[float, float]:
    limits = {parameter_range(kind, p) for p in parameters}
    (limit,) = limits  # both components of a pair share one range
    return as_pair(value, field, limit, camera)


def _egt_pose(ypr_deg: tuple[float, float, float], position: tuple[float, float, float]) -> Pose:
    """``Pose.from_egt(egt_rotation_from_ypr(*radians(ypr_deg)), position)``: the camera-axes convention of a
    pin-hole (and of the unified and fisheye cameras, whose frame is a pin-hole's)."""
    yaw, pitch, roll = (math.radians(a) for a in ypr_deg)
    # Built from checked angles and a checked position: a rotation to rounding, nothing to check again.
    return Pose(EGT_CAMERA_BASE @ egt_rotation_from_ypr(yaw, pitch, roll), position, check=False)


def _egt_ypr_from_world_rotation(R_world: np.ndarray) -> tuple[float, float, float]:
    """Yaw, pitch, roll (degrees) of a camera in the convention of :func:`_egt_pose` whose pose rotation is
    ``R_world``."""
    try:
        R = np.asarray(R_world, dtype=np.float64)
    except (TypeError, ValueError):
        R = None  # Pose below raises the error
    if R is not None and R.shape == (3, 3):
        w = R.tolist()
        if _isfinite(sum(w[0]) + sum(w[1]) + sum(w[2])) and _is_rotation(w):
            # The entries of R_egt = EGT_CAMERA_BASE^T R_world that ypr_from_egt_rotation's closed form
            # (away from the gimbal lock) reads, in plain floats.
            def egt(i: int, j: int) -> float:
                b = _BASE_T[i]
                return b[0] * w[0][j] + b[1] * w[1][j] + b[2] * w[2][j]

            m02, m12, m22 = egt(0, 2), egt(1, 2), egt(2, 2)
            if abs(m12) < 0.999:
                yaw = math.atan2(m02, m22)
                pitch = math.atan2(-m12, math.hypot(m02, m22))
                roll = math.atan2(egt(1, 0), egt(1, 1))
                return math.degrees(yaw), math.degrees(pitch), math.degrees(roll)
    # Not a clean rotation (Pose raises the error) or near the gimbal lock (scipy).
    R_egt = Pose(R_world, np.zeros(3)).egt_rotation
    return tuple(float(np.degrees(a)) for a in ypr_from_egt_rotation(R_egt))  # type: ignore[return-value]


def _egt_placement(xy: tuple[float, float], target_xy: tuple[float, float], height: float) -> dict[str, Any]:
    """``position`` and ``ypr_deg`` (pin-hole convention) of a camera at ``xy``, ``height`` up, looking at
    ``target_xy`` and 3 degrees down."""
    x, y = float(xy[0]), float(xy[1])
    yaw = math.degrees(math.atan2(target_xy[0] - x, target_xy[1] - y))
    return {"position": (x, y, height), "ypr_deg": (yaw, -3.0, 0.0)}


@lru_cache(maxsize=128)
def _model_at_origin(kind: str, values: tuple[tuple[str, float], ...]) -> CameraModel:
    """The registered model ``kind`` with these parameters at the identity pose: built (and checked) once per set
    of values; a spec's camera is this one :meth:`~egtviz.geometry.camera_model.CameraModel.moved` to its pose."""
    return CAMERA_MODELS[kind].build(Pose(), **dict(values))


class _CameraSpecBase:
    """What every camera spec shares: a name, a place, and the camera model its fields describe.

    A subclass is a frozen dataclass with ``name``, ``position``, ``ypr_deg`` and its model's fields; it says
    which registered model it builds (:attr:`model_kind`), with which parameter values (:meth:`model_values`),
    and how its angles make a pose (:attr:`pose`, :meth:`ypr_from_world_rotation`).
    """

    name: str
    position: tuple[float, float, float]
    ypr_deg: tuple[float, float, float]

    kind: ClassVar[str]
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str]
    """A new camera's name: this and a number."""
    POSE_FIELDS: ClassVar[frozenset[str]] = frozenset({"position", "ypr_deg"})
    """The fields that place the camera (what a gizmo moves and a lock holds); every other field is its model's."""

    def _check_place(self) -> str:
        name = _check_name(self.name)
        set_ = object.__setattr__
        set_(self, "name", name)
        set_(self, "position", as_triple(self.position, "position", COORDINATE, name))
        set_(self, "ypr_deg", as_triple(self.ypr_deg, "ypr_deg", ANGLE_DEG, name))
        return name

    @property
    def model_kind(self) -> str:
        """The registry key of the camera model this spec builds (``egtviz.geometry.CAMERA_MODELS``)."""
        raise NotImplementedError

    @property
    def model(self) -> CameraModelInfo:
        """The registry entry of :attr:`model_kind`."""
        return CAMERA_MODELS[self.model_kind]

    #: The registered models (``egtviz.geometry.CAMERA_MODELS``) this spec builds, and the field values that select
    #: each (``{"mirror": "parabolic"}``; empty for a spec of one model): the spec's registry entry.
    MODELS: ClassVar[dict[str, dict[str, Any]]] = {}
    #: How the viewer shows each of those models: ``"module:Class"`` of its 3D drawing (in ``egtviz.viewer.workbench.models``,
    #: imported by the viewer on first use) and a few words naming it in the GUI.
    DRAWINGS: ClassVar[dict[str, tuple[str, str]]] = {}

    #: Where each model parameter is stored: ``parameter -> (field, index in the field's pair or None)``.
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {}

    def model_values(self) -> dict[str, float]:
        """The model's parameters (``from_parameters`` keywords, in the model's order) from this spec's fields."""
        out = {}
        for p in self.model.parameters:
            field, index = self.PARAMETER_FIELDS[p.name]
            value = getattr(self, field)
            out[p.name] = value if index is None else value[index]
        return out

    def fields_for_parameters(self, **values: float) -> dict[str, Any]:
        """The spec fields (``update_camera`` keywords) that store these model parameter values."""
        fields: dict[str, Any] = {}
        for name, value in values.items():
            where = self.PARAMETER_FIELDS.get(name)
            if where is None or name not in {p.name for p in self.model.parameters}:
                raise SceneError(f"camera {self.name!r}: {name}: not a parameter of the {self.model_kind} model")
            field, index = where
            if index is None:
                fields[field] = value
            else:
                pair = list(fields.get(field, getattr(self, field)))
                pair[index] = value
                fields[field] = tuple(pair)
        return fields

    def with_parameters(self, **values: float) -> Any:
        """This spec with some model parameters changed (:meth:`fields_for_parameters`; checked as any change)."""
        return self.with_fields(**self.fields_for_parameters(**values))

    @property
    def pose(self) -> Pose:
        """The camera's place: the pose a drag gave (:meth:`with_world_pose`, kept as it was given), else the one
        ``position`` and ``ypr_deg`` describe (a typed value, a file)."""
        pose = self.__dict__.get("_pose")
        if pose is None:
            pose = self._pose_from_fields()
            object.__setattr__(self, "_pose", pose)
        return pose

    def _pose_from_fields(self) -> Pose:
        raise NotImplementedError

    @staticmethod
    def ypr_from_world_rotation(R_world: Any) -> tuple[float, float, float]:
        """Yaw, pitch, roll (degrees, the spec's convention) of a camera whose pose rotation is ``R_world``."""
        raise NotImplementedError

    @staticmethod
    def placement(xy: tuple[float, float], target_xy: tuple[float, float]) -> dict[str, Any]:
        """Fields of a new camera at ``xy`` that sees ``target_xy``."""
        raise NotImplementedError

    def with_world_pose(self, position: Any, R_world: Any) -> Any:
        """This spec at the world pose (``position``, ``R_world``) of a gizmo drag: quaternion -> rotation -> this
        pose, once. The camera is built from that pose itself; ``position`` and ``ypr_deg`` are its view for the
        fields and the file (a scene saved and read again has the same pose to rounding).

        Raises:
            GeometryError: ``R_world`` is not a rotation (named by the core's check).
            SceneError: ``position`` is out of range.
        """
        R = np.asarray(R_world, dtype=np.float64)
        m = R.tolist() if R.shape == (3, 3) else None
        if m is None or not (_isfinite(sum(m[0]) + sum(m[1]) + sum(m[2])) and _is_rotation(m)):
            Pose(R, np.zeros(3))  # the core names what is wrong
            raise GeometryError("R_world: expected a rotation")  # a rotation to the core's tolerance, not ours
        new = dataclasses.replace(self, position=position, ypr_deg=self.ypr_from_world_rotation(R))  # type: ignore[type-var]
        # A rotation to rounding (a gizmo's quaternion) and a checked position: nothing for the core to check again.
        # One only within the looser tolerance (a script's matrix) is made orthonormal by the core.
        exact = _is_rotation(m, 1e-12)
        object.__setattr__(new, "_pose", Pose(R, np.array(new.position), check=not exact))
        return new

    def camera(self) -> CameraModel:
        """The camera model of this spec (built once per spec: specs are immutable)."""
        return self._camera

    @cached_property
    def _camera(self) -> CameraModel:
        return _model_at_origin(self.model_kind, self.model_key).moved(self.pose)

    @property
    def model_key(self) -> tuple[tuple[str, float], ...]:
        """``tuple(model_values().items())``, remembered when the spec was checked: what the camera depends on
        besides the pose (a key for caches of pose-free content, such as the drawn region)."""
        return self.__dict__["_model_key"]

    def _check_model(self) -> None:
        """Build the model once at the origin: a value the model refuses is a SceneError naming this camera."""
        key = tuple(self.model_values().items())
        try:
            _model_at_origin(self.model_kind, key)
        except GeometryError as exc:
            raise SceneError(f"camera {self.name!r}: {exc}") from exc
        object.__setattr__(self, "_model_key", key)

    def with_pose(self, position: Any = None, ypr_deg: Any = None) -> Any:
        """This spec at another place (a drag): ``dataclasses.replace`` with the new position and angles."""
        changes = {}
        if position is not None:
            changes["position"] = position
        if ypr_deg is not None:
            changes["ypr_deg"] = ypr_deg
        return dataclasses.replace(self, **changes)  # type: ignore[type-var]

    def with_fields(self, **fields: Any) -> Any:
        """This spec with other field values (``dataclasses.replace``); a subclass may adapt the rest sensibly."""
        return dataclasses.replace(self, **fields)  # type: ignore[type-var]


class _EgtPlacedSpec(_CameraSpecBase):
    """A camera spec placed like EGT's pin-hole (``f_Rt2H``): its model's frame is a pin-hole's, its angles yaw,
    pitch, roll about the camera's own axes (all zero: looking along world +y)."""

    @staticmethod
    def placement(xy: tuple[float, float], target_xy: tuple[float, float]) -> dict[str, Any]:
        """Fields of a camera at ``xy`` (1.5 m up) looking at ``target_xy``, slightly down."""
        return _egt_placement(xy, target_xy, 1.5)

    def _pose_from_fields(self) -> Pose:
        """``Pose.from_egt(egt_rotation_from_ypr(*radians(ypr_deg)), position)``."""
        return _egt_pose(self.ypr_deg, self.position)

    @staticmethod
    def ypr_from_world_rotation(R_world: np.ndarray) -> tuple[float, float, float]:
        """Yaw, pitch, roll (degrees) of a camera whose pose rotation is ``R_world``."""
        return _egt_ypr_from_world_rotation(R_world)

    def _check_image_fields(self, name: str, fields: tuple[str, ...]) -> None:
        """Check the model fields ``fields``, then ``principal_point``, ``width`` and ``height`` (whole pixels),
        each against its model parameter, setting the checked values."""
        set_ = object.__setattr__
        k = self.model_kind
        for field in fields:
            set_(self, field, _parameter(getattr(self, field), k, field, field, name))
        set_(self, "principal_point", _parameter_pair(getattr(self, "principal_point"), k, ("u0", "v0"),
                                                      "principal_point", name))
        for field in ("width", "height"):
            set_(self, field, int(_parameter(getattr(self, field), k, field, field, name)))


#: The image fields' parameters, shared by the models placed like a pin-hole (``PARAMETER_FIELDS``' tail).
_IMAGE_PARAMETER_FIELDS: dict[str, tuple[str, int | None]] = {
    "u0": ("principal_point", 0), "v0": ("principal_point", 1), "width": ("width", None), "height": ("height", None),
}


@dataclass(frozen=True)
class PinholeSpec(_EgtPlacedSpec):
    """A pin-hole camera placed in EGT's convention (``f_Rt2H``); the ``pinhole`` model."""

    name: str
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Camera centre in world coordinates."""
    ypr_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Yaw, pitch, roll in degrees about the camera's own axes: ``R = roty(yaw) rotx(pitch) rotz(roll)``,
    then ``H = [rotx(-90 deg) R, t]``. All zero: looking along world +y."""
    focal_length: float = 0.008
    """Metres."""
    pixels_per_metre: tuple[float, float] = (100_000.0, 100_000.0)
    principal_point: tuple[float, float] = (320.0, 240.0)
    skew: float = 0.0
    width: int = 640
    height: int = 480

    MODELS: ClassVar[dict[str, dict[str, Any]]] = {PinholeCamera.kind: {}}
    DRAWINGS: ClassVar[dict[str, tuple[str, str]]] = {
        PinholeCamera.kind: ("egtviz.viewer.workbench.models.pinhole:PinholeDrawing", "pin-hole")}
    kind: ClassVar[str] = "pinhole"
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str] = "cam"
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = (
        "EGT convention (f_Rt2H): yaw, pitch, roll turn the camera about its own axes "
        "(x right, y down, z = optical axis): R = roty(yaw) rotx(pitch) rotz(roll), then H = [rotx(-90) R, t]. "
        "All zero: looking along world +y."
    )
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {
        "focal_length": ("focal_length", None), "ku": ("pixels_per_metre", 0), "kv": ("pixels_per_metre", 1),
        "skew": ("skew", None), **_IMAGE_PARAMETER_FIELDS,
    }

    def __post_init__(self) -> None:
        name = self._check_place()
        set_ = object.__setattr__
        k = self.model_kind
        set_(self, "focal_length", _parameter(self.focal_length, k, "focal_length", "focal_length", name))
        set_(self, "pixels_per_metre", _parameter_pair(self.pixels_per_metre, k, ("ku", "kv"), "pixels_per_metre", name))
        set_(self, "principal_point", _parameter_pair(self.principal_point, k, ("u0", "v0"), "principal_point", name))
        set_(self, "skew", _parameter(self.skew, k, "skew", "skew", name))
        set_(self, "width", int(_parameter(self.width, k, "width", "width", name)))
        set_(self, "height", int(_parameter(self.height, k, "height", "height", name)))
        for ku in self.pixels_per_metre:
            if self.focal_length * ku not in FOCAL_PIXELS:
                raise OutOfRangeError(name, "focal_length * pixels_per_metre", self.focal_length * ku, FOCAL_PIXELS)
        if self.skew / (self.focal_length * self.pixels_per_metre[0]) not in SKEW_OVER_FOCAL:
            raise OutOfRangeError(
                name, "skew / (focal_length * pixels_per_metre[0])",
                self.skew / (self.focal_length * self.pixels_per_metre[0]), SKEW_OVER_FOCAL,
            )
        self._check_model()

    @property
    def model_kind(self) -> str:
        return PinholeCamera.kind


    @property
    def intrinsics(self) -> Intrinsics:
        return self.camera().intrinsics  # type: ignore[attr-defined]


def panoramic_rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Mirror-frame rotation ``R = rotz(yaw) roty(pitch) rotx(roll)`` (radians); all zero: upright mirror."""
    return rotz(yaw) @ roty(pitch) @ rotx(roll)


@dataclass(frozen=True)
class PanoramicSpec(_CameraSpecBase):
    """A central catadioptric camera: mirror focus at ``position``, mirror axis the frame's z; the ``hyperbolic``
    or ``parabolic`` model, as ``mirror`` says."""

    name: str
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ypr_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Degrees: ``R = rotz(yaw) roty(pitch) rotx(roll)``; zero is an upright mirror."""
    mirror: Literal["hyperbolic", "parabolic"] = "hyperbolic"
    """The model's registry kind: the mirror's shape."""
    a: float = 3.0
    """Hyperbola ``a``; for a parabolic mirror, its parameter ``h``."""
    b: float = 1.0
    """Hyperbola ``b`` (unused by a parabolic mirror)."""
    focal_pixels: float = 1000.0
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480

    MODELS: ClassVar[dict[str, dict[str, Any]]] = {HYPERBOLIC.kind: {"mirror": HYPERBOLIC.kind},
                                                  PARABOLIC.kind: {"mirror": PARABOLIC.kind}}
    DRAWINGS: ClassVar[dict[str, tuple[str, str]]] = {
        HYPERBOLIC.kind: ("egtviz.viewer.workbench.models.catadioptric:CatadioptricDrawing", "panoramic, hyperbolic mirror"),
        PARABOLIC.kind: ("egtviz.viewer.workbench.models.catadioptric:CatadioptricDrawing", "panoramic, parabolic mirror")}
    kind: ClassVar[str] = "panoramic"
    """The entry's ``kind`` in a scene file (the mirror's shape is ``mirror``)."""
    NAME_PREFIX: ClassVar[str] = "pano"
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = (
        "Mirror frame: z = mirror axis. R = rotz(yaw) roty(pitch) rotx(roll); all zero: an upright mirror."
    )
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {
        "a": ("a", None), "b": ("b", None), "h": ("a", None), "focal_pixels": ("focal_pixels", None),
        "u0": ("principal_point", 0), "v0": ("principal_point", 1),
        "width": ("width", None), "height": ("height", None),
    }

    @staticmethod
    def placement(xy: tuple[float, float], target_xy: tuple[float, float]) -> dict[str, Any]:
        """Fields of an upright mirror at ``xy``, 0.5 m up (it sees all around)."""
        return {"position": (float(xy[0]), float(xy[1]), 0.5)}

    def __post_init__(self) -> None:
        name = self._check_place()
        set_ = object.__setattr__
        if not isinstance(self.mirror, str) or self.mirror not in _MIRROR_KINDS:
            raise SceneError(f"camera {name!r}: mirror: expected 'hyperbolic' or 'parabolic', got {short_text(self.mirror)}")
        k = self.mirror
        shape = _MIRROR_KINDS[k]
        set_(self, "a", _parameter(self.a, k, shape[0], "a", name))
        # b is stored for a parabolic mirror too (switching back restores it): it takes the hyperbola's range.
        set_(self, "b", _parameter(self.b, _HYPERBOLIC, "b", "b", name))
        if len(shape) == 2 and self.b / self.a not in MIRROR_B_OVER_A:
            raise OutOfRangeError(name, "b/a", self.b / self.a, MIRROR_B_OVER_A)
        set_(self, "focal_pixels", _parameter(self.focal_pixels, k, "focal_pixels", "focal_pixels", name))
        set_(self, "principal_point", _parameter_pair(self.principal_point, k, ("u0", "v0"), "principal_point", name))
        set_(self, "width", int(_parameter(self.width, k, "width", "width", name)))
        set_(self, "height", int(_parameter(self.height, k, "height", "height", name)))
        self._check_model()

    @property
    def model_kind(self) -> str:
        return self.mirror


    @property
    def K(self) -> np.ndarray:
        u0, v0 = self.principal_point
        f = self.focal_pixels
        return np.array([[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]])

    def mirror_model(self) -> Any:
        """The core mirror (``HyperbolicMirror`` or ``ParabolicMirror``)."""
        return self.camera().mirror  # type: ignore[attr-defined]

    def _pose_from_fields(self) -> Pose:
        """``Pose(panoramic_rotation_from_ypr(*radians(ypr_deg)), position)``."""
        yaw, pitch, roll = (math.radians(a) for a in self.ypr_deg)
        return Pose(panoramic_rotation_from_ypr(yaw, pitch, roll), self.position, check=False)

    def with_fields(self, **fields: Any) -> PanoramicSpec:
        """``dataclasses.replace``; a new ``mirror`` shape alone keeps the image as it was.

        The new mirror's horizon (the image of the horizontal rays, where a panoramic scene's points mostly are)
        stays at the radius it had about the principal point: a parabola's ``h`` is set for the CCD's focal
        length, or for a hyperbola (EGT's ``a = 3``, ``b = 1``) the CCD's focal length. Without this, a hyperbolic
        camera's ``a = 3`` read as a parabola's ``h`` would image the rim 6000 px out and every point outside the
        image.
        """
        mirror = fields.get("mirror", self.mirror)
        if mirror == self.mirror or not {"a", "b", "focal_pixels"}.isdisjoint(fields) or mirror not in _MIRROR_KINDS:
            return dataclasses.replace(self, **fields)
        radius = _horizon_radius(self.camera())
        if len(_MIRROR_KINDS[mirror]) == 1:
            # Orthographic CCD: a horizontal ray meets the parabola at radius h, imaged at radius h f.
            h = min(max(radius / self.focal_pixels, MIRROR_PARAMETER.low), MIRROR_PARAMETER.high)
            return dataclasses.replace(self, **fields, a=h)
        a, b = 3.0, 1.0
        unit = CAMERA_MODELS[mirror].build(Pose(), a=a, b=b, focal_pixels=1.0, u0=0.0, v0=0.0)
        f = min(max(radius / _horizon_radius(unit), PANORAMIC_FOCAL_PIXELS.low), PANORAMIC_FOCAL_PIXELS.high)
        return dataclasses.replace(self, **fields, a=a, b=b, focal_pixels=f)

    @staticmethod
    def ypr_from_world_rotation(R_world: np.ndarray) -> tuple[float, float, float]:
        m = np.asarray(R_world, dtype=np.float64).tolist()
        if abs(m[2][0]) < 0.999:  # away from the gimbal lock: closed form for R = rotz(yaw) roty(pitch) rotx(roll)
            yaw = math.atan2(m[1][0], m[0][0])
            pitch = math.atan2(-m[2][0], math.hypot(m[2][1], m[2][2]))
            roll = math.atan2(m[2][1], m[2][2])
            return math.degrees(yaw), math.degrees(pitch), math.degrees(roll)
        from scipy.spatial.transform import Rotation

        yaw, pitch, roll = Rotation.from_matrix(R_world).as_euler("ZYX")
        return float(np.degrees(yaw)), float(np.degrees(pitch)), float(np.degrees(roll))


def _horizon_radius(camera: CameraModel) -> float:
    """Largest distance (pixels) from the principal point of the camera's horizon, the image of the plane through its
    centre perpendicular to its axis (of its drawn region's boundary when the horizon is not seen)."""
    p = camera.parameters()
    arcs = camera.plane_image_arcs(camera.pose.R[:, 2], 64)[0]
    curve = np.vstack(arcs) if arcs else camera.rim(64)
    return float(np.hypot(curve[:, 0] - p["u0"], curve[:, 1] - p["v0"]).max())


_HYPERBOLIC = HYPERBOLIC.kind
#: The catadioptric models a ``PanoramicSpec`` builds (file format: its ``mirror``), and the parameters its fields
#: ``a``, ``b`` hold (a parabolic mirror's ``h`` is stored as ``a``).
_MIRROR_KINDS = {HYPERBOLIC.kind: ("a", "b"), PARABOLIC.kind: ("h",)}


@dataclass(frozen=True)
class UnifiedSpec(_EgtPlacedSpec):
    """A unified sphere camera, placed like a pin-hole (its frame is a pin-hole's); the ``unified`` model."""

    name: str
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The sphere's centre (the viewpoint) in world coordinates."""
    ypr_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Yaw, pitch, roll in degrees, as a pin-hole's (all zero: looking along world +y)."""
    xi: float = 0.8
    """0: a pin-hole, 1: a parabolic mirror, between: a hyperbolic one."""
    focal_pixels: float = 300.0
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480

    MODELS: ClassVar[dict[str, dict[str, Any]]] = {UnifiedCamera.kind: {}}
    DRAWINGS: ClassVar[dict[str, tuple[str, str]]] = {
        UnifiedCamera.kind: ("egtviz.viewer.workbench.models.unified:UnifiedDrawing", "unified sphere")}
    kind: ClassVar[str] = "unified"
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str] = "uni"
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = (
        "As a pin-hole (EGT's f_Rt2H): yaw, pitch, roll about the camera's own axes (z = optical axis, the sphere's "
        "axis); all zero: looking along world +y. The projection centre is xi behind the sphere's centre."
    )
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {
        "xi": ("xi", None), "focal_pixels": ("focal_pixels", None), **_IMAGE_PARAMETER_FIELDS,
    }

    def __post_init__(self) -> None:
        self._check_image_fields(self._check_place(), ("xi", "focal_pixels"))
        self._check_model()

    @property
    def model_kind(self) -> str:
        return UnifiedCamera.kind


@dataclass(frozen=True)
class FisheyeSpec(_EgtPlacedSpec):
    """An equidistant fisheye camera (``r = f theta``), placed like a pin-hole (its frame is a pin-hole's); the
    ``fisheye`` model."""

    name: str
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The lens's centre (the viewpoint) in world coordinates."""
    ypr_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Yaw, pitch, roll in degrees, as a pin-hole's (all zero: looking along world +y)."""
    field_of_view: float = 180.0
    """Degrees: the full angle of the cone of rays that have an image (at most 180)."""
    focal_pixels: float = 150.0
    """Pixels per radian of the angle from the axis."""
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480

    MODELS: ClassVar[dict[str, dict[str, Any]]] = {FisheyeCamera.kind: {}}
    DRAWINGS: ClassVar[dict[str, tuple[str, str]]] = {
        FisheyeCamera.kind: ("egtviz.viewer.workbench.models.fisheye:FisheyeDrawing", "equidistant fisheye")}
    kind: ClassVar[str] = "fisheye"
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str] = "fish"
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = (
        "As a pin-hole (EGT's f_Rt2H): yaw, pitch, roll about the camera's own axes (z = optical axis); all zero: "
        "looking along world +y."
    )
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {
        "field_of_view": ("field_of_view", None), "focal_pixels": ("focal_pixels", None), **_IMAGE_PARAMETER_FIELDS,
    }

    def __post_init__(self) -> None:
        self._check_image_fields(self._check_place(), ("field_of_view", "focal_pixels"))
        self._check_model()

    @property
    def model_kind(self) -> str:
        return FisheyeCamera.kind


CameraSpec = PinholeSpec | PanoramicSpec | UnifiedSpec | FisheyeSpec
#: The scene file's camera entries: ``kind`` -> spec class. Every spec builds a registered camera model
#: (``spec.model_kind``); a ``panoramic`` entry is a hyperbolic or parabolic one as its ``mirror`` says.
SPEC_CLASSES: tuple[type[_CameraSpecBase], ...] = (PinholeSpec, PanoramicSpec, UnifiedSpec, FisheyeSpec)
"""Every camera spec, one entry per spec class: the scene's registry of camera models (each class names the models
it builds, their parameters' fields and their drawings)."""
CAMERA_KINDS: dict[str, type[_CameraSpecBase]] = {cls.kind: cls for cls in SPEC_CLASSES}


def spec_for_model(model_kind: str) -> tuple[type[_CameraSpecBase], dict[str, Any]]:
    """The spec class that builds the registered model ``model_kind``, and the fields that select it.

    Raises:
        SceneError: for a kind no spec builds.
    """
    found = _SPEC_FOR_MODEL.get(model_kind) if type(model_kind) is str else None
    if found is None:
        raise SceneError(f"kind: expected one of {sorted(CAMERA_MODELS)}, got {short_text(model_kind)}")
    cls, selection = found
    return cls, dict(selection)


def model_choices(spec_cls: type) -> dict[str, tuple[str, ...]]:
    """The fields of ``spec_cls`` that choose among the models it builds, and their values (``{"mirror":
    ("hyperbolic", "parabolic")}`` for :class:`PanoramicSpec`; empty for a spec of one model)."""
    out: dict[str, list[str]] = {}
    for cls, selection in _SPEC_FOR_MODEL.values():
        if cls is spec_cls:
            for field, value in selection.items():
                out.setdefault(field, []).append(value)
    return {field: tuple(values) for field, values in out.items()}


_SPEC_FOR_MODEL: dict[str, tuple[type[_CameraSpecBase], dict[str, Any]]] = {
    model: (cls, selection) for cls in SPEC_CLASSES for model, selection in cls.MODELS.items()
}


@dataclass(frozen=True)
class SurfaceSpec:
    """A surface sampled into points with normals (EGT's ``f_3Dsurface``)."""

    kind: Literal["plane", "sphere", "mesh"] = "plane"
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    size: float = 2.0
    """Plane side length or sphere radius; the mesh's scale factor."""
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    """Plane normal (ignored by sphere and mesh)."""
    samples: int = 100
    path: str = ""
    """For ``kind = "mesh"``: the name of a mesh in the package's assets (:func:`egtviz.scene.surfaces.mesh_names`).
    The spec holds the name only; :func:`egtviz.scene.surfaces.check_surface` loads and checks the mesh (a scene
    file and ``SceneModel.add_surface`` call it), and only a plain file name in the assets is ever read."""

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in ("plane", "sphere", "mesh"):
            raise SceneError(f"surface kind: expected plane, sphere or mesh, got {short_text(self.kind)}")
        set_ = object.__setattr__
        set_(self, "center", as_triple(self.center, "center"))
        set_(self, "normal", as_triple(self.normal, "normal"))
        if math.hypot(*self.normal) < 1e-6:
            raise SceneError(f"surface normal: must not be (nearly) zero, got {self.normal}")
        set_(self, "size", as_ranged(self.size, SURFACE_SIZE, "size"))
        set_(self, "samples", int(as_ranged(self.samples, SURFACE_SAMPLES, "samples")))
        if not isinstance(self.path, str):
            raise SceneError(f"surface path: expected a mesh name, got {short_text(self.path)}")
        if self.kind != "mesh" and self.path:
            raise SceneError(f"surface path: only a mesh surface has one, got {short_text(self.path)}")


@dataclass(frozen=True)
class DisplayOptions:
    """What the viewer shows."""

    show_rays: bool = True
    show_planes: bool = True
    show_frames: bool = True
    show_labels: bool = True
    show_surfaces: bool = True

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            if type(getattr(self, f.name)) is not bool:
                raise SceneError(f"options: {f.name}: expected true or false, got {short_text(getattr(self, f.name))}")


def spec_to_dict(spec: Any) -> dict[str, Any]:
    """A spec as plain JSON data (tuples become lists)."""
    out = {}
    for f in dataclasses.fields(spec):
        v = getattr(spec, f.name)
        out[f.name] = list(v) if isinstance(v, tuple) else v
    if hasattr(type(spec), "kind") and isinstance(type(spec).__dict__.get("kind"), str):
        out = {"kind": spec.kind, **out}
    return out
