"""Column/row conversion, argument checks and the drawing hook (:func:`draw`) shared by the facade's modules."""

from __future__ import annotations

import importlib
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from ..geometry._validate import (
    MAX_MAGNITUDE,
    GeometryError,
    as_array,
    as_calibration,
    as_count,
    as_matrix,
    as_positive,
)
from ..geometry.catadioptric import CatadioptricCamera
from ..geometry.mirrors import HyperbolicMirror, ParabolicMirror
from ..geometry.pinhole import Intrinsics, PinholeCamera
from ..geometry.planar_mirror import split_virtual_pose
from ..geometry.poses import Pose

#: The tutorial's panoramic CCD calibration (Example 2).
DEFAULT_PANORAMIC_K = np.array([[1e3, 0.0, 320.0], [0.0, 1e3, 240.0], [0.0, 0.0, 1.0]])

#: The module that draws EGT's figures, when it is installed.
FIGURE_MODULE = "egtviz.egt_figure"


def columns(X: npt.ArrayLike, name: str, rows: int) -> np.ndarray:
    """EGT columns ``(rows, N)`` (or one flat point) -> core rows ``(N, rows)``."""
    return _column_rows(as_array(X, name, allow_empty=False), name, rows)


def _column_rows(arr: np.ndarray, name: str, rows: int) -> np.ndarray:
    """:func:`columns` of an array checked already (one check of a large array is a pass over it)."""
    if arr.ndim == 1 and arr.shape[0] == rows:
        return arr[None, :]
    if arr.ndim != 2 or arr.shape[0] != rows or arr.shape[1] == 0:
        raise GeometryError(f"{name}: expected shape ({rows}, N) with N >= 1 (EGT columns), got {arr.shape}")
    return arr.T


def world_columns(X: npt.ArrayLike, name: str) -> np.ndarray:
    """World points as ``(3, N)`` or homogeneous ``(4, N)`` columns -> ``(N, 3)`` rows (EGT passes both)."""
    arr = cast(np.ndarray, X) if _plainly_in_range(X) else as_array(X, name, allow_empty=False)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim == 2 and arr.shape[0] == 4 and arr.shape[1] > 0:
        w = arr[3]
        if np.any(np.abs(w) <= 1e-12 * np.abs(arr).max(axis=0)):
            raise GeometryError(f"{name}: a homogeneous point has last coordinate 0 (a point at infinity)")
        arr = as_array(arr[:3] / w, name)  # the division can leave the accepted range
    return _column_rows(arr, name, 3)


#: Sum of squares below which every entry is within ``MAX_MAGNITUDE``: half of ``MAX_MAGNITUDE**2`` leaves room for
#: the sum's rounding (relative error at most n eps, far below 1/2 for any array that fits in memory).
_SQUARES_LIMIT = 0.5 * MAX_MAGNITUDE**2


def _plainly_in_range(X: object) -> bool:
    """Whether ``X`` is a large contiguous float64 array whose entries are all finite and within ``MAX_MAGNITUDE``,
    by one BLAS pass (the sum of squares: NaN and inf make it NaN or inf, a huge entry makes it large) instead of
    the check's two reductions, min and max. False is no verdict: the caller runs the full check, which names
    what is wrong, or accepts an array of many large but acceptable entries."""
    if type(X) is not np.ndarray or X.dtype != np.float64 or X.size <= 64 or X.ndim > 2:
        return False
    if not (X.flags.c_contiguous or X.flags.f_contiguous):
        return False
    flat = X.ravel(order="K")  # a view of a contiguous array
    with np.errstate(over="ignore", invalid="ignore"):  # a huge entry overflowing to inf is the answer "no"
        return bool(flat @ flat <= _SQUARES_LIMIT)


def pixels(m: npt.ArrayLike, name: str) -> np.ndarray:
    """Pixels as ``(2, N)`` or homogeneous ``(3, N)`` columns -> ``(N, 2)`` rows."""
    arr = as_array(m, name, allow_empty=False)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] not in (2, 3):
        raise GeometryError(f"{name}: expected pixels of shape (2, N) or homogeneous (3, N), got {arr.shape}")
    if arr.shape[0] == 3:
        if np.any(np.abs(arr[2]) <= 1e-12 * np.abs(arr).max(axis=0)):
            raise GeometryError(f"{name}: a homogeneous pixel has last coordinate 0 (a point at infinity)")
        arr = arr[:2] / arr[2]
    return arr.T


