"""The instructor's secret token: checked in constant time, rate limited per peer, never logged in full.

A wrong token is refused with no detail. After :data:`MAX_FAILURES` wrong tries within :data:`WINDOW_S`
seconds a peer is refused for :data:`LOCKOUT_S` seconds, even with the right token, so the token cannot be
guessed at the speed of a network. Asking with no token at all (a student's URL) is not a try.
"""

from __future__ import annotations

import hmac
import logging
import re
import secrets
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable

__all__ = [
    "INSTRUCTOR_PATH", "LOCKOUT_S", "MAX_FAILURES", "MAX_PEERS", "WINDOW_S", "RedactingFilter", "TokenGuard",
    "redact", "redact_url",
]

MAX_FAILURES = 5
"""Wrong tries a peer may make within :data:`WINDOW_S` before it is locked out."""
WINDOW_S = 60.0
LOCKOUT_S = 60.0
MAX_PEERS = 4096
"""Peers whose wrong tries are remembered (the oldest is forgotten first), so a flood of peers cannot fill memory."""
MIN_TOKEN_LENGTH = 16
_SHOWN = 4
INSTRUCTOR_PATH = "/egtviz-instructor/"
"""The path under which the instructor's page takes its token (``/egtviz-instructor/<token>``): a query would
not reach the server, because viser's page opens its websocket on the page's URL without the query."""
_TOKEN_PARAMETER = re.compile(r"([?&;]token=|" + re.escape(INSTRUCTOR_PATH) + r")([^&#/?\s\"'<>]+)")


def redact(text: str, token: str) -> str:
    """``text`` with every occurrence of ``token`` replaced by its first four characters and ``…``."""
    if not token:
        return text
    return text.replace(token, token[:_SHOWN] + "…")


def redact_url(url: str, token: str) -> str:
    """``url`` (or a log line holding URLs) as a log may show it: ``token`` shortened wherever it occurs, and
    the value of every ``token=`` parameter and :data:`INSTRUCTOR_PATH` segment shortened even when it is not
    ``token`` (a guess is not logged either)."""
    return _TOKEN_PARAMETER.sub(_shorten_parameter, redact(url, token))


def _shorten_parameter(match: re.Match[str]) -> str:
    value = match.group(2)
    return match.group(1) + (value if len(value) <= _SHOWN + 1 and value.endswith("…") else value[:_SHOWN] + "…")


class RedactingFilter(logging.Filter):
    """A logging filter that writes every record's message with the token shortened (:func:`redact_url`);
    install it on the handlers of a server that logs request URLs."""

    def __init__(self, token: str) -> None:
        super().__init__()
        self._token = token

    def filter(self, record: logging.LogRecord) -> bool:
        try:
            message = record.getMessage()
        except Exception:  # a record whose arguments do not format: leave it to the handler to report
            return True
        shown = redact_url(message, self._token)
        if shown != message:
            record.msg, record.args = shown, None
        return True


class TokenGuard:
    """The instructor token and the record of wrong tries.

    Args:
        token: the secret (default ``secrets.token_urlsafe(24)``); at least :data:`MIN_TOKEN_LENGTH` characters.
        clock: seconds, monotonic (a test passes a fake one).

    Raises:
        ValueError: a token that is too short or not plain ASCII.
    """

    def __init__(self, token: str | None = None, *, clock: Callable[[], float] = time.monotonic) -> None:
        if token is None:
            token = secrets.token_urlsafe(24)
        if not isinstance(token, str) or len(token) < MIN_TOKEN_LENGTH or not token.isascii() \
                or not token.isprintable() or " " in token:
            raise ValueError(f"token: expected at least {MIN_TOKEN_LENGTH} printable ASCII characters without spaces")
        self._token = token
        self._clock = clock
        self._lock = threading.Lock()
        self._failures: OrderedDict[str, deque[float]] = OrderedDict()
        self._locked_until: dict[str, float] = {}

    @property
    def token(self) -> str:
        return self._token

    def __repr__(self) -> str:
        return f"TokenGuard(token={redact(self._token, self._token)!r})"

    def check(self, candidate: str | None, peer: str) -> bool:
        """Whether ``candidate`` is the token and ``peer`` (an address) is not locked out. No token (None or
        empty) is False and is not counted; a wrong one is counted against ``peer``."""
        now = self._clock()
        with self._lock:
            until = self._locked_until.get(peer)
            if until is not None:
                if now < until:
                    return False
                del self._locked_until[peer]
                self._failures.pop(peer, None)
            if not candidate or not isinstance(candidate, str):
                return False
            ok = hmac.compare_digest(candidate.encode("utf-8", "replace"), self._token.encode("ascii"))
            if not ok:
                self._fail(peer, now)
            return ok

    def locked_out(self, peer: str) -> bool:
        """Whether ``peer`` is refused at the moment whatever it sends."""
        with self._lock:
            until = self._locked_until.get(peer)
            return until is not None and self._clock() < until

    def _fail(self, peer: str, now: float) -> None:
        tries = self._failures.pop(peer, None) or deque()
        self._failures[peer] = tries  # most recent last: the oldest peer is forgotten first
        tries.append(now)
        while tries and tries[0] <= now - WINDOW_S:
            tries.popleft()
        if len(tries) >= MAX_FAILURES:
            self._locked_until[peer] = now + LOCKOUT_S
            tries.clear()
        while len(self._failures) > MAX_PEERS:
            old, _ = self._failures.popitem(last=False)
            if self._locked_until.get(old, now) <= now:
                self._locked_until.pop(old, None)
        if len(self._locked_until) > MAX_PEERS:
            for p in [p for p, t in self._locked_until.items() if t <= now]:
                del self._locked_until[p]
            while len(self._locked_until) > MAX_PEERS:
                del self._locked_until[next(iter(self._locked_until))]

    def redact(self, text: str) -> str:
        """:func:`redact` with this token."""
        return redact(text, self._token)

    def redact_url(self, url: str) -> str:
        """:func:`redact_url` with this token."""
        return redact_url(url, self._token)

    def log_filter(self) -> RedactingFilter:
        """A :class:`RedactingFilter` for this token."""
        return RedactingFilter(self._token)
