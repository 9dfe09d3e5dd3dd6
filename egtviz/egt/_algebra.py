"""EGT's small linear-algebra helpers: skew matrices, E decomposition, normalisation, rank 2, stacking, angles."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ..geometry._validate import as_up_to_scale
from ..geometry.essential import decompose_essential
from ..geometry.matrices import full_angle, hartley_normalization, nearest_rank2, stack_columns, unstack_columns
from ..geometry.poses import skew
from ..geometry.procrustes import rotation_aligning
from ._convert import columns, pixels


def f_skew(v: npt.ArrayLike) -> np.ndarray:
    r"""The cross-product matrix :math:`[v]_\times = [0, -v_3, v_2;\ v_3, 0, -v_1;\ -v_2, v_1, 0]`."""
    return skew(v)


def f_E2Motion(E: npt.ArrayLike) -> np.ndarray:
    r"""The four motions ``[R | t]`` compatible with an essential matrix (H&Z Result 9.19), a (3, 4, 4) array.

    ``Sol[:, :, k] = [R_k, t_k]`` in EGT's order: :math:`(R_1, t), (R_1, -t), (R_2, t), (R_2, -t)`.
    Each satisfies :math:`E = \pm [t]_\times R`: :math:`|t| = (\sigma_1 + \sigma_2) / 2`, the
    scale of ``E`` (so the essential matrix of :func:`f_panE` returns the true baseline length).
    """
    s = np.linalg.svd(as_up_to_scale(E, "E", (3, 3)), compute_uv=False)
    scale = 0.5 * (s[0] + s[1]) * float(np.abs(np.asarray(E, dtype=np.float64)).max())
    sol = np.empty((3, 4, 4))
    for k, (R, t) in enumerate(decompose_essential(E)):
        sol[:, :3, k] = R
        sol[:, 3, k] = scale * t
    return sol


def f_normalize(U: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Hartley's normalisation of pixels ``U`` (2, N) or (3, N): centroid 0, mean distance :math:`\sqrt 2`.

    H&Z's definition (section 4.4.4), as ``docs/conventions.md`` states; EGT's own code divided the
    root of the summed squares by ``N``, which is neither the mean nor the RMS distance.

    Returns ``(Un, T)``: (2, N) normalised points and the 3x3 ``T`` with
    :math:`(Un; 1) = T (U; 1)`.
    """
    un, T = hartley_normalization(pixels(U, "U"))
    return un.T, T


def f_forcerank2(M: npt.ArrayLike) -> np.ndarray:
    r"""The nearest rank-2 matrix: :math:`U \operatorname{diag}(\sigma_1, \sigma_2, 0) V^T`."""
    return nearest_rank2(M)


def f_stack(M: npt.ArrayLike) -> np.ndarray:
    """Column-wise stacking :math:`\\mathrm{vec}(M)`, as a column ``(m n, 1)`` like MATLAB's ``M(:)``."""
    return stack_columns(M)[:, None]


def f_unstacked(v: npt.ArrayLike, dimension: int) -> np.ndarray:
    """The inverse of :func:`f_stack`: ``v`` filled column by column into ``dimension`` columns."""
    return unstack_columns(v, dimension)


def f_atan(y: npt.ArrayLike, x: npt.ArrayLike) -> np.ndarray:
    r"""The angle of :math:`(x, y)` in :math:`[0, 2\pi)`."""
    return full_angle(y, x)


def f_Procrustes(X: npt.ArrayLike, Y: npt.ArrayLike) -> np.ndarray:
    r"""The rotation ``R`` that best maps the columns of ``Y`` onto those of ``X`` (both (3, N)).

    .. math:: \min_{R \in SO(3)} \| X - R Y \|_F, \quad X Y^T = U \Sigma V^T,\quad
        R = U \operatorname{diag}(1, 1, \det U V^T) V^T
    """
    return rotation_aligning(columns(X, "X", 3), columns(Y, "Y", 3))
