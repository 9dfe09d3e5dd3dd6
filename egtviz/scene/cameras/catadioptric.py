"""The central catadioptric camera above the core: one scene spec (a file's ``panoramic`` entry) for the hyperbolic
and the parabolic models, as its ``mirror`` says; their GUI fields and their drawing (the mirror over its CCD)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from ...geometry import Pose
from ...geometry.camera_model import CAMERA_MODELS, CameraModel
from ...geometry.catadioptric import HYPERBOLIC, PARABOLIC
from ...geometry.poses import rotx, roty, rotz
from ..camera_entry import FOCAL_PIXELS_FIELD, FOCAL_PIXELS_TERMS, CameraEntry
from ..limits import MIRROR_B_OVER_A, MIRROR_PARAMETER, PANORAMIC_FOCAL_PIXELS
from ..specs import CameraSpecBase, OutOfRangeError, SceneError, model_parameter, model_parameter_pair
from .._values import short_text

__all__ = ["ENTRIES", "PanoramicSpec", "panoramic_rotation_from_ypr"]


def panoramic_rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Mirror-frame rotation ``R = rotz(yaw) roty(pitch) rotx(roll)`` (radians); all zero: upright mirror."""
    return rotz(yaw) @ roty(pitch) @ rotx(roll)


@dataclass(frozen=True, init=False)
class PanoramicSpec(CameraSpecBase):
    """A central catadioptric camera: mirror focus at ``position``, mirror axis the frame's z; the ``hyperbolic``
    or ``parabolic`` model, as ``mirror`` says.

    ``ypr_deg``: degrees, ``R = rotz(yaw) roty(pitch) rotx(roll)``; zero is an upright mirror.
    """

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
        set_ = object.__setattr__
        name = self.name
        if not isinstance(self.mirror, str) or self.mirror not in _MIRROR_KINDS:
            raise SceneError(f"camera {name!r}: mirror: expected 'hyperbolic' or 'parabolic', got {short_text(self.mirror)}")
        k = self.mirror
        shape = _MIRROR_KINDS[k]
        set_(self, "a", model_parameter(self.a, k, shape[0], "a", name))
        # b is stored for a parabolic mirror too (switching back restores it): it takes the hyperbola's range.
        set_(self, "b", model_parameter(self.b, _HYPERBOLIC, "b", "b", name))
        if len(shape) == 2 and self.b / self.a not in MIRROR_B_OVER_A:
            raise OutOfRangeError(name, "b/a", self.b / self.a, MIRROR_B_OVER_A)
        set_(self, "focal_pixels", model_parameter(self.focal_pixels, k, "focal_pixels", "focal_pixels", name))
        set_(self, "principal_point", model_parameter_pair(self.principal_point, k, ("u0", "v0"), "principal_point",
                                                           name))
        set_(self, "width", int(model_parameter(self.width, k, "width", "width", name)))
        set_(self, "height", int(model_parameter(self.height, k, "height", "height", name)))
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

    @staticmethod
    def rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
        """``panoramic_rotation_from_ypr(yaw, pitch, roll)``."""
        return panoramic_rotation_from_ypr(yaw, pitch, roll)

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
            return self._replaced(**fields)
        radius = _horizon_radius(self.camera())
        if len(_MIRROR_KINDS[mirror]) == 1:
            # Orthographic CCD: a horizontal ray meets the parabola at radius h, imaged at radius h f.
            h = min(max(radius / self.focal_pixels, MIRROR_PARAMETER.low), MIRROR_PARAMETER.high)
            return self._replaced(**fields, a=h)
        a, b = 3.0, 1.0
        unit = CAMERA_MODELS[mirror].build(Pose(), a=a, b=b, focal_pixels=1.0, u0=0.0, v0=0.0)
        f = min(max(radius / _horizon_radius(unit), PANORAMIC_FOCAL_PIXELS.low), PANORAMIC_FOCAL_PIXELS.high)
        return self._replaced(**fields, a=a, b=b, focal_pixels=f)

    @staticmethod
    def ypr_from_world_rotation(R_world: Any) -> tuple[float, float, float]:
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

_DRAWING = "egtviz.viewer.workbench.models.catadioptric:CatadioptricDrawing"
_TERMS = {**FOCAL_PIXELS_TERMS, "b/a": ("b / a", "", 1.0)}

ENTRIES = (
    CameraEntry(HYPERBOLIC.kind, PanoramicSpec, "panoramic, hyperbolic mirror", _DRAWING,
                selection={"mirror": HYPERBOLIC.kind}, fields=(FOCAL_PIXELS_FIELD,), terms=_TERMS),
    CameraEntry(PARABOLIC.kind, PanoramicSpec, "panoramic, parabolic mirror", _DRAWING,
                selection={"mirror": PARABOLIC.kind}, fields=(FOCAL_PIXELS_FIELD,), terms=_TERMS),
)
"""The catadioptric models' entries: one spec, the mirror's shape selecting the model; the mirror drawn as a
reflective surface over its CCD."""
