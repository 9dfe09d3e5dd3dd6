"""A servo demo's run without a page: its settings checked from typed text, and what a finished run says.

:class:`ServoRunSettings` holds the last valid value of every run parameter (:attr:`ServoRunSettings.values`) and
judges a field's text or choice by the demo's rules (:mod:`egtviz.controllers.workbench_fields`): a refused value
raises :class:`~egtviz.controllers.workbench_fields.FieldError` with the message the tab shows, and the value stays
the last valid one. :class:`ServoOutcome` is what a run ended with (its result and frames, or the error in words, or
the server's refusal), and :class:`ServoStatus` the status line it shows.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..servo import ServoResult
from ..servo.frames import ServoFrames
from .servo_demos import Progress, RunValue, ServoDemoModel, SimulationKwargs
from .workbench_fields import FieldError, format_number, parse_numbers

__all__ = ["ServoOutcome", "ServoRunSettings", "ServoStatus", "compute_run", "result_status"]


@dataclass(frozen=True)
class ServoStatus:
    """The status line of a demo: ``level`` (``ok``, ``warn``, ``error``, ``running``) and its text."""

    level: str
    text: str


@dataclass(frozen=True)
class ServoOutcome:
    """How a run ended: ``result`` and its ``frames``, or ``error`` in words (the run raised), or ``busy`` (the
    server's frame budget refused it; nothing was simulated)."""

    result: ServoResult | None = None
    frames: ServoFrames | None = None
    error: str = ""
    busy: str = ""


def result_status(result: ServoResult) -> ServoStatus:
    """The status line of a finished run: converged (with its errors) or why not."""
    if result.converged:
        return ServoStatus("ok", f"Converged in {result.sim_time_s:.2f} s ({result.steps} steps): rotation error "
                                 f"{math.degrees(result.final_rotation_error_rad):.3g} deg, translation error "
                                 f"{100 * result.final_translation_error:.3g} cm.")
    return ServoStatus("warn", f"Did not converge: {result.reason}")


def compute_run(model: ServoDemoModel, values: dict[str, RunValue], progress: Progress, stop: Callable[[], bool]
                ) -> ServoOutcome:
    """Simulate with the run ``values`` and derive the frames; a run that raises is said in words, never raised."""
    try:
        result = model.simulate(values, progress)
        return ServoOutcome(result=result, frames=model.derive(result, stop))
    except (ValueError, TypeError) as exc:
        return ServoOutcome(error=f"Bad parameters: {exc}")
    except Exception as exc:  # noqa: BLE001 - shown in the UI, never a traceback
        return ServoOutcome(error=f"The simulation failed: {type(exc).__name__}: {exc}")


class ServoRunSettings:
    """The run parameters of one demo: their last valid values and their checks.

    Args:
        model: the demo (its rules and choices, its simulation keywords).
        given: the parameters' first values (checked here).

    Raises:
        ValueError: a parameter in ``given`` that the demo does not have, or a value its rule or choices refuse.
    """

    def __init__(self, model: ServoDemoModel, given: dict[str, object]) -> None:
        self.model = model
        self.rules, self.choices = model.RULES, model.CHOICES
        #: The last valid value of each run field (what Run uses), in the fields' units.
        self.values: dict[str, RunValue] = {key: self.checked(key, value) for key, value in given.items()}

    def checked(self, key: str, value: object) -> RunValue:
        """A run parameter given in code (a number or a field's text, or a choice), checked by its rule."""
        if key in self.choices:
            label, options = self.choices[key]
            if not isinstance(value, str) or value not in options:
                shown = "".join(c if c.isprintable() else "?" for c in repr(value))[:40]
                raise FieldError(f"{label}: expected one of {', '.join(options)}, got {shown}")
            return value
        rule = self.rules.get(key)
        if rule is None:
            raise ValueError(f"{key}: not a parameter of the {self.model.kind} demo")
        if isinstance(value, str):
            (number,) = parse_numbers(value, (rule,))
        elif isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise FieldError(f"{rule.label}: expected a number, got {type(value).__name__}")
        else:
            number = rule.check(float(value))
        return int(number) if rule.integer else float(number)

    def set_text(self, key: str, text: str) -> None:
        """Take the text typed in number field ``key``, or raise its refusal (the value stays)."""
        rule = self.rules[key]
        (value,) = parse_numbers(text, (rule,))
        self.values[key] = int(value) if rule.integer else value

    def choose(self, key: str, option: str) -> None:
        """Take the option picked in drop-down ``key``, or raise its refusal (a raw client can send any string)."""
        self.values[key] = self.checked(key, option)

    def set_params(self, **params: object) -> None:
        """Check every value first, then take them all (nothing changes if one is refused)."""
        new = dict(self.values)
        for key, value in params.items():
            new[key] = self.checked(key, value)
        self.values = new

    def shown(self, key: str) -> str:
        """The last valid value of ``key`` as its field shows it."""
        value = self.values[key]
        return value if isinstance(value, str) else format_number(value)

    def params(self) -> SimulationKwargs:
        """The run parameters the next run uses (the keyword arguments of the simulation)."""
        return self.model.kwargs(self.values)

    @property
    def speed(self) -> float:
        """The playback speed, simulated seconds per real second."""
        return float(str(self.values["speed"]).rstrip("x"))
