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

from dataclasses import InitVar, dataclass, field
from functools import cached_property
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from ._validate import (
    MAX_IMAGE_SIZE,
    GeometryError,
    as_calibration,
    as_count,
    as_points,
    as_up_to_scale_rows,
    short_repr,
)
from .camera_model import (
    IMAGE_SIZE_PARAMETERS,
    PRINCIPAL_POINT_PARAMETERS,
    DirectionImages,
    ParameterSpec,
    arc_normals,
    as_direction,
    as_normals,
    check_pose,
    check_sample_count,
    finite_nonzero_rows,
    parameters_from_specs,
    unchecked_normals,
)
from .homogeneous import normalize_homogeneous
from .mirrors import HyperbolicMirror, Mirror, ParabolicMirror
from .poses import Pose
from .unified_sphere import great_circle_arcs, great_circle_conics

__all__ = [
    "B_OVER_A_RANGE",
    "HYPERBOLIC",
    "PARABOLIC",
    "UNIFIED_FLIP",
    "CatadioptricCamera",
    "CatadioptricKind",
    "PanoramicProjection",
]

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
        check: check ``mirror``, ``K``, ``width`` and ``height`` (the pose is always checked). ``False`` is the fast
            path for values taken from a camera that was checked (what :meth:`moved` does); the caller vouches for
            them, as with pytransform3d's ``check=False``.

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
    check: InitVar[bool] = True

    no_image = "in the blind cone"
    """Where points without an image lie (the camera-model interface)."""

    def __post_init__(self, check: bool) -> None:
        check_pose(self.pose)
        if check is not False:
            self._check_fields()

    def _check_fields(self) -> None:
        if not isinstance(self.mirror, (HyperbolicMirror, ParabolicMirror)):
            raise GeometryError(
                f"mirror: expected a HyperbolicMirror or ParabolicMirror, got {type(self.mirror).__name__}"
            )
        K = as_calibration(self.K, "K").copy()
        K.setflags(write=False)
        object.__setattr__(self, "K", K)
        for name in ("width", "height"):
            object.__setattr__(self, name, as_count(getattr(self, name), name, minimum=1, maximum=MAX_IMAGE_SIZE))

    # ------------------------------------------------------------------ the camera-model interface
    @property
    def kind(self) -> str:
        """The registry kind: the mirror's shape, ``"hyperbolic"`` or ``"parabolic"``."""
        return self.mirror.kind

    @property
    def PARAMETERS(self) -> tuple[ParameterSpec, ...]:
        """The parameters of this camera's kind (:data:`HYPERBOLIC` or :data:`PARABOLIC`)."""
        return _KINDS[self.mirror.kind].PARAMETERS

    def from_parameters(self, pose: Pose, **values: float) -> CatadioptricCamera:
        """A camera of this one's kind at ``pose`` (:meth:`CatadioptricKind.from_parameters`)."""
        return _KINDS[self.mirror.kind].from_parameters(pose, **values)

    def parameters(self) -> dict[str, float | int]:
        """The mirror's parameters (``a``, ``b`` or ``h``), then ``focal_pixels``, ``u0``, ``v0``, ``width``,
        ``height`` of the CCD (its ``K[0, 0]`` and ``K[0, 2]``, ``K[1, 2]``)."""
        m = self.mirror
        shape = {"a": m.a, "b": m.b} if isinstance(m, HyperbolicMirror) else {"h": m.h}
        K = self.K
        return {**shape, "focal_pixels": float(K[0, 0]), "u0": float(K[0, 2]), "v0": float(K[1, 2]),
                "width": self.width, "height": self.height}

    @property
    def centre(self) -> np.ndarray:
        """(3,) the mirror focus (single viewpoint) in the world, ``pose.t`` (read-only)."""
        return self.pose.t

    @property
    def projective_calibration(self) -> None:
        """None: a mirror images lines to conics, not linearly."""
        return None

    def light_paths(self, X_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        """(N, 3, 3) polylines point -> mirror point -> CCD (:attr:`ccd_center_world`); NaN rows where not visible.

        ``check=False``: as for :meth:`project`.
        """
        X = as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world)
        proj = self._project_world(X)
        out = np.empty((len(X), 3, 3))
        out[:, 0] = X
        np.matmul(proj.mirror_points, self.pose.R.T, out=out[:, 1])  # NaN rows where not visible
        out[:, 1] += self.pose.t
        out[:, 2] = self.ccd_center_world
        out[~proj.visible] = np.nan
        return out

    def baseline_images(self, direction_world: npt.ArrayLike, *, check: bool = True) -> DirectionImages:
        r"""The images of :math:`\pm R^T d` by the unified model, :math:`K_g (F \hat d + (0, 0, \xi))`, visible where
        the mirror shows the ray (both are on every image conic of a plane containing the line).

        ``check=False``: the caller promises a float64 (3,) finite, non-zero ``direction_world`` (not checked).
        """
        d = self.pose.R.T @ (as_direction(direction_world) if check else direction_world)
        dirs = np.stack([d, -d])
        s = (dirs / np.linalg.norm(d)) @ UNIFIED_FLIP.T
        s[:, 2] += self.mirror.xi
        m = s @ self.unified_calibration.T
        return DirectionImages(normalize_homogeneous(m), self._project_mirror_frame(dirs).visible)

    def plane_image_lines(self, normals_world: npt.ArrayLike, *, check: bool = True) -> None:
        """None (once the normals are checked, unless ``check=False``): a mirror images planes to conics."""
        if check:
            as_normals(normals_world)

    def plane_image_conics(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        """Image conics (N, 3, 3) of planes through the focus with world normals (N, 3) (of their mirror-frame normals
        :math:`R^T n`, ``panoramic_epipolar.conic_from_plane``); NaN rows for zero or NaN normals.

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN.
        """
        n = as_normals(normals_world) if check else unchecked_normals(cast(np.ndarray, normals_world))
        C = np.full((len(n), 3, 3), np.nan)
        good = finite_nonzero_rows(n)
        if len(good):
            C[good] = self._mirror_plane_conics(n[good] @ self.pose.R)
        return C

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96, *,
                         check: bool = True) -> list[tuple[np.ndarray, ...]]:
        """Per world normal, the arcs of its plane's image that the mirror shows (ends on the rim's image).

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN and a whole
        number ``n_samples`` in ``3..MAX_SAMPLES``; nothing is checked.
        """
        n, n_samples = arc_normals(normals_world, n_samples, check)
        # Each normal's arcs as a tuple (a sequence, as the interface asks): no copy of hundreds of small lists.
        return great_circle_arcs(np.ascontiguousarray((n @ self.pose.R).T), n_samples, self.mirror.rim_cosine,
                                 self._unit_ray_pixels)

    def _mirror_plane_conics(self, n_mirror: np.ndarray) -> np.ndarray:
        r"""Image conics (N, 3, 3) of planes through the focus with float64 mirror-frame normals (N, 3) (unchecked):
        :math:`C = K_g^{-T} \Omega(F n) K_g^{-1}` (``great_circle_conics``); NaN rows for zero normals."""
        return great_circle_conics(n_mirror @ UNIFIED_FLIP.T, self.mirror.xi, np.linalg.inv(self.unified_calibration))

    def rim(self, n: int = 128) -> np.ndarray:
        """Closed polyline (n + 1, 2) of the rim's image, the boundary of the drawn region."""
        r = self.rim_image(check_sample_count(n, "n", 3))
        return np.vstack([r, r[:1]])

    # ------------------------------------------------------------------ frames
    def moved(self, pose: Pose) -> CatadioptricCamera:
        """The same camera at a new pose: mirror and calibration, checked when this camera was made, are shared and
        not checked again (the fast path of a drag)."""
        return CatadioptricCamera(check_pose(pose), self.mirror, self.K, self.width, self.height, check=False)

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
    def project(self, X_world: npt.ArrayLike, *, check: bool = True) -> PanoramicProjection:
        r"""Project world points through the mirror onto the CCD.

        .. math:: X = R^T (X_w - t), \quad X_h = \lambda X, \quad
            m \sim K (X_h + (0, 0, 2e)) \ \text{or}\ m \sim K (x_h, y_h, 1).

        Args:
            X_world: (N, 3) world points (a single (3,) point is N = 1).
            check: convert and check ``X_world`` (default). ``check=False``: the caller promises a float64 (N, 3)
                array of finite values within ``MAX_MAGNITUDE``; nothing is converted or checked, and anything else
                gives an undefined result (never a ``GeometryError``).

        Returns:
            A :class:`PanoramicProjection`; points in the blind cone, above the
            rim or at the focus itself have NaN pixels and ``visible = False``.
        """
        return self._project_world(as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world))

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
        r"""Unnormalised homogeneous pixels :math:`K_g (s_x, s_y, s_z + \xi)` of (N, 3) float64 mirror-frame
        directions (unchecked; a zero direction gives NaN).

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


B_OVER_A_RANGE = (0.01, 100.0)
"""Accepted ``b / a`` of a hyperbolic mirror: flatter or sharper mirrors are not drawn reliably."""

_CCD_PARAMETERS = (
    ParameterSpec("focal_pixels", "CCD focal length", "px", 1.0, 1e6, 1000.0),
    *PRINCIPAL_POINT_PARAMETERS,
    *IMAGE_SIZE_PARAMETERS,
)


@dataclass(frozen=True)
class CatadioptricKind:
    """One registered kind of catadioptric camera, by the shape of its mirror: its parameters and how to build one.

    The registry names :data:`HYPERBOLIC` and :data:`PARABOLIC`; a :class:`CatadioptricCamera` reports its kind from
    its mirror.
    """

    kind: str
    """``"hyperbolic"`` or ``"parabolic"``."""
    PARAMETERS: tuple[ParameterSpec, ...]
    """The mirror's parameters, then the CCD's."""

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in (HyperbolicMirror.kind, ParabolicMirror.kind):
            raise GeometryError(f"kind: expected 'hyperbolic' or 'parabolic', got {short_repr(self.kind)}")
        if not isinstance(self.PARAMETERS, tuple) or not all(isinstance(p, ParameterSpec) for p in self.PARAMETERS):
            raise GeometryError("PARAMETERS: expected a tuple of ParameterSpec")

    def from_parameters(self, pose: Pose, **values: Any) -> CatadioptricCamera:
        """A camera of this kind at ``pose``; defaults for the parameters not given.

        Raises:
            GeometryError: naming a parameter outside its range (or ``b/a`` outside :data:`B_OVER_A_RANGE`).
        """
        p = parameters_from_specs(self.PARAMETERS, values)
        if self.kind == HyperbolicMirror.kind:
            ratio = p["b"] / p["a"]
            if not B_OVER_A_RANGE[0] <= ratio <= B_OVER_A_RANGE[1]:
                raise GeometryError(f"b/a: expected {B_OVER_A_RANGE[0]:g}..{B_OVER_A_RANGE[1]:g}, got {ratio:g}")
            mirror: Mirror = HyperbolicMirror(p["a"], p["b"])
        else:
            mirror = ParabolicMirror(p["h"])
        f, u0, v0 = p["focal_pixels"], p["u0"], p["v0"]
        K = np.array([[f, 0.0, u0], [0.0, f, v0], [0.0, 0.0, 1.0]])
        return CatadioptricCamera(check_pose(pose), mirror, K, int(p["width"]), int(p["height"]))


HYPERBOLIC = CatadioptricKind("hyperbolic", (
    ParameterSpec("a", "a", "m", 1e-3, 100.0, 3.0),
    ParameterSpec("b", "b", "m", 1e-3, 100.0, 1.0),
    *_CCD_PARAMETERS,
))
"""A hyperbolic mirror (``a``, ``b``) over a pin-hole CCD at its second focus (EGT's default, ``a = 3``, ``b = 1``)."""
PARABOLIC = CatadioptricKind("parabolic", (
    ParameterSpec("h", "h", "m", 1e-3, 100.0, 1.0),
    *_CCD_PARAMETERS,
))
"""A parabolic mirror (``h``) over an orthographic CCD."""
_KINDS = {k.kind: k for k in (HYPERBOLIC, PARABOLIC)}
