"""Starting the viewer's server in this process: the address checked before viser starts (viser would retry an
unusable one forever: the host is resolved with a time limit and a socket is bound to it), the URLs it is reached
under, then viser, the guards of :mod:`egtviz.viewer.server.guard` and the app.

Both ``egtviz serve`` (:mod:`.cli`) and each worker of ``egtviz serve --workers N`` (:mod:`.workers`) start their
server here.
"""

from __future__ import annotations

import dataclasses
import errno
import ipaddress
import signal
import socket
import threading
from pathlib import Path

from ...scene import scene_from_argument

__all__ = ["BindCheck", "RESOLVE_TIMEOUT", "ServeAddressError", "check_bind", "could_be_host", "is_wildcard",
           "reachable_urls", "start", "student_url", "terminate_as_interrupt"]

#: Seconds allowed for resolving ``--host`` (a name server that never answers must not hang the command).
RESOLVE_TIMEOUT = 3.0

#: ``egtviz serve --scene NAME_OR_FILE`` reads scenes through the scene package's one reader.


class ServeAddressError(OSError):
    """``--host``/``--port`` cannot be used; the message is one line naming the option and the reason."""


@dataclasses.dataclass(frozen=True)
class BindCheck:
    """The result of :func:`check_bind`.

    Attributes:
        addresses: the socket addresses ``host`` resolved to (IPv4 and/or IPv6 literals).
        port_busy: ``port`` is taken on one of them (viser then uses the next free port).
    """

    addresses: tuple[str, ...]
    port_busy: bool


def could_be_host(host: object) -> bool:
    """``host`` is text a host name or an address could be (the resolver judges the rest)."""
    # No name or address holds a control character; refused here, one shown on a terminal could move its
    # cursor or change its colours (repr writes it out).
    return isinstance(host, str) and bool(host.strip()) and host.isprintable()


def _resolve(host: str, port: int, timeout: float) -> list[tuple]:
    """``socket.getaddrinfo`` for a passive TCP socket, given up after ``timeout`` seconds."""
    result: list = []
    failure: list[BaseException] = []

    def lookup() -> None:
        try:
            result.extend(socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE))
        except (OSError, UnicodeError) as exc:
            failure.append(exc)

    # getaddrinfo has no timeout of its own; a daemon thread left waiting costs nothing at exit.
    worker = threading.Thread(target=lookup, daemon=True, name="egtviz-resolve")
    worker.start()
    worker.join(timeout)
    if worker.is_alive():
        raise ServeAddressError(f"cannot use --host {host}: no answer from the name resolver in {timeout:g} s")
    if failure or not result:
        reason = getattr(failure[0], "strerror", None) or str(failure[0]) if failure else "no address"
        raise ServeAddressError(f"cannot use --host {host}: {reason}")
    return result


