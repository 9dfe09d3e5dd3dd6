"""The run form of a servo demo: its settings fields and the Run action with its background thread.

:class:`ServoRunForm` draws the run parameters of its tab's :class:`~egtviz.controllers.servo.ServoController` (which
holds their last valid values and judges every text): the *Run* folder (seed, the demo's own fields, noise, max
steps, Run and a progress bar), the status line and every run field's handle (the *speed* drop-down too, which sits
in the *Playback* folder). A field's text is judged once the user stopped typing
(:class:`~egtviz.viewer.workbench.fields.Debouncer`); a refused value gets a notification and the field shows the last
valid one.

*Run* simulates in a background thread. The run first reserves its frames from the server-wide budget
(:mod:`egtviz.controllers.servo_budget`): it may wait in the queue (the status says so) or be refused (a notification);
when it ends, the form lands the outcome in the controller and tells its player (``land``) under the lock and, once
the lock is released, tells it a good run is there (``finished``). What the form asks of its player comes in one
:class:`RunHooks`. A run started after another replaces it: the stale thread's outcome is dropped.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from html import escape

import viser

from egtviz.controllers.servo import ServoController, ServoRunTicket
from egtviz.controllers.servo_budget import ServoBusy
from egtviz.controllers.servo_run import ServoOutcome, compute_run
from egtviz.scene.limits import SERVO_DEMO_STEPS
from egtviz.servo import ServoResult

from ..workbench.fields import Debouncer, on_event
from ..workbench.gui_text import set_value

__all__ = ["RunField", "RunHooks", "ServoRunForm", "notify_busy", "status_html"]

#: A run field's handle: a number's text field or a choice's drop-down.
RunField = viser.GuiTextHandle | viser.GuiDropdownHandle[str]

_STATUS_COLOURS = {"ok": "#1a7f37", "warn": "#b35900", "error": "#b00020", "running": "#555"}


def status_html(level: str, text: str) -> str:
    """The status line's HTML: ``text`` in the colour of ``level`` (``ok``, ``warn``, ``error``, ``running``)."""
    return (f'<div data-egtviz="servo-status" data-level="{level}" style="font-size:0.85em;'
            f'color:{_STATUS_COLOURS[level]};padding:2px 0"><b>{escape(text)}</b></div>')


def notify_busy(client: viser.ClientHandle, exc: ServoBusy) -> None:
    """Tell ``client``'s tab its run was refused (a yellow notification); a tab already gone is left alone."""
    try:
        client.add_notification("Server busy", str(exc), color="yellow", auto_close_seconds=8.0)
    except Exception:  # noqa: BLE001 - the client may be gone
        pass


@dataclass(frozen=True)
class RunHooks:
    """What a run form asks of its player.

    Attributes:
        report: tell the tab what went wrong (and show the last valid values).
        land: the controller took the run's outcome (called with the lock held, inside ``client.atomic()``):
            draw it, or its error.
        finished: a good run was drawn (called without the lock; listeners, autoplay).
        before_run: called with the lock held as a run starts (the player pauses its playback).
    """

    report: Callable[[BaseException], None]
    land: Callable[[], None]
    finished: Callable[[ServoResult], None]
    before_run: Callable[[], None]


