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
from ..geometry.poses import EGT_CAMERA_BASE, rotx, roty, rotz, ypr_from_egt_rotation
from .limits import (
    ANGLE_DEG,
    COORDINATE,
    FOCAL_LENGTH,
    FOCAL_PIXELS,
    IMAGE_SIZE,
    MAX_NAME_LENGTH,
    MIRROR_B_OVER_A,
    MIRROR_PARAMETER,
    PANORAMIC_FOCAL_PIXELS,
    PIXELS_PER_METRE,
    PRINCIPAL_POINT,
    SKEW,
    SKEW_OVER_FOCAL,
    SURFACE_SAMPLES,
    SURFACE_SIZE,
    Range,
)

_isfinite = math.isfinite
_BASE_T = EGT_CAMERA_BASE.T.tolist()


class SceneError(ValueError):
    """A change to a scene that cannot be applied (the scene is left unchanged)."""


class OutOfRangeError(SceneError):
    """A number outside its plausible range (``egtviz.scene.limits``).

    The attributes let a GUI restate the refusal in its own units.
    """

    def __init__(self, camera: str | None, field: str, value: float, limit: Range) -> None:
        self.camera = camera
        """Name of the camera the value belongs to, or None (a point, a surface)."""
        self.field = field
        """The spec field (``"focal_length"``, ``"position"``, ...)."""
        self.value = value
        self.limit = limit
        owner = f"camera {camera!r}: " if camera is not None else ""
        kind = "a whole number in " if limit.integer else ""
        super().__init__(f"{owner}{field}: expected {kind}{limit.describe()}, got {_short(value)}")


def _short(value: Any) -> str:
    """``repr(value)`` cut to a short prefix (a bad value may be a huge string or integer)."""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**30:
        return "an integer with more than 30 digits"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


_NUMBER_TYPES = (int, float, np.integer, np.floating)


def _number(value: Any, name: str, owner: str = "") -> float:
    """``value`` as a finite float; strings, booleans, None and containers are refused."""
    if type(value) is float:
        x = value
    elif isinstance(value, (bool, np.bool_)) or not isinstance(value, _NUMBER_TYPES):
        raise SceneError(f"{owner}{name}: expected a number, got {_short(value)}")
    else:
        try:
            x = float(value)
        except OverflowError:
            raise SceneError(f"{owner}{name}: expected a finite number, got {_short(value)}") from None
    if not _isfinite(x):
        raise SceneError(f"{owner}{name}: expected a finite number, got {_short(value)}")
    return x


def _ranged(value: Any, limit: Range, name: str, camera: str | None = None) -> float:
    """``value`` as a float inside ``limit`` (a whole number if ``limit.integer``), or an error naming it."""
    owner = f"camera {camera!r}: " if camera is not None else ""
    x = _number(value, name, owner)
    if x not in limit or (limit.integer and not x.is_integer()):
        raise OutOfRangeError(camera, name, x, limit)
    return x


def _numbers(value: Any, name: str, n: int, limit: Range = COORDINATE, camera: str | None = None) -> tuple[float, ...]:
    """``value`` as ``n`` floats inside ``limit``, or a SceneError naming ``name``."""
    lo, hi = limit.low, limit.high
    if type(value) is tuple and len(value) == n and all(type(v) is float for v in value):
        if all(lo <= v <= hi for v in value):  # the usual case (every drag): nothing to convert
            return value
        x = value
    else:
        owner = f"camera {camera!r}: " if camera is not None else ""
        if isinstance(value, np.ndarray):
            if value.ndim != 1:
                raise SceneError(f"{owner}{name}: expected {_COUNT[n]} numbers, got an array of shape {value.shape}")
            value = value.tolist()
        if not isinstance(value, (tuple, list)):
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} numbers, got {_short(value)}")
        if len(value) != n:
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} finite numbers, got {len(value)}")
        for v in value:
            if isinstance(v, (bool, np.bool_)) or not isinstance(v, _NUMBER_TYPES):
                raise SceneError(f"{owner}{name}: expected {_COUNT[n]} numbers, got {_short(v)}")
        try:
            x = tuple(float(v) for v in value)
        except OverflowError:
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} finite numbers, got {_short(value)}") from None
    for v in x:
        if not _isfinite(v):
            owner = f"camera {camera!r}: " if camera is not None else ""
            raise SceneError(f"{owner}{name}: expected {_COUNT[n]} finite numbers, got {_short(v)}")
        if not lo <= v <= hi:
            raise OutOfRangeError(camera, name, v, limit)
    return x


_COUNT = {2: "two", 3: "three"}


