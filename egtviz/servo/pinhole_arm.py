r"""Pin-hole camera on a Puma 560: Rives' hybrid task function (EGT reference, section 7).

The camera is fixed to the arm's end effector (:data:`CAMERA_TOOL`: 6 cm along
the tool z axis, the optical axis along tool z, image v pointing along tool x).
Given the image of a few scene points at the target pose (the *desired*
features), the controller:

1. **priority task** :math:`e_1` (rotation): for every feature, the distance of
   the current ray :math:`p_i` from the epipolar plane spanned by the epipole
   direction :math:`\hat e` (the image of the target centre, from F) and the
   desired ray :math:`q_i`,

   .. math:: e_{1,i} = p_i \cdot \frac{\hat e \times q_i}{\lVert \hat e \times q_i \rVert}.

   :math:`e_1 = 0` means that every current feature lies on the line through the
   epipole and its desired position: the two views differ by a pure
   translation (Rives, IROS 2000). Rays are :math:`K^{-1} m` normalised, so
   :math:`e_{1,i}` is (the sine of) an angle; in pixels it is the distance of the
   feature to its epipolar line (``extras["epipolar_distances_px"]``).

2. **secondary task** (the camera's distance to the target pose)
   :math:`h_s = \tfrac12 \lVert c - c^* \rVert^2`, whose gradient in the camera
   frame is :math:`g = \partial h_s / \partial X^T = (R^T (c - c^*), 0)`, acts in
   the null space of the first:

   .. math:: e = W^+ e_1 + \beta\,\kappa\,(I - W^+ W)\, g, \qquad
      \tau = -\lambda\, e,

   with :math:`\tau = (v, \omega)` the camera twist in the camera frame and
   :math:`W = \partial e_1 / \partial X` restricted to its depth-independent
   (rotational) columns, :math:`W = [0 \mid J_\omega]`,
   :math:`J_{\omega,i} = -((p_i \times \hat e) \times q_i)^T / \lVert \hat e \times q_i\rVert`.
   The priority task therefore turns the camera, the secondary task translates it
   (``beta = 0`` switches the translation off). ``kappa`` (``secondary_gain``)
   makes the translation slower than the rotation, so the two phases show.

3. The camera twist, rotated into the world frame, becomes joint velocities by
   damped least squares, :math:`\dot q = J^T (J J^T + \mu^2 I)^{-1} \tau_w`,
   with :math:`\mu` growing as the manipulability falls below a threshold
   (Nakamura). Joint angles are clipped to the arm's limits and the clipping is
   reported.

F comes either from the true poses (``f_algorithm=None``; the epipole is then
:math:`R^T (c^* - c)`) or is estimated at every step from the noisy current and
desired features with :mod:`egtviz.geometry.fundamental` (1 linear 8-point,
2 normalised 8-point, 3 Sampson), with ``m_desired^T F m_current = 0``; the
epipole is the right null vector of F, :math:`\hat e \propto K^{-1} e`.
The secondary task uses the true camera position, as Rives' simulations do.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from egtviz.geometry.epipolar import essential_from_fundamental
from egtviz.geometry.pinhole import Intrinsics
from egtviz.geometry.poses import Pose

from .result import Recorder, ServoResult
from .settings import NoiseDefaults, run_summary

__all__ = [
    "CAMERA_TOOL",
    "TARGET_Q",
    "ESTIMATORS",
    "default_intrinsics",
    "default_scene",
    "puma",
    "camera_pose_from_q",
    "draw_start_pose",
    "rays_from_pixels",
    "epipole_direction",
    "epipolar_task",
    "secondary_gradient",
    "hybrid_twist",
    "rotation_vector",
    "exact_priority_step",
    "joint_velocities",
    "step_joints",
    "rotation_angle",
    "PinholeSettings",
    "PinholeScene",
    "PinholeLaw",
    "PinholeControl",
    "pinhole_law",
    "pinhole_control_law",
    "world_twist",
    "observe_features",
    "pinhole_recorder",
    "record_pinhole_step",
    "simulate_pinhole",
]

#: Camera frame relative to the Puma's flange: 6 cm along tool z, then a -90 degree turn about z
#: so that the image v axis points along tool x (image "down" is world down at the target).
CAMERA_TOOL = np.array(
    [
        [0.0, 1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.06],
        [0.0, 0.0, 0.0, 1.0],
    ]
)

#: Target joint angles (radians): the camera, 0.38 m above the base plane and 0.6 m in front of
#: the base, looks forward and 30 degrees down at the scene (chosen for a roomy, well-conditioned
#: neighbourhood: most 20-60 degree / 0.2-0.5 m starts are reachable within the joint limits).
TARGET_Q = np.array([0.0, np.radians(20.0), np.radians(-180.0), 0.0, np.radians(40.0), 0.0])

#: Distance from the target camera to the centre of the scene, metres.
SCENE_DEPTH = 0.5

#: F estimators by EGT's number (``f_Festim``'s ``algorithm``) and CLI name.
ESTIMATORS = {1: "fundamental_8point", 2: "fundamental_normalized_8point", 3: "fundamental_sampson"}
ESTIMATOR_NAMES = {None: "true", 1: "linear", 2: "normalized", 3: "sampson"}

#: Manipulability below which a start configuration is called singular.
SINGULAR_MANIPULABILITY = 1e-3


def default_intrinsics() -> Intrinsics:
    """A wide-angle 640x480 camera (focal length 150 px, about 130 x 116 degrees).

    Rotating first and translating later (the two phases) turns the camera towards
    the target orientation while it is still up to 0.5 m away; with a narrower lens
    (250 px) a fifth of the starts lose features out of the image on the way.
    """
    return Intrinsics(focal_length=0.0015, pixels_per_metre=(1e5, 1e5), principal_point=(320.0, 240.0))


@lru_cache(maxsize=1)
def puma() -> tuple[Any, Any]:
    """The cached ``(robot, ets)`` pair: rtb's Puma 560 with :data:`CAMERA_TOOL`, and its compiled ETS.

    ``ets.eval(q)`` is the 4x4 camera pose and ``ets.jacob0(q)`` its world-frame Jacobian
    ``[v; omega]`` (the same as ``robot.fkine``/``robot.jacob0``, about 20x faster).
    """
    import roboticstoolbox as rtb
    from spatialmath import SE3

    robot = rtb.models.DH.Puma560()
    robot.tool = SE3(CAMERA_TOOL, check=False)
    return robot, robot.ets()


def camera_pose_from_q(q: npt.ArrayLike) -> Pose:
    """The camera pose of the arm at joint angles ``q`` (6,)."""
    _, ets = puma()
    return Pose.from_matrix(ets.eval(np.asarray(q, dtype=float)))


def default_scene(target_pose: Pose, n_points: int = 12) -> np.ndarray:
    """(n, 3) world points in a 30 x 30 x 20 cm box, :data:`SCENE_DEPTH` in front of ``target_pose``.

    Fixed (its own generator), so every seed sees the same scene.
    """
    rng = np.random.default_rng(20_000)
    local = rng.uniform([-0.15, -0.15, SCENE_DEPTH - 0.1], [0.15, 0.15, SCENE_DEPTH + 0.1], size=(n_points, 3))
    return target_pose.to_world(local)


def _axis_angle_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def draw_start_pose(
    rng: np.random.Generator,
    target_pose: Pose,
    look_at_point: npt.ArrayLike,
    angle_range: tuple[float, float] = (np.radians(20.0), np.radians(60.0)),
    distance_range: tuple[float, float] = (0.2, 0.5),
) -> Pose:
    r"""A start pose ``angle_range`` from the target about a random axis, ``distance_range`` away.

    The rotation :math:`R_\Delta` (random axis, angle uniform in ``angle_range``) is
    applied in the world, :math:`R_s = R_\Delta R^*`, and the centre is moved on
    the orbit around ``look_at_point`` (:math:`c_s = p + s R_\Delta (c^* - p)`) so
    that the scene stays in view; ``s`` is chosen so that
    :math:`\lVert c_s - c^* \rVert` is a distance drawn uniformly from the part of
    ``distance_range`` that the orbit can reach.
    """
    p = np.asarray(look_at_point, dtype=float)
    axis = rng.normal(size=3)
    angle = rng.uniform(*angle_range)
    R_delta = _axis_angle_matrix(axis, angle)
    w = target_pose.t - p
    w2 = R_delta @ w
    ww = float(w @ w)
    cos_phi = float(w @ w2) / ww
    sin2 = max(0.0, 1.0 - cos_phi**2)
    d_min = math.sqrt(ww * sin2)
    lo = max(distance_range[0], d_min * 1.001)
    hi = max(distance_range[1], lo)
    d = rng.uniform(lo, hi)
    root = math.sqrt(max(0.0, d * d / ww - sin2))
    s = min((cos_phi + root, cos_phi - root), key=lambda x: abs(x - 1.0))
    return Pose(R_delta @ target_pose.R, p + s * w2)


# ---------------------------------------------------------------- control law (pure functions)
def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (N, 3) (or (3,)) arrays; several times faster than ``np.cross`` on small inputs."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rays_from_pixels(pixels: np.ndarray, K_inv: np.ndarray) -> np.ndarray:
    """Unit rays (N, 3) in the camera frame of pixels (N, 2): :math:`K^{-1} m` normalised."""
    r = pixels @ K_inv[:, :2].T + K_inv[:, 2]
    return r / np.linalg.norm(r, axis=1, keepdims=True)


def epipole_direction(F: np.ndarray, K_inv: np.ndarray) -> np.ndarray | None:
    r"""Unit direction :math:`K^{-1} e` of the epipole of image 1 (``F e = 0``), or ``None`` if F is zero or not finite."""
    if not np.all(np.isfinite(F)) or np.linalg.norm(F) == 0.0:
        return None
    _, _, Vt = np.linalg.svd(F)
    d = K_inv @ Vt[2]
    n = np.linalg.norm(d)
    return d / n if n > 0 else None


def epipolar_task(p: np.ndarray, q: np.ndarray, e_dir: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    r"""Priority task :math:`e_1` (N,) and its rotational Jacobian :math:`J_\omega` (N, 3).

    Args:
        p: (N, 3) unit current rays (camera frame).
        q: (N, 3) unit desired rays (target camera frame).
        e_dir: (3,) epipole direction in the current camera frame (either sign), or
            ``None`` when the centres coincide (the task is then zero).

    .. math:: e_{1,i} = p_i \cdot n_i,\quad n_i = \frac{\hat e \times q_i}{\lVert\hat e \times q_i\rVert},\quad
       J_{\omega,i} = -\frac{((p_i \times \hat e) \times q_i)^T}{\lVert \hat e \times q_i \rVert}

    (camera rotation :math:`\omega` turns :math:`p_i` and :math:`\hat e` alike,
    :math:`\dot p = p \times \omega`, while the desired rays stay). Features whose
    desired ray is parallel to the epipole carry no information: their rows are 0.
    """
    n = len(p)
    if e_dir is None:
        return np.zeros(n), np.zeros((n, 3))
    eq = _cross(np.broadcast_to(e_dir, q.shape), q)
    norm = np.sqrt(np.einsum("ij,ij->i", eq, eq))
    w = np.where(norm > 1e-9, 1.0 / np.where(norm > 1e-9, norm, 1.0), 0.0)
    e1 = np.einsum("ij,ij->i", p, eq) * w
    J = -_cross(_cross(p, np.broadcast_to(e_dir, p.shape)), q) * w[:, None]
    return e1, J


def secondary_gradient(R: np.ndarray, c: np.ndarray, c_target: np.ndarray) -> np.ndarray:
    r""":math:`\partial h_s/\partial X^T = (R^T (c - c^*), 0)` for :math:`h_s = \tfrac12\lVert c - c^*\rVert^2`, camera frame."""
    return np.concatenate([R.T @ (c - c_target), np.zeros(3)])


def hybrid_twist(
    e1: np.ndarray,
    J_omega: np.ndarray,
    g: np.ndarray,
    *,
    beta: float,
    gain: float,
    secondary_gain: float,
    priority_step: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Camera twist :math:`\tau = -\lambda\,(W^+ e_1 + \beta\kappa (I - W^+ W) g)` and the task vector.

    ``W = [0 | J_omega]`` (N, 6). ``priority_step`` (3,), when given, replaces the
    rotational part of the first-order step :math:`W^+ e_1` by an exact one (the
    rotation vector that zeroes :math:`e_1`, see :func:`exact_priority_step`).
    Returns ``(twist (6,), e (6,))``; twist is ``(v, omega)`` in the camera frame.
    """
    # W = [0 | J_omega] is block structured: W^+ = [0; J_omega^+] and W^+ W = diag(0, J_omega^+ J_omega),
    # so only the (N, 3) block is pseudo-inverted (normal equations when well conditioned, SVD otherwise).
    A = J_omega.T @ J_omega
    tr = float(np.trace(A))
    # det(A) / (tr A / 3)^3 is 1 for a perfectly conditioned A and 0 when singular (cheap, no SVD).
    if tr > 0 and np.linalg.det(A) > 1e-12 * (tr / 3.0) ** 3:
        Jp = np.linalg.solve(A, J_omega.T)
    else:
        Jp = np.linalg.pinv(J_omega, rcond=1e-6)
    P_rot = np.eye(3) - Jp @ J_omega
    e = np.empty(6)
    e[:3] = beta * secondary_gain * g[:3]
    step = Jp @ e1 if priority_step is None else priority_step
    e[3:] = step + beta * secondary_gain * (P_rot @ g[3:])
    return -gain * e, e


