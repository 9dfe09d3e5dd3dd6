"""Issue 15's messages, by routes the first fixes did not cover: what a user typed is shown with its control
characters written out (a host name cannot move the terminal's cursor or change its colours)."""

from __future__ import annotations

import pytest

from egtviz.cli import main
from egtviz.viewer.server.cli import ServeAddressError, check_bind

ESCAPES = "\x1b[31mX\x07"
SHOWN = "'\\x1b[31mX\\x07': expected a host name or an IP address"


@pytest.mark.parametrize("argv", [
    ["serve", "--port", "0"],
    ["serve", "--port", "0", "--workers", "2"],
    ["lesson", "03-intrinsics", "--port", "0"],
], ids=["serve", "workers", "lesson"])
def test_a_host_with_escape_sequences_is_refused_with_them_written_out(capsys, argv):
    assert main([*argv, "--host", ESCAPES]) in (1, 2)
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\x07" not in err
    assert f"argument --host: {SHOWN}" in err


def test_check_bind_refuses_a_host_with_control_characters_before_resolving_it():
    with pytest.raises(ServeAddressError) as info:
        check_bind(ESCAPES, 0)
    assert str(info.value) == f"cannot use --host {SHOWN}"
