"""Subprocesses in tests, waited for by what they print or by their exit, never for a fixed time.

:func:`run` is ``subprocess.run`` with the generous :data:`~_waiting.PATIENCE` bound, failing with what it waited
for; :class:`Printed` reads a running process's stdout and stderr line by line in threads, so that a test waits for
the line it needs (``egtviz running at ...``) and still sees everything the process said when it does not come.
"""

from __future__ import annotations

import subprocess
import threading
from collections.abc import Sequence
from typing import IO, Any

from _waiting import PATIENCE, wait_until


def run(args: Sequence[str], what: str, **kwargs: Any) -> subprocess.CompletedProcess:
    """``subprocess.run(args, capture_output=True, text=True, **kwargs)``, waited for at most :data:`PATIENCE`.

    Raises:
        AssertionError: the process had not exited by then, naming ``what`` was awaited and what it printed.
    """
    kwargs.setdefault("capture_output", True)
    kwargs.setdefault("text", True)
    try:
        return subprocess.run(list(args), timeout=PATIENCE, **kwargs)
    except subprocess.TimeoutExpired as exc:
        raise AssertionError(f"waited {PATIENCE:.0f} s for {what}; it printed {exc.stdout!r} {exc.stderr!r}") from None


class Printed:
    """The stdout and stderr of ``proc`` (opened with ``text=True`` and both piped), read as it prints them."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.proc = proc
        self.out: list[str] = []
        self.err: list[str] = []
        self._readers = [threading.Thread(target=self._read, args=(stream, into), daemon=True)
                         for stream, into in ((proc.stdout, self.out), (proc.stderr, self.err))]
        for reader in self._readers:
            reader.start()

    @staticmethod
    def _read(stream: IO[str], into: list[str]) -> None:
        for line in iter(stream.readline, ""):
            into.append(line)

    def _ended(self) -> bool:
        return not any(reader.is_alive() for reader in self._readers)

    def said(self) -> str:
        """Everything printed so far, for a failure's message."""
        return f"stdout {''.join(self.out)!r}, stderr {''.join(self.err)!r}, exit code {self.proc.poll()}"

    def wait_line(self, wanted: str, what: str) -> str:
        """The first stdout line containing ``wanted``, once printed.

        Raises:
            AssertionError: the process ended without printing it, or did not within :data:`PATIENCE`; naming
                ``what`` was awaited, with what the process printed.
        """
        def found() -> str | None:
            return next((line for line in list(self.out) if wanted in line), None)

        if not wait_until(lambda: found() is not None or self._ended(), PATIENCE) or found() is None:
            raise AssertionError(f"waited for {what} ({wanted!r} on stdout); {self.said()}")
        line = found()
        assert line is not None
        return line

    def finish(self, what: str) -> tuple[str, str]:
        """Wait for the process to exit and its output to be read; ``(stdout, stderr)``.

        Raises:
            AssertionError: it had not exited within :data:`PATIENCE`, naming ``what`` was awaited.
        """
        try:
            self.proc.wait(PATIENCE)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"waited {PATIENCE:.0f} s for {what}; {self.said()}") from None
        for reader in self._readers:
            reader.join(PATIENCE)
        return "".join(self.out), "".join(self.err)

    def kill(self) -> None:
        """Kill the process if it still runs (a test's ``finally``)."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(PATIENCE)
