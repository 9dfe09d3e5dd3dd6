r"""Iterative estimation of the fundamental matrix: minimisation of the Sampson distance.

Hartley & Zisserman, *Multiple View Geometry*, 2nd ed. (H&Z), section 11.4.3 ("The Sampson
distance") over the minimal parameterisation of a rank-2 ``F`` of section 11.4.2
("Parametrization of rank-2 matrices"): :func:`fundamental_sampson` (EGT's ``f_Festim`` algorithm 3),
and :func:`refine_sampson`, the same minimisation in Hartley-normalised coordinates with optional
weights, which the robust estimators of :mod:`egtviz.geometry.robust` and
:mod:`egtviz.geometry.mestimator` use as their last step.

Conventions (``docs/conventions.md``): pixels as rows ``(N, 2)``; :math:`m_2^T F m_1 = 0`.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.linalg import lapack as _lapack
from scipy.optimize import leastsq

from ._validate import GeometryError, as_up_to_scale
from .fundamental import canonical_fundamental, normalized_design, null_vector
from .matrices import nearest_rank2, point_pairs

__all__ = ["fundamental_sampson", "polish_sampson", "refine_sampson"]


# The generators of so(3): [c]_x = sum_i c_i _GENERATORS[i]. A contraction with them builds a stack of
# cross-product matrices in one product (each entry is one +-c_i: the same numbers as writing them out).
_GENERATORS = np.array(
    [
        [[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
        [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]],
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
    ]
)


def _skew_stack(c: np.ndarray) -> np.ndarray:
    """Cross-product matrices ``(K, 3, 3)`` of vectors ``(K, 3)``."""
    return (c @ _GENERATORS.reshape(3, 9)).reshape(-1, 3, 3)


_EYE3 = np.eye(3)
_EYE3.setflags(write=False)


def _rodrigues_jr(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Rotation :math:`R(\omega)` and right Jacobian :math:`J_r(\omega)`.

    :math:`R(\omega + \delta) \approx R(\omega) \exp([J_r(\omega) \delta]_\times)`, with
    :math:`W = [\omega]_\times`, :math:`R = I + a W + b W^2`, :math:`J_r = I - b W + c W^2`,
    :math:`a = \sin\theta / \theta`, :math:`b = (1 - \cos\theta) / \theta^2`,
    :math:`c = (\theta - \sin\theta) / \theta^3`. Written with Python floats: numpy's per-call
    cost would dominate on these 3x3 matrices, which the Levenberg-Marquardt loop builds at every step.
    """
    x, y, z = w.tolist()
    if x == y == z == 0.0:
        return _EYE3, _EYE3  # what the formulas give at 0, exactly (every start of an iteration is there)
    th = math.sqrt(x * x + y * y + z * z)
    if th < 1e-8:
        a, b, c = 1.0, 0.5, 1.0 / 6.0
    else:
        a = math.sin(th) / th
        b = (1.0 - math.cos(th)) / th**2
        c = (th - math.sin(th)) / th**3
    # W @ W, entry by entry as the product computes it; then R and J entry by entry (W's diagonal is zero).
    q00, q01, q02 = -z * z - y * y, y * x, z * x
    q10, q11, q12 = x * y, -z * z - x * x, z * y
    q20, q21, q22 = x * z, y * z, -y * y - x * x
    R = (
        (1.0 + b * q00, a * -z + b * q01, a * y + b * q02),
        (a * z + b * q10, 1.0 + b * q11, a * -x + b * q12),
        (a * -y + b * q20, a * x + b * q21, 1.0 + b * q22),
    )
    J = (
        (1.0 + c * q00, -b * -z + c * q01, -b * y + c * q02),
        (-b * z + c * q10, 1.0 + c * q11, -b * -x + c * q12),
        (-b * -y + c * q20, -b * x + c * q21, 1.0 + c * q22),
    )
    return np.array(R), np.array(J)


