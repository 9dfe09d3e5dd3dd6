"""``egtviz lessons``, ``egtviz progress`` and ``egtviz check PATH...``: argument setup and runners.

The lead wires each ``add_*_arguments`` / ``run_*`` pair into ``egtviz/cli.py`` as a sub-command. Every
runner returns the exit status and never lets a traceback through for bad input.
"""

from __future__ import annotations

import argparse
import os
import re
import sys

from ..files import FileSafetyError, printable, read_limited
from ..scene.limits import MAX_SCENE_FILE_BYTES
from .errors import LessonError
from .locate import json_locator, scene_entry_path

__all__ = [
    "add_check_arguments",
    "add_lessons_arguments",
    "add_progress_arguments",
    "check_file",
    "run_check",
    "run_lessons",
    "run_progress",
]


def add_lessons_arguments(parser: argparse.ArgumentParser) -> None:
    """``egtviz lessons``: no arguments."""
    parser.description = "List the lessons shipped with egtviz: one line each, its name then its title."


def run_lessons(args: argparse.Namespace) -> int:
    """Print ``name  title`` per shipped lesson; 2 if a shipped lesson is broken."""
    from .catalog import list_lessons

    try:
        lessons = list_lessons()
    except LessonError as exc:
        print(f"egtviz: {exc}", file=sys.stderr)
        return 2
    width = max((len(info.name) for info in lessons), default=0)
    for info in lessons:
        print(f"{info.name:<{width}}  {printable(info.title)}")
    return 0


def add_progress_arguments(parser: argparse.ArgumentParser) -> None:
    """``egtviz progress [--database PATH] [--csv] [--out FILE.csv]``."""
    parser.description = ("Print a table of the learners, the lessons they started, their step and tasks done; "
                          "with --csv, one row per learner, lesson, step and task (passed, attempts, hints used, "
                          "last attempt).")
    parser.add_argument("--database", default=None, help="the progress database (default: in the user's data folder)")
    parser.add_argument("--csv", action="store_true", help="CSV, one row per task checked, to standard output")
    parser.add_argument("--out", default=None, metavar="FILE.csv",
                        help="write the CSV to this file instead (implies --csv; an existing file is replaced)")


def run_progress(args: argparse.Namespace) -> int:
    """Print the progress table (learner, lesson, step, tasks done, attempts); 2 if the database cannot be read.

    A report: the database is opened read-only (``mode=ro``), so nothing is created, written or journalled; a
    path that does not exist has no progress yet; anything that is not a progress database is refused.
    """
    from .progress import ProgressStore, default_database_path
    from .records import records_csv

    path = args.database if args.database is not None else default_database_path()
    store = ProgressStore(path, read_only=True)
    if store.fault is not None:
        print(f"egtviz: progress: {store.fault}", file=sys.stderr)
        return 2
    out = getattr(args, "out", None)  # a Namespace built by hand may have neither
    if getattr(args, "csv", False) or out is not None:
        return _write_csv(records_csv(store.task_records()), out)
    rows = store.summary()
    if not rows:
        print("no progress recorded yet")
        return 0
    header = ("learner", "lesson", "step", "tasks done", "attempts")
    table = [header] + [(_learner_shown(r.learner), printable(r.lesson), str(r.step + 1), str(r.tasks_passed),
                         str(r.attempts)) for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    for row in table:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip())
    return 0


def _write_csv(text: str, out: str | None) -> int:
    """CSV ``text`` to standard output or to ``out`` (written atomically); 2 if ``out`` is refused."""
    from ..files import write_atomic
    if out is None:
        sys.stdout.write(text)
        return 0
    try:
        write_atomic(out, text.encode("utf-8"))
    except FileSafetyError as exc:
        print(f"egtviz: progress: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {printable(out)}")
    return 0


def _learner_shown(name: str) -> str:
    """A learner's name for the terminal: as typed when it is a name the course accepts (an emoji family's
    joiners included), else with its control characters written out."""
    from .progress import LearnerNameError, learner_key

    try:
        return name if learner_key(name) == name else printable(name)
    except LearnerNameError:
        return printable(name)


def add_check_arguments(parser: argparse.ArgumentParser) -> None:
    """``egtviz check PATH...``."""
    parser.description = (
        "Validate lesson files (.toml) and scene files (.json) with the viewer's own validation and limits; "
        "print 'file:line: reason' for each error. Exit status 2 if any file has an error."
    )
    parser.add_argument("paths", nargs="+", metavar="PATH", help="lesson (.toml) or scene (.json) files")


def check_file(path: str) -> str | None:
    """None if ``path`` is a valid lesson (``.toml``, any case) or scene file (anything else), else
    ``file:line: reason``.

    A lesson is also proven against wrong answers: each task's counter-examples, applied from the step's
    start, must fail (:func:`~egtviz.lessons.proof.prove_counter_examples`).

    Scene files go through the scene layer's own reader (``scene_from_bytes``, as ``load_scene_file``); the line
    of a refused entry is found in the JSON text (:func:`~egtviz.lessons.locate.json_locator`).
    """
    shown = printable(path)
    if path.lower().endswith(".toml"):
        from .format import load_lesson
        from .proof import prove_counter_examples

        try:
            prove_counter_examples(load_lesson(path))
        except LessonError as exc:
            return str(exc)
        return None
    from ..scene import SceneFileError, scene_from_bytes

    try:
        data = read_limited(path, MAX_SCENE_FILE_BYTES)
    except FileSafetyError as exc:
        return f"{shown}:1: {str(exc).removeprefix(shown + ': ')}"
    try:
        scene_from_bytes(data, "scene")
    except SceneFileError as exc:
        reason = str(exc).removeprefix("scene: ")
        at = re.match(r"line (\d+)\b", reason)  # JSON syntax, nesting: "line L[, column C]: ..."
        if at:
            line = int(at.group(1))
        else:
            text = data.decode("utf-8", errors="replace")
            line = json_locator(text).line(*scene_entry_path(reason))
        return f"{shown}:{line}: {reason}"
    return None


def run_check(args: argparse.Namespace) -> int:
    """Check each path (:func:`check_file`): ``path: ok`` or ``file:line: reason``; 2 if any failed."""
    failed = 0
    for path in args.paths:
        message = check_file(os.fspath(path))
        if message is None:
            print(f"{printable(path)}: ok")
        else:
            failed += 1
            print(message)
    return 2 if failed else 0


def _main(argv: list[str] | None = None) -> int:  # pragma: no cover - the lead's egtviz/cli.py replaces this
    parser = argparse.ArgumentParser(prog="egtviz")
    sub = parser.add_subparsers(dest="command", required=True)
    add_lessons_arguments(sub.add_parser("lessons"))
    add_progress_arguments(sub.add_parser("progress"))
    add_check_arguments(sub.add_parser("check"))
    args = parser.parse_args(argv)
    return {"lessons": run_lessons, "progress": run_progress, "check": run_check}[args.command](args)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(_main())
