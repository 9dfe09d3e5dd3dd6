r"""The unified sphere model of central catadioptric projection, in EGT's two parameters.

Geyer and Daniilidis' model (Barreto's formulation), parameterised as in EGT:
a scene point :math:`X` in the sphere frame is put on the unit sphere,
:math:`x_s = X / |X|`, projected from the point :math:`(0, 0, \ell)` onto the
plane :math:`z = -m`, and the plane point is imaged by ``K``:

.. math:: \lambda = \frac{\ell - z_s}{\ell + m}, \qquad
    \tilde x = \frac{x_s - (0, 0, \ell)}{\lambda}, \qquad
    p \sim K (\tilde x_x, \tilde x_y, 1).

:math:`\tilde x_z = -(\ell + m)` always. With a mirror of the toolbox,
:math:`\ell = \xi` and :math:`\ell + m = \gamma` (``docs/conventions.md``:
hyperbola :math:`\xi = 2ae/(2a^2 + b^2)`, :math:`\gamma = b^2/(2a^2 + b^2)`;
parabola :math:`\xi = 1`, :math:`\gamma = h`), and the pixels are those of
:class:`~egtviz.geometry.catadioptric.CatadioptricCamera` for every visible point.
Points are rows.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_array, as_calibration, as_points, as_scalar

__all__ = [
    "MAX_CONIC_SAMPLES",
    "SphereProjection",
    "UnitRayPixels",
    "great_circle_arcs",
    "great_circle_conics",
    "sphere_back_project",
    "sphere_project",
]

#: Most samples per great circle (a drawing: a few hundred are plenty).
MAX_CONIC_SAMPLES = 100_000

UnitRayPixels = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]
"""``f(dx, dy, dz, u, v)``: writes the pixels of visible unit directions into ``u``, ``v``."""


@dataclass(frozen=True)
class SphereProjection:
    """The three stages of :func:`sphere_project`, each (N, 3)."""

    sphere: np.ndarray
    """Points on the unit sphere, sphere frame."""
    plane: np.ndarray
    r"""Points on the plane :math:`z = -m`, relative to the projection centre :math:`(0, 0, \ell)`."""
    pixels: np.ndarray
    r"""Homogeneous pixels, last coordinate 1; NaN where :math:`z_s \ge \ell` (no ray from the projection
    centre through the sphere point reaches the image plane: the blind part of a mirror)."""


def _parameters(ell: float, m: float) -> tuple[float, float]:
    ell = as_scalar(ell, "ell")
    m = as_scalar(m, "m")
    if not ell + m > 0.0:
        raise GeometryError(f"ell, m: expected ell + m > 0 (the image plane below the projection centre), got {ell + m}")
    return ell, m


def sphere_project(X: npt.ArrayLike, ell: float, m: float, K: npt.ArrayLike) -> SphereProjection:
    r"""Project (N, 3) points given in the sphere frame (module docstring).

    Raises:
        GeometryError: bad shapes, a point at the sphere centre, :math:`\ell + m \le 0`, a bad ``K``.
    """
    P = as_points(X, "X", 3)
    ell, m = _parameters(ell, m)
    Kc = as_calibration(K, "K")
    norm = np.linalg.norm(P, axis=1)
    if np.any(norm == 0.0):
        raise GeometryError(f"X: point {int(np.flatnonzero(norm == 0.0)[0])} is the sphere centre; it has no ray")
    s = P / norm[:, None]
    lam = (ell - s[:, 2]) / (ell + m)
    # A ray grazing the blind edge (lam -> 0+) goes to infinity: inf or NaN pixels, not warnings.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        plane = np.where(lam[:, None] > 0.0, (s - [0.0, 0.0, ell]) / lam[:, None], np.nan)
        q = np.column_stack([plane[:, :2], np.ones(len(P))]) @ Kc.T
        pixels = q / q[:, 2:3]
    return SphereProjection(s, plane, pixels)


def sphere_back_project(pixels: npt.ArrayLike, ell: float, m: float, K: npt.ArrayLike) -> np.ndarray:
    r"""Lift pixels back to the unit sphere: the inverse of :func:`sphere_project`.

    With :math:`(x, y, 1) = K^{-1} p` the plane point is :math:`\tilde x = (x, y, -(\ell + m))`
    and the sphere point :math:`x_s = \lambda \tilde x + (0, 0, \ell)`, :math:`|x_s| = 1`, with
    the root in front of the projection centre

    .. math:: \lambda = \frac{\ell (\ell + m) + \sqrt{(\ell + m)^2 + (1 - \ell^2)(x^2 + y^2)}}
        {x^2 + y^2 + (\ell + m)^2}.

    Args:
        pixels: (N, 2) pixels, or homogeneous (N, 3).

    Returns:
        (N, 3) unit vectors; NaN rows where the square root is imaginary (:math:`\ell > 1`, far pixels).
    """
    arr = as_array(pixels, "pixels", allow_empty=False)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] not in (2, 3):
        raise GeometryError(f"pixels: expected shape (N, 2) or homogeneous (N, 3), got {arr.shape}")
    if arr.shape[1] == 3:
        if np.any(np.abs(arr[:, 2]) <= 1e-12 * np.abs(arr).max(axis=1)):
            raise GeometryError("pixels: a homogeneous pixel has last coordinate 0 (a point at infinity)")
        arr = arr[:, :2] / arr[:, 2:3]
    ell, m = _parameters(ell, m)
    Kc = as_calibration(K, "K")
    q = np.linalg.solve(Kc, np.column_stack([arr, np.ones(len(arr))]).T).T
    x, y = q[:, 0] / q[:, 2], q[:, 1] / q[:, 2]
    g = ell + m
    r2 = x * x + y * y
    with np.errstate(invalid="ignore"):
        lam = (ell * g + np.sqrt(g * g + (1.0 - ell * ell) * r2)) / (r2 + g * g)
    return np.column_stack([lam * x, lam * y, ell - lam * g])


def great_circle_conics(normals: np.ndarray, xi: float, K_inv: np.ndarray) -> np.ndarray:
    r"""Image conics (N, 3, 3) of great circles of the unit sphere, seen from the projection centre on its axis.

    A plane through the sphere's centre with unit normal :math:`n` (sphere frame, ``normals`` (N, 3) of any
    length) cuts the sphere in a great circle whose image is

    .. math:: C = K^{-T} \Omega K^{-1}, \qquad
        \Omega = (1 - \xi^2)\, n n^T + \xi^2 n_z (e_z n^T + n e_z^T) - \xi^2 n_z^2 I,

    returned symmetric with unit Frobenius norm (sign arbitrary); NaN rows for zero or non-finite normals.
    Unchecked: the callers pass float64 arrays of validated cameras (``normals`` (N, 3), ``K_inv`` (3, 3)).
    """
    norm = np.linalg.norm(normals, axis=1, keepdims=True)
    bad = ~(norm[:, 0] > 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = normals / norm
    xi2 = xi * xi
    nz = n[:, 2]
    omega = (1.0 - xi2) * n[:, :, None] * n[:, None, :]
    omega[:, 2, :] += xi2 * nz[:, None] * n
    omega[:, :, 2] += xi2 * nz[:, None] * n
    idx = np.arange(3)
    omega[:, idx, idx] -= (xi2 * nz * nz)[:, None]
    C = K_inv.T @ omega @ K_inv
    C = 0.5 * (C + np.swapaxes(C, 1, 2))  # exactly symmetric, whatever the rounding
    with np.errstate(divide="ignore", invalid="ignore"):
        C = C / np.linalg.norm(C, axis=(1, 2), keepdims=True)
    C[bad] = np.nan
    return C


def _circle_basis(n: np.ndarray) -> np.ndarray:
    r"""Orthonormal :math:`u = n \times h / |n \times h|`, :math:`v = n \times u` of unit normals ``n`` (3, N).

    The helper :math:`h` is :math:`e_x` unless the normal is close to it (:math:`|n_x| \ge 0.9`), then
    :math:`e_y`; the cross products with a unit axis are written out: :math:`n \times e_x = (0, n_z, -n_y)`,
    :math:`n \times e_y = (-n_z, 0, n_x)`. Returns ``uv`` (2, 3, N): ``uv[0]`` is ``u``, ``uv[1]`` is ``v``.
    """
    uv = np.empty((2,) + n.shape)
    u = np.where(np.abs(n[0]) < 0.9, n[[2, 2, 1]] * _CROSS_X, n[[2, 0, 0]] * _CROSS_Y)
    np.divide(u, np.sqrt(np.add.reduce(u * u, axis=0)), out=uv[0])
    u = uv[0]
    np.subtract(n[[1, 2, 0]] * u[[2, 0, 1]], n[[2, 0, 1]] * u[[1, 2, 0]], out=uv[1])  # n x u
    return uv


# n x e_x = (0, n_z, -n_y) = (n_z, n_z, n_y) * _CROSS_X; n x e_y = (-n_z, 0, n_x) = (n_z, n_x, n_x) * _CROSS_Y.
_CROSS_X = np.array([[0.0], [1.0], [-1.0]])
_CROSS_Y = np.array([[-1.0], [0.0], [1.0]])
_CROSS_X.setflags(write=False)
_CROSS_Y.setflags(write=False)


@lru_cache(maxsize=16)
def _full_circle_samples(n: int) -> tuple[np.ndarray, np.ndarray]:
    r"""``(t, cs)`` for ``n`` samples: :math:`t_j = j / (n - 1)`, and the rows :math:`(\cos\theta_j, \sin\theta_j)`
    (n, 2) at the angles :math:`\theta_j = 2\pi \frac{n-1}{n} t_j` of a closed circle (the same for every fully
    visible circle)."""
    t = np.linspace(0.0, 1.0, n)
    theta = 2.0 * np.pi * (n - 1) / n * t
    cs = np.column_stack([np.cos(theta), np.sin(theta)])
    t.setflags(write=False)
    cs.setflags(write=False)
    return t, cs


def great_circle_arcs(normals_T: np.ndarray, n: int, c_rim: float,
                      unit_ray_pixels: UnitRayPixels) -> list[tuple[np.ndarray, ...]]:
    r"""Visible arcs of the images of great circles, a tuple of polylines per normal (column of ``normals_T``), for a
    camera that sees exactly the unit rays with :math:`d_z \le c_{rim}` (a mirror, in its frame).

    A ray from a mirror's focus meets the mirror inside its rim exactly when its angle
    from the mirror axis exceeds the rim's: :math:`d_z / |d| \le c_{rim}`, with
    :math:`c_{rim} = z_{rim} / \sqrt{r_{rim}^2 + z_{rim}^2}` (the hit radius grows
    monotonically with elevation, and a hyperbola's rim lies below its asymptote).
    On the circle :math:`d(\theta) = \cos\theta\,u + \sin\theta\,v`,
    :math:`d_z = A \cos(\theta - \theta_0)` with :math:`A = \sqrt{u_z^2 + v_z^2}`, so the
    visible part is the single arc :math:`|\theta - \theta_0| \ge \arccos(c_{rim} / A)`:
    sampled directly, its ends exactly on the rim, with no splitting and no
    phantom branch. A fully visible circle is one closed polyline.

    Every sample is thus a visible unit direction, projected without a rim test by ``unit_ray_pixels(dx, dy, dz, u,
    v)``, which writes the pixels of unit directions (coordinates as arrays of one shape) into ``u`` and ``v``.
    The fully visible circles share their angles, so their directions are one
    matrix product, :math:`[d_x\ d_y\ d_z] = [\cos\theta_j\ \sin\theta_j]\,[u; v]`.

    The normals are given coordinate-major, ``normals_T`` (3, N) float64 (mirror frame); they
    need not be unit or finite (zero and NaN normals get no arc). Nothing is checked: ``n`` is a whole number
    in ``3..MAX_CONIC_SAMPLES`` and ``c_rim`` in ``[-1, 1]`` (the callers checked them; the viewer samples
    hundreds of circles per drag).
    """
    out: list[tuple[np.ndarray, ...]] = [()] * normals_T.shape[1]
    norm = np.sqrt(np.add.reduce(normals_T * normals_T, axis=0))
    good = np.flatnonzero(np.isfinite(norm) & (norm > 0))
    if len(good) == 0:
        return out
    if len(good) < len(out):
        normals_T, norm = normals_T[:, good], norm[good]
    uv = _circle_basis(normals_T / norm)  # (u or v, coordinate, circle)
    A = np.hypot(uv[0, 2], uv[1, 2])
    full = A <= c_rim
    rows = np.flatnonzero(full | (c_rim > -A))
    if len(rows) == 0:
        return out
    m = len(rows)
    if m < len(full):
        uv, full, A = uv[:, :, rows], full[rows], A[rows]
    # Directions (coordinate, circle, sample), all at the angles of a full circle: one matrix product.
    t, cs = _full_circle_samples(n)
    d = (uv.reshape(2, 3 * m).T @ cs.T).reshape(3, m, n)
    all_full = bool(full.all())
    if not all_full:
        # Partial circles: the arc |theta - theta0| >= half_blind, a hair inside the rim so that rounding
        # never puts an end point outside it. A > 0 here (a horizontal circle is all visible or all blind).
        part = np.flatnonzero(~full)
        u, v = uv[0][:, part], uv[1][:, part]
        half_blind = np.arccos(c_rim / A[part])  # |c_rim| < A: in [-1, 1] even after rounding
        inset = 1e-13
        start = np.arctan2(v[2], u[2]) + half_blind + inset
        span = 2.0 * (np.pi - half_blind - inset)
        theta = start[:, None] + span[:, None] * t
        d[:, part] = np.cos(theta) * u[:, :, None] + np.sin(theta) * v[:, :, None]
    buf = np.empty((m, n + 1, 2))  # pixels, with room for the closing point of the full circles
    unit_ray_pixels(d[0], d[1], d[2], buf[:, :n, 0], buf[:, :n, 1])
    buf[:, n] = buf[:, 0]
    arcs: list[tuple[np.ndarray, ...]] = list(zip(buf))  # 1-tuples (closed polyline,), built in C
    if not all_full:
        for j in part.tolist():
            arcs[j] = (buf[j, :n],)
    if m == len(out):
        return arcs
    for k, arc in zip(good[rows].tolist(), arcs):
        out[k] = arc
    return out