def _triple(value: Any, name: str, limit: Range = COORDINATE, camera: str | None = None) -> tuple[float, float, float]:
    return _numbers(value, name, 3, limit, camera)  # type: ignore[return-value]


def _pair(value: Any, name: str, limit: Range, camera: str | None = None) -> tuple[float, float]:
    return _numbers(value, name, 2, limit, camera)  # type: ignore[return-value]


def _trusted_pose(R: Any, t: tuple[float, float, float]) -> Pose:
    """A :class:`Pose` of a rotation this module built from angles (orthonormal to rounding) and a checked position.

    ``Pose(R, t)`` would check both again and re-orthonormalise ``R`` by an SVD, which is most of the cost of a
    camera drag's new camera; here nothing can be wrong, so the arrays are set as ``Pose.__post_init__`` leaves
    them (float64, read-only).
    """
    R = np.array(R, dtype=np.float64)
    t = np.array(t, dtype=np.float64)
    R.setflags(write=False)
    t.setflags(write=False)
    pose = object.__new__(Pose)
    object.__setattr__(pose, "R", R)
    object.__setattr__(pose, "t", t)
    return pose


def _egt_rotation(yaw: float, pitch: float, roll: float) -> list[list[float]]:
    """``egt_rotation_from_ypr`` (``roty(yaw) rotx(pitch) rotz(roll)``, radians) in plain floats."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    rows = ((cy, sy * sp, sy * cp), (0.0, cp, -sp), (-sy, cy * sp, cy * cp))  # roty(yaw) rotx(pitch)
    return [[a0 * cr + a1 * sr, a1 * cr - a0 * sr, a2] for a0, a1, a2 in rows]


def _panoramic_rotation(yaw: float, pitch: float, roll: float) -> list[list[float]]:
    """:func:`panoramic_rotation_from_ypr` (``rotz(yaw) roty(pitch) rotx(roll)``, radians) in plain floats."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    rows = ((cy * cp, -sy, cy * sp), (sy * cp, cy, sy * sp), (-sp, 0.0, cp))  # rotz(yaw) roty(pitch)
    return [[a0, a1 * cr + a2 * sr, a2 * cr - a1 * sr] for a0, a1, a2 in rows]


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


@lru_cache(maxsize=64, typed=True)
def _intrinsics_cached(*args: Any) -> Intrinsics:
    return Intrinsics(*args)


def _intrinsics(*args: Any) -> Intrinsics:
    """``Intrinsics(*args)``, one shared (immutable) object per distinct set of values: a drag re-validates none."""
    try:
        hash(args)
    except TypeError:
        return Intrinsics(*args)
    return _intrinsics_cached(*args)


def has_control_characters(text: str) -> bool:
    """True if ``text`` holds a control character (C0, DEL, C1): refused in names and titles."""
    return _CONTROL.search(text) is not None


_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")


def _check_name(name: Any) -> str:
    if not isinstance(name, str) or not name.strip():
        raise SceneError(f"name: expected a non-empty string, got {_short(name)}")
    name = name.strip()
    if len(name) > MAX_NAME_LENGTH or has_control_characters(name) or name.startswith("point:"):
        raise SceneError(
            f"name: expected at most {MAX_NAME_LENGTH} characters, no control characters and no 'point:' prefix, "
            f"got {_short(name)}"
        )
    return name


def _whole(value: Any, limit: Range, name: str, camera: str | None) -> int:
    """A whole number inside ``limit`` (``640`` or ``640.0``; ``640.5`` and ``True`` are refused)."""
    return int(_ranged(value, limit, name, camera))


