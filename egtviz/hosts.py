"""Names a page may be reached under through a proxy (a JupyterHub's), as the server's Origin guard compares them.

Layer 0 (standard library only), so that the JupyterHub entry point (:mod:`egtviz.jupyter_proxy`), which runs
inside every user's Jupyter server, checks names without importing the viewer. The guard
(:mod:`egtviz.viewer.server.guard`) uses these names; ``egtviz serve --allow-host NAME`` and
``EGTVIZ_ALLOWED_HOSTS`` give them.
"""

from __future__ import annotations

import ipaddress
import os
import re
from collections.abc import Iterable, Mapping

from .files import printable

__all__ = ["ALLOWED_HOSTS_ENV", "allowed_host", "allowed_hosts"]

#: Host names (comma-separated) under which the page may be reached besides this machine's own: a proxy's.
ALLOWED_HOSTS_ENV = "EGTVIZ_ALLOWED_HOSTS"
_DNS_LABEL = re.compile(r"[a-z0-9_](?:[a-z0-9_-]{0,61}[a-z0-9_])?\Z")


def allowed_host(text: str, *, what: str = "host") -> str:
    """One name under which the page may be reached, as the guard's ``origin_allowed`` compares it (lower case,
    no final dot).

    A DNS name (``hub.example.edu``; an international name in its ``xn--`` form) or an IP literal. Whatever
    else could be meant as a pattern or an origin is refused, since a wildcard would open the app to any page.

    Args:
        text: the name as given.
        what: where it came from, for the message (``--allow-host``, ``EGTVIZ_ALLOWED_HOSTS``).

    Raises:
        ValueError: a scheme, port, path, wildcard, space or empty name; one line naming it.
    """
    name = text.strip().lower().rstrip(".") if isinstance(text, str) else ""
    try:
        return str(ipaddress.ip_address(name[1:-1] if name.startswith("[") and name.endswith("]") else name))
    except ValueError:
        pass
    if not name or len(name) > 253 or not all(_DNS_LABEL.match(label) for label in name.split(".")):
        raise ValueError(f"{what}: '{printable(text)}' is not a host name (expected a name such as hub.example.edu, "
                         "without scheme, port, path or wildcard)")
    return name


def allowed_hosts(names: Iterable[str] = (), environ: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """The names of ``--allow-host`` and of ``EGTVIZ_ALLOWED_HOSTS`` (comma-separated), checked, each once, in order.

    Args:
        names: names given on the command line (or by a caller such as the JupyterHub entry point).
        environ: the environment (default: this process's).

    Raises:
        ValueError: a name that :func:`allowed_host` refuses, naming where it came from.
    """
    env = os.environ if environ is None else environ
    out = [allowed_host(n, what="--allow-host") for n in names]
    out += [allowed_host(n, what=ALLOWED_HOSTS_ENV) for n in env.get(ALLOWED_HOSTS_ENV, "").split(",") if n.strip()]
    return tuple(dict.fromkeys(out))
