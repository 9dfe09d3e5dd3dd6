"""The run form of a servo demo: its settings fields, their checks and the Run action with its background thread.

:class:`ServoRunForm` holds the last valid value of every run parameter (:attr:`ServoRunForm.values`), the *Run*
folder (seed, the demo's own fields, noise, max steps, Run and a progress bar), the status line and every run
field's handle (the *speed* drop-down too, which sits in the *Playback* folder). A field's text is judged once the
user stopped typing (:class:`~egtviz.viewer.workbench.fields.Debouncer`); a refused value gets a notification and the field
shows the last valid one.

*Run* simulates in a background thread. The run first reserves its frames from the server-wide budget
(:mod:`egtviz.viewer.servo.servo_budget`): it may wait in the queue (the status says so) or be refused (a notification);
when it ends, the form hands the result or the error to its player (``land``) under the lock and, once the lock is
released, tells it a good run is there (``finished``). What the form asks of its player comes in one
:class:`RunHooks`. A run started after another replaces it: the stale thread's outcome is dropped.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from html import escape
from typing import Any

import numpy as np
import viser

from egtviz.scene.limits import SERVO_DEMO_STEPS
from egtviz.servo import ServoResult
from egtviz.servo.frames import ServoFrames

from ..workbench.fields import Debouncer, FieldError, NumberRule, format_number, on_event, parse_numbers
from ..workbench.gui_text import set_value
from .servo_budget import ServoBudget, ServoBusy, notify_busy

__all__ = ["Choice", "RunField", "RunHooks", "RunValue", "ServoRunForm", "SimulationKwargs", "status_html"]

#: A choice field: its label in messages and its options.
Choice = tuple[str, tuple[str, ...]]
#: A run parameter's last valid value: a number (whole for an integer rule) or one of a choice's options.
RunValue = int | float | str
#: A run field's handle: a number's text field or a choice's drop-down.
RunField = viser.GuiTextHandle | viser.GuiDropdownHandle[str]
#: The keyword arguments of a demo's simulation function; its own signature types them (they differ per demo).
SimulationKwargs = dict[str, Any]

_STATUS_COLOURS = {"ok": "#1a7f37", "warn": "#b35900", "error": "#b00020", "running": "#555"}


def status_html(level: str, text: str) -> str:
    """The status line's HTML: ``text`` in the colour of ``level`` (``ok``, ``warn``, ``error``, ``running``)."""
    return (f'<div data-egtviz="servo-status" data-level="{level}" style="font-size:0.85em;'
            f'color:{_STATUS_COLOURS[level]};padding:2px 0"><b>{escape(text)}</b></div>')


@dataclass(frozen=True)
class RunHooks:
    """What a run form asks of its player.

    Attributes:
        report: tell the tab what went wrong (and show the last valid values).
        kwargs: the demo's own simulation keywords from the run values (beside seed, noise and steps).
        simulate: run the simulation with the keywords of :meth:`ServoRunForm.params` and a ``progress(step, steps)``.
        derive: the run's per-frame geometry (``None`` if ``stop()`` became True).
        land: the run ended (called with the lock held, inside ``client.atomic()``): ``(result, frames, "")``, or
            ``(None, None, error)`` for a run that raised.
        finished: a good run was drawn (called without the lock; listeners, autoplay).
        before_run: called with the lock held as a run starts (the player pauses its playback).
    """

    report: Callable[[BaseException], None]
    kwargs: Callable[[dict[str, RunValue]], SimulationKwargs]
    simulate: Callable[[SimulationKwargs, Callable[[int, int], None]], ServoResult]
    derive: Callable[[ServoResult, Callable[[], bool]], ServoFrames | None]
    land: Callable[[ServoResult | None, ServoFrames | None, str], None]
    finished: Callable[[ServoResult], None]
    before_run: Callable[[], None]


