r"""Mirrors of central catadioptric (panoramic) cameras.

Both mirrors are surfaces of revolution about the z axis of the *mirror frame*,
whose origin is the mirror's focus :math:`O_m` (the single effective viewpoint);
see ``docs/conventions.md``, "Central catadioptric camera", and the EGT
reference, section 3 (Baker & Nayar's single-viewpoint mirrors).

A scene direction :math:`d` from the focus is seen through the mirror point
:math:`X_h = \lambda d` with :math:`\lambda > 0` on the visible sheet and inside
the rim. Rays that never meet that part of the mirror form the *blind cone*:
they have no image (``hit`` is ``False``, ``lambda`` is NaN).

Both mirrors also carry the parameters of the equivalent unified sphere model
(Geyer & Daniilidis 2000; Barreto & Araujo 2001): a direction :math:`d`
(any length) has normalised image coordinates

.. math:: (x, y) = \gamma \, \frac{(d_x, d_y)}{\xi |d| - d_z},

i.e. the projection from the point :math:`(0, 0, \xi)` of the unit sphere onto a
plane, followed by a scaling by :math:`\gamma` (:attr:`HyperbolicMirror.xi`,
:attr:`HyperbolicMirror.gamma`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, ClassVar, Literal, NamedTuple, cast

import numpy as np
import numpy.typing as npt

from ._validate import MIN_MAGNITUDE, GeometryError, as_array, as_count, as_points, as_positive, as_scalar, row_scales

__all__ = ["HyperbolicMirror", "Mirror", "MirrorHit", "ParabolicMirror"]


class MirrorHit(NamedTuple):
    """Result of :meth:`HyperbolicMirror.intersect`; unpacks as ``lam, hit = ...``."""

    lam: np.ndarray
    """(N,) ray parameter, the mirror point is ``lam * d``; NaN where not ``hit``."""
    hit: np.ndarray
    """(N,) bool: the ray meets the visible sheet inside the rim."""


#: Most vertices a mirror mesh or rim polyline may have (a drawing, not a computation).
MAX_SAMPLES = 1_000_000


def _positive_int(value: int, name: str, minimum: int) -> int:
    return as_count(value, name, minimum=minimum, maximum=MAX_SAMPLES)


def _length(value: float, name: str) -> float:
    """A mirror parameter: positive, and large enough that its square is a normal float."""
    return as_positive(value, name, min_value=MIN_MAGNITUDE)


def _radii(r: npt.ArrayLike) -> np.ndarray:
    """Distances from the axis: a non-empty array (any shape) of non-negative numbers."""
    arr = as_array(r, "r", allow_empty=False)
    if (arr < 0).any():
        raise GeometryError("r: expected radii >= 0")
    return arr


def _ray_directions(directions: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Directions (N, 3) each divided by its largest entry (a zero direction stays zero), and those scales."""
    return row_scales(directions, "directions", 3, allow_zero=True)


def _rim_tolerance(rim_tol: float) -> float:
    tol = as_scalar(rim_tol, "rim_tol")
    if not 0.0 <= tol < 1.0:
        raise GeometryError(f"rim_tol: expected a relative tolerance in [0, 1), got {tol!r}")
    return tol


def _surface_of_revolution(
    profile_z, rim_radius: float, n_radial: int, n_angular: int
) -> tuple[np.ndarray, np.ndarray]:
    """Triangle mesh of ``z = profile_z(r)`` for ``0 <= r <= rim_radius``.

    Vertex 0 is the apex; ring ``k`` (``k = 1..n_radial``) has ``n_angular``
    vertices at radius ``rim_radius * k / n_radial``. Faces are wound so that
    their normals point away from the focus (towards the CCD, the reflecting side).
    """
    n_radial = _positive_int(n_radial, "n_radial", 1)
    n_angular = _positive_int(n_angular, "n_angular", 3)
    if n_radial * n_angular > MAX_SAMPLES:
        raise GeometryError(f"n_angular: n_radial * n_angular may be at most {MAX_SAMPLES}, got {n_radial * n_angular}")
    r = rim_radius * np.arange(1, n_radial + 1) / n_radial
    phi = 2.0 * np.pi * np.arange(n_angular) / n_angular
    rr, pp = np.meshgrid(r, phi, indexing="ij")  # (n_radial, n_angular)
    ring = np.stack([rr * np.cos(pp), rr * np.sin(pp), profile_z(rr)], axis=-1).reshape(-1, 3)
    vertices = np.vstack([[0.0, 0.0, float(profile_z(np.zeros(1))[0])], ring])

    j = np.arange(n_angular)
    jn = (j + 1) % n_angular
    # Apex fan: (apex, next, current) has a downward normal (rings run counter-clockwise from above).
    fan = np.stack([np.zeros(n_angular, dtype=np.int64), 1 + jn, 1 + j], axis=1)
    k = np.arange(n_radial - 1)[:, None]
    a = 1 + k * n_angular + j  # inner ring, current
    b = 1 + k * n_angular + jn  # inner ring, next
    c = 1 + (k + 1) * n_angular + j  # outer ring, current
    d = 1 + (k + 1) * n_angular + jn  # outer ring, next
    quads1 = np.stack([a, b, d], axis=-1).reshape(-1, 3)
    quads2 = np.stack([a, d, c], axis=-1).reshape(-1, 3)
    faces = np.vstack([fan, quads1, quads2]).astype(np.int64)
    return vertices, faces


