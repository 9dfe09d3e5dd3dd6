"""The instructor token: none, wrong and right; the per-peer rate limit; redaction in logs."""

from __future__ import annotations

import pytest

from egtviz.classroom import Classroom, TokenGuard, redact, redact_url
from egtviz.classroom.tokens import LOCKOUT_S, MAX_FAILURES, MAX_PEERS, WINDOW_S

TOKEN = "s3cret-token-0123456789abcdef"


class Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_none_wrong_and_right():
    guard = TokenGuard(TOKEN, clock=Clock())
    assert guard.check(None, "1.2.3.4") is False
    assert guard.check("", "1.2.3.4") is False
    assert guard.check(TOKEN[:-1] + "x", "1.2.3.4") is False
    assert guard.check(TOKEN + "x", "1.2.3.4") is False
    assert guard.check(TOKEN[:-1], "1.2.3.4") is False
    assert guard.check(TOKEN, "1.2.3.4") is True


def test_non_ascii_candidate_is_refused_not_raised():
    guard = TokenGuard(TOKEN, clock=Clock())
    assert guard.check("é" * 29, "p") is False
    assert guard.check("\ud800", "p") is False


def test_a_random_token_is_long_and_differs_each_time():
    a, b = Classroom().instructor_token, Classroom().instructor_token
    assert a != b
    assert len(a) >= 32  # 24 random bytes in URL-safe base64


def test_a_short_token_is_refused():
    with pytest.raises(ValueError, match="at least 16"):
        TokenGuard("short")


def test_after_five_wrong_tries_the_peer_is_refused_even_with_the_right_token():
    clock = Clock()
    guard = TokenGuard(TOKEN, clock=clock)
    for _ in range(MAX_FAILURES):
        assert guard.check("wrong", "10.0.0.1") is False
    assert guard.locked_out("10.0.0.1")
    assert guard.check(TOKEN, "10.0.0.1") is False
    assert guard.check(TOKEN, "10.0.0.2") is True  # another peer is not affected
    clock.now += LOCKOUT_S - 1
    assert guard.check(TOKEN, "10.0.0.1") is False
    clock.now += 1.0
    assert guard.check(TOKEN, "10.0.0.1") is True


def test_wrong_tries_spread_past_the_window_do_not_lock_out():
    clock = Clock()
    guard = TokenGuard(TOKEN, clock=clock)
    for _ in range(3 * MAX_FAILURES):
        assert guard.check("wrong", "p") is False
        clock.now += WINDOW_S / (MAX_FAILURES - 1) + 0.1
    assert not guard.locked_out("p")
    assert guard.check(TOKEN, "p") is True


def test_no_token_is_not_counted_as_a_try():
    guard = TokenGuard(TOKEN, clock=Clock())
    for _ in range(3 * MAX_FAILURES):
        assert guard.check(None, "student") is False
    assert guard.check(TOKEN, "student") is True


def test_many_peers_keep_memory_bounded():
    guard = TokenGuard(TOKEN, clock=Clock())
    for i in range(MAX_PEERS + 500):
        guard.check("wrong", f"peer{i}")
    assert len(guard._failures) == MAX_PEERS  # noqa: SLF001 - the bound is the point of this test


def test_redact_keeps_four_characters():
    assert redact(f"GET /?token={TOKEN} 200", TOKEN) == "GET /?token=s3cr… 200"
    assert TOKEN not in redact(TOKEN + TOKEN, TOKEN)
    assert redact("no secret here", TOKEN) == "no secret here"


def test_redact_url_shortens_a_wrong_token_too():
    url = "http://host:8080/?token=guessguessguess&x=1"
    assert redact_url(url, TOKEN) == "http://host:8080/?token=gues…&x=1"
    assert redact_url(f"http://h/?token={TOKEN}", TOKEN) == "http://h/?token=s3cr…"


def test_classroom_token_methods():
    room = Classroom(token=TOKEN)
    assert room.instructor_token == TOKEN
    assert room.check_token(TOKEN, "a") and not room.check_token("nope", "a")
    assert room.redact_url(f"http://h/i?token={TOKEN}") == "http://h/i?token=s3cr…"
    assert TOKEN not in repr(room._guard)  # noqa: SLF001


def test_redact_url_in_a_log_line_with_several_urls():
    line = f'"GET /?token={TOKEN}&lesson=2 HTTP/1.1" from http://h/x;token=abcdefgh'
    assert redact_url(line, TOKEN) == '"GET /?token=s3cr…&lesson=2 HTTP/1.1" from http://h/x;token=abcd…'


def test_the_log_filter_shortens_the_token_in_formatted_records(caplog):
    import logging

    room = Classroom(token=TOKEN)
    log = logging.getLogger("egtviz.test.access")
    handler_filter = room.log_filter()
    caplog.handler.addFilter(handler_filter)
    try:
        with caplog.at_level(logging.INFO, logger="egtviz.test.access"):
            log.info("GET %s 101", f"/ws?token={TOKEN}")
            log.info("wrong try %s", "/?token=guessedvalue")
            log.info("plain %d", 5)
    finally:
        caplog.handler.removeFilter(handler_filter)
    assert [r.getMessage() for r in caplog.records] == ["GET /ws?token=s3cr… 101", "wrong try /?token=gues…",
                                                         "plain 5"]
    assert TOKEN not in caplog.text


def test_redact_url_shortens_a_token_in_the_instructor_path():
    assert redact_url(f"http://h:8080/egtviz-instructor/{TOKEN}", TOKEN) == "http://h:8080/egtviz-instructor/s3cr…"
    assert redact_url("GET /egtviz-instructor/wrongguess12/x?y=1", TOKEN) == "GET /egtviz-instructor/wron…/x?y=1"