def rotation_vector(R: np.ndarray) -> np.ndarray:
    r"""The rotation vector :math:`\theta u` of ``R`` (:math:`R = \exp([\theta u]_\times)`), :math:`\theta \in [0, \pi]`."""
    theta = rotation_angle(R)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = np.linalg.norm(axis)
    if theta < 1e-9:
        return 0.5 * axis
    if s < 1e-9:  # half-turn: the axis is the eigenvector of eigenvalue 1
        w, v = np.linalg.eigh(0.5 * (R + R.T))
        return theta * v[:, np.argmax(w)]
    return theta * axis / s


def exact_priority_step(R_cd: np.ndarray) -> np.ndarray:
    r"""The priority task's exact step: the rotation vector :math:`\log(R_{cd})` with :math:`X_d = R_{cd} X_c + t`.

    Turning the camera by :math:`-\log R_{cd}` (its own frame) makes the two views
    differ by a pure translation, i.e. puts every feature on its epipolar line
    (:math:`e_1 = 0`). :math:`W^+ e_1` is the first-order approximation of this
    step; solving :math:`e_1 = 0` exactly (from F via the essential matrix) avoids
    the local minima of the linearised law.
    """
    return rotation_vector(R_cd)


def joint_velocities(
    J: np.ndarray, twist_world: np.ndarray, *, damping: float = 0.05, threshold: float = 0.02
) -> tuple[np.ndarray, float]:
    r"""Damped least squares :math:`\dot q = J^T (J J^T + \mu^2 I)^{-1} \tau_w`; returns ``(qd, manipulability)``.

    :math:`\mu^2 = \mu_0^2 (1 - (w / w_0)^2)` when the manipulability
    :math:`w = \sqrt{\det J J^T}` is below ``threshold`` :math:`w_0`, else 0.
    """
    JJt = J @ J.T
    w = math.sqrt(max(0.0, float(np.linalg.det(JJt))))
    mu2 = damping**2 * (1.0 - (w / threshold) ** 2) if w < threshold else 0.0
    qd = J.T @ np.linalg.solve(JJt + mu2 * np.eye(len(JJt)), twist_world)
    return qd, w


