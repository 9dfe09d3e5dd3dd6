"""Line numbers for errors found after parsing: where a table or key of a TOML file, or an entry of a JSON
scene file, starts.

``tomllib`` and ``json`` give a line only for syntax errors; a refused value is found again here by scanning
the text: the i-th ``[[steps]]``, the j-th ``[[steps.tasks]]`` under it, the line of a key. Paths are tuples
of keys and list indices, e.g. ``("steps", 2, "tasks", 0, "within_px")``; :meth:`Locator.line` falls back to
the nearest enclosing table that was found.
"""

from __future__ import annotations

import bisect
import json.decoder
import re
from collections.abc import Callable

__all__ = ["Locator", "json_locator", "scene_entry_path", "toml_locator"]

# The stdlib's JSON string scanner: json.decoder exports it, typeshed's stub leaves it out.
_scanstring: Callable[[str, int], tuple[str, int]] = json.decoder.scanstring  # type: ignore[attr-defined]
_KEY = re.compile(r"""\s*((?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*'))*)\s*=""")
_ENTRY = re.compile(r"([A-Za-z_]+)(?:\[(\d+)\])?(?:\.([A-Za-z_]+))?(?::\s*camera '[^']*':\s*([A-Za-z_]+))?")


class Locator:
    """Lines of the tables and keys of one file, by path."""

    def __init__(self, lines: dict[tuple, int]) -> None:
        self._lines = lines

    def line(self, *path: object) -> int:
        """The line of ``path``, or of its longest prefix that was found (1 if none)."""
        p = tuple(path)
        while p:
            if p in self._lines:
                return self._lines[p]
            p = p[:-1]
        return 1


def _parts(dotted: str) -> list[str]:
    return [p.strip().strip("\"'") for p in re.findall(r"""[A-Za-z0-9_-]+|"[^"]*"|'[^']*'""", dotted)]


def toml_locator(text: str) -> Locator:
    """Scan a TOML text for its table headers and keys (multi-line strings are skipped)."""
    lines: dict[tuple, int] = {}
    counters: dict[tuple, int] = {}
    current: tuple = ()
    open_string: str | None = None
    for no, raw in enumerate(text.splitlines(), 1):
        if open_string is not None:
            if raw.count(open_string) % 2 == 1:
                open_string = None
            continue
        stripped = raw.strip()
        header = re.match(r"\[\[\s*([^\]]+?)\s*\]\]|\[\s*([^\]]+?)\s*\]", stripped)
        if header and not _KEY.match(stripped):
            is_array = header.group(1) is not None
            parts = _parts(header.group(1) or header.group(2))
            path: tuple = ()
            for part in parts[:-1]:
                path += (part,)
                if path in counters:
                    path += (counters[path] - 1,)
            path += (parts[-1],)
            if is_array:
                index = counters.get(path, 0)
                counters[path] = index + 1
                path += (index,)
            lines.setdefault(path, no)
            current = path
            continue
        key = _KEY.match(raw)
        if key:
            lines.setdefault(current + tuple(_parts(key.group(1))), no)
            rest = raw[key.end():]
            for delimiter in ('"""', "'''"):
                if rest.count(delimiter) % 2 == 1:
                    open_string = delimiter
                    break
    return Locator(lines)


def json_locator(text: str) -> Locator:
    """The line where each value of a (valid) JSON text starts, by path (object keys and list indices)."""
    starts = [0] + [m.end() for m in re.finditer("\n", text)]
    lines: dict[tuple, int] = {}
    ws = re.compile(r"[ \t\n\r]*")
    scalar = re.compile(r"-?(?:0|[1-9]\d*)(?:\.\d+)?(?:[eE][-+]?\d+)?|true|false|null")

    def skip(i: int) -> int:
        return ws.match(text, i).end()  # type: ignore[union-attr]

    def value(i: int, path: tuple) -> int:
        i = skip(i)
        lines.setdefault(path, bisect.bisect_right(starts, i))
        c = text[i : i + 1]
        if c == "{":
            i = skip(i + 1)
            if text[i : i + 1] == "}":
                return i + 1
            while True:
                key, i = _scanstring(text, skip(i) + 1)
                i = skip(i) + 1  # the colon
                i = skip(value(i, path + (key,)))
                if text[i] == "}":
                    return i + 1
                i += 1  # the comma
        if c == "[":
            i = skip(i + 1)
            if text[i : i + 1] == "]":
                return i + 1
            k = 0
            while True:
                i = skip(value(i, path + (k,)))
                k += 1
                if text[i] == "]":
                    return i + 1
                i += 1
        if c == '"':
            return _scanstring(text, i + 1)[1]
        m = scalar.match(text, i)
        return m.end() if m else i + 1

    try:
        value(0, ())
    except (IndexError, ValueError):  # not JSON after all: only what was found so far
        pass
    return Locator(lines)


def scene_entry_path(message: str) -> tuple:
    """The entry a scene-layer message starts with, as a path: ``"cameras[1]: camera 'c': focal_length: ..."``
    gives ``("cameras", 1, "focal_length")``, ``"pair: ..."`` gives ``("pair",)``."""
    m = _ENTRY.match(message)
    if m is None:
        return ()
    path: tuple = (m.group(1),)
    if m.group(2) is not None:
        path += (int(m.group(2)),)
    if m.group(3):
        path += (m.group(3),)
    elif m.group(4):
        path += (m.group(4),)
    return path
