"""The pin-hole camera above the core: its scene spec (EGT's placement, ``f_Rt2H``), its GUI fields and its drawing."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ...geometry import Intrinsics, PinholeCamera
from ..camera_entry import CameraEntry, CameraField
from ..limits import FOCAL_PIXELS, SKEW_OVER_FOCAL
from ..specs import IMAGE_PARAMETER_FIELDS, EgtPlacedSpec, OutOfRangeError, model_parameter, model_parameter_pair

__all__ = ["ENTRIES", "PinholeSpec"]


@dataclass(frozen=True, init=False)
class PinholeSpec(EgtPlacedSpec):
    """A pin-hole camera placed in EGT's convention (``f_Rt2H``); the ``pinhole`` model.

    ``ypr_deg``: yaw, pitch, roll in degrees about the camera's own axes, ``R = roty(yaw) rotx(pitch) rotz(roll)``,
    then ``H = [rotx(-90 deg) R, t]``; all zero: looking along world +y.
    """

    focal_length: float = 0.008
    """Metres."""
    pixels_per_metre: tuple[float, float] = (100_000.0, 100_000.0)
    principal_point: tuple[float, float] = (320.0, 240.0)
    skew: float = 0.0
    width: int = 640
    height: int = 480

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
        "skew": ("skew", None), **IMAGE_PARAMETER_FIELDS,
    }

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        k, name = self.model_kind, self.name
        set_(self, "focal_length", model_parameter(self.focal_length, k, "focal_length", "focal_length", name))
        set_(self, "pixels_per_metre", model_parameter_pair(self.pixels_per_metre, k, ("ku", "kv"),
                                                            "pixels_per_metre", name))
        set_(self, "principal_point", model_parameter_pair(self.principal_point, k, ("u0", "v0"),
                                                           "principal_point", name))
        set_(self, "skew", model_parameter(self.skew, k, "skew", "skew", name))
        set_(self, "width", int(model_parameter(self.width, k, "width", "width", name)))
        set_(self, "height", int(model_parameter(self.height, k, "height", "height", name)))
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


ENTRIES = (
    CameraEntry(
        PinholeCamera.kind, PinholeSpec, "pin-hole", "egtviz.viewer.workbench.models.pinhole:PinholeDrawing",
        fields=(CameraField("focal", "focal length", "mm", ("focal_length",), scale=1e3),
                CameraField("pixel", "pixel size", "µm", ("ku", "kv"), scale=1e6, reciprocal=True, hint="x, y")),
        terms={"focal_length": ("focal length", "mm", 1e3),
               "focal_length * pixels_per_metre": ("focal length in pixels (focal length / pixel size)", "px", 1.0)},
    ),
)
"""The pin-hole model's entry: its spec, its fields (focal length in mm, pixel size in µm) and its drawing (the
frustum with the image on its image plane)."""
