"""Names a proxy reaches egtviz under (a JupyterHub's): ``--allow-host``, ``EGTVIZ_ALLOWED_HOSTS`` and the Origin guard.

A JupyterHub forwards the browser's ``Host`` and ``Origin`` unchanged, so behind ``hub.example.edu`` the guard sees
that name; before these options it refused every such handshake and nothing could allow it.
"""

from __future__ import annotations

import base64
import os
import socket
import sys

import pytest
import viser

from egtviz.viewer.server.launch import start
from egtviz.hosts import ALLOWED_HOSTS_ENV, allowed_host, allowed_hosts
from egtviz.viewer.server.guard import GuardLimits

from _subprocesses import run
from _waiting import PATIENCE

EGTVIZ = [sys.executable, "-m", "egtviz.cli"]


@pytest.mark.parametrize(("text", "name"), [
    ("hub.example.edu", "hub.example.edu"),
    ("HUB.Example.EDU.", "hub.example.edu"),
    ("  jupyter  ", "jupyter"),
    ("192.168.1.20", "192.168.1.20"),
    ("[::1]", "::1"),
    ("xn--bcher-kva.example", "xn--bcher-kva.example"),
])
def test_allowed_host_normalises_names_and_ip_literals(text, name):
    assert allowed_host(text) == name


@pytest.mark.parametrize("text", ["*", "*.example.edu", "https://hub.example.edu", "hub.example.edu:443",
                                  "hub.example.edu/user", "a b", "", ".", "-hub.example", "a" * 64 + ".edu"])
def test_allowed_host_refuses_patterns_origins_and_junk(text):
    with pytest.raises(ValueError, match="is not a host name"):
        allowed_host(text, what="--allow-host")


def test_allowed_hosts_joins_the_options_and_the_environment_once_each():
    env = {ALLOWED_HOSTS_ENV: " Hub.Example.edu , ,other.example"}
    assert allowed_hosts(["hub.example.edu", "cli.example"], env) == ("hub.example.edu", "cli.example",
                                                                      "other.example")
    assert allowed_hosts((), {}) == ()
    with pytest.raises(ValueError, match=f"^{ALLOWED_HOSTS_ENV}: '\\*' is not a host name"):
        allowed_hosts((), {ALLOWED_HOSTS_ENV: "ok.example,*"})


def test_guard_limits_refuse_a_wildcard_host():
    with pytest.raises(ValueError, match="allowed_hosts: '\\*' is not a host name"):
        GuardLimits(allowed_hosts=("*",))


def _handshake_status(port: int, host: str, origin: str) -> int:
    """The HTTP status of a websocket handshake sent to ``127.0.0.1:port`` with these ``Host`` and ``Origin``
    (as a proxy forwards a browser's: the connection is local, the headers are the hub's)."""
    key = base64.b64encode(os.urandom(16)).decode()
    request = (f"GET / HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nOrigin: {origin}\r\n"
               f"Sec-WebSocket-Protocol: viser-v{viser.__version__}\r\n\r\n")
    with socket.create_connection(("127.0.0.1", port), timeout=PATIENCE) as sock:  # waits for the server's answer
        sock.sendall(request.encode())
        status_line = sock.makefile("rb").readline().decode()
    return int(status_line.split()[1])


@pytest.fixture(scope="module")
def hub_server():
    env_before = os.environ.pop(ALLOWED_HOSTS_ENV, None)
    os.environ[ALLOWED_HOSTS_ENV] = "env.example"
    try:
        server, _app = start("127.0.0.1", 0, allow_hosts=("hub.example.edu",))
    finally:
        os.environ.pop(ALLOWED_HOSTS_ENV)
        if env_before is not None:
            os.environ[ALLOWED_HOSTS_ENV] = env_before
    try:
        yield server.get_port()
    finally:
        server.stop()


@pytest.mark.parametrize(("host", "origin", "status"), [
    ("hub.example.edu", "https://hub.example.edu", 101),  # the hub, from --allow-host (TLS ended at the hub)
    ("hub.example.edu:443", "https://hub.example.edu", 101),
    ("hub.example.edu:8443", "https://hub.example.edu", 403),  # another port of that name: another site
    ("env.example", "http://env.example", 101),  # from EGTVIZ_ALLOWED_HOSTS
    ("hub.example.edu:443", "https://evil.example", 403),  # a foreign page is still refused
    ("evil.example", "http://evil.example", 403),  # DNS rebinding: names agree, not allowed
    ("other.example.edu", "http://other.example.edu", 403),
])
def test_allowed_names_pass_the_origin_guard_and_others_do_not(hub_server, host, origin, status):
    assert _handshake_status(hub_server, host, origin) == status


def test_without_the_option_a_hub_name_is_refused():
    server, _app = start("127.0.0.1", 0)
    try:
        assert _handshake_status(server.get_port(), "hub.example.edu:443", "https://hub.example.edu") == 403
    finally:
        server.stop()


@pytest.mark.parametrize(("args", "env", "message"), [
    (["--allow-host", "*"], {}, "argument --allow-host: '*' is not a host name"),
    (["--allow-host", "https://hub.example.edu"], {}, "argument --allow-host: 'https://hub.example.edu' is not"),
    ([], {ALLOWED_HOSTS_ENV: "hub.example.edu:8000"}, f"egtviz: cannot use {ALLOWED_HOSTS_ENV}: "
                                                      "'hub.example.edu:8000' is not a host name"),
])
def test_a_bad_name_is_refused_before_serving_in_one_line_exit_2(args, env, message):
    done = run([*EGTVIZ, "serve", "--port", "0", *args], "egtviz serve to refuse the name and exit",
               env={**os.environ, **env})
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert message in done.stderr
    assert "Traceback" not in done.stderr and "running at" not in done.stdout
    if env:
        assert len(done.stderr.strip().splitlines()) == 1
