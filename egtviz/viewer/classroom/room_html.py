"""What the instructor's panel and a student's bar show, as HTML built from data: every name, question and
message is escaped text, never markup (a student called ``<b>x</b>`` reads as those characters).

Pure functions: the same data gives the same HTML, which is all the tests need to read.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from html import escape
from typing import TYPE_CHECKING

from ...classroom import Histogram, RosterRow

if TYPE_CHECKING:
    from ...lessons import LessonRun

__all__ = ["histogram_html", "pause_html", "roster_html", "status_html", "step_caption", "student_status_html"]

#: Bars of the histogram are drawn in this colour (the palette's blue, readable on a projector).
BAR_COLOUR = "#0072B2"


#: The roster's cells: top-aligned, a little apart; no header is wider than its word.
_TD = "vertical-align:top;padding:0.2em 0.5em 0 0"
_TH = "text-align:left;white-space:nowrap;padding:0 0.5em 0.1em 0;font-weight:600"


def _where(row: RosterRow, numbers: Mapping[str, int]) -> tuple[str, str]:
    """Where a roster row's student is: following, on their own scene, or away; and the lesson and step."""
    state = "away" if not row.connected else "following" if row.following else "own scene"
    if row.lesson is None:
        return state, ""
    lesson = f"lesson {numbers[row.lesson]}" if row.lesson in numbers else row.lesson
    return state, lesson if row.step is None else f"{lesson} · step {row.step + 1}"


def roster_html(rows: Sequence[RosterRow], numbers: Mapping[str, int] | None = None) -> str:
    """The roster as a table that fits the instructor's panel without scrolling sideways, two lines a student:
    their name and the tasks passed of the lesson's ("3/12"); under it, where they are (following, own scene or
    away, and the lesson and step, from 1).

    ``rows`` are :class:`egtviz.classroom.RosterRow`; ``numbers`` gives each lesson's number in the course (the
    lesson is said as "lesson 6"; a lesson not in it by its name).
    """
    if not rows:
        return '<div data-egtviz="roster" data-rows="0" style="padding:0.3em 0.6em">No student has joined yet.</div>'
    numbers = numbers or {}
    head = f"<th style='{_TH}'>name</th><th style='{_TH};text-align:right;padding-right:0'>tasks</th>"
    body = []
    for r in rows:
        state, lesson = _where(r, numbers)
        tasks = f"{r.tasks_passed}/{r.tasks_total}" if r.tasks_total else str(r.tasks_passed)
        where = f"{state} · {lesson}" if lesson else state
        body.append(
            f'<tr data-name="{escape(r.name)}" style="border-top:1px solid #ddd">'
            f'<td data-col="name" style="{_TD};overflow-wrap:anywhere;font-weight:600">{escape(r.name)}</td>'
            f'<td data-col="tasks" style="{_TD};text-align:right;white-space:nowrap;padding-right:0">'
            f"{escape(tasks)}</td></tr>"
            f'<tr data-where="{escape(r.name)}"><td colspan="2" data-col="where" data-state="{state}" '
            f'style="padding:0 0 0.25em 0.8em;font-size:0.92em;color:{"#555" if r.connected else "#999"}">'
            f"{escape(where)}</td></tr>")
    return (f'<div data-egtviz="roster" data-rows="{len(rows)}" style="padding:0 0.6em">'
            f'<table style="border-collapse:collapse;width:100%;font-size:0.9em"><thead><tr>{head}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table></div>')


def _number(x: float) -> str:
    return f"{x:.4g}"


