"""A call that must not block, made in a thread of its own so that a test fails, saying what blocked, instead of
hanging (a FIFO opened for reading with nobody writing, say); and threads joined with that same bound."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from _waiting import PATIENCE


def returns(call: Callable[[], Any], what: str) -> Any:
    """``call()``'s value (or its exception, raised here), once it returns.

    Raises:
        AssertionError: it had not returned within :data:`~_waiting.PATIENCE`, naming ``what`` was awaited.
    """
    result: list[Any] = []
    failure: list[BaseException] = []

    def run() -> None:
        try:
            result.append(call())
        except BaseException as exc:  # noqa: BLE001 - raised again in the test's thread
            failure.append(exc)

    thread = threading.Thread(target=run, daemon=True, name="egtviz-test-call")
    thread.start()
    thread.join(PATIENCE)
    if thread.is_alive():
        raise AssertionError(f"waited {PATIENCE:.0f} s for {what} (it blocks)")
    if failure:
        raise failure[0]
    return result[0]


def joined(thread: threading.Thread, what: str) -> None:
    """Wait for ``thread`` to end.

    Raises:
        AssertionError: it had not within :data:`~_waiting.PATIENCE`, naming ``what`` was awaited.
    """
    thread.join(PATIENCE)
    if thread.is_alive():
        raise AssertionError(f"waited {PATIENCE:.0f} s for {what}")
