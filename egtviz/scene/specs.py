"""What a scene holds: camera, surface and display specifications (frozen, serialisable).

A camera spec stores the camera's :class:`~egtviz.geometry.Pose` (rotation and centre) and its model's parameters;
``position`` and ``ypr_deg`` (angles in degrees, in the spec's convention) are views of the pose, for the GUI's
fields and the scene file. ``.camera()`` turns a spec into the numeric core's camera. The spec classes of the
camera models are declared in their model files (``egtviz/scene/cameras/``); this module holds what they share.
Rotation conventions: ``docs/conventions.md``.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np

from ..geometry import GeometryError, Pose
from ..geometry.camera_model import CAMERA_MODELS, CameraModel, CameraModelInfo
from ..geometry.poses import EGT_CAMERA_BASE, egt_rotation_from_ypr, ypr_from_egt_rotation
from ._values import (
    OutOfRangeError,
    SceneError,
    as_pair,
    as_ranged,
    as_triple,
    has_control_characters,
    short_text,
)
from .limits import ANGLE_DEG, COORDINATE, MAX_NAME_LENGTH, SURFACE_SAMPLES, SURFACE_SIZE, parameter_range

__all__ = [
    "IMAGE_PARAMETER_FIELDS",
    "CameraSpec",
    "CameraSpecBase",
    "DisplayOptions",
    "EgtPlacedSpec",
    "OutOfRangeError",
    "SceneError",
    "SurfaceSpec",
    "has_control_characters",
    "is_rotation",
    "model_parameter",
    "model_parameter_pair",
    "spec_to_dict",
]

_isfinite = math.isfinite
_BASE_T = EGT_CAMERA_BASE.T.tolist()


def is_rotation(m: list[list[float]], tol: float = 1e-6) -> bool:
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


def model_parameter(value: Any, kind: str, parameter: str, field: str, camera: str) -> float:
    """``value`` checked against the range of ``parameter`` of the registered model ``kind`` (a SceneError naming
    ``field``: the spec's own name for it)."""
    return as_ranged(value, parameter_range(kind, parameter), field, camera)


def model_parameter_pair(value: Any, kind: str, parameters: tuple[str, str], field: str,
                         camera: str) -> tuple[float, float]:
    """A pair of parameters of the registered model ``kind`` that share one range, checked (as
    :func:`model_parameter`)."""
    limits = {parameter_range(kind, p) for p in parameters}
    (limit,) = limits  # both components of a pair share one range
    return as_pair(value, field, limit, camera)


@lru_cache(maxsize=128)
def _model_at_origin(kind: str, values: tuple[tuple[str, float], ...]) -> CameraModel:
    """The registered model ``kind`` with these parameters at the identity pose: built (and checked) once per set
    of values; a spec's camera is this one :meth:`~egtviz.geometry.camera_model.CameraModel.moved` to its pose."""
    return CAMERA_MODELS[kind].build(Pose(), **dict(values))


def _model_fields(cls: type) -> tuple[tuple[str, Any], ...]:
    """The model fields of the spec class ``cls`` and their defaults (every dataclass field but ``name`` and
    ``pose``), read once per class."""
    found = _MODEL_FIELDS.get(cls)
    if found is None:
        found = _MODEL_FIELDS[cls] = tuple((f.name, f.default) for f in dataclasses.fields(cls)
                                           if f.name not in ("name", "pose"))
    return found


_MODEL_FIELDS: dict[type, tuple[tuple[str, Any], ...]] = {}


@dataclass(frozen=True, init=False)
class CameraSpecBase:
    """What every camera spec shares: a name, a pose, and the camera model its fields describe.

    A subclass is a ``@dataclass(frozen=True, init=False)`` with its model's fields (each with its default; the
    constructor is this class's); it
    says which registered model it builds (:attr:`model_kind`), with which parameter values (:meth:`model_values`),
    and how its angles ``ypr_deg`` make a rotation (:meth:`rotation_from_ypr`, :meth:`ypr_from_world_rotation`).

    Args:
        name: the camera's name.
        position: the centre, world coordinates (a view of the pose; default: the pose's, or the origin).
        ypr_deg: yaw, pitch, roll in degrees, the spec's convention (a view of the pose's rotation; default: the
            pose's, or all zero).
        *args: the model's fields in their order (as a dataclass's constructor takes them).
        pose: the camera's pose; ``position`` or ``ypr_deg`` given as well replace its centre or its rotation.
        **fields: the model's fields by name (defaults for the others).

    Raises:
        SceneError: a field is out of its range (an :class:`OutOfRangeError` names it).
        TypeError: a field the spec does not have.
    """

    name: str
    pose: Pose = field(default_factory=Pose)
    """The camera's place: the truth of the spec (``position`` and ``ypr_deg`` are its views)."""

    if TYPE_CHECKING:
        # Every model's spec has an image size (a field of its own, declared by each spec class).
        width: int = 0
        height: int = 0

    kind: ClassVar[str]
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str]
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = ""
    """How ``ypr_deg`` turns the camera, in words (the GUI's hint)."""
    POSE_FIELDS: ClassVar[frozenset[str]] = frozenset({"position", "ypr_deg"})
    """The views that place the camera (what a gizmo moves and a lock holds); every other field is its model's."""
    #: Where each model parameter is stored: ``parameter -> (field, index in the field's pair or None)``.
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {}

    def __init__(self, name: str, position: Any = None, ypr_deg: Any = None, *args: Any, pose: Pose | None = None,
                 **fields: Any) -> None:
        set_ = object.__setattr__
        name = _check_name(name)
        set_(self, "name", name)
        model_fields = _model_fields(type(self))
        if len(args) > len(model_fields):
            raise TypeError(f"{type(self).__name__}() takes at most {3 + len(model_fields)} positional arguments")
        for (key, _), value in zip(model_fields, args):
            if key in fields:
                raise TypeError(f"{type(self).__name__}() got multiple values for argument {key!r}")
            fields[key] = value
        for key, default in model_fields:
            set_(self, key, fields.pop(key) if key in fields else default)
        if fields:
            raise TypeError(f"{type(self).__name__}() got an unexpected keyword argument {next(iter(fields))!r}")
        set_(self, "pose", self._placed(name, position, ypr_deg, pose))
        self.__post_init__()

    def __post_init__(self) -> None:
        """Check the model's fields (a subclass's), then build the model once (:meth:`_check_model`)."""
        raise NotImplementedError

    def _placed(self, name: str, position: Any, ypr_deg: Any, pose: Pose | None) -> Pose:
        """The pose of the new spec: ``pose`` with the centre ``position`` and the rotation ``ypr_deg`` when they
        are given; the angles given are kept as the spec's view of its rotation (a file says what it said)."""
        if pose is not None and not isinstance(pose, Pose):
            raise SceneError(f"camera {name!r}: pose: expected a Pose, got {short_text(pose)}")
        t = None if position is None and pose is not None else as_triple(
            (0.0, 0.0, 0.0) if position is None else position, "position", COORDINATE, name)
        if t is not None:
            self.__dict__["_position"] = t
        if ypr_deg is None and pose is not None:
            if t is None:
                as_triple(tuple(pose.t.tolist()), "position", COORDINATE, name)  # a script's pose: in range
                return pose
            return Pose(pose.R, t, check=False)
        ypr = as_triple((0.0, 0.0, 0.0) if ypr_deg is None else ypr_deg, "ypr_deg", ANGLE_DEG, name)
        self.__dict__["_ypr"] = ypr
        centre = t if t is not None else pose.t  # type: ignore[union-attr]
        if pose is not None and ypr == self.ypr_from_world_rotation(pose.R):
            return pose if t is None else Pose(pose.R, centre, check=False)  # the same orientation: kept exactly
        # Built from checked angles and a checked centre: a rotation to rounding, nothing to check again.
        yaw, pitch, roll = (math.radians(a) for a in ypr)
        return Pose(self.rotation_from_ypr(yaw, pitch, roll), centre, check=False)

    @property
    def position(self) -> tuple[float, float, float]:
        """The camera's centre in world coordinates (a view of :attr:`pose`)."""
        t = self.__dict__.get("_position")
        if t is None:
            t = self.__dict__["_position"] = tuple(self.pose.t.tolist())
        return t

    @property
    def ypr_deg(self) -> tuple[float, float, float]:
        """Yaw, pitch, roll in degrees, the spec's convention (a view of :attr:`pose`'s rotation: the angles the
        spec was given, else computed from the rotation when first asked for)."""
        ypr = self.__dict__.get("_ypr")
        if ypr is None:
            ypr = self.__dict__["_ypr"] = self.ypr_from_world_rotation(self.pose.R)
        return ypr

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """What a scene file's entry and an edit may name: ``name``, the pose's views, the model's fields."""
        return ("name", "position", "ypr_deg", *(key for key, _ in _model_fields(cls)))

    def file_fields(self) -> dict[str, Any]:
        """The spec's fields as a scene file writes them (in :meth:`field_names` order)."""
        return {key: getattr(self, key) for key in self.field_names()}

    @property
    def model_kind(self) -> str:
        """The registry key of the camera model this spec builds (``egtviz.geometry.CAMERA_MODELS``)."""
        raise NotImplementedError

    @property
    def model(self) -> CameraModelInfo:
        """The registry entry of :attr:`model_kind`."""
        return CAMERA_MODELS[self.model_kind]

    def model_values(self) -> dict[str, float]:
        """The model's parameters (``from_parameters`` keywords, in the model's order) from this spec's fields."""
        out = {}
        for p in self.model.parameters:
            key, index = self.PARAMETER_FIELDS[p.name]
            value = getattr(self, key)
            out[p.name] = value if index is None else value[index]
        return out

    def fields_for_parameters(self, **values: float) -> dict[str, Any]:
        """The spec fields (``update_camera`` keywords) that store these model parameter values."""
        fields: dict[str, Any] = {}
        for name, value in values.items():
            where = self.PARAMETER_FIELDS.get(name)
            if where is None or name not in {p.name for p in self.model.parameters}:
                raise SceneError(f"camera {self.name!r}: {name}: not a parameter of the {self.model_kind} model")
            key, index = where
            if index is None:
                fields[key] = value
            else:
                pair = list(fields.get(key, getattr(self, key)))
                pair[index] = value
                fields[key] = tuple(pair)
        return fields

    def with_parameters(self, **values: float) -> Any:
        """This spec with some model parameters changed (:meth:`fields_for_parameters`; checked as any change)."""
        return self.with_fields(**self.fields_for_parameters(**values))

    @staticmethod
    def rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
        """The pose rotation of a camera at these angles (radians, the spec's convention)."""
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
        """This spec at the world pose (``position``, ``R_world``) of a gizmo drag: the pose itself, once (no
        angles on the way: ``ypr_deg`` is computed from it only when a field or the file asks).

        Raises:
            GeometryError: ``R_world`` is not a rotation (named by the core's check).
            SceneError: ``position`` is out of range.
        """
        R = np.asarray(R_world, dtype=np.float64)
        m = R.tolist() if R.shape == (3, 3) else None
        if m is None or not (_isfinite(sum(m[0]) + sum(m[1]) + sum(m[2])) and is_rotation(m)):
            Pose(R, np.zeros(3))  # the core names what is wrong
            raise GeometryError("R_world: expected a rotation")  # a rotation to the core's tolerance, not ours
        t = as_triple(position, "position", COORDINATE, self.name)
        # A rotation to rounding (a gizmo's quaternion) and a checked position: nothing for the core to check again.
        # One only within the looser tolerance (a script's matrix) is made orthonormal by the core.
        pose = Pose(R, np.array(t), check=not is_rotation(m, 1e-12))
        # Only the pose is new: the model's fields were checked when this spec was made (every drag step comes
        # here, so they are not checked again). The copy keeps them and the model key, and none of the views or
        # the camera of the old pose.
        new = copy.copy(self)
        for key in _POSE_CACHES:
            new.__dict__.pop(key, None)
        new.__dict__["pose"] = pose
        new.__dict__["_position"] = t
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
        """This spec at another place (a typed value, a lesson's move): the new centre and/or angles."""
        changes = {}
        if position is not None:
            changes["position"] = position
        if ypr_deg is not None:
            changes["ypr_deg"] = ypr_deg
        return self._replaced(**changes)

    def with_fields(self, **fields: Any) -> Any:
        """This spec with other field values (``dataclasses.replace``); a subclass may adapt the rest sensibly."""
        return self._replaced(**fields)

    def _replaced(self, **changes: Any) -> Any:
        """``dataclasses.replace``; the rotation unchanged, its angles stay the view they were (as given)."""
        new = dataclasses.replace(self, **changes)
        ypr = self.__dict__.get("_ypr")
        if ypr is not None and "ypr_deg" not in changes and "pose" not in changes:
            new.__dict__["_ypr"] = ypr
        return new


