"""``egtviz serve``: start the viewer on a local port and block until Ctrl-C.

Before viser starts, the address is checked here (viser would retry an unusable one forever): the
host is resolved with a time limit and a socket is bound to it. What the server then refuses from
browsers is in :mod:`egtviz.viewer.server.guard`; both are described in ``docs/server.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import errno
import ipaddress
import signal
import socket
import sys
import threading
from pathlib import Path

from ...scene import scene_from_argument

__all__ = ["BindCheck", "ServeAddressError", "add_parser", "check_bind", "reachable_urls", "run", "serve", "start",
           "terminate_as_interrupt"]

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


def _port(text: str) -> int:
    """argparse type of ``--port``: an integer 0..65535."""
    try:
        value = int(text, 10)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (expected an integer 0..65535)") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"{value} is not a port number (expected an integer 0..65535)")
    return value


def _host(text: str) -> str:
    """argparse type of ``--host``: text a host name or an address could be (the resolver judges the rest)."""
    if not _could_be_host(text):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a host name or an IP address")
    return text


def _could_be_host(host: object) -> bool:
    # No name or address holds a control character; refused here, one shown on a terminal could move its
    # cursor or change its colours (repr writes it out).
    return isinstance(host, str) and bool(host.strip()) and host.isprintable()


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``serve`` sub-command on an ``argparse`` sub-parser set."""
    p = subparsers.add_parser("serve", help="start the interactive viewer in the browser",
                              description="Start the egtviz viewer (each browser tab gets its own scene). "
                              "See docs/server.md for what the server refuses from browsers.")
    add_arguments(p)
    _one_line_address_errors(p)
    p.set_defaults(func=run)
    return p


def _one_line_address_errors(parser: argparse.ArgumentParser) -> None:
    """A bad ``--host``/``--port`` is one line and exit status 1, like an unusable address found later."""
    usage_error = parser.error

    def error(message: str):  # noqa: ANN202 - argparse's signature
        if message.startswith(("argument --port", "argument --host")):
            print(f"egtviz serve: {message}", file=sys.stderr)
            raise SystemExit(1)
        usage_error(message)

    parser.error = error  # type: ignore[method-assign]


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--host", default="127.0.0.1", type=_host,
                   help="address to listen on (default 127.0.0.1: this computer only; 0.0.0.0: every network "
                   "interface, so that other computers can connect)")
    p.add_argument("--port", type=_port, default=8080,
                   help="port 0..65535 (default 8080; 0 = any free port; a busy port is reported and the next "
                   "free one used)")
    p.add_argument("--scene", metavar="FILE", default=None,
                   help="start every tab from this scene: a JSON file saved by egtviz, or a built-in name "
                   "(see `egtviz scene list`)")
    p.add_argument("--demo", choices=["pinhole", "panoramic"], default=None,
                   help="open this visual-servoing demo in every new tab (docs/servo.md)")
    p.add_argument("--lesson", metavar="NAME", default=None,
                   help="open this lesson in every new tab (`egtviz lessons` lists them; docs/lessons.md). "
                   "Without --scene, --demo or --lesson every new tab opens the course's start page")
    p.add_argument("--present", action="store_true",
                   help="presentation mode in every new tab: large type, thick lines, high contrast (a projector)")
    p.add_argument("--classroom", action="store_true",
                   help="teach a class: print the student URL (with its QR code) and a separate instructor URL "
                   "holding a secret token; students follow the instructor's scene (docs/classroom.md)")
    p.add_argument("--workers", metavar="N", type=_workers, default=1,
                   help="serve from N processes behind the one URL (a supervisor hands each new connection to the "
                   "worker with the fewest; one that dies is restarted and its tabs reconnect); default 1")
    p.add_argument("--allow-host", metavar="NAME", action="append", default=[], type=_allow_host,
                   help="a name the page is reached under through a proxy (a JupyterHub's, e.g. hub.example.edu), "
                   "whose pages may then connect; repeatable; EGTVIZ_ALLOWED_HOSTS adds comma-separated names")


def _workers(text: str) -> int:
    """argparse type of ``--workers``: a whole number 1..MAX_WORKERS."""
    from .workers import MAX_WORKERS

    try:
        value = int(text, 10)
    except ValueError:
        value = 0
    if not 1 <= value <= MAX_WORKERS:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number 1 to {MAX_WORKERS}")
    return value


def _allow_host(text: str) -> str:
    """argparse type of ``--allow-host``: a DNS name or an IP literal."""
    from .guard import allowed_host

    try:
        return allowed_host(text, what="--allow-host")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--allow-host: ")) from None


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
    if not _could_be_host(host):
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


def _is_wildcard(host: str) -> bool:
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
    if not _is_wildcard(host):
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

    from ..workbench.app import EgtvizApp
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


