"""The result of a visual-servoing simulation, shared by both demos, and its JSON form.

A simulation records ``T = steps + 1`` samples: the state at ``time[k]`` and the
control computed from the image at that state (the control of the last sample
is the one that would be applied next). Arrays are rows over time, points are
rows (``docs/conventions.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

__all__ = ["ServoResult", "SUMMARY_KEYS"]

#: The scalar summary keys of :meth:`ServoResult.to_json_dict`.
SUMMARY_KEYS = (
    "demo",
    "converged",
    "reason",
    "translation_servoed",
    "initial_rotation_error_rad",
    "initial_translation_error",
    "final_rotation_error_rad",
    "final_translation_error",
    "steps",
    "sim_time_s",
    "wall_time_s",
)


def _jsonable(value: Any) -> Any:
    """Arrays to nested lists, NaN/inf to ``None`` (strict JSON), numpy scalars to Python."""
    if isinstance(value, np.ndarray):
        if value.dtype == bool:
            return value.tolist()
        return _jsonable(value.tolist())
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        x = float(value)
        return x if math.isfinite(x) else None
    return value


@dataclass(frozen=True, eq=False)
class ServoResult:
    """Time series and summary of one servoing run (pin-hole arm or panoramic robot)."""

    demo: Literal["pinhole", "panoramic"]
    """Which demo produced the run."""
    time: np.ndarray
    """(T,) simulated time in seconds, ``T = steps + 1``."""
    camera_poses: np.ndarray
    """(T, 4, 4) camera (pin-hole) or mirror-frame (panoramic) poses ``H = [R t; 0 1]`` in the world."""
    features: np.ndarray
    """(T, N, 2) measured feature pixels (with noise); NaN where a feature has no image."""
    desired_features: np.ndarray
    """(N, 2) measured feature pixels at the target pose."""
    controls: dict[str, np.ndarray]
    """Control inputs over time, each (T, k): pin-hole ``camera_twist`` (v, omega in the camera
    frame) and ``joint_velocities``; panoramic ``robot_velocity`` (v_x, v_y, omega in the robot frame)."""
    errors: dict[str, np.ndarray]
    """(T,) error series: ``task_error_norm``, ``rotation_error_rad``, ``translation_error`` (metres), ..."""
    converged: bool
    """The final pose is within the tolerances of the target (see ``params``)."""
    reason: str
    """Why the run did not converge; empty on success."""
    initial_rotation_error_rad: float
    initial_translation_error: float
    final_rotation_error_rad: float
    final_translation_error: float
    steps: int
    """Number of state updates performed (``T - 1``)."""
    sim_time_s: float
    """Simulated time, ``steps * dt``."""
    wall_time_s: float = 0.0
    """Wall-clock time the simulation took."""
    translation_servoed: bool = True
    """False when the translation task was off (pin-hole ``beta = 0``)."""
    joint_angles: np.ndarray | None = None
    """(T, 6) arm joint angles (pin-hole demo), else ``None``."""
    states: np.ndarray | None = None
    """(T, 3) robot state ``(x, y, theta)`` (panoramic demo), else ``None``."""
    extras: dict[str, np.ndarray] = field(default_factory=dict)
    """Demo-specific series (epipolar distances, phase, bi-conics, ...); see each demo."""
    params: dict[str, Any] = field(default_factory=dict)
    """The parameters of the run (seed, gains, tolerances, ...), JSON-friendly."""

    @classmethod
    def not_run(
        cls,
        demo: Literal["pinhole", "panoramic"],
        reason: str,
        *,
        rotation_error: float,
        translation_error: float,
        camera_poses: np.ndarray,
        n_features: int,
        controls: dict[str, int],
        **fields: Any,
    ) -> ServoResult:
        """A run that ended before its first step: the start pose only (if any), errors unchanged.

        ``controls`` names each control series and its width; ``fields`` sets the
        remaining attributes (``wall_time_s``, ``params``, ``states``, ...).
        """
        T = len(camera_poses)
        r0, t0 = float(rotation_error), float(translation_error)
        return cls(
            demo=demo,
            time=np.zeros(T),
            camera_poses=camera_poses,
            features=np.full((T, n_features, 2), np.nan),
            desired_features=np.full((n_features, 2), np.nan),
            controls={name: np.zeros((T, k)) for name, k in controls.items()},
            errors={"rotation_error_rad": np.full(T, r0), "translation_error": np.full(T, t0)},
            converged=False,
            reason=reason,
            initial_rotation_error_rad=r0,
            initial_translation_error=t0,
            final_rotation_error_rad=r0,
            final_translation_error=t0,
            steps=0,
            sim_time_s=0.0,
            **fields,
        )

    @property
    def n_samples(self) -> int:
        """``T``, the number of recorded samples."""
        return int(len(self.time))

    def summary(self) -> str:
        """One paragraph for a terminal."""
        p = self.params
        head = f"{self.demo} servo (seed {p.get('seed')}"
        if self.demo == "pinhole":
            head += f", beta {p.get('beta')}, F {p.get('estimator')}"
        head += f", noise {p.get('noise_px')} px)"
        status = "converged" if self.converged else f"did not converge: {self.reason}"
        return (
            f"{head}: {status}. "
            f"Rotation error {math.degrees(self.initial_rotation_error_rad):.2f} deg -> "
            f"{math.degrees(self.final_rotation_error_rad):.4f} deg, translation error "
            f"{self.initial_translation_error:.4f} m -> {self.final_translation_error:.6f} m "
            f"after {self.steps} steps ({self.sim_time_s:.2f} s simulated, {self.wall_time_s:.3f} s wall)."
        )

    def to_json_dict(self) -> dict[str, Any]:
        """A strict-JSON dict: the summary keys (:data:`SUMMARY_KEYS`) and every time series as lists.

        NaN and inf become ``null``.
        """
        out: dict[str, Any] = {k: _jsonable(getattr(self, k)) for k in SUMMARY_KEYS}
        out.update(
            {
                "params": _jsonable(self.params),
                "time": _jsonable(self.time),
                "camera_poses": _jsonable(self.camera_poses),
                "features": _jsonable(self.features),
                "desired_features": _jsonable(self.desired_features),
                "controls": _jsonable(self.controls),
                "errors": _jsonable(self.errors),
                "joint_angles": _jsonable(self.joint_angles),
                "states": _jsonable(self.states),
                "extras": _jsonable(self.extras),
            }
        )
        return out


class Recorder:
    """Preallocated per-step buffers, trimmed on :meth:`trim` (keeps the loop free of list appends)."""

    def __init__(self, capacity: int, shapes: dict[str, tuple[int, ...]]) -> None:
        self.buffers = {name: np.full((capacity, *shape), np.nan) for name, shape in shapes.items()}
        self.count = 0

    def trim(self) -> dict[str, np.ndarray]:
        return {name: buf[: self.count].copy() for name, buf in self.buffers.items()}
