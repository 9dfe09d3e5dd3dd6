"""Learners' records as CSV: one row per learner, lesson, step and task (``egtviz progress --csv`` for a
lecturer; the start page's "download my record" for one learner).

Names, lesson names and task ids are data: a cell a spreadsheet would read as a formula (starting with
``=``, ``+``, ``-`` or ``@``, or with a tab or carriage return) is written with a leading single quote.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable
from datetime import UTC, datetime

from .progress import TaskRecord

__all__ = ["CSV_HEADER", "records_csv", "safe_cell"]

CSV_HEADER = ("learner", "lesson", "step", "task", "passed", "attempts", "hints used", "last attempt (UTC)")
"""The CSV's columns; ``step`` counts from 1, as the lesson panel shows it."""

_FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def safe_cell(text: str) -> str:
    """``text`` as a CSV cell a spreadsheet shows as text: a leading formula character gets a ``'`` before it."""
    return "'" + text if text.startswith(_FORMULA_STARTS) else text


def records_csv(records: Iterable[TaskRecord]) -> str:
    """The records as CSV text (a header row, then one row per record; ``\\r\\n`` line ends, RFC 4180)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n")
    writer.writerow(CSV_HEADER)
    for r in records:
        when = datetime.fromtimestamp(r.updated, UTC).strftime("%Y-%m-%d %H:%M:%S")
        writer.writerow((safe_cell(r.learner), safe_cell(r.lesson), r.step + 1, safe_cell(r.task),
                         "yes" if r.passed else "no", r.attempts, r.hints, when))
    return out.getvalue()
