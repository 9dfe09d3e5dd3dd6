r"""Pin-hole camera: intrinsics, projection with visibility, back-projection, frustum.

.. math:: m \sim K [R^T \mid -R^T t] X_w,\qquad
   K = \begin{bmatrix} k_u f & \gamma & u_0 \\ 0 & k_v f & v_0 \\ 0 & 0 & 1 \end{bmatrix}

(EGT reference, section 2; Hartley & Zisserman 6.1). Frames: ``docs/conventions.md``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import InitVar, dataclass
from functools import lru_cache
from typing import ClassVar, cast

import numpy as np
import numpy.typing as npt

from ._validate import (
    MAX_IMAGE_SIZE,
    GeometryError,
    as_calibration,
    as_count,
    as_points,
    as_positive,
    as_scalar,
    as_vector,
)
from .camera_model import (
    IMAGE_SIZE_PARAMETERS,
    PRINCIPAL_POINT_PARAMETERS,
    DirectionImages,
    ParameterSpec,
    as_direction,
    check_pose,
    check_sample_count,
    double_line_conics,
    finite_nonzero_rows,
    normals_with_planes,
    unchecked_normals,
    parameters_from_specs,
    rectangle_rim,
)
from ._shared import cached_value, inverse_calibration, normalize_homogeneous3
from .homogeneous import clip_lines_to_rect
from .poses import Pose

__all__ = [
    "FOCAL_PIXELS_RANGE",
    "SKEW_OVER_FOCAL_RANGE",
    "Intrinsics",
    "PinholeCamera",
    "PinholeProjection",
]

FOCAL_PIXELS_RANGE = (1.0, 1e6)
"""Accepted ``ku f`` and ``kv f`` (pixels) of :meth:`PinholeCamera.from_parameters`: with the principal point's and
the skew's ranges this keeps :math:`K` well conditioned."""
SKEW_OVER_FOCAL_RANGE = (-1.0, 1.0)
r"""Accepted :math:`\gamma / (k_u f)` (the cotangent of the angle between the pixel axes: 45 to 135 degrees)."""