def step_joints(q: np.ndarray, qd: np.ndarray, dt: float, qlim: np.ndarray) -> tuple[np.ndarray, bool]:
    r"""State update :math:`q' = \mathrm{clip}(q + \Delta t\,\dot q,\ q_{\min}, q_{\max})`, and whether it clipped.

    ``qlim`` (2, n) holds :math:`q_{\min}` and :math:`q_{\max}`.
    """
    q_new = q + dt * qd
    clipped = np.clip(q_new, qlim[0], qlim[1])
    return clipped, bool(np.any(clipped != q_new))


def rotation_angle(R: np.ndarray) -> float:
    r"""Angle of a rotation matrix, accurate near 0: :math:`2 \arcsin(\lVert R - I\rVert_F / (2\sqrt2))`."""
    return 2.0 * math.asin(min(1.0, float(np.linalg.norm(R - np.eye(3))) / (2.0 * math.sqrt(2.0))))


# ---------------------------------------------------------------- simulation
def _check_params(beta: float, noise_px: float, f_algorithm: int | None, steps: int, dt: float) -> None:
    if not isinstance(beta, (int, float)) or not math.isfinite(beta) or beta < 0:
        raise ValueError(f"beta: expected a finite number >= 0, got {beta!r}")
    if not isinstance(noise_px, (int, float)) or not math.isfinite(noise_px) or noise_px < 0:
        raise ValueError(f"noise_px: expected a finite number of pixels >= 0, got {noise_px!r}")
    if f_algorithm not in ESTIMATORS and f_algorithm is not None:
        raise ValueError(f"f_algorithm: expected None (true F), 1, 2 or 3, got {f_algorithm!r}")
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise ValueError(f"steps: expected a positive integer, got {steps!r}")
    if not isinstance(dt, (int, float)) or not math.isfinite(dt) or dt <= 0:
        raise ValueError(f"dt: expected a positive time step in seconds, got {dt!r}")


def _solve_ik(T: np.ndarray, q_guess: np.ndarray) -> np.ndarray | None:
    robot, ets = puma()
    sol = ets.ikine_LM(T, q0=q_guess, ilimit=100, slimit=20, tol=1e-10, seed=0, joint_limits=True)
    if not sol.success:
        return None
    q = np.asarray(sol.q, dtype=float)
    if np.any(q < robot.qlim[0] - 1e-9) or np.any(q > robot.qlim[1] + 1e-9):
        return None
    return q


#: How many start poses a seed may draw before giving up (rejection sampling).
START_DRAW_TRIES = 50

#: Start poses must keep every feature this many pixels inside the image.
START_IMAGE_MARGIN_PX = 20.0