class ServoRunForm:
    """The run parameters of one demo in one tab, their fields and the Run action.

    Args:
        owner: what holds the run's frames in ``budget`` (the player).
        client: the tab.
        kind: the demo's name (messages, the thread's name).
        rules: every numeric run parameter and what its field accepts.
        choices: every drop-down parameter: its label and options.
        given: the parameters' first values (checked here).
        field_delay: seconds a run field must stay unchanged before it is judged (0: at once).
        budget: the server's frame budget the runs reserve from.
        lock: the player's lock.
        closed: set once the player closed.
        hooks: what the form asks of its player (:class:`RunHooks`).

    Raises:
        ValueError: a parameter in ``given`` that ``rules`` and ``choices`` do not have, or a value they refuse.
    """

    def __init__(self, owner: object, *, client: viser.ClientHandle, kind: str, rules: dict[str, NumberRule],
                 choices: dict[str, Choice], given: dict[str, object], field_delay: float, budget: ServoBudget,
                 lock: threading.RLock, closed: threading.Event, hooks: RunHooks) -> None:
        self.kind, self.rules, self.choices = kind, rules, choices
        #: The last valid value of each run field (what Run uses), in the fields' units.
        self.values: dict[str, RunValue] = {key: self.checked(key, value) for key, value in given.items()}
        self._typing = Debouncer(field_delay)
        self._owner, self.client, self.budget, self.lock, self._closed = owner, client, budget, lock, closed
        self._hooks = hooks
        self._syncing = False
        self._gen = 0
        self._thread: threading.Thread | None = None
        self.running = False
        #: The last error message of a run that raised (bad parameters), else "".
        self.error = ""
        #: The run fields by parameter name (numbers and drop-downs).
        self.fields: dict[str, RunField] = {}

    # -- GUI ----------------------------------------------------------------------------

    def add_number_field(self, key: str, label: str, hint: str) -> None:
        handle = self.client.gui.add_text(label, self._shown(key), hint=hint)
        on_event(handle.on_update, lambda e: self._text_event(key, e.target.value), self._hooks.report)
        self.fields[key] = handle

    def add_choice_field(self, key: str, label: str, hint: str) -> None:
        handle = self.client.gui.add_dropdown(label, self.choices[key][1], initial_value=self._shown(key), hint=hint)
        on_event(handle.on_update, lambda e: self._choice_event(key, e.target.value), self._hooks.report)
        self.fields[key] = handle

    def build(self, add_demo_fields: Callable[[], None]) -> None:
        """Add the *Run* folder (the demo's own fields from ``add_demo_fields`` after the seed) and the status."""
        gui = self.client.gui
        self.folder = gui.add_folder("Run", expand_by_default=True)
        with self.folder:
            self.add_number_field("seed", "seed", "Draws the start pose and the image noise: a whole number >= 0.")
            add_demo_fields()
            self.add_number_field("noise_px", "noise (px)", "Standard deviation of the Gaussian pixel noise, >= 0.")
            self.add_number_field("steps", "max steps",
                                  f"{SERVO_DEMO_STEPS.low:g} to {SERVO_DEMO_STEPS.high:g}; the run stops earlier "
                                  "once the features reach their goal.")
            self.btn_run = gui.add_button("Run", icon=viser.Icon.PLAYER_PLAY)
            on_event(self.btn_run.on_click, lambda _: self.run(), self._hooks.report)
            self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        self.status = gui.add_html("")

    def remove(self) -> None:
        """Take the *Run* folder and the status line out of the tab (the player closes)."""
        self.folder.remove()
        self.status.remove()

    def say(self, level: str, text: str) -> None:
        """Show ``text`` in the status line (see :func:`status_html`)."""
        self.status.content = status_html(level, text)

    # -- values -------------------------------------------------------------------------

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
            raise ValueError(f"{key}: not a parameter of the {self.kind} demo")
        if isinstance(value, str):
            (number,) = parse_numbers(value, (rule,))
        elif isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise FieldError(f"{rule.label}: expected a number, got {type(value).__name__}")
        else:
            number = rule.check(float(value))
        return int(number) if rule.integer else float(number)

    def _text_event(self, key: str, text: str) -> None:
        """A run field changed: judge its text once the user stopped typing (latest text wins)."""
        if self._syncing or self._closed.is_set():
            return

        def judge() -> None:
            try:
                with self.lock:
                    if self._syncing or self._closed.is_set():
                        return
                    (value,) = parse_numbers(text, (self.rules[key],))
                    self.values[key] = int(value) if self.rules[key].integer else value
            except Exception as exc:  # noqa: BLE001 - from a timer thread: no callback wrapper above us
                self._hooks.report(exc)

        self._typing.submit(key, judge)

    def _choice_event(self, key: str, value: str) -> None:
        with self.lock:
            if self._syncing or self._closed.is_set():
                return
            self.values[key] = self.checked(key, value)  # a raw client can send any string

    def _shown(self, key: str) -> str:
        """The last valid value of ``key`` as its field shows it."""
        value = self.values[key]
        return value if isinstance(value, str) else format_number(value)

    def sync(self) -> None:
        """Write the last valid run parameters into the fields (not user edits)."""
        self._syncing = True
        try:
            for key, handle in self.fields.items():
                set_value(handle, self._shown(key))
        finally:
            self._syncing = False

    def set_params(self, **params: object) -> None:
        """Check every value first, then take them all (nothing changes if one is refused)."""
        new = dict(self.values)
        for key, value in params.items():
            new[key] = self.checked(key, value)
        with self.lock:
            self.values = new
            self.sync()

    def params(self) -> SimulationKwargs:
        """The run parameters the next run uses (the keyword arguments of the simulation)."""
        v = self.values
        return {"seed": int(v["seed"]), "noise_px": float(v["noise_px"]), "steps": int(v["steps"]),
                **self._hooks.kwargs(v)}

    # -- the run ------------------------------------------------------------------------

    def run(self) -> bool:
        """Stop the playback (``before_run``) and simulate with the current values in a background thread;
        ``False`` if a run is in progress or the form closed."""
        with self.lock:
            if self._closed.is_set() or self.running:
                return False
            self._hooks.before_run()
            self.running = True
            self._gen += 1
            gen = self._gen
            kw = self.params()
            self.btn_run.disabled = True
            # viser's _GuiInputHandle.value has a setter (it syncs the bar); mypy sees the props class's read-only one.
            self.progress.value = 0.0  # type: ignore[misc]
            self.progress.visible = True
            self.say("running", "Simulating ...")
        self._thread = threading.Thread(target=self._simulate, args=(gen, kw), daemon=True,
                                        name=f"servo-sim-{self.kind}")
        self._thread.start()
        return True

    def wait(self, timeout: float = 60.0) -> bool:
        """Block until no run is in progress; ``True`` if it finished in time."""
        t = self._thread
        if t is not None:
            t.join(timeout)
            return not t.is_alive()
        return True

    def cancel(self) -> threading.Thread | None:
        """The form closes: drop the run in progress, free the frames; the run's thread (to join) if any."""
        with self.lock:
            self.budget.release(self._owner)
            self._typing.close()
            self._gen += 1
        return self._thread

    def _simulate(self, gen: int, kw: SimulationKwargs) -> None:
        stale = lambda: self._closed.is_set() or gen != self._gen

        def progress(step: int, steps: int) -> None:
            if not stale():
                percent = float(min(100.0, 100.0 * step / max(steps, 1)))
                self.progress.value = percent  # type: ignore[misc]  # settable, as above

        try:
            self.budget.reserve(self._owner, kw["steps"] + 1, cancelled=stale,
                                waiting=lambda why: self._say(gen, "warn", f"Queued: {why}"))
        except ServoBusy as exc:
            self._say(gen, "warn", str(exc), running=False)
            notify_busy(self.client, exc)
            return
        self._say(gen, "running", "Simulating ...")
        result, frames, error = self._compute(kw, progress, stale)
        with self.lock:
            if stale():
                return
            self.running = False
            with self.client.atomic():
                self.btn_run.disabled = False
                self.progress.visible = False
                if result is None:
                    self.budget.release(self._owner)
                    self.error = error
                    self.say("error", error)
                    self._hooks.land(None, None, error)
                else:
                    self.error = ""
                    self.budget.shrink(self._owner, result.n_samples)
                    self._hooks.land(result, frames, "")
            if result is None:
                try:
                    self.client.add_notification("Servo run failed", error, color="red", auto_close_seconds=8.0)
                except Exception:  # noqa: BLE001 - the client may be gone
                    pass
                return
        self._hooks.finished(result)

    def _compute(self, kw: SimulationKwargs, progress: Callable[[int, int], None], stale: Callable[[], bool]
                 ) -> tuple[ServoResult | None, ServoFrames | None, str]:
        """``(result, frames, "")`` of the run, or ``(None, None, message)`` if it raised (said in words)."""
        try:
            result = self._hooks.simulate(kw, progress)
            return result, self._hooks.derive(result, stale), ""
        except (ValueError, TypeError) as exc:
            return None, None, f"Bad parameters: {exc}"
        except Exception as exc:  # noqa: BLE001 - shown in the UI, never a traceback
            return None, None, f"The simulation failed: {type(exc).__name__}: {exc}"

    def _say(self, gen: int, level: str, text: str, *, running: bool = True) -> None:
        """Show ``text`` in the status line while run ``gen`` is the tab's; ``running=False`` ends the run."""
        with self.lock:
            if self._closed.is_set() or gen != self._gen:
                return
            self.say(level, text)
            if not running:
                self.running = False
                self.btn_run.disabled = False
                self.progress.visible = False