@dataclass(frozen=True)
class PinholeSpec:
    """A pin-hole camera placed in EGT's convention (``f_Rt2H``)."""

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

    kind: ClassVar[Literal["pinhole"]] = "pinhole"

    def __post_init__(self) -> None:
        name = _check_name(self.name)
        set_ = object.__setattr__
        set_(self, "name", name)
        set_(self, "position", _triple(self.position, "position", COORDINATE, name))
        set_(self, "ypr_deg", _triple(self.ypr_deg, "ypr_deg", ANGLE_DEG, name))
        set_(self, "focal_length", _ranged(self.focal_length, FOCAL_LENGTH, "focal_length", name))
        set_(self, "pixels_per_metre", _pair(self.pixels_per_metre, "pixels_per_metre", PIXELS_PER_METRE, name))
        set_(self, "principal_point", _pair(self.principal_point, "principal_point", PRINCIPAL_POINT, name))
        set_(self, "skew", _ranged(self.skew, SKEW, "skew", name))
        set_(self, "width", _whole(self.width, IMAGE_SIZE, "width", name))
        set_(self, "height", _whole(self.height, IMAGE_SIZE, "height", name))
        for k in self.pixels_per_metre:
            if self.focal_length * k not in FOCAL_PIXELS:
                raise OutOfRangeError(name, "focal_length * pixels_per_metre", self.focal_length * k, FOCAL_PIXELS)
        if self.skew / (self.focal_length * self.pixels_per_metre[0]) not in SKEW_OVER_FOCAL:
            raise OutOfRangeError(
                name, "skew / (focal_length * pixels_per_metre[0])",
                self.skew / (self.focal_length * self.pixels_per_metre[0]), SKEW_OVER_FOCAL,
            )
        try:
            self.intrinsics  # noqa: B018 - validates focal length, pixel size, image size
        except GeometryError as exc:
            raise SceneError(f"camera {self.name!r}: {exc}") from exc

    @property
    def intrinsics(self) -> Intrinsics:
        return _intrinsics(
            self.focal_length, self.pixels_per_metre, self.principal_point, self.skew, self.width, self.height
        )

    @property
    def pose(self) -> Pose:
        """``Pose.from_egt(egt_rotation_from_ypr(*radians(ypr_deg)), position)``."""
        yaw, pitch, roll = (math.radians(a) for a in self.ypr_deg)
        return _trusted_pose(EGT_CAMERA_BASE @ np.array(_egt_rotation(yaw, pitch, roll)), self.position)

    def with_pose(self, position: Any = None, ypr_deg: Any = None) -> PinholeSpec:
        """This spec at another place (``dataclasses.replace(spec, position=..., ypr_deg=...)``, for a drag).

        Only the new values are checked (the rest was checked when this spec was made); the intrinsics
        are shared.
        """
        return _with_pose(self, position, ypr_deg)

    def camera(self) -> PinholeCamera:
        return self._camera

    @cached_property
    def _camera(self) -> PinholeCamera:
        # Specs are immutable, so the core camera is built once per spec.
        return PinholeCamera(self.pose, self.intrinsics)

    @staticmethod
    def ypr_from_world_rotation(R_world: np.ndarray) -> tuple[float, float, float]:
        """Yaw, pitch, roll (degrees) of a camera whose pose rotation is ``R_world``."""
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


