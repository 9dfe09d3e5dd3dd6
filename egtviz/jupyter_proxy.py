"""egtviz as a jupyter-server-proxy application: on a JupyterHub, each user opens their own egtviz from the launcher.

``pyproject.toml`` registers :func:`setup_egtviz` under the ``jupyter_serverproxy_servers`` entry points; the
``hub`` extra installs jupyter-server and jupyter-server-proxy. The first request to ``<base_url>/egtviz/``
starts ``egtviz serve`` (the course's start page) on a free loopback port chosen by the proxy, which then
forwards that path prefix to it. ``docs/deploy.md`` has the hub's configuration. The proxy loads this module
inside every user's Jupyter server when that starts, so it imports only the standard library and egtviz's
layer-0 modules, never the viewer.

Two things the proxy does not do by itself, and what this module does about them:

* **The websocket under the named route.** viser's client builds its websocket URL from the page's URL with the
  trailing slash dropped: the page ``.../egtviz/`` connects to ``.../egtviz``, which jupyter-server-proxy answers
  with a redirect to ``.../egtviz/`` that browsers do not follow on a websocket. :func:`page_at_index` turns the
  page's answer at ``.../egtviz/`` into a redirect to ``.../egtviz/index.html``, the same page (viser serves its
  client under that name too), whose websocket URL ``.../egtviz/index.html`` is inside the proxied prefix (viser
  accepts a websocket on any path). The generic ``/proxy/<port>/`` route needs nothing: its pattern also takes
  ``/proxy/<port>`` without the slash.
* **The Origin guard.** The proxy forwards the browser's ``Host`` and ``Origin`` unchanged, so egtviz sees the
  hub's DNS name, which is not this machine's. :func:`hub_host_names` reads it from the environment JupyterHub
  gives a user's server (``JUPYTERHUB_PUBLIC_URL`` and the like), and the entry passes it as ``--allow-host``;
  ``EGTVIZ_ALLOWED_HOSTS`` (read by ``egtviz serve`` itself) adds names a hub does not announce. A page of any
  other site is still refused, by Jupyter's own origin check and by egtviz's.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from typing import Any
from urllib.parse import urlsplit

from .hosts import allowed_host
from .resources import shipped_folder

__all__ = ["ENTRY_NAME", "HUB_URL_VARIABLES", "hub_host_names", "icon_path", "page_at_index", "setup_egtviz"]

#: The proxy's route and the launcher's entry: ``<base_url>/egtviz/``.
ENTRY_NAME = "egtviz"
#: What JupyterHub puts in a user's server environment that names the hub as browsers reach it (URLs or names).
HUB_URL_VARIABLES = ("JUPYTERHUB_PUBLIC_URL", "JUPYTERHUB_PUBLIC_HUB_URL", "JUPYTERHUB_HOST")
#: Seconds the proxy waits for egtviz to answer after starting it (imports and the first lesson scan on a busy
#: node take a few seconds; the proxy's default is 5).
START_TIMEOUT = 60.0
#: The page viser serves at ``/`` under the name the redirect gives it.
INDEX = "index.html"


def hub_host_names(environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The host names of :data:`HUB_URL_VARIABLES` that are set (a URL or a bare name each), checked, each once.

    A value that names no usable host is left out: the hub then needs ``EGTVIZ_ALLOWED_HOSTS``.
    """
    env = os.environ if environ is None else environ
    names: list[str] = []
    for variable in HUB_URL_VARIABLES:
        value = env.get(variable, "").strip()
        if not value:
            continue
        try:
            host = urlsplit(value if "//" in value else "//" + value).hostname
            if host:
                names.append(allowed_host(host, what=variable))
        except ValueError:
            continue
    return tuple(dict.fromkeys(names))


def icon_path() -> str:
    """The launcher's icon (an SVG shipped with egtviz); ``""`` when missing, so that the launcher shows its default."""
    path = shipped_folder("assets") / "egtviz-icon.svg"
    return str(path) if path.is_file() else ""


def page_at_index(response: Any, request: Any, path: str) -> None:
    """jupyter-server-proxy ``rewrite_response``: the page at the route's root becomes a redirect to ``index.html``.

    Only a successful ``GET``/``HEAD`` of ``/`` is changed; the query (a classroom link's, say) is kept. The
    ``Location`` is relative, so the browser resolves it under whatever prefix it used and the proxy leaves it alone.

    Args:
        response: the proxy's ``RewritableResponse`` (its ``code``, ``headers`` and ``body`` are replaced).
        request: the browser's request (tornado's ``HTTPServerRequest``).
        path: the path sent to egtviz (``/`` for the route's root).
    """
    if path != "/" or request.method not in ("GET", "HEAD") or response.code != 200:
        return
    location = INDEX + (f"?{request.query}" if request.query else "")
    for header in ("Content-Type", "Content-Encoding", "Content-Length", "Etag", "Last-Modified"):
        if header in response.headers:
            del response.headers[header]
    response.headers["Location"] = location
    response.headers["Cache-Control"] = "no-store"
    response.code = 302
    response.body = b""


def setup_egtviz(environ: Mapping[str, str] | None = None) -> dict[str, Any]:
    """The ``jupyter_serverproxy_servers`` entry: how the proxy starts egtviz and shows it in the launcher.

    ``{port}`` is filled in by the proxy. egtviz listens on loopback only: the proxy is its one way in.
    """
    command = [sys.executable, "-m", "egtviz.cli", "serve", "--host", "127.0.0.1", "--port", "{port}"]
    for name in hub_host_names(environ):
        command += ["--allow-host", name]
    return {
        "command": command,
        "timeout": START_TIMEOUT,
        "absolute_url": False,
        "new_browser_tab": True,
        "rewrite_response": page_at_index,
        "launcher_entry": {"enabled": True, "title": "egtviz", "icon_path": icon_path()},
    }
