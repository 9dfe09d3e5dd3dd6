r"""Panoramic camera on a holonomic mobile robot: the auto-epipolar servo (EGT reference, section 7).

The robot's state is :math:`(x, y, \theta)` and its inputs are the body-frame
velocities :math:`(v_x, v_y, \omega)`. A central catadioptric camera (hyperbolic
mirror, axis vertical, focus :data:`CAMERA_HEIGHT` above the ground) rides on it,
its mirror frame equal to the robot frame. Only the image drives the controller:
current and desired pixels are back-projected to unit rays :math:`d_i`,
:math:`d^*_i` in the mirror frame (the camera's model, not its pose).

**Bi-conics.** For each pair, the *bi-conic* is the image of the plane through
the focus containing both rays (:func:`egtviz.geometry.panoramic_epipolar.biconic`),
with normal :math:`n_i = d_i \times d^*_i`. If the two views had the same
orientation, every such plane would contain the baseline: all bi-conics would meet
in the same two points (the epipoles) and the stack :math:`N = [n_1; \dots; n_N]`
would have rank 2. Its smallest eigenvalue
:math:`\sigma(\alpha) = \lambda_{\min}(\sum_i n_i(\alpha) n_i(\alpha)^T)`, with the
desired rays turned by :math:`\alpha` about the axis,
:math:`n_i(\alpha) = d_i \times R_z(\alpha) d^*_i`, is an image-only measure of the
orientation disagreement; it vanishes at :math:`\alpha = \theta^* - \theta`.

**Step 1** (rotation): :math:`\hat\alpha = \arg\min_\alpha \sigma(\alpha)` (a
vectorised grid search refined around its minimum) and
:math:`\omega = k_\omega \hat\alpha`, :math:`v = 0`, until
:math:`|\hat\alpha|` is below ``switch_rad``.

**Step 2** (translation): while the rays still show parallax (mean angle above
``freeze_angle``) the baseline is the common line of the planes, the
eigenvector :math:`b` of :math:`\lambda_{\min}` at :math:`\hat\alpha`; its sign is
chosen so that the scene points lie in front of both views (cheirality vote). The
robot translates along it, :math:`(v_x, v_y) = k_v\, s_\angle(t)\, b_{xy}`, with
:math:`s_\angle` the mean angle between the current and (derotated) desired rays,
while :math:`\omega = k_\omega \hat\alpha` keeps the orientation. The run ends when
the feature distance :math:`s(t)` (mean pixel distance between current and
desired features) is below ``stop_px``. Closer than that, the planes' common
line drowns in the image noise, so the last centimetres follow the ray-alignment
gradient :math:`-\sum_i (I - d_i d_i^T)(d_i - \tilde d^*_i)` instead (it points
along the baseline too, and averages the noise out).
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry.mirrors import HyperbolicMirror
from egtviz.geometry.panoramic_epipolar import biconic
from egtviz.geometry.poses import Pose, rotz

from .result import Recorder, ServoResult
from .settings import NoiseDefaults, run_summary

__all__ = [
    "CAMERA_HEIGHT",
    "default_camera",
    "default_scene",
    "draw_start_state",
    "mirror_pose",
    "rotation_measure",
    "estimate_rotation",
    "baseline_direction",
    "control_law",
    "step_state",
    "PanoramicSettings",
    "PanoramicScene",
    "panoramic_errors",
    "observe_panoramic",
    "panoramic_recorder",
    "record_panoramic_state",
    "record_panoramic_control",
    "simulate_panoramic",
]

#: Height of the mirror focus above the ground, metres.
CAMERA_HEIGHT = 0.5


def default_camera() -> CatadioptricCamera:
    """EGT's default hyperbolic mirror (a = 3, b = 1) scaled to a robot: a = 3 cm, b = 1 cm, rim 2 cm.

    The CCD (f = 1100 px) images the rim as a circle of about 223 px around (320, 240),
    so the whole mirror fits the 640 x 480 image. Field of view: from straight down
    to about 60 degrees above the horizon. The pose is the identity: this is the
    controller's model of the camera (rays come out in the mirror frame).
    """
    K = np.array([[1100.0, 0.0, 320.0], [0.0, 1100.0, 240.0], [0.0, 0.0, 1.0]])
    return CatadioptricCamera(Pose(), HyperbolicMirror(0.03, 0.01), K, 640, 480)


def default_scene(n_points: int = 10) -> np.ndarray:
    """(n, 3) world points on a ring 4.5-6 m around the target, 0-2.5 m high (fixed generator).

    The spread in height matters: the rotation about the vertical axis is seen by
    the bi-conics through the rays' elevations.
    """
    rng = np.random.default_rng(10_000)
    ang = rng.uniform(-np.pi, np.pi, n_points)
    r = rng.uniform(4.5, 6.0, n_points)
    z = rng.uniform(0.0, 2.5, n_points)
    return np.column_stack([r * np.cos(ang), r * np.sin(ang), z])


def mirror_pose(state: Iterable[float]) -> Pose:
    r"""Mirror frame of the robot at ``(x, y, theta)``: :math:`R_z(\theta)`, focus at ``(x, y, CAMERA_HEIGHT)``."""
    x, y, th = (float(v) for v in state)
    c, s = math.cos(th), math.sin(th)
    return Pose(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]), [x, y, CAMERA_HEIGHT])


def draw_start_state(
    rng: np.random.Generator,
    target: Iterable[float] = (0.0, 0.0, 0.0),
    heading_range: tuple[float, float] = (np.radians(30.0), np.radians(120.0)),
    distance_range: tuple[float, float] = (1.0, 3.0),
) -> np.ndarray:
    """Start ``(x, y, theta)``: heading ``heading_range`` off (either sign), ``distance_range`` away in a random direction."""
    tx, ty, tth = (float(v) for v in target)
    dth = rng.uniform(*heading_range) * rng.choice([-1.0, 1.0])
    d = rng.uniform(*distance_range)
    phi = rng.uniform(-np.pi, np.pi)
    return np.array([tx + d * math.cos(phi), ty + d * math.sin(phi), _wrap(tth + dth)])


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


# ---------------------------------------------------------------- control law (pure functions)
def _scatter_coefficients(d: np.ndarray, d_star: np.ndarray) -> np.ndarray:
    r"""Coefficients (6, 3, 3) of :math:`\sum_i n_i n_i^T` as a quadratic form in :math:`(\cos\alpha, \sin\alpha, 1)`.

    :math:`R_z(\alpha) d^* = \cos\alpha\,(x^*, y^*, 0) + \sin\alpha\,(-y^*, x^*, 0) + (0, 0, z^*)`, so
    :math:`n_i = d_i \times R_z(\alpha) d^*_i = \cos\alpha\,A_i + \sin\alpha\,B_i + C_i` and the scatter is
    :math:`c^2 AA + s^2 BB + CC + cs(AB + BA) + c(AC + CA) + s(BC + CB)`: computed once per step,
    then evaluated at any number of trial angles without touching the N rays again.
    """
    # The three cross products written out: np.cross costs more than the arithmetic here.
    dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
    x, y, z = d_star[:, 0], d_star[:, 1], d_star[:, 2]
    A = np.column_stack([-dz * y, dz * x, dx * y - dy * x])  # d x (x*, y*, 0)
    B = np.column_stack([-dz * x, -dz * y, dx * x + dy * y])  # d x (-y*, x*, 0)
    C = np.column_stack([dy * z, -dx * z, np.zeros_like(z)])  # d x (0, 0, z*)
    AB, AC, BC = A.T @ B, A.T @ C, B.T @ C
    return np.stack([A.T @ A, B.T @ B, C.T @ C, AB + AB.T, AC + AC.T, BC + BC.T])


def _scatter_at(coefficients: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """The scatter matrices (A, 3, 3) at trial angles ``alpha`` (A,)."""
    c, s = np.cos(alpha), np.sin(alpha)
    w = np.stack([c * c, s * s, np.ones_like(c), c * s, c, s], axis=1)
    return np.tensordot(w, coefficients, axes=1)


def _normal_scatter(d: np.ndarray, d_star: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    r""":math:`\sum_i n_i n_i^T` (A, 3, 3) with :math:`n_i = d_i \times R_z(\alpha) d^*_i`."""
    return _scatter_at(_scatter_coefficients(d, d_star), alpha)


def _min_eig_sym3(M: np.ndarray) -> np.ndarray:
    """Smallest eigenvalue of symmetric 3x3 matrices (A, 3, 3), closed form (Smith 1961), vectorised."""
    a00, a11, a22 = M[:, 0, 0], M[:, 1, 1], M[:, 2, 2]
    a01, a02, a12 = M[:, 0, 1], M[:, 0, 2], M[:, 1, 2]
    q = (a00 + a11 + a22) / 3.0
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p = np.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1) / 6.0)
    ps = np.where(p > 0, p, 1.0)
    det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02)
    r = np.clip(det / (2.0 * ps**3), -1.0, 1.0)
    phi = np.arccos(r) / 3.0
    return np.where(p > 0, q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0), q)


def rotation_measure(d: np.ndarray, d_star: np.ndarray, alpha: npt.ArrayLike = 0.0) -> np.ndarray:
    r"""The bi-conic measure :math:`\sigma(\alpha) = \lambda_{\min}(\sum_i n_i n_i^T)`; zero when the orientations agree.

    Args:
        d: (N, 3) current unit rays (mirror frame).
        d_star: (N, 3) desired unit rays (desired mirror frame).
        alpha: trial rotation(s) of the desired rays about the mirror axis.
    """
    a = np.atleast_1d(np.asarray(alpha, dtype=float))
    out = _min_eig_sym3(_normal_scatter(d, d_star, a))
    return out if np.ndim(alpha) else out[:1].reshape(())


def estimate_rotation(
    d: np.ndarray, d_star: np.ndarray, n_grid: int = 180, refine: int = 3, near: float | None = None
) -> float:
    r"""The orientation offset :math:`\hat\alpha = \arg\min \sigma(\alpha)` in :math:`(-\pi, \pi]`: the desired
    frame turned by :math:`\hat\alpha` about the axis has the current orientation (:math:`\hat\alpha = \theta^* - \theta`).

    A grid of ``n_grid`` angles (or 21 angles within 0.2 rad of ``near``, the previous
    step's estimate, once the robot turns slowly), then ``refine`` rounds of a 21-point grid shrinking
    around the best, then a parabola through the last three samples.
    """
    if near is None:
        alpha = np.linspace(-np.pi, np.pi, n_grid, endpoint=False)
        half = 2.0 * np.pi / n_grid
    else:  # warm start: a local grid of +-0.2 rad around the previous estimate
        alpha = near + np.linspace(-0.2, 0.2, 21)
        half = 0.02
    coefficients = _scatter_coefficients(d, d_star)

    def measure(angles: np.ndarray) -> np.ndarray:
        return _min_eig_sym3(_scatter_at(coefficients, angles))

    f = measure(alpha)
    best = float(alpha[int(np.argmin(f))])
    for _ in range(refine):
        a = best + np.linspace(-half, half, 21)
        f = measure(a)
        i = int(np.argmin(f))
        best = float(a[i])
        half = 2.0 * half / 20.0
    a = best + np.array([-half, 0.0, half])
    f = measure(a)
    den = f[0] - 2.0 * f[1] + f[2]
    if den > 0:
        best += 0.5 * half * (f[0] - f[2]) / den
    return _wrap(best)


def baseline_direction(d: np.ndarray, d_star_aligned: np.ndarray) -> np.ndarray | None:
    r"""Unit baseline (current focus to desired focus, current frame): the common line of the bi-conic planes.

    :math:`b` is the eigenvector of the smallest eigenvalue of :math:`\sum n_i n_i^T`
    (:math:`n_i = d_i \times \tilde d^*_i`, desired rays already derotated); its sign
    makes the points lie in front of both views: :math:`\rho d_i = s b + \rho^* \tilde d^*_i`
    with :math:`\rho^* > 0` gives :math:`s\,(d_i \times b)\cdot(d_i \times \tilde d^*_i) < 0`.
    ``None`` when the rays all coincide (the views coincide).
    """
    n = np.cross(d, d_star_aligned)
    M = n.T @ n
    if np.trace(M) < 1e-24:
        return None
    w, v = np.linalg.eigh(M)
    b = v[:, 0]
    vote = float(np.einsum("ij,ij->", np.cross(d, b[None, :]), n))
    return -b if vote > 0 else b


def control_law(
    d: np.ndarray,
    d_star: np.ndarray,
    *,
    phase: int,
    k_omega: float,
    k_v: float,
    switch_rad: float,
    freeze_angle: float = 0.02,
    alpha_prev: float | None = None,
) -> tuple[np.ndarray, int, dict[str, float]]:
    r"""One step of the two-phase law from the image rays only (a pure function of ``d`` and ``d_star``).

    With :math:`\hat\alpha = \arg\min_\alpha \sigma(\alpha)` (:func:`estimate_rotation`),
    :math:`\tilde d^*_i = R_z(\hat\alpha) d^*_i` and the mean ray angle
    :math:`s_\angle = \frac1N \sum_i \arccos(d_i \cdot \tilde d^*_i)`:

    .. math::
       \text{step 1: } u = (0, 0, k_\omega \hat\alpha), \qquad
       \text{step 2: } u = (k_v\, s_\angle\, b_{xy} / \lVert b_{xy} \rVert,\ k_\omega \hat\alpha),

    with :math:`b` the common line of the bi-conic planes (:func:`baseline_direction`); step 2 starts once
    :math:`|\hat\alpha| <` ``switch_rad``. In step 2 the rotation is only corrected while
    :math:`s_\angle >` ``freeze_angle``: with little parallax every plane through the (short) baseline fits
    and the orientation is no longer observable from the bi-conics. There (:math:`\omega = 0`,
    :math:`\tilde d^* = d^*`) the translation follows the ray-alignment gradient,
    :math:`(v_x, v_y) = \frac{2 k_v}{N} \sum_i [(I - d_i d_i^T)(d_i - \tilde d^*_i)]_{xy}`.

    Returns:
        ``(u, phase, info)``: ``u = (v_x, v_y, omega)`` in the robot frame, the (possibly advanced) phase 1
        or 2, and the measures ``alpha_hat`` (:math:`\hat\alpha`), ``biconic_measure``
        (:math:`\sigma(0)`) and ``s_angle`` (:math:`s_\angle`).
    """
    alpha = estimate_rotation(d, d_star, near=alpha_prev)
    aligned = d_star @ rotz(alpha).T
    s_angle = float(np.mean(np.arccos(np.clip(np.einsum("ij,ij->i", d, aligned), -1.0, 1.0))))
    if phase == 1 and abs(alpha) < switch_rad:
        phase = 2
    # Near the goal the planes' common line (and with it the rotation measure) is lost in the
    # parallax-free rays: keep the orientation reached and only translate.
    u = np.array([0.0, 0.0, k_omega * alpha if (phase == 1 or s_angle > freeze_angle) else 0.0])
    if phase == 2 and s_angle <= freeze_angle:
        aligned = d_star  # orientation compensated; alpha_hat is no longer observable here
    if phase == 2:
        b = baseline_direction(d, aligned) if s_angle > freeze_angle else None
        if b is not None:
            bxy = b[:2] / max(np.linalg.norm(b[:2]), 1e-12)
            u[:2] = k_v * s_angle * bxy
        else:
            # Close to the goal: the ray-alignment gradient (spherical IBVS with equal depths),
            # +sum_i (I - d_i d_i^T)(d_i - d*_i) (rays move by -(I - d d^T) v / rho); noise averages out instead of turning b around.
            diff = d - aligned
            g = diff - d * np.einsum("ij,ij->i", d, diff)[:, None]
            u[:2] = 2.0 * k_v * g[:, :2].mean(axis=0)
    info = {"alpha_hat": alpha, "biconic_measure": float(rotation_measure(d, d_star)), "s_angle": s_angle}
    return u, phase, info


def step_state(state: np.ndarray, u: np.ndarray, dt: float) -> np.ndarray:
    r"""State update: body velocities ``u = (v_x, v_y, omega)`` held for ``dt``, integrated exactly on SE(2).

    .. math::
       \begin{pmatrix} x' \\ y' \end{pmatrix} = \begin{pmatrix} x \\ y \end{pmatrix}
       + R(\theta) \begin{pmatrix} a & -b \\ b & a \end{pmatrix}
       \begin{pmatrix} v_x \\ v_y \end{pmatrix} \Delta t, \qquad \theta' = \theta + \omega \Delta t,

    with :math:`a = \sin(\omega\Delta t) / (\omega\Delta t)`, :math:`b = (1 - \cos(\omega\Delta t)) / (\omega\Delta t)`
    (their series near :math:`\omega = 0`) and :math:`\theta'` wrapped to :math:`[-\pi, \pi)`.
    """
    x, y, th = state
    vx, vy, w = u
    wt = w * dt
    if abs(wt) < 1e-9:
        a, b = 1.0 - wt * wt / 6.0, wt / 2.0
    else:
        a, b = math.sin(wt) / wt, (1.0 - math.cos(wt)) / wt
    dx_body = (a * vx - b * vy) * dt
    dy_body = (b * vx + a * vy) * dt
    c, s = math.cos(th), math.sin(th)
    return np.array([x + c * dx_body - s * dy_body, y + s * dx_body + c * dy_body, _wrap(th + wt)])


# ---------------------------------------------------------------- simulation: settings, scene, image
@dataclass(frozen=True)
class PanoramicSettings(NoiseDefaults):
    """The checked settings of one panoramic run: :func:`simulate_panoramic`'s scalar arguments.

    Raises:
        ValueError: on an invalid value (negative noise, a gain or time step not positive, ...).
    """

    seed: int
    """Seed of the start-state draw and of the image noise."""
    noise_px: float
    """Standard deviation of the Gaussian pixel noise."""
    steps: int
    """Maximum number of state updates."""
    dt: float
    """Time step, seconds."""
    k_omega: float
    """Rotation gain :math:`k_\\omega` (1/s)."""
    k_v: float
    """Translation gain :math:`k_v` (m/s per radian of mean ray angle)."""
    switch_rad: float
    """Step 1 ends when :math:`|\\hat\\alpha|` is below this."""
    freeze_angle: float
    """In step 2 the rotation is corrected only while the mean ray angle (rad) exceeds this."""
    stop_px: float | None
    """Early-stop threshold on :math:`s(t)`, or ``None`` for :attr:`stop_threshold_px`'s default."""
    rotation_tol: float | None
    """Convergence tolerance (rad), or ``None`` for the default."""
    translation_tol: float | None
    """Convergence tolerance (m), or ``None`` for the default."""
    conic_every: int
    """Store the bi-conics every this many steps (and at the first and last)."""

    STOP_PX_DEFAULT: ClassVar[float] = 5e-4
    """The default early-stop threshold (pixels) without noise."""

    def __post_init__(self) -> None:
        noise_px, steps = self.noise_px, self.steps
        if not isinstance(noise_px, (int, float)) or not math.isfinite(noise_px) or noise_px < 0:
            raise ValueError(f"noise_px: expected a finite number of pixels >= 0, got {noise_px!r}")
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
            raise ValueError(f"steps: expected a positive integer, got {steps!r}")
        for name in ("dt", "k_omega", "k_v", "switch_rad"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError(f"{name}: expected a positive finite number, got {value!r}")
        every = self.conic_every
        if isinstance(every, bool) or not isinstance(every, (int, np.integer)) or every < 1:
            raise ValueError(f"conic_every: expected a positive integer, got {every!r}")


@dataclass(frozen=True)
class PanoramicScene:
    """The camera model, the scene and the target of a run, with the desired features measured there (once)."""

    camera: CatadioptricCamera
    """The controller's camera model, posed at the identity (rays come out in the mirror frame)."""
    points: np.ndarray
    """(N, 3) world points."""
    target: np.ndarray
    """(3,) target state ``(x, y, theta)``."""
    desired: np.ndarray
    """(N, 2) desired feature pixels (with noise) :math:`m^*_i`."""
    desired_rays: np.ndarray
    """(N, 3) desired unit rays :math:`d^*_i` (desired mirror frame), back-projected from :attr:`desired`."""


def panoramic_errors(state: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    r"""``(rotation, translation)`` errors of ``state``: :math:`|\theta - \theta^*|` wrapped, the x-y distance."""
    return abs(_wrap(state[2] - target[2])), float(np.hypot(state[0] - target[0], state[1] - target[1]))


def observe_panoramic(
    state: np.ndarray, scene: PanoramicScene, noise_px: float, rng: np.random.Generator
) -> tuple[Any, np.ndarray]:
    r"""The robot at ``state`` sees ``(projection, m)``: the camera's projection and the noisy pixels (N, 2).

    The points in the mirror frame are :math:`R_z(\theta)^T (X - (x, y, h))`; the noise (``noise_px``) is
    drawn from ``rng`` only when ``noise_px > 0``.
    """
    X = scene.points
    c_th, s_th = math.cos(state[2]), math.sin(state[2])
    rel = X - np.array([state[0], state[1], CAMERA_HEIGHT])
    local = np.column_stack([c_th * rel[:, 0] + s_th * rel[:, 1], -s_th * rel[:, 0] + c_th * rel[:, 1], rel[:, 2]])
    proj = scene.camera.project_directions(local)  # == cam.moved(mirror_pose(state)).project(X)
    m = proj.pixels + (rng.normal(scale=noise_px, size=(len(X), 2)) if noise_px > 0 else 0.0)
    return proj, m


def _current_rays(scene: PanoramicScene, proj: Any, m: np.ndarray, t: float) -> tuple[np.ndarray | None, str]:
    """The current unit rays of ``m`` (mirror frame), or ``None`` and why the run must stop at time ``t``."""
    if not np.all(proj.in_image):
        i = int(np.flatnonzero(~proj.in_image)[0])
        return None, f"feature {i} left the mirror's field of view at t = {t:.2f} s"
    d = scene.camera.back_project(m)
    if not np.all(np.isfinite(d)):
        return None, f"a feature does not back-project to a mirror ray at t = {t:.2f} s"
    return d, ""


# ---------------------------------------------------------------- simulation: recording
def panoramic_recorder(capacity: int, n_features: int) -> Recorder:
    """NaN-filled buffers for ``capacity`` samples of a run with ``n_features`` features."""
    scalars = ("rot", "trans", "s_px", "s_ang", "alpha", "measure", "phase")
    return Recorder(
        capacity, {"state": (3,), "features": (n_features, 2), "u": (3,), **{name: () for name in scalars}}
    )


def record_panoramic_state(rec: Recorder, k: int, state: np.ndarray, m: np.ndarray, target: np.ndarray) -> None:
    """Store sample ``k``'s state, features and errors (:func:`panoramic_errors`); the sample now counts."""
    b = rec.buffers
    b["state"][k] = state
    b["features"][k] = m
    b["rot"][k], b["trans"][k] = panoramic_errors(state, target)
    rec.count = k + 1


def record_panoramic_control(
    rec: Recorder, k: int, u: np.ndarray, phase: int, info: dict[str, float], m: np.ndarray, desired: np.ndarray
) -> float:
    r"""Store sample ``k``'s control and measures; returns the feature distance :math:`s(t)` in pixels.

    :math:`s(t) = \frac1N \sum_i \lVert m_i - m^*_i \rVert`; the measures are :func:`control_law`'s
    :math:`\hat\alpha`, :math:`\sigma(0)` and :math:`s_\angle`.
    """
    b = rec.buffers
    s_px = float(np.mean(np.linalg.norm(m - desired, axis=1)))
    b["u"][k] = u
    b["s_px"][k] = s_px
    b["s_ang"][k] = info["s_angle"]
    b["alpha"][k] = info["alpha_hat"]
    b["measure"][k] = info["biconic_measure"]
    b["phase"][k] = phase
    return s_px


# ---------------------------------------------------------------- simulation: set-up, loop, result
class _NotRun(Exception):
    """The run cannot start, for the reason given."""


def _panoramic_scene(
    cam: CatadioptricCamera, X: np.ndarray, target: np.ndarray, noise_px: float, rng: np.random.Generator
) -> PanoramicScene:
    """The scene, with the desired features measured once (with noise) at ``target``.

    Raises:
        _NotRun: too few features, or one unseen at the target.
    """
    n_feat = len(X)
    cam0 = cam.moved(Pose())
    if n_feat < 4:
        raise _NotRun(f"the bi-conic test needs at least 4 features, got {n_feat}")
    goal_proj = cam.moved(mirror_pose(target)).project(X)
    if not np.all(goal_proj.in_image):
        i = int(np.flatnonzero(~goal_proj.in_image)[0])
        raise _NotRun(f"feature {i} is outside the mirror's field of view at the target")
    m_des = goal_proj.pixels + (rng.normal(scale=noise_px, size=(n_feat, 2)) if noise_px > 0 else 0.0)
    d_star = cam0.back_project(m_des)
    if not np.all(np.isfinite(d_star)):
        raise _NotRun("a desired feature does not back-project to a ray of the mirror")
    return PanoramicScene(cam0, X, target, m_des, d_star)


def _panoramic_params(s: PanoramicSettings, cam: CatadioptricCamera, target: np.ndarray) -> dict[str, Any]:
    return {
        "seed": s.seed, "noise_px": float(s.noise_px), "dt": float(s.dt), "max_steps": int(s.steps),
        "k_omega": float(s.k_omega), "k_v": float(s.k_v), "switch_rad": float(s.switch_rad),
        "freeze_angle": float(s.freeze_angle), "stop_px": s.stop_threshold_px, "rotation_tol": s.rotation_tolerance,
        "translation_tol": s.translation_tolerance, "K": np.asarray(cam.K).tolist(),
        "mirror": {"kind": cam.mirror.kind, "a": getattr(cam.mirror, "a", None), "b": getattr(cam.mirror, "b", None)},
        "camera_height": CAMERA_HEIGHT, "target": target.tolist(),
    }


@dataclass(frozen=True)
class _PanoramicRun:
    data: dict[str, np.ndarray]
    steps: int
    reason: str
    phase: int
    conics: list[np.ndarray]
    conic_steps: list[int]


def _panoramic_loop(
    s: PanoramicSettings, scene: PanoramicScene, state: np.ndarray, rng: np.random.Generator,
    progress: Callable[[int, int], None] | None,
) -> _PanoramicRun:
    """Image, control law, record, state update, until the features are lost, the goal or the last step."""
    rec = panoramic_recorder(s.steps + 1, len(scene.points))
    conics: list[np.ndarray] = []
    conic_steps: list[int] = []
    phase, alpha_prev, k = 1, None, 0
    while True:
        proj, m = observe_panoramic(state, scene, s.noise_px, rng)
        record_panoramic_state(rec, k, state, m, scene.target)
        d, reason = _current_rays(scene, proj, m, k * s.dt)
        if d is None:
            break
        u, phase, info = control_law(
            d, scene.desired_rays, phase=phase, k_omega=s.k_omega, k_v=s.k_v, switch_rad=s.switch_rad,
            freeze_angle=s.freeze_angle, alpha_prev=alpha_prev,
        )
        # warm start the next search once the turn per step is small (the global grid otherwise)
        alpha_prev = info["alpha_hat"] if abs(u[2]) * s.dt < 0.05 else None
        s_px = record_panoramic_control(rec, k, u, phase, info, m, scene.desired)
        done = phase == 2 and s.stop_threshold_px > 0 and s_px < s.stop_threshold_px
        if k % s.conic_every == 0 or done or k >= s.steps:
            conics.append(biconic(scene.camera, d, scene.desired_rays))
            conic_steps.append(k)
        if done or k >= s.steps:
            break
        state = step_state(state, u, s.dt)
        k += 1
        if progress is not None and k % 50 == 0:
            progress(k, s.steps)
    if progress is not None:
        progress(k, s.steps)
    return _PanoramicRun(rec.trim(), k, reason, phase, conics, conic_steps)


def _panoramic_result(
    s: PanoramicSettings, scene: PanoramicScene, run: _PanoramicRun, params: dict[str, Any], wall0: float
) -> ServoResult:
    data, k = run.data, run.steps
    rot, trans = data["rot"], data["trans"]
    final_rot, final_trans = float(rot[-1]), float(trans[-1])
    rot_tol, trans_tol = s.rotation_tolerance, s.translation_tolerance
    reason = run.reason
    if not reason and (final_rot >= rot_tol or final_trans >= trans_tol):
        reason = (
            f"not converged after {k} steps (phase {run.phase}): rotation error {final_rot:.2e} rad "
            f"(tol {rot_tol:g}), translation error {final_trans:.2e} m (tol {trans_tol:g})"
        )
    return ServoResult(
        demo="panoramic",
        camera_poses=np.stack([mirror_pose(st).matrix for st in data["state"]]),
        features=data["features"],
        desired_features=scene.desired,
        controls={"robot_velocity": data["u"]},
        errors={
            "task_error_norm": np.hypot(data["alpha"], data["s_ang"]),
            "rotation_error_rad": rot,
            "translation_error": trans,
            "feature_error_px": data["s_px"],
        },
        converged=not reason,
        reason=reason,
        **run_summary(rot, trans, s.dt, k, wall0),
        states=data["state"],
        extras={
            "s_px": data["s_px"],
            "s_angle_rad": data["s_ang"],
            "alpha_hat": data["alpha"],
            "biconic_measure": data["measure"],
            "phase": data["phase"],
            "biconics": np.stack(run.conics) if run.conics else np.zeros((0, len(scene.points), 3, 3)),
            "biconic_steps": np.asarray(run.conic_steps, dtype=int),
            "scene_points": scene.points,
            "target_state": scene.target,
        },
        params=params,
    )


def simulate_panoramic(
    *, seed: int = 0, noise_px: float = 0.0, steps: int = 1500, dt: float = 0.05, k_omega: float = 2.0,
    k_v: float = 3.0, switch_rad: float = 5e-3, freeze_angle: float = 0.02, stop_px: float | None = None,
    rotation_tol: float | None = None, translation_tol: float | None = None, conic_every: int = 10,
    points: npt.ArrayLike | None = None, camera: CatadioptricCamera | None = None,
    target: npt.ArrayLike = (0.0, 0.0, 0.0), start: npt.ArrayLike | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> ServoResult:
    r"""Simulate the panoramic holonomic-robot servo (module docstring); deterministic for a ``seed``.

    Each step: the image (:func:`observe_panoramic`), the control law (:func:`control_law`, from the rays
    only), the record (:func:`record_panoramic_state`, :func:`record_panoramic_control`) and the state update
    (:func:`step_state`, exact on SE(2)).

    Args:
        seed: draws the start (:func:`draw_start_state`: heading 30-120 degrees off, 1-3 m away) and the
            image noise.
        noise_px, steps, dt, k_omega, k_v, switch_rad, freeze_angle, conic_every: see
            :class:`PanoramicSettings`; the run stops once ``s(t) < stop_px`` in step 2.
        stop_px: early-stop threshold on ``s(t)``; default 5e-4 px without noise, none with noise.
        rotation_tol: convergence tolerance (rad); default 1e-3, or 1e-2 with noise.
        translation_tol: convergence tolerance (m); default 1e-3, or 1e-2 with noise.
        points: (N, 3) scene points; default :func:`default_scene`.
        camera: the catadioptric camera model (its pose is ignored); default :func:`default_camera`.
        target: target state ``(x, y, theta)``.
        start: start state instead of the drawn one.
        progress: called as ``progress(step, steps)`` every 50 steps.

    Returns:
        A :class:`ServoResult` with ``states`` (T, 3), controls ``robot_velocity`` (T, 3) = (v_x, v_y, omega),
        errors and extras ``s_px`` (= s(t)), ``alpha_hat``, ``biconic_measure``, ``phase``, ``biconics``
        (S, N, 3, 3) at ``biconic_steps`` (S,). Features leaving the mirror's field of view end the run with
        ``converged=False`` and a reason.

    Raises:
        ValueError: on invalid parameters.
    """
    s = PanoramicSettings(
        seed=seed, noise_px=noise_px, steps=steps, dt=dt, k_omega=k_omega, k_v=k_v, switch_rad=switch_rad,
        freeze_angle=freeze_angle, stop_px=stop_px, rotation_tol=rotation_tol, translation_tol=translation_tol,
        conic_every=conic_every,
    )
    wall0 = _time.perf_counter()
    rng = np.random.default_rng(seed)
    cam = camera if camera is not None else default_camera()
    X = default_scene() if points is None else np.asarray(points, dtype=float).reshape(-1, 3)
    target = np.asarray(target, dtype=float).reshape(3)
    state = draw_start_state(rng, target) if start is None else np.asarray(start, dtype=float).reshape(3).copy()
    params = _panoramic_params(s, cam, target)
    try:
        scene = _panoramic_scene(cam, X, target, noise_px, rng)
    except _NotRun as exc:
        r0, t0 = panoramic_errors(state, target)
        return ServoResult.not_run(
            "panoramic", str(exc), rotation_error=r0, translation_error=t0,
            camera_poses=mirror_pose(state).matrix[None], n_features=len(X), controls={"robot_velocity": 3},
            wall_time_s=_time.perf_counter() - wall0, states=state[None].copy(), params=params,
        )
    return _panoramic_result(s, scene, _panoramic_loop(s, scene, state, rng, progress), params, wall0)
