"""One visual-servoing demo in one tab, without a page: its run settings, its run and the playback of the run.

:class:`ServoController` owns what a servo demo's tab is: the run parameters (checked from the text typed in their
fields, :class:`~egtviz.controllers.servo_run.ServoRunSettings`), the last run's result and per-frame geometry (or
why there is none), the frame shown and whether it plays. It takes typed intents (``set_text("beta", "0.5")``,
``choose("estimator", "linear")``, ``run()``, ``play()``, ``pause()``, ``seek(k)``, ``step(n)``,
``seek_time(t)``) and exposes typed state (:attr:`~ServoController.values`, :attr:`~ServoController.result`,
:attr:`~ServoController.status`, :attr:`~ServoController.frame`, :attr:`~ServoController.playing`,
:meth:`~ServoController.image`), which the viewer's servo player (:mod:`egtviz.viewer.servo.servo_player`) draws.

A run reserves its frames from the server's budget (:mod:`egtviz.controllers.servo_budget`), simulates and derives
the frames. :meth:`ServoController.run` does it all in the caller's thread; a page runs the steps itself
(:meth:`~ServoController.start_run`, :meth:`~ServoController.reserve`, :func:`~egtviz.controllers.servo_run.compute_run`,
:meth:`~ServoController.land`) so that the simulation runs in a background thread and a newer run drops an older
one's outcome. The controller takes no lock: its page calls it from one thread at a time.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..servo import ServoResult
from ..servo.frames import ServoFrames
from .servo_budget import SERVER_BUDGET, ServoBudget, ServoBusy
from .servo_demos import SERVO_MODELS, Progress, RunValue, ServoDemoModel, SimulationKwargs
from .servo_playback import advanced, checked_time, clip_frame, nearest_frame, run_dt
from .servo_run import ServoOutcome, ServoRunSettings, ServoStatus, compute_run, result_status

__all__ = ["NOT_CONVERGED_MESSAGE", "ServoController", "ServoFrameImage", "ServoRunTicket"]

#: The image's message at the last frame of a run that did not converge.
NOT_CONVERGED_MESSAGE = "did not converge (see the status on the left)"
#: The status line while a run is simulated.
SIMULATING = ServoStatus("running", "Simulating ...")


@dataclass(frozen=True)
class ServoRunTicket:
    """A run started by :meth:`ServoController.start_run`: its number (a newer run makes it stale) and the run
    values it simulates with."""

    number: int
    values: dict[str, RunValue]

    @property
    def steps(self) -> int:
        return int(self.values["steps"])


@dataclass(frozen=True)
class ServoFrameImage:
    """What the image plane shows at a frame (the page turns it into SVG).

    Attributes:
        frame: the frame's index.
        current, desired: (N, 2) the features and their goals, pixels.
        trails: (M, N, 2) the features' thinned trails up to the frame.
        lines: the frame's epipolar lines (pin-hole), clipped to the image.
        conics: per feature, the sampled arcs of its bi-conic (panoramic).
        epipoles: ``(label, pixel)`` of each epipole in the image.
        rim: the mirror's rim (``None``: no mirror).
        caption: the caption (the time, the panoramic law's step).
        message: what the image says instead of geometry ("" for none).
    """

    frame: int
    current: np.ndarray
    desired: np.ndarray
    trails: np.ndarray
    lines: np.ndarray | None
    conics: list[tuple[np.ndarray, ...]]
    epipoles: list[tuple[str, np.ndarray]]
    rim: np.ndarray | None
    caption: str
    message: str


class ServoController:
    """One servo demo in one tab: its run settings, its last run and the frame shown.

    Args:
        model: the demo (:class:`~egtviz.controllers.servo_demos.ServoDemoModel`), or its name (a key of
            :data:`~egtviz.controllers.servo_demos.SERVO_MODELS`).
        seed: start pose / noise seed.
        noise_px: image noise, pixels.
        steps: maximum number of simulation steps (``None``: the demo's ``DEFAULT_STEPS``).
        speed: playback speed, one of :data:`~egtviz.controllers.servo_demos.SPEEDS`.
        budget: the server's frame budget runs reserve from (:data:`~egtviz.controllers.servo_budget.SERVER_BUDGET`).
        owner: what holds the run's frames in ``budget`` (the page's demo; this controller by default).
        **params: the demo's own run parameters (its ``RULES`` and ``CHOICES``; by default its ``DEFAULTS``), e.g.
            ``beta``, ``estimator``.

    Raises:
        ValueError: an unknown demo, a parameter the demo does not have, or a value its rule or choices refuse.
    """

    def __init__(self, model: ServoDemoModel | str, *, seed: int = 0, noise_px: float = 0.0, steps: int | None = None,
                 speed: str = "1x", budget: ServoBudget | None = None, owner: object = None,
                 **params: object) -> None:
        if not isinstance(model, ServoDemoModel):
            cls = SERVO_MODELS.get(model) if isinstance(model, str) else None
            if cls is None:
                raise ValueError(f"kind: expected one of {', '.join(map(repr, SERVO_MODELS))}, got {model!r}")
            model = cls()
        self.model = model
        given = {"seed": seed, "noise_px": noise_px, "steps": model.DEFAULT_STEPS if steps is None else steps,
                 "speed": speed, **model.DEFAULTS, **params}
        #: The run parameters' last valid values and their checks.
        self.settings = ServoRunSettings(model, given)
        #: The server's frame budget the runs reserve from.
        self.budget = SERVER_BUDGET if budget is None else budget
        self._owner = self if owner is None else owner
        #: The last finished run (``None`` before the first one or after a failed one), and its per-frame geometry.
        self.result: ServoResult | None = None
        self.frames: ServoFrames | None = None
        #: The last error message of a run that raised (bad parameters), else "".
        self.error = ""
        #: The status line (``None`` before the first run).
        self.status: ServoStatus | None = None
        #: A run is being simulated (or waits for frames).
        self.running = False
        self._run_number = 0
        #: The frame shown (index into ``result.time``) and whether the playback runs.
        self.frame = 0
        self.playing = False

    # -- settings -----------------------------------------------------------------------

    @property
    def kind(self) -> str:
        return self.model.kind

    @property
    def values(self) -> dict[str, RunValue]:
        """The last valid value of every run field (what the next run uses)."""
        return self.settings.values

    def shown(self, key: str) -> str:
        """Run field ``key``'s value as its field shows it."""
        return self.settings.shown(key)

    def set_text(self, key: str, text: str) -> None:
        """Take the text typed in number field ``key``.

        Raises:
            FieldError: the text is refused (the message is for the user); the value stays the last valid one.
        """
        self.settings.set_text(key, text)

    def choose(self, key: str, option: str) -> None:
        """Take the option picked in drop-down ``key`` (``speed``, ``estimator``); refused as :meth:`set_text`."""
        self.settings.choose(key, option)

    def set_params(self, **params: object) -> None:
        """Set run parameters given in code; nothing changes if one is refused (``ValueError``)."""
        self.settings.set_params(**params)

    def params(self) -> SimulationKwargs:
        """The run parameters the next run uses (the keyword arguments of the simulation)."""
        return self.settings.params()

    # -- a run --------------------------------------------------------------------------

    def run(self, progress: Progress | None = None) -> ServoOutcome:
        """Reserve, simulate, derive and take a run in the caller's thread (``busy``: the budget refused it)."""
        ticket = self.start_run()
        if ticket is None:
            raise RuntimeError("a run is in progress")
        try:
            self.reserve(ticket)
        except ServoBusy as exc:
            self.refuse(ticket, str(exc))
            return ServoOutcome(busy=str(exc))
        outcome = compute_run(self.model, ticket.values, progress or (lambda step, steps: None), lambda: False)
        self.land(outcome)
        return outcome

    def start_run(self) -> ServoRunTicket | None:
        """Begin a run with the current values (the playback pauses); ``None`` if one is in progress."""
        if self.running:
            return None
        self.playing = False
        self.running = True
        self._run_number += 1
        self.status = SIMULATING
        return ServoRunTicket(self._run_number, dict(self.values))

    def is_current(self, ticket: ServoRunTicket) -> bool:
        """``ticket`` is the latest run (not replaced, not dropped)."""
        return ticket.number == self._run_number

    def drop_run(self) -> None:
        """The page closes: the run in progress is stale, its frames are free."""
        self.budget.release(self._owner)
        self._run_number += 1

    def reserve(self, ticket: ServoRunTicket, *, cancelled: Callable[[], bool] | None = None,
                waiting: Callable[[str], None] | None = None) -> None:
        """Hold the run's frames (``steps + 1``) in the server's budget, waiting in its queue if need be
        (``waiting`` gets the reason, in words).

        Raises:
            ServoBusy: the budget refused the run.
        """
        self.budget.reserve(self._owner, ticket.steps + 1, cancelled=cancelled,
                            waiting=None if waiting is None else lambda why: waiting(f"Queued: {why}"))

    def queued(self, text: str) -> None:
        """The run waits for frames: the status says why."""
        self.status = ServoStatus("warn", text)

    def simulating(self) -> None:
        """The run's frames are held: it simulates."""
        self.status = SIMULATING

    def refuse(self, ticket: ServoRunTicket, message: str) -> None:
        """The budget refused run ``ticket``: it ends, the status says why."""
        if self.is_current(ticket):
            self.running = False
            self.status = ServoStatus("warn", message)

    def land(self, outcome: ServoOutcome) -> None:
        """The run ended: take its result and frames at frame 0, or its error (its frames are freed)."""
        self.running = False
        self.result, self.frames = outcome.result, outcome.frames
        if outcome.result is None:
            self.budget.release(self._owner)
            self.error = outcome.error
            self.status = ServoStatus("error", outcome.error)
            return
        self.error = ""
        self.budget.shrink(self._owner, outcome.result.n_samples)
        self.status = result_status(outcome.result)
        self.frame = 0

    def time_span(self) -> tuple[float, float]:
        """``(t_end, dt)`` of the run: its last time (1 s for a single frame) and its time step."""
        r = self._run()
        t_end = float(r.time[-1]) if r.n_samples > 1 else 1.0
        return t_end, run_dt(r)

    # -- playback -----------------------------------------------------------------------

    @property
    def n_frames(self) -> int:
        return 0 if self.result is None else self.result.n_samples

    @property
    def time(self) -> float:
        """Simulated time of the frame shown."""
        return 0.0 if self.result is None else float(self.result.time[self.frame])

    def seek(self, frame: int) -> int | None:
        """Show frame ``frame`` (clipped to the run); the frame, or ``None`` without a run."""
        if self.result is None:
            return None
        self.frame = clip_frame(self.result, frame)
        return self.frame

    def step(self, n: int = 1) -> int | None:
        """Pause and move ``n`` frames (negative: back); the frame, or ``None`` without a run."""
        self.playing = False
        return self.seek(self.frame + n)

    def seek_time(self, t: float) -> int | None:
        """Show the frame at simulated time ``t`` (the nearest sample); the frame, or ``None`` without a run."""
        if self.result is None:
            return None
        self.frame = nearest_frame(self.result, t)
        return self.frame

    def frame_at(self, t: object) -> int | None:
        """The frame the scrubber's time ``t`` points at (nothing changes), ``None`` without a run.

        Raises:
            FieldError: ``t`` is not a finite number of seconds.
        """
        if self.result is None:
            return None
        return nearest_frame(self.result, checked_time(t))

    def play(self) -> int | None:
        """Play from the frame shown, or from the start if at the end: then the frame to show (0), else ``None``.
        Without a run, or while playing, nothing changes (see :attr:`playing`)."""
        if self.result is None or self.playing:
            return None
        self.playing = True
        if self.frame >= self.n_frames - 1:
            self.frame = 0
            return 0
        return None

    def pause(self) -> bool:
        """Stop the playback; whether it was playing."""
        was, self.playing = self.playing, False
        return was

    def advance(self, position: float, elapsed_s: float) -> tuple[float, int]:
        """The playing clock moved ``elapsed_s`` real seconds at the speed set: its new fractional frame and the
        frame to show (the playback stops at the last frame)."""
        position, k = advanced(self._run(), position, elapsed_s, self.settings.speed)
        if k >= self.n_frames - 1:
            self.playing = False
        return position, k

    # -- what a frame shows -------------------------------------------------------------

    def image(self, k: int) -> ServoFrameImage:
        """The image plane at frame ``k``: features, goals, trails and the frame's epipolar geometry."""
        r, frames = self._run(), self.frames
        if frames is None:
            raise RuntimeError("no frames: the run was not derived")
        g = frames.at(k)
        message = NOT_CONVERGED_MESSAGE if k == r.n_samples - 1 and not r.converged else g.message
        return ServoFrameImage(frame=k, current=r.features[k], desired=r.desired_features, trails=frames.trail(k),
                               lines=g.lines, conics=list(g.conics), epipoles=list(g.epipoles), rim=frames.rim,
                               caption=self.model.caption(r, k), message=message)

    def _run(self) -> ServoResult:
        if self.result is None:
            raise RuntimeError("no run yet")
        return self.result
