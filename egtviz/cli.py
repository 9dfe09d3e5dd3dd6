"""The ``egtviz`` command: ``serve`` (the default: the course's start page), ``lesson``, ``scene``, ``servo``,
``figure``, ``export``, ``bench``, ``version``.

Exit status: 0 success; 1 a run that did not succeed (a servo run that did not converge, an output that
could not be written); 2 a refused argument or input file (argparse usage errors too). Messages never
carry a traceback, and names taken from files or arguments are printed without control characters.
"""

from __future__ import annotations

import argparse
import sys

from . import __version__
from .files import printable


def _add_bench(subparsers) -> None:
    from .servo.cli import whole_number_in

    p = subparsers.add_parser(
        "bench",
        help="measure speed and print a table (ours vs OpenCV where it has the same function)",
        description="Time the numeric core, the viewer's update path or the servo simulations; prints medians.",
    )
    p.add_argument("suite", nargs="?", default="all",
                   choices=["core", "viewer", "servo", "classroom", "figures", "progress", "all"],
                   help="what to measure (default all; classroom: many tabs on one server, figures: EGT's plots "
                        "and drawing loops with tabs open, progress: the start page's read of a large progress "
                        "database; none of these three in all)")
    p.add_argument("--repeats", type=whole_number_in(1, 10_000), default=20,
                   help="timed repetitions per case, 1..10000 (median is reported; default 20)")
    p.add_argument("--json", metavar="FILE", default=None,
                   help="classroom only: also write the figures (CPU per update, the viser floor at the same rate, "
                        "the parts, the lag per tab count) to FILE as JSON")
    p.add_argument("--scene", default=None, help="classroom only: the scene the tabs drag (default: the default)")
    p.add_argument("--points", type=whole_number_in(1, 1000), default=None,
                   help="classroom only: give the scene that many random points (1..1000)")
    p.add_argument("--workers", type=whole_number_in(1, 64), default=None,
                   help="classroom only: serve from N worker processes (egtviz serve --workers N) and measure 30 "
                        "tabs dragging at once, and with --followers one instructor and M followers")
    p.add_argument("--followers", type=whole_number_in(1, 1000), default=None,
                   help="classroom only: also measure one instructor dragging with this many students following")


def _run_bench(args) -> int:
    from .bench.runner import run

    return run(args.suite, repeats=args.repeats, json_path=args.json, scene=args.scene, points=args.points,
               workers=args.workers, followers=args.followers)


def _add_scene(subparsers) -> None:
    p = subparsers.add_parser(
        "scene",
        help="list the built-in scenes, save one to a file, or check a scene file",
        description="Scene files are JSON (docs/limits.md lists what they may hold).",
    )
    sub = p.add_subparsers(dest="scene_command", required=True, metavar="{list,save,check}", help="what to do")
    sub.add_parser("list", help="the built-in scenes and their titles", description="Print the built-in scenes.")
    save = sub.add_parser(
        "save",
        help="write a built-in scene to a JSON file (to edit, then serve with --scene)",
        description="Write a built-in scene to FILE atomically. An existing regular file is replaced; "
        "a folder, device, FIFO or symbolic link is refused.",
    )
    save.add_argument("name", help="a built-in scene (see `egtviz scene list`)")
    save.add_argument("file", help="the JSON file to write")
    check = sub.add_parser(
        "check",
        help="read a scene file and report what it holds, or what is wrong with it",
        description="Check a scene file exactly as `egtviz serve --scene FILE` and the browser's Load do: "
        "it passes if and only if the viewer can draw it. Exit status 0 if it passes, 2 if not.",
    )
    check.add_argument("file", help="the JSON scene file to check (a regular file of at most 2 MB)")


def _error(message: str) -> int:
    print(f"egtviz: {message}", file=sys.stderr)
    return 2


def _run_scene(args) -> int:
    from .files import FileSafetyError, check_write_target
    from .scene import SCENES, SceneFileError, load_scene_file, save_scene_file

    if args.scene_command == "list":
        for name, make in SCENES.items():
            print(f"{name:<10} {make().title}")
        return 0
    if args.scene_command == "save":
        if args.name not in SCENES:
            return _error(f"no built-in scene '{printable(args.name)}' (built-in: {', '.join(SCENES)})")
        try:
            check_write_target(args.file)
            save_scene_file(SCENES[args.name](), args.file)
        except FileSafetyError as exc:
            return _error(str(exc))
        print(f"saved {args.name} to {printable(args.file)}")
        return 0
    try:
        scene = load_scene_file(args.file)
    except SceneFileError as exc:
        return _error(str(exc))
    kinds = ", ".join(f"{printable(c.name)} ({c.kind})" for c in scene.cameras) or "no cameras"
    print(
        f"{printable(args.file)}: {printable(scene.title) or 'untitled'}: {kinds}; "
        f"{len(scene.points)} points, {len(scene.surfaces)} surfaces"
    )
    return 0


