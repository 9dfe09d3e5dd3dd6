"""The local egtviz server that shows the current figure, and the notebook check for inline display.

In a notebook the figure shows inline, in a frame. Its page is served on the kernel's machine at
``127.0.0.1``, which only a browser on that machine can reach; a Jupyter server with jupyter-server-proxy
(a JupyterHub's, say) forwards ``<base_url>/proxy/<port>/`` to that port, so there the frame uses that
path (:func:`notebook_url`), which the browser reaches wherever it runs.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
import os
import sys
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

__all__ = ["FigureServer", "figure_port", "figures_enabled", "in_jupyter", "jupyter_base_url", "notebook_url",
           "on_cell_end", "show_inline"]

#: The first port tried; the server takes the next free one above it when it is busy.
FIRST_PORT = 8080
#: ``EGTVIZ_FIGURE=off``: no server; figures are kept in memory only (headless scripts, tests).
ENV = "EGTVIZ_FIGURE"
#: ``EGTVIZ_FIGURE_PORT=N``: the port the figure server starts on (0: any free one) instead of :data:`FIRST_PORT`.
PORT_ENV = "EGTVIZ_FIGURE_PORT"
#: Height of the inline frame in a notebook (CSS pixels).
INLINE_HEIGHT = 640


def figures_enabled(environ: Mapping[str, str] = os.environ) -> bool:
    """False when ``EGTVIZ_FIGURE`` is ``off`` (or ``0``, ``false``, ``no``): figures stay in memory, no server
    starts (headless scripts; the test suite sets it for every test and the scripts it runs)."""
    value = environ.get(ENV)
    return value is None or value.strip().lower() not in ("off", "0", "false", "no")


def figure_port(port: int | None = None, environ: Mapping[str, str] = os.environ) -> int:
    """The port the figure server starts on: ``port`` if given, else ``EGTVIZ_FIGURE_PORT``, else
    :data:`FIRST_PORT`; a busy port makes the server take the next free one, and 0 any free one (what a shared
    machine, a JupyterHub node, wants: students' kernels never race for one port).

    Raises:
        ValueError: the port (or the variable, named) is not a whole number 0..65535.
    """
    if port is None:
        text = environ.get(PORT_ENV, "").strip()
        if not text:
            return FIRST_PORT
        if not text.isdigit() or int(text) > 65535:
            raise ValueError(f"{PORT_ENV}={text!r}: expected a port, a whole number 0..65535 (0: any free port)")
        return int(text)
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"port: expected a whole number 0..65535 (0: any free port), got {port!r}")
    return port


def in_jupyter(modules: Mapping[str, Any] = sys.modules) -> bool:
    """True inside a Jupyter kernel: IPython is imported and its shell has a kernel (a terminal IPython has none).

    Only modules already imported are looked at, so this never imports IPython.
    """
    ipython = modules.get("IPython")
    get_ipython = getattr(ipython, "get_ipython", None)
    if get_ipython is None:
        return False
    try:
        shell = get_ipython()
    except Exception:  # noqa: BLE001 - a broken or partial IPython is not a notebook
        return False
    return shell is not None and getattr(shell, "kernel", None) is not None


def _running_servers(environ: Mapping[str, str]) -> list[dict[str, Any]]:
    """What the Jupyter servers of this user wrote to their runtime folder (``jpserver-<pid>.json``: pid, port,
    base_url); the folder is Jupyter's (``JUPYTER_RUNTIME_DIR``), read without importing Jupyter."""
    try:
        from jupyter_core.paths import jupyter_runtime_dir

        folder = Path(environ.get("JUPYTER_RUNTIME_DIR") or jupyter_runtime_dir())
    except ImportError:
        return []
    found = []
    for path in sorted(folder.glob("jpserver-*.json")):
        try:
            info = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(info, dict):
            found.append(info)
    return found


def jupyter_base_url(environ: Mapping[str, str] = os.environ,
                     servers: Callable[[Mapping[str, str]], list[dict[str, Any]]] = _running_servers) -> str | None:
    """The base URL (a path, ``/`` or ``/user/name/``) of the Jupyter server this kernel runs under, if that server
    has jupyter-server-proxy; None otherwise (no Jupyter server, or no proxy in this environment).

    On a JupyterHub it is ``JUPYTERHUB_SERVICE_PREFIX``; elsewhere the server whose process started the kernel
    (``JPY_PARENT_PID``) is looked up among the running ones.
    """
    if importlib.util.find_spec("jupyter_server_proxy") is None:
        return None
    prefix = environ.get("JUPYTERHUB_SERVICE_PREFIX", "").strip()
    if prefix.startswith("/"):
        return prefix
    parent = environ.get("JPY_PARENT_PID", "").strip()
    if not parent.isdigit():
        return None
    for info in servers(environ):
        base = info.get("base_url")
        if str(info.get("pid")) == parent and isinstance(base, str) and base.startswith("/"):
            return base
    return None


def notebook_url(url: str, environ: Mapping[str, str] = os.environ,
                 servers: Callable[[Mapping[str, str]], list[dict[str, Any]]] = _running_servers) -> str:
    """The address a notebook's frame opens the figure page ``url`` (``http://127.0.0.1:<port>``) at: the
    kernel's Jupyter server's ``<base_url>/proxy/<port>/`` when it has jupyter-server-proxy (a path on the
    notebook's own site, which the browser reaches wherever it runs), else ``url`` itself."""
    port = urlsplit(url).port
    base = jupyter_base_url(environ, servers)
    if base is None or port is None:
        return url
    return f"{base.rstrip('/')}/proxy/{port}/"


def show_inline(url: str, modules: Mapping[str, Any] = sys.modules, environ: Mapping[str, str] = os.environ) -> Any:
    """Display the figure's page ``url`` in the notebook cell (an ``IPython.display.IFrame`` on
    :func:`notebook_url`); returns the frame."""
    display = modules["IPython"].display
    frame = display.IFrame(notebook_url(url, environ), width="100%", height=INLINE_HEIGHT)
    display.display(frame)
    return frame


def on_cell_end(callback: Any, modules: Mapping[str, Any] = sys.modules) -> bool:
    """Call ``callback`` after each notebook cell runs (IPython's ``post_run_cell`` event); True if registered.

    Only a kernel IPython already imported is used (as :func:`in_jupyter`); a shell without events is left alone.
    """
    try:
        shell = modules["IPython"].get_ipython()
        shell.events.register("post_run_cell", callback)
    except Exception:  # noqa: BLE001 - without the hook, the tabs still catch up on their own
        return False
    return True


class FigureServer:
    """An egtviz viewer on the loopback interface (``127.0.0.1``, on :func:`figure_port`).

    viser serves from its own daemon thread, so a script goes on while the page is open. Every tab shows
    the scene last given to :meth:`show`.
    """

    def __init__(self, port: int | None = None, *, viewer: tuple[Any, Any] | None = None) -> None:
        """Start the viewer on :func:`figure_port` ``(port)`` or the next free one; ``viewer``: an already started
        ``(server, app)`` pair instead (tests)."""
        if viewer is None:
            from ..viewer.server.launch import start
            from ..jupyter_proxy import hub_host_names

            port = figure_port(port)
            # viser prints a box with its address; the figure's own line (or the notebook's frame) gives the
            # address to open, which behind a hub is not the loopback one.
            with contextlib.redirect_stdout(io.StringIO()):
                # Behind a hub's proxy the page is reached under the hub's name (EGTVIZ_ALLOWED_HOSTS adds others).
                viewer = start("127.0.0.1", port, allow_hosts=hub_host_names())
        self.server, self.app = viewer
        self.url = f"http://127.0.0.1:{self.server.get_port()}"
        self._lock = threading.Lock()
        self._latest: Any = None
        self._given: set[int] = set()
        """The tabs :meth:`show` gave the latest scene to (or that opened on it)."""

    def show(self, scene: Any) -> None:
        """Show ``scene`` in every open tab and in tabs opened later."""
        with self._lock:
            given = set(self.app.views)  # before show_scene lists them: each of these is given the scene
            self._latest = scene
            self.app.show_scene(scene)
            self._given = given

    def catch_up(self) -> None:
        """Give the latest scene to a tab that opened while :meth:`show` ran (it started on the scene before)."""
        with self._lock:
            for client_id, view in list(self.app.views.items()):
                if client_id not in self._given:
                    if self._latest is not None and view.model.scene is not self._latest:
                        view.model.load_scene(self._latest)
                    self._given.add(client_id)

    def stop(self) -> None:
        self.server.stop()
