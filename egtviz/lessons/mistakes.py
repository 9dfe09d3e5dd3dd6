"""What a computed task asks (:class:`Quantity`) and the classic mistakes a learner makes on the way
(:class:`Mistake`), each computed from the learner's own scene through :mod:`egtviz.geometry`.

A quantity's value is what :class:`~egtviz.lessons.tasks.computed.ComputedTask` accepts; a mistake's value is
what a learner who made that mistake would type, so a typed answer that matches it is recognised and named
("F transposed: ..."). A mistake that gives the right value in this scene (e.g. an OpenGL ``v`` for a point on
the horizon line) is not named. ``docs/lessons.md`` lists the mistakes with the lesson that teaches each.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..geometry import PinholeCamera, UnifiedCamera, epipolar_lines, epipolar_lines_in_first, epipolar_pair
from ..geometry import normalize_homogeneous
from ..scene import Scene, SceneError

__all__ = ["MISTAKES", "QUANTITIES", "Mistake", "Quantity", "Where"]


@dataclass(frozen=True)
class Where:
    """What a quantity is about: ``camera``, the ``other`` camera of a pair, and point ``point`` (index from 0)."""

    camera: str
    other: str | None = None
    point: int | None = None

    @property
    def other_camera(self) -> str:
        """``other``, which every quantity with ``needs_other`` is given."""
        if self.other is None:
            raise SceneError(f"a quantity of {self.camera} needs the other camera of the pair")
        return self.other

    @property
    def point_index(self) -> int:
        """``point``, which every quantity with ``needs_point`` is given."""
        if self.point is None:
            raise SceneError(f"a quantity of {self.camera} needs a point")
        return self.point


Compute = Callable[[Scene, Where], np.ndarray]


@dataclass(frozen=True)
class Mistake:
    """A classic mistake: its ``name`` (as lesson files write it), a ``title`` and ``why`` it is wrong."""

    name: str
    title: str
    why: str
    value: Compute


@dataclass(frozen=True)
class Quantity:
    """What a computed task asks for: its ``shape`` (``()``, ``(2,)``, ``(3,)``, ``(3, 3)``), ``unit``,
    whether it is defined ``up_to_scale``, what it needs (``other``, ``point``) and which camera models."""

    name: str
    shape: tuple[int, ...]
    unit: str
    up_to_scale: bool | str
    """False; True (compared as unit-norm vectors); ``"line"`` (an image line, compared in pixels);
    ``"pixels"`` (a matrix between pixels, balanced first)."""
    value: Compute
    mistakes: tuple[Mistake, ...]
    needs_other: bool = False
    needs_point: bool = True
    pinhole_only: bool = True
    default_tolerance: float = 0.5


# -- the learner's scene, as the core sees it ---------------------------------------------------------------

def _camera(scene: Scene, name: str):
    return scene.camera(name).camera()


def _pinhole(scene: Scene, name: str) -> PinholeCamera:
    cam = _camera(scene, name)
    if not isinstance(cam, PinholeCamera):
        raise SceneError(f"{name} is not a pin-hole camera any more")
    return cam


def _point(scene: Scene, where: Where) -> np.ndarray:
    return np.asarray(scene.points[where.point_index], dtype=float)


def _local(scene: Scene, where: Where) -> np.ndarray:
    """The point in the camera's frame (x right, y down, z along the optical axis)."""
    return np.asarray(_camera(scene, where.camera).pose.to_local(_point(scene, where)), dtype=float).reshape(3)


def _pixel_of(K: np.ndarray, local: np.ndarray) -> np.ndarray:
    return normalize_homogeneous(K @ local)[:2]


# -- quantities ---------------------------------------------------------------------------------------------

def _pixel(scene: Scene, where: Where) -> np.ndarray:
    projection = _camera(scene, where.camera).project(_point(scene, where)[None, :])
    if not bool(projection.visible[0]):
        raise SceneError(f"point {where.point_index + 1} has no image in {where.camera}")
    return np.asarray(projection.pixels[0], dtype=float)


