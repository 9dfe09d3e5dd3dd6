"""The unified sphere camera above the core: its scene spec (placed like a pin-hole), its GUI fields (``xi`` a
slider) and its drawing (the sphere, its projection centre, the selected point's great circle)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ...geometry.unified import UnifiedCamera
from ..camera_entry import FOCAL_PIXELS_FIELD, FOCAL_PIXELS_TERMS, CameraEntry, CameraField
from ..specs import IMAGE_PARAMETER_FIELDS, EgtPlacedSpec

__all__ = ["ENTRIES", "UnifiedSpec"]


@dataclass(frozen=True, init=False)
class UnifiedSpec(EgtPlacedSpec):
    """A unified sphere camera, placed like a pin-hole (its frame is a pin-hole's); the ``unified`` model.

    ``position`` is the sphere's centre (the viewpoint); ``ypr_deg`` as a pin-hole's (all zero: looking along world
    +y).
    """

    xi: float = 0.8
    """0: a pin-hole, 1: a parabolic mirror, between: a hyperbolic one."""
    focal_pixels: float = 300.0
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480

    kind: ClassVar[str] = "unified"
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str] = "uni"
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = (
        "As a pin-hole (EGT's f_Rt2H): yaw, pitch, roll about the camera's own axes (z = optical axis, the sphere's "
        "axis); all zero: looking along world +y. The projection centre is xi behind the sphere's centre."
    )
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {
        "xi": ("xi", None), "focal_pixels": ("focal_pixels", None), **IMAGE_PARAMETER_FIELDS,
    }

    def __post_init__(self) -> None:
        self._check_image_fields(("xi", "focal_pixels"))

    @property
    def model_kind(self) -> str:
        return UnifiedCamera.kind


ENTRIES = (
    CameraEntry(
        UnifiedCamera.kind, UnifiedSpec, "unified sphere", "egtviz.viewer.workbench.models.unified:UnifiedDrawing",
        fields=(FOCAL_PIXELS_FIELD,
                CameraField("xi", "xi", "", ("xi",), slider=True, hint="The sphere model's xi: 0 is a pin-hole "
                            "camera, 1 a parabolic mirror, between a hyperbolic one.")),
        terms=FOCAL_PIXELS_TERMS,
    ),
)
"""The unified sphere model's entry: ``xi`` is a slider (it morphs the image live)."""