def _add_figure(subparsers, with_arguments: bool) -> None:
    """``figure``: its arguments come from ``egtviz.viewer.render.figure_export``, imported only when it runs."""
    p = subparsers.add_parser(
        "figure",
        help="export a scene's figure to a file (see `egtviz figure --help`)",
        description="Export a scene's figure to a file.",
    )
    if with_arguments:
        try:
            from .viewer.render import figure_export
        except ImportError as exc:
            p.set_defaults(figure_missing=str(exc))
            return
        figure_export.add_arguments(p)


def _run_figure(args) -> int:
    missing = getattr(args, "figure_missing", None)
    if missing is not None:
        print(f"egtviz figure: not available in this installation ({printable(missing)})", file=sys.stderr)
        return 1
    from .viewer.render import figure_export

    return figure_export.run(args)


def _add_lessons(subparsers) -> None:
    """``lessons``, ``progress`` and ``check`` (``egtviz.lessons.cli``)."""
    from .lessons.cli import add_check_arguments, add_lessons_arguments, add_progress_arguments

    add_lessons_arguments(subparsers.add_parser(
        "lessons", help="list the lessons (name, then title)", description="List the course's lessons."))
    add_progress_arguments(subparsers.add_parser(
        "progress", help="print the learners' progress", description="Print a table of learners, lessons and tasks done."))
    add_check_arguments(subparsers.add_parser(
        "check", help="validate lesson files and scene files",
        description="Validate lesson (.toml) and scene (.json) files: file, line and reason for each error."))


_LESSON_COMMANDS = {"lessons": "run_lessons", "progress": "run_progress", "check": "run_check"}


def _serve_options_epilog() -> str:
    """The ``serve`` options as the top-level help shows them (``egtviz --port 8081`` means ``egtviz serve ...``)."""
    from .viewer.server.cli import add_arguments

    p = argparse.ArgumentParser(prog="egtviz [serve]", add_help=False)
    add_arguments(p)
    options = p.format_help().split("\n\n", 1)[-1].strip()
    return (
        "With no command, or with only these options, egtviz serves the viewer (the `serve` command):\n"
        + options.replace("options:", "serve options:", 1)
    )


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``egtviz`` argument parser; ``command`` (the first word of the command line) lets sub-commands with
    heavy imports add their arguments only when they run."""
    parser = argparse.ArgumentParser(
        prog="egtviz",
        description="Interactive multiple-view geometry in the browser (a Python Epipolar Geometry Toolbox). "
        "With no command, starts the viewer on the course's start page (the workbench is one click away).",
        epilog=_serve_options_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"egtviz {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="{serve,lesson,lessons,progress,check,scene,servo,figure,export,bench,version}",
                                help="what to do (default: serve)")
    from .viewer.server.cli import add_parser as add_serve

    add_serve(sub)
    _add_lesson(sub)
    _add_lessons(sub)
    _add_scene(sub)
    from .servo.cli import add_parser as add_servo

    add_servo(sub)
    _add_figure(sub, with_arguments=command == "figure")
    from .viewer.export.cli import add_parser as add_export

    add_export(sub)
    _add_bench(sub)
    sub.add_parser("version", help="print the version", description="Print the version of egtviz.")
    return parser


def _add_lesson(subparsers) -> None:
    """``egtviz lesson NAME [serve options]``: serve with ``--lesson NAME``."""
    from .viewer.server.cli import add_arguments

    p = subparsers.add_parser(
        "lesson", help="open one lesson in the viewer (egtviz serve --lesson NAME)",
        description="Serve the viewer with this lesson in every new tab (`egtviz lessons` lists them).")
    p.add_argument("lesson_name", metavar="NAME", help="a lesson's name, e.g. 06-pinhole-epipolar")
    add_arguments(p)


def _check_scene_argument(args) -> int | None:
    """``serve --scene``: refused here with the built-in names listed, before a server is started."""
    if getattr(args, "scene", None) is None:
        return None
    from .scene import SceneFileError, scene_from_argument

    try:
        scene_from_argument(args.scene)
    except SceneFileError as exc:
        return _error(f"cannot use --scene: {exc}")
    return None


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0].startswith("--") and argv[0] not in ("--help", "--version"):
        argv = ["serve", *argv]
    parser = build_parser(argv[0] if argv else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: usage error (2) or --help/--version (0)
        return int(exc.code or 0)
    if args.command == "version":
        print(f"egtviz {__version__}")
        return 0
    if args.command == "bench":
        return _run_bench(args)
    if args.command == "scene":
        return _run_scene(args)
    if args.command == "figure":
        return _run_figure(args)
    if args.command == "export":
        from .viewer.export.cli import run as run_export

        return run_export(args)
    if args.command in _LESSON_COMMANDS:
        from .lessons import cli as lessons_cli

        return getattr(lessons_cli, _LESSON_COMMANDS[args.command])(args)
    if args.command == "lesson":
        args.command, args.lesson = "serve", args.lesson_name
    if args.command == "serve":
        refused = _check_scene_argument(args)
        if refused is not None:
            return refused
        from .viewer.server.cli import run as run_serve

        return run_serve(args)
    if args.command == "servo":
        from .servo.cli import run as run_servo

        return run_servo(args)
    parser.print_help()
    return 2


if __name__ == "__main__":
    sys.exit(main())
