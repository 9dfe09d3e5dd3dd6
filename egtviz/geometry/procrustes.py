r"""Rotation fitting between two sets of corresponding directions (orthogonal Procrustes, Kabsch).

Points are rows.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import DegenerateConfigurationError, GeometryError, as_points

__all__ = ["rotation_aligning"]


def rotation_aligning(X: npt.ArrayLike, Y: npt.ArrayLike) -> np.ndarray:
    r"""The rotation :math:`R` that best maps ``Y`` onto ``X``: :math:`\min_R \sum_i |x_i - R y_i|^2`.

    With :math:`M = \sum_i x_i y_i^T = U \Sigma V^T` (Kabsch),

    .. math:: R = U \operatorname{diag}(1, 1, \det(U V^T)) V^T ,

    a proper rotation (:math:`\det R = +1`) even when the unconstrained
    orthogonal optimum is a reflection.

    Args:
        X: (N, 3) target vectors.
        Y: (N, 3) source vectors, the same N.

    Raises:
        GeometryError: bad shapes or counts.
        DegenerateConfigurationError: the vectors span less than a plane (rotation not unique).
    """
    x = as_points(X, "X", 3)
    y = as_points(Y, "Y", 3)
    if x.shape != y.shape:
        raise GeometryError(f"Y: expected as many vectors as X ({len(x)}), got {len(y)}")
    U, s, Vt = np.linalg.svd(x.T @ y)
    if s[1] <= 1e-12 * max(s[0], 1e-300):
        raise DegenerateConfigurationError("X, Y: the vectors are collinear; the rotation is not unique")
    sign = np.sign(np.linalg.det(U @ Vt))
    return (U * np.array([1.0, 1.0, sign])) @ Vt
