"""The playback clock of a servo demo: Play/Pause, steps and the time scrubber, and the thread that plays.

:class:`ServoClock` owns the *Playback* folder's buttons and time slider and the playback thread, which advances
the frame at the chosen speed (simulated seconds per real second). Which frame a button, the scrubber or the
running clock lands on, and whether the run plays, is the tab's :class:`~egtviz.controllers.servo.ServoController`'s;
the clock draws nothing: it asks its player to show the frame (``show(k)``, called with the lock held).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import viser

from egtviz.controllers.servo import ServoController

from ..workbench.fields import on_event

__all__ = ["FPS", "ServoClock"]

FPS = 15.0
"""Frames per real second the playback thread looks at the clock (and redraws when the frame changed)."""


class ServoClock:
    """Playback of one demo's run in one tab. Every method takes the player's lock.

    Args:
        controller: the tab's demo (the run played, the frame shown, playing or not, the speed).
        lock: the player's lock (one per tab; the clock's thread and the GUI callbacks share it).
        closed: set once the player closed; the clock then does nothing and its thread ends.
        show: draw frame ``k`` everywhere (called with the lock held).
        name: the playback thread's name.
    """

    def __init__(self, controller: ServoController, *, lock: threading.RLock, closed: threading.Event,
                 show: Callable[[int], None], name: str) -> None:
        self.controller = controller
        self.lock = lock
        self._closed = closed
        self._show = show
        self._name = name
        self._gen = 0
        self._thread: threading.Thread | None = None
        self._syncing = False

    # -- GUI ----------------------------------------------------------------------------

    def build(self, gui: viser.GuiApi, report: Callable[[BaseException], None],
              add_speed_field: Callable[[], None]) -> None:
        """Add the *Playback* folder: Play/Pause, step back/forward, the speed field (``add_speed_field``) and the
        time slider; whatever a callback raises goes to ``report`` (``fields.on_event``)."""
        self.folder = gui.add_folder("Playback", expand_by_default=True)
        with self.folder:
            self.btn_play = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY)
            on_event(self.btn_play.on_click, lambda _: self.toggle_play(), report)
            self.btn_step_back = gui.add_button("Step back", icon=viser.Icon.PLAYER_TRACK_PREV)
            on_event(self.btn_step_back.on_click, lambda _: self.step(-1), report)
            self.btn_step = gui.add_button("Step", icon=viser.Icon.PLAYER_TRACK_NEXT)
            on_event(self.btn_step.on_click, lambda _: self.step(1), report)
            add_speed_field()
            self.slider = gui.add_slider("time (s)", min=0.0, max=1.0, step=0.05, initial_value=0.0,
                                         hint="Drag to any time of the run.")
            on_event(self.slider.on_update, self._slider_event, report)

    def remove(self) -> None:
        """Take the *Playback* folder out of the tab (the player closes)."""
        self.folder.remove()

    def _set_slider(self, **values: float) -> None:
        """Write the slider's attributes without taking the write for the user's scrubbing."""
        self._syncing = True
        try:
            for key, value in values.items():
                setattr(self.slider, key, value)
        finally:
            self._syncing = False

    def rewind(self, t_end: float, dt: float) -> None:
        """A new run: the slider spans ``[0, t_end]`` (at least one step ``dt``) in steps of ``dt``, at 0."""
        self._set_slider(max=max(t_end, dt), step=dt, value=0.0)

    def show_time(self, t: float) -> None:
        """Put the slider at simulated time ``t`` (the frame drawn), within its range."""
        self._set_slider(value=float(min(t, self.slider.max)))

    def sync(self) -> None:
        """Show the time of the frame drawn in the slider again (after a refused value)."""
        shown_t = float(min(self.time, self.slider.max))
        if self.slider.value != shown_t:
            self._set_slider(value=shown_t)

    # -- what is shown ------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated time of the frame shown."""
        return self.controller.time

    @property
    def thread(self) -> threading.Thread | None:
        """The playback thread last started (``None`` before the first Play)."""
        return self._thread

    # -- control ------------------------------------------------------------------------

    def play(self) -> None:
        """Play from the current frame (from the start if at the end)."""
        with self.lock:
            if self._closed.is_set() or self.controller.playing:
                return
            rewound = self.controller.play()
            if not self.controller.playing:
                return  # no run to play
            if rewound is not None:
                self._show(rewound)
            self._gen += 1
            gen = self._gen
            self.btn_play.label = "Pause"
            self.btn_play.icon = viser.Icon.PLAYER_PAUSE
        self._thread = threading.Thread(target=self._loop, args=(gen,), daemon=True, name=self._name)
        self._thread.start()

    def pause(self) -> None:
        with self.lock:
            self._gen += 1
            if self.controller.pause() and not self._closed.is_set():
                self.btn_play.label = "Play"
                self.btn_play.icon = viser.Icon.PLAYER_PLAY

    def halt(self) -> None:
        """Stop the playback thread for good (the player closes; the buttons are left as they are)."""
        with self.lock:
            self._gen += 1
            self.controller.pause()

    def toggle_play(self) -> None:
        with self.lock:
            if self.controller.playing:
                self.pause()
            else:
                self.play()

    def step(self, n: int = 1) -> None:
        """Pause and move ``n`` frames (negative: back)."""
        with self.lock:
            self.pause()
            k = self.controller.step(n)
            if k is not None:
                self._show(k)

    def seek(self, frame: int) -> None:
        """Show frame ``frame`` (clipped to the run)."""
        with self.lock:
            k = self.controller.seek(frame)
            if k is not None:
                self._show(k)

    def seek_time(self, t: float) -> None:
        """Show the frame at simulated time ``t`` (the nearest sample)."""
        with self.lock:
            k = self.controller.seek_time(t)
            if k is not None:
                self._show(k)

    # -- the playback thread and the scrubber -------------------------------------------------

    def _loop(self, gen: int) -> None:
        t_last = time.perf_counter()
        with self.lock:
            pos = float(self.controller.frame)
        while not self._closed.wait(1.0 / FPS):
            with self.lock:
                if gen != self._gen or not self.controller.playing or self.controller.result is None:
                    return
                now = time.perf_counter()
                pos, k = self.controller.advance(pos, now - t_last)
                t_last = now
                if k != self.controller.frame:
                    self.controller.seek(k)
                    self._show(k)
                if not self.controller.playing:
                    self.btn_play.label = "Play"
                    self.btn_play.icon = viser.Icon.PLAYER_PLAY
                    return

    def _slider_event(self, event: viser.GuiEvent[viser.GuiSliderHandle[float]]) -> None:
        with self.lock:
            if self._syncing or self._closed.is_set():
                return
            k = self.controller.frame_at(self.slider.value)
            if k is None:
                return
            self.pause()
            if k != self.controller.frame:
                self.controller.seek(k)
                self._show(k)
