"""egtviz behind jupyter-server-proxy, as on a JupyterHub: the launcher's path, the start page and a live panel.

A real ``jupyter server`` (loopback, a random port, a token, no browser, a temporary root) with
jupyter-server-proxy and egtviz's entry point. Chromium reaches it under the name ``hub.test`` (mapped to
127.0.0.1 by a resolver rule, no DNS), as students reach a hub by its DNS name: the proxy forwards that
``Host`` and ``Origin`` unchanged, and the server's environment announces the name as JupyterHub does
(``JUPYTERHUB_PUBLIC_URL``). Before this change the named route's page loaded but its websocket was answered
with a redirect, and the guard refused the hub's name: no panel ever appeared.
"""

from __future__ import annotations

import json
import os
import secrets
import socket
import subprocess
import sys
import time
import urllib.request

import pytest

from _waiting import PATIENCE, PATIENCE_MS, wait_for
from egtviz.viewer.server.browser import PANEL_SELECTOR, close_notifications, shared_chromium, wait_for_js

pytestmark = pytest.mark.browser
pytest.importorskip("jupyter_server_proxy", reason="the hub extra (pip install -e '.[test]' installs it)")

HUB_NAME = "hub.test"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def jupyter(tmp_path_factory):
    """``(base URL under the hub's name, token, runtime dir)`` of a running jupyter server; stopped afterwards."""
    root = tmp_path_factory.mktemp("hub")
    for sub in ("notebooks", "runtime", "config", "data", "egtviz"):
        (root / sub).mkdir()
    (root / "config" / "jupyter_server_config.json").write_text(json.dumps(
        # A loopback server answers only loopback Host names unless told the hub's (Jupyter's DNS-rebinding check).
        {"ServerApp": {"local_hostnames": ["localhost", HUB_NAME]}}))
    port, token = _free_port(), secrets.token_hex(16)
    env = {**os.environ, "JUPYTER_RUNTIME_DIR": str(root / "runtime"), "JUPYTER_CONFIG_DIR": str(root / "config"),
           "JUPYTER_DATA_DIR": str(root / "data"), "EGTVIZ_DATA_DIR": str(root / "egtviz"),
           "JUPYTERHUB_PUBLIC_URL": f"http://{HUB_NAME}:{port}/", "PYTHONUNBUFFERED": "1"}
    env.pop("EGTVIZ_ALLOWED_HOSTS", None)
    log = (root / "jupyter.log").open("w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "jupyter_server", "--ServerApp.ip=127.0.0.1", f"--ServerApp.port={port}",
         "--ServerApp.port_retries=0", f"--IdentityProvider.token={token}", "--ServerApp.open_browser=False",
         "--allow-root",  # CI runs as root
         f"--ServerApp.root_dir={root / 'notebooks'}"],
        stdout=log, stderr=subprocess.STDOUT, env=env)
    try:
        deadline = time.monotonic() + PATIENCE
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/status?token={token}", timeout=PATIENCE):
                    break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"waited {PATIENCE:.0f} s for the jupyter server to answer on port {port} "
                                       f"(exited: {proc.poll() is not None}):\n"
                                       + (root / "jupyter.log").read_text()[-3000:])
                time.sleep(0.1)
        yield f"http://{HUB_NAME}:{port}", token, root
    finally:
        proc.terminate()  # the proxy stops the egtviz it started when the server stops
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)
        log.close()


@pytest.fixture(scope="module")
def browser():
    """The test process's Chromium launched with the hub's name mapped to loopback (closed after this module)."""
    b = shared_chromium(timeout_ms=PATIENCE_MS, args=[f"--host-resolver-rules=MAP {HUB_NAME} 127.0.0.1"], quiet=True)
    yield b
    b.close()


def test_the_launcher_lists_egtviz_with_its_icon(jupyter):
    base, token, _root = jupyter
    port = base.rsplit(":", 1)[1]
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/server-proxy/servers-info?token={token}",
                                timeout=PATIENCE) as answer:
        servers = json.load(answer)["server_processes"]
    (entry,) = [s for s in servers if s["name"] == "egtviz"]
    assert entry["launcher_entry"]["title"] == "egtviz"
    assert entry["launcher_entry"]["path_info"] == "egtviz/"
    assert entry["launcher_entry"]["icon_url"]  # the SVG from assets/ is served to the launcher


