"""Ready-made scenes: the default classroom pair, a panoramic pair, the EGT tutorial's Examples 1-4, and a
planar mirror with a camera and its reflection."""

from __future__ import annotations

from typing import TypedDict

import numpy as np

from .annotations import Annotations, PlanarMirror
from .scene import Scene
from .cameras.catadioptric import PanoramicSpec
from .cameras.pinhole import PinholeSpec

#: Corners of a 2 m cube standing on the ground at the origin: easy to read in both images.
CUBE = tuple(
    (x, y, z) for z in (0.0, 2.0) for (x, y) in ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))
)


#: Eight points on the walls of a room round the panoramic pair (x, y in metres), at varied heights.
PANORAMIC_ROOM = (
    (2.26, 0.92, 0.6), (1.01, 1.93, 1.6), (-0.82, 1.99, 1.0), (-2.18, 1.06, 2.2),
    (-2.26, -0.32, 0.8), (-1.01, -1.33, 1.9), (0.82, -1.39, 1.3), (2.18, -0.46, 2.5),
)

class CCDOptions(TypedDict, total=False):
    """A panoramic camera's CCD as keyword arguments of :class:`PanoramicSpec`."""

    focal_pixels: float
    principal_point: tuple[float, float]
    width: int
    height: int


class PanoramicOptions(CCDOptions, total=False):
    """Keyword arguments shared by the panoramic cameras of an example (:class:`PanoramicSpec`)."""

    a: float
    b: float


class PinholeOptions(TypedDict, total=False):
    """Keyword arguments shared by the pin-hole cameras of an example (:class:`PinholeSpec`)."""

    focal_length: float
    pixels_per_metre: tuple[float, float]
    principal_point: tuple[float, float]
    width: int
    height: int


#: The tutorial's panoramic CCD: ``K = [[1e3, 0, 320], [0, 1e3, 240], [0, 0, 1]]`` on a 640 x 480 image.
TUTORIAL_CCD = CCDOptions(focal_pixels=1000.0, principal_point=(320.0, 240.0), width=640, height=480)


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
    """Two hyperbolic-mirror cameras (EGT's ``a = 3``, ``b = 1`` scaled by 1/10) among eight points.

    The points stand around both mirrors at elevations between about 10 and 55 degrees, so that they
    and their epipolar conics spread from the middle of each mirror image out towards its rim (a mirror
    image packs the horizon into a small circle round the centre; higher points fill the rest).
    The image does not change with the mirror's scale; the CCD focal length fills the image.
    """
    mirror = PanoramicOptions(a=0.3, b=0.1, focal_pixels=1100.0)
    return Scene(
        cameras=(
            PanoramicSpec("pano1", (-0.7, -0.2, 0.2), (45.0, 0.0, 0.0), **mirror),
            PanoramicSpec("pano2", (0.8, 0.1, 0.2), **mirror),
        ),
        points=PANORAMIC_ROOM,
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
    unit = PinholeOptions(focal_length=1.0, pixels_per_metre=(1.0, 1.0), principal_point=(0.0, 0.0), width=2, height=2)
    return Scene(
        cameras=(
            PinholeSpec("cam1", (-10.0, -10.0, 0.0), (0.0, 0.0, 45.0), **unit),
            PinholeSpec("cam2", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), **unit),
        ),
        points=((0.0, 10.0, 10.0), (-10.0, 5.0, 5.0)),
        title="Tutorial example 3: pin-hole epipolar geometry",
    )


def tutorial_example_2() -> Scene:
    """Example 2: ``H = [rotoz(pi/4), [-5, -5, 0]; 0 1]``, hyperbolic mirror ``a = 3``, ``b = 1``, the tutorial's
    CCD, and the point ``Xw = [0, 0, 4]`` (its image is ``u = 410.49``, ``v = 240``)."""
    cam = PanoramicSpec("pano", (-5.0, -5.0, 0.0), (45.0, 0.0, 0.0), a=3.0, b=1.0, **TUTORIAL_CCD)
    return Scene(cameras=(cam,), points=((0.0, 0.0, 4.0),), title="Tutorial example 2: panoramic placement")


def tutorial_example_4() -> Scene:
    """Example 4: two panoramic cameras placed as in Example 3 (``rotoz(pi/4)`` at ``[-10, -10, 0]``; upright at
    the origin), EGT's mirror ``a = 3``, ``b = 1`` and CCD, and eight points that both mirrors see."""
    mirror = PanoramicOptions(a=3.0, b=1.0, **TUTORIAL_CCD)
    return Scene(
        cameras=(
            PanoramicSpec("pano1", (-10.0, -10.0, 0.0), (45.0, 0.0, 0.0), **mirror),
            PanoramicSpec("pano2", (0.0, 0.0, 0.0), **mirror),
        ),
        points=tuple((x, y, z) for z in (2.0, 5.0) for (x, y) in ((-8.0, -4.0), (-4.0, -4.0), (-4.0, 2.0), (-8.0, 2.0))),
        title="Tutorial example 4: panoramic epipolar geometry",
    )


def mirror_scene() -> Scene:
    """A plane mirror (``y = 3``), a pin-hole camera in front of it, and the camera's reflection.

    The virtual camera ``cam_virtual`` is the mirror image of ``cam``, kept up to date by the scene when
    ``cam`` moves (:func:`egtviz.scene.annotations.resolve_reflections`); its gizmo is locked. Both see the
    cube: ``cam`` directly, ``cam_virtual`` as ``cam`` sees it in the mirror (left and right swapped back),
    so the drawn pair is the planar mirror's two-view geometry: every epipolar line of ``cam`` passes through
    the vanishing point of the mirror's normal.
    """
    mirror = PlanarMirror(normal=(0.0, 1.0, 0.0), distance=3.0, centre=(0.0, 3.0, 1.0), size=6.0, reflects="cam",
                          virtual="cam_virtual")
    return Scene(
        cameras=(_looking_at_origin("cam", (-3.0, -8.0, 1.5)),),
        points=CUBE,
        annotations=Annotations(mirrors=(mirror,)),
        pair=("cam", "cam_virtual"),
        locked=frozenset({"cam_virtual"}),
        title="Planar mirror: a camera and its reflection",
    )


SCENES = {
    "default": default_scene,
    "panoramic": panoramic_scene,
    "example1": tutorial_example_1,
    "example2": tutorial_example_2,
    "example3": tutorial_example_3,
    "example4": tutorial_example_4,
    "mirror": mirror_scene,
}
