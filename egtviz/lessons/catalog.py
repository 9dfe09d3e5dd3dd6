"""The lessons shipped with egtviz: the checkout's top-level ``lessons/`` folder, or ``egtviz/_lessons/`` in an
installed wheel (:func:`egtviz.resources.shipped_folder`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..resources import shipped_folder
from .errors import LessonError
from ..scene.limits import MAX_LESSON_FILE_BYTES
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
    return {f.name[: -len(".toml")]: f for f in folder.iterdir() if f.name.endswith(".toml") and f.is_file()}


def list_lessons() -> list[LessonInfo]:
    """Every shipped lesson, by name (the numbered file names sort in course order).

    Raises:
        LessonError: a shipped lesson that does not parse (the test suite keeps this from happening).
    """
    return [LessonInfo(lesson.name, lesson.title, lesson.summary) for lesson in (load(n) for n in sorted(_files()))]


def load(name: str) -> Lesson:
    """The shipped lesson ``name`` (its file name without ``.toml``), validated.

    Raises:
        LessonError: no such lesson, or the file is invalid.
    """
    files = _files()
    if name not in files:
        raise LessonError(str(name)[:80], 1, f"no lesson of that name (have: {', '.join(sorted(files))})")
    data = files[name].read_bytes()
    if len(data) > MAX_LESSON_FILE_BYTES:
        raise LessonError(name, 1, f"more than the {MAX_LESSON_FILE_BYTES / 1e6:g} MB limit")
    return parse_lesson(data, source=f"lessons/{name}.toml", name=name, known_lessons=frozenset(files))