def _draw_start_q(
    rng: np.random.Generator, goal: Pose, q_goal: np.ndarray, X: np.ndarray, K: np.ndarray, width: int, height: int
) -> np.ndarray | None:
    """Joint angles of a start pose drawn with :func:`draw_start_pose`, redrawn until usable.

    Usable: reachable within the joint limits, manipulability above 10x
    :data:`SINGULAR_MANIPULABILITY`, and every feature at least
    :data:`START_IMAGE_MARGIN_PX` inside the image. The seeded distribution is thus
    the one of :func:`draw_start_pose` conditioned on the arm being able to start there.
    """
    _, ets = puma()
    centre = X.mean(axis=0)
    for _ in range(START_DRAW_TRIES):
        pose = draw_start_pose(rng, goal, centre)
        Xc = pose.to_local(X)
        if np.any(Xc[:, 2] <= 0):
            continue
        m = (Xc @ K.T)[:, :2] / Xc[:, 2:3]
        mg = START_IMAGE_MARGIN_PX
        if np.any(m < mg) or np.any(m > [width - mg, height - mg]):
            continue
        q = _solve_ik(pose.matrix, q_goal)
        if q is None:
            continue
        J = ets.jacob0(q)
        if math.sqrt(max(0.0, float(np.linalg.det(J @ J.T)))) < 10 * SINGULAR_MANIPULABILITY:
            continue
        return q
    return None


# ---------------------------------------------------------------- simulation: settings, scene, control law
@dataclass(frozen=True)
class PinholeSettings(NoiseDefaults):
    """The checked settings of one pin-hole run: :func:`simulate_pinhole`'s scalar arguments.

    Raises:
        ValueError: on an invalid value (negative noise, NaN beta, unknown algorithm, ...).
    """

    seed: int
    """Seed of the start-pose draw and of the image noise."""
    beta: float
    """Weight :math:`\\beta` of the secondary (translation) task; 0 servos the rotation only."""
    noise_px: float
    """Standard deviation of the Gaussian image noise, pixels."""
    f_algorithm: int | None
    """``None`` for F from the true poses, else a key of :data:`ESTIMATORS`."""
    steps: int
    """Maximum number of state updates."""
    dt: float
    """Time step, seconds."""
    gain: float
    """:math:`\\lambda` of the task function (1/s)."""
    secondary_gain: float
    """:math:`\\kappa`, the weight of the translation task relative to the rotation."""
    damping: float
    """Maximum damping :math:`\\mu_0` of the damped least squares."""
    priority: str
    """``"exact"``: solve :math:`e_1 = 0` for the rotation each step (:math:`R_{cd}` from the true poses or, for
    an estimated F, from :math:`E = K^T F K` by ``essential.pose_from_essential``'s cheirality test);
    ``"linearized"``: Rives' first-order step :math:`W^+ e_1`, which can stall in a local minimum of
    :math:`\\lVert e_1 \\rVert` (about a third of the seeds with ``beta = 0``)."""
    parallax_min_px: float
    """With an estimated F, below this median translation parallax (pixels) the essential matrix is dominated
    by noise and the linearised step is used instead (near the goal, where it has no local minima)."""
    stop_px: float | None
    """Early-stop threshold in pixels, or ``None`` for :attr:`stop_threshold_px`'s default."""
    rotation_tol: float | None
    """Convergence tolerance on the rotation error (rad), or ``None`` for the default."""
    translation_tol: float | None
    """Convergence tolerance on the translation error (m), or ``None`` for the default."""

    STOP_PX_DEFAULT: ClassVar[float] = 0.005
    """The default early-stop threshold (pixels) without noise."""

    def __post_init__(self) -> None:
        _check_params(self.beta, self.noise_px, self.f_algorithm, self.steps, self.dt)
        if self.priority not in ("exact", "linearized"):
            raise ValueError(f"priority: expected 'exact' or 'linearized', got {self.priority!r}")
        for name in ("gain", "secondary_gain", "damping"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"{name}: expected a finite number >= 0, got {value!r}")


@dataclass(frozen=True)
class PinholeScene:
    """The camera, the scene and the target of a run, with the desired features measured there (once)."""

    K: np.ndarray
    """(3, 3) intrinsic matrix."""
    K_inv: np.ndarray
    """(3, 3) its inverse."""
    image_size: tuple[int, int]
    """``(width, height)`` in pixels."""
    points: np.ndarray
    """(N, 3) world points."""
    target: Pose
    """The target camera pose."""
    target_q: np.ndarray
    """(6,) the arm's joint angles at the target."""
    desired: np.ndarray
    """(N, 2) desired feature pixels (with noise) :math:`m^*_i`."""
    desired_rays: np.ndarray
    """(N, 3) unit desired rays :math:`q_i = K^{-1} m^*_i / \\lVert K^{-1} m^*_i \\rVert` (target camera frame)."""
    desired_h: np.ndarray
    """(N, 3) the desired pixels in homogeneous coordinates :math:`(m^*_i, 1)`."""


@dataclass(frozen=True)
class PinholeLaw:
    """The controller: the gains of the hybrid task function and how it finds the epipole."""

    beta: float
    """:math:`\\beta`, the weight of the translation task."""
    gain: float
    """:math:`\\lambda` (1/s)."""
    secondary_gain: float
    """:math:`\\kappa`."""
    exact: bool
    """Solve the priority task exactly (:func:`exact_priority_step`) rather than to first order."""
    parallax_min: float
    """With an estimated F, the median parallax angle (rad) below which the exact step is not trusted."""
    estimator: Callable[[np.ndarray, np.ndarray], Any] | None = None
    """F from (current, desired) pixels, ``m_desired^T F m_current = 0``; ``None`` for F from the true poses."""
    pose_from_essential: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
    """The cheirality-tested relative pose from E (needed with an estimator)."""


def pinhole_law(settings: PinholeSettings, K: np.ndarray) -> PinholeLaw:
    """The controller of ``settings`` for a camera ``K`` (imports the F estimator only when one is asked for)."""
    estimator = pose_from_essential = None
    if settings.f_algorithm is not None:
        from egtviz.geometry import essential, fundamental, sampson_refinement

        module = sampson_refinement if settings.f_algorithm == 3 else fundamental
        estimator = getattr(module, ESTIMATORS[settings.f_algorithm])
        pose_from_essential = essential.pose_from_essential
    return PinholeLaw(
        beta=settings.beta, gain=settings.gain, secondary_gain=settings.secondary_gain,
        exact=settings.priority == "exact", parallax_min=float(settings.parallax_min_px) / float(K[0, 0]),
        estimator=estimator, pose_from_essential=pose_from_essential,
    )