def _normalised(scene: Scene, where: Where) -> np.ndarray:
    return normalize_homogeneous(_local(scene, where))[:2]


def _depth(scene: Scene, where: Where) -> np.ndarray:
    return np.array(_local(scene, where)[2])


def _pair(scene: Scene, where: Where):
    return epipolar_pair(_pinhole(scene, where.camera), _pinhole(scene, where.other_camera))


def _epipole(scene: Scene, where: Where) -> np.ndarray:
    cam = _camera(scene, where.camera)
    if isinstance(cam, PinholeCamera):
        e = _pair(scene, where).e1
        if e[2] == 0.0:
            raise SceneError(f"the epipole of {where.camera} is at infinity: it has no pixel")
        return np.asarray(e[:2], dtype=float)
    projection = cam.project(_camera(scene, where.other_camera).centre[None, :])
    if not bool(projection.visible[0]):
        raise SceneError(f"{where.camera} does not see {where.other}'s centre")
    return np.asarray(projection.pixels[0], dtype=float)


def _fundamental(scene: Scene, where: Where) -> np.ndarray:
    return np.asarray(_pair(scene, where).F, dtype=float)


def _essential(scene: Scene, where: Where) -> np.ndarray:
    return np.asarray(_pair(scene, where).E, dtype=float)


def _seen_by_other(scene: Scene, where: Where) -> np.ndarray:
    """The point's pixel in the other camera."""
    return _pixel(scene, Where(where.other_camera, None, where.point))


def _line(scene: Scene, where: Where) -> np.ndarray:
    return np.asarray(epipolar_lines_in_first(_fundamental(scene, where), _seen_by_other(scene, where)),
                      dtype=float).reshape(3)


def _axis(scene: Scene, name: str) -> np.ndarray:
    return np.asarray(_camera(scene, name).pose.direction_to_world([0.0, 0.0, 1.0]), dtype=float).reshape(3)


def _angle_rad(scene: Scene, where: Where) -> float:
    c = float(np.clip(_axis(scene, where.camera) @ _axis(scene, where.other_camera), -1.0, 1.0))
    return math.acos(c)


def _angle_deg(scene: Scene, where: Where) -> np.ndarray:
    return np.array(math.degrees(_angle_rad(scene, where)))


def _sphere(scene: Scene, where: Where) -> np.ndarray:
    local = _local(scene, where)
    return local / np.linalg.norm(local)


def _camera_coordinates(scene: Scene, where: Where) -> np.ndarray:
    return _local(scene, where)


# -- mistakes -----------------------------------------------------------------------------------------------

def _no_division(scene: Scene, where: Where) -> np.ndarray:
    return (_camera(scene, where.camera).K @ _local(scene, where))[:2]


def _no_k(scene: Scene, where: Where) -> np.ndarray:
    return _normalised(scene, where)


def _opengl_pixel(scene: Scene, where: Where) -> np.ndarray:
    x, y, z = _local(scene, where)
    return _pixel_of(_camera(scene, where.camera).K, np.array([x, -y, z]))


def _opengl_local(scene: Scene, where: Where) -> np.ndarray:
    x, y, z = _local(scene, where)
    return np.array([x, -y, -z])


def _opengl_depth(scene: Scene, where: Where) -> np.ndarray:
    return np.array(-_local(scene, where)[2])


def _xi_ignored(scene: Scene, where: Where) -> np.ndarray:
    cam = _camera(scene, where.camera)
    if not isinstance(cam, UnifiedCamera):
        raise SceneError(f"{where.camera} is not a unified camera")
    return _pixel_of(cam.K, _local(scene, where))


def _distance(scene: Scene, where: Where) -> np.ndarray:
    return np.array(np.linalg.norm(_point(scene, where) - _camera(scene, where.camera).centre))


def _world_z(scene: Scene, where: Where) -> np.ndarray:
    return np.array(_point(scene, where)[2])


