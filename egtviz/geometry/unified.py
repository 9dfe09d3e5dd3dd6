r"""The unified sphere camera: one parameter :math:`\xi` from a pin-hole to a parabolic mirror.

Geyer & Daniilidis (2000) and Barreto & Araujo (2001) showed that every central catadioptric camera
projects like this: put the ray direction :math:`d` on the unit sphere around the centre and project it
from a point on the sphere's axis at distance :math:`\xi` from the centre (``docs/conventions.md``,
"Unified sphere model").

**Model frame.** The frame of :attr:`UnifiedCamera.pose` is a pin-hole camera's frame: x right, y down,
z forward (the optical axis). The projection centre is :math:`(0, 0, -\xi)`, on the axis *behind* the
sphere's centre (the conventions' point :math:`(0, 0, \xi)` of the mirror frame, whose z axis points
the other way; this frame is the catadioptric camera's *unified frame*), and the image plane is perpendicular
to the axis:

.. math::
    s = \frac{d}{|d|}, \qquad
    m \sim K \begin{bmatrix} s_x \\ s_y \\ s_z + \xi \end{bmatrix}, \qquad
    K = \begin{bmatrix} f & 0 & u_0 \\ 0 & f & v_0 \\ 0 & 0 & 1 \end{bmatrix}.

A ray has an image iff the denominator is positive, :math:`s_z + \xi > 0`. So :math:`\xi = 0` is exactly
a pin-hole camera with calibration :math:`K` (only the front hemisphere :math:`s_z > 0` is seen),
:math:`\xi = 1` is a parabolic mirror (every ray but :math:`-z`; stereographic projection) and
:math:`0 < \xi < 1` a hyperbolic one: a :class:`~egtviz.geometry.catadioptric.CatadioptricCamera` whose
``unified_calibration`` is :math:`K` and whose mirror frame is this frame turned half a turn about x
gives the same pixels wherever its mirror shows the ray.

**Back-projection** lifts :math:`q = K^{-1} m = (x, y, 1)`, :math:`r^2 = x^2 + y^2`, to the sphere point
in front of the projection centre:

.. math::
    s = \big(\eta x,\ \eta y,\ \eta - \xi\big), \qquad
    \eta = \frac{\xi + \sqrt{1 + (1 - \xi^2) r^2}}{1 + r^2}, \qquad
    \eta - \xi = \frac{1 - \xi^2 r^2}{\sqrt{1 + (1 - \xi^2) r^2} + \xi r^2}.

**Planes through the centre.** A plane with unit normal :math:`n` (model frame) cuts the sphere in a great
circle whose image is the conic :math:`C = K^{-T} \Omega K^{-1}` (substitute the lifted :math:`s` in
:math:`n \cdot s = 0`, :math:`|s| = 1`):

.. math:: \Omega = (1 - \xi^2)\, n n^T + \xi^2 n_z (e_3 n^T + n e_3^T) - \xi^2 n_z^2 I.

For :math:`\xi = 0`, :math:`\Omega = n n^T`: the double line :math:`l l^T`, :math:`l = K^{-T} n`.

**Drawn region.** Everything that lands on the sensor lies in the disc around the principal point through
the sensor's farthest corner; the camera draws curves inside that disc (:meth:`UnifiedCamera.rim`). The
normalised image radius :math:`r = \sin\theta / (\cos\theta + \xi)` grows with the angle :math:`\theta`
from the axis, so the disc of radius :math:`\rho` is the image of the spherical cap
:math:`s_z \ge c_\rho = (1 - \xi^2 \rho^2) / (\sqrt{1 + (1 - \xi^2)\rho^2} + \xi \rho^2)` (:math:`> -\xi`),
and a great circle's drawn part is the single arc of the circle inside that cap.

**Horizon.** The image of the great circle :math:`s_z = 0` (the boundary of the forward hemisphere, the
field of the :math:`\xi = 0` pin-hole): the circle of radius :math:`f / \xi` about the principal point.
Forward rays image inside it, backward rays that are still seen (:math:`-\xi < s_z < 0`) outside; for
:math:`\xi = 0` it is at infinity (:meth:`UnifiedCamera.horizon` returns None).
"""

from __future__ import annotations

