r"""Small matrix utilities of two-view geometry: rank-2 projection, stacking, point normalisation, angles.

Points are rows, ``(N, 2)`` pixels; conventions: ``docs/conventions.md``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import cast

import numpy as np
import numpy.typing as npt
from scipy.linalg import lapack as _lapack

from ._validate import (
    MAX_MAGNITUDE,
    DegenerateConfigurationError,
    GeometryError,
    as_array,
    as_count,
    as_matrix,
    as_points,
)

__all__ = [
    "full_angle",
    "hartley_normalization",
    "hartley_scales",
    "nearest_rank2",
    "point_pairs",
    "stack_columns",
    "unstack_columns",
]

#: Smallest mean distance of the points from their centroid that can be normalised: ``F``'s entries scale as
#: ``1 / spread^2`` against ``F[2, 2]``, and below this they are not representable.
_MIN_SPREAD = 1e-100


def nearest_rank2(M: npt.ArrayLike, *, check: bool = True) -> np.ndarray:
    r"""The rank-2 matrix nearest to ``M`` in Frobenius norm (Eckart-Young; H&Z 2nd ed., section 11.1.1).

    .. math:: M = U \operatorname{diag}(\sigma_1, \sigma_2, \sigma_3) V^T
        \ \mapsto\ U \operatorname{diag}(\sigma_1, \sigma_2, 0) V^T

    Args:
        M: (3, 3) matrix, in the caller's scale.
        check: validate ``M``. ``False`` is the estimators' inner-loop path: ``M`` must then be a
            finite float64 (3, 3) array already checked by the caller.
    """
    A = as_matrix(M, "M", (3, 3), max_abs=None) if check else cast(np.ndarray, M)
    # LAPACK directly: numpy.linalg's wrapper costs more than a 3x3 SVD.
    U, s, Vt, info = _lapack.dgesvd(A)
    if info != 0:  # pragma: no cover - LAPACK failure
        U, s, Vt = np.linalg.svd(A)
    return (U[:, :2] * s[:2]) @ Vt[:2]


def point_pairs(
    U1: npt.ArrayLike, U2: npt.ArrayLike, min_count: int = 1, names: tuple[str, str] = ("U1", "U2")
) -> tuple[np.ndarray, np.ndarray]:
    """Two validated ``(N, 2)`` pixel arrays of corresponding points, the same ``N >= min_count``.

    Raises:
        GeometryError: a bad array (named), too few points, or different counts.
    """
    u1 = as_points(U1, names[0], 2, min_count=min_count)
    u2 = as_points(U2, names[1], 2, min_count=min_count)
    if u1.shape[0] != u2.shape[0]:
        raise GeometryError(
            f"{names[0]}, {names[1]}: expected the same number of points, got {u1.shape[0]} and {u2.shape[0]}"
        )
    return u1, u2


def stack_columns(M: npt.ArrayLike) -> np.ndarray:
    r"""The column-wise stacking :math:`\mathrm{vec}(M)` of an (m, n) matrix: an (m n,) vector, column 1 first."""
    A = as_array(M, "M", allow_empty=False, max_abs=None)
    if A.ndim != 2:
        raise GeometryError(f"M: expected a 2-D matrix, got shape {A.shape}")
    return A.reshape(-1, order="F")


def unstack_columns(v: npt.ArrayLike, columns: int) -> np.ndarray:
    r"""The inverse of :func:`stack_columns`: an (len(v) / columns, columns) matrix filled column by column.

    Raises:
        GeometryError: ``columns`` does not divide the length of ``v``.
    """
    a = as_array(v, "v", allow_empty=False, max_abs=None).reshape(-1)
    k = as_count(columns, "columns", minimum=1)
    if a.size % k:
        raise GeometryError(f"columns: {k} does not divide the vector's length {a.size}")
    return a.reshape(k, -1).T.copy()


def hartley_normalization(
    U: npt.ArrayLike | Sequence[np.ndarray], name: str | Sequence[str] = "U", *, check: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    r"""Hartley's isotropic normalisation of pixels (H&Z 2nd ed., section 4.4.4 and Algorithm 11.1).

    .. math:: T = \begin{bmatrix} s & 0 & -s c_u \\ 0 & s & -s c_v \\ 0 & 0 & 1 \end{bmatrix},
        \qquad s = \frac{\sqrt 2}{\tfrac1N \sum_i |u_i - c|}

    with :math:`c` the centroid: the normalised points :math:`\hat u = T u` have centroid 0 and MEAN
    distance :math:`\sqrt 2` from it (H&Z's definition, as OpenCV and kornia normalise; not the
    root-mean-square distance). ``docs/conventions.md`` states the choice.

    Args:
        U: (N, 2) pixels; or K images normalised each on its own (the two images of an estimator),
            as a (K, N, 2) stack or a sequence of K (N, 2) arrays.
        name: the argument's name in error messages; for K images, one name per image.
        check: validate ``U`` first. ``False`` for float64 (N, 2) arrays whose type and shape the caller
            has checked: their values are then checked on the way, from the centroid and the mean
            distance (a NaN or inf makes the centroid non-finite; every coordinate is within
            :math:`|c| + N \bar d` of the origin), and a bad one raises the same ``GeometryError`` as
            the full check, before any degeneracy of any image is reported.

    Returns:
        ``(Un, T)``: (N, 2) normalised pixels and the (3, 3) similarity ``T``; for K images, (K, N, 2)
        and (K, 3, 3).

    Raises:
        DegenerateConfigurationError: all points coincide (to 1e-9 of their distance from the origin).
        GeometryError: a bad ``U``, or points spread over less than 1e-100 (rescale the coordinates).
    """
    single = isinstance(name, str)
    names = [name] if isinstance(name, str) else list(name)
    images = _images(U, names, single, check)
    k, n = len(images), images[0].shape[0]
    # Each row (x, y) read as one complex number x + iy, all images stacked: the centroids, the distances
    # |u_i - c| (a hypot) and the scaling are then one numpy call each for all images, on contiguous
    # memory; numpy's per-call cost, not the arithmetic, dominates at the sizes of an estimation.
    Un = np.empty((k, n, 2))
    np.concatenate(images, out=Un.reshape(k * n, 2))
    Z = Un.view(np.complex128)[..., 0]
    centres = [c / n for c in np.add.reduce(Z, axis=1).tolist()]
    hartley_scales(centres, None, n, images, names)
    Z -= np.array(centres)[:, None]
    means = [d / n for d in np.add.reduce(np.abs(Z), axis=1).tolist()]
    scales = hartley_scales(centres, means, n, images, names)
    Z *= np.array(scales)[:, None]
    flat: list[float] = []
    for c, s in zip(centres, scales):
        flat += [s, 0.0, -s * c.real, 0.0, s, -s * c.imag, 0.0, 0.0, 1.0]
    T = np.array(flat).reshape(k, 3, 3)
    return (Un[0], T[0]) if single else (Un, T)


def hartley_scales(
    centres: Sequence[complex],
    means: Sequence[float] | None,
    n: int,
    images: Sequence[np.ndarray],
    names: Sequence[str],
) -> list[float]:
    r"""The scales :math:`s = \sqrt 2 / \bar d` of :func:`hartley_normalization`, checking the images' values.

    For a caller that has computed, for each image of ``n`` points, the centroid :math:`c` (as
    ``x + iy``) and the mean distance :math:`\bar d` from it itself, from float64 arrays whose type and
    shape it has checked (``check=False`` of :func:`hartley_normalization`). Every centroid must be
    finite (else the NaN or inf is named); every coordinate, within :math:`|c| + n \bar d` of the
    origin, must be in range (else the full check decides); the points must spread. ``means=None``
    checks the centroids only and returns ``[]``.

    Raises:
        GeometryError: a NaN, inf or huge value (the image named), or a spread below 1e-100.
        DegenerateConfigurationError: all points of an image coincide.
    """
    for image, c, nm in zip(images, centres, names):
        if not (math.isfinite(c.real) and math.isfinite(c.imag)):
            as_points(image, nm, 2)  # names the NaN or inf (or the magnitude that overflowed the sum)
    if means is None:
        return []
    for image, c, mean, nm in zip(images, centres, means, names):
        if not max(abs(c.real), abs(c.imag)) + n * mean <= MAX_MAGNITUDE:
            as_points(image, nm, 2)  # a coordinate may exceed MAX_MAGNITUDE: the full check decides
    for c, mean, nm in zip(centres, means, names):
        _check_spread(mean, c, nm)
    return [math.sqrt(2.0) / mean for mean in means]


def _images(U: npt.ArrayLike | Sequence[np.ndarray], names: list[str], single: bool, check: bool) -> list[np.ndarray]:
    """The images of :func:`hartley_normalization` as a list of (N, 2) arrays, validated if ``check``."""
    if single:
        return [as_points(U, names[0], 2) if check else cast(np.ndarray, U)]
    images = list(cast(Sequence[np.ndarray], U)) if isinstance(U, (list, tuple)) or not check else None
    if images is None:
        stack = as_array(U, ", ".join(names))
        if stack.ndim != 3 or stack.shape[2] != 2:
            raise GeometryError(f"{', '.join(names)}: expected shape ({len(names)}, N, 2), got {stack.shape}")
        images = list(stack)
    if len(images) != len(names):
        raise GeometryError(f"{', '.join(names)}: expected {len(names)} images, got {len(images)}")
    if check:
        images = [as_points(a, nm, 2) for a, nm in zip(images, names)]
        if len({a.shape[0] for a in images}) != 1:
            raise GeometryError(f"{', '.join(names)}: expected the same number of points in every image")
    return images


def _check_spread(mean: float, centroid: complex, name: str) -> None:
    """Refuse coincident points and a spread below ``_MIN_SPREAD``, naming the image."""
    if not mean > 1e-9 * max(abs(centroid.real), abs(centroid.imag)) or mean == 0.0:
        raise DegenerateConfigurationError(f"{name}: all points coincide; no normalisation exists")
    if mean < _MIN_SPREAD:
        raise GeometryError(
            f"{name}: the points spread over {mean:.3g} only; below a spread of {_MIN_SPREAD:.0e} they cannot be "
            "normalised and F cannot be computed (rescale the coordinates)"
        )


def full_angle(y: npt.ArrayLike, x: npt.ArrayLike) -> np.ndarray:
    r"""The angle of :math:`(x, y)` in :math:`[0, 2\pi)`: :math:`\operatorname{atan2}(y, x) \bmod 2\pi`.

    ``y`` and ``x`` broadcast against each other; ``(0, 0)`` gives 0.
    """
    yy = as_array(y, "y", allow_empty=False)
    xx = as_array(x, "x", allow_empty=False)
    try:
        a = np.arctan2(yy, xx)
    except ValueError as exc:
        raise GeometryError(f"y, x: shapes {yy.shape} and {xx.shape} do not broadcast") from exc
    a = np.where(a < 0.0, a + 2.0 * np.pi, a)
    # A tiny negative angle rounds to exactly 2 pi; it is the angle 0.
    return np.where(a >= 2.0 * np.pi, 0.0, a)
