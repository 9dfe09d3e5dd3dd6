"""``egtviz export``: a lesson step or a scene as a static page (see :mod:`egtviz.viewer.export`)."""

from __future__ import annotations

import argparse
import sys

__all__ = ["add_parser", "run"]


def _step(text: str) -> int:
    """argparse type of ``--step``: a whole number (its range depends on the lesson, checked later)."""
    try:
        return int(text, 10)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a step number (1 is the first step)") from None


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``export`` sub-command."""
    p = subparsers.add_parser(
        "export", help="write a lesson step or a scene as a static page (opens from disk, no server)",
        description="Write a static page: the 3D scene with each camera's image panel drawn in it, beside the "
        "step's text. It opens from disk (file://) or any static web host; nothing is downloaded when it opens.")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--lesson", metavar="NAME", help="a lesson (`egtviz lessons` lists them)")
    what.add_argument("--scene", metavar="FILE", help="a scene file, or a built-in scene (`egtviz scene list`)")
    p.add_argument("--step", metavar="K", type=_step, default=None,
                   help="with --lesson: the step to show, 1 for the first (default 1)")
    p.add_argument("--out", metavar="DIR", required=True,
                   help="the folder to write (index.html, scene.html, egtviz-export.json): a new or empty folder, "
                   "or an earlier export, whose files are replaced")
    return p


def run(args: argparse.Namespace) -> int:
    """Run a parsed ``export``; exit status 0, 2 for input that cannot be used, 1 for an export that could not be
    finished (a file not written), each with one line on stderr."""
    from ...files import printable
    from . import ExportError, ExportFailed, export_lesson, export_scene

    try:
        if args.lesson is not None:
            page = export_lesson(args.lesson, 1 if args.step is None else args.step, args.out)
        elif args.step is not None:
            raise ExportError("--step: only with --lesson")
        else:
            page = export_scene(args.scene, args.out)
    except ExportError as exc:
        print(f"egtviz export: {exc}", file=sys.stderr)
        return 2
    except ExportFailed as exc:
        print(f"egtviz export: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {printable(page)} (open it in a browser; no server needed)")
    return 0