class _SampsonProblem:
    r"""Sampson residuals over the rank-2 parameterisation used by :func:`fundamental_sampson`.

    :math:`F = U_0 R(\omega_1)\,\mathrm{diag}(1, \sigma, 0)\,R(\omega_2)^T V_0^T`, ``p = (w1, w2, sigma)``,
    in Hartley-normalised coordinates; the residuals are pixel Sampson distances
    (see :func:`~egtviz.geometry.error_metrics.sampson_distances_normalized`), optionally weighted.
    """

    def __init__(
        self, Fn0: np.ndarray, At: np.ndarray, s1: float, s2: float, weights: np.ndarray | None = None
    ) -> None:
        # LAPACK's divide-and-conquer SVD directly (numpy.linalg.svd's routine, the same numbers): its wrapper
        # costs more than the 3x3 decomposition.
        U0, S, V0t, info = _lapack.dgesdd(Fn0)
        if info != 0:  # pragma: no cover - LAPACK failure
            U0, S, V0t = np.linalg.svd(Fn0)
        self.sw = None if weights is None else np.sqrt(weights)
        self.U0, self.V0t = U0, V0t
        self.p0 = np.zeros(7)
        self.p0[6] = S[1] / S[0]
        self.At = At
        self.h1 = At[6:9]  # m1 as rows (3, N)
        self.h2 = At[2::3]  # m2 as rows (3, N); each row contiguous, as BLAS needs
        self.q1, self.q2 = s1 * s1, s2 * s2
        self._key: bytes | None = None
        self._jkey: bytes | None = None
        self._jac = np.empty((0, 7))

    def F(self, p: np.ndarray) -> np.ndarray:
        return self._eval(p)[0]

    def _eval(self, p: np.ndarray):
        key = p.tobytes()
        if key != self._key:
            R1, J1 = _rodrigues_jr(p[:3])
            R2, J2 = _rodrigues_jr(p[3:6])
            L = self.U0 @ R1
            Rt = R2.T @ self.V0t
            F = (L[:, :2] * np.array([1.0, p[6]])) @ Rt[:2]
            l2 = F[:2] @ self.h1  # (F m1)_{1,2}: lines in image 2, (2, N)
            l1 = F[:, :2].T @ self.h2  # (F^T m2)_{1,2}: lines in image 1
            e = F.ravel() @ self.At
            den = self.q2 * (l2[0] ** 2 + l2[1] ** 2) + self.q1 * (l1[0] ** 2 + l1[1] ** 2)
            np.maximum(den, 1e-300, out=den)
            self._cache = (F, l1, l2, e, den, L, Rt, J1, J2)
            self._key = key
        return self._cache

    def residuals(self, p: np.ndarray) -> np.ndarray:
        e, den = self._eval(p)[3:5]
        r = e / np.sqrt(den)
        return r if self.sw is None else r * self.sw

    def jacobian(self, p: np.ndarray) -> np.ndarray:
        # leastsq evaluates the Jacobian at the start once to check its shape, then again to iterate.
        key = p.tobytes()
        if key == self._jkey:
            return self._jac
        dF, D = self._jacobian_factors(p)
        self._jkey, self._jac = key, (dF @ D).T
        return self._jac

    def normal_equations(self, p: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(J^T J, J^T r)`` at ``p`` from the factors ``J = (dF D)^T``, without the ``(N, 7)`` Jacobian itself."""
        dF, D = self._jacobian_factors(p)
        return dF @ (D @ D.T) @ dF.T, dF @ (D @ r)

    def _jacobian_factors(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(dF, D)``, ``(7, 9)`` and ``(9, N)``: the Jacobian of the residuals is ``(dF @ D).T``."""
        _, l1, l2, e, den, L, Rt, J1, J2 = self._eval(p)
        dF = np.empty((7, 3, 3))
        S = np.diag([1.0, p[6], 0.0])
        dF[0:3] = L @ _skew_stack(J1.T) @ (S @ Rt)
        dF[3:6] = -((L @ S) @ _skew_stack(J2.T) @ Rt)
        dF[6] = np.outer(L[:, 1], Rt[1])
        # r = e / sqrt(den) with e = m2^T F m1 and den = q2 |(F m1)_{1,2}|^2 + q1 |(F^T m2)_{1,2}|^2 is a function
        # of F: dr/dF_ij = m2_i m1_j / sqrt(den) - e / den^1.5 (q2 (F m1)_i m1_j [i < 2] + q1 (F^T m2)_j m2_i [j < 2]),
        # the (9, N) array D; each of the seven directions dF_k gives the row dF_k . D of the Jacobian.
        N = e.shape[0]
        rs = 1.0 / np.sqrt(den)
        g = e * rs / den
        D = np.multiply(self.At, rs)
        Dv = D.reshape(3, 3, N)
        Dv[:2] -= (l2 * (self.q2 * g))[:, None, :] * self.h1[None]
        Dv[:, :2] -= self.h2[:, None, :] * (l1 * (self.q1 * g))[None]
        if self.sw is not None:
            D *= self.sw
        return dF.reshape(7, 9), D


def refine_sampson(
    Fn0: np.ndarray,
    At: np.ndarray,
    s1: float,
    s2: float,
    weights: np.ndarray | None = None,
    tol: float = 1e-10,
) -> np.ndarray:
    r"""Minimise the (weighted) pixel Sampson distance over rank-2 ``F`` in normalised coordinates (H&Z 11.4.3).

    Args:
        Fn0: (3, 3) rank-2 start in normalised coordinates, unit Frobenius norm.
        At: (9, N) design matrix of the normalised points
            (:func:`~egtviz.geometry.fundamental.normalized_design`).
        s1, s2: the normalisations' scales, so that the residuals are pixel distances.
        weights: optional (N,) non-negative weights of the squared residuals.
        tol: relative tolerance (``ftol`` and ``xtol``) of the Levenberg-Marquardt iteration.

    Returns:
        The refined ``F`` (unit Frobenius norm); ``Fn0`` itself if the minimisation raised the cost
        or gave a non-finite matrix.
    """
    prob = _SampsonProblem(Fn0, At, s1, s2, weights)
    r0 = prob.residuals(prob.p0)
    cost0 = float(r0 @ r0)
    # MINPACK's lmder through scipy.optimize.leastsq: the iteration of least_squares(method="lm") (same
    # call, same factor and scaling), without its wrappers and its extra Jacobian at the solution.
    x, _, info, _, _ = leastsq(
        prob.residuals, prob.p0, Dfun=prob.jacobian, full_output=True, ftol=tol, xtol=tol, gtol=1e-12, maxfev=50
    )
    F = prob.F(x)
    fvec = info["fvec"]
    if not (np.all(np.isfinite(F)) and float(fvec @ fvec) <= cost0):
        return Fn0
    return F / np.linalg.norm(F)


def polish_sampson(Fn0: np.ndarray, At: np.ndarray, s1: float, s2: float, *, max_steps: int = 3,
                   tol: float = 1e-3) -> np.ndarray:
    r"""Minimise the pixel Sampson distance over rank-2 ``F`` from a close start by Gauss-Newton steps (H&Z 11.4.3,
    the parameterisation of :func:`refine_sampson`, unweighted).

    Each step solves the normal equations :math:`(J^T J)\,\delta = -J^T r` (with the diagonal raised by
    :math:`10^{-9}` of itself: the parameterisation has a gauge direction when the two singular values are
    equal) and halves the step, at most four times, until the cost falls. It stops after ``max_steps`` steps,
    when the cost falls by at most ``tol`` of itself, or when no step lowers it. From a start near the minimum
    (a robust estimator's locally refitted model) it reaches the minimum that Levenberg-Marquardt reaches, to
    the tolerance, without MINPACK's per-call cost.

    Args:
        Fn0: (3, 3) rank-2 start in normalised coordinates, unit Frobenius norm.
        At: (9, N) design matrix of the normalised points, ``N >= 8``.
        s1, s2: the normalisations' scales, so that the residuals are pixel distances.
        max_steps: at most this many accepted steps.
        tol: relative fall of the cost below which the iteration stops.

    Returns:
        The refined ``F`` (unit Frobenius norm); ``Fn0`` itself when no step lowered the cost.
    """
    prob = _SampsonProblem(Fn0, At, s1, s2)
    p = prob.p0
    r = prob.residuals(p)
    cost = float(r @ r)
    moved = False
    for _ in range(max_steps):
        H, g = prob.normal_equations(p, r)
        H[_DIAGONAL_7] *= 1.0 + 1e-9
        # LAPACK's LU solve directly (numpy.linalg.solve's routine): its wrapper costs more than the 7x7 system.
        delta, info = _lapack.dgesv(H, -g)[2:]
        if info != 0:  # singular
            break
        for _halving in range(4):
            p_new = p + delta
            r_new = prob.residuals(p_new)
            cost_new = float(r_new @ r_new)
            if cost_new < cost:
                break
            delta *= 0.5
        else:
            break
        small = cost - cost_new <= tol * cost
        p, r, cost, moved = p_new, r_new, cost_new, True
        if small:
            break
    F = prob.F(p)
    if not (moved and np.all(np.isfinite(F))):
        return Fn0
    f = F.ravel()
    return F / math.sqrt(f.dot(f))  # np.linalg.norm's arithmetic without its wrapper


_DIAGONAL_7 = np.diag_indices(7)


def fundamental_sampson(
    U1: npt.ArrayLike, U2: npt.ArrayLike, F0: npt.ArrayLike | None = None
) -> np.ndarray:
    r"""Iterative minimisation of the Sampson distance (H&Z 2nd ed., section 11.4.3).

    Minimises the first-order geometric error (H&Z eq. 11.9)

    .. math:: \sum_i \frac{(m_{2i}^T F m_{1i})^2}
              {(F m_{1i})_1^2 + (F m_{1i})_2^2 + (F^T m_{2i})_1^2 + (F^T m_{2i})_2^2}

    with MINPACK's Levenberg-Marquardt (``scipy.optimize.leastsq``, analytic
    Jacobian) over a minimal rank-2 parameterisation: in Hartley-normalised
    coordinates :math:`F = U R(\omega_1)\,\mathrm{diag}(1, \sigma, 0)\,R(\omega_2)^T V^T`
    (7 parameters, H&Z section 11.4.2). The result is exactly rank 2 and its
    Sampson cost never exceeds that of the start.

    Args:
        U1: ``(N, 2)`` pixels in image 1, ``N >= 8``.
        U2: ``(N, 2)`` corresponding pixels in image 2.
        F0: optional ``(3, 3)`` starting estimate (projected to rank 2);
            default :func:`fundamental_normalized_8point`.

    Returns:
        ``(3, 3)`` ``F``, rank 2, unit Frobenius norm, largest entry positive.

    Raises:
        GeometryError: bad shapes, NaN/inf, ``N < 8``, mismatched ``N``, or a
            rank < 2 ``F0``.
        DegenerateConfigurationError: coincident points or rank-deficient data.
    """
    u1, u2 = point_pairs(U1, U2, 8)
    At, T1, T2 = normalized_design(u1, u2)
    if F0 is None:
        Fn0 = nearest_rank2(null_vector(At).reshape(3, 3), check=False)
    else:
        F0 = as_up_to_scale(F0, "F0", (3, 3))
        Fn0 = np.linalg.inv(T2).T @ F0 @ np.linalg.inv(T1)
        sv = np.linalg.svd(Fn0, compute_uv=False)
        if sv[1] <= 1e-12 * sv[0]:
            raise GeometryError("F0: expected a matrix of rank 2, got rank < 2")
        Fn0 = nearest_rank2(Fn0, check=False)
    Fn0 = Fn0 / np.linalg.norm(Fn0)
    return canonical_fundamental(T2.T @ refine_sampson(Fn0, At, T1[0, 0], T2[0, 0]) @ T1)
