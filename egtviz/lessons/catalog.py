"""The lessons shipped with egtviz: the checkout's top-level ``lessons/`` folder, or ``egtviz/_lessons/`` in an
installed wheel (:func:`egtviz.resources.shipped_folder`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..files import FileSafetyError, printable, read_limited
from ..resources import shipped_folder
from ..scene.limits import MAX_LESSON_FILE_BYTES
from .errors import LessonError
from .format import Lesson, parse_lesson

__all__ = ["LessonInfo", "lessons_folder", "list_lessons", "load"]


@dataclass(frozen=True)
class LessonInfo:
    """A catalog entry, read without validating the whole lesson."""

    name: str
    title: str
    summary: str


def lessons_folder() -> Path:
    """The checkout's ``lessons/``, or ``egtviz/_lessons`` when installed from a wheel."""
    return shipped_folder("lessons")


def _files() -> dict[str, Path]:
    folder = lessons_folder()
    if not folder.is_dir():
        return {}
    return {f.stem: f for f in folder.iterdir() if f.suffix.lower() == ".toml" and f.is_file()}


def list_lessons() -> list[LessonInfo]:
    """Every shipped lesson, by name (the numbered file names sort in course order).

    Raises:
        LessonError: a shipped lesson that does not parse (the test suite keeps this from happening).
    """
    return [LessonInfo(lesson.name, lesson.title, lesson.summary) for lesson in (load(n) for n in sorted(_files()))]


def load(name: str) -> Lesson:
    """The shipped lesson ``name`` (its file name without ``.toml``), validated.

    Raises:
        LessonError: no such lesson, or the file is invalid. A name is shown with its control characters
            written out (``\\x1b``), as typed on a command line.
    """
    files = _files()
    if name not in files:
        raise LessonError(printable(str(name)[:80]), 1, f"no lesson of that name (have: {', '.join(sorted(files))})")
    source = f"lessons/{files[name].name}"
    try:
        data = read_limited(files[name], MAX_LESSON_FILE_BYTES)
    except FileSafetyError as exc:
        raise LessonError(source, 1, str(exc).removeprefix(f"{printable(str(files[name]))}: ")) from None
    return parse_lesson(data, source=source, name=name, known_lessons=frozenset(files), folder=files[name].parent)