@dataclass(frozen=True)
class PinholeControl:
    """What the control law computed from one image."""

    twist: np.ndarray
    """(6,) camera twist :math:`\\tau = (v, \\omega)` in the camera frame."""
    task: np.ndarray
    """(N,) the priority task :math:`e_1`."""
    epipole: np.ndarray | None
    """(3,) unit epipole direction :math:`\\hat e` in the current camera frame, or ``None`` when unknown."""
    exact_step: bool
    """Whether the rotation came from the exact priority step."""
    estimation_failed: bool = False
    """Whether F (or its epipole) could not be estimated from this image (the previous epipole was kept)."""


def _true_epipole(
    R: np.ndarray, c: np.ndarray, target: Pose, exact: bool
) -> tuple[np.ndarray | None, np.ndarray | None]:
    r"""From the true poses: the epipole :math:`R^T (c^* - c)` normalised (``None`` at the target), the exact step."""
    base = R.T @ (target.t - c)
    nb = float(np.linalg.norm(base))
    e_dir = base / nb if nb > 1e-12 else None
    return e_dir, exact_priority_step(target.R.T @ R) if exact else None


def _estimated_epipole(
    m: np.ndarray, p_rays: np.ndarray, scene: PinholeScene, law: PinholeLaw, e_dir_prev: np.ndarray | None
) -> tuple[np.ndarray | None, np.ndarray | None, bool]:
    r"""Epipole, exact step and failure flag from F estimated on the features (``m_desired^T F m = 0``).

    :math:`\hat e \propto K^{-1} e` with :math:`F e = 0`, signed like ``e_dir_prev`` (a null vector's sign is
    arbitrary) and replaced by it when F fails. The exact step is :math:`\log R_{cd}` from
    :math:`E = K^T F K`, used only while the median angle between the current rays and the derotated desired
    rays exceeds ``law.parallax_min``.
    """
    K, K_inv, q_rays = scene.K, scene.K_inv, scene.desired_rays
    # Only called for a law with an estimator, which make_law always pairs with pose_from_essential.
    assert law.estimator is not None and law.pose_from_essential is not None
    R_cd = step = None
    try:
        F = np.asarray(law.estimator(m, scene.desired), dtype=float)
        e_dir = epipole_direction(F, K_inv)
        if law.exact and e_dir is not None:
            E = essential_from_fundamental(F, K, K)
            R_cd, _, _ = law.pose_from_essential(E, p_rays[:, :2] / p_rays[:, 2:3], q_rays[:, :2] / q_rays[:, 2:3])
    except (ValueError, np.linalg.LinAlgError):
        e_dir = None
    failed = e_dir is None
    if e_dir is None:
        e_dir = e_dir_prev
    elif e_dir_prev is not None and e_dir @ e_dir_prev < 0:
        e_dir = -e_dir  # the sign of a null vector is arbitrary; keep it continuous for the record
    if R_cd is not None:
        # translation parallax: angle between the current rays and the derotated desired rays
        cosang = np.einsum("ij,ij->i", p_rays, q_rays @ R_cd)
        if np.median(np.arccos(np.clip(cosang, -1.0, 1.0))) > law.parallax_min:
            step = exact_priority_step(R_cd)
    return e_dir, step, failed


def pinhole_control_law(
    m: np.ndarray,
    R: np.ndarray,
    c: np.ndarray,
    scene: PinholeScene,
    law: PinholeLaw,
    *,
    e_dir_prev: np.ndarray | None = None,
) -> PinholeControl:
    r"""The hybrid task function's camera twist from the current features ``m`` (N, 2) at the pose ``(R, c)``.

    With :math:`p_i = K^{-1} m_i` and :math:`q_i = K^{-1} m^*_i` normalised and the epipole direction
    :math:`\hat e` (true poses, or F estimated from ``m`` and :math:`m^*`),

    .. math:: e_{1,i} = p_i \cdot \frac{\hat e \times q_i}{\lVert \hat e \times q_i \rVert}, \qquad
       g = (R^T (c - c^*), 0), \qquad
       \tau = -\lambda\,\bigl(W^+ e_1 + \beta\kappa\,(I - W^+ W)\, g\bigr),

    with :math:`W = [0 \mid J_\omega]` (:func:`epipolar_task`, :func:`hybrid_twist`); ``law.exact`` replaces
    the rotational part of :math:`W^+ e_1` by :math:`\log R_{cd}` (:func:`exact_priority_step`). The camera
    position enters only the secondary task, as in Rives' simulations. Pure: ``e_dir_prev`` (the previous
    step's epipole) only signs and stands in for an estimated one.
    """
    p_rays = rays_from_pixels(m, scene.K_inv)
    if law.estimator is None:
        e_dir, step = _true_epipole(R, c, scene.target, law.exact)
        failed = False
    else:
        e_dir, step, failed = _estimated_epipole(m, p_rays, scene, law, e_dir_prev)
    e1, J_w = epipolar_task(p_rays, scene.desired_rays, e_dir)
    g = secondary_gradient(R, c, scene.target.t)
    twist, _ = hybrid_twist(
        e1, J_w, g, beta=law.beta, gain=law.gain, secondary_gain=law.secondary_gain, priority_step=step
    )
    return PinholeControl(twist, e1, e_dir, step is not None, failed)


def world_twist(R: np.ndarray, twist: np.ndarray) -> np.ndarray:
    r"""A camera-frame twist :math:`(v, \omega)` in the world frame: :math:`\tau_w = (R v, R \omega)`."""
    return np.concatenate([R @ twist[:3], R @ twist[3:]])


