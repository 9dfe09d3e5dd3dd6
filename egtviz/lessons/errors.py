"""The two errors of the lessons package: a refused lesson file, and a refused entry inside one."""

from __future__ import annotations


class LessonError(ValueError):
    """A lesson file that cannot be used: ``"<file>:<line>: <reason>"``.

    Raised by :func:`egtviz.lessons.format.load_lesson` for every refusal (bad TOML, unknown keys or task
    kinds, a change naming a missing camera, values outside ``egtviz.scene.limits``); never a traceback.
    """

    def __init__(self, file: str, line: int, reason: str) -> None:
        self.file = file
        """The file as given (a path or a name)."""
        self.line = line
        """1-based line of the offending table or key (1 when the whole file is at fault)."""
        self.reason = reason
        super().__init__(f"{file}:{line}: {reason}")


class EntryError(ValueError):
    """A bad value inside one table of a lesson file; the loader adds the file and the line.

    ``key`` names the offending key of the table (None: the table as a whole).
    """

    def __init__(self, key: str | None, reason: str) -> None:
        self.key = key
        self.reason = reason
        super().__init__(f"{key}: {reason}" if key else reason)