def _rotation_not_transposed(scene: Scene, where: Where) -> np.ndarray:
    cam = _camera(scene, where.camera)
    return cam.pose.R @ (_point(scene, where) - cam.centre)


def _centre_kept(scene: Scene, where: Where) -> np.ndarray:
    return _camera(scene, where.camera).pose.R.T @ _point(scene, where)


def _other_epipole(scene: Scene, where: Where) -> np.ndarray:
    e2 = _pair(scene, where).e2
    if e2[2] == 0.0:
        raise SceneError("the other epipole is at infinity")
    return np.asarray(e2[:2], dtype=float)


def _epipole_normalised(scene: Scene, where: Where) -> np.ndarray:
    cam = _pinhole(scene, where.camera)
    return normalize_homogeneous(cam.K_inv @ _pair(scene, where).e1)[:2]


def _antipodal_epipole(scene: Scene, where: Where) -> np.ndarray:
    cam = _camera(scene, where.camera)
    away = 2.0 * cam.centre - _camera(scene, where.other_camera).centre
    return np.asarray(cam.project(away[None, :]).pixels[0], dtype=float)


def _f_transposed(scene: Scene, where: Where) -> np.ndarray:
    return _fundamental(scene, where).T


def _e_transposed(scene: Scene, where: Where) -> np.ndarray:
    return _essential(scene, where).T


def _line_from_f_m2(scene: Scene, where: Where) -> np.ndarray:
    return np.asarray(epipolar_lines(_fundamental(scene, where), _seen_by_other(scene, where)), dtype=float).reshape(3)


def _radians(scene: Scene, where: Where) -> np.ndarray:
    return np.array(_angle_rad(scene, where))


def _sphere_unnormalised(scene: Scene, where: Where) -> np.ndarray:
    return _local(scene, where)


def _sphere_world(scene: Scene, where: Where) -> np.ndarray:
    return (_point(scene, where) - _camera(scene, where.camera).centre) / float(_distance(scene, where))


_M = Mistake
NO_DIVISION = _M("no_depth_division", "a projection without dividing by depth",
                 "K X_c is a homogeneous pixel: divide it by its third coordinate, the depth, to get (u, v)",
                 _no_division)
NO_K = _M("normalised_for_pixels", "normalised coordinates, not pixels",
          "(x/z, y/z) is the point on the plane z = 1; multiply by K to get pixels", _no_k)
OPENGL = _M("opengl_axes", "OpenGL's camera axes",
            "here the camera's y axis points down (v grows downwards) and z looks forwards; OpenGL's y is up "
            "and its camera looks down -z", _opengl_pixel)