def observe_features(
    T: np.ndarray, scene: PinholeScene, noise_px: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""The camera at pose ``T`` (4, 4) sees ``(m, m_true, visible)``: noisy and true pixels (N, 2), and a mask.

    :math:`X_c = R^T (X - c)`, :math:`m = (K X_c)_{1,2} / z_c` plus Gaussian noise of ``noise_px``
    (drawn from ``rng`` only when ``noise_px > 0``); visible: in front and inside the image.
    """
    R, c = T[:3, :3], T[:3, 3]
    W_img, H_img = scene.image_size
    Xc = (scene.points - c) @ R
    z = Xc[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        m_true = (Xc @ scene.K.T)[:, :2] / z[:, None]
    visible = (z > 0) & (m_true[:, 0] >= 0) & (m_true[:, 0] <= W_img) & (m_true[:, 1] >= 0) & (m_true[:, 1] <= H_img)
    m = m_true + (rng.normal(scale=noise_px, size=m_true.shape) if noise_px > 0 else 0.0)
    return m, m_true, visible


# ---------------------------------------------------------------- simulation: recording
def pinhole_recorder(capacity: int, n_features: int) -> Recorder:
    """NaN-filled buffers for ``capacity`` samples of a run with ``n_features`` features."""
    n = n_features
    shapes = {"poses": (4, 4), "q": (6,), "features": (n, 2), "features_true": (n, 2), "twist": (6,), "qd": (6,)}
    scalars = ("task", "rot", "trans", "feat_err", "manip", "limit", "exact")
    return Recorder(capacity, {**shapes, "epi_px": (n,), "epipole": (3,), **{name: () for name in scalars}})


def record_pinhole_step(
    rec: Recorder,
    k: int,
    T: np.ndarray,
    q: np.ndarray,
    m: np.ndarray,
    m_true: np.ndarray,
    control: PinholeControl,
    qd: np.ndarray,
    manip: float,
    scene: PinholeScene,
) -> np.ndarray:
    r"""Store sample ``k``; returns the feature errors :math:`\lVert m_i - m^*_i \rVert` (N,) in pixels.

    Besides the state, features and controls it stores :math:`\lVert e_1 \rVert`, the rotation error
    :math:`\angle(R^{*T} R)`, the distance :math:`\lVert c - c^* \rVert`, the mean feature error, the signed
    distance of each feature to its epipolar line :math:`l_i = e \times m^*_i` (:math:`e = K \hat e`, pixels,
    NaN without an epipole) and the epipole in pixels (its direction where it is at infinity).
    """
    b = rec.buffers
    R, c = T[:3, :3], T[:3, 3]
    b["exact"][k] = control.exact_step
    b["poses"][k] = T
    b["q"][k] = q
    b["features"][k] = m
    b["features_true"][k] = m_true
    b["twist"][k] = control.twist
    b["qd"][k] = qd
    b["task"][k] = float(np.linalg.norm(control.task))
    b["rot"][k] = rotation_angle(scene.target.R.T @ R)
    b["trans"][k] = float(np.linalg.norm(c - scene.target.t))
    feat_err = np.linalg.norm(m - scene.desired, axis=1)
    b["feat_err"][k] = float(feat_err.mean())
    if control.epipole is not None:
        e_px = scene.K @ control.epipole
        lines = _cross(np.broadcast_to(e_px, scene.desired_h.shape), scene.desired_h)
        with np.errstate(divide="ignore", invalid="ignore"):
            b["epi_px"][k] = (lines[:, :2] * m).sum(axis=1) + lines[:, 2]
            b["epi_px"][k] /= np.hypot(lines[:, 0], lines[:, 1])
        b["epipole"][k] = e_px / (e_px[2] if abs(e_px[2]) > 1e-12 * np.linalg.norm(e_px) else np.linalg.norm(e_px))
    b["manip"][k] = manip
    b["limit"][k] = 0.0
    rec.count = k + 1
    return feat_err


# ---------------------------------------------------------------- simulation: set-up, loop, result
class _NotRun(Exception):
    """The run cannot start: ``reason``, and the start and target poses when known."""

    def __init__(self, reason: str, start: Pose | None = None, target: Pose | None = None) -> None:
        super().__init__(reason)
        self.reason, self.start, self.target = reason, start, target


def _target_q(target_pose: Pose | None, target_q: npt.ArrayLike | None) -> np.ndarray:
    if target_pose is None:
        return TARGET_Q.copy() if target_q is None else np.asarray(target_q, dtype=float).reshape(6)
    q_goal = _solve_ik(target_pose.matrix, TARGET_Q if target_q is None else np.asarray(target_q, float))
    if q_goal is None:
        raise _NotRun("target unreachable: no inverse-kinematics solution within the joint limits")
    return q_goal


def _start_q(
    rng: np.random.Generator, goal: Pose, q_goal: np.ndarray, X: np.ndarray, intr: Intrinsics,
    start_pose: Pose | None, q0: npt.ArrayLike | None,
) -> np.ndarray:
    """Start joint angles: ``q0``, else by inverse kinematics of ``start_pose``, else drawn (:func:`_draw_start_q`)."""
    robot, ets = puma()
    qlim = np.asarray(robot.qlim, dtype=float)
    q: np.ndarray | None
    if q0 is not None:
        q = np.asarray(q0, dtype=float).reshape(6)
        if np.any(q < qlim[0]) or np.any(q > qlim[1]):
            raise _NotRun("start configuration outside the joint limits")
    elif start_pose is not None:
        q = _solve_ik(start_pose.matrix, q_goal)
        if q is None:
            reason = "start pose unreachable: no inverse-kinematics solution within the joint limits"
            raise _NotRun(reason, start_pose, goal)
    else:
        q = _draw_start_q(rng, goal, q_goal, X, intr.K, intr.width, intr.height)
        if q is None:
            raise _NotRun(f"no reachable start pose found in {START_DRAW_TRIES} draws", None, goal)
    start = Pose.from_matrix(ets.eval(q))
    w0 = math.sqrt(max(0.0, float(np.linalg.det(ets.jacob0(q) @ ets.jacob0(q).T))))
    if w0 < SINGULAR_MANIPULABILITY:
        raise _NotRun(f"start configuration is singular (manipulability {w0:.2e})", start, goal)
    return q


def _prepare_pinhole(
    s: PinholeSettings, intr: Intrinsics, rng: np.random.Generator, *, points: npt.ArrayLike | None,
    target_q: npt.ArrayLike | None, target_pose: Pose | None, start_pose: Pose | None, q0: npt.ArrayLike | None,
) -> tuple[PinholeScene, np.ndarray]:
    """The scene (target, desired features measured once with noise) and the start joint angles.

    Raises:
        _NotRun: the target or start is unreachable or singular, too few features, or a feature unseen at the target.
    """
    _, ets = puma()
    K, (W_img, H_img) = intr.K, (intr.width, intr.height)
    q_goal = _target_q(target_pose, target_q)
    goal = Pose.from_matrix(ets.eval(q_goal))
    X = default_scene(goal) if points is None else np.asarray(points, dtype=float).reshape(-1, 3)
    if s.f_algorithm is not None and len(X) < 8:
        raise _NotRun(f"estimated F needs at least 8 features, got {len(X)}")
    if len(X) < 3:
        raise _NotRun(f"the epipolar task needs at least 3 features, got {len(X)}")
    q = _start_q(rng, goal, q_goal, X, intr, start_pose, q0)
    start = Pose.from_matrix(ets.eval(q))
    Xg = (X - goal.t) @ goal.R
    if np.any(Xg[:, 2] <= 0):
        raise _NotRun("some scene points are behind the camera at the target pose", start, goal)
    m_goal = (Xg @ K.T)[:, :2] / Xg[:, 2:3]
    if np.any((m_goal < 0) | (m_goal > [W_img, H_img])):
        raise _NotRun("some features are outside the image at the target pose", start, goal)
    m_des = m_goal + (rng.normal(scale=s.noise_px, size=m_goal.shape) if s.noisy else 0.0)
    K_inv = np.linalg.inv(K)
    m_des_h = np.column_stack([m_des, np.ones(len(X))])
    scene = PinholeScene(K, K_inv, (W_img, H_img), X, goal, q_goal, m_des, rays_from_pixels(m_des, K_inv), m_des_h)
    return scene, q


def _pinhole_params(s: PinholeSettings, intr: Intrinsics) -> dict[str, Any]:
    return {
        "seed": s.seed, "beta": float(s.beta), "noise_px": float(s.noise_px),
        "estimator": ESTIMATOR_NAMES[s.f_algorithm], "f_algorithm": s.f_algorithm, "dt": float(s.dt),
        "max_steps": int(s.steps), "gain": float(s.gain), "secondary_gain": float(s.secondary_gain),
        "damping": float(s.damping), "priority": s.priority, "parallax_min_px": float(s.parallax_min_px),
        "stop_px": s.stop_threshold_px, "rotation_tol": s.rotation_tolerance,
        "translation_tol": s.translation_tolerance, "K": intr.K.tolist(), "image_size": [intr.width, intr.height],
        "camera_tool": CAMERA_TOOL.tolist(),
    }


def _pinhole_not_run(exc: _NotRun, s: PinholeSettings, params: dict[str, Any], wall0: float) -> ServoResult:
    pose0, goal = exc.start, exc.target
    rotation_error = translation_error = float("nan")
    if pose0 is not None and goal is not None:
        rotation_error = rotation_angle(goal.R.T @ pose0.R)
        translation_error = float(np.linalg.norm(pose0.t - goal.t))
    return ServoResult.not_run(
        "pinhole", exc.reason,
        rotation_error=rotation_error,
        translation_error=translation_error,
        camera_poses=pose0.matrix[None] if pose0 is not None else np.zeros((0, 4, 4)),
        n_features=0, controls={"camera_twist": 6, "joint_velocities": 6},
        wall_time_s=_time.perf_counter() - wall0, translation_servoed=s.beta > 0, params=params,
    )


def _stop_reason(
    s: PinholeSettings, k: int, visible: np.ndarray, manip: float, feat_err: np.ndarray, epi_px: np.ndarray
) -> tuple[bool, str]:
    """Whether the run ends at step ``k``, and the reason when it fails there.

    It fails when a feature leaves the image or the arm is singular; it ends when the features are within
    ``stop_px`` of their goal (desired positions, or epipolar lines when beta = 0) or at the last step.
    """
    if not np.all(visible):
        return True, f"feature {int(np.flatnonzero(~visible)[0])} left the image at t = {k * s.dt:.2f} s"
    if manip < SINGULAR_MANIPULABILITY:
        return True, f"the arm reached a singular configuration at t = {k * s.dt:.2f} s (manipulability {manip:.1e})"
    goal_px = feat_err.max() if s.beta > 0 else float(np.nanmax(np.abs(epi_px)))
    stop_px = s.stop_threshold_px
    return (stop_px > 0 and goal_px < stop_px) or k >= s.steps, ""


@dataclass(frozen=True)
class _PinholeRun:
    data: dict[str, np.ndarray]
    steps: int
    reason: str
    estimation_failures: int
    limit_hits: int


def _pinhole_loop(
    s: PinholeSettings, scene: PinholeScene, q: np.ndarray, rng: np.random.Generator,
    progress: Callable[[int, int], None] | None,
) -> _PinholeRun:
    """Image, control law, record, state update, until :func:`_stop_reason` ends the run."""
    robot, ets = puma()
    qlim = np.asarray(robot.qlim, dtype=float)
    law = pinhole_law(s, scene.K)
    rec = pinhole_recorder(s.steps + 1, len(scene.points))
    k, e_dir, failures, limit_hits = 0, None, 0, 0
    while True:
        T = ets.eval(q)
        m, m_true, visible = observe_features(T, scene, s.noise_px, rng)
        control = pinhole_control_law(m, T[:3, :3], T[:3, 3], scene, law, e_dir_prev=e_dir)
        e_dir, failures = control.epipole, failures + control.estimation_failed
        qd, manip = joint_velocities(ets.jacob0(q), world_twist(T[:3, :3], control.twist), damping=s.damping)
        feat_err = record_pinhole_step(rec, k, T, q, m, m_true, control, qd, manip, scene)
        stop, reason = _stop_reason(s, k, visible, manip, feat_err, rec.buffers["epi_px"][k])
        if stop:
            break
        q, hit = step_joints(q, qd, s.dt, qlim)
        rec.buffers["limit"][k] = float(hit)
        limit_hits += hit
        k += 1
        if progress is not None and k % 50 == 0:
            progress(k, s.steps)
    if progress is not None:
        progress(k, s.steps)
    return _PinholeRun(rec.trim(), k, reason, failures, limit_hits)


def _final_reason(s: PinholeSettings, run: _PinholeRun) -> str:
    """The run's failure reason ("" when converged): its stop reason, or the final errors against the tolerances."""
    if run.reason:
        return run.reason
    final_rot, final_trans = float(run.data["rot"][-1]), float(run.data["trans"][-1])
    rot_tol, trans_tol = s.rotation_tolerance, s.translation_tolerance
    if s.beta == 0:
        reason = "translation not servoed (beta = 0): only the priority (rotation) task acts"
        if final_rot >= rot_tol:
            reason += f"; rotation error {final_rot:.2e} rad is above {rot_tol:g}"
        return reason
    if final_rot < rot_tol and final_trans < trans_tol:
        return ""
    reason = (
        f"not converged after {run.steps} steps: rotation error {final_rot:.2e} rad (tol {rot_tol:g}), "
        f"translation error {final_trans:.2e} m (tol {trans_tol:g})"
    )
    if run.limit_hits:
        reason += f"; joint limits clipped the motion at {run.limit_hits} steps"
    return reason


def _pinhole_result(
    s: PinholeSettings, scene: PinholeScene, run: _PinholeRun, params: dict[str, Any], wall0: float
) -> ServoResult:
    data, k = run.data, run.steps
    rot, trans = data["rot"], data["trans"]
    reason = _final_reason(s, run)
    params["estimation_failures"] = run.estimation_failures
    params["joint_limit_steps"] = run.limit_hits
    epi = data["epi_px"]
    return ServoResult(
        demo="pinhole",
        camera_poses=data["poses"],
        features=data["features"],
        desired_features=scene.desired,
        controls={"camera_twist": data["twist"], "joint_velocities": data["qd"]},
        errors={
            "task_error_norm": data["task"],
            "rotation_error_rad": rot,
            "translation_error": trans,
            "feature_error_px": data["feat_err"],
            "max_epipolar_distance_px": np.nanmax(np.abs(epi), axis=1)
            if np.any(np.isfinite(epi))
            else np.full(len(rot), np.nan),
        },
        converged=not reason,
        reason=reason,
        **run_summary(rot, trans, s.dt, k, wall0),
        translation_servoed=s.beta > 0,
        joint_angles=data["q"],
        extras={
            "features_true": data["features_true"],
            "epipolar_distances_px": epi,
            "epipole_px": data["epipole"],
            "manipulability": data["manip"],
            "joint_limit_clipped": data["limit"].astype(bool),
            "exact_priority_step": data["exact"].astype(bool),
            "scene_points": scene.points,
            "target_pose": scene.target.matrix,
            "target_q": scene.target_q,
        },
        params=params,
    )


def simulate_pinhole(
    *, seed: int = 0, beta: float = 1.0, noise_px: float = 0.0, f_algorithm: int | None = None, steps: int = 1000,
    dt: float = 0.05, gain: float = 3.0, secondary_gain: float = 0.1, damping: float = 0.05, priority: str = "exact",
    parallax_min_px: float = 10.0, stop_px: float | None = None, rotation_tol: float | None = None,
    translation_tol: float | None = None, points: npt.ArrayLike | None = None, intrinsics: Intrinsics | None = None,
    target_q: npt.ArrayLike | None = None, target_pose: Pose | None = None, start_pose: Pose | None = None,
    q0: npt.ArrayLike | None = None, progress: Callable[[int, int], None] | None = None,
) -> ServoResult:
    r"""Simulate the Puma 560 pin-hole servo (module docstring); deterministic for a ``seed``.

    Each step: the image (:func:`observe_features`), the control law (:func:`pinhole_control_law`, the camera
    twist; :func:`joint_velocities`, the arm's), the record (:func:`record_pinhole_step`) and the state update
    (:func:`step_joints`, :math:`q \leftarrow \mathrm{clip}(q + \Delta t\,\dot q)`).

    Args:
        seed: draws the start pose (:func:`draw_start_pose`: 20-60 degrees about a random axis, 0.2-0.5 m
            away) and the image noise.
        beta, noise_px, f_algorithm, steps, dt, gain, secondary_gain, damping: see :class:`PinholeSettings`.
        priority: ``"exact"`` (default) solves the priority task exactly each step: the rotation
            :math:`R_{cd}` that puts every feature on its epipolar line, from the true poses or, for an
            estimated F, from :math:`E = K^T F K` (cheirality test); ``"linearized"`` uses Rives' first-order
            step :math:`W^+ e_1`, which can stall in a local minimum of :math:`\lVert e_1 \rVert`.
        parallax_min_px: with an estimated F, below this median translation parallax (pixels) the essential
            matrix is dominated by noise and the linearised step is used instead.
        stop_px: early stop once the features are within this many pixels of their goal (desired positions,
            or epipolar lines when ``beta = 0``); default 0.005 px without noise, no early stop with noise.
        rotation_tol, translation_tol: convergence tolerances (rad, m); default 1e-3, or 1e-2 with noise.
        points: (N, 3) world points; default :func:`default_scene`.
        intrinsics: the camera; default :func:`default_intrinsics`.
        target_q: target joint angles; default :data:`TARGET_Q`.
        target_pose: target camera pose instead of ``target_q`` (solved by inverse kinematics).
        start_pose: start camera pose instead of the drawn one (solved by inverse kinematics).
        q0: start joint angles instead of a start pose.
        progress: called as ``progress(step, steps)`` every 50 steps (for a progress bar).

    Returns:
        A :class:`ServoResult`; failures (unreachable pose, singular start, features leaving the image, too
        few features for an estimated F) end the run with ``converged=False`` and a ``reason``.

    Raises:
        ValueError: on invalid parameters (negative noise, NaN beta, unknown algorithm, ...).
    """
    s = PinholeSettings(
        seed=seed, beta=beta, noise_px=noise_px, f_algorithm=f_algorithm, steps=steps, dt=dt, gain=gain,
        secondary_gain=secondary_gain, damping=damping, priority=priority, parallax_min_px=parallax_min_px,
        stop_px=stop_px, rotation_tol=rotation_tol, translation_tol=translation_tol,
    )
    wall0 = _time.perf_counter()
    rng = np.random.default_rng(seed)
    intr = intrinsics if intrinsics is not None else default_intrinsics()
    params = _pinhole_params(s, intr)
    try:
        scene, q = _prepare_pinhole(
            s, intr, rng, points=points, target_q=target_q, target_pose=target_pose, start_pose=start_pose, q0=q0
        )
    except _NotRun as exc:
        return _pinhole_not_run(exc, s, params, wall0)
    return _pinhole_result(s, scene, _pinhole_loop(s, scene, q, rng, progress), params, wall0)
