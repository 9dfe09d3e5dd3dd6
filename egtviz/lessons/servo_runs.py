r"""Servo runs a lesson step works with: the demo and its run fields, simulated headless, and what is measured.

An ``open_demo`` change (:class:`DemoRun`) names a visual-servoing demo (``pinhole``: the Puma 560 under
Rives' hybrid task; ``panoramic``: the holonomic robot and its bi-conics) and the run fields its *Run*
folder starts with. The viewer's lesson panel offers a button that opens that demo with those fields; a
``servo_number`` task asks for a number read off that run, and the answer is computed here by the same
simulation the demo runs (:func:`egtviz.servo.simulate_pinhole` / :func:`egtviz.servo.simulate_panoramic`
with the same keywords), never written in the lesson file.

The measures (:data:`MEASURES`), each in the unit the demo's read-out shows:

* ``steps``: the number of steps of the run (the status line's "(N steps)");
* ``sim_time``: the simulated time of the run, s;
* ``rotation_below_time``: the first time :math:`t_k` at which the rotation error
  :math:`\theta_k = \arccos((\operatorname{tr}(R_k^T R^*) - 1) / 2)` is below ``below`` degrees, s;
* ``translation_below_time``: the first time at which :math:`\|t_k - t^*\|` is below ``below`` cm, s;
* ``initial_rotation_error``, ``final_rotation_error``: :math:`\theta_0`, :math:`\theta_T` in degrees;
* ``initial_translation_error``, ``final_translation_error``: :math:`\|t_0 - t^*\|`, :math:`\|t_T - t^*\|`
  in cm;
* ``translation_phase_time`` (panoramic only): the first time the robot is in step 2 (translation), s.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..scene.limits import SERVO_DEMO_STEPS, SERVO_SERVER_FRAMES, Range
from ..servo import ServoResult, simulate_panoramic, simulate_pinhole
from ..servo.pinhole_arm import ESTIMATOR_NAMES
from . import fields
from .errors import EntryError

__all__ = ["DEMOS", "MEASURES", "DemoRun", "Measure", "measure_run", "parse_run_fields", "simulate"]

DEMOS = ("pinhole", "panoramic")
"""The demos a lesson can open."""

ESTIMATORS = {name: algorithm for algorithm, name in ESTIMATOR_NAMES.items()}
"""The pin-hole demo's F estimators by name (``true``: F from the poses) and the simulation's ``f_algorithm``."""

_SEED = Range(0, 2**32 - 1, "", integer=True)
_NOISE = Range(0.0, 50.0, "px")
_STEPS = SERVO_DEMO_STEPS
_BETA = Range(0.0, 100.0, "")
RUN_FIELDS: dict[str, tuple[str, ...]] = {
    "pinhole": ("seed", "noise_px", "steps", "beta", "estimator"),
    "panoramic": ("seed", "noise_px", "steps"),
}
"""The run fields each demo's *Run* folder has (the same limits as the demo's fields)."""
DEFAULT_STEPS = {"pinhole": 1000, "panoramic": 1500}
"""The demos' own default for ``steps`` (their *max steps* field)."""


@dataclass(frozen=True)
class DemoRun:
    """A servo demo with the run fields it opens with (``open_demo``); fields left out keep the demo's default."""

    demo: str
    run: tuple[tuple[str, Any], ...] = ()
    """``(field, value)`` pairs, sorted by field (fields of :data:`RUN_FIELDS` of the demo)."""

    def options(self) -> dict[str, Any]:
        """The demo's keyword options (``make_servo_demo(client, demo, **options)``)."""
        return dict(self.run)

    def simulation_kwargs(self) -> dict[str, Any]:
        """The keywords of the simulation the demo runs with these fields."""
        run = {"seed": 0, "noise_px": 0.0, "steps": DEFAULT_STEPS[self.demo], **dict(self.run)}
        if self.demo == "pinhole":
            run.setdefault("beta", 1.0)
            run["f_algorithm"] = ESTIMATORS[run.pop("estimator", "true")]
        return run

    def describe(self) -> str:
        """The fields as the learner sets them, e.g. ``seed 0, beta 0``."""
        shown = {"noise_px": "noise (px)", "steps": "max steps"}
        return ", ".join(f"{shown.get(k, k)} {v:g}" if not isinstance(v, str) else f"{k} {v}" for k, v in self.run)


