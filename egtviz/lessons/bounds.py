"""Bounds on the work a lesson file asks for, checked before the work is done.

A lesson file of a few kilobytes could otherwise keep ``egtviz check`` (and the server loading a lesson) busy for
minutes: a TOML parser's work grows with the square of a dotted key's parts, and loading applies every change
and simulates every measured servo run. So, in this order:

* :func:`check_toml_text` scans the text before ``tomllib`` sees it: parts of each dotted key and table header
  (:data:`~egtviz.scene.limits.MAX_LESSON_KEY_PARTS`), arrays and inline tables nested in a value
  (:data:`~egtviz.scene.limits.MAX_LESSON_NESTING`) and keys in all
  (:data:`~egtviz.scene.limits.MAX_LESSON_KEYS`);
* :func:`check_lesson_work` counts, in the parsed document and before any change is applied, the changes of each
  step and each solution (:data:`~egtviz.scene.limits.MAX_CHANGES`), of the whole lesson
  (:data:`~egtviz.scene.limits.MAX_LESSON_CHANGES`) and the points they place
  (:data:`~egtviz.scene.limits.MAX_LESSON_POINTS`).

Each refusal is a :class:`~egtviz.lessons.errors.LessonError` ``file:line: reason``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..scene.limits import (
    MAX_CHANGES,
    MAX_LESSON_CHANGES,
    MAX_LESSON_KEY_PARTS,
    MAX_LESSON_KEYS,
    MAX_LESSON_NESTING,
    MAX_LESSON_POINTS,
)
from .errors import LessonError
from .locate import Locator

__all__ = ["TomlShape", "check_lesson_work", "check_toml_text", "toml_shape"]

# What the scanner skips between tokens: blanks, newlines and comments.
_GAP = re.compile(r"(?:[ \t\r\n]+|#[^\n]*)*")
_INLINE_GAP = re.compile(r"[ \t]*")
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_STRINGS = (
    re.compile(r'"""(?:[^"\\]|\\[\s\S]|"(?!""))*"""(?:""?(?!"))?'),
    re.compile(r"'''(?:[^']|'(?!''))*'''(?:''?(?!'))?"),
    re.compile(r'"(?:[^"\\\n]|\\.)*"'),
    re.compile(r"'[^'\n]*'"),
)
# A scalar value: inside an array or inline table it ends at a separator, at the top level at the line's end.
_NESTED_SCALAR = re.compile(r"""[^\s\[\]{},"'#]+""")
_TOP_SCALAR = re.compile(r"""[^\n#"']+""")


class _Stop(Exception):
    """The text is not TOML the scanner follows: ``tomllib`` reports the error at that place."""


class _Refusal(Exception):
    """A limit the text goes beyond, at ``line``."""

    def __init__(self, line: int, reason: str) -> None:
        self.line = line
        self.reason = reason


@dataclass(frozen=True)
class TomlShape:
    """What :func:`check_toml_text` bounds, measured in one TOML text."""

    keys: int
    """Keys and table headers, inline tables' keys included."""
    key_parts: int
    """Parts of the longest dotted key or table header."""
    nesting: int
    """Arrays and inline tables nested in the deepest value."""
    complete: bool
    """False: the scan stopped at text that is not TOML (what it measured up to there is kept)."""


class _Scanner:
    """One pass over a TOML text, measuring what :func:`check_toml_text` bounds and refusing beyond the limits."""

    def __init__(self, text: str, parts: float = MAX_LESSON_KEY_PARTS, nesting: float = MAX_LESSON_NESTING,
                 keys: float = MAX_LESSON_KEYS) -> None:
        self.text = text
        self.limits = (parts, nesting, keys)
        self.keys = 0
        self.key_parts = 0
        self.nesting = 0

    def refuse(self, pos: int, reason: str) -> _Refusal:
        return _Refusal(self.text.count("\n", 0, pos) + 1, reason)

    def string(self, pos: int) -> int:
        for pattern in _STRINGS:
            m = pattern.match(self.text, pos)
            if m:
                return m.end()
        raise _Stop

    def key(self, pos: int, header: bool = False) -> int:
        """Past a dotted key (and its ``=``, or a header's closing brackets), its parts and the key count checked."""
        start, parts, text = pos, 0, self.text
        while True:
            pos = _INLINE_GAP.match(text, pos).end()  # type: ignore[union-attr]
            if text.startswith(('"', "'"), pos):
                pos = self.string(pos)
            else:
                m = _BARE_KEY.match(text, pos)
                if m is None:
                    raise _Stop
                pos = m.end()
            parts += 1
            self.key_parts = max(self.key_parts, parts)
            if parts > self.limits[0]:
                what = "a table header" if header else "a dotted key"
                raise self.refuse(start, f"{what} of more than {MAX_LESSON_KEY_PARTS} parts "
                                         f"(a lesson's keys have at most {MAX_LESSON_KEY_PARTS})")
            pos = _INLINE_GAP.match(text, pos).end()  # type: ignore[union-attr]
            if text.startswith(".", pos):
                pos += 1
                continue
            break
        self.keys += 1
        if self.keys > self.limits[2]:
            raise self.refuse(start, f"more than {MAX_LESSON_KEYS} keys and tables in the file")
        if header:
            if not text.startswith("]", pos):
                raise _Stop
            return pos + (2 if text.startswith("]]", pos) else 1)
        if not text.startswith("=", pos):
            raise _Stop
        return pos + 1

    def value(self, pos: int) -> int:
        """Past one value (arrays and inline tables followed to their end, their nesting checked)."""
        text = self.text
        pos = _INLINE_GAP.match(text, pos).end()  # type: ignore[union-attr]
        if not text.startswith(("[", "{"), pos):
            if text.startswith(('"', "'"), pos):
                return self.string(pos)
            m = _TOP_SCALAR.match(text, pos)
            return m.end() if m else pos
        stack: list[str] = []
        want_key = False
        while True:
            pos = _GAP.match(text, pos).end()  # type: ignore[union-attr]
            if pos >= len(text):
                raise _Stop
            c = text[pos]
            if c in "]}":
                if not stack or stack.pop() != ("[" if c == "]" else "{"):
                    raise _Stop
                pos += 1
                want_key = False
                if not stack:
                    return pos
            elif c == ",":
                pos += 1
                want_key = bool(stack) and stack[-1] == "{"
            elif want_key:
                pos = self.key(pos)
                want_key = False
            elif c in "[{":
                stack.append(c)
                self.nesting = max(self.nesting, len(stack))
                if len(stack) > self.limits[1]:
                    raise self.refuse(pos, f"arrays and inline tables nested more than {MAX_LESSON_NESTING} "
                                           "levels deep")
                pos += 1
                want_key = c == "{"
            elif c in "\"'":
                pos = self.string(pos)
            else:
                m = _NESTED_SCALAR.match(text, pos)
                if m is None:
                    raise _Stop
                pos = m.end()

    def run(self) -> None:
        text, pos = self.text, 0
        while True:
            pos = _GAP.match(text, pos).end()  # type: ignore[union-attr]
            if pos >= len(text):
                return
            if text.startswith("[", pos):
                pos = self.key(pos + (2 if text.startswith("[[", pos) else 1), header=True)
            else:
                pos = self.value(self.key(pos))


def check_toml_text(text: str, source: str) -> None:
    """Refuse a lesson text whose keys are too deep or too many, or whose values nest too deeply, before it is
    parsed (the scan is linear in the text's length). Text that is not TOML is left to the parser to report.

    Raises:
        LessonError: ``file:line: reason``, the line of the first key or bracket beyond a limit.
    """
    try:
        _Scanner(text).run()
    except _Stop:
        return
    except _Refusal as exc:
        raise LessonError(source, exc.line, exc.reason) from None


def toml_shape(text: str) -> TomlShape:
    """The keys, the longest key and the deepest value of a TOML text (no limit applied)."""
    scanner = _Scanner(text, math.inf, math.inf, math.inf)
    try:
        scanner.run()
    except _Stop:
        return TomlShape(scanner.keys, scanner.key_parts, scanner.nesting, complete=False)
    return TomlShape(scanner.keys, scanner.key_parts, scanner.nesting, complete=True)


def _count_points(change: object) -> int:
    """Points a change table places (``random_points`` ``n``, ``set_points``); its type is checked later."""
    if not isinstance(change, dict):
        return 0
    if change.get("do") == "random_points":
        n = change.get("n")
        if isinstance(n, float) and n.is_integer():
            n = int(n)
        return n if type(n) is int and n > 0 else 0
    if change.get("do") == "set_points" and isinstance(change.get("points"), list):
        return len(change["points"])
    return 0


class _Tally:
    def __init__(self, source: str, where: Locator) -> None:
        self.source, self.where = source, where
        self.changes = 0
        self.points = 0

    def add(self, tables: list, at: tuple, what: str, owner: str) -> None:
        """Count ``tables``, the changes of one step or one solution (``owner``), at ``at`` in the file."""
        if len(tables) > MAX_CHANGES:
            raise LessonError(self.source, self.where.line(*at, MAX_CHANGES),
                              f"{what}: {len(tables)} changes, more than the {MAX_CHANGES} one {owner} may make")
        for j, table in enumerate(tables):
            self.changes += 1
            self.points += _count_points(table)
            line = self.where.line(*at, j)
            if self.changes > MAX_LESSON_CHANGES:
                raise LessonError(self.source, line, f"{what}[{j}]: more than {MAX_LESSON_CHANGES} changes in the "
                                                     "lesson (its steps' changes and its tasks' solutions)")
            if self.points > MAX_LESSON_POINTS:
                raise LessonError(self.source, line, f"{what}[{j}]: the lesson's changes place more than "
                                                     f"{MAX_LESSON_POINTS} points in all ({self.points} so far)")


def check_lesson_work(steps: list, source: str, where: Locator) -> None:
    """Refuse a lesson whose changes are too many or place too many points, before any of them is applied.

    Args:
        steps: the parsed ``[[steps]]`` tables (entries of other types are refused later, where they are read).
        source: the file, for messages.
        where: the lines of the file's tables and keys.

    Raises:
        LessonError: ``file:line: reason``, at the first change beyond a limit.
    """
    tally = _Tally(source, where)
    for i, step in enumerate(steps):
        if not isinstance(step, dict):
            continue
        changes = step.get("changes", [])
        if isinstance(changes, list):
            tally.add(changes, ("steps", i, "changes"), f"steps[{i}].changes", "step")
        tasks = step.get("tasks", [])
        for j, task in enumerate(tasks if isinstance(tasks, list) else ()):
            solution = task.get("solution") if isinstance(task, dict) else None
            if isinstance(solution, list):
                tally.add(solution, ("steps", i, "tasks", j, "solution"), f"steps[{i}].tasks[{j}].solution",
                          "solution")