import math
from dataclasses import InitVar, dataclass, field
from functools import cached_property
from typing import ClassVar, cast

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_points, as_positive, as_vector
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
    unchecked_normals,
)
from .homogeneous import normalize_homogeneous
from .poses import Pose
from .unified_sphere import great_circle_conics

__all__ = ["UnifiedCamera"]


@dataclass(frozen=True, eq=False)
class UnifiedCamera:
    r"""A camera of the unified sphere model (see the module docstring for frame and formulas).

    Args:
        pose: the model frame in the world (x right, y down, z forward; ``H = [R t; 0 1]``).
        xi: :math:`\xi \in [0, 1]`, the distance from the sphere's centre back to the projection centre.
        focal_pixels: :math:`f > 0` in pixels.
        principal_point: :math:`(u_0, v_0)` in pixels.
        width: image width in pixels.
        height: image height in pixels.
        check: check the parameters against :attr:`PARAMETERS` (the pose is always checked). ``False`` is the fast
            path for values taken from a camera that was checked (what :meth:`moved` does).

    Raises:
        GeometryError: naming the field, when one is outside its range (:attr:`PARAMETERS`).
    """

    pose: Pose = field(default_factory=Pose)
    """The model frame in the world."""
    xi: float = 0.8
    """Sphere-model parameter: 0 pin-hole, 1 parabolic, between: hyperbolic."""
    focal_pixels: float = 300.0
    """Focal length in pixels."""
    principal_point: tuple[float, float] = (320.0, 240.0)
    """(u0, v0) in pixels."""
    width: int = 640
    """Image width in pixels."""
    height: int = 480
    """Image height in pixels."""
    check: InitVar[bool] = True

    kind: ClassVar[str] = "unified"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = (
        ParameterSpec("xi", "xi", "", 0.0, 1.0, 0.8),
        ParameterSpec("focal_pixels", "focal length", "px", 1.0, 1e6, 300.0),
        *PRINCIPAL_POINT_PARAMETERS,
        *IMAGE_SIZE_PARAMETERS,
    )
    no_image: ClassVar[str] = "behind the projection centre"

    def __post_init__(self, check: bool) -> None:
        check_pose(self.pose)
        if check is not False:
            check_parameters(self, ("xi", "focal_pixels", "width", "height"))

    # ------------------------------------------------------------------ parameters and frames
    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> UnifiedCamera:
        """The camera at ``pose`` with parameters ``xi``, ``focal_pixels``, ``u0``, ``v0``, ``width``, ``height``."""
        return camera_from_parameters(cls, cls.PARAMETERS, pose, values)

    def parameters(self) -> dict[str, float | int]:
        return parameter_values(self)

    def moved(self, pose: Pose) -> UnifiedCamera:
        """The same camera at another pose (the fast path of a drag: the parameters, checked once, are not checked again)."""
        check_pose(pose)
        return UnifiedCamera(pose, self.xi, self.focal_pixels, self.principal_point, self.width, self.height,
                             check=False)

    @property
    def centre(self) -> np.ndarray:
        """(3,) the sphere's centre (the single viewpoint) in the world, ``pose.t``."""
        return self.pose.t

    @property
    def projective_calibration(self) -> np.ndarray | None:
        r""":math:`K` for :math:`\xi = 0` (the model is then a pin-hole camera), else None."""
        return self.K if self.xi == 0.0 else None

    def light_paths(self, X_world: npt.ArrayLike, radius: float = 0.5, *, check: bool = True) -> np.ndarray:
        """(N, 3, 3) polylines point -> its point on the sphere of ``radius`` -> the projection centre; NaN rows for
        points without an image.

        ``check=False``: as for :meth:`project`, and ``radius`` a positive float (not checked).
        """
        if check:
            X, radius = as_points(X_world, "X_world", 3), as_positive(radius, "radius")
        else:
            X = cast(np.ndarray, X_world)
        v = X - self.pose.t
        out = np.empty((len(X), 3, 3))
        out[:, 0] = X
        out[:, 1] = self._sphere_points(v, radius)
        out[:, 2] = self._projection_centre(radius)
        out[~self._project_local(v @ self.pose.R).visible] = np.nan
        return out

    @cached_property
    def K(self) -> np.ndarray:
        """(3, 3) read-only calibration ``[[f, 0, u0], [0, f, v0], [0, 0, 1]]``."""
        u0, v0 = self.principal_point
        f = self.focal_pixels
        K = np.array([[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]])
        K.setflags(write=False)
        return K

    @cached_property
    def _K_inv(self) -> np.ndarray:
        u0, v0 = self.principal_point
        f = self.focal_pixels
        K_inv = np.array([[1.0 / f, 0.0, -u0 / f], [0.0, 1.0 / f, -v0 / f], [0.0, 0.0, 1.0]])
        K_inv.setflags(write=False)
        return K_inv

    def projection_centre(self, radius: float = 1.0, *, check: bool = True) -> np.ndarray:
        r"""(3,) world position of the projection centre :math:`(0, 0, -\xi)` for a sphere of ``radius``
        (``check=False``: the caller promises a positive float ``radius``)."""
        return self._projection_centre(as_positive(radius, "radius") if check else radius)

    def _projection_centre(self, radius: float) -> np.ndarray:
        return self.pose.t - (radius * self.xi) * self.pose.R[:, 2]

    def sphere_points(self, X_world: npt.ArrayLike, radius: float = 1.0, *, check: bool = True) -> np.ndarray:
        """(N, 3) world points where the rays to ``X_world`` (N, 3) cross the sphere of ``radius``.

        A point at the centre has no ray: NaN row. ``check=False``: the caller promises a float64 (N, 3) (or (3,))
        finite ``X_world`` and a positive ``radius``; nothing is checked.
        """
        if check:
            radius, X = as_positive(radius, "radius"), as_points(X_world, "X_world", 3)
        else:
            X = cast(np.ndarray, X_world).reshape(-1, 3)
        return self._sphere_points(X - self.pose.t, radius)

    def _sphere_points(self, v: np.ndarray, radius: float) -> np.ndarray:
        """:meth:`sphere_points` of the offsets ``v = X - t`` (N, 3), unchecked."""
        norm = np.linalg.norm(v, axis=1, keepdims=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(norm > 0, v / norm, np.nan)
        return self.pose.t + radius * s

    def great_circle(self, normal_world: npt.ArrayLike, n: int = 128, radius: float = 1.0, *,
                     check: bool = True) -> np.ndarray:
        """Closed world polyline (n + 1, 3) of the sphere's great circle in the plane through the centre with
        normal ``normal_world`` (3,).

        ``check=False``: the caller promises a float64 (3,) finite ``normal_world``, a whole number ``n`` in range
        and a positive ``radius``; nothing is checked (a zero normal still raises).
        """
        if check:
            n = check_sample_count(n, "n", 3)
            radius = as_positive(radius, "radius")
            normal = as_vector(normal_world, "normal_world", 3)
        else:
            normal = cast(np.ndarray, normal_world)
        norm = np.linalg.norm(normal)
        if not norm > 0:
            raise GeometryError("normal_world: a zero normal defines no plane")
        u, v = _circle_basis((normal / norm)[None, :])
        theta = 2.0 * np.pi * np.arange(n + 1) / n
        theta[-1] = 0.0
        return self.pose.t + radius * (np.cos(theta)[:, None] * u[0] + np.sin(theta)[:, None] * v[0])

    # ------------------------------------------------------------------ projection
    def project(self, X_world: npt.ArrayLike, *, check: bool = True) -> CameraProjection:
        r"""Project world points (N, 3) through the sphere.

        .. math:: s = \frac{R^T (X - t)}{|R^T (X - t)|}, \qquad m \sim K (s_x, s_y, s_z + \xi).

        Args:
            X_world: (N, 3) world points.
            check: convert and check ``X_world`` (default). ``check=False``: the caller promises a float64 (N, 3)
                array of finite values within ``MAX_MAGNITUDE``; nothing is converted or checked, and anything else
                gives an undefined result (never a ``GeometryError``).

        Returns:
            A :class:`~egtviz.geometry.camera_model.CameraProjection`: NaN pixels and ``visible`` False where
            :math:`s_z + \xi \le 0` (for :math:`\xi = 0`, behind the camera) or at the centre itself.
        """
        X = as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world)
        return self._project_local((X - self.pose.t) @ self.pose.R)

    def _project_local(self, d: np.ndarray) -> CameraProjection:
        norm = np.linalg.norm(d, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = d / norm[:, None]
            den = s[:, 2] + self.xi
            visible = (norm > 0) & (den > 0)
            scale = self.focal_pixels / den
            u0, v0 = self.principal_point
            pixels = np.column_stack([s[:, 0] * scale + u0, s[:, 1] * scale + v0])
        pixels[~visible] = np.nan
        with np.errstate(invalid="ignore"):
            u, v = pixels[:, 0], pixels[:, 1]
            in_image = visible & (u >= 0) & (u <= self.width) & (v >= 0) & (v <= self.height)
        return CameraProjection(pixels, visible, in_image)

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        r"""Unit world rays (N, 3) of pixels (N, 2) by the closed-form lifting (module docstring).

        Every pixel is the image of exactly one visible ray, so no row is NaN; the ray's sphere point
        satisfies :math:`s_z + \xi = \eta > 0`.
        """
        m = as_points(pixels, "pixels", 2)
        u0, v0 = self.principal_point
        x = (m[:, 0] - u0) / self.focal_pixels
        y = (m[:, 1] - v0) / self.focal_pixels
        r2 = x * x + y * y
        xi = self.xi
        root = np.sqrt(1.0 + (1.0 - xi * xi) * r2)
        eta = (xi + root) / (1.0 + r2)
        s = np.column_stack([eta * x, eta * y, (1.0 - xi * xi * r2) / (root + xi * r2)])
        s /= np.linalg.norm(s, axis=1, keepdims=True)
        return s @ self.pose.R.T

    def baseline_images(self, direction_world: npt.ArrayLike, *, check: bool = True) -> DirectionImages:
        r"""The images :math:`K (s_x, s_y, s_z + \xi)` of :math:`s = \pm R^T d / |d|`, visible where
        :math:`s_z + \xi > 0` (the image of a ray not seen is the other intersection of its line with the
        sphere's image, still on every conic of a plane containing the line).

        ``check=False``: the caller promises a float64 (3,) finite, non-zero ``direction_world`` (not checked).
        """
        d = self.pose.R.T @ (as_direction(direction_world) if check else direction_world)
        s = np.stack([d, -d]) / np.linalg.norm(d)
        q = s.copy()
        q[:, 2] += self.xi
        return DirectionImages(normalize_homogeneous(q @ self.K.T), q[:, 2] > 0)

    # ------------------------------------------------------------------ planes through the centre
    def plane_image_conics(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        r"""Image conics (N, 3, 3) :math:`C = K^{-T} \Omega K^{-1}` of planes through the centre (world normals
        (N, 3)), symmetric with unit Frobenius norm (sign arbitrary); NaN rows for zero or NaN normals.

        ``C`` is the image of the whole great circle; where :math:`\xi > 0` and the circle dips below
        :math:`s_z = -\xi`, part of it (a branch to infinity) belongs to rays that are not seen.

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN.
        """
        n = as_normals(normals_world) if check else unchecked_normals(cast(np.ndarray, normals_world))
        return great_circle_conics(n @ self.pose.R, self.xi, self._K_inv)

    def plane_image_lines(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray | None:
        r"""For :math:`\xi = 0` (a pin-hole) the image lines :math:`l = K^{-T} R^T n` (N, 3), NaN rows for zero or NaN
        normals; otherwise None.

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN.
        """
        if self.xi != 0.0:
            return None
        n = as_normals(normals_world) if check else unchecked_normals(cast(np.ndarray, normals_world))
        lines = np.full((len(n), 3), np.nan)
        good = finite_nonzero_rows(n)
        lines[good] = (n[good] @ self.pose.R) @ self._K_inv
        return lines

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96, *,
                         check: bool = True) -> list[list[np.ndarray]]:
        r"""Per world normal, the drawn arc of its plane's image: the part of the great circle inside the cap
        :math:`s_z \ge c_\rho` of the drawn disc (module docstring).

        On the circle :math:`s(\theta) = \cos\theta\, u + \sin\theta\, v` (:math:`u, v` orthonormal, normal to
        :math:`n`), :math:`s_z = A \cos(\theta - \theta_0)` with :math:`A = \sqrt{u_z^2 + v_z^2}`, so the arc is
        :math:`|\theta - \theta_0| \le \arccos(c_\rho / A)`, sampled with ``n_samples`` points, both ends on
        the rim; a circle wholly inside the cap is one closed polyline of ``n_samples + 1`` points. Every
        sample has :math:`s_z + \xi \ge c_\rho + \xi > 0`: no invisible ray and no branch to infinity.

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN and a whole
        number ``n_samples`` in ``3..MAX_SAMPLES``; nothing is checked.

        Returns:
            For each normal a list with one (k, 2) polyline, or an empty list (zero or NaN normal, or the
            circle misses the cap).
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
        # Angles (circle, sample): a closed turn for the full circles, the arc about theta0 for the others
        # (every circle has n_samples + 1 columns; a partial arc's last column repeats its end and is dropped).
        theta = np.empty((len(drawn), n_samples + 1))
        theta[:] = 2.0 * np.pi * np.arange(n_samples + 1) / n_samples
        part = np.flatnonzero(~full)
        if len(part):
            half = np.arccos(np.minimum(1.0, c / A[part]))
            t = np.append(np.arange(n_samples) / (n_samples - 1), 1.0)
            theta[part] = np.arctan2(v[part, 2], u[part, 2])[:, None] + half[:, None] * (2.0 * t - 1.0)
        cos, sin = np.cos(theta), np.sin(theta)
        # s = cos(theta) u + sin(theta) v per coordinate (circle, sample); m = f (s_x, s_y) / (s_z + xi) + (u0, v0).
        scale = cos * u[:, 2:3]
        scale += sin * v[:, 2:3]
        scale += self.xi
        np.divide(self.focal_pixels, scale, out=scale)
        pix = np.empty((len(drawn), n_samples + 1, 2))
        for j, c0 in enumerate(self.principal_point):
            coord = cos * u[:, j:j + 1]
            coord += sin * v[:, j:j + 1]
            coord *= scale
            coord += c0
            pix[:, :, j] = coord
        pix[full, -1] = pix[full, 0]
        for k, row in enumerate(good[drawn].tolist()):
            out[row] = [pix[k] if full[k] else pix[k, :n_samples]]
        return out

    @cached_property
    def rim_radius(self) -> float:
        """Radius in pixels of the drawn disc: the distance from the principal point to the farthest sensor corner."""
        u0, v0 = self.principal_point
        return max(math.hypot(cu - u0, cv - v0) for cu in (0.0, self.width) for cv in (0.0, self.height))

    @cached_property
    def _cap_cosine(self) -> float:
        r""":math:`c_\rho`: the cap :math:`s_z \ge c_\rho` images onto the drawn disc (module docstring)."""
        rho2 = (self.rim_radius / self.focal_pixels) ** 2
        xi = self.xi
        return (1.0 - xi * xi * rho2) / (math.sqrt(1.0 + (1.0 - xi * xi) * rho2) + xi * rho2)

    def rim(self, n: int = 128) -> np.ndarray:
        """Closed polyline (n + 1, 2) of the drawn disc's boundary, radius :attr:`rim_radius`."""
        return _circle(self.principal_point, self.rim_radius, check_sample_count(n, "n", 3))

    def horizon(self, n: int = 128) -> np.ndarray | None:
        r"""Closed polyline (n + 1, 2) of the horizon's image, the circle of radius :math:`f / \xi` about the
        principal point (module docstring); None for :math:`\xi = 0` (at infinity)."""
        n = check_sample_count(n, "n", 3)
        if self.xi == 0.0:
            return None
        return _circle(self.principal_point, self.focal_pixels / self.xi, n)


def _circle(centre: tuple[float, float], radius: float, n: int) -> np.ndarray:
    theta = 2.0 * np.pi * np.arange(n + 1) / n
    out = np.column_stack([centre[0] + radius * np.cos(theta), centre[1] + radius * np.sin(theta)])
    out[-1] = out[0]
    return out


def _circle_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Orthonormal rows :math:`u = n \times h / |n \times h|`, :math:`v = n \times u` for unit normals ``n`` (N, 3);
    :math:`h = e_x` unless :math:`|n_x| \ge 0.9`, then :math:`e_y`."""
    h = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    u = np.cross(n, h)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(n, u)