def pinhole(
    H: npt.ArrayLike, K: npt.ArrayLike, name: str = "K", pose_name: str = "H"
) -> tuple[PinholeCamera, np.ndarray | None]:
    r"""A pin-hole camera from EGT's ``H`` and ``K``, and the image flip of a reflected (virtual) camera.

    A virtual camera ``H`` (rotation with determinant -1, from ``f_reflcamera``)
    is the proper camera with its x axis reversed followed by the pixel map
    :math:`M = K S K^{-1}`, :math:`S = \mathrm{diag}(-1, 1, 1)`; ``M`` is None
    for an ordinary camera.
    """
    Kc = as_calibration(K, name)
    pose, flipped = split_virtual_pose(H, pose_name)
    camera = PinholeCamera(pose, Intrinsics.from_K(Kc, check=False))  # Kc: checked just above
    flip = Kc @ np.diag([-1.0, 1.0, 1.0]) @ np.linalg.inv(Kc) if flipped else None
    return camera, flip


def mirror(a: float, b: float, quadric: int) -> HyperbolicMirror | ParabolicMirror:
    """EGT's mirror: ``quadric`` 1 hyperbolic (``a``, ``b``), 2 parabolic (``h = a``)."""
    kind = as_count(quadric, "quadric", minimum=1, maximum=2)
    if kind == 1:
        return HyperbolicMirror(as_positive(a, "a"), as_positive(b, "b"))
    return ParabolicMirror(as_positive(a, "a"))


def catadioptric(
    H: npt.ArrayLike, K: npt.ArrayLike | None, a: float, b: float, quadric: int, pose_name: str = "H"
) -> CatadioptricCamera:
    """A central catadioptric camera from EGT's arguments (``K`` None: :data:`DEFAULT_PANORAMIC_K`)."""
    Kc = DEFAULT_PANORAMIC_K if K is None else as_calibration(K, "K")
    M = as_matrix(H, pose_name, (4, 4))
    if not np.allclose(M[3], [0.0, 0.0, 0.0, 1.0]):
        raise GeometryError(f"{pose_name}: expected a 4x4 pose [R t; 0 1] with last row (0, 0, 0, 1)")
    try:
        pose = Pose(M[:3, :3], M[:3, 3])
    except GeometryError as exc:
        raise GeometryError(f"{pose_name}: {exc}") from exc
    return CatadioptricCamera(pose, mirror(a, b, quadric), Kc)


def flag(value: Any) -> int:
    """EGT's plot flag (0 off, 1 or 2 on): numbers and booleans; anything else counts as off."""
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if isinstance(value, (int, float, np.integer, np.floating)) and np.isfinite(value):
        return int(value)
    return 0


def style(values: tuple[Any, ...]) -> str | None:
    """The first string among EGT's trailing plot arguments (a MATLAB colour/line style such as ``'b:'``)."""
    return next((v for v in values if isinstance(v, str)), None)


def draw(kind: str, **data: Any) -> Any:
    """Hand one drawing to the figure front-end, if it is installed; otherwise nothing happens.

    The facade never draws itself: EGT's plotting arguments become one call
    ``egtviz.egt_figure.draw(kind, **data)``. Arrays are EGT columns, world
    coordinates unless said otherwise; ``style`` is a MATLAB colour/line style
    string or None; ``figure`` an EGT figure number or None. The kinds:

    - ``"image_points"``: ``pixels`` (2, N), the camera's ``H`` (4, 4) and ``K`` (3, 3), ``figure``, ``style``
      -- an image-plane plot.
    - ``"projection_rays"``: ``points`` (3, N), ``centre`` (3,) -- lines from a camera centre to its points.
    - ``"epipolar_lines"``: ``lines`` (3, N), ``points`` (2, N), ``epipole`` (3,), ``figure``, ``style``
      -- one call per image.
    - ``"panoramic_points"``: ``points`` (3, N), ``mirror_points`` (3, N) world, ``focus`` (3,), ``style``.
    - ``"sphere_model"``: ``H`` (4, 4), ``ell``, ``m``, ``points`` (3, N), ``sphere_points`` (3, N) world,
      ``style``, ``rays`` (bool).
    - ``"circle"``: ``centre`` (2,), ``radius``, ``figure``, ``style`` -- an image-plane circle.
    - ``"normal"``: ``origin`` (3,), ``direction`` (3,), ``style``.
    - ``"line3d"``: ``points`` (3, 2), ``style``.
    - ``"scene_points"``: ``points`` (3, N), ``style``.
    - ``"camera"``: ``H`` (4, 4) (possibly a reflected, left-handed frame), ``style``, ``scale``,
      ``frame_length``, ``title``.
    - ``"surface"``: ``x``, ``y``, ``z``, ``nx``, ``ny``, ``nz`` (n, n) grids.

    Returns:
        Whatever the front-end returns, or None when it is not installed.
    """
    try:
        module = importlib.import_module(FIGURE_MODULE)
    except ModuleNotFoundError as exc:
        if exc.name != FIGURE_MODULE:
            raise
        return None
    return module.draw(kind, **data)