@dataclass(frozen=True)
class HyperbolicMirror:
    r"""Hyperbolic mirror imaged by a pin-hole CCD at its second focus.

    In the mirror frame the quadric is

    .. math:: \frac{(z + e)^2}{a^2} - \frac{x^2 + y^2}{b^2} = 1,
        \qquad e = \sqrt{a^2 + b^2},

    with foci at the origin (:math:`O_m`) and at :math:`(0, 0, -2e)`, where the
    CCD pin-hole sits looking up +z: :math:`m \sim K (X_h + (0, 0, 2e))`. The
    visible sheet is the one around the origin,
    :math:`z = -e + a \sqrt{1 + r^2 / b^2}` (apex at :math:`z = a - e`), cut at
    ``rim_radius``. Rays from the focus steeper than the asymptote
    (:math:`d_z / |d| \ge a / e`) never meet it.

    Args:
        a: semi-axis along z (> 0). EGT's default mirror has ``a = 3``.
        b: transverse semi-axis (> 0). EGT's default mirror has ``b = 1``.
        rim_radius: radius of the mirror's rim (> 0); ``None`` means ``2 b``.

    Raises:
        GeometryError: if ``a``, ``b`` or ``rim_radius`` is not a finite number in ``[1e-100, 1e100]``.
    """

    a: float = 3.0
    """Semi-axis along the mirror axis."""
    b: float = 1.0
    """Transverse semi-axis."""
    # The constructor takes None for the default rim (typed below); the field always holds the checked radius.
    rim_radius: float = cast(float, None)
    """Radius of the rim (distance from the axis); ``2 b`` by default."""

    if TYPE_CHECKING:
        def __init__(self, a: float = 3.0, b: float = 1.0, rim_radius: float | None = None) -> None: ...

    kind: ClassVar[Literal["hyperbolic"]] = "hyperbolic"

    def __post_init__(self) -> None:
        a = _length(self.a, "a")
        b = _length(self.b, "b")
        rim = 2.0 * b if self.rim_radius is None else _length(self.rim_radius, "rim_radius")
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "rim_radius", rim)

    @property
    def e(self) -> float:
        r"""Half the distance between the foci, :math:`e = \sqrt{a^2 + b^2}`."""
        return float(np.hypot(self.a, self.b))

    @property
    def xi(self) -> float:
        r"""Unified-sphere parameter :math:`\xi \in (0, 1)`.

        With the distance between the foci :math:`d = 2e` and the latus rectum
        :math:`4p = 2 b^2 / a`,

        .. math:: \xi = \frac{d}{\sqrt{d^2 + 4p^2}}
            = \frac{2 a e}{a^2 + e^2} = \frac{2 a e}{2 a^2 + b^2}.
        """
        e = self.e
        return 2.0 * self.a * e / (self.a**2 + e**2)

    @property
    def gamma(self) -> float:
        r"""Focal scaling of the unified model (the CCD's ``K`` has unit focal here).

        .. math:: \gamma = \psi - \xi = \frac{2p}{\sqrt{d^2 + 4p^2}} = \frac{b^2}{a^2 + e^2}.
        """
        return self.b**2 / (self.a**2 + self.e**2)

    @property
    def ccd_offset(self) -> float:
        """Distance from the focus down to the CCD pin-hole, ``2 e``."""
        return 2.0 * self.e

    @property
    def apex_z(self) -> float:
        """Height of the mirror's apex (on the axis), ``a - e`` (< 0)."""
        return self.a - self.e

    @property
    def rim_z(self) -> float:
        r"""Height of the rim, :math:`-e + a \sqrt{1 + \rho^2 / b^2}` with :math:`\rho` the rim radius."""
        return float(self.profile_z(np.array([self.rim_radius]))[0])

    @cached_property
    def rim_cosine(self) -> float:
        r""":math:`c_{rim} = z_{rim} / \sqrt{r_{rim}^2 + z_{rim}^2}`: the cosine of the rim's angle from the axis; a
        unit ray from the focus meets the mirror inside its rim exactly when :math:`d_z \le c_{rim}`."""
        return float(self.rim_z / np.hypot(self.rim_radius, self.rim_z))

    def profile_z(self, r: npt.ArrayLike) -> np.ndarray:
        r"""Height of the visible sheet at distance ``r`` from the axis: :math:`-e + a\sqrt{1 + r^2/b^2}`."""
        r = _radii(r)
        return -self.e + self.a * np.sqrt(1.0 + (r / self.b) ** 2)

    def implicit(self, X: npt.ArrayLike) -> np.ndarray:
        r"""The quadric's residual :math:`(z+e)^2/a^2 - (x^2+y^2)/b^2 - 1` for points ``X`` (N, 3)."""
        X = as_points(X, "X", 3)
        return (X[:, 2] + self.e) ** 2 / self.a**2 - (X[:, 0] ** 2 + X[:, 1] ** 2) / self.b**2 - 1.0

    def intersect(self, directions: npt.ArrayLike, *, rim_tol: float = 1e-12) -> MirrorHit:
        r"""Where rays from the focus meet the visible sheet, in closed form.

        Substituting :math:`X = \lambda d` in the quadric and multiplying by
        :math:`a^2 b^2` gives

        .. math:: (b^2 d_z^2 - a^2 \rho^2)\,\lambda^2 + 2 e b^2 d_z\,\lambda + b^4 = 0,
            \qquad \rho^2 = d_x^2 + d_y^2,

        whose discriminant is :math:`4 a^2 b^4 |d|^2`, so the roots are, in a
        form free of cancellation,

        .. math:: \lambda_\pm = \frac{b^2}{\pm a |d| - e d_z}.

        On :math:`\lambda_+` one finds
        :math:`z + e = a (e|d| - a d_z) / (a|d| - e d_z)`, so :math:`\lambda_+` is
        positive *and* on the sheet :math:`z + e > 0` exactly when
        :math:`a|d| > e d_z` (below the asymptote); :math:`\lambda_-` is either
        negative or on the other sheet and is never used.

        Args:
            directions: (N, 3) ray directions in the mirror frame (any length).
            rim_tol: relative tolerance on the rim radius (rays hitting up to
                ``rim_radius * (1 + rim_tol)`` from the axis count as hits).

        Returns:
            :class:`MirrorHit` ``(lam, hit)``: (N,) ``lam`` with :math:`X_h = \lambda d`, NaN where
            not ``hit``; (N,) bool ``hit``, true when the ray meets the sheet at
            a distance from the axis at most ``rim_radius``. Zero directions and
            the blind cone (above the rim, at or beyond the asymptote) are not hit.
        """
        d, scale = _ray_directions(directions)
        lam, hit = self._intersect_xyz(d[:, 0], d[:, 1], d[:, 2], _rim_tolerance(rim_tol))
        return MirrorHit(lam / scale, hit)

    @cached_property
    def _ray_constants(self) -> tuple[float, float, float]:
        """``(a, b^2, e)`` as plain floats (the properties recompute them on every access)."""
        return self.a, self.b**2, self.e

    def _intersect_xyz(self, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray, rim_tol: float = 1e-12) -> MirrorHit:
        """:meth:`intersect` of directions given by their coordinates (arrays of any one shape), unchecked.

        Internal fast path (the epipolar conics project thousands of directions per drag): no
        validation and no (N, 3) temporaries. ``rho = sqrt(dx^2 + dy^2)`` shares its squares with ``|d|``.
        """
        a, b2, e = self._ray_constants
        rho2 = dx * dx
        rho2 += dy * dy
        norm = dz * dz
        norm += rho2
        np.sqrt(norm, out=norm)
        denom = a * norm
        denom -= e * dz
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = b2 / denom
            # denom > 0 also excludes |d| = 0 (then denom = 0) and NaN directions.
            hit = denom > 0
            np.sqrt(rho2, out=rho2)
            rho2 *= lam
            hit &= rho2 <= self.rim_radius * (1.0 + rim_tol)
        lam[~hit] = np.nan
        return MirrorHit(lam, hit)

    def _hit_parameter(self, dx: float, dy: float, dz: float, rim_tol: float = 1e-12) -> float | None:
        """:meth:`intersect` of one direction in plain floats: ``lam``, or None where not hit (the same formulas)."""
        a, b2, e = self._ray_constants
        rho2 = dx * dx + dy * dy
        denom = a * math.sqrt(rho2 + dz * dz) - e * dz
        if not denom > 0:
            return None
        lam = b2 / denom
        return lam if lam * math.sqrt(rho2) <= self.rim_radius * (1.0 + rim_tol) else None

    def surface(self, n_radial: int = 24, n_angular: int = 64) -> tuple[np.ndarray, np.ndarray]:
        """Triangle mesh of the visible sheet from the apex to the rim (mirror frame).

        Args:
            n_radial: number of rings between apex and rim (>= 1).
            n_angular: vertices per ring (>= 3).

        Returns:
            ``(vertices, faces)``: (1 + n_radial * n_angular, 3) float vertices
            (vertex 0 is the apex) and (F, 3) int64 faces with normals pointing away
            from the focus (the reflecting side, towards the CCD).
        """
        return _surface_of_revolution(self.profile_z, self.rim_radius, n_radial, n_angular)

    def rim_points(self, n: int = 128) -> np.ndarray:
        """(n, 3) points of the rim circle, counter-clockwise seen from +z, mirror frame."""
        n = _positive_int(n, "n", 1)
        phi = 2.0 * np.pi * np.arange(n) / n
        r = self.rim_radius
        return np.stack([r * np.cos(phi), r * np.sin(phi), np.full(n, self.rim_z)], axis=1)


