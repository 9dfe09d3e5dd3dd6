r"""The essential matrix from correspondences and rays, its decomposition, and the cheirality test.

Hartley & Zisserman, *Multiple View Geometry*, 2nd ed. (H&Z), section 9.6 ("The essential matrix"):

* :func:`essential_from_correspondences`: ``E`` from calibrated pixel correspondences (the
  normalised 8-point algorithm of section 11.2 on :math:`K^{-1} m`, then the projection of
  Result 9.17 onto the essential matrices).
* :func:`essential_from_rays`: ``E`` from corresponding rays (bearing vectors, mirror points;
  EGT's ``f_panEestim`` without the sampling).
* :func:`decompose_essential`: the four poses of section 9.6.2, Result 9.19.
* :func:`pose_from_essential`: the pose of those four that puts the points in front of both cameras
  (section 9.6.3, "Geometrical interpretation of the four solutions").

``E`` from two poses is :func:`~egtviz.geometry.epipolar.essential_from_poses`. The ray kernels
:func:`ray_pairs`, :func:`essential_linear`, :func:`essential_projection` and :func:`ray_sampson` are
public for :func:`~egtviz.geometry.robust.essential_from_rays_ransac`.

Conventions (``docs/conventions.md``): points are rows; the pose between the cameras maps camera-1
coordinates to camera-2 coordinates, :math:`X_{c2} = R X_{c1} + t` and :math:`E = [t]_\times R`,
:math:`x_2^T E x_1 = 0`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_calibration, as_points, as_up_to_scale, as_up_to_scale_rows
from .fundamental import canonical_fundamental, design_matrix, fundamental_normalized_8point, null_vector
from .matrices import point_pairs

__all__ = [
    "decompose_essential",
    "essential_from_correspondences",
    "essential_from_rays",
    "essential_linear",
    "essential_projection",
    "pose_from_essential",
    "ray_pairs",
    "ray_sampson",
]


def _homogeneous(u: np.ndarray) -> np.ndarray:
    h = np.empty((u.shape[0], 3))
    h[:, :2] = u
    h[:, 2] = 1.0
    return h


def essential_from_correspondences(
    U1: npt.ArrayLike, U2: npt.ArrayLike, K1: npt.ArrayLike, K2: npt.ArrayLike
) -> np.ndarray:
    r"""Essential matrix from calibrated correspondences (H&Z 2nd ed., sections 9.6 and 11.1).

    The pixels are normalised, :math:`\hat x = K^{-1} m`, the normalised
    8-point algorithm gives :math:`E_0` with :math:`\hat x_2^T E_0 \hat x_1 = 0`,
    and :math:`E_0 = U \Sigma V^T` is projected onto the essential matrices
    (two equal singular values, one zero, H&Z Result 9.17):

    .. math:: E = U \operatorname{diag}(1, 1, 0) V^T / \sqrt 2 .

    Decompose it with :func:`decompose_essential` / :func:`pose_from_essential`.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        K1: ``(3, 3)`` calibration of camera 1.
        K2: ``(3, 3)`` calibration of camera 2.

    Returns:
        ``(3, 3)`` ``E``, unit Frobenius norm, largest entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8``, mismatched ``N`` or a
            non-invertible calibration.
        DegenerateConfigurationError: coincident points or rank-deficient data.
    """
    u1, u2 = point_pairs(U1, U2, 8)
    x1 = np.linalg.solve(as_calibration(K1, "K1"), _homogeneous(u1).T).T
    x2 = np.linalg.solve(as_calibration(K2, "K2"), _homogeneous(u2).T).T
    E0 = fundamental_normalized_8point(x1[:, :2] / x1[:, 2:], x2[:, :2] / x2[:, 2:])
    U, _, Vt = np.linalg.svd(E0)
    return canonical_fundamental(U @ np.diag([1.0, 1.0, 0.0]) @ Vt)


def ray_pairs(d1: npt.ArrayLike, d2: npt.ArrayLike, min_count: int) -> tuple[np.ndarray, np.ndarray]:
    """Two ``(N, 3)`` ray arrays (any nonzero length each) with the same ``N``, scaled to unit rows."""
    r1 = as_up_to_scale_rows(d1, "d1", 3, min_count=min_count)
    r2 = as_up_to_scale_rows(d2, "d2", 3, min_count=min_count)
    if r1.shape[0] != r2.shape[0]:
        raise GeometryError(f"d1, d2: expected the same number of rays, got {r1.shape[0]} and {r2.shape[0]}")
    return (
        r1 / np.linalg.norm(r1, axis=1, keepdims=True),
        r2 / np.linalg.norm(r2, axis=1, keepdims=True),
    )


def essential_projection(M: np.ndarray) -> np.ndarray:
    r"""Nearest essential matrices :math:`U \operatorname{diag}(1, 1, 0) V^T / \sqrt 2` of a stack ``(..., 3, 3)``."""
    U, _, Vt = np.linalg.svd(M)
    return (U[..., :, :2] @ Vt[..., :2, :]) / math.sqrt(2.0)


def ray_sampson(Es: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    r"""Squared angular Sampson distances ``(M, N)`` (radians squared) of unit rays under ``M`` matrices ``Es``.

    The first-order distance to the constraint :math:`d_2^T E d_1 = 0` when each unit ray moves on its
    sphere: the gradients are projected on the tangent planes,
    :math:`g_1 = (I - d_1 d_1^T) E^T d_2`, :math:`g_2 = (I - d_2 d_2^T) E d_1`, and
    :math:`\delta = (d_2^T E d_1)^2 / (|g_1|^2 + |g_2|^2)`.
    """
    Ed1 = np.einsum("mij,nj->mni", Es, r1)  # (M, N, 3)
    Etd2 = np.einsum("mji,nj->mni", Es, r2)
    e = np.einsum("mni,ni->mn", Ed1, r2)
    e1 = np.einsum("mni,ni->mn", Etd2, r1)  # equal to e; used to project Etd2
    g1 = np.einsum("mni,mni->mn", Etd2, Etd2) - e1 * e1
    g2 = np.einsum("mni,mni->mn", Ed1, Ed1) - e * e
    return e * e / np.maximum(g1 + g2, 1e-300)


def essential_linear(r1: np.ndarray, r2: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Linear E of unit rays (rows), optionally with row weights; unit Frobenius norm, canonical sign."""
    At = design_matrix(r1, r2)
    if weights is not None:
        At = At * np.sqrt(weights)
    E0 = null_vector(At, "d1, d2").reshape(3, 3)
    return canonical_fundamental(essential_projection(E0))


