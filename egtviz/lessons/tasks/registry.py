"""The vocabulary of task kinds (:data:`TASK_KINDS`) and the reading of one ``[[steps.tasks]]`` table
(:func:`parse_task`): the keys every task has here, the kind's own keys by its class
(:meth:`~egtviz.lessons.tasks.base.Task.from_table`)."""

from __future__ import annotations

import re
import string
from typing import Any

from .. import fields
from ..changes import parse_change
from ..errors import EntryError
from ..markup import MarkupError, render_markdown
from .base import Task
from .cameras import CameraFieldTask, SameOrientationTask, XiBetweenTask
from .epipolar import EpipoleNearTask, LinesParallelTask, PointInImageTask
from .estimation import InliersRecallTask, SampsonBelowTask, TriangulationErrorTask
from .lens import PointOnLineTask
from .questions import ChoiceTask, NumberTask
from .servo import ServoNumberTask
from .computed import ComputedTask

__all__ = ["MAX_HINT_TIERS", "TASK_KINDS", "parse_task"]

MAX_HINT_TIERS = 3
"""Tiers of a task's hint: the idea, a concrete pointer, the answer."""

TASK_KINDS: dict[str, type[Task]] = {
    cls.kind: cls
    for cls in (NumberTask, ChoiceTask, EpipoleNearTask, SameOrientationTask, LinesParallelTask, PointOnLineTask,
                SampsonBelowTask, InliersRecallTask, PointInImageTask, CameraFieldTask, XiBetweenTask,
                TriangulationErrorTask, ServoNumberTask, ComputedTask)
}
"""Every task kind by its ``kind`` name (in the order the docs list them, which messages repeat)."""

_COMMON = ("kind", "id", "prompt", "hint", "solution")
_ID = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,39}")
# A placeholder may round its value ({u:.1f}); nothing that could build a huge string.
_FORMAT_SPEC = re.compile(r"\.\d?[fg]")


def _check_prompt(prompt: str, names: set[str]) -> None:
    try:
        parsed = list(string.Formatter().parse(prompt))
    except ValueError as exc:
        raise EntryError("prompt", f"bad placeholder ({exc}); write {{{{ and }}}} for braces") from None
    for _, name, spec, conversion in parsed:
        if name is None:
            continue
        if name not in names:
            raise EntryError("prompt", f"placeholder {{{name}}}: expected one of "
                                       f"{', '.join('{' + n + '}' for n in sorted(names)) or 'none'}")
        if conversion or (spec and not _FORMAT_SPEC.fullmatch(spec)):
            raise EntryError("prompt", f"placeholder {{{name}}}: only {{{name}}} or a rounding such as "
                                       f"{{{name}:.1f}} is allowed")


def _hint_tiers(table: dict) -> tuple[str, ...]:
    """``hint``: one text (one tier) or a list of up to :data:`MAX_HINT_TIERS` texts, the idea first."""
    value = table.get("hint", "")
    if isinstance(value, str):
        tiers = [fields.text(table, "hint", limit=fields.MAX_TEXT, multiline=True)] if value else []
    elif isinstance(value, list) and 1 <= len(value) <= MAX_HINT_TIERS:
        tiers = []
        for k, item in enumerate(value, start=1):
            try:
                tiers.append(fields.text({"hint": item}, "hint", limit=fields.MAX_TEXT, multiline=True))
            except EntryError as exc:
                raise EntryError("hint", f"tier {k}: {exc.reason}") from None
            if not item.strip():
                raise EntryError("hint", f"tier {k}: expected text (it is empty)")
    else:
        raise EntryError("hint", f"expected a text or a list of 1 to {MAX_HINT_TIERS} texts (the idea, a "
                                 f"pointer, the answer), got {fields.short(value)}")
    return tuple(tiers)


def _common_fields(table: dict, default_id: str) -> dict[str, Any]:
    """``id``, ``prompt``, ``hint`` and ``solution``, which every kind has."""
    task_id = fields.text(table, "id", required=False, default=default_id)
    if not _ID.fullmatch(task_id):
        raise EntryError(
            "id", f"expected a letter then letters, digits, '_' or '-' (at most 40), got {fields.short(task_id)}"
        )
    common: dict[str, Any] = {
        "id": task_id,
        "prompt": fields.text(table, "prompt", limit=fields.MAX_TEXT, multiline=True),
        "hint": _hint_tiers(table),
    }
    solution = table.get("solution", [])
    if not isinstance(solution, list):
        raise EntryError("solution", f"expected a list of changes, got {fields.short(solution)}")
    try:
        common["solution"] = tuple(parse_change(c) for c in solution)
    except EntryError as exc:
        raise EntryError("solution", f"change: {exc}") from None
    return common


def parse_task(table: Any, default_id: str) -> Task:
    """One ``[[steps.tasks]]`` table as a :class:`Task` (types and ranges checked; the names of cameras and
    points are checked against the step's scene by :meth:`Task.validate`).

    Raises:
        EntryError: naming the offending key.
    """
    if not isinstance(table, dict):
        raise EntryError(None, f"expected a table, got {fields.short(table)}")
    kind = table.get("kind")
    if type(kind) is not str or kind not in TASK_KINDS:
        raise EntryError("kind", f"unknown task kind {fields.short(kind)} (expected one of {', '.join(TASK_KINDS)})")
    cls = TASK_KINDS[kind]
    fields.refuse_unknown(table, _COMMON + cls.table_keys, f"a {kind!r} task")
    task = cls.from_table(table, _common_fields(table, default_id))
    _check_prompt(task.prompt, set(task.params()))
    for key, text in (("prompt", task.prompt), *(("hint", tier) for tier in task.hint)):
        try:
            render_markdown(text)
        except MarkupError as exc:
            raise EntryError(key, str(exc)) from None
    return task
