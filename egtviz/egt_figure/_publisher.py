"""The figure's way to the open tabs: one background thread pushes the latest state, a burst of drawings once.

A drawing call only records the figure's state (an immutable :class:`~egtviz.scene.Scene`) and returns; the
publisher's thread shows the newest recorded state in every open tab. States recorded while a push is under
way replace each other (the latest wins), so 300 drawings in a loop cost a handful of pushes whatever the
number of tabs. Between two pushes of a burst the thread rests :data:`REST_PER_PUSH` times as long as the last
push took: the script's own thread keeps most of the interpreter while tabs are open. :meth:`Publisher.flush`
waits until the tabs show the last state (the end of a script, :func:`egtviz.egt_figure.show`, a notebook
cell's end). A while after the last push the thread calls ``settle`` once (the figure server brings a tab that
opened during a push up to date).
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from typing import Any

__all__ = ["COALESCE_SECONDS", "MAX_REST_SECONDS", "REST_PER_PUSH", "SETTLE_SECONDS", "Publisher"]

#: How long the thread waits after the first new state before pushing, so a loop's drawings go out together.
COALESCE_SECONDS = 0.05
#: Rest between two pushes of a burst, in multiples of the last push's time: the push shares the interpreter
#: with the script while it runs, so the script keeps at least ``(1 + REST_PER_PUSH / 2) / (1 + REST_PER_PUSH)``
#: of it (5/6 with 2).
REST_PER_PUSH = 2.0
#: The longest rest between two pushes (a slow push with many tabs does not hold the next one back longer).
MAX_REST_SECONDS = 2.0
#: Seconds without a new state after a push before ``settle`` is called.
SETTLE_SECONDS = 0.5


class Publisher:
    """Shows the latest submitted state with ``show`` from one daemon thread (see the module docstring).

    Args:
        show: pushes one state to every open tab (called in the publisher's thread only).
        coalesce: seconds to wait after a new state before pushing it (:data:`COALESCE_SECONDS`).
        settle: called once in the publisher's thread when :data:`SETTLE_SECONDS` pass without a new state
            after a push.
    """

    def __init__(self, show: Callable[[Any], None], *, coalesce: float = COALESCE_SECONDS,
                 settle: Callable[[], None] | None = None) -> None:
        self._show = show
        self._settle = settle
        self._coalesce = coalesce
        self._cond = threading.Condition()
        self._pending: Any = None
        self._submitted = 0
        """Number of the newest submitted state."""
        self._shown = 0
        """Number of the newest state pushed (or failed to push)."""
        self._urgent = False
        self._closing = False
        self.pushes = 0
        """Pushes made so far."""
        self._thread = threading.Thread(target=self._run, name="egtviz-figure-publisher", daemon=True)
        self._thread.start()

    def submit(self, state: Any) -> None:
        """Record ``state`` as the one the tabs should show next; returns at once."""
        with self._cond:
            self._pending = state
            self._submitted += 1
            self._cond.notify_all()

    def flush(self, timeout: float | None = 30.0) -> bool:
        """Push the last submitted state now and wait until it is shown; True if it was within ``timeout``."""
        with self._cond:
            target = self._submitted
            self._urgent = True
            self._cond.notify_all()
            self._cond.wait_for(lambda: self._shown >= target or not self._thread.is_alive(), timeout)
            if self._shown >= self._submitted:
                self._urgent = False  # nothing left to hurry: the next burst is coalesced again
            return self._shown >= target

    def close(self, *, flush: bool = True, timeout: float = 10.0) -> None:
        """Stop the thread (after pushing the last state, with ``flush``)."""
        if flush:
            self.flush(timeout)
        with self._cond:
            self._closing = True
            self._cond.notify_all()
        if self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def _pause(self, seconds: float) -> None:
        """Wait ``seconds`` unless a flush or close asks for the state now (called holding the condition)."""
        self._cond.wait_for(lambda: self._urgent or self._closing, seconds)

    def _run(self) -> None:
        settled = True
        while True:
            with self._cond:
                arrived = self._cond.wait_for(lambda: self._pending is not None or self._closing,
                                              None if settled or self._settle is None else SETTLE_SECONDS)
                if self._closing and self._pending is None:
                    return
                if arrived:
                    self._pause(self._coalesce)
                    state, number = self._pending, self._submitted
                    self._pending = None
                    self._urgent = False
            if not arrived:
                settled = True
                self._call(self._settle)
                continue
            settled = False
            start = time.perf_counter()
            self._call(self._show, state)
            elapsed = time.perf_counter() - start
            with self._cond:
                self.pushes += 1
                self._shown = max(self._shown, number)
                self._cond.notify_all()
                if self._pending is not None:
                    self._pause(min(REST_PER_PUSH * elapsed, MAX_REST_SECONDS))

    @staticmethod
    def _call(fn: Callable[..., None] | None, *args: Any) -> None:
        try:
            if fn is not None:
                fn(*args)
        except Exception as exc:  # noqa: BLE001 - a tab that cannot be updated must not stop the figures
            print(f"egtviz figure: the browser tabs were not updated ({type(exc).__name__}: {exc})",
                  file=sys.stderr, flush=True)
