"""What the split simulations' settings and results share: the noise-dependent defaults of their stop threshold and
convergence tolerances, and the summary fields of a run's :class:`~egtviz.servo.result.ServoResult`."""

from __future__ import annotations

import time as _time
from typing import Any, ClassVar

import numpy as np

__all__ = ["NoiseDefaults", "run_summary"]


class NoiseDefaults:
    """The stop threshold and the convergence tolerances of a run, each its field or, when ``None``, a default that
    depends on whether the features carry noise (a mixin of a frozen settings dataclass with these fields)."""

    noise_px: float
    stop_px: float | None
    rotation_tol: float | None
    translation_tol: float | None

    STOP_PX_DEFAULT: ClassVar[float]
    """The early-stop threshold (pixels) without noise; with noise the default is 0 (no early stop)."""

    @property
    def noisy(self) -> bool:
        """Whether the features carry noise."""
        return self.noise_px > 0

    @property
    def stop_threshold_px(self) -> float:
        """``stop_px``; by default :attr:`STOP_PX_DEFAULT` without noise, 0 (no early stop) with noise."""
        return (0.0 if self.noisy else self.STOP_PX_DEFAULT) if self.stop_px is None else float(self.stop_px)

    @property
    def rotation_tolerance(self) -> float:
        """``rotation_tol``; by default 1e-3 rad, or 1e-2 with noise."""
        return (1e-2 if self.noisy else 1e-3) if self.rotation_tol is None else float(self.rotation_tol)

    @property
    def translation_tolerance(self) -> float:
        """``translation_tol``; by default 1e-3 m, or 1e-2 with noise."""
        return (1e-2 if self.noisy else 1e-3) if self.translation_tol is None else float(self.translation_tol)


def run_summary(rot: np.ndarray, trans: np.ndarray, dt: float, steps: int, wall0: float) -> dict[str, Any]:
    """The :class:`~egtviz.servo.result.ServoResult` fields of a run of ``steps`` steps of ``dt`` seconds whose
    rotation and translation errors per step are ``rot`` and ``trans``, started at ``time.perf_counter()`` ``wall0``:
    its time axis, its first and last errors, its length and its wall time."""
    return {
        "time": np.arange(len(rot)) * dt,
        "initial_rotation_error_rad": float(rot[0]),
        "initial_translation_error": float(trans[0]),
        "final_rotation_error_rad": float(rot[-1]),
        "final_translation_error": float(trans[-1]),
        "steps": steps,
        "sim_time_s": steps * dt,
        "wall_time_s": _time.perf_counter() - wall0,
    }
