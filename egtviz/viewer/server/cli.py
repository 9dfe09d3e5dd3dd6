"""``egtviz serve``: start the viewer on a local port and block until Ctrl-C.

Before viser starts, the address is checked (:func:`~egtviz.viewer.server.launch.check_bind`; viser would retry an
unusable one forever): the host is resolved with a time limit and a socket is bound to it. What the server then
refuses from browsers is in :mod:`egtviz.viewer.server.guard`; both are described in ``docs/server.md``.
"""

from __future__ import annotations

import argparse
import sys
import threading
from pathlib import Path
from typing import TYPE_CHECKING

from .launch import (
    check_bind, could_be_host, is_wildcard, reachable_urls, start, student_url,
    terminate_as_interrupt,
)

if TYPE_CHECKING:
    from ..classroom import ClassroomHost

__all__ = ["add_arguments", "add_parser", "main", "run", "serve"]


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
    if not could_be_host(text):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a host name or an IP address")
    return text


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
        if is_wildcard(host):
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


def _print_classroom(classroom: ClassroomHost, host: str, port: int) -> None:
    """The class's two links; the instructor's (with the token) is printed once, here, and nowhere else."""
    from ..classroom import instructor_url, qr_terminal

    url = student_url(host, port)
    token = classroom.room.instructor_token
    print(f"egtviz classroom: students open {url}", flush=True)
    print(qr_terminal(url), end="", flush=True)
    if is_wildcard(host) and len(reachable_urls(host, port)) < 2:
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
