"""Waiting in tests for what a server, a subprocess or a browser does: for the event itself, never a fixed time.

A test waits for the event it needs (a printed line, a socket, a panel's revision, a notification) by polling
for it. The bound on that wait is only there so that a broken build fails instead of hanging: it is generous
(:data:`PATIENCE`, minutes) because a busy machine (a CI runner beside other jobs, two CPU hogs on two cores)
makes every step many times slower, and it says what it waited for when it runs out.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable

#: Seconds a test waits for an event before it fails (``EGTVIZ_TEST_PATIENCE`` overrides): minutes, not the
#: seconds an idle machine needs, so that a loaded machine is slow but green.
PATIENCE = float(os.environ.get("EGTVIZ_TEST_PATIENCE", "300"))

#: The same bound in milliseconds, as playwright's ``timeout=`` arguments take it.
PATIENCE_MS = PATIENCE * 1000.0


def wait_until(predicate: Callable[[], object], timeout: float = PATIENCE) -> bool:
    """Poll ``predicate`` until it is true or ``timeout`` seconds have passed; its last value, as a bool.

    Use it as ``assert wait_until(...)`` where the caller's assertion message says what was awaited, or
    :func:`wait_for`, which raises with that message itself.
    """
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return bool(predicate())


def wait_for(predicate: Callable[[], object], what: str, timeout: float = PATIENCE) -> None:
    """Poll ``predicate`` until it is true.

    Raises:
        AssertionError: naming ``what`` was awaited and for how long, when ``timeout`` seconds pass first.
    """
    if not wait_until(predicate, timeout):
        raise AssertionError(f"waited {timeout:.0f} s for {what}")
