"""Snapshots of a student's scene, anonymised, to show to the room ("two of you placed the cameras like this").

A snapshot keeps what the student built (cameras, points, their names, surfaces, what is drawn) and carries a
label such as ``Student A`` instead of their name: the name is replaced by the label wherever the scene holds
free text (the title, labels, frame labels, figure messages). The label of a student stays the same for the
life of the class, so the room can say "Student A again".
"""

from __future__ import annotations

import re
import string
from dataclasses import dataclass, replace
from typing import Any

from ..scene import Scene
from ..scene.limits import MAX_TEXT_LENGTH, MAX_TITLE_LENGTH

__all__ = ["Snapshot", "anonymise", "label_for"]


@dataclass(frozen=True)
class Snapshot:
    """An anonymised copy of one student's scene."""

    label: str
    """``Student A``, ``Student B``, ... ``Student Z``, ``Student AA``, ..."""
    scene: Scene
    number: int
    """Counts the snapshots taken in this class (1, 2, ...): two snapshots of one student differ by it."""


def label_for(index: int) -> str:
    """The label of the ``index``-th student (0-based) to have a snapshot taken: A..Z, AA..ZZ, ..."""
    letters = string.ascii_uppercase
    name = ""
    index += 1
    while index > 0:
        index, rest = divmod(index - 1, 26)
        name = letters[rest] + name
    return f"Student {name}"


def _scrub(text: str, pattern: re.Pattern[str], label: str, limit: int = MAX_TEXT_LENGTH) -> str:
    """``text`` with the name replaced by ``label``, cut to ``limit`` characters (the label may be longer)."""
    return pattern.sub(label, text)[:limit] if text else text


def _scrubbed(item: Any, field: str, pattern: re.Pattern[str], label: str) -> Any:
    text = getattr(item, field)
    new = _scrub(text, pattern, label)
    return item if new == text else replace(item, **{field: new})


def anonymise(scene: Scene, name: str, label: str) -> Scene:
    """``scene`` with ``name`` (any case) replaced by ``label`` in every free-text field; cameras, points and
    their names are kept as they are."""
    pattern = re.compile(re.escape(name), re.IGNORECASE)
    notes = scene.annotations
    labels = tuple(_scrubbed(a, "text", pattern, label) for a in notes.labels)
    frames = tuple(_scrubbed(f, "label", pattern, label) for f in notes.frames)
    messages = tuple(_scrub(m, pattern, label) for m in notes.messages)
    if labels != notes.labels or frames != notes.frames or messages != notes.messages:
        notes = replace(notes, labels=labels, frames=frames, messages=messages)
    title = _scrub(scene.title, pattern, label, MAX_TITLE_LENGTH)
    if title == scene.title and notes is scene.annotations:
        return scene
    return scene.replace(title=title, annotations=notes)
