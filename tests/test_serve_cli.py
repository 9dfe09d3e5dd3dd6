"""``egtviz serve`` with addresses it cannot use, a wildcard host and a busy port (real subprocesses)."""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

from egtviz.viewer.server.cli import _port
from egtviz.viewer.server.launch import RESOLVE_TIMEOUT, ServeAddressError, check_bind, reachable_urls

from _subprocesses import Printed, run

EGTVIZ = [sys.executable, "-m", "egtviz.cli"]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONUNBUFFERED": "1", "COLUMNS": "120"}


def _timed(args: list[str], what: str) -> tuple[subprocess.CompletedProcess, float]:
    t0 = time.monotonic()
    done = run([*EGTVIZ, *args], what, env=_env())
    return done, time.monotonic() - t0


@pytest.mark.parametrize(("args", "named"), [
    (["--host", "8.8.8.8", "--port", "0"], "8.8.8.8"),  # not an address of this machine
    (["--host", "not-a-host", "--port", "0"], "not-a-host"),  # does not resolve
    (["--port", "99999"], "99999"),
    (["--port", "-5"], "-5"),
])
def test_unusable_address_is_one_line_and_exit_1(args, named):
    # What a start that gives up at once costs on this machine now (an argument refused before anything starts):
    # the process under test may take a few times as long, and the resolver its own time limit, not more.
    _, baseline = _timed(["--port", "70000"], "egtviz --port 70000 to exit (the baseline)")
    done, elapsed = _timed(["serve", *args], f"egtviz serve {' '.join(args)} to give up (before the fix it hung)")
    assert done.returncode == 1, (done.stdout, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert named in lines[0] and "Traceback" not in done.stderr
    assert done.stdout == ""
    assert elapsed < 5.0 * baseline + 2.0 * RESOLVE_TIMEOUT, (elapsed, baseline)  # it gives up, it does not retry


def test_top_level_options_are_checked_the_same_way():
    done = run([*EGTVIZ, "--port", "70000"], "egtviz --port 70000 to exit", env=_env())
    assert done.returncode == 1
    assert done.stderr.strip() == ("egtviz serve: argument --port: 70000 is not a port number "
                                   "(expected an integer 0..65535)")


def _serve_until_running(args: list[str], stop: signal.Signals = signal.SIGINT) -> tuple[str, str]:
    """Start ``egtviz serve``, wait for its "running at" line, stop it with ``stop`` (Ctrl-C); (stdout, stderr)."""
    proc = subprocess.Popen([*EGTVIZ, "serve", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_env())
    printed = Printed(proc)
    try:
        printed.wait_line("egtviz running at", f"egtviz serve {' '.join(args)} to say it is running")
        proc.send_signal(stop)
        out, err = printed.finish(f"egtviz serve to stop on {stop.name}")
        assert proc.returncode == 0, (out, err)
        return out, err
    finally:
        printed.kill()


def _running_line(stdout: str) -> str:
    return next(line for line in stdout.splitlines() if line.startswith("egtviz running at"))


def test_wildcard_host_prints_reachable_urls_and_a_warning():
    out, err = _serve_until_running(["--host", "0.0.0.0", "--port", "0"])
    line = _running_line(out)
    urls = line.removeprefix("egtviz running at ").split()
    assert urls and urls[0].startswith("http://127.0.0.1:")
    assert all("0.0.0.0" not in u for u in urls)
    port = int(urls[0].rsplit(":", 1)[1])
    assert port > 0 and all(u.endswith(f":{port}") for u in urls)
    assert "warning: --host 0.0.0.0 opens the app to the network" in err


def test_busy_port_is_reported_and_the_next_free_one_used():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        out, err = _serve_until_running(["--port", str(port)])
    assert f"port {port} is busy" in err
    served = int(_running_line(out).rsplit(":", 1)[1])
    assert served != port and served > 0


# -- the checks in-process ------------------------------------------------------------------------------------


def test_check_bind_accepts_loopback_and_reports_busy_ports():
    assert check_bind("127.0.0.1", 0).addresses == ("127.0.0.1",)
    assert check_bind("127.0.0.1", 0).port_busy is False
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        assert check_bind("127.0.0.1", taken.getsockname()[1]).port_busy is True


@pytest.mark.parametrize(("host", "port", "match"), [
    ("8.8.8.8", 0, "8.8.8.8 is not an address of this machine"),
    ("127.0.0.1", 65536, "expected an integer 0..65535"),
    ("127.0.0.1", True, "expected an integer 0..65535"),
    ("", 0, "expected a host name or an IP address"),
])
def test_check_bind_refuses_in_one_line(host, port, match):
    with pytest.raises(ServeAddressError, match=match) as info:
        check_bind(host, port)
    assert "\n" not in str(info.value)


def test_port_argument_type():
    assert _port("0") == 0 and _port("65535") == 65535
    for bad in ("-5", "65536", "80.5", "eighty", ""):
        with pytest.raises(argparse.ArgumentTypeError, match="expected an integer 0..65535"):
            _port(bad)


def test_reachable_urls():
    assert reachable_urls("127.0.0.1", 8080) == ["http://127.0.0.1:8080"]
    assert reachable_urls("::1", 8080) == ["http://[::1]:8080"]
    urls = reachable_urls("0.0.0.0", 8080)
    assert urls[0] == "http://127.0.0.1:8080"
    assert len(urls) == len(set(urls))
    assert all("0.0.0.0" not in u and u.endswith(":8080") and "[" not in u for u in urls)
    v6 = reachable_urls("::", 8080)
    assert v6[0] == "http://[::1]:8080" and all(u.startswith("http://[") for u in v6)


@pytest.mark.parametrize("args", [["--port", "0"], ["--port", "0", "--workers", "2"]], ids=["one", "workers"])
@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "terminate"])
def test_ctrl_c_and_a_service_managers_terminate_both_stop_the_server_and_say_so(args, stop):
    out, err = _serve_until_running(args, stop)
    assert "egtviz: stopped" in out.splitlines(), (out, err)
    assert "Traceback" not in err
