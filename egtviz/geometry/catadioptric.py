r"""Central catadioptric (panoramic) camera: a mirror plus a CCD.

EGT reference, section 3; ``docs/conventions.md``, "Central catadioptric
camera". A world point :math:`X_w` goes into the mirror frame,
:math:`X = R^T (X_w - t)`, the ray from the focus towards it meets the mirror at
:math:`X_h = \lambda X` (:math:`\lambda > 0`, see
:meth:`~egtviz.geometry.mirrors.HyperbolicMirror.intersect`), and the CCD images
the mirror point:

.. math::
    m \sim K (X_h + (0, 0, 2e)) \quad \text{(hyperbolic, pin-hole CCD at } (0,0,-2e)),
    \qquad m \sim K (x_h, y_h, 1) \quad \text{(parabolic, orthographic CCD)}.

The same pixels follow from the unified sphere model (Geyer & Daniilidis;
Barreto): with the *unified frame* obtained from the mirror frame by the
rotation :math:`F = \mathrm{diag}(1, -1, -1)` (its z axis points from the mirror
to the CCD), a direction is put on the unit sphere, :math:`s = F d / |d|`, and
projected from :math:`(0, 0, -\xi)`:

.. math:: m \sim K_g \begin{bmatrix} s_x \\ s_y \\ s_z + \xi \end{bmatrix},
    \qquad K_g = K\, \mathrm{diag}(\gamma, -\gamma, 1),

with :math:`\xi`, :math:`\gamma` from the mirror (:attr:`HyperbolicMirror.xi`,
:attr:`HyperbolicMirror.gamma`). Indeed for the hyperbola with a unit direction
:math:`\lambda = b^2 / (a - e d_z)` and
:math:`x_h / (z_h + 2e) = b^2 d_x / (2ae - (a^2 + e^2) d_z) = \gamma d_x / (\xi - d_z)`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import numpy.typing as npt

from ._validate import MAX_IMAGE_SIZE, GeometryError, as_calibration, as_count, as_points, as_up_to_scale_rows
from .mirrors import HyperbolicMirror, Mirror, ParabolicMirror
from .poses import Pose

__all__ = ["CatadioptricCamera", "PanoramicProjection", "UNIFIED_FLIP"]

#: Rotation from the mirror frame to the unified-model frame (a half turn about x).
UNIFIED_FLIP = np.diag([1.0, -1.0, -1.0])
UNIFIED_FLIP.setflags(write=False)

_DEFAULT_K = ((1e3, 0.0, 320.0), (0.0, 1e3, 240.0), (0.0, 0.0, 1.0))


@dataclass(frozen=True, eq=False)
class PanoramicProjection:
    """Result of projecting points through a catadioptric camera."""

    pixels: np.ndarray
    """(N, 2) pixel coordinates; NaN where not ``visible``."""
    mirror_points: np.ndarray
    """(N, 3) mirror points :math:`X_h` in the mirror frame; NaN where not ``visible``."""
    visible: np.ndarray
    """(N,) bool: the ray from the focus meets the mirror inside the rim."""
    in_image: np.ndarray
    """(N,) bool: ``visible`` and the pixel lies in ``[0, width] x [0, height]``."""


@dataclass(frozen=True, eq=False)
class CatadioptricCamera:
    r"""A central catadioptric camera: mirror with focus at ``pose.t``, axis ``pose.R[:, 2]``.

    Args:
        pose: the mirror frame in the world (``H = [R t; 0 1]``; ``R = I`` is an
            upright mirror).
        mirror: a :class:`HyperbolicMirror` (pin-hole CCD) or
            :class:`ParabolicMirror` (orthographic CCD).
        K: (3, 3) CCD calibration. For the orthographic CCD its focal entries
            are pixels per scene unit.
        width: image width in pixels.
        height: image height in pixels.

    Raises:
        GeometryError: on a bad pose, mirror, calibration or image size.
    """

    pose: Pose = field(default_factory=Pose)
    """Mirror frame in the world."""
    mirror: Mirror = field(default_factory=HyperbolicMirror)
    """The mirror (EGT's default: hyperbolic, ``a = 3``, ``b = 1``)."""
    K: np.ndarray = field(default_factory=lambda: np.array(_DEFAULT_K))
    """(3, 3) calibration of the CCD, normalised to ``K[2, 2] = 1``."""
    width: int = 640
    """Image width in pixels."""
    height: int = 480
    """Image height in pixels."""

    def __post_init__(self) -> None:
        if not isinstance(self.pose, Pose):
            raise GeometryError(f"pose: expected a Pose, got {type(self.pose).__name__}")
        if not isinstance(self.mirror, (HyperbolicMirror, ParabolicMirror)):
            raise GeometryError(
                f"mirror: expected a HyperbolicMirror or ParabolicMirror, got {type(self.mirror).__name__}"
            )
        K = as_calibration(self.K, "K").copy()
        K.setflags(write=False)
        object.__setattr__(self, "K", K)
        for name in ("width", "height"):
            object.__setattr__(self, name, as_count(getattr(self, name), name, minimum=1, maximum=MAX_IMAGE_SIZE))

    # ------------------------------------------------------------------ frames
    def moved(self, pose: Pose) -> CatadioptricCamera:
        """The same camera at a new pose."""
        return replace(self, pose=pose)

    @property
    def focus_world(self) -> np.ndarray:
        """(3,) the mirror focus (single viewpoint) in the world, ``pose.t``."""
        return self.pose.t.copy()

    @property
    def ccd_center_world(self) -> np.ndarray:
        """(3,) the CCD's position in the world: the point ``(0, 0, -ccd_offset)`` of the mirror frame.

        For the hyperbola this is the CCD pin-hole (second focus, ``2 e`` below
        the focus); for the parabola's orthographic CCD it is only where it is drawn.
        """
        return self.pose.to_world([0.0, 0.0, -self.mirror.ccd_offset])[0]

    @property
    def unified_calibration(self) -> np.ndarray:
        r"""The generalised calibration :math:`K_g = K\,\mathrm{diag}(\gamma, -\gamma, 1)` of the unified model."""
        g = self.mirror.gamma
        return self.K @ np.diag([g, -g, 1.0])

    # -------------------------------------------------------------- projection
    def project(self, X_world: npt.ArrayLike) -> PanoramicProjection:
        r"""Project world points through the mirror onto the CCD.

        .. math:: X = R^T (X_w - t), \quad X_h = \lambda X, \quad
            m \sim K (X_h + (0, 0, 2e)) \ \text{or}\ m \sim K (x_h, y_h, 1).

        Args:
            X_world: (N, 3) world points (a single (3,) point is N = 1).

        Returns:
            A :class:`PanoramicProjection`; points in the blind cone, above the
            rim or at the focus itself have NaN pixels and ``visible = False``.
        """
        return self._project_world(as_points(X_world, "X_world", 3))

    def _project_world(self, X: np.ndarray) -> PanoramicProjection:
        """:meth:`project` of checked (N, 3) float64 world points (internal: no conversion, no check)."""
        return self._project_mirror_frame((X - self.pose.t) @ self.pose.R)

    def project_directions(self, d_mirror: npt.ArrayLike) -> PanoramicProjection:
        """Like :meth:`project` for ray directions ``d_mirror`` (N, 3) already in the mirror frame.

        A direction is defined up to scale (each is first divided by its largest entry, so any finite
        magnitude gives the same pixels and mirror points); a zero direction is no ray and is not visible.
        """
        return self._project_mirror_frame(as_up_to_scale_rows(d_mirror, "d_mirror", 3, allow_zero=True))

    def _project_mirror_frame(self, d: np.ndarray) -> PanoramicProjection:
        dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
        lam, visible = self.mirror._intersect_xyz(dx, dy, dz)
        Xh = lam[:, None] * d  # NaN rows where not visible
        pixels = np.empty((len(d), 2))
        self._ray_pixels(lam, dx, dy, dz, pixels[:, 0], pixels[:, 1])
        return PanoramicProjection(pixels, Xh, visible, visible & self._inside(pixels))

    @cached_property
    def _ccd_constants(self) -> tuple[float | None, tuple[float, ...]]:
        """``(ccd_offset or None for the orthographic CCD, (K00, K01, K02, K10, K11, K12))`` as floats."""
        offset = self.mirror.ccd_offset if isinstance(self.mirror, HyperbolicMirror) else None
        return offset, tuple(self.K[:2].ravel().tolist())

    def _ray_pixels(self, lam: np.ndarray, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray,
                    u: np.ndarray, v: np.ndarray) -> None:
        r"""Pixels of the mirror points :math:`X_h = \lambda d` (coordinates as arrays of one shape) into ``u``, ``v``.

        The CCD point is :math:`P = X_h + (0, 0, 2e)` (hyperbolic) or :math:`(x_h, y_h, 1)` (orthographic),
        then :math:`m \sim K P`: the arithmetic of :meth:`_pixels`, per coordinate (no (N, 3) temporaries).
        """
        offset = self._ccd_constants[0]
        x = lam * dx
        y = lam * dy
        if offset is not None:
            pz = lam * dz
            pz += offset
            with np.errstate(divide="ignore", invalid="ignore"):
                x /= pz
                y /= pz
        self._affine_pixels(x, y, u, v)

    def _affine_pixels(self, x: np.ndarray, y: np.ndarray, u: np.ndarray, v: np.ndarray) -> None:
        """``u = K00 x + K01 y + K02``, ``v = K10 x + K11 y + K12`` (into ``u``, ``v``); zero entries are skipped."""
        _, (k00, k01, k02, k10, k11, k12) = self._ccd_constants
        np.multiply(x, k00, out=u)
        if k01 != 0.0:
            u += k01 * y
        u += k02
        np.multiply(y, k11, out=v)
        if k10 != 0.0:
            v += k10 * x
        v += k12

    def _direction_pixel(self, dx: float, dy: float, dz: float) -> tuple[float, float] | None:
        """:meth:`project_directions` of one mirror-frame direction in plain floats (the epipoles, on every drag):
        its pixel ``(u, v)``, or None where the mirror does not show it. The arithmetic of :meth:`_ray_pixels`."""
        lam = self.mirror._hit_parameter(dx, dy, dz)
        if lam is None:
            return None
        offset, (k00, k01, k02, k10, k11, k12) = self._ccd_constants
        x, y = lam * dx, lam * dy
        if offset is not None:
            pz = lam * dz + offset
            x, y = x / pz, y / pz
        return k00 * x + k01 * y + k02, k10 * x + k11 * y + k12

    def _unit_ray_pixels(self, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray, u: np.ndarray, v: np.ndarray) -> None:
        r"""Pixels of unit directions (mirror frame, coordinates as arrays of one shape) known to be visible, into
        ``u`` and ``v`` (arrays of that shape, maybe strided views).

        Internal, for the epipolar conics' samples (visible by construction, so there is no rim test): the mirror
        path of :meth:`project_directions` with :math:`|d| = 1` and the ray parameter :math:`\lambda` divided out
        of the CCD point, which keeps its accuracy near the blind cone:

        .. math:: P \sim d + \Big(0, 0, \frac{2e}{\lambda}\Big), \ \frac{2e}{\lambda} = \frac{2e}{b^2}(a - e d_z)
            \ \text{(hyperbolic)}, \qquad
            P \sim \Big(d_x, d_y, \frac{1}{\lambda}\Big), \ \frac{1}{\lambda} = \frac{1 - d_z}{h}
            = \frac{d_x^2 + d_y^2}{(1 + d_z)\,h} \ \text{(parabolic)},

        then :math:`m \sim K P`.
        """
        if isinstance(self.mirror, HyperbolicMirror):
            a, b2, e = self.mirror._ray_constants
            w = dz * -e
            w += a
            w *= 2.0 * e / b2
            w += dz
        else:
            rho2 = dx * dx
            rho2 += dy * dy
            with np.errstate(divide="ignore", invalid="ignore"):
                # 1 - d_z without cancellation when the ray points up (d_z > 0).
                w = np.where(dz > 0, rho2 / (1.0 + dz), 1.0 - dz)
            w /= self.mirror.h
        self._affine_pixels(dx / w, dy / w, u, v)

    def _pixels(self, P: np.ndarray) -> np.ndarray:
        """Pixels of CCD-frame points ``P`` (N, 3): ``K P`` dehomogenised (element-wise, no BLAS)."""
        x = P[:, 0] / P[:, 2]
        y = P[:, 1] / P[:, 2]
        K = self.K
        return np.column_stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 0] * x + K[1, 1] * y + K[1, 2]])

    def _inside(self, pixels: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            u, v = pixels[:, 0], pixels[:, 1]
            return (u >= 0) & (u <= self.width) & (v >= 0) & (v <= self.height)

    def _unified_homogeneous(self, d_mirror: np.ndarray) -> np.ndarray:
        r"""Unnormalised homogeneous pixels :math:`K_g (s_x, s_y, s_z + \xi)` of (N, 3) mirror-frame directions.

        No visibility test: this is the algebraic image of the whole sphere
        (including the blind cone's phantom points), as used by the conics.
        """
        norm = np.linalg.norm(d_mirror, axis=1, keepdims=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (d_mirror / norm) @ UNIFIED_FLIP.T
        q = s + np.array([0.0, 0.0, self.mirror.xi])
        return q @ self.unified_calibration.T

    def project_unified(self, X_world: npt.ArrayLike) -> np.ndarray:
        r"""Project world points with the unified sphere model (the same pixels as :meth:`project`).

        .. math:: s = F \frac{X}{|X|}, \qquad
            m \sim K_g \begin{bmatrix} s_x \\ s_y \\ s_z + \xi \end{bmatrix}.

        Args:
            X_world: (N, 3) world points.

        Returns:
            (N, 2) pixels; NaN where the point is not visible (the unified
            formula alone would also give the phantom images of blind-cone rays).
        """
        X = self.pose.to_local(as_points(X_world, "X_world", 3))
        _, visible = self.mirror.intersect(X)
        m = self._unified_homogeneous(X)
        with np.errstate(divide="ignore", invalid="ignore"):
            pixels = m[:, :2] / m[:, 2:3]
        pixels[~visible] = np.nan
        return pixels

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        r"""Unit rays from the focus, in the world frame, that image at ``pixels``.

        Lifts :math:`q = K_g^{-1} m = (x, y, 1)` to the unit sphere (the root in
        front of the projection centre),

        .. math:: s = \eta\,(x, y, 1) - (0, 0, \xi), \qquad
            \eta = \frac{\xi + \sqrt{1 + (1 - \xi^2)(x^2 + y^2)}}{x^2 + y^2 + 1},

        then :math:`d = R F s`.

        Args:
            pixels: (N, 2) pixel coordinates.

        Returns:
            (N, 3) unit world directions; NaN rows for pixels that are not the
            image of a visible mirror point (outside the rim's image, or a
            hyperbola pixel only reachable by blind-cone rays).
        """
        m = as_points(pixels, "pixels", 2)
        q = np.column_stack([m, np.ones(len(m))]) @ np.linalg.inv(self.unified_calibration).T
        x, y = q[:, 0] / q[:, 2], q[:, 1] / q[:, 2]
        xi = self.mirror.xi
        r2 = x * x + y * y
        eta = (xi + np.sqrt(1.0 + (1.0 - xi * xi) * r2)) / (r2 + 1.0)
        s = np.column_stack([eta * x, eta * y, eta - xi])
        d = s @ UNIFIED_FLIP.T
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        # A pixel of the rim's image may round to just outside the rim: allow 1e-9.
        _, hit = self.mirror.intersect(d, rim_tol=1e-9)
        d[~hit] = np.nan
        return d @ self.pose.R.T

    def rim_image(self, n: int = 256) -> np.ndarray:
        """(n, 2) pixels of the mirror's rim: the outer boundary of the mirror's image."""
        P = self.mirror.rim_points(n)  # checks n
        if isinstance(self.mirror, HyperbolicMirror):
            P = P + np.array([0.0, 0.0, self.mirror.ccd_offset])
        else:
            P = np.column_stack([P[:, 0], P[:, 1], np.ones(len(P))])
        return self._pixels(P)
