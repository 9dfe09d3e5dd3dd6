r"""Epipolar geometry of two central catadioptric cameras: epipoles and epipolar conics.

EGT reference, section 5 (``f_panepipoles``, ``f_epipconics``) and section 7
(bi-conics of the panoramic visual-servoing demo); ``docs/conventions.md``.

Every plane through a mirror focus cuts the unit sphere around it in a great
circle, and the unified projection (see :mod:`egtviz.geometry.catadioptric`)
maps that circle to a conic of the image. In normalised coordinates
:math:`q = K_g^{-1} m` of the unified frame, for a plane normal :math:`n`
expressed in that frame (Barreto & Araujo; Geyer & Daniilidis), substituting
:math:`s = (\eta x, \eta y, \eta - \xi)` in :math:`n^T s = 0` and
:math:`|s| = 1` gives :math:`q^T \Omega q = 0` with

.. math::
    \Omega = (1 - \xi^2)\, n n^T + \xi^2 n_z (e_3 n^T + n e_3^T) - \xi^2 n_z^2 I
    = \begin{bmatrix}
        n_x^2 (1-\xi^2) - n_z^2 \xi^2 & n_x n_y (1-\xi^2) & n_x n_z \\
        n_x n_y (1-\xi^2) & n_y^2 (1-\xi^2) - n_z^2 \xi^2 & n_y n_z \\
        n_x n_z & n_y n_z & n_z^2
    \end{bmatrix},

and in pixels :math:`C = K_g^{-T} \Omega K_g^{-1}`. The algebraic conic is the
image of the *whole* great circle; for a hyperbolic mirror part of it belongs
to blind-cone rays (a phantom branch) and any mirror clips it at the rim's
image. :func:`sample_plane_conic` returns only the real, visible arcs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_count, as_points, as_up_to_scale_rows
from .catadioptric import CatadioptricCamera
from .poses import skew
from .unified_sphere import MAX_CONIC_SAMPLES, great_circle_arcs

__all__ = [
    "MAX_CONIC_SAMPLES",
    "PanoramicEpipoles",
    "biconic",
    "conic_from_plane",
    "epipolar_conics",
    "panoramic_epipoles",
    "panoramic_essential",
    "sample_epipolar_conics",
    "sample_plane_conic",
    "sample_plane_conics",
]

_DEGENERATE_REL = 1e-10


def _check_camera(camera: object, name: str) -> CatadioptricCamera:
    if not isinstance(camera, CatadioptricCamera):
        raise GeometryError(f"{name}: expected a CatadioptricCamera, got {type(camera).__name__}")
    return camera


def _baseline(cam1: CatadioptricCamera, cam2: CatadioptricCamera) -> np.ndarray:
    """``O2 - O1`` in the world; raises when the foci coincide."""
    b = cam2.pose.t - cam1.pose.t
    scale = max(1.0, float(np.linalg.norm(cam1.pose.t)), float(np.linalg.norm(cam2.pose.t)))
    if np.linalg.norm(b) <= 1e-12 * scale:
        raise DegenerateConfigurationError("no epipolar geometry: the centres coincide")
    return b


def _homogeneous(m: np.ndarray) -> np.ndarray:
    """Scale a homogeneous 3-vector: last coordinate 1, or unit norm if at infinity; NaN if zero."""
    norm = np.linalg.norm(m)
    if not norm > 0:
        return np.full(3, np.nan)
    if abs(m[2]) < 1e-12 * norm:
        out = m / norm
        out[2] = 0.0
        return out
    return m / m[2]


def panoramic_essential(cam1: CatadioptricCamera, cam2: CatadioptricCamera) -> np.ndarray:
    r"""Essential matrix between the two mirror frames.

    With :math:`R = R_2^T R_1`, :math:`t = R_2^T (t_1 - t_2)` (so that mirror-1
    coordinates map to mirror-2 coordinates as :math:`X_2 = R X_1 + t`),

    .. math:: E = [t]_\times R, \qquad X_{h2}^T E X_{h1} = 0

    for the mirror points of one scene point (they are :math:`\lambda`-multiples
    of :math:`X_1`, :math:`X_2`, coplanar with the baseline). ``E`` is not
    rescaled: its Frobenius norm is :math:`\sqrt{2}\,|t|`.

    Raises:
        DegenerateConfigurationError: if the two foci coincide.
    """
    cam1 = _check_camera(cam1, "cam1")
    cam2 = _check_camera(cam2, "cam2")
    _baseline(cam1, cam2)
    R1, R2 = cam1.pose.R, cam2.pose.R
    R = R2.T @ R1
    t = R2.T @ (cam1.pose.t - cam2.pose.t)
    return skew(t) @ R


@dataclass(frozen=True, eq=False)
class PanoramicEpipoles:
    """The two epipoles of each image of a panoramic pair.

    The baseline through a focus meets its mirror twice (once on each side);
    ``e`` is the image of the ray towards the other focus, ``e_p`` of the ray
    away from it. Pixels are homogeneous 3-vectors, last coordinate 1 (a
    point at infinity, which needs a ray exactly through the unified model's
    projection centre, is unit-norm with last coordinate 0). They are the
    common points of all epipolar conics of the image, so they are given even
    when the corresponding ray misses the mirror (a blind-cone ray's *phantom*
    image); the ``*_visible`` flags say whether the mirror really shows them,
    and the ``*_mirror`` points are NaN when it does not. One case has no
    epipole at all: for a parabolic mirror, the ray straight up its axis is
    the unified model's projection centre (every epipolar conic then contains
    the whole line at infinity); that epipole is NaN and not visible.
    """

    e1: np.ndarray
    """(3,) image 1: towards focus 2."""
    e1p: np.ndarray
    """(3,) image 1: away from focus 2."""
    e2: np.ndarray
    """(3,) image 2: towards focus 1."""
    e2p: np.ndarray
    """(3,) image 2: away from focus 1."""
    e1_visible: bool
    """The ray of ``e1`` meets mirror 1 inside its rim."""
    e1p_visible: bool
    """The ray of ``e1p`` meets mirror 1 inside its rim."""
    e2_visible: bool
    """The ray of ``e2`` meets mirror 2 inside its rim."""
    e2p_visible: bool
    """The ray of ``e2p`` meets mirror 2 inside its rim."""
    e1_mirror: np.ndarray
    """(3,) mirror point of ``e1`` in mirror frame 1 (NaN if not visible)."""
    e1p_mirror: np.ndarray
    """(3,) mirror point of ``e1p`` in mirror frame 1 (NaN if not visible)."""
    e2_mirror: np.ndarray
    """(3,) mirror point of ``e2`` in mirror frame 2 (NaN if not visible)."""
    e2p_mirror: np.ndarray
    """(3,) mirror point of ``e2p`` in mirror frame 2 (NaN if not visible)."""


def panoramic_epipoles(cam1: CatadioptricCamera, cam2: CatadioptricCamera) -> PanoramicEpipoles:
    r"""Both epipoles of both images (EGT's ``f_panepipoles``).

    In mirror frame 1 the baseline direction is :math:`d_1 = R_1^T (t_2 - t_1)`;
    ``e1`` is the image of :math:`d_1`, ``e1p`` of :math:`-d_1` (and likewise
    for camera 2 with :math:`d_2 = R_2^T (t_1 - t_2)`), computed with the
    unified model so that they are the exact common points of the epipolar conics.

    Raises:
        DegenerateConfigurationError: if the two foci coincide.
    """
    cam1 = _check_camera(cam1, "cam1")
    cam2 = _check_camera(cam2, "cam2")
    b = _baseline(cam1, cam2)
    out: dict[str, object] = {}
    for cam, d, tag in ((cam1, b @ cam1.pose.R, "e1"), (cam2, -b @ cam2.pose.R, "e2")):
        dirs = np.stack([d, -d])
        m = cam._unified_homogeneous(dirs)
        proj = cam.project_directions(dirs)
        for i, suffix in enumerate(("", "p")):
            out[tag + suffix] = _homogeneous(m[i])
            out[tag + suffix + "_visible"] = bool(proj.visible[i])
            out[tag + suffix + "_mirror"] = proj.mirror_points[i]
    return PanoramicEpipoles(**out)  # type: ignore[arg-type]


def _conics_from_normals(camera: CatadioptricCamera, n_mirror: np.ndarray) -> np.ndarray:
    """Vectorised conics (N, 3, 3) of planes through the focus; NaN rows for zero normals."""
    return camera._mirror_plane_conics(n_mirror)


def conic_from_plane(camera: CatadioptricCamera, n_mirror: npt.ArrayLike) -> np.ndarray:
    r"""Image conics of planes through the mirror focus.

    .. math:: C = K_g^{-T}\, \Omega(F n)\, K_g^{-1}, \qquad m^T C m = 0,

    with :math:`\Omega` as in the module docstring, :math:`F = \mathrm{diag}(1,-1,-1)`
    taking the normal from the mirror frame into the unified frame and
    :math:`K_g` the camera's :attr:`~CatadioptricCamera.unified_calibration`.
    ``C`` is symmetric with unit Frobenius norm (its overall sign is arbitrary).

    Args:
        camera: the catadioptric camera.
        n_mirror: (N, 3) plane normals in the mirror frame (any length).

    Returns:
        (N, 3, 3) conics; NaN for zero normals. A normal is defined up to scale (each is divided by its
        largest entry first, so any finite magnitude gives the same conic).
    """
    camera = _check_camera(camera, "camera")
    return _conics_from_normals(camera, as_up_to_scale_rows(n_mirror, "n_mirror", 3, allow_zero=True))


def _epipolar_normals(cam1: CatadioptricCamera, cam2: CatadioptricCamera, X: np.ndarray) -> np.ndarray:
    """World normals ``(O2 - O1) x (X - O1)``; NaN rows for points on the baseline."""
    b = _baseline(cam1, cam2)
    v = X - cam1.pose.t
    n = np.cross(b, v)
    degenerate = np.linalg.norm(n, axis=1) <= _DEGENERATE_REL * np.linalg.norm(b) * np.linalg.norm(v, axis=1)
    n[degenerate] = np.nan
    return n


def epipolar_conics(
    cam1: CatadioptricCamera, cam2: CatadioptricCamera, X_world: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    r"""Epipolar conics of scene points in both images (EGT's ``f_epipconics``).

    The epipolar plane of :math:`X` passes through both foci and :math:`X`; its
    world normal :math:`n = (O_2 - O_1) \times (X - O_1)` is rotated into each
    mirror frame (:math:`R_i^T n`) and imaged with :func:`conic_from_plane`.
    Each conic passes through the image of :math:`X` and through both epipoles
    of its image.

    Args:
        cam1: first camera.
        cam2: second camera.
        X_world: (N, 3) scene points.

    Returns:
        ``(C1, C2)``, each (N, 3, 3). Points on the baseline (including the foci)
        have no unique epipolar plane: their rows are NaN.

    Raises:
        DegenerateConfigurationError: if the two foci coincide.
    """
    cam1 = _check_camera(cam1, "cam1")
    cam2 = _check_camera(cam2, "cam2")
    X = as_points(X_world, "X_world", 3)
    n = _epipolar_normals(cam1, cam2, X)
    return _conics_from_normals(cam1, n @ cam1.pose.R), _conics_from_normals(cam2, n @ cam2.pose.R)


def biconic_normals(d_current: npt.ArrayLike, d_desired: npt.ArrayLike) -> np.ndarray:
    r"""Normals :math:`n = d_c \times d_d` (N, 3) of the bi-conic planes; zero rows where the rays are parallel.

    Directions are defined up to scale: each is divided by its largest entry first (a zero direction gives a
    zero normal).

    Args:
        d_current: (N, 3) current viewing directions, mirror frame.
        d_desired: (N, 3) desired viewing directions, mirror frame.
    """
    dc = as_up_to_scale_rows(d_current, "d_current", 3, allow_zero=True)
    dd = as_up_to_scale_rows(d_desired, "d_desired", 3, allow_zero=True)
    if dc.shape != dd.shape:
        raise GeometryError(f"d_desired: expected shape {dc.shape} like d_current, got {dd.shape}")
    n = np.cross(dc, dd)
    degenerate = np.linalg.norm(n, axis=1) <= _DEGENERATE_REL * np.linalg.norm(dc, axis=1) * np.linalg.norm(
        dd, axis=1
    )
    n[degenerate] = 0.0
    return n


def biconic(camera: CatadioptricCamera, d_current: npt.ArrayLike, d_desired: npt.ArrayLike) -> np.ndarray:
    r"""Bi-conics: images of the planes through the focus containing two viewing rays.

    For each pair, :math:`n = d_c \times d_d` (mirror frame, :func:`biconic_normals`) and
    :math:`C = ` :func:`conic_from_plane` (``camera``, :math:`n`); used by the
    panoramic visual-servoing demo (EGT reference, section 7), where all
    bi-conics meet in the epipoles once the rotation is compensated.

    Args:
        camera: the catadioptric camera.
        d_current: (N, 3) current viewing directions, mirror frame.
        d_desired: (N, 3) desired viewing directions, mirror frame.

    Returns:
        (N, 3, 3) conics; NaN rows where the two directions are parallel.
    """
    camera = _check_camera(camera, "camera")
    return _conics_from_normals(camera, biconic_normals(d_current, d_desired))


def sample_biconics(
    camera: CatadioptricCamera, d_current: npt.ArrayLike, d_desired: npt.ArrayLike, n: int = 96
) -> list[list[np.ndarray]]:
    """Visible arcs of the bi-conics (:func:`sample_plane_conics` of :func:`biconic_normals`); empty where parallel."""
    camera = _check_camera(camera, "camera")
    return _sample_circles(camera, biconic_normals(d_current, d_desired), n)


def _sample_circles(camera: CatadioptricCamera, normals: np.ndarray, n: int) -> list[list[np.ndarray]]:
    """Visible arcs of the images of great circles, one list of polylines per normal (checked mirror-frame
    normals (N, 3); :func:`~egtviz.geometry.unified_sphere.great_circle_arcs`)."""
    n = as_count(n, "n", minimum=3, maximum=MAX_CONIC_SAMPLES)
    arcs = great_circle_arcs(np.ascontiguousarray(normals.T), n, camera.mirror.rim_cosine, camera._unit_ray_pixels)
    return [list(a) for a in arcs]


def sample_plane_conic(camera: CatadioptricCamera, n_mirror: npt.ArrayLike, n: int = 256) -> list[np.ndarray]:
    """Polylines of the real image of a plane through the focus, clipped to the visible mirror.

    Samples ``n`` unit directions on the plane's great circle, keeps those
    whose ray meets the mirror (inside the rim, outside the blind cone),
    projects them, and splits them into contiguous runs. The sampling is
    rotated so that no run straddles the circle's start, so there is neither a
    phantom branch nor a jump segment. Each arc is extended at both ends by the
    point where the circle leaves the visible field (found by bisection), so it
    ends on the rim's image. A fully visible circle is returned as one closed
    polyline (first point repeated at the end). Pixels may lie outside the
    image rectangle; viewers clip them.

    Args:
        camera: the catadioptric camera.
        n_mirror: (3,) plane normal in the mirror frame (non-zero).
        n: number of samples on the full circle (>= 3).

    Returns:
        A list of (k, 2) pixel polylines, ``k >= 3``; empty if nothing is visible.

    Raises:
        GeometryError: on a zero normal.
    """
    camera = _check_camera(camera, "camera")
    normal = as_up_to_scale_rows(n_mirror, "n_mirror", 3, allow_zero=True)
    if len(normal) != 1:
        raise GeometryError(f"n_mirror: expected one normal (3,), got {len(normal)}")
    if not normal.any():
        raise GeometryError("n_mirror: a zero normal defines no plane")
    return _sample_circles(camera, normal, n)[0]


def sample_plane_conics(
    camera: CatadioptricCamera, n_mirror: npt.ArrayLike, n: int = 256
) -> list[list[np.ndarray]]:
    """:func:`sample_plane_conic` for many planes at once (one vectorised projection).

    Args:
        camera: the catadioptric camera.
        n_mirror: (N, 3) plane normals in the mirror frame.
        n: number of samples on each full circle (>= 3).

    Returns:
        For each normal, its list of (k, 2) pixel polylines; an empty list for
        a zero normal or a plane that misses the visible mirror.
    """
    camera = _check_camera(camera, "camera")
    return _sample_circles(camera, as_up_to_scale_rows(n_mirror, "n_mirror", 3, allow_zero=True), n)


def sample_epipolar_conics(
    cam1: CatadioptricCamera, cam2: CatadioptricCamera, X_world: npt.ArrayLike, n: int = 256
) -> tuple[list[list[np.ndarray]], list[list[np.ndarray]]]:
    """Visible arcs of the epipolar conics of scene points, in both images.

    Args:
        cam1: first camera.
        cam2: second camera.
        X_world: (N, 3) scene points.
        n: samples per great circle.

    Returns:
        ``(arcs1, arcs2)``: for each point, the list of polylines of
        :func:`sample_plane_conic` in image 1 and in image 2 (empty for points
        on the baseline).

    Raises:
        DegenerateConfigurationError: if the two foci coincide.
    """
    cam1 = _check_camera(cam1, "cam1")
    cam2 = _check_camera(cam2, "cam2")
    X = as_points(X_world, "X_world", 3)
    nw = _epipolar_normals(cam1, cam2, X)
    return _sample_circles(cam1, nw @ cam1.pose.R, n), _sample_circles(cam2, nw @ cam2.pose.R, n)