def test_the_named_route_shows_the_start_page_and_a_live_image_panel(jupyter, browser):
    base, token, root = jupyter
    page = browser.new_page(viewport={"width": 1366, "height": 768})
    refused = []
    page.on("websocket", lambda ws: ws.on("socketerror", lambda e: refused.append(e)))
    page.goto(f"{base}/egtviz/?token={token}")
    page.get_by_role("button", name="Open the workbench").wait_for()
    # The page at the launcher's path is the same page under index.html, inside the proxied prefix.
    assert page.url.split("?")[0] == f"{base}/egtviz/index.html"
    assert page.locator('[data-egtviz="start-page"]').count() >= 1
    close_notifications(page)
    page.get_by_role("button", name="Open the workbench").click()
    wait_for_js(page,
                f"() => [...document.querySelectorAll('{PANEL_SELECTOR}')].filter("
                "s => s.querySelectorAll('[data-kind=\"point\"]').length > 0).length >= 2",
                "two image-plane panels with points")
    points = page.evaluate(
        f"() => [...document.querySelectorAll('{PANEL_SELECTOR}')].map("
        "s => s.querySelectorAll('[data-kind=\"point\"] circle, circle[data-kind=\"point\"]').length)")
    assert len(points) >= 2 and all(n > 0 for n in points), points
    assert refused == []
    assert "refused a websocket connection" not in (root / "jupyter.log").read_text()
    page.close()


def test_the_figure_of_a_notebook_shows_through_the_generic_route(jupyter, browser, monkeypatch):
    """An EGT figure's inline frame: ``<base_url>/proxy/<port>/`` of the kernel's server, not 127.0.0.1."""
    from egtviz.egt_figure._server import FigureServer, notebook_url

    base, token, root = jupyter
    port = int(base.rsplit(":", 1)[1])
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(root / "runtime"))
    monkeypatch.setenv("EGTVIZ_ALLOWED_HOSTS", HUB_NAME)
    server_pid = next(json.loads(p.read_text())["pid"] for p in (root / "runtime").glob("jpserver-*.json")
                      if json.loads(p.read_text())["port"] == port)
    figure = FigureServer(port=0)
    try:
        inline = notebook_url(figure.url, {"JPY_PARENT_PID": str(server_pid)})
        assert inline == f"/proxy/{figure.server.get_port()}/"
        page = browser.new_page(viewport={"width": 1366, "height": 768})
        page.goto(f"{base}{inline}?token={token}")
        wait_for_js(page, f"() => document.querySelectorAll('{PANEL_SELECTOR}').length >= 2",
                    "the figure's two image-plane panels")
        page.close()
    finally:
        figure.stop()


def _handshake(port: int, path: str, host: str, origin: str, cookie: str = "") -> tuple[int, str]:
    """A websocket handshake to the jupyter server on loopback, as a browser at ``origin`` asking for ``host``
    sends it: ``(HTTP status, then "open" or "closed")``: after a 101, whether the proxied socket stays open
    (a first frame that is not a close, or silence for :data:`PATIENCE`) or is closed (egtviz refused the proxy)."""
    import base64

    import viser

    key = base64.b64encode(os.urandom(16)).decode()
    request = (f"GET {path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\nOrigin: {origin}\r\n"
               + (f"Cookie: {cookie}\r\n" if cookie else "")
               + f"Sec-WebSocket-Protocol: viser-v{viser.__version__}\r\n\r\n")
    with socket.create_connection(("127.0.0.1", port), timeout=PATIENCE) as sock:
        sock.sendall(request.encode())
        reader = sock.makefile("rb")
        status = int(reader.readline().decode().split()[1])
        while reader.readline() not in (b"\r\n", b""):
            pass
        if status != 101:
            return status, "closed"
        # The server speaks first on a socket it keeps (viser sends the tab's state), and closes one it refuses.
        sock.settimeout(PATIENCE)
        try:
            first = reader.read(1)
        except TimeoutError:
            return status, "open"
        return status, "closed" if not first or first[0] & 0x0F == 0x8 else "open"


def test_through_the_proxy_the_hubs_own_page_connects_and_a_foreign_one_does_not(jupyter):
    base, token, root = jupyter
    port = int(base.rsplit(":", 1)[1])
    host = f"{HUB_NAME}:{port}"
    # A browser's session: the login cookie Jupyter sets on the first request with the token.
    login = urllib.request.Request(f"http://127.0.0.1:{port}/api/status?token={token}", headers={"Host": host})
    with urllib.request.urlopen(login, timeout=PATIENCE) as answer:
        cookie = "; ".join(c.split(";", 1)[0] for c in answer.headers.get_all("Set-Cookie"))
    page = "/egtviz/index.html"
    assert _handshake(port, page, host, f"http://{HUB_NAME}:{port}", cookie) == (101, "open")
    assert _handshake(port, page, host, "http://evil.example", cookie)[0] == 403  # Jupyter's origin check
    # A program holding the token passes Jupyter's origin check; egtviz's still refuses a foreign origin.
    assert _handshake(port, f"{page}?token={token}", host, f"http://{HUB_NAME}:{port}") == (101, "open")
    assert _handshake(port, f"{page}?token={token}", host, "http://evil.example") == (101, "closed")
    wait_for(lambda: "refused a websocket connection from origin 'http://evil.example'" in
             (root / "jupyter.log").read_text(), "egtviz's guard to report the refusal in the server's log")