#: What a spec remembers of its pose besides the pose itself (its views and its camera).
_POSE_CACHES = ("_position", "_ypr", "_camera")

CameraSpec = CameraSpecBase
"""The type of any camera spec."""


class EgtPlacedSpec(CameraSpecBase):
    """A camera spec placed like EGT's pin-hole (``f_Rt2H``): its model's frame is a pin-hole's, its angles yaw,
    pitch, roll about the camera's own axes (all zero: looking along world +y)."""

    @staticmethod
    def placement(xy: tuple[float, float], target_xy: tuple[float, float]) -> dict[str, Any]:
        """Fields of a camera at ``xy`` (1.5 m up) looking at ``target_xy``, 3 degrees down."""
        x, y = float(xy[0]), float(xy[1])
        yaw = math.degrees(math.atan2(target_xy[0] - x, target_xy[1] - y))
        return {"position": (x, y, 1.5), "ypr_deg": (yaw, -3.0, 0.0)}

    @staticmethod
    def rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
        """``EGT_CAMERA_BASE @ egt_rotation_from_ypr(yaw, pitch, roll)`` (``Pose.from_egt``'s rotation)."""
        return EGT_CAMERA_BASE @ egt_rotation_from_ypr(yaw, pitch, roll)

    @staticmethod
    def ypr_from_world_rotation(R_world: Any) -> tuple[float, float, float]:
        """Yaw, pitch, roll (degrees) of a camera whose pose rotation is ``R_world``."""
        return _egt_ypr_from_world_rotation(R_world)

    def _check_image_fields(self, fields: tuple[str, ...]) -> None:
        """Check the model fields ``fields``, then ``principal_point``, ``width`` and ``height`` (whole pixels),
        each against its model parameter, setting the checked values; then build the model once."""
        set_ = object.__setattr__
        k, name = self.model_kind, self.name
        for key in fields:
            set_(self, key, model_parameter(getattr(self, key), k, key, key, name))
        set_(self, "principal_point", model_parameter_pair(getattr(self, "principal_point"), k, ("u0", "v0"),
                                                           "principal_point", name))
        for key in ("width", "height"):
            set_(self, key, int(model_parameter(getattr(self, key), k, key, key, name)))
        self._check_model()


