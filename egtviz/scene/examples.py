"""Ready-made scenes: the default classroom pair and the tutorial's examples (EGT reference, section 8)."""

from __future__ import annotations

import numpy as np

from .scene import Scene
from .specs import PanoramicSpec, PinholeSpec

#: Corners of a 2 m cube standing on the ground at the origin: easy to read in both images.
CUBE = tuple(
    (x, y, z) for z in (0.0, 2.0) for (x, y) in ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))
)


def _looking_at_origin(name: str, position: tuple[float, float, float], target_z: float = 1.0) -> PinholeSpec:
    x, y, z = position
    yaw = np.degrees(np.arctan2(-x, -y))  # EGT yaw turns the optical axis from +y towards +x
    pitch = np.degrees(np.arctan2(target_z - z, np.hypot(x, y)))
    return PinholeSpec(name, position, (float(yaw), float(pitch), 0.0))


def default_scene() -> Scene:
    """Two pin-hole cameras looking at the eight corners of a cube."""
    return Scene(
        cameras=(
            _looking_at_origin("cam1", (-3.0, -8.0, 1.5)),
            _looking_at_origin("cam2", (3.5, -7.5, 2.5)),
        ),
        points=CUBE,
        title="Two pin-hole cameras",
    )


def panoramic_scene() -> Scene:
    """Two hyperbolic-mirror cameras (tutorial Example 4, at table-top scale): eight points around them.

    The mirrors are EGT's ``a = 3``, ``b = 1`` scaled by 1/10 (the image does
    not change with the scale), with a CCD focal length that fills the image.
    """
    mirror = dict(a=0.3, b=0.1, focal_pixels=1100.0)
    return Scene(
        cameras=(
            PanoramicSpec("pano1", (-1.5, -0.8, 0.2), (45.0, 0.0, 0.0), **mirror),
            PanoramicSpec("pano2", (1.6, -0.4, 0.2), **mirror),
        ),
        points=tuple((x * 1.2, y * 1.2 + 2.0, z * 0.6 + 0.9) for (x, y, z) in CUBE),
        title="Two panoramic cameras",
    )


def tutorial_example_1() -> Scene:
    """Example 1: one pin-hole camera, ``R = rotoy(pi/4)``, ``t = [-10, -5, 0]``, ``K = I``, a 6 x 6 panel."""
    cam = PinholeSpec(
        "cam", (-10.0, -5.0, 0.0), (45.0, 0.0, 0.0), focal_length=1.0, pixels_per_metre=(1.0, 1.0),
        principal_point=(0.0, 0.0), width=2, height=2,
    )
    pts = ((-3.0, 3.0, -3.0), (3.0, 3.0, -3.0), (3.0, 3.0, 3.0), (-3.0, 3.0, 3.0))
    return Scene(cameras=(cam,), points=pts, title="Tutorial example 1: pin-hole placement")


def tutorial_example_3() -> Scene:
    """Example 3: ``R1 = rotoz(pi/4)``, ``t1 = [-10, -10, 0]``; ``R2 = I``, ``t2 = 0``; ``K = I``; two points."""
    unit = dict(focal_length=1.0, pixels_per_metre=(1.0, 1.0), principal_point=(0.0, 0.0), width=2, height=2)
    return Scene(
        cameras=(
            PinholeSpec("cam1", (-10.0, -10.0, 0.0), (0.0, 0.0, 45.0), **unit),
            PinholeSpec("cam2", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), **unit),
        ),
        points=((0.0, 10.0, 10.0), (-10.0, 5.0, 5.0)),
        title="Tutorial example 3: pin-hole epipolar geometry",
    )


SCENES = {
    "default": default_scene,
    "panoramic": panoramic_scene,
    "example1": tutorial_example_1,
    "example3": tutorial_example_3,
}