@dataclass(frozen=True)
class ParabolicMirror:
    r"""Parabolic mirror imaged by an orthographic CCD along its axis.

    In the mirror frame the mirror is

    .. math:: z = \frac{x^2 + y^2 - h^2}{2h},

    with its focus at the origin and apex at :math:`z = -h/2`; the orthographic
    camera images a mirror point as :math:`m \sim K (x_h, y_h, 1)`. Every ray
    from the focus except straight up (+z) meets the paraboloid; the rim
    (``rim_radius``) limits the field of view.

    Args:
        h: the mirror parameter (> 0): twice the focal distance, and the radius
            of the mirror at the focus' height.
        rim_radius: radius of the rim (> 0); ``None`` means ``2 h``.

    Raises:
        GeometryError: if ``h`` or ``rim_radius`` is not a finite number in ``[1e-100, 1e100]``.
    """

    h: float = 1.0
    """Mirror parameter (twice the focal distance)."""
    # The constructor takes None for the default rim (typed below); the field always holds the checked radius.
    rim_radius: float = cast(float, None)
    """Radius of the rim (distance from the axis); ``2 h`` by default."""

    if TYPE_CHECKING:
        def __init__(self, h: float = 1.0, rim_radius: float | None = None) -> None: ...

    kind: ClassVar[Literal["parabolic"]] = "parabolic"

    def __post_init__(self) -> None:
        h = _length(self.h, "h")
        rim = 2.0 * h if self.rim_radius is None else _length(self.rim_radius, "rim_radius")
        object.__setattr__(self, "h", h)
        object.__setattr__(self, "rim_radius", rim)

    @property
    def xi(self) -> float:
        r"""Unified-sphere parameter, :math:`\xi = 1` (stereographic projection)."""
        return 1.0

    @property
    def gamma(self) -> float:
        r"""Focal scaling of the unified model, :math:`\gamma = 2p = h` (latus rectum :math:`4p = 2h`)."""
        return self.h

    @property
    def ccd_offset(self) -> float:
        """Nominal distance below the focus at which viewers draw the orthographic CCD, ``2 h``.

        An orthographic camera has no centre; this number only places its drawing.
        """
        return 2.0 * self.h

    @property
    def apex_z(self) -> float:
        """Height of the mirror's apex, ``-h / 2``."""
        return -0.5 * self.h

    @property
    def rim_z(self) -> float:
        r"""Height of the rim, :math:`(\rho^2 - h^2) / (2h)` with :math:`\rho` the rim radius."""
        return float(self.profile_z(np.array([self.rim_radius]))[0])

    @cached_property
    def rim_cosine(self) -> float:
        r""":math:`c_{rim} = z_{rim} / \sqrt{r_{rim}^2 + z_{rim}^2}`: the cosine of the rim's angle from the axis; a
        unit ray from the focus meets the mirror inside its rim exactly when :math:`d_z \le c_{rim}`."""
        return float(self.rim_z / np.hypot(self.rim_radius, self.rim_z))

    def profile_z(self, r: npt.ArrayLike) -> np.ndarray:
        r"""Height of the mirror at distance ``r`` from the axis: :math:`(r^2 - h^2) / (2h)`."""
        r = _radii(r)
        return (r**2 - self.h**2) / (2.0 * self.h)

    def implicit(self, X: npt.ArrayLike) -> np.ndarray:
        r"""The residual :math:`(x^2 + y^2 - h^2)/(2h) - z` for points ``X`` (N, 3)."""
        X = as_points(X, "X", 3)
        return (X[:, 0] ** 2 + X[:, 1] ** 2 - self.h**2) / (2.0 * self.h) - X[:, 2]

    def intersect(self, directions: npt.ArrayLike, *, rim_tol: float = 1e-12) -> MirrorHit:
        r"""Where rays from the focus meet the paraboloid, in closed form.

        Substituting :math:`X = \lambda d` gives

        .. math:: \rho^2 \lambda^2 - 2 h d_z \lambda - h^2 = 0,
            \qquad \rho^2 = d_x^2 + d_y^2,

        with roots :math:`\lambda = h / (|d| - d_z) > 0` and
        :math:`\lambda = -h / (|d| + d_z) < 0` (behind the focus, never used).
        :math:`|d| - d_z` is evaluated as :math:`\rho^2 / (|d| + d_z)` when
        :math:`d_z > 0` to avoid cancellation.

        Args:
            directions: (N, 3) ray directions in the mirror frame (any length).
            rim_tol: relative tolerance on the rim radius.

        Returns:
            ``(lam, hit)`` as for :meth:`HyperbolicMirror.intersect`: ``lam`` NaN
            where not ``hit``; ``hit`` true when the ray meets the mirror within
            the rim.
        """
        d, scale = _ray_directions(directions)
        lam, hit = self._intersect_xyz(d[:, 0], d[:, 1], d[:, 2], _rim_tolerance(rim_tol))
        return MirrorHit(lam / scale, hit)

    def _intersect_xyz(self, dx: np.ndarray, dy: np.ndarray, dz: np.ndarray, rim_tol: float = 1e-12) -> MirrorHit:
        """:meth:`intersect` of directions given by their coordinates (arrays of any one shape), unchecked."""
        rho2 = dx * dx
        rho2 += dy * dy
        norm = np.sqrt(rho2 + dz * dz)
        with np.errstate(divide="ignore", invalid="ignore"):
            denom = np.where(dz > 0, rho2 / (norm + dz), norm - dz)
            lam = self.h / denom
            # denom > 0 also excludes |d| = 0 (then denom is 0 or NaN) and NaN directions.
            hit = denom > 0
            hit &= lam * np.sqrt(rho2) <= self.rim_radius * (1.0 + rim_tol)
        lam[~hit] = np.nan
        return MirrorHit(lam, hit)

    def _hit_parameter(self, dx: float, dy: float, dz: float, rim_tol: float = 1e-12) -> float | None:
        """:meth:`intersect` of one direction in plain floats: ``lam``, or None where not hit (the same formulas)."""
        rho2 = dx * dx + dy * dy
        norm = math.sqrt(rho2 + dz * dz)
        denom = rho2 / (norm + dz) if dz > 0 else norm - dz
        if not denom > 0:
            return None
        lam = self.h / denom
        return lam if lam * math.sqrt(rho2) <= self.rim_radius * (1.0 + rim_tol) else None

    def surface(self, n_radial: int = 24, n_angular: int = 64) -> tuple[np.ndarray, np.ndarray]:
        """Triangle mesh of the mirror from the apex to the rim; see :meth:`HyperbolicMirror.surface`."""
        return _surface_of_revolution(self.profile_z, self.rim_radius, n_radial, n_angular)

    def rim_points(self, n: int = 128) -> np.ndarray:
        """(n, 3) points of the rim circle, counter-clockwise seen from +z, mirror frame."""
        n = _positive_int(n, "n", 1)
        phi = 2.0 * np.pi * np.arange(n) / n
        r = self.rim_radius
        return np.stack([r * np.cos(phi), r * np.sin(phi), np.full(n, self.rim_z)], axis=1)


Mirror = HyperbolicMirror | ParabolicMirror
"""Either central catadioptric mirror."""
