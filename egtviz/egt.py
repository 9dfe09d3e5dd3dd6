"""The EGT facade: the tutorial's MATLAB function names, in Python.

A student can type the tutorial's code almost verbatim::

    from egtviz.egt import *
    H = f_Rt2H(rotoy(pi / 4), [-10, -5, 0])
    u, v = f_perspproj(Xw, H, eye(3))

Points are EGT's **columns** here: world points ``(3, N)``, pixels ``(2, N)``
(or homogeneous ``(3, N)``); a single point may be a flat vector. Everything
else in egtviz uses rows; this module only converts and delegates to
:mod:`egtviz.geometry` (conventions: ``docs/conventions.md``).
"""

from __future__ import annotations

from math import pi  # noqa: F401 - for tutorial code typed after `from egtviz.egt import *`

import numpy as np
import numpy.typing as npt
from numpy import eye  # noqa: F401

from .geometry import estimation
from .geometry._validate import GeometryError, as_array, as_matrix, as_positive
from .geometry.catadioptric import CatadioptricCamera
from .geometry.epipolar import epipolar_lines, epipolar_lines_in_first, epipolar_pair
from .geometry.mirrors import HyperbolicMirror, ParabolicMirror
from .geometry.panoramic_epipolar import epipolar_conics, panoramic_epipoles
from .geometry.pinhole import Intrinsics, PinholeCamera
from .geometry.poses import Pose, rotx, roty, rotz

__all__ = [
    "rotox", "rotoy", "rotoz", "f_Rt2H", "f_perspproj", "f_panproj", "f_epipole", "f_epipline",
    "f_panepipoles", "f_epipconics", "f_Festim", "DEFAULT_PANORAMIC_K", "pi", "eye",
]

#: The tutorial's panoramic CCD calibration (Example 2).
DEFAULT_PANORAMIC_K = np.array([[1e3, 0.0, 320.0], [0.0, 1e3, 240.0], [0.0, 0.0, 1.0]])

rotox = rotx
rotoy = roty
rotoz = rotz


def _columns(X: npt.ArrayLike, name: str, rows: int) -> np.ndarray:
    """EGT columns ``(rows, N)`` (or one flat point) -> core rows ``(N, rows)``."""
    arr = as_array(X, name)
    if arr.ndim == 1 and arr.shape[0] == rows:
        return arr[None, :]
    if arr.ndim != 2 or arr.shape[0] != rows:
        raise GeometryError(f"{name}: expected shape ({rows}, N) (EGT columns), got {arr.shape}")
    return arr.T


def _pixels(m: npt.ArrayLike, name: str) -> np.ndarray:
    """Pixels as ``(2, N)`` or homogeneous ``(3, N)`` columns -> ``(N, 2)`` rows."""
    arr = as_array(m, name)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] not in (2, 3):
        raise GeometryError(f"{name}: expected pixels of shape (2, N) or homogeneous (3, N), got {arr.shape}")
    if arr.shape[0] == 3:
        if np.any(np.abs(arr[2]) < 1e-300):
            raise GeometryError(f"{name}: a homogeneous pixel has last coordinate 0 (a point at infinity)")
        arr = arr[:2] / arr[2]
    return arr.T


def f_Rt2H(R: npt.ArrayLike, t: npt.ArrayLike) -> np.ndarray:
    r"""EGT's pose of a pin-hole camera: :math:`H = [R_x(-\pi/2) R\ t;\ 0\ 1]` (4x4).

    ``R`` turns the camera about its own axes (identity: looking along world +y),
    ``t`` is its centre in world coordinates (3-vector or 3x1).
    """
    return Pose.from_egt(R, t).matrix


def _pinhole(H: npt.ArrayLike, K: npt.ArrayLike, name: str = "K") -> PinholeCamera:
    try:
        intrinsics = Intrinsics.from_K(K)
    except GeometryError as exc:  # name the facade's argument (K1, K2), not Intrinsics'
        raise GeometryError(str(exc).replace("K:", f"{name}:", 1)) from exc
    return PinholeCamera(Pose.from_matrix(H), intrinsics)