MISTAKES: dict[str, tuple[Mistake, ...]] = {
    "pixel": (NO_DIVISION, NO_K, OPENGL,
              _M("xi_ignored", "the pin-hole projection of a unified camera",
                 "a unified camera first puts the point on the unit sphere and projects it from (0, 0, -xi): "
                 "xi is not 0", _xi_ignored)),
    "normalised": (_M("pixels_for_normalised", "pixels, not normalised coordinates",
                      "normalised coordinates are K^-1 times the pixel: the plane z = 1, without K", _pixel),
                   _M("no_depth_division", "camera coordinates without dividing by depth",
                      "the normalised point is (x/z, y/z): divide by the depth z", lambda s, w: _local(s, w)[:2])),
    "depth": (_M("distance_for_depth", "the distance, not the depth",
                 "the depth is the coordinate along the optical axis (z in the camera frame), shorter than the "
                 "distance to the centre unless the point is on the axis", _distance),
              _M("world_z", "the world z coordinate",
                 "the depth is measured along the camera's optical axis, not along the world's z", _world_z),
              _M("opengl_axes", "OpenGL's camera axes",
                 "here a point in front of the camera has positive z; an OpenGL camera looks down -z",
                 _opengl_depth)),
    "camera_coordinates": (
        _M("rotation_not_transposed", "R instead of R^T",
           "the pose's R turns camera axes into world axes; to go from the world into the camera use R^T",
           _rotation_not_transposed),
        _M("centre_not_subtracted", "the centre not subtracted",
           "X_c = R^T (X - C): move the origin to the camera's centre before turning", _centre_kept),
        _M("opengl_axes", "OpenGL's camera axes",
           "here the camera's y axis points down and z forwards; OpenGL's y is up and z backwards",
           _opengl_local)),
    "epipole": (_M("wrong_null_space", "the epipole from the wrong null space",
                   "F e1 = 0 gives the epipole of image 1 (the right null space); F^T e2 = 0 gives the other "
                   "image's", _other_epipole),
                _M("normalised_for_pixels", "normalised coordinates, not pixels",
                   "K^-1 e is the epipole on the plane z = 1; the epipole in pixels has K applied",
                   _epipole_normalised)),
    "panoramic_epipole": (
        _M("antipodal_epipole", "the other of the two epipoles",
           "the baseline meets the mirror twice; the image of the other camera's centre is the one towards it, "
           "the other is the direction away from it", _antipodal_epipole),),
    "fundamental": (_M("f_transposed", "F transposed",
                       "with m2^T F m1 = 0, F maps points of image 1 to lines of image 2; F^T goes the other way",
                       _f_transposed),
                    _M("e_for_f", "E without the calibration",
                       "E relates normalised coordinates; F = K2^-T E K1^-1 relates pixels", _essential)),
    "essential": (_M("f_for_e", "F, not E",
                     "F relates pixels; E = K2^T F K1 relates normalised coordinates", _fundamental),
                  _M("e_transposed", "E transposed",
                     "with m2^T E m1 = 0 (normalised), E^T swaps the roles of the two images", _e_transposed)),
    "epipolar_line": (_M("line_from_f_m2", "the line from F m2 instead of F^T m2",
                         "with m2^T F m1 = 0, the line of m2 in image 1 is F^T m2; F m2 mixes the images",
                         _line_from_f_m2),),
    "angle_deg": (_M("radians_for_degrees", "radians, not degrees",
                     "the answer is asked in degrees: multiply the radians by 180/pi", _radians),),
    "sphere_point": (_M("not_normalised", "the direction not normalised",
                        "a point on the unit sphere has length 1: divide X_c by its norm", _sphere_unnormalised),
                     _M("world_frame", "the world frame, not the camera's",
                        "the sphere point is in the camera frame: turn the direction by R^T", _sphere_world)),
}
"""Per quantity, the mistakes recognised (each named in lesson files by ``name``)."""


def _q(name: str, shape: tuple[int, ...], unit: str, value: Compute, **kw) -> Quantity:
    return Quantity(name, shape, unit, kw.pop("up_to_scale", False), value, MISTAKES.get(name, ()), **kw)


QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    _q("pixel", (2,), "px", _pixel, pinhole_only=False),
    _q("normalised", (2,), "", _normalised, default_tolerance=1e-3),
    _q("depth", (), "m", _depth, default_tolerance=0.01),
    _q("camera_coordinates", (3,), "m", _camera_coordinates, default_tolerance=0.01),
    _q("epipole", (2,), "px", _epipole, needs_other=True, needs_point=False),
    _q("panoramic_epipole", (2,), "px", _epipole, needs_other=True, needs_point=False, pinhole_only=False),
    _q("fundamental", (3, 3), "", _fundamental, needs_other=True, needs_point=False, up_to_scale="pixels",
       default_tolerance=0.01),
    _q("essential", (3, 3), "", _essential, needs_other=True, needs_point=False, up_to_scale=True,
       default_tolerance=0.01),
    _q("epipolar_line", (3,), "", _line, needs_other=True, up_to_scale="line", default_tolerance=1.0),
    _q("angle_deg", (), "deg", _angle_deg, needs_other=True, needs_point=False, default_tolerance=0.5),
    _q("sphere_point", (3,), "", _sphere, pinhole_only=False, default_tolerance=0.01),
)}
"""Every quantity a ``computed`` task may ask for, by name."""
