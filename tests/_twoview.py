"""Synthetic two-view scenes for the estimation tests (after kornia's ``generate_two_view_random_scene``).

Two pin-hole cameras with ``f ~ 800`` px, 640 x 480 images, a baseline of
about 1 m and a non-trivial rotation; scene points 4-10 m in front of both
cameras and inside both images. Camera 1 is the world frame, and
``X_c2 = R X_c1 + t``. The true ``F = K2^-T [t]_x R K1^-1`` is computed here
from the fixture's own ``R``, ``t``, ``K``; it does not use the code under test.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

WIDTH, HEIGHT = 640.0, 480.0


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _rotvec(w: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(w)
    if th < 1e-15:
        return np.eye(3)
    k = _skew(w / th)
    return np.eye(3) + np.sin(th) * k + (1 - np.cos(th)) * k @ k


def unit_sign(F: np.ndarray) -> np.ndarray:
    """Scale to unit Frobenius norm with the largest-magnitude entry positive."""
    F = F / np.linalg.norm(F)
    return F if F.flat[np.argmax(np.abs(F))] > 0 else -F


@dataclass(frozen=True)
class TwoView:
    K1: np.ndarray
    K2: np.ndarray
    R: np.ndarray
    t: np.ndarray
    X: np.ndarray  # (N, 3) in camera-1 (world) frame
    U1_true: np.ndarray
    U2_true: np.ndarray
    U1: np.ndarray  # noisy, with outliers
    U2: np.ndarray
    inliers: np.ndarray  # (N,) bool, False for the outliers
    F: np.ndarray  # true F, unit norm, sign-normalised
    E: np.ndarray  # [t]_x R

    @property
    def P1(self) -> np.ndarray:
        return self.K1 @ np.hstack([np.eye(3), np.zeros((3, 1))])

    @property
    def P2(self) -> np.ndarray:
        return self.K2 @ np.hstack([self.R, self.t[:, None]])


def _project(K: np.ndarray, Xc: np.ndarray) -> np.ndarray:
    x = Xc @ K.T
    return x[:, :2] / x[:, 2:]


def _in_image(u: np.ndarray) -> np.ndarray:
    return (u[:, 0] > 0) & (u[:, 0] < WIDTH) & (u[:, 1] > 0) & (u[:, 1] < HEIGHT)


def make_two_view(
    rng: np.random.Generator,
    n: int,
    *,
    noise: float = 0.0,
    outlier_ratio: float = 0.0,
    min_outlier_px: float = 4.0,
) -> TwoView:
    """A random two-view scene with ``n`` correspondences.

    Args:
        rng: the generator (pass ``np.random.default_rng(seed)``).
        n: number of correspondences.
        noise: standard deviation (pixels) of the Gaussian noise on every coordinate.
        outlier_ratio: fraction of correspondences replaced by random pixel pairs
            whose true Sampson distance exceeds ``min_outlier_px``.
    """
    f1, f2 = rng.uniform(760, 840, 2)
    K1 = np.array([[f1, 0.0, 320.0 + rng.uniform(-10, 10)], [0.0, f1 * rng.uniform(0.98, 1.02), 240.0], [0, 0, 1]])
    K2 = np.array([[f2, 0.0, 320.0], [0.0, f2, 240.0 + rng.uniform(-10, 10)], [0, 0, 1]])
    # Camera 2's centre in camera-1 coordinates: about 1 m, mostly sideways.
    d = np.array([rng.choice([-1.0, 1.0]), rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3)])
    C2 = d / np.linalg.norm(d) * rng.uniform(0.8, 1.2)
    # Converge on the scene centre (7 m ahead), plus a random tilt and roll.
    yaw = np.arctan2(C2[0], 7.0)  # rotation of camera 2 about y towards the scene
    w = np.array([rng.uniform(-0.08, 0.08), yaw + rng.uniform(-0.05, 0.05), rng.uniform(-0.1, 0.1)])
    R_c2_to_c1 = _rotvec(w)
    R = R_c2_to_c1.T
    t = -R @ C2
    pts = []
    count = 0
    while count < n:
        m = 2 * (n - count) + 16
        uv = rng.uniform([0, 0], [WIDTH, HEIGHT], (m, 2))
        z = rng.uniform(4.0, 10.0, m)
        X = (np.c_[uv, np.ones(m)] @ np.linalg.inv(K1).T) * z[:, None]
        X2 = X @ R.T + t
        ok = (X2[:, 2] > 1.0) & _in_image(_project(K2, X2))
        pts.append(X[ok])
        count += int(ok.sum())
    X = np.concatenate(pts)[:n]
    U1t = _project(K1, X)
    U2t = _project(K2, X @ R.T + t)
    E = _skew(t) @ R
    F = unit_sign(np.linalg.inv(K2).T @ E @ np.linalg.inv(K1))
    U1 = U1t + rng.normal(0.0, noise, U1t.shape) if noise > 0 else U1t.copy()
    U2 = U2t + rng.normal(0.0, noise, U2t.shape) if noise > 0 else U2t.copy()
    inl = np.ones(n, bool)
    n_out = int(round(outlier_ratio * n))
    if n_out:
        idx = rng.choice(n, n_out, replace=False)
        inl[idx] = False
        todo = idx
        while todo.size:
            U1[todo] = rng.uniform([0, 0], [WIDTH, HEIGHT], (todo.size, 2))
            U2[todo] = rng.uniform([0, 0], [WIDTH, HEIGHT], (todo.size, 2))
            todo = todo[true_sampson(F, U1[todo], U2[todo]) < min_outlier_px**2]
    return TwoView(K1, K2, R, t, X, U1t, U2t, U1, U2, inl, F, E)


def true_sampson(F: np.ndarray, U1: np.ndarray, U2: np.ndarray) -> np.ndarray:
    """Independent squared Sampson distance (reference implementation for the tests)."""
    h1 = np.c_[U1, np.ones(len(U1))]
    h2 = np.c_[U2, np.ones(len(U2))]
    Fx1 = h1 @ F.T
    Ftx2 = h2 @ F
    e = np.sum(h2 * Fx1, axis=1)
    return e**2 / (Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2 + Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2)


def true_symmetric(F: np.ndarray, U1: np.ndarray, U2: np.ndarray) -> np.ndarray:
    """Independent squared symmetric epipolar distance."""
    h1 = np.c_[U1, np.ones(len(U1))]
    h2 = np.c_[U2, np.ones(len(U2))]
    Fx1 = h1 @ F.T
    Ftx2 = h2 @ F
    e = np.sum(h2 * Fx1, axis=1)
    return e**2 * (1 / (Fx1[:, 0] ** 2 + Fx1[:, 1] ** 2) + 1 / (Ftx2[:, 0] ** 2 + Ftx2[:, 1] ** 2))


def f_distance(Fa: np.ndarray, Fb: np.ndarray) -> float:
    """Distance between two F's up to scale and sign."""
    a = Fa / np.linalg.norm(Fa)
    b = Fb / np.linalg.norm(Fb)
    return float(min(np.linalg.norm(a - b), np.linalg.norm(a + b)))


def transfer_error(F_est: np.ndarray, scene: TwoView) -> float:
    """Mean symmetric epipolar distance (pixels) of the estimate on the noise-free true inliers."""
    m = scene.inliers
    return float(np.mean(np.sqrt(true_symmetric(F_est, scene.U1_true[m], scene.U2_true[m]))))