def check_bind(host: str, port: int, *, timeout: float = RESOLVE_TIMEOUT) -> BindCheck:
    """Check that the server can listen on ``host:port`` before starting it.

    ``host`` is resolved (at most ``timeout`` seconds) and a socket is bound to every address it
    names, as the server will do. A port in use is not an error (the server takes the next free one).

    Raises:
        ServeAddressError: ``port`` is outside 0..65535, ``host`` does not resolve, or it is not an
            address of this machine (e.g. ``8.8.8.8``), or binding is not permitted; one line.
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ServeAddressError(f"cannot use --port {port!r}: expected an integer 0..65535")
    if not could_be_host(host):
        raise ServeAddressError(f"cannot use --host {host!r}: expected a host name or an IP address")
    busy = False
    addresses = []
    for family, kind, proto, _name, sockaddr in _resolve(host, port, timeout):
        addresses.append(sockaddr[0])
        with socket.socket(family, kind, proto) as sock:
            # As asyncio's server does, so that a port left in TIME_WAIT does not count as busy.
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6:
                sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            try:
                sock.bind(sockaddr)
            except OSError as exc:
                if exc.errno == errno.EADDRINUSE:
                    busy = True
                    continue
                if exc.errno == errno.EADDRNOTAVAIL:
                    raise ServeAddressError(f"cannot use --host {host}: {sockaddr[0]} is not an address of this "
                                            "machine") from None
                raise ServeAddressError(f"cannot use --host {host} --port {port}: {exc.strerror or exc}") from None
    return BindCheck(tuple(dict.fromkeys(addresses)), busy)


def is_wildcard(host: str) -> bool:
    try:
        return ipaddress.ip_address(host.strip("[]")).is_unspecified
    except ValueError:
        return False


def _url(address: str, port: int) -> str:
    return f"http://[{address}]:{port}" if ":" in address else f"http://{address}:{port}"


def reachable_urls(host: str, port: int) -> list[str]:
    """The URLs under which this machine serves ``host:port``; for a wildcard host, every local address.

    Local addresses come from resolving this machine's own name and from the routing table (a UDP
    socket *connected* to a public address picks the outgoing interface; no packet is sent).
    Loopback comes first.
    """
    if not is_wildcard(host):
        return [_url(host.strip("[]"), port)]
    want = socket.AF_INET6 if ":" in host else socket.AF_INET
    found: list[str] = []
    try:
        found += [str(ai[4][0]) for ai in socket.getaddrinfo(socket.gethostname(), None, type=socket.SOCK_STREAM)]
    except OSError:
        pass
    for family, probe in ((socket.AF_INET, "192.0.2.1"), (socket.AF_INET6, "2001:db8::1")):
        try:
            with socket.socket(family, socket.SOCK_DGRAM) as s:
                s.connect((probe, 9))
                found.append(s.getsockname()[0])
        except OSError:
            pass
    out = ["::1" if want == socket.AF_INET6 else "127.0.0.1"]
    for address in found:
        try:
            ip = ipaddress.ip_address(address.split("%")[0])
        except ValueError:
            continue
        usable = not (ip.is_loopback or ip.is_unspecified or ip.is_link_local)
        # The server's IPv6 socket is IPv6-only (asyncio sets IPV6_V6ONLY), so "::" serves no IPv4 address.
        if usable and ip.version == (6 if want == socket.AF_INET6 else 4) and address not in out:
            out.append(address)
    return [_url(a, port) for a in out]


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def terminate_as_interrupt() -> None:
    """Make SIGTERM (a service manager's stop, ``kill``) end the server as Ctrl-C does: tabs closed, the class
    closed, ``egtviz: stopped`` printed. Only the main thread can install a handler; elsewhere this does nothing."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _interrupt)


def start(host: str = "127.0.0.1", port: int = 8080, scene_path: str | Path | None = None, *, verbose: bool = False,
          demo: str | None = None, present: bool = False, lesson: str | None = None, course: bool = False,
          allow_hosts: tuple[str, ...] = (), classroom: bool = False):
    """Start a server and the app without blocking; returns ``(server, app)``.

    ``course``: every new tab opens the course's start page; ``lesson``: every new tab opens that lesson.
    ``classroom``: a class is taught (``app.classroom``, :class:`egtviz.viewer.classroom.ClassroomHost`).
    ``allow_hosts``: names a proxy reaches the page under, with those of ``EGTVIZ_ALLOWED_HOSTS``
    (:func:`egtviz.viewer.server.guard.allowed_hosts`; a bad name raises ``ValueError``).

    The server gets the guards of :func:`egtviz.viewer.server.guard.install_guards` before any tab connects.

    Raises:
        SceneFileError: the scene file cannot be read (the message names the file and entry).
        LessonError: ``lesson`` is not one of the course's lessons.
        ServeAddressError: ``host``/``port`` cannot be used (see :func:`check_bind`).
        RuntimeError: the installed viser lacks a private name the guards use (the server is stopped again).
    """
    import viser

    from ..tabs import EgtvizApp
    from .guard import GuardLimits, allowed_hosts, install_guards

    limits = GuardLimits(allowed_hosts=allowed_hosts(allow_hosts))
    scene = scene_from_argument(str(scene_path)) if scene_path is not None else None
    if lesson is not None:
        from ...lessons import load

        load(lesson)  # before a server starts: LessonError names the lessons there are
    check_bind(host, port)
    server = viser.ViserServer(host=host, port=port, verbose=verbose)
    try:
        install_guards(server, limits)
        app = EgtvizApp(server, scene, demo=demo, present=present, course=course, lesson=lesson)
        if classroom:
            from ..classroom import ClassroomHost

            ClassroomHost(app, student_url=student_url(host, server.get_port()))
    except BaseException:
        server.stop()
        raise
    return server, app



def student_url(host: str, port: int) -> str:
    """The URL students open: on a wildcard host the first address other computers can reach, else ``host``'s."""
    urls = reachable_urls(host, port)
    return urls[1] if len(urls) > 1 else urls[0]