def essential_from_rays(d1: npt.ArrayLike, d2: npt.ArrayLike) -> np.ndarray:
    r"""Essential matrix from corresponding rays (H&Z 2nd ed., sections 9.6 and 11.1; EGT's ``f_panEestim``).

    A ray is any direction from a camera's centre (a bearing vector, a point
    on a mirror seen from its focus, :math:`K^{-1} m` for a pin-hole camera);
    each row is scaled to unit length, which conditions the linear system as
    Hartley's normalisation does for pixels. Each correspondence gives one
    equation in :math:`e = \mathrm{vec}(E)`,

    .. math:: d_2^T E d_1 = (d_2^T \otimes d_1^T)\, e = 0, \qquad
              \hat e = \arg\min_{\|e\| = 1} \|A e\| ,

    and :math:`\hat E = U \Sigma V^T` is projected onto the essential
    matrices (H&Z Result 9.17): :math:`E = U \operatorname{diag}(1, 1, 0) V^T / \sqrt 2`.
    With :math:`X_2 = R X_1 + t` between the two frames, :math:`E \simeq [t]_\times R`.

    Args:
        d1: ``(N, 3)`` rays in frame 1 (any nonzero lengths), ``N >= 8``.
        d2: ``(N, 3)`` corresponding rays in frame 2.

    Returns:
        ``(3, 3)`` ``E`` with :math:`d_2^T E d_1 = 0`, singular values
        :math:`(1/\sqrt 2, 1/\sqrt 2, 0)` (unit Frobenius norm), largest-magnitude
        entry positive.

    Raises:
        GeometryError: bad types or shapes, NaN/inf, a zero ray, ``N < 8`` or mismatched ``N``.
        DegenerateConfigurationError: a design matrix of rank below 8 (e.g. the
            scene points and both centres on one plane, or repeated rays).
    """
    r1, r2 = ray_pairs(d1, d2, 8)
    return essential_linear(r1, r2)