def histogram_html(hist: Histogram, *, names: Mapping[str, float | str] | None = None, width_px: int = 320) -> str:
    """A bar chart of the answers to one question (an :class:`egtviz.classroom.Histogram`), no names in it;
    ``names`` (each student's answer) adds a list under it, for the instructor's eyes only."""
    q = escape(hist.question)
    if hist.n == 0:
        return (f'<div data-egtviz="histogram" data-n="0" style="padding:0.3em 0.6em"><b>{q}</b><br>'
                "No answer yet.</div>")
    bars: list[tuple[str, int]] = []
    for i, count in enumerate(hist.counts):
        bars.append((f"{_number(hist.edges[i])} to {_number(hist.edges[i + 1])}", count))
    bars += [(text, count) for text, count in hist.categories]
    top = max(count for _, count in bars) or 1
    row_h, label_w = 26, 150
    height = row_h * len(bars) + 8
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="100%" viewBox="0 0 {width_px} {height}" '
             'style="display:block;font-family:sans-serif">']
    for k, (label, count) in enumerate(bars):
        y = 4 + k * row_h
        w = (width_px - label_w - 40) * count / top
        parts.append(f'<text x="{label_w - 6}" y="{y + 17}" text-anchor="end" font-size="15">{escape(label)}</text>'
                     f'<rect data-kind="bar" data-count="{count}" x="{label_w}" y="{y + 3}" width="{w:.1f}" '
                     f'height="{row_h - 6}" fill="{BAR_COLOUR}"/>'
                     f'<text x="{label_w + w + 5:.1f}" y="{y + 17}" font-size="15">{count}</text>')
    parts.append("</svg>")
    listing = ""
    if names:
        items = "".join(f"<li>{escape(n)}: {escape(v if isinstance(v, str) else _number(v))}</li>"
                        for n, v in sorted(names.items(), key=lambda kv: kv[0].casefold()))
        listing = f'<ul data-egtviz="answers-by-name" style="margin:0.3em 0">{items}</ul>'
    return (f'<div data-egtviz="histogram" data-n="{hist.n}" style="padding:0 0.6em"><b>{q}</b> '
            f'({hist.n} answered){"".join(parts)}{listing}</div>')


def status_html(students: int, following: int, mode: str, paused: str | None) -> str:
    """The instructor's summary of the room, in a box two lines high whether or not it wraps: the controls below
    it stay where they are when a count, the mode or the pause changes (a click aimed at them lands on them)."""
    pause = f' · <b style="color:#D55E00">paused</b>' if paused is not None else ""
    return (f'<div data-egtviz="room-status" style="padding:0 0.6em;font-size:1.05em;line-height:1.3;'
            f'min-height:2.6em">'
            f"{students} connected · {following} following · mode: {escape(mode)}{pause}</div>")


def student_status_html(name: str, following: bool, question: str | None) -> str:
    """A student's bar: who they are, whether they follow the instructor, and the question asked, if any."""
    where = "You are following the instructor's scene." if following else "This is your own scene."
    ask = f'<div data-egtviz="question" style="margin-top:0.3em"><b>Question:</b> {escape(question)}</div>' \
        if question else ""
    return (f'<div data-egtviz="student-bar" data-following="{str(following).lower()}" style="padding:0 0.6em">'
            f"<b>{escape(name)}</b> · {where}{ask}</div>")


def pause_html(message: str) -> str:
    """What a paused student's screen says (the instructor's message, as text)."""
    return (f'<div data-egtviz="paused" style="font-size:1.6em;line-height:1.4;padding:0.6em 0.2em">'
            f"{escape(message)}</div>")


def step_caption(run: LessonRun | None) -> str:
    """The lesson step a :class:`~egtviz.lessons.LessonRun` is on, for followers: lesson and step titles (text)
    and the step's text (the lesson's own HTML, made from its markup); ``""`` for None."""
    if run is None:
        return ""
    i, n = run.step_index, len(run.lesson.steps)
    return (f'<div data-egtviz="room-step" data-lesson="{escape(run.lesson.name)}" data-step="{i}" '
            f'style="padding:0 0.6em"><div style="color:#555">{escape(run.lesson.title)}</div>'
            f"<b>Step {i + 1} of {n}: {escape(run.step.title)}</b>{run.step.html}</div>")
