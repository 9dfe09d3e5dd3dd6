"""The frame arithmetic of a servo run's playback: which frame a step, a time or the running clock lands on."""

from __future__ import annotations

import math

import numpy as np

from ..servo import ServoResult
from .workbench_fields import FieldError

__all__ = ["DEFAULT_DT", "advanced", "checked_time", "clip_frame", "nearest_frame", "run_dt"]

#: The time step of a run whose parameters do not name one, seconds.
DEFAULT_DT = 0.05


def run_dt(result: ServoResult) -> float:
    """The run's time step, seconds."""
    return float(result.params.get("dt", DEFAULT_DT))


def clip_frame(result: ServoResult, k: int) -> int:
    """Frame ``k`` clipped to the run's frames."""
    return int(np.clip(k, 0, result.n_samples - 1))


def nearest_frame(result: ServoResult, t: float) -> int:
    """The frame nearest to simulated time ``t``."""
    return int(np.argmin(np.abs(result.time - float(t))))


def checked_time(t: object) -> float:
    """A time the scrubber sent, refused unless a finite number of seconds (a raw client can send anything)."""
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
        raise FieldError(f"time: expected a number of seconds, got {repr(t)[:40]}")
    return float(t)


def advanced(result: ServoResult, position: float, elapsed_s: float, speed: float) -> tuple[float, int]:
    """The playback's fractional frame ``position`` after ``elapsed_s`` real seconds at ``speed`` simulated seconds
    per real second, and the frame it shows (never past the last)."""
    position += elapsed_s * speed / run_dt(result)
    return position, min(int(position), result.n_samples - 1)