def _egt_ypr_from_world_rotation(R_world: np.ndarray) -> tuple[float, float, float]:
    """Yaw, pitch, roll (degrees) of a camera in :class:`EgtPlacedSpec`'s convention whose pose rotation is
    ``R_world``."""
    try:
        R = np.asarray(R_world, dtype=np.float64)
    except (TypeError, ValueError):
        R = None  # Pose below raises the error
    if R is not None and R.shape == (3, 3):
        w = R.tolist()
        if _isfinite(sum(w[0]) + sum(w[1]) + sum(w[2])) and is_rotation(w):
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


#: The image fields' parameters, shared by the models placed like a pin-hole (``PARAMETER_FIELDS``' tail).
IMAGE_PARAMETER_FIELDS: dict[str, tuple[str, int | None]] = {
    "u0": ("principal_point", 0), "v0": ("principal_point", 1), "width": ("width", None), "height": ("height", None),
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
    if isinstance(spec, CameraSpecBase):
        values = spec.file_fields()  # the pose as its views: position, ypr_deg
    else:
        values = {f.name: getattr(spec, f.name) for f in dataclasses.fields(spec)}
    out = {key: list(v) if isinstance(v, tuple) else v for key, v in values.items()}
    if hasattr(type(spec), "kind") and isinstance(type(spec).__dict__.get("kind"), str):
        out = {"kind": spec.kind, **out}
    return out
