"""What the instructor's panel and a student's bar show, as HTML built from data: every name, question and
message is escaped text, never markup (a student called ``<b>x</b>`` reads as those characters).

Pure functions: the same data gives the same HTML, which is all the tests need to read.
"""

from __future__ import annotations

from collections.abc import Sequence
from html import escape
from typing import TYPE_CHECKING

from ...controllers.class_state import AnswersView, PacingView, RosterLine, RoomStatus

if TYPE_CHECKING:
    from ...lessons import LessonRun

__all__ = [
    "histogram_html", "pacing_html", "pause_html", "roster_html", "status_html", "step_caption", "student_status_html",
]

#: Bars of the histogram are drawn in this colour (the palette's blue, readable on a projector).
BAR_COLOUR = "#0072B2"


#: The roster's cells: top-aligned, a little apart; no header is wider than its word.
_TD = "vertical-align:top;padding:0.2em 0.5em 0 0"
_TH = "text-align:left;white-space:nowrap;padding:0 0.5em 0.1em 0;font-weight:600"


def roster_html(lines: Sequence[RosterLine]) -> str:
    """The roster (:func:`egtviz.controllers.class_state.roster_lines`) as a table that fits the instructor's panel
    without scrolling sideways, two lines a student: their name and the tasks passed of the lesson's ("3/12");
    under it, where they are (following, own scene or away, and the lesson and step, from 1)."""
    if not lines:
        return '<div data-egtviz="roster" data-rows="0" style="padding:0.3em 0.6em">No student has joined yet.</div>'
    head = f"<th style='{_TH}'>name</th><th style='{_TH};text-align:right;padding-right:0'>tasks</th>"
    body = []
    for r in lines:
        body.append(
            f'<tr data-name="{escape(r.name)}" style="border-top:1px solid #ddd">'
            f'<td data-col="name" style="{_TD};overflow-wrap:anywhere;font-weight:600">{escape(r.name)}</td>'
            f'<td data-col="tasks" style="{_TD};text-align:right;white-space:nowrap;padding-right:0">'
            f"{escape(r.tasks)}</td></tr>"
            f'<tr data-where="{escape(r.name)}"><td colspan="2" data-col="where" data-state="{r.state}" '
            f'style="padding:0 0 0.25em 0.8em;font-size:0.92em;color:{"#555" if r.connected else "#999"}">'
            f"{escape(r.where)}</td></tr>")
    return (f'<div data-egtviz="roster" data-rows="{len(lines)}" style="padding:0 0.6em">'
            f'<table style="border-collapse:collapse;width:100%;font-size:0.9em"><thead><tr>{head}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table></div>')


def histogram_html(view: AnswersView | None, *, width_px: int = 320) -> str:
    """A bar chart of the answers to the question asked (:func:`egtviz.controllers.class_state.answers_view`), no
    names in it; the answers by name, if the view has them, listed under it (for the instructor's eyes only).
    None: no question asked."""
    if view is None:
        return '<div data-egtviz="histogram" data-n="0" style="padding:0 0.6em">No question asked.</div>'
    q = escape(view.question)
    if view.n == 0:
        return (f'<div data-egtviz="histogram" data-n="0" style="padding:0.3em 0.6em"><b>{q}</b><br>'
                "No answer yet.</div>")
    bars = view.bars
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
    if view.by_name:
        items = "".join(f"<li>{escape(n)}: {escape(v)}</li>" for n, v in view.by_name)
        listing = f'<ul data-egtviz="answers-by-name" style="margin:0.3em 0">{items}</ul>'
    return (f'<div data-egtviz="histogram" data-n="{view.n}" style="padding:0 0.6em"><b>{q}</b> '
            f'({view.n} answered){"".join(parts)}{listing}</div>')


def status_html(status: RoomStatus) -> str:
    """The instructor's summary of the room, in a box two lines high whether or not it wraps: the controls below
    it stay where they are when a count, the mode or the pause changes (a click aimed at them lands on them)."""
    pause = f' · <b style="color:#D55E00">paused</b>' if status.paused is not None else ""
    return (f'<div data-egtviz="room-status" style="padding:0 0.6em;font-size:1.05em;line-height:1.3;'
            f'min-height:2.6em">'
            f"{status.connected} connected · {status.following} following · mode: {escape(status.mode.value)}{pause}"
            "</div>")


def pacing_html(view: PacingView) -> str:
    """What the panel says of the pacing: the lessons open, and the last step open of each paced one, "of n"."""
    lines = "all lessons" if view.allowed is None else escape(", ".join(view.allowed))
    for p in view.paced:
        lines += f"<br>{escape(p.lesson)}: up to step {p.up_to}" + (f" of {p.of}" if p.of else "")
    return f'<div data-egtviz="pacing" style="padding:0 0.6em">{lines}</div>'


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
