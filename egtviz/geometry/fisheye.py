r"""The equidistant fisheye camera: the image radius grows with the angle from the axis, :math:`r = f \theta`.

This is the Kannala-Brandt model with only its first term (:math:`k_2 = k_3 = k_4 = 0`). Its frame is a pin-hole
camera's: x right, y down, z forward (the optical axis). A ray with direction :math:`d = R^T (X - c)` in the model
frame makes the angle :math:`\theta = \operatorname{atan2}(\sqrt{d_x^2 + d_y^2},\ d_z)` with the axis and images at

.. math::
    m = \begin{bmatrix} u_0 \\ v_0 \end{bmatrix}
        + f\,\theta\, \frac{(d_x,\ d_y)}{\sqrt{d_x^2 + d_y^2}}
    \qquad (m = (u_0, v_0) \text{ on the axis}).

A ray has an image iff :math:`\theta \le \Theta / 2`, :math:`\Theta` the field of view (at most 180 degrees: every
ray in front of the lens and those along its rim). **Back-projection**: :math:`q = (m - (u_0, v_0)) / f`,
:math:`\theta = |q|`, the ray :math:`(\sin\theta\, q / |q|,\ \cos\theta)`; a pixel with :math:`\theta > \Theta/2` is
no ray's image (NaN row).

**Planes through the centre.** A plane with unit normal :math:`n` (model frame) cuts the unit sphere of ray
directions in a great circle :math:`s(t) = \cos t\, u + \sin t\, v`; its image is not a conic (nor a line), so
the model has no ``plane_image_conics`` or ``plane_image_lines`` (None) and images the plane by sampling the part
of the circle inside the drawn cap, :math:`s_z \ge \cos\theta_\rho`, through the projection above
(:meth:`FisheyeCamera.plane_image_arcs`; :math:`s_z = A \cos(t - t_0)`, :math:`A = \sqrt{u_z^2 + v_z^2}`). The
drawn region is the disc about the principal point of radius
:math:`\rho = \min(f\,\Theta/2,\ \text{distance to the farthest sensor corner})`, the image of the cap
:math:`\theta \le \theta_\rho = \rho / f`.
"""

from __future__ import annotations

import math
from dataclasses import InitVar, dataclass, field
from functools import cached_property
from typing import ClassVar, cast

import numpy as np
import numpy.typing as npt

from ._validate import as_points
from .camera_model import (
    IMAGE_SIZE_PARAMETERS,
    PRINCIPAL_POINT_PARAMETERS,
    CameraProjection,
    DirectionImages,
    ParameterSpec,
    arc_normals,
    as_direction,
    as_normals,
    camera_from_parameters,
    check_parameters,
    check_pose,
    check_sample_count,
    finite_nonzero_rows,
    parameter_values,
)
from .poses import Pose

__all__ = ["FisheyeCamera"]