def serve(host: str = "127.0.0.1", port: int = 8080, scene_path: str | Path | None = None,
          *, stop_event: threading.Event | None = None, demo: str | None = None, present: bool = False,
          lesson: str | None = None, course: bool = False, allow_hosts: tuple[str, ...] = (),
          classroom: bool = False) -> int:
    """Serve until Ctrl-C (or until ``stop_event`` is set); returns the exit status.

    Exit status 2 for a scene file that cannot be read, a lesson that does not exist or a bad name in
    ``EGTVIZ_ALLOWED_HOSTS``, 1 for an address that cannot be used; either is reported in one line on stderr.
    """
    from .guard import allowed_hosts

    try:
        allow_hosts = allowed_hosts(allow_hosts)
    except ValueError as exc:
        print(f"egtviz: cannot use {exc}", file=sys.stderr)
        return 2
    from ...lessons import LessonError
    from ...scene import SceneFileError

    try:
        bind = check_bind(host, port)
        if bind.port_busy:
            print(f"egtviz: port {port} is busy on {host}; using the next free one", file=sys.stderr, flush=True)
        server, app = start(host, port, scene_path, demo=demo, present=present, lesson=lesson, course=course,
                            allow_hosts=allow_hosts, classroom=classroom)
    except SceneFileError as exc:
        print(f"egtviz: cannot read the scene file: {exc}", file=sys.stderr)
        return 2
    except LessonError as exc:
        print(f"egtviz: cannot open the lesson: {exc}", file=sys.stderr)
        return 2
    except (OSError, RuntimeError) as exc:
        print(f"egtviz: cannot start the server: {exc}", file=sys.stderr)
        return 1
    stop = stop_event or threading.Event()
    try:
        terminate_as_interrupt()
        if _is_wildcard(host):
            print(f"egtviz: warning: --host {host} opens the app to the network: anyone who can reach this "
                  "machine can use it (each tab has its own scene; see docs/server.md)", file=sys.stderr, flush=True)
        print(f"egtviz running at {' '.join(reachable_urls(host, server.get_port()))}", flush=True)
        if app.classroom is not None:
            _print_classroom(app.classroom, host, server.get_port())
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        print("egtviz: stopped", flush=True)
    finally:
        if app.classroom is not None:
            app.classroom.close()
        server.stop()
    return 0


def student_url(host: str, port: int) -> str:
    """The URL students open: on a wildcard host the first address other computers can reach, else ``host``'s."""
    urls = reachable_urls(host, port)
    return urls[1] if len(urls) > 1 else urls[0]


def _print_classroom(classroom: object, host: str, port: int) -> None:
    """The class's two links; the instructor's (with the token) is printed once, here, and nowhere else."""
    from ..classroom import instructor_url, qr_terminal

    url = student_url(host, port)
    token = classroom.room.instructor_token  # type: ignore[attr-defined]
    print(f"egtviz classroom: students open {url}", flush=True)
    print(qr_terminal(url), end="", flush=True)
    if _is_wildcard(host) and len(reachable_urls(host, port)) < 2:
        print("egtviz classroom: no network address found: students on other computers cannot reach this one",
              file=sys.stderr, flush=True)
    # The instructor works on this computer: loopback, where the token never crosses the network.
    print(f"egtviz classroom: instructor (keep this secret) {instructor_url(reachable_urls(host, port)[0], token)}",
          flush=True)


def run(args: argparse.Namespace) -> int:
    """Entry point for the parsed ``serve`` sub-command."""
    demo, lesson = getattr(args, "demo", None), getattr(args, "lesson", None)
    # Nothing chosen to open: the course's start page, from which the workbench is one click away.
    course = args.scene is None and demo is None and lesson is None
    if getattr(args, "workers", 1) > 1:
        from .workers import WorkerOptions, serve_workers

        return serve_workers(args.workers, args.port, WorkerOptions(
            args.host, args.scene, demo, lesson, bool(getattr(args, "present", False)), course,
            tuple(getattr(args, "allow_host", None) or ()), bool(getattr(args, "classroom", False))))
    return serve(args.host, args.port, args.scene, demo=demo, present=bool(getattr(args, "present", False)),
                 lesson=lesson, course=course, allow_hosts=tuple(getattr(args, "allow_host", None) or ()),
                 classroom=bool(getattr(args, "classroom", False)))


def main(argv: list[str] | None = None) -> int:
    """``python -m egtviz.viewer.server.cli [--host H] [--port P] [--scene FILE]``."""
    parser = argparse.ArgumentParser(prog="egtviz-serve")
    add_arguments(parser)
    _one_line_address_errors(parser)
    args = parser.parse_args(argv)
    return run(args)


if __name__ == "__main__":
    raise SystemExit(main())
