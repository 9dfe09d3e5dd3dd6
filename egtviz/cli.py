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


def _add_scene(subparsers) -> None:
    p = subparsers.add_parser("scene", help="list the built-in scenes, save one to a file, or check a scene file")
    sub = p.add_subparsers(dest="scene_command", required=True)
    sub.add_parser("list", help="the built-in scenes")
    save = sub.add_parser("save", help="write a built-in scene to a JSON file (to edit, then serve with --scene)")
    save.add_argument("name", help="a built-in scene (see `egtviz scene list`)")
    save.add_argument("file")
    check = sub.add_parser("check", help="read a scene file and report what it holds, or what is wrong with it")
    check.add_argument("file")


def _run_scene(args) -> int:
    from .scene import SCENES, Scene, SceneFileError

    if args.scene_command == "list":
        for name, make in SCENES.items():
            print(f"{name:<10} {make().title}")
        return 0
    if args.scene_command == "save":
        if args.name not in SCENES:
            print(f"egtviz: no built-in scene {args.name!r} (have {', '.join(SCENES)})", file=sys.stderr)
            return 2
        SCENES[args.name]().save(args.file)
        print(f"saved {args.name} to {args.file}")
        return 0
    try:
        scene = Scene.load(args.file)
    except SceneFileError as exc:
        print(f"egtviz: {exc}", file=sys.stderr)
        return 2
    kinds = ", ".join(f"{c.name} ({c.kind})" for c in scene.cameras) or "no cameras"
    print(f"{args.file}: {scene.title or 'untitled'}: {kinds}; {len(scene.points)} points, {len(scene.surfaces)} surfaces")
    return 0


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
    _add_scene(sub)
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
    if args.command == "scene":
        return _run_scene(args)
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
