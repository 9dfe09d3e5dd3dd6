"""EGT's estimators: the fundamental matrix from pixels (``f_Festim``) and E from mirror points (``f_panEestim``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ..geometry.fundamental import fundamental_8point, fundamental_normalized_8point
from ..geometry.mestimator import fundamental_mestimator
from ..geometry.robust import essential_from_rays_ransac, fundamental_lmeds, fundamental_mapsac, fundamental_ransac
from ..geometry.sampson_refinement import fundamental_sampson
from ..geometry._validate import GeometryError, as_count, as_positive, short_repr
from ._convert import columns, pixels

#: ``f_Festim`` algorithms: EGT 2.0's numbers 1-6, and RANSAC under 7 (EGT has no RANSAC).
FESTIM_ALGORITHMS = {
    1: "linear 8-point",
    2: "normalized 8-point (Hartley)",
    3: "Sampson distance minimisation",
    4: "Torr's M-estimator",
    5: "LMedS",
    6: "MAPSAC",
    7: "RANSAC",
}

#: Names accepted for ``algorithm``, each for one number of :data:`FESTIM_ALGORITHMS`.
FESTIM_NAMES = {"linear": 1, "normalized": 2, "sampson": 3, "mestimator": 4, "lmeds": 5, "mapsac": 6, "ransac": 7}


def _algorithm(algorithm: int | str) -> int:
    if isinstance(algorithm, str):
        key = algorithm.strip().lower()
        if key not in FESTIM_NAMES:
            raise GeometryError(f"algorithm: expected one of {sorted(FESTIM_NAMES)} or 1-7, got {short_repr(algorithm)}")
        return FESTIM_NAMES[key]
    try:
        number = as_count(algorithm, "algorithm", minimum=1)
    except GeometryError as exc:
        raise GeometryError(f"algorithm: expected one of {sorted(FESTIM_ALGORITHMS)} or a name {sorted(FESTIM_NAMES)}, "
                            f"got {short_repr(algorithm)}") from exc
    if number not in FESTIM_ALGORITHMS:
        raise GeometryError(f"algorithm: expected one of {sorted(FESTIM_ALGORITHMS)} or a name {sorted(FESTIM_NAMES)}, "
                            f"got {number}")
    return number


def f_Festim(U1: npt.ArrayLike, U2: npt.ArrayLike, algorithm: int | str = 2, *unused: Any) -> np.ndarray:
    r"""Fundamental matrix from pixel correspondences ``U1``, ``U2`` (2, N), with :math:`u_2^T F u_1 = 0`.

    Args:
        U1, U2: (2, N) or homogeneous (3, N) pixels in images 1 and 2.
        algorithm: EGT 2.0's numbers, 1 linear 8-point, 2 normalized 8-point,
            3 Sampson, 4 Torr's M-estimator, 5 LMedS, 6 MAPSAC; 7 (or
            ``"ransac"``) RANSAC; or the names of :data:`FESTIM_NAMES`.
        *unused: EGT's ``roundf`` (rounding of the result) is accepted and has no effect.

    Returns:
        (3, 3) ``F`` of rank 2 and unit Frobenius norm.
    """
    kind = _algorithm(algorithm)
    p1, p2 = pixels(U1, "U1"), pixels(U2, "U2")
    if kind == 1:
        return fundamental_8point(p1, p2)
    if kind == 2:
        return fundamental_normalized_8point(p1, p2)
    if kind == 3:
        return fundamental_sampson(p1, p2)
    if kind == 4:
        return fundamental_mestimator(p1, p2, weight="torr").F
    if kind == 5:
        return fundamental_lmeds(p1, p2).F
    if kind == 6:
        return fundamental_mapsac(p1, p2).F
    return fundamental_ransac(p1, p2).F


def f_panEestim(M: npt.ArrayLike, n: int = 2000, error: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    r"""Robust essential matrix from mirror points: ``M = [X1; X2]`` (6, N), :math:`X_2^T E X_1 = 0`.

    The rows 1-3 of ``M`` are the mirror points (any point on each ray from the
    focus) in camera 1's mirror frame, rows 4-6 those of the same scene points
    in camera 2's; the same convention as :func:`f_panE` (EGT 2.0's own code
    solves :math:`X_1^T E X_2 = 0`, the transpose). RANSAC over 8-ray samples
    with an angular Sampson threshold, then a refit on the inliers
    (:func:`~egtviz.geometry.robust.essential_from_rays_ransac`).

    Args:
        M: (6, N) stacked mirror points, ``N >= 8``.
        n: most RANSAC samples.
        error: inlier threshold on the angular Sampson distance, radians.

    Returns:
        ``(E, gE)``: ``E`` with unit Frobenius norm and singular values
        :math:`(1/\sqrt2, 1/\sqrt2, 0)`, and the (N,) inlier flags (1 inlier, 0 outlier).
    """
    rows = columns(M, "M", 6)
    est = essential_from_rays_ransac(
        rows[:, :3], rows[:, 3:], threshold_rad=as_positive(error, "error"), max_iterations=as_count(n, "n")
    )
    return est.F, est.inliers.astype(int)