def decompose_essential(E: npt.ArrayLike) -> list[tuple[np.ndarray, np.ndarray]]:
    r"""The four poses compatible with an essential matrix (H&Z 2nd ed., Result 9.19, section 9.6.2).

    With :math:`E = U\,\mathrm{diag}(1, 1, 0)\,V^T` (:math:`\det U = \det V = 1`)
    and :math:`W = \begin{bmatrix}0&-1&0\\1&0&0\\0&0&1\end{bmatrix}`:

    .. math:: R \in \{U W V^T,\ U W^T V^T\}, \qquad t = \pm u_3 ,

    where :math:`u_3` is the last column of :math:`U` (unit norm). Each pair
    satisfies :math:`E \simeq [t]_\times R` with :math:`X_{c2} = R X_{c1} + t`.

    Args:
        E: ``(3, 3)`` essential matrix (any nonzero scale; noise is tolerated,
            the closest essential matrix is used).

    Returns:
        ``[(R1, t), (R1, -t), (R2, t), (R2, -t)]``, rotations ``(3, 3)``, unit ``t`` ``(3,)``.

    Raises:
        GeometryError: bad shape, NaN/inf, or ``E`` of rank below 2.
    """
    E = as_up_to_scale(E, "E", (3, 3))
    U, S, Vt = np.linalg.svd(E)
    if S[0] == 0 or S[1] <= 1e-9 * S[0]:
        raise GeometryError("E: expected an essential matrix of rank 2")
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    Ra = U @ W @ Vt
    Rb = U @ W.T @ Vt
    t = U[:, 2].copy()
    return [(Ra, t), (Ra, -t), (Rb, t.copy()), (Rb, -t)]


def _depths(R: np.ndarray, t: np.ndarray, h1: np.ndarray, h2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Depths :math:`z_1, z_2` minimising :math:`\|z_1 R x_1 + t - z_2 x_2\|` per point (NaN if parallel)."""
    a = h1 @ R.T
    b = h2
    aa = np.einsum("ij,ij->i", a, a)
    bb = np.einsum("ij,ij->i", b, b)
    ab = np.einsum("ij,ij->i", a, b)
    at = a @ t
    bt = b @ t
    det = aa * bb - ab * ab
    ok = det > 1e-14 * aa * bb
    dets = np.where(ok, det, 1.0)
    # Normal equations: [aa, -ab; ab, -bb] [z1; z2] = [-at; -bt]
    z1 = (-at * bb + ab * bt) / dets
    z2 = (aa * bt - ab * at) / dets
    return np.where(ok, z1, np.nan), np.where(ok, z2, np.nan)


def pose_from_essential(
    E: npt.ArrayLike, x1n: npt.ArrayLike, x2n: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Relative pose from ``E`` by the cheirality test (H&Z 2nd ed., section 9.6.3).

    Of the four poses of :func:`decompose_essential` the one that puts the most
    triangulated points in front of both cameras is chosen. Depths solve, per
    point, the two-ray least-squares problem

    .. math:: \min_{z_1, z_2} \| z_1 R x_1 + t - z_2 x_2 \| ,

    and a point is in front if :math:`z_1 > 0` and :math:`z_2 > 0`.
    ``cv2.recoverPose`` uses the same convention (:math:`X_{c2} = R X_{c1} + t`).

    Args:
        E: ``(3, 3)`` essential matrix, :math:`x_2^T E x_1 = 0`.
        x1n: ``(N, 2)`` normalised (calibrated) coordinates :math:`K_1^{-1} m_1` in image 1.
        x2n: ``(N, 2)`` normalised coordinates in image 2.

    Returns:
        ``(R, t, in_front)``: rotation ``(3, 3)``, unit translation ``(3,)``
        (the baseline's scale is unobservable) and the ``(N,)`` bool mask of
        points in front of both cameras.
    """
    sols = decompose_essential(E)
    a1 = as_points(x1n, "x1n", 2, min_count=1)
    a2 = as_points(x2n, "x2n", 2, min_count=1)
    if a1.shape[0] != a2.shape[0]:
        raise GeometryError(
            f"x1n, x2n: expected the same number of points, got {a1.shape[0]} and {a2.shape[0]}"
        )
    h1 = _homogeneous(a1)
    h2 = _homogeneous(a2)
    best = None
    for R, t in sols:
        z1, z2 = _depths(R, t, h1, h2)
        mask = (z1 > 0) & (z2 > 0)
        if best is None or mask.sum() > best[2].sum():
            best = (R, t, mask)
    assert best is not None
    return best