@lru_cache(maxsize=32)
def _size_row(size: tuple[int, int]) -> np.ndarray:
    """``(width, height)`` as a read-only float row, the upper bounds of a pixel's coordinates."""
    return _read_only(np.array(size, dtype=np.float64))


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Intrinsics:
    """Calibration of a pin-hole camera and the size of its image."""

    focal_length: float = 0.008
    """f, metres."""
    pixels_per_metre: tuple[float, float] = (100_000.0, 100_000.0)
    """(ku, kv): pixels per metre along u and v (the inverse of the pixel size)."""
    principal_point: tuple[float, float] = (320.0, 240.0)
    """(u0, v0) in pixels."""
    skew: float = 0.0
    """gamma, in pixels."""
    width: int = 640
    """Image width in pixels."""
    height: int = 480
    """Image height in pixels."""
    check: InitVar[bool] = True
    """``False``: the fields are trusted (plain numbers that a checked ``Intrinsics`` or ``as_calibration`` gave);
    they are only converted to ``float`` and ``int``, not checked (:meth:`from_K` of a checked ``K``)."""

    def __post_init__(self, check: bool) -> None:
        if not check:
            set_ = object.__setattr__
            set_(self, "focal_length", float(self.focal_length))
            set_(self, "pixels_per_metre", tuple(float(x) for x in self.pixels_per_metre))
            set_(self, "principal_point", tuple(float(x) for x in self.principal_point))
            set_(self, "skew", float(self.skew))
            set_(self, "width", int(self.width))
            set_(self, "height", int(self.height))
            return
        object.__setattr__(self, "focal_length", as_positive(self.focal_length, "focal_length"))
        ku, kv = as_vector(self.pixels_per_metre, "pixels_per_metre", 2).tolist()
        if not (ku > 0 and kv > 0):
            raise GeometryError(f"pixels_per_metre: expected two positive numbers, got ({ku!r}, {kv!r})")
        object.__setattr__(self, "pixels_per_metre", (ku, kv))
        u0, v0 = as_vector(self.principal_point, "principal_point", 2).tolist()
        object.__setattr__(self, "principal_point", (u0, v0))
        object.__setattr__(self, "skew", as_scalar(self.skew, "skew"))
        for name in ("width", "height"):
            object.__setattr__(self, name, as_count(getattr(self, name), name, minimum=1, maximum=MAX_IMAGE_SIZE))
        try:
            as_calibration(self.K, "K")
        except GeometryError as exc:
            # Each field is fine on its own; together they make no usable K (a focal length of 1e-300 m).
            raise GeometryError(
                f"focal_length, pixels_per_metre, skew: K = [[{self.K[0, 0]:.3g}, {self.skew:.3g}, ...], "
                f"[0, {self.K[1, 1]:.3g}, ...], [0, 0, 1]] cannot be inverted ({exc})"
            ) from None

    @classmethod
    def from_K(cls, K: npt.ArrayLike, width: int = 640, height: int = 480, focal_length: float = 1.0, *,
               check: bool = True) -> Intrinsics:
        """Intrinsics whose matrix is ``K``; ``focal_length`` only splits ``ku f`` into its factors.

        ``check=False``: the caller promises ``K`` is what ``as_calibration`` returned (float64, upper triangular,
        ``K[2, 2] = 1``, invertible), ``width`` and ``height`` whole numbers in range and ``focal_length`` a
        positive float; positive focal lengths are still required. Anything else gives an undefined result.
        """
        if check:
            K = as_calibration(K, "K")
            f = as_positive(focal_length, "focal_length")
        else:
            K = cast(np.ndarray, K)
            f = float(focal_length)
        if K[0, 0] <= 0 or K[1, 1] <= 0:
            raise GeometryError("K: expected positive focal lengths K[0,0], K[1,1]")
        return cls(f, (K[0, 0] / f, K[1, 1] / f), (K[0, 2], K[1, 2]), K[0, 1], width, height, check=check)

    @cached_value
    def K(self) -> np.ndarray:
        """The 3x3 calibration matrix (read-only: built once, shared by the cameras with these intrinsics; copy it
        to change it)."""
        ku, kv = self.pixels_per_metre
        u0, v0 = self.principal_point
        f = self.focal_length
        return _read_only(np.array([[ku * f, self.skew, u0], [0.0, kv * f, v0], [0.0, 0.0, 1.0]]))

    @cached_value
    def K_inv(self) -> np.ndarray:
        """:math:`K^{-1}` (read-only; the same array as ``inverse_calibration(K)``)."""
        return inverse_calibration(self.K, "K")

    @property
    def focal_pixels(self) -> tuple[float, float]:
        """(ku f, kv f): the focal length in pixels."""
        ku, kv = self.pixels_per_metre
        return ku * self.focal_length, kv * self.focal_length

    @property
    def fov_y(self) -> float:
        """Vertical field of view in radians."""
        return 2.0 * float(np.arctan2(self.height / 2.0, self.focal_pixels[1]))

    @property
    def aspect(self) -> float:
        """width / height."""
        return self.width / self.height


@dataclass(frozen=True)
class PinholeProjection:
    """Result of projecting N world points into a pin-hole camera."""

    pixels: np.ndarray
    """(N, 2) pixels; NaN where the point is behind the camera."""
    depth: np.ndarray
    """(N,) z in the camera frame (negative or zero: behind)."""
    in_front: np.ndarray
    """(N,) bool, ``depth > 0``: the point has an image."""
    image_size: tuple[int, int]
    """``(width, height)`` of the image, in pixels."""

    @cached_value
    def in_image(self) -> np.ndarray:
        """(N,) bool, in front and inside ``[0, width] x [0, height]`` (computed when first read)."""
        # NaN compares False, without a warning (no error context needed): points behind are never in the image.
        # Both coordinates at once on the contiguous (N, 2) pixels: numpy's loops over the strided columns cost
        # several times more (every drag).
        px = self.pixels
        ok = px >= 0.0
        ok &= px <= _size_row(self.image_size)
        return np.logical_and(ok[:, 0], ok[:, 1])

    @property
    def visible(self) -> np.ndarray:
        """(N,) bool: the point has an image (``in_front``; the camera-model interface's name)."""
        return self.in_front


