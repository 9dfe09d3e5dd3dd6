"""The ``egtviz`` command: ``serve`` (the default), ``servo``, ``bench``, ``version``."""

from __future__ import annotations

import argparse
import sys

from . import __version__


def _add_bench(subparsers) -> None:
    p = subparsers.add_parser("bench", help="measure speed and print a table (ours vs OpenCV where it has the same function)")
    p.add_argument("suite", nargs="?", default="all", choices=["core", "viewer", "servo", "all"])
    p.add_argument("--repeats", type=int, default=20, help="timed repetitions per case (median is reported)")


def _run_bench(args) -> int:
    from .bench.runner import run

    return run(args.suite, repeats=args.repeats)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="egtviz",
        description="Interactive multiple-view geometry in the browser (a Python Epipolar Geometry Toolbox). "
        "With no command, starts the viewer on the default scene.",
    )
    parser.add_argument("--version", action="version", version=f"egtviz {__version__}")
    sub = parser.add_subparsers(dest="command")
    from .viewer.cli import add_parser as add_serve

    add_serve(sub)
    from .servo.cli import add_parser as add_servo

    add_servo(sub)
    _add_bench(sub)
    sub.add_parser("version", help="print the version")
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    if not argv or argv[0].startswith("--") and argv[0] not in ("--help", "--version"):
        argv = ["serve", *argv]
    args = parser.parse_args(argv)
    if args.command == "version":
        print(f"egtviz {__version__}")
        return 0
    if args.command == "bench":
        return _run_bench(args)
    if args.command == "serve":
        from .viewer.cli import run as run_serve

        return run_serve(args)
    if args.command == "servo":
        from .servo.cli import run as run_servo

        return run_servo(args)
    parser.print_help()
    return 2


if __name__ == "__main__":
    sys.exit(main())