def panoramic_rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Mirror-frame rotation ``R = rotz(yaw) roty(pitch) rotx(roll)`` (radians); all zero: upright mirror."""
    return rotz(yaw) @ roty(pitch) @ rotx(roll)


@dataclass(frozen=True)
class PanoramicSpec:
    """A central catadioptric camera: mirror focus at ``position``, mirror axis the frame's z."""

    name: str
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ypr_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Degrees: ``R = rotz(yaw) roty(pitch) rotx(roll)``; zero is an upright mirror."""
    mirror: Literal["hyperbolic", "parabolic"] = "hyperbolic"
    a: float = 3.0
    """Hyperbola ``a``; for a parabolic mirror, its parameter ``h``."""
    b: float = 1.0
    """Hyperbola ``b`` (unused by a parabolic mirror)."""
    focal_pixels: float = 1000.0
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480

    kind: ClassVar[Literal["panoramic"]] = "panoramic"

    def __post_init__(self) -> None:
        name = _check_name(self.name)
        set_ = object.__setattr__
        set_(self, "name", name)
        set_(self, "position", _triple(self.position, "position", COORDINATE, name))
        set_(self, "ypr_deg", _triple(self.ypr_deg, "ypr_deg", ANGLE_DEG, name))
        if not isinstance(self.mirror, str) or self.mirror not in ("hyperbolic", "parabolic"):
            raise SceneError(f"camera {name!r}: mirror: expected 'hyperbolic' or 'parabolic', got {_short(self.mirror)}")
        set_(self, "a", _ranged(self.a, MIRROR_PARAMETER, "a", name))
        set_(self, "b", _ranged(self.b, MIRROR_PARAMETER, "b", name))
        if self.mirror == "hyperbolic" and self.b / self.a not in MIRROR_B_OVER_A:
            raise OutOfRangeError(name, "b/a", self.b / self.a, MIRROR_B_OVER_A)
        set_(self, "focal_pixels", _ranged(self.focal_pixels, PANORAMIC_FOCAL_PIXELS, "focal_pixels", name))
        set_(self, "principal_point", _pair(self.principal_point, "principal_point", PRINCIPAL_POINT, name))
        set_(self, "width", _whole(self.width, IMAGE_SIZE, "width", name))
        set_(self, "height", _whole(self.height, IMAGE_SIZE, "height", name))
        try:
            self.camera()
        except GeometryError as exc:
            raise SceneError(f"camera {self.name!r}: {exc}") from exc

    @property
    def K(self) -> np.ndarray:
        u0, v0 = self.principal_point
        f = self.focal_pixels
        return np.array([[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]])

    @property
    def pose(self) -> Pose:
        """``Pose(panoramic_rotation_from_ypr(*radians(ypr_deg)), position)``."""
        yaw, pitch, roll = (math.radians(a) for a in self.ypr_deg)
        return _trusted_pose(_panoramic_rotation(yaw, pitch, roll), self.position)

    def with_pose(self, position: Any = None, ypr_deg: Any = None) -> PanoramicSpec:
        """This spec at another place (``dataclasses.replace(spec, position=..., ypr_deg=...)``, for a drag).

        Only the new values are checked (the rest was checked when this spec was made), and the new spec's
        camera is this camera moved: mirror and calibration are shared, not built and checked again.
        """
        return _with_pose(self, position, ypr_deg)

    def mirror_model(self):
        from ..geometry.mirrors import HyperbolicMirror, ParabolicMirror

        if self.mirror == "hyperbolic":
            return HyperbolicMirror(self.a, self.b)
        return ParabolicMirror(self.a)

    def camera(self):
        return self._camera

    @cached_property
    def _camera(self):
        from ..geometry.catadioptric import CatadioptricCamera

        elsewhere = self.__dict__.pop("_camera_elsewhere", None)
        if elsewhere is not None:  # made by with_pose: the same mirror and CCD, moved
            return _moved_camera(elsewhere, self.pose)

        return CatadioptricCamera(self.pose, self.mirror_model(), self.K, self.width, self.height)

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


CameraSpec = PinholeSpec | PanoramicSpec
CAMERA_KINDS: dict[str, type] = {"pinhole": PinholeSpec, "panoramic": PanoramicSpec}


@lru_cache(maxsize=None)
def _field_names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls))


def _with_pose(spec: Any, position: Any, ypr_deg: Any) -> Any:
    """``spec.with_pose``: a new spec object made without ``__post_init__`` (nothing else changed)."""
    cls = type(spec)
    new = object.__new__(cls)
    state = new.__dict__
    old = spec.__dict__
    for name in _field_names(cls):  # the fields only: cached values (the camera) belong to the old pose
        state[name] = old[name]
    if position is not None:
        state["position"] = _triple(position, "position", COORDINATE, old["name"])
    if ypr_deg is not None:
        state["ypr_deg"] = _triple(ypr_deg, "ypr_deg", ANGLE_DEG, old["name"])
    if cls is PanoramicSpec:
        built = old.get("_camera", old.get("_camera_elsewhere"))
        if built is not None:
            state["_camera_elsewhere"] = built  # moved to the new pose on first use
    return new


def _moved_camera(cam: Any, pose: Pose) -> Any:
    """``cam`` at ``pose``: its other (checked, immutable) fields are shared, its ``__post_init__`` not run again."""
    new = object.__new__(type(cam))
    for f in dataclasses.fields(cam):
        object.__setattr__(new, f.name, getattr(cam, f.name))
    object.__setattr__(new, "pose", pose)
    return new


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
    Only a plain file name there is accepted; the mesh is loaded and checked when the spec is made."""

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in ("plane", "sphere", "mesh"):
            raise SceneError(f"surface kind: expected plane, sphere or mesh, got {_short(self.kind)}")
        set_ = object.__setattr__
        set_(self, "center", _triple(self.center, "center"))
        set_(self, "normal", _triple(self.normal, "normal"))
        if math.hypot(*self.normal) < 1e-6:
            raise SceneError(f"surface normal: must not be (nearly) zero, got {self.normal}")
        set_(self, "size", _ranged(self.size, SURFACE_SIZE, "size"))
        set_(self, "samples", int(_ranged(self.samples, SURFACE_SAMPLES, "samples")))
        if not isinstance(self.path, str):
            raise SceneError(f"surface path: expected a mesh name, got {_short(self.path)}")
        if self.kind != "mesh":
            if self.path:
                raise SceneError(f"surface path: only a mesh surface has one, got {_short(self.path)}")
            return
        from .surfaces import mesh_samples

        mesh_samples(self.path, self.samples)  # loads and checks the mesh (cached by name)


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
                raise SceneError(f"options: {f.name}: expected true or false, got {_short(getattr(self, f.name))}")


def spec_to_dict(spec: Any) -> dict[str, Any]:
    """A spec as plain JSON data (tuples become lists)."""
    out = {}
    for f in dataclasses.fields(spec):
        v = getattr(spec, f.name)
        out[f.name] = list(v) if isinstance(v, tuple) else v
    if hasattr(type(spec), "kind") and isinstance(type(spec).__dict__.get("kind"), str):
        out = {"kind": spec.kind, **out}
    return out
