"""The equidistant fisheye camera above the core: its scene spec (placed like a pin-hole), its GUI fields and its 3D
body (a translucent dome over the lens, facing the optical axis).

The whole model above ``egtviz/geometry/fisheye.py``: the registry finds this file by the core module's name.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...geometry.fisheye import FisheyeCamera
from ..camera_entry import FOCAL_PIXELS_FIELD, FOCAL_PIXELS_TERMS, CameraEntry, MeshBody
from ..specs import IMAGE_PARAMETER_FIELDS, EgtPlacedSpec

__all__ = ["ENTRIES", "LENS_RADIUS", "FisheyeSpec", "lens_mesh"]


@dataclass(frozen=True, init=False)
class FisheyeSpec(EgtPlacedSpec):
    """An equidistant fisheye camera (``r = f theta``), placed like a pin-hole (its frame is a pin-hole's); the
    ``fisheye`` model.

    ``position`` is the lens's centre (the viewpoint); ``ypr_deg`` as a pin-hole's (all zero: looking along world
    +y).
    """

    field_of_view: float = 180.0
    """Degrees: the full angle of the cone of rays that have an image (at most 180)."""
    focal_pixels: float = 150.0
    """Pixels per radian of the angle from the axis."""
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480

    kind: ClassVar[str] = "fisheye"
    """The entry's ``kind`` in a scene file."""
    NAME_PREFIX: ClassVar[str] = "fish"
    """A new camera's name: this and a number."""
    ANGLE_CONVENTION: ClassVar[str] = (
        "As a pin-hole (EGT's f_Rt2H): yaw, pitch, roll about the camera's own axes (z = optical axis); all zero: "
        "looking along world +y."
    )
    PARAMETER_FIELDS: ClassVar[dict[str, tuple[str, int | None]]] = {
        "field_of_view": ("field_of_view", None), "focal_pixels": ("focal_pixels", None), **IMAGE_PARAMETER_FIELDS,
    }

    def __post_init__(self) -> None:
        self._check_image_fields(("field_of_view", "focal_pixels"))

    @property
    def model_kind(self) -> str:
        return FisheyeCamera.kind


#: Radius of the drawn lens, scene units (metres).
LENS_RADIUS = 0.25
#: Rings and segments of the drawn cap.
_RINGS, _SEGMENTS = 8, 32


def lens_mesh(parameters: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (T, 3) of the drawn lens, model frame (z forward): the half of a sphere of
    radius :data:`LENS_RADIUS` in front of the lens, the rays a 180-degree fisheye images (the same dome at every
    field of view)."""
    theta = np.linspace(0.0, math.pi / 2, _RINGS + 1)[1:]
    phi = 2.0 * np.pi * np.arange(_SEGMENTS) / _SEGMENTS
    ring = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.sin(theta)[:, None] * np.sin(phi),
                     np.broadcast_to(np.cos(theta)[:, None], (_RINGS, _SEGMENTS))], axis=-1)
    vertices = LENS_RADIUS * np.vstack([[0.0, 0.0, 1.0], ring.reshape(-1, 3)])
    faces = [(0, 1 + j, 1 + (j + 1) % _SEGMENTS) for j in range(_SEGMENTS)]
    for i in range(_RINGS - 1):
        a, b = 1 + i * _SEGMENTS, 1 + (i + 1) * _SEGMENTS
        for j in range(_SEGMENTS):
            k = (j + 1) % _SEGMENTS
            faces += [(a + j, b + j, b + k), (a + j, b + k, a + k)]
    return vertices.astype(np.float32), np.asarray(faces, np.uint32)


ENTRIES = (
    CameraEntry(FisheyeCamera.kind, FisheyeSpec, "equidistant fisheye", MeshBody(lens_mesh, name="lens", opacity=0.35),
                fields=(FOCAL_PIXELS_FIELD,), terms=FOCAL_PIXELS_TERMS),
)
"""The fisheye's entry: the field of view in degrees (as its parameter says), the focal length in pixels; its body
a translucent dome."""