@dataclass(frozen=True)
class PinholeCamera:
    r"""A pin-hole camera: a pose in the world and intrinsics; the ``pinhole`` camera model
    (:class:`~egtviz.geometry.camera_model.CameraModel`).

    A plane through the centre with world normal :math:`n` images to the line :math:`l = K^{-T} R^T n` (its conic is
    the double line :math:`l l^T`); its drawn arc is the line clipped to the image rectangle. The line through the
    centre along :math:`d` images to the one point :math:`K R^T d`, shown when :math:`(R^T d)_z > 0`.
    """

    pose: Pose = dataclasses.field(default_factory=Pose)
    intrinsics: Intrinsics = dataclasses.field(default_factory=Intrinsics)

    kind: ClassVar[str] = "pinhole"
    PARAMETERS: ClassVar[tuple[ParameterSpec, ...]] = (
        ParameterSpec("focal_length", "focal length", "m", 1e-4, 10.0, 0.008),
        ParameterSpec("ku", "pixels per metre along u", "px/m", 1.0, 1e7, 100_000.0),
        ParameterSpec("kv", "pixels per metre along v", "px/m", 1.0, 1e7, 100_000.0),
        *PRINCIPAL_POINT_PARAMETERS,
        ParameterSpec("skew", "skew", "px", -100_000.0, 100_000.0, 0.0),
        *IMAGE_SIZE_PARAMETERS,
    )
    no_image: ClassVar[str] = "behind the camera"

    def __post_init__(self) -> None:
        if not isinstance(self.pose, Pose):
            raise GeometryError(f"pose: expected a Pose, got {type(self.pose).__name__}")
        if not isinstance(self.intrinsics, Intrinsics):
            raise GeometryError(f"intrinsics: expected an Intrinsics, got {type(self.intrinsics).__name__}")

    @property
    def K(self) -> np.ndarray:
        return self.intrinsics.K

    # ------------------------------------------------------------------ the camera-model interface
    @classmethod
    def from_parameters(cls, pose: Pose, **values: float) -> PinholeCamera:
        """The camera at ``pose`` with ``focal_length``, ``ku``, ``kv``, ``u0``, ``v0``, ``skew``, ``width``, ``height``
        (:attr:`PARAMETERS`; defaults for the others).

        Raises:
            GeometryError: naming a parameter outside its range.
        """
        p = parameters_from_specs(cls.PARAMETERS, values)
        lo, hi = FOCAL_PIXELS_RANGE
        for name in ("ku", "kv"):
            fp = p["focal_length"] * p[name]
            if not lo <= fp <= hi:
                raise GeometryError(f"focal_length * {name}: expected {lo:g}..{hi:g} px, got {fp:g}")
        ratio = p["skew"] / (p["focal_length"] * p["ku"])
        if not SKEW_OVER_FOCAL_RANGE[0] <= ratio <= SKEW_OVER_FOCAL_RANGE[1]:
            raise GeometryError(f"skew / (focal_length * ku): expected -1..1, got {ratio:g}")
        intr = Intrinsics(p["focal_length"], (p["ku"], p["kv"]), (p["u0"], p["v0"]), p["skew"], int(p["width"]),
                          int(p["height"]))
        return cls(check_pose(pose), intr)

    def parameters(self) -> dict[str, float | int]:
        i = self.intrinsics
        (ku, kv), (u0, v0) = i.pixels_per_metre, i.principal_point
        return {"focal_length": i.focal_length, "ku": ku, "kv": kv, "u0": u0, "v0": v0, "skew": i.skew,
                "width": i.width, "height": i.height}

    @property
    def width(self) -> int:
        return self.intrinsics.width

    @property
    def height(self) -> int:
        return self.intrinsics.height

    @property
    def centre(self) -> np.ndarray:
        """(3,) the camera centre in world coordinates (``pose.t``)."""
        return self.pose.t

    @property
    def projective_calibration(self) -> np.ndarray:
        """:math:`K`: a pin-hole camera images every point linearly."""
        return self.K

    def light_paths(self, X_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        """(N, 2, 3) segments point -> centre; NaN rows for points behind the camera.

        ``check=False``: as for :meth:`project`.
        """
        X = as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world)
        out = np.empty((len(X), 2, 3))
        out[:, 0] = X
        out[:, 1] = self.pose.t
        # The depth exactly as :meth:`project` computes it (the same product), without the pixels.
        M = self.K_Rt
        behind = (X @ M.T)[:, 2] <= (M @ self.pose.t)[2]
        if np.logical_or.reduce(behind):
            out[behind] = np.nan
        return out

    def baseline_images(self, direction_world: npt.ArrayLike, *, check: bool = True) -> DirectionImages:
        """The one image :math:`K R^T d` of the line through the centre along ``d`` (both directions image to it),
        normalised (``normalize_homogeneous``); shown when :math:`(R^T d)_z > 0` (the direction is in front).

        ``check=False``: the caller promises a float64 (3,) finite, non-zero ``direction_world``; nothing is checked
        (anything else gives an undefined result).
        """
        m = self.K_Rt @ (as_direction(direction_world) if check else direction_world)
        x, y, z = m.tolist()
        return DirectionImages(normalize_homogeneous3(x, y, z)[None, :], np.array([z > 0]))

    def plane_image_lines(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        r"""Image lines :math:`l = K^{-T} R^T n` (N, 3) of planes through the centre; NaN rows for zero or NaN
        normals.

        ``check=False``: the caller promises a float64 (N, 3) array whose rows are finite or all NaN (each is still
        divided by its largest entry, as in the checked call); anything else gives an undefined result.
        """
        if not check:
            return unchecked_normals(cast(np.ndarray, normals_world)) @ self.plane_to_line.T
        n, good = normals_with_planes(normals_world)
        if len(good) == len(n):
            return n @ self.plane_to_line.T
        lines = np.full((len(n), 3), np.nan)
        if len(good):
            lines[good] = n[good] @ self.plane_to_line.T
        return lines

    def plane_image_conics(self, normals_world: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
        """The double lines :math:`l l^T / |l|^2` of :meth:`plane_image_lines` (``check`` as there)."""
        return double_line_conics(self.plane_image_lines(normals_world, check=check))

    def plane_image_arcs(self, normals_world: npt.ArrayLike, n_samples: int = 96, *,
                         check: bool = True) -> list[list[np.ndarray]]:
        """Per normal, its image line clipped to the image rectangle as one (2, 2) segment (or none).

        ``check=False``: as for :meth:`plane_image_lines`, and ``n_samples`` (not needed here) is not checked.
        """
        if check:
            check_sample_count(n_samples, "n_samples", 2)
        lines = self.plane_image_lines(normals_world, check=check)
        out: list[list[np.ndarray]] = [[] for _ in range(len(lines))]
        good = finite_nonzero_rows(lines)
        if len(good):
            seg, hit = clip_lines_to_rect(lines[good], self.width, self.height)
            for k, s, h in zip(good.tolist(), seg, hit.tolist(), strict=True):
                if h:
                    out[k] = [s]
        return out

    def rim(self, n: int = 128) -> np.ndarray:
        """The image rectangle as a closed polyline (5, 2) (``n``, checked, is not needed)."""
        check_sample_count(n, "n", 3)
        return rectangle_rim(self.width, self.height)

    # Read-only matrices of this (immutable) camera, built once: the epipolar geometry of a pair
    # uses them on every drag of the other camera.
    @property
    def K_inv(self) -> np.ndarray:
        """:math:`K^{-1}` (read-only; the same array as ``inverse_calibration(K)``, shared by the cameras with these
        intrinsics)."""
        return self.intrinsics.K_inv

    @cached_value
    def K_Rt(self) -> np.ndarray:
        r""":math:`K R^T` (read-only): a world direction :math:`d` images to :math:`m \sim K R^T d`."""
        return _read_only(self.K @ self.pose.R.T)

    @cached_value
    def plane_to_line(self) -> np.ndarray:
        r""":math:`K^{-T} R^T` (read-only): a plane through the centre with world normal :math:`n` images to the line
        :math:`l = K^{-T} R^T n`."""
        return _read_only(self.R_K_inv.T.copy())

    @cached_value
    def R_K_inv(self) -> np.ndarray:
        r""":math:`R K^{-1}` (read-only): pixel :math:`m` at depth :math:`z_c` is the world point
        :math:`z_c R K^{-1} m + t`."""
        return _read_only(self.pose.R @ self.K_inv)

    @cached_value
    def ray_frames(self) -> np.ndarray:
        r"""(2, 3, 3) read-only stack :math:`(R, R K^{-1})`: directions of the camera frame and of pixels in the world
        (both epipolar matrices of a pair are built from them in one product, ``epipolar.epipolar_pair``)."""
        return _read_only(np.array([self.pose.R, self.R_K_inv]))

    @property
    def center(self) -> np.ndarray:
        """(3,) camera centre in world coordinates."""
        return self.pose.t

    @property
    def P(self) -> np.ndarray:
        r"""3x4 projection matrix :math:`P = K [R^T \mid -R^T t]`."""
        R, t = self.pose.R, self.pose.t
        return self.K @ np.hstack([R.T, (-R.T @ t)[:, None]])

    def moved(self, pose: Pose) -> PinholeCamera:
        """The same camera at another pose (the intrinsics, checked once, are shared)."""
        return PinholeCamera(check_pose(pose), self.intrinsics)

    def with_intrinsics(self, intrinsics: Intrinsics) -> PinholeCamera:
        return dataclasses.replace(self, intrinsics=intrinsics)

    def project(self, X_world: npt.ArrayLike, *, check: bool = True) -> PinholeProjection:
        r"""Project world points (N, 3): :math:`m \sim K R^T (X_w - t)`.

        Points with :math:`z_c \le 0` are behind the camera: NaN pixel, ``in_front`` False.

        Args:
            X_world: (N, 3) world points (a (3,) point is N = 1).
            check: convert and check ``X_world`` (default). ``check=False`` is the fast path for points checked
                once already (a scene's points on every drag): the caller promises a float64 (N, 3) array of
                finite values within ``MAX_MAGNITUDE``; nothing is converted or checked, and anything else gives an
                undefined result (wrong values or a numpy error, never a ``GeometryError``).
        """
        return self._project(as_points(X_world, "X_world", 3) if check else cast(np.ndarray, X_world))

    def _project(self, X: np.ndarray) -> PinholeProjection:
        """:meth:`project` of checked (N, 3) float64 points (internal: no conversion, no check)."""
        M = self.K_Rt
        c = M @ self.pose.t
        size = (self.intrinsics.width, self.intrinsics.height)
        if X.flags.f_contiguous and not X.flags.c_contiguous:
            return self._project_columns(X.T, M, c, size)
        # K R^T (X - t) = K R^T X - K R^T t: one thin product, then per-column work (no (N, 3) temporaries).
        m = X @ M.T
        depth = m[:, 2] - c[2]
        in_front = depth > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / depth
            pixels = np.empty((len(X), 2))
            np.multiply(m[:, 0] - c[0], inv, out=pixels[:, 0])
            np.multiply(m[:, 1] - c[1], inv, out=pixels[:, 1])
        if not np.logical_and.reduce(in_front):
            pixels[~in_front] = np.nan
        return PinholeProjection(pixels, depth, in_front, size)

    @staticmethod
    def _project_columns(XT: np.ndarray, M: np.ndarray, c: np.ndarray, size: tuple[int, int]) -> PinholeProjection:
        """:meth:`_project` of points given as the rows of a (3, N) array (EGT's columns, transposed): the same
        arithmetic on contiguous coordinate rows (a product of the transposed view would be several times slower);
        the pixels are the rows (N, 2) of a (2, N) array."""
        m = M @ XT
        m -= c[:, None]  # (m - c): the same values as the row path's differences
        depth = m[2]
        in_front = depth > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            pixels_T = m[:2] * (1.0 / depth)
        if not in_front.all():
            pixels_T[:, ~in_front] = np.nan
        return PinholeProjection(pixels_T.T, depth, in_front, size)

    def back_project(self, pixels: npt.ArrayLike) -> np.ndarray:
        r"""Unit world directions (N, 3) of the rays through ``pixels`` (N, 2): :math:`d \propto R K^{-1} m`."""
        m = as_points(pixels, "pixels", 2)
        d = np.column_stack([m, np.ones(len(m))]) @ self.R_K_inv.T
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def frustum_corners(self, depth: float = 1.0) -> np.ndarray:
        """(4, 3) world points of the image corners at ``depth`` along the optical axis.

        Order: (0, 0), (w, 0), (w, h), (0, h) in pixels.
        """
        depth = as_positive(depth, "depth")
        w, h = self.intrinsics.width, self.intrinsics.height
        corners = np.array([[0.0, 0.0, 1.0], [w, 0.0, 1.0], [w, h, 1.0], [0.0, h, 1.0]])
        d_cam = corners @ self.K_inv.T
        d_cam = d_cam * (depth / d_cam[:, 2:3])
        return self.pose.to_world(d_cam)

    def image_to_world(self, pixels: npt.ArrayLike, depth: float = 1.0, *, check: bool = True) -> np.ndarray:
        """World points (N, 3) of ``pixels`` (N, 2) on the plane ``z_c = depth`` (for drawing the image in 3D).

        ``check=False`` (the viewer, on every drag, with the derived pixels): the caller promises a float64 (N, 2)
        array of finite pixels and a positive finite ``depth``; nothing is checked, anything else gives an
        undefined result.
        """
        if check:
            m, depth = as_points(pixels, "pixels", 2), as_positive(depth, "depth")
        else:
            m = cast(np.ndarray, pixels)
        d_cam = np.column_stack([m, np.ones(len(m))]) @ self.K_inv.T
        return (d_cam * depth) @ self.pose.R.T + self.pose.t
