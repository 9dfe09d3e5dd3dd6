"""EGT's central catadioptric (panoramic) functions: projection, mirror geometry, epipoles, conics, E."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ..geometry._validate import DegenerateConfigurationError, GeometryError, as_vector
from ..geometry.mirrors import HyperbolicMirror
from ..geometry.mirror_roots import line_quadric_roots
from ..geometry.panoramic_epipolar import conic_from_plane, epipolar_conics, panoramic_epipoles, panoramic_essential
from ..geometry.poses import Pose
from ..geometry.unified_sphere import sphere_back_project, sphere_project
from ._convert import draw as _draw
from ._convert import catadioptric, columns, flag, mirror, pixels, style, world_columns


def f_panproj(
    Xw: npt.ArrayLike,
    H: npt.ArrayLike,
    K: npt.ArrayLike | None = None,
    a: float = 3.0,
    b: float = 1.0,
    quadric: int = 1,
    *plot: Any,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Central catadioptric projection of ``Xw`` (3, N) through a mirror at pose ``H``.

    .. math:: X = R^T (X_w - t), \quad X_h = \lambda X, \quad m \sim K (X_h + (0, 0, 2e))

    (hyperbola), :math:`m \sim K (x_h, y_h, 1)` (parabola).

    Args:
        Xw: (3, N) world points.
        H: 4x4 mirror pose ``[R t; 0 1]`` (``R = I``: upright mirror).
        K: CCD calibration; None: :data:`DEFAULT_PANORAMIC_K`.
        a, b: mirror parameters (``quadric=2``: ``a`` is the parabola's ``h``).
        quadric: 1 hyperbolic mirror with a pin-hole CCD, 2 parabolic with an orthographic CCD.
        *plot: EGT's ``col``: a colour string draws the points, their mirror points and rays.

    Returns:
        ``(m, Xh)``: ``m`` (3, N) homogeneous pixels (last row 1), ``Xh`` (3, N)
        mirror points in the mirror frame; NaN columns where not visible.
    """
    cam = catadioptric(H, K, a, b, quadric)
    X = world_columns(Xw, "Xw")
    proj = cam.project(X)
    m = np.vstack([proj.pixels.T, np.where(proj.visible, 1.0, np.nan)])
    colour = style(plot)
    if colour is not None:
        Xh_world = proj.mirror_points @ cam.pose.R.T + cam.pose.t  # NaN columns stay NaN
        _draw("panoramic_points", points=X.T, mirror_points=Xh_world.T, focus=cam.pose.t.copy(), style=colour)
    return m, proj.mirror_points.T