def parse_run_fields(table: dict, demo: str) -> tuple[tuple[str, Any], ...]:
    """The run fields of ``table`` for ``demo`` (keys of :data:`RUN_FIELDS`), checked against the demo's limits.

    Raises:
        EntryError: naming the offending key.
    """
    out: dict[str, Any] = {}
    for key in RUN_FIELDS[demo]:
        if key not in table:
            continue
        if key == "seed":
            out[key] = fields.whole(table, key, _SEED)
        elif key == "steps":
            out[key] = fields.whole(table, key, _STEPS)
        elif key == "noise_px":
            out[key] = fields.number(table, key, _NOISE)
        elif key == "beta":
            out[key] = fields.number(table, key, _BETA)
        else:
            name = fields.text(table, key)
            if name not in ESTIMATORS:
                raise EntryError(key, f"expected one of {', '.join(ESTIMATORS)}, got {fields.short(name)}")
            out[key] = name
    return tuple(sorted(out.items()))


class _RunCache:
    """The newest runs simulated, at most ``samples`` samples in all (a 10,000-step run is about 8 MB)."""

    def __init__(self, samples: int) -> None:
        self.samples = samples
        self._runs: OrderedDict[DemoRun, ServoResult] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, run: DemoRun) -> ServoResult | None:
        with self._lock:
            result = self._runs.get(run)
            if result is not None:
                self._runs.move_to_end(run)
            return result

    def put(self, run: DemoRun, result: ServoResult) -> None:
        with self._lock:
            self._runs[run] = result
            self._runs.move_to_end(run)
            while len(self._runs) > 1 and sum(r.n_samples for r in self._runs.values()) > self.samples:
                self._runs.popitem(last=False)

    def clear(self) -> None:
        with self._lock:
            self._runs.clear()


_RUNS = _RunCache(SERVO_SERVER_FRAMES)


def simulate(run: DemoRun) -> ServoResult:
    """The run the demo shows for ``run`` (deterministic: the same keywords give the same result).

    The newest runs are kept, at most :data:`~egtviz.scene.limits.SERVO_SERVER_FRAMES` samples in all (the
    demos' frame budget): a run dropped from the cache is simulated again. ``simulate.cache_clear()`` empties it.
    """
    cached = _RUNS.get(run)
    if cached is not None:
        return cached
    kwargs = run.simulation_kwargs()
    result = simulate_pinhole(**kwargs) if run.demo == "pinhole" else simulate_panoramic(**kwargs)
    _RUNS.put(run, result)
    return result


simulate.cache_clear = _RUNS.clear  # type: ignore[attr-defined]  # as functools' caches offer


def _first_time(result: ServoResult, below: np.ndarray) -> float:
    hits = np.flatnonzero(below)
    return float(result.time[hits[0]]) if len(hits) else math.nan


@dataclass(frozen=True)
class Measure:
    """One number read off a run: its unit, whether it needs ``below`` (and in which unit), the demos it has."""

    unit: str
    of: Callable[[ServoResult, float], float]
    below_unit: str = ""
    """The unit of ``below`` ("" : the measure takes no ``below``)."""
    demos: tuple[str, ...] = DEMOS


def _phase_time(result: ServoResult, below: float) -> float:
    phase = result.extras.get("phase")
    return math.nan if phase is None else _first_time(result, np.asarray(phase) == 2)


MEASURES: dict[str, Measure] = {
    "steps": Measure("steps", lambda r, _: float(r.steps)),
    "sim_time": Measure("s", lambda r, _: float(r.sim_time_s)),
    "rotation_below_time": Measure(
        "s", lambda r, b: _first_time(r, np.degrees(r.errors["rotation_error_rad"]) < b), below_unit="deg"),
    "translation_below_time": Measure(
        "s", lambda r, b: _first_time(r, 100.0 * r.errors["translation_error"] < b), below_unit="cm"),
    "initial_rotation_error": Measure("deg", lambda r, _: math.degrees(r.initial_rotation_error_rad)),
    "final_rotation_error": Measure("deg", lambda r, _: math.degrees(r.final_rotation_error_rad)),
    "initial_translation_error": Measure("cm", lambda r, _: 100.0 * r.initial_translation_error),
    "final_translation_error": Measure("cm", lambda r, _: 100.0 * r.final_translation_error),
    "translation_phase_time": Measure("s", _phase_time, demos=("panoramic",)),
}
"""Every measure by name (see the module docstring)."""


def measure_run(run: DemoRun, measure: str, below: float = math.nan) -> float:
    """``measure`` of the simulated ``run`` (NaN: the run never gets there, e.g. never below ``below``)."""
    return float(MEASURES[measure].of(simulate(run), below))