class ServoRunForm:
    """The run fields of one demo in one tab and the Run action.

    Args:
        controller: the tab's demo (the run values, their checks, the run and its outcome).
        client: the tab.
        field_delay: seconds a run field must stay unchanged before it is judged (0: at once).
        lock: the player's lock.
        closed: set once the player closed.
        hooks: what the form asks of its player (:class:`RunHooks`).
    """

    def __init__(self, controller: ServoController, *, client: viser.ClientHandle, field_delay: float,
                 lock: threading.RLock, closed: threading.Event, hooks: RunHooks) -> None:
        self.controller, self.client, self.lock, self._closed = controller, client, lock, closed
        self._typing = Debouncer(field_delay)
        self._hooks = hooks
        self._syncing = False
        self._thread: threading.Thread | None = None
        #: The run fields by parameter name (numbers and drop-downs).
        self.fields: dict[str, RunField] = {}

    # -- GUI ----------------------------------------------------------------------------

    def add_number_field(self, key: str, label: str, hint: str) -> None:
        handle = self.client.gui.add_text(label, self.controller.shown(key), hint=hint)
        on_event(handle.on_update, lambda e: self._text_event(key, e.target.value), self._hooks.report)
        self.fields[key] = handle

    def add_choice_field(self, key: str, label: str, hint: str) -> None:
        handle = self.client.gui.add_dropdown(label, self.controller.model.CHOICES[key][1],
                                              initial_value=self.controller.shown(key), hint=hint)
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

    def show_status(self) -> None:
        """Show the controller's status line (see :func:`status_html`)."""
        status = self.controller.status
        if status is not None:
            self.status.content = status_html(status.level, status.text)

    def say(self, level: str, text: str) -> None:
        """Show ``text`` in the status line (see :func:`status_html`)."""
        self.status.content = status_html(level, text)

    # -- values -------------------------------------------------------------------------

    def _text_event(self, key: str, text: str) -> None:
        """A run field changed: judge its text once the user stopped typing (latest text wins)."""
        if self._syncing or self._closed.is_set():
            return

        def judge() -> None:
            try:
                with self.lock:
                    if self._syncing or self._closed.is_set():
                        return
                    self.controller.set_text(key, text)
            except Exception as exc:  # noqa: BLE001 - from a timer thread: no callback wrapper above us
                self._hooks.report(exc)

        self._typing.submit(key, judge)

    def _choice_event(self, key: str, value: str) -> None:
        with self.lock:
            if self._syncing or self._closed.is_set():
                return
            self.controller.choose(key, value)

    def sync(self) -> None:
        """Write the last valid run parameters into the fields (not user edits)."""
        self._syncing = True
        try:
            for key, handle in self.fields.items():
                set_value(handle, self.controller.shown(key))
        finally:
            self._syncing = False

    def set_params(self, **params: object) -> None:
        """Check every value first, then take them all (nothing changes if one is refused)."""
        with self.lock:
            self.controller.set_params(**params)
            self.sync()

    # -- the run ------------------------------------------------------------------------

    def run(self) -> bool:
        """Stop the playback (``before_run``) and simulate with the current values in a background thread;
        ``False`` if a run is in progress or the form closed."""
        with self.lock:
            if self._closed.is_set() or self.controller.running:
                return False
            self._hooks.before_run()
            ticket = self.controller.start_run()
            if ticket is None:
                return False
            self.btn_run.disabled = True
            # viser's _GuiInputHandle.value has a setter (it syncs the bar); mypy sees the props class's read-only one.
            self.progress.value = 0.0  # type: ignore[misc]
            self.progress.visible = True
            self.show_status()
        self._thread = threading.Thread(target=self._simulate, args=(ticket,), daemon=True,
                                        name=f"servo-sim-{self.controller.kind}")
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
            self.controller.drop_run()
            self._typing.close()
        return self._thread

    def _simulate(self, ticket: ServoRunTicket) -> None:
        stale = lambda: self._closed.is_set() or not self.controller.is_current(ticket)

        def progress(step: int, steps: int) -> None:
            if not stale():
                percent = float(min(100.0, 100.0 * step / max(steps, 1)))
                self.progress.value = percent  # type: ignore[misc]  # settable, as above

        try:
            self.controller.reserve(ticket, cancelled=stale,
                                    waiting=lambda why: self._tell(ticket, lambda: self.controller.queued(why)))
        except ServoBusy as exc:
            self._tell(ticket, lambda: self.controller.refuse(ticket, str(exc)))
            notify_busy(self.client, exc)
            return
        self._tell(ticket, self.controller.simulating)
        outcome = compute_run(self.controller.model, ticket.values, progress, stale)
        with self.lock:
            if stale():
                return
            with self.client.atomic():
                self.btn_run.disabled = False
                self.progress.visible = False
                self.controller.land(outcome)
                if outcome.result is None:
                    self.show_status()
                self._hooks.land()
            if outcome.result is None:
                self._notify_failed(outcome)
                return
        self._hooks.finished(outcome.result)

    def _notify_failed(self, outcome: ServoOutcome) -> None:
        try:
            self.client.add_notification("Servo run failed", outcome.error, color="red", auto_close_seconds=8.0)
        except Exception:  # noqa: BLE001 - the client may be gone
            pass

    def _tell(self, ticket: ServoRunTicket, change: Callable[[], None]) -> None:
        """Change the controller's status (``change``) and show it while run ``ticket`` is the tab's; a run that
        ended there (refused) frees the Run button."""
        with self.lock:
            if self._closed.is_set() or not self.controller.is_current(ticket):
                return
            change()
            self.show_status()
            if not self.controller.running:
                self.btn_run.disabled = False
                self.progress.visible = False