@dataclass(frozen=True, eq=False)
class FisheyeCamera:
    r"""An equidistant fisheye camera, :math:`r = f\theta` (see the module docstring for frame and formulas).

    Args:
        pose: the model frame in the world (x right, y down, z forward).
        field_of_view: :math:`\Theta`, the full angle of the cone of rays that have an image, in degrees.
        focal_pixels: :math:`f > 0`, pixels per radian of :math:`\theta`.
        principal_point: :math:`(u_0, v_0)` in pixels.
        width: image width in pixels.
        height: image height in pixels.
        check: check the parameters against :attr:`PARAMETERS` (``False``: values of a checked camera, :meth:`moved`).

    Raises:
        GeometryError: naming the field, when one is outside its range (:attr:`PARAMETERS`).
    """

    pose: Pose = field(default_factory=Pose)
    field_of_view: float = 180.0
    focal_pixels: float = 150.0
    principal_point: tuple[float, float] = (320.0, 240.0)
    width: int = 640
    height: int = 480
    check: InitVar[bool] = True

    kind: ClassVar[str] = "fisheye"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = (
        ParameterSpec("field_of_view", "field of view", "deg", 1.0, 180.0, 180.0),
        ParameterSpec("focal_pixels", "focal length", "px", 1.0, 1e6, 150.0),
        *PRINCIPAL_POINT_PARAMETERS,
        *IMAGE_SIZE_PARAMETERS,
    )
    no_image: ClassVar[str] = "outside the field of view"

    def __post_init__(self, check: bool) -> None:
        check_pose(self.pose)
        if check is not False:
            check_parameters(self, ("field_of_view", "focal_pixels", "width", "height"))

    # ------------------------------------------------------------------ parameters and frames
    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> FisheyeCamera:
        """The camera at ``pose`` with ``field_of_view``, ``focal_pixels``, ``u0``, ``v0``, ``width``, ``height``."""
        return camera_from_parameters(cls, cls.PARAMETERS, pose, values)

    def parameters(self) -> dict[str, float | int]:
        return parameter_values(self)

    def moved(self, pose: Pose) -> FisheyeCamera:
        """The same camera at another pose (the parameters, checked once, are not checked again)."""
        check_pose(pose)
        return FisheyeCamera(pose, self.field_of_view, self.focal_pixels, self.principal_point, self.width,
                             self.height, check=False)

    @property
    def centre(self) -> np.ndarray:
        """(3,) the lens's single viewpoint in the world, ``pose.t``."""
        return self.pose.t

    @property
    def projective_calibration(self) -> None:
        """None: the fisheye does not image points linearly."""
        return None

    @cached_property
    def half_angle(self) -> float:
        r""":math:`\Theta / 2` in radians: the largest angle from the axis of a ray that has an image."""
        return math.radians(self.field_of_view) / 2.0

    # ------------------------------------------------------------------ projection
    def project(self, X_world: npt.ArrayLike, *, check: bool = True) -> CameraProjection:
        r"""Project world points (N, 3): :math:`m = (u_0, v_0) + f\theta\,(d_x, d_y)/\sqrt{d_x^2 + d_y^2}`.

        ``check=False``: the caller promises a float64 (N, 3) array of finite values (nothing is checked).

        Returns:
            NaN pixels and ``visible`` False where :math:`\theta > \Theta/2` or at the centre itself.
        """
        X = as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world)
        return self._project_local((X - self.pose.t) @ self.pose.R)

    def _project_local(self, d: np.ndarray) -> CameraProjection:
        rho = np.hypot(d[:, 0], d[:, 1])
        theta = np.arctan2(rho, d[:, 2])
        visible = ((rho > 0) | (d[:, 2] > 0)) & (theta <= self.half_angle)
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(rho > 0, self.focal_pixels * theta / rho, 0.0)
        u0, v0 = self.principal_point
        pixels = np.column_stack([d[:, 0] * scale + u0, d[:, 1] * scale + v0])
        pixels[~visible] = np.nan
        with np.errstate(invalid="ignore"):
            u, v = pixels[:, 0], pixels[:, 1]
            in_image = visible & (u >= 0) & (u <= self.width) & (v >= 0) & (v <= self.height)
        return CameraProjection(pixels, visible, in_image)

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        r"""Unit world rays (N, 3) of pixels (N, 2): :math:`(\sin\theta\, q/|q|,\ \cos\theta)`, :math:`\theta = |q|`;
        NaN rows where :math:`\theta > \Theta / 2` (no ray images there)."""
        m = as_points(pixels, "pixels", 2)
        u0, v0 = self.principal_point
        q = np.column_stack([m[:, 0] - u0, m[:, 1] - v0]) / self.focal_pixels
        theta = np.hypot(q[:, 0], q[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            sinc = np.where(theta > 0, np.sin(theta) / theta, 1.0)
        s = np.column_stack([q * sinc[:, None], np.cos(theta)])
        s[theta > self.half_angle * (1.0 + 1e-12)] = np.nan  # the rim itself, to rounding, is seen
        return s @ self.pose.R.T

    def light_paths(self, X_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        """(N, 2, 3) segments point -> centre; NaN rows for points outside the field of view."""
        X = as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world)
        out = np.empty((len(X), 2, 3))
        out[:, 0] = X
        out[:, 1] = self.pose.t
        out[~self._project_local((X - self.pose.t) @ self.pose.R).visible] = np.nan
        return out

    def baseline_images(self, direction_world: npt.ArrayLike, *, check: bool = True) -> DirectionImages:
        r"""The images of the rays :math:`\pm R^T d` (homogeneous, last coordinate 1), visible where
        :math:`\theta \le \Theta/2`. The ray straight back (:math:`\theta = \pi`) images to a whole circle: its row
        is the principal point, not visible.

        ``check=False``: the caller promises a float64 (3,) finite, non-zero ``direction_world`` (not checked).
        """
        d = self.pose.R.T @ (as_direction(direction_world) if check else direction_world)
        p = self._project_local(np.stack([d, -d]))
        rho = math.hypot(d[0], d[1])
        pixels = np.empty((2, 3))
        pixels[:, 2] = 1.0
        for k, sign in enumerate((1.0, -1.0)):
            theta = math.atan2(rho, sign * d[2])
            scale = self.focal_pixels * theta / rho if rho > 0 else 0.0
            pixels[k, 0] = sign * d[0] * scale + self.principal_point[0]
            pixels[k, 1] = sign * d[1] * scale + self.principal_point[1]
        return DirectionImages(pixels, p.visible.copy())

    # ------------------------------------------------------------------ planes through the centre
    def plane_image_conics(self, normals_world: npt.ArrayLike, *, check: bool = True) -> None:
        """None: a plane through the centre does not image to a conic (its arcs: :meth:`plane_image_arcs`)."""
        if check:
            as_normals(normals_world)
        return None

    def plane_image_lines(self, normals_world: npt.ArrayLike, *, check: bool = True) -> None:
        """None: a plane through the centre does not image to a line."""
        if check:
            as_normals(normals_world)
        return None

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96, *,
                         check: bool = True) -> list[list[np.ndarray]]:
        r"""Per world normal, the drawn arc of its plane's image: the great circle :math:`s(t) = \cos t\, u + \sin t\,
        v` inside the cap :math:`s_z \ge \cos\theta_\rho`, sampled with ``n_samples`` points and projected (module
        docstring). A circle wholly inside the cap is one closed polyline of ``n_samples + 1`` points.

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN and a whole
        number ``n_samples`` in ``3..MAX_SAMPLES``; nothing is checked.
        """
        n, n_samples = arc_normals(normals_world, n_samples, check)
        out: list[list[np.ndarray]] = [[] for _ in range(len(n))]
        good = finite_nonzero_rows(n)
        if len(good) == 0:
            return out
        nl = n[good] @ self.pose.R
        u, v = _circle_basis(nl / np.linalg.norm(nl, axis=1, keepdims=True))
        c = self._cap_cosine
        A = np.hypot(u[:, 2], v[:, 2])
        full = -A >= c
        drawn = np.flatnonzero(full | (A > c))
        if len(drawn) == 0:
            return out
        u, v, A, full = u[drawn], v[drawn], A[drawn], full[drawn]
        theta = np.empty((len(drawn), n_samples + 1))
        theta[:] = 2.0 * np.pi * np.arange(n_samples + 1) / n_samples
        part = np.flatnonzero(~full)
        if len(part):
            half = np.arccos(np.minimum(1.0, c / A[part]))
            t = np.append(np.arange(n_samples) / (n_samples - 1), 1.0)
            theta[part] = np.arctan2(v[part, 2], u[part, 2])[:, None] + half[:, None] * (2.0 * t - 1.0)
        cos, sin = np.cos(theta)[:, :, None], np.sin(theta)[:, :, None]
        s = cos * u[:, None, :] + sin * v[:, None, :]  # (circle, sample, 3) unit rays
        pix = self._project_local(s.reshape(-1, 3)).pixels.reshape(len(drawn), n_samples + 1, 2)
        # A sample on the cap's edge may round to just outside the field of view: keep it where the cap is inside.
        pix = np.where(np.isnan(pix), self._unclipped(s), pix)
        pix[full, -1] = pix[full, 0]
        for k, row in enumerate(good[drawn].tolist()):
            out[row] = [pix[k] if full[k] else pix[k, :n_samples]]
        return out

    def _unclipped(self, s: np.ndarray) -> np.ndarray:
        """The projection formula of unit rays ``s`` (..., 3) without the field-of-view test."""
        rho = np.hypot(s[..., 0], s[..., 1])
        theta = np.arctan2(rho, s[..., 2])
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(rho > 0, self.focal_pixels * theta / rho, 0.0)
        return np.stack([s[..., 0] * scale + self.principal_point[0], s[..., 1] * scale + self.principal_point[1]],
                        axis=-1)

    @cached_property
    def rim_radius(self) -> float:
        r"""Radius in pixels of the drawn disc: :math:`f\,\Theta/2`, or the distance to the farthest sensor corner
        when that is nearer."""
        u0, v0 = self.principal_point
        corner = max(math.hypot(cu - u0, cv - v0) for cu in (0.0, self.width) for cv in (0.0, self.height))
        return min(self.focal_pixels * self.half_angle, corner)

    @cached_property
    def _cap_cosine(self) -> float:
        return math.cos(self.rim_radius / self.focal_pixels)

    def rim(self, n: int = 128) -> np.ndarray:
        """Closed polyline (n + 1, 2) of the drawn disc's boundary, radius :attr:`rim_radius`."""
        n = check_sample_count(n, "n", 3)
        t = 2.0 * np.pi * np.arange(n + 1) / n
        u0, v0 = self.principal_point
        out = np.column_stack([u0 + self.rim_radius * np.cos(t), v0 + self.rim_radius * np.sin(t)])
        out[-1] = out[0]
        return out


def _circle_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Orthonormal rows :math:`u, v` spanning the planes of unit normals ``n`` (N, 3)."""
    h = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    u = np.cross(n, h)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(n, u)
