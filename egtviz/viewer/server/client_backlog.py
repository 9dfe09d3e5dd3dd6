"""Whether viser still holds messages for a tab that its event loop has not sent yet.

The classroom's sender asks before it shows a follower the room's newest frame: a tab whose last frame is still
waiting to be sent would only have it replaced (viser keeps the latest update of each element), so drawing it
again now is work thrown away, taken from the event loop that has to send it. The sender comes back to that tab
once it has been sent everything (and then shows it the newest frame).

viser has no public question for this. The private names read (viser 1.1.1): ``ClientHandle._websock_connection``
(whose ``get_message_buffer()`` is the tab's own buffer), and the buffer's ``message_counter`` (one more than the
last message pushed) and ``generator_cursors`` (the last message each connection's sender took). When any is
missing the answer is "nothing waits" (the sender then behaves as if this module did not exist);
:func:`missing_internals` says which, for a test to notice an upgrade.
"""

from __future__ import annotations

from typing import Any

__all__ = ["PRIVATE_NAMES", "missing_internals", "waiting"]

#: The private names read, from a viser client handle.
PRIVATE_NAMES = ("_websock_connection", "_websock_connection.get_message_buffer().message_counter",
                 "_websock_connection.get_message_buffer().generator_cursors")


def _buffer(client: Any) -> Any:
    conn = getattr(client, "_websock_connection", None)
    get = getattr(conn, "get_message_buffer", None)
    return get() if callable(get) else None


def missing_internals(client: Any) -> list[str]:
    """The names of :data:`PRIVATE_NAMES` that ``client`` (a viser client handle) lacks; empty when all exist."""
    buffer = _buffer(client)
    if buffer is None:
        return list(PRIVATE_NAMES)
    return [name for name, attr in zip(PRIVATE_NAMES[1:], ("message_counter", "generator_cursors"))
            if not hasattr(buffer, attr)]


def waiting(client: Any) -> bool:
    """True when messages pushed for ``client``'s tab have not been taken by its connection's sender yet."""
    buffer = _buffer(client)
    if buffer is None:
        return False
    try:
        taken = buffer.generator_cursors.get(client.client_id)
        return taken is not None and buffer.message_counter - 1 > taken
    except (AttributeError, TypeError):
        return False
