r"""Sampled surfaces with their normals, and random scene points.

Each surface is sampled on an ``n x n`` parameter grid in its own frame and
then placed by a rotation ``R`` and a translation ``t``:
:math:`X_w = R X + t`, :math:`n_w = R n`. The normals are the analytic unit
outward normals (:math:`\partial_u X \times \partial_v X` normalised):

- ``plane`` (width ``w``, height ``h``): :math:`(u, v, 0)`,
  :math:`u \in [-w/2, w/2]`, :math:`v \in [-h/2, h/2]`; normal :math:`(0, 0, 1)`.
- ``sphere`` (radius ``r``): :math:`r(\cos\theta\cos\phi, \cos\theta\sin\phi, \sin\theta)`,
  :math:`\theta \in [-\pi/2, \pi/2]`, :math:`\phi \in [0, 2\pi]`; normal :math:`X / r`.
- ``cylinder`` (radius ``r``, height ``h``): :math:`(r\cos\phi, r\sin\phi, z)`,
  :math:`z \in [-h/2, h/2]`; normal :math:`(\cos\phi, \sin\phi, 0)`.
- ``cone`` (base radius ``r``, height ``h``, apex on +z): :math:`((1-s) r\cos\phi, (1-s) r\sin\phi, s h)`,
  :math:`s \in [0, 1]`; normal :math:`(h\cos\phi, h\sin\phi, r) / \sqrt{h^2 + r^2}`.
- ``torus`` (major radius ``R``, minor radius ``r``):
  :math:`((R + r\cos\theta)\cos\phi, (R + r\cos\theta)\sin\phi, r\sin\theta)`,
  :math:`\theta, \phi \in [0, 2\pi]`; normal :math:`(\cos\theta\cos\phi, \cos\theta\sin\phi, \sin\theta)`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_array, as_count, as_positive, as_rotation, as_vector

__all__ = ["SURFACE_KINDS", "SampledSurface", "random_points_in_ball", "sample_surface_grid"]

SurfaceKind = Literal["plane", "sphere", "cylinder", "cone", "torus"]

#: Surface kinds and the names of their parameters, in order.
SURFACE_KINDS: dict[str, tuple[str, ...]] = {
    "plane": ("width", "height"),
    "sphere": ("radius",),
    "cylinder": ("radius", "height"),
    "cone": ("radius", "height"),
    "torus": ("major_radius", "minor_radius"),
}

#: Most samples along one grid direction (n x n points in all).
MAX_GRID = 2000


@dataclass(frozen=True)
class SampledSurface:
    """A surface sampled on a grid: points and unit normals, in the world."""

    points: np.ndarray
    """(n, n, 3) world points."""
    normals: np.ndarray
    """(n, n, 3) unit outward normals in the world."""


def _grid(kind: str, p: tuple[float, ...], n: int) -> tuple[np.ndarray, np.ndarray]:
    s = np.linspace(0.0, 1.0, n)
    a, b = np.meshgrid(s, s, indexing="ij")
    if kind == "plane":
        w, h = p
        X = np.stack([(a - 0.5) * w, (b - 0.5) * h, np.zeros_like(a)], axis=-1)
        N = np.broadcast_to([0.0, 0.0, 1.0], X.shape).copy()
    elif kind == "sphere":
        (r,) = p
        th, ph = (a - 0.5) * np.pi, b * 2.0 * np.pi
        N = np.stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)], axis=-1)
        X = r * N
    elif kind == "cylinder":
        r, h = p
        ph, z = a * 2.0 * np.pi, (b - 0.5) * h
        N = np.stack([np.cos(ph), np.sin(ph), np.zeros_like(ph)], axis=-1)
        X = np.stack([r * np.cos(ph), r * np.sin(ph), z], axis=-1)
    elif kind == "cone":
        r, h = p
        ph, t = a * 2.0 * np.pi, b
        X = np.stack([(1 - t) * r * np.cos(ph), (1 - t) * r * np.sin(ph), t * h], axis=-1)
        N = np.stack([h * np.cos(ph), h * np.sin(ph), np.full_like(ph, r)], axis=-1) / np.hypot(h, r)
    else:  # torus
        R, r = p
        th, ph = a * 2.0 * np.pi, b * 2.0 * np.pi
        N = np.stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)], axis=-1)
        X = np.stack([(R + r * np.cos(th)) * np.cos(ph), (R + r * np.cos(th)) * np.sin(ph), r * np.sin(th)], axis=-1)
    return X, N


def sample_surface_grid(
    kind: SurfaceKind,
    params: npt.ArrayLike,
    n: int = 20,
    R: npt.ArrayLike | None = None,
    t: npt.ArrayLike | None = None,
) -> SampledSurface:
    """Sample a plane, sphere, cylinder, cone or torus (module docstring) on an ``n x n`` grid.

    Args:
        kind: one of :data:`SURFACE_KINDS`.
        params: the kind's positive parameters, in the order of :data:`SURFACE_KINDS`.
        n: samples along each grid direction, 2 to :data:`MAX_GRID`.
        R: (3, 3) rotation placing the surface (identity by default).
        t: (3,) translation (origin by default).

    Raises:
        GeometryError: an unknown kind, a wrong number of parameters, a
            non-positive one, a bad grid size, rotation or translation.
    """
    if not isinstance(kind, str) or kind not in SURFACE_KINDS:
        raise GeometryError(f"kind: expected one of {sorted(SURFACE_KINDS)}, got {kind!r}")
    names = SURFACE_KINDS[kind]
    values = as_array(params, "params", allow_empty=False).reshape(-1)
    if values.size != len(names):
        raise GeometryError(f"params: a {kind} takes {len(names)} parameter(s) {names}, got {values.size}")
    p = tuple(as_positive(v, f"params ({name})") for v, name in zip(values, names))
    if kind == "torus" and p[1] >= p[0]:
        raise GeometryError(f"params: a torus needs minor_radius < major_radius, got {p[1]} >= {p[0]}")
    count = as_count(n, "n", minimum=2, maximum=MAX_GRID)
    Rm = np.eye(3) if R is None else as_rotation(R, "R")
    tv = np.zeros(3) if t is None else as_vector(t, "t", 3)
    X, N = _grid(kind, p, count)
    return SampledSurface(X @ Rm.T + tv, N @ Rm.T)


def random_points_in_ball(
    n: int, centre: npt.ArrayLike, radius: float, rng: np.random.Generator | int | None = None
) -> np.ndarray:
    r"""``n`` points uniformly distributed inside the ball of ``radius`` around ``centre``, (n, 3) rows.

    A direction uniform on the sphere (a normalised Gaussian vector) times
    :math:`r\,U^{1/3}`, :math:`U` uniform on [0, 1], gives a uniform density in the ball.

    Args:
        n: number of points, at least 1.
        centre: (3,) centre.
        radius: positive radius.
        rng: a ``numpy.random.Generator``, a seed, or ``None`` for fresh entropy.
    """
    count = as_count(n, "n", minimum=1, maximum=10_000_000)
    c = as_vector(centre, "centre", 3)
    r = as_positive(radius, "radius")
    if isinstance(rng, bool) or not (rng is None or isinstance(rng, (int, np.integer, np.random.Generator))):
        raise GeometryError(f"rng: expected a numpy Generator, an integer seed or None, got {type(rng).__name__}")
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    d = gen.standard_normal((count, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return c + r * np.cbrt(gen.uniform(0.0, 1.0, count))[:, None] * d
