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

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_array, as_calibration, as_points, as_scalar

__all__ = ["SphereProjection", "sphere_back_project", "sphere_project"]


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


def _great_circle_conics(normals: np.ndarray, xi: float, K_inv: np.ndarray) -> np.ndarray:
    r"""Image conics (N, 3, 3) of great circles of the unit sphere, seen from the projection centre on its axis.

    A plane through the sphere's centre with unit normal :math:`n` (sphere frame, ``normals`` (N, 3) of any
    length) cuts the sphere in a great circle whose image is

    .. math:: C = K^{-T} \Omega K^{-1}, \qquad
        \Omega = (1 - \xi^2)\, n n^T + \xi^2 n_z (e_z n^T + n e_z^T) - \xi^2 n_z^2 I,

    returned symmetric with unit Frobenius norm (sign arbitrary); NaN rows for zero or non-finite normals.
    Internal and unchecked: the callers pass validated cameras' arrays.
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