def f_perspproj(Xw: npt.ArrayLike, H: npt.ArrayLike, K: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Pin-hole projection :math:`m \sim K [R^T | -R^T t] X_w` of world points ``Xw`` (3, N).

    Returns ``(u, v)``, arrays of length N; NaN for a point behind the camera.
    """
    proj = _pinhole(H, K).project(_columns(Xw, "Xw", 3))
    return proj.pixels[:, 0], proj.pixels[:, 1]


def _catadioptric(H: npt.ArrayLike, K: npt.ArrayLike | None, a: float, b: float, quadric: int) -> CatadioptricCamera:
    if quadric == 1:
        mirror = HyperbolicMirror(as_positive(a, "a"), as_positive(b, "b"))
    elif quadric == 2:
        mirror = ParabolicMirror(as_positive(a, "a"))
    else:
        raise GeometryError(f"quadric: expected 1 (hyperbolic) or 2 (parabolic), got {quadric!r}")
    return CatadioptricCamera(Pose.from_matrix(H), mirror, DEFAULT_PANORAMIC_K if K is None else K)


def f_panproj(
    Xw: npt.ArrayLike, H: npt.ArrayLike, K: npt.ArrayLike | None = None, a: float = 3.0, b: float = 1.0, *, quadric: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    r"""Central catadioptric projection of ``Xw`` (3, N) through a mirror at pose ``H``.

    ``quadric=1``: hyperbolic mirror ``a``, ``b`` with a pin-hole CCD; ``quadric=2``:
    parabolic mirror with ``h = a`` and an orthographic CCD.

    Returns ``(m, Xh)``: ``m`` (3, N) homogeneous pixels (last row 1), ``Xh``
    (3, N) mirror points in the mirror frame; NaN columns where not visible.
    """
    proj = _catadioptric(H, K, a, b, quadric).project(_columns(Xw, "Xw", 3))
    m = np.vstack([proj.pixels.T, np.where(proj.visible, 1.0, np.nan)])
    return m, proj.mirror_points.T


def f_epipole(
    H1: npt.ArrayLike, H2: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Epipoles and fundamental matrix of two pin-hole cameras.

    Returns ``(e1, e2, F)``: ``e1`` the epipole in image 1 (``F e1 = 0``), ``e2``
    in image 2, homogeneous 3-vectors (last coordinate 1, or 0 at infinity),
    and ``F`` with :math:`m_2^T F m_1 = 0`.
    """
    pair = epipolar_pair(_pinhole(H1, K1, "K1"), _pinhole(H2, K2, "K2"))
    return pair.e1, pair.e2, pair.F


def f_epipline(m1: npt.ArrayLike, m2: npt.ArrayLike, F: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Epipolar lines ``(l1, l2)``, each (3, N): :math:`l_1 = F^T m_2` in image 1, :math:`l_2 = F m_1` in image 2."""
    F = as_matrix(F, "F", (3, 3))
    return epipolar_lines_in_first(F, _pixels(m2, "m2")).T, epipolar_lines(F, _pixels(m1, "m1")).T


def f_panepipoles(
    H1: npt.ArrayLike, H2: npt.ArrayLike, K: npt.ArrayLike | None = None, a: float = 3.0, b: float = 1.0, *, quadric: int = 1
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both image epipoles of both panoramic cameras: ``(e1, e1p, e2, e2p)``, homogeneous 3-vectors.

    ``e1`` is the image of the ray from focus 1 towards focus 2, ``e1p`` of the
    ray away from it (both intersections of the baseline with mirror 1).
    """
    ep = panoramic_epipoles(_catadioptric(H1, K, a, b, quadric), _catadioptric(H2, K, a, b, quadric))
    return ep.e1, ep.e1p, ep.e2, ep.e2p


def f_epipconics(
    Xw: npt.ArrayLike,
    H1: npt.ArrayLike,
    H2: npt.ArrayLike,
    K: npt.ArrayLike | None = None,
    a: float = 3.0,
    b: float = 1.0,
    *,
    quadric: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """Epipolar conics of the points ``Xw`` (3, N) in both images: ``(C1, C2)``, each (N, 3, 3), ``m^T C m = 0``."""
    return epipolar_conics(
        _catadioptric(H1, K, a, b, quadric), _catadioptric(H2, K, a, b, quadric), _columns(Xw, "Xw", 3)
    )


#: ``f_Festim`` algorithm numbers: EGT's Table I (1-3) and EGT 2.0's robust estimators.
FESTIM_ALGORITHMS = {
    1: "linear 8-point",
    2: "normalized 8-point (Hartley)",
    3: "Sampson distance minimisation",
    4: "RANSAC",
    5: "LMedS",
}


def f_Festim(U1: npt.ArrayLike, U2: npt.ArrayLike, algorithm: int = 2) -> np.ndarray:
    r"""Fundamental matrix from pixel correspondences ``U1``, ``U2`` (2, N), with :math:`u_2^T F u_1 = 0`.

    ``algorithm``: 1 linear 8-point, 2 normalized 8-point, 3 Sampson, 4 RANSAC,
    5 LMedS (:data:`FESTIM_ALGORITHMS`). The result has rank 2 and unit norm.
    """
    p1, p2 = _pixels(U1, "U1"), _pixels(U2, "U2")
    if algorithm == 1:
        return estimation.fundamental_8point(p1, p2)
    if algorithm == 2:
        return estimation.fundamental_normalized_8point(p1, p2)
    if algorithm == 3:
        return estimation.fundamental_sampson(p1, p2)
    if algorithm == 4:
        return estimation.fundamental_ransac(p1, p2).F
    if algorithm == 5:
        return estimation.fundamental_lmeds(p1, p2).F
    raise GeometryError(f"algorithm: expected one of {sorted(FESTIM_ALGORITHMS)}, got {algorithm!r}")