def f_panepipoles(
    H1: npt.ArrayLike,
    H2: npt.ArrayLike,
    K: npt.ArrayLike | None = None,
    a: float = 3.0,
    b: float = 1.0,
    quadric: int = 1,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both image epipoles of both panoramic cameras: ``(e1, e1p, e2, e2p)``, homogeneous 3-vectors.

    ``e1`` is the image of the ray from focus 1 towards focus 2, ``e1p`` of the
    ray away from it (both intersections of the baseline with mirror 1); the
    same for image 2. Computed with the unified model: finite pixels even where
    the mirror does not show them.
    """
    ep = panoramic_epipoles(catadioptric(H1, K, a, b, quadric, "H1"), catadioptric(H2, K, a, b, quadric, "H2"))
    return ep.e1, ep.e1p, ep.e2, ep.e2p


def f_epipconics(
    Xw: npt.ArrayLike,
    H1: npt.ArrayLike,
    H2: npt.ArrayLike,
    K: npt.ArrayLike | None = None,
    a: float = 3.0,
    b: float = 1.0,
    quadric: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """Epipolar conics of the points ``Xw`` (3, N) in both images: ``(C1, C2)``, each (N, 3, 3), ``m^T C m = 0``."""
    return epipolar_conics(
        catadioptric(H1, K, a, b, quadric, "H1"), catadioptric(H2, K, a, b, quadric, "H2"), world_columns(Xw, "Xw")
    )


def f_panE(H1: npt.ArrayLike, H2: npt.ArrayLike | None = None) -> np.ndarray:
    r"""Essential matrix between two mirror frames: :math:`E = [t]_\times R`, :math:`X_{h2}^T E X_{h1} = 0`.

    :math:`R = R_2^T R_1`, :math:`t = R_2^T (t_1 - t_2)`; not rescaled
    (:math:`|E|_F = \sqrt 2 |t|`). With one argument, ``H1`` is the pose of
    mirror 2 in mirror 1's frame (mirror 1 at the origin).
    """
    if H2 is None:
        return panoramic_essential(catadioptric(np.eye(4), None, 3.0, 1.0, 1), catadioptric(H1, None, 3.0, 1.0, 1, "H1"))
    return panoramic_essential(catadioptric(H1, None, 3.0, 1.0, 1, "H1"), catadioptric(H2, None, 3.0, 1.0, 1, "H2"))


def f_catmod(
    P: npt.ArrayLike, R: npt.ArrayLike, t: npt.ArrayLike, ell: float, m: float, K: npt.ArrayLike, *plot: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""The unified sphere model: world points ``P`` (3, N) through the sphere at pose ``(R, t)``.

    .. math:: x_s = \frac{X}{|X|},\ X = R^T (P - t), \qquad
        \tilde x = \frac{\ell + m}{\ell - z_s} \big(x_s - (0, 0, \ell)\big), \qquad
        p \sim K (\tilde x_x, \tilde x_y, 1)

    Args:
        P: (3, N) world points.
        R, t: the sphere frame's rotation and centre.
        ell, m: projection centre :math:`(0, 0, \ell)` and image plane :math:`z = -m`
            (a mirror: :math:`\ell = \xi`, :math:`m = \gamma - \xi`).
        K: calibration.
        *plot: EGT's ``col, fig``: a colour draws the sphere; ``fig == 2`` also the rays.

    Returns:
        ``(x, xt, p)``, each (3, N): sphere points (sphere frame), plane points
        relative to the projection centre, homogeneous pixels.
    """
    pose = Pose(R, as_vector(t, "t", 3))
    X = world_columns(P, "P")
    out = sphere_project(pose.to_local(X), ell, m, K)
    colour = style(plot)
    if colour is not None:
        rays = len(plot) > 1 and flag(plot[1]) == 2
        _draw("sphere_model", H=pose.matrix, ell=ell, m=m, points=X.T, sphere_points=pose.to_world(out.sphere).T,
              style=colour, rays=rays)
    return out.sphere.T, out.plane.T, out.pixels.T


def f_backcatmod(p: npt.ArrayLike, m: float, ell: float, K: npt.ArrayLike) -> np.ndarray:
    r"""Back-projection of the unified sphere model: pixels ``p`` (2, N) or (3, N) -> unit sphere points (3, N).

    Note EGT's argument order ``(p, m, ell, K)``. The inverse of :func:`f_catmod`:
    ``f_backcatmod(f_catmod(P, R, t, ell, m, K)[2], m, ell, K)`` returns the sphere points.
    """
    return sphere_back_project(pixels(p, "p"), ell, m, K).T


def f_lambda(a: float, b: float, quadric: int, v: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Both intersections :math:`\lambda_{1,2} v` of the line through the focus and ``v`` with the mirror quadric.

    Hyperbola: :math:`\lambda_{1,2} = b^2 (-e v_z \pm a |v|) / (b^2 v_z^2 - a^2 (v_x^2 + v_y^2))`;
    parabola (``h = a``): :math:`\lambda_{1,2} = h (v_z \pm |v|) / (v_x^2 + v_y^2)`.

    Args:
        a, b: mirror parameters; quadric: 1 hyperbolic, 2 parabolic.
        v: (3, N) directions in the mirror frame.

    Returns:
        ``(lambda1, lambda2)``, each (N,).
    """
    mir = mirror(a, b, quadric)
    d = columns(v, "v", 3)
    if isinstance(mir, HyperbolicMirror):
        return line_quadric_roots(d, mir.a, mir.b)
    return line_quadric_roots(d, mir.h)


def f_projectmir(a: float, b: float, quadric: int, Xmir: npt.ArrayLike) -> np.ndarray:
    r"""The mirror point :math:`X_h = \lambda X` seen towards ``Xmir`` (3, N, mirror frame): (3, N).

    The intersection of the ray from the focus towards the point (:math:`\lambda > 0`)
    with the sheet the CCD sees, inside the rim; NaN where the mirror does not
    show the point (blind cone, above the rim).
    """
    mir = mirror(a, b, quadric)
    d = columns(Xmir, "Xmir", 3)
    lam, _ = mir.intersect(d)
    return (lam[:, None] * d).T


def f_daqaXhmir(
    Q: npt.ArrayLike, K: npt.ArrayLike | None = None, a: float = 3.0, b: float = 1.0, quadric: int = 1
) -> np.ndarray:
    """Mirror points (3, N, mirror frame) imaged at the pixels ``Q`` (2, N) or homogeneous (3, N).

    The inverse of :func:`f_panproj`'s second output: NaN columns for pixels
    that no visible mirror point images to.
    """
    cam = catadioptric(np.eye(4), K, a, b, quadric)
    d = cam.back_project(pixels(Q, "Q"))
    seen = ~np.isnan(d[:, 0])
    Xh = np.full_like(d, np.nan)
    if seen.any():
        lam, _ = cam.mirror.intersect(d[seen], rim_tol=1e-9)
        Xh[seen] = lam[:, None] * d[seen]
    return Xh.T


def f_findepipoles(
    F: npt.ArrayLike, a: float = 3.0, b: float = 1.0, K: npt.ArrayLike | None = None, quadric: int = 1
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Epipoles of a mirror whose focus is at the origin, for another focus at ``F`` (mirror frame).

    Returns:
        ``(qe1, qe2, e1, e2)``: ``e1`` the mirror point towards ``F``, ``e2``
        the one away from it (3-vectors, mirror frame), ``qe1``, ``qe2`` their
        homogeneous pixels (last coordinate 1); NaN where the mirror does not
        show that direction.
    """
    f = as_vector(F, "F", 3)
    if not np.linalg.norm(f) > 0.0:
        raise DegenerateConfigurationError("F: the other focus coincides with this one; no baseline")
    cam = catadioptric(np.eye(4), K, a, b, quadric)
    proj = cam.project_directions(np.array([f, -f]))
    q = np.column_stack([proj.pixels, np.where(proj.visible, 1.0, np.nan)])
    return q[0], q[1], proj.mirror_points[0], proj.mirror_points[1]


def f_panparconic(
    P: npt.ArrayLike, H: npt.ArrayLike, K: npt.ArrayLike | None = None, a: float = 3.0, b: float = 1.0,
    quadric: int = 2, *plot: Any,
) -> tuple[float, float, float, np.ndarray, np.ndarray]:
    r"""The circle that a parabolic mirror images the plane through its focus and two points onto.

    The plane through the focus and ``P[:, 0]``, ``P[:, 1]`` has the normal
    :math:`n = X_{h2} \times X_{h1} / |\cdot|` (mirror frame); its image is the
    circle (stereographic projection of a great circle)

    .. math:: c = (u_0, v_0) - h \alpha (n_x / n_z, n_y / n_z), \qquad r = h \alpha / |n_z|

    for :math:`K = [\alpha, 0, u_0; 0, \alpha, v_0; 0, 0, 1]`. Computed as the
    image conic of the plane (:func:`~egtviz.geometry.panoramic_epipolar.conic_from_plane`).

    Args:
        P: (3, 2) world points.
        H, K, a, b: the camera as in :func:`f_panproj` (``h = a``).
        quadric: must be 2 (a hyperbolic mirror images planes to general conics: :func:`f_epipconics`).
        *plot: EGT's ``col, f_3d, f_image``: a colour draws the normal and the circle.

    Returns:
        ``(cx, cy, r, n, P_mirror)``: centre, radius in pixels, the unit normal (3,)
        and the two points in the mirror frame (3, 2).

    Raises:
        GeometryError: ``quadric`` is not 2, ``K`` has skew or non-square pixels,
            a point is not visible, or the plane is vertical through the axis (its image is a line).
    """
    if quadric != 2:
        raise GeometryError(f"quadric: f_panparconic is for a parabolic mirror (quadric 2), got {quadric!r}")
    cam = catadioptric(H, K, a, b, 2)
    X = world_columns(P, "P")
    if len(X) != 2:
        raise GeometryError(f"P: expected two points, shape (3, 2), got {len(X)}")
    Kc = cam.K
    if abs(Kc[0, 1]) > 1e-12 * abs(Kc[0, 0]) or abs(Kc[0, 0] - Kc[1, 1]) > 1e-12 * abs(Kc[0, 0]):
        raise GeometryError("K: the image of a plane is a circle only with square pixels and no skew")
    proj = cam.project(X)
    if not proj.visible.all():
        raise GeometryError("P: both points must be visible in the mirror")
    Xh = proj.mirror_points
    n = np.cross(Xh[1], Xh[0])
    if not np.linalg.norm(n) > 1e-12 * np.linalg.norm(Xh[0]) * np.linalg.norm(Xh[1]):
        raise DegenerateConfigurationError("P: the two points are on one ray from the focus; no plane")
    n = n / np.linalg.norm(n)
    C = conic_from_plane(cam, n)[0]
    if abs(C[0, 0]) <= 1e-12 * np.abs(C).max():
        raise DegenerateConfigurationError("P: the plane contains the mirror axis; its image is a line")
    cx, cy = -C[0, 2] / C[0, 0], -C[1, 2] / C[0, 0]
    r = float(np.sqrt(cx * cx + cy * cy - C[2, 2] / C[0, 0]))
    colour = style(plot)
    if colour is not None:
        # EGT draws the normal at the centroid of the focus and the two points.
        origin = cam.pose.to_world(cam.pose.to_local(X).sum(axis=0) / 3.0)[0]
        _draw("normal", origin=origin, direction=cam.pose.R @ n, style=colour)
        _draw("circle", centre=np.array([cx, cy]), radius=r, figure=None, style=colour)
    return float(cx), float(cy), r, n, cam.pose.to_local(X).T

