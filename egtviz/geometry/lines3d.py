r"""Images of 3D lines in a pin-hole camera.

A 3D line and the camera centre :math:`C` span the *interpretation plane*;
its normal in the world is :math:`n = (X_1 - C) \times (X_2 - C)` for two
points of the line, and its image is the line (H&Z 2nd ed., 8.1.2)

.. math:: l \sim K^{-T} R^T n ,

which contains the images of all the line's points in front of the camera.
Lines are ``(a, b, c)`` with :math:`a u + b v + c = 0`, scaled to
:math:`a^2 + b^2 = 1` (``docs/conventions.md``).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_points, as_vector
from .epipolar import lines_of_planes
from .homogeneous import normalize_lines
from .pinhole import PinholeCamera

__all__ = ["image_of_line", "image_of_plucker_line"]


def _check_camera(camera: object) -> PinholeCamera:
    if not isinstance(camera, PinholeCamera):
        raise GeometryError(f"camera: expected a PinholeCamera, got {type(camera).__name__}")
    return camera


def image_of_line(camera: PinholeCamera, X1: npt.ArrayLike, X2: npt.ArrayLike) -> np.ndarray:
    r"""The image (3,) of the 3D line through ``X1`` and ``X2`` (world points, 3-vectors).

    .. math:: l \sim K^{-T} R^T \big((X_1 - C) \times (X_2 - C)\big)

    Raises:
        DegenerateConfigurationError: the line passes through the camera centre
            (its image is a single point) or ``X1 == X2``.
    """
    cam = _check_camera(camera)
    a = as_vector(X1, "X1", 3) - cam.center
    b = as_vector(X2, "X2", 3) - cam.center
    n = np.cross(a, b)
    if np.linalg.norm(n) <= 1e-12 * np.linalg.norm(a) * np.linalg.norm(b):
        raise DegenerateConfigurationError("X1, X2: the line passes through the camera centre (or X1 == X2)")
    return normalize_lines(lines_of_planes(cam, n / np.linalg.norm(n)))[0]


def image_of_plucker_line(camera: PinholeCamera, L: npt.ArrayLike) -> np.ndarray:
    r"""The image (3,) of a 3D line given by Plücker coordinates ``(d, m)`` in the *camera* frame.

    ``d`` is the direction, :math:`m = X \times d` the moment about the camera
    centre (the interpretation plane's normal), so :math:`l \sim K^{-T} m`.

    Raises:
        GeometryError: ``L`` is not a 6-vector or violates :math:`d \cdot m = 0`.
        DegenerateConfigurationError: ``m = 0``, the line passes through the centre.
    """
    cam = _check_camera(camera)
    p = as_vector(L, "L", 6)
    d, m = p[:3], p[3:]
    if abs(d @ m) > 1e-9 * max(float(np.linalg.norm(d) * np.linalg.norm(m)), 1e-300):
        raise GeometryError("L: expected Plücker coordinates (d, m) with d . m = 0")
    if not np.linalg.norm(m) > 0.0:
        raise DegenerateConfigurationError("L: the moment is zero; the line passes through the camera centre")
    line = np.linalg.solve(cam.K.T, m)
    return normalize_lines(as_points(line, "L", 3))[0]
