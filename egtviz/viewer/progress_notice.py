"""The notice a tab shows when learners' progress is not being kept (the progress database cannot be used)."""

from __future__ import annotations

from html import escape

__all__ = ["progress_notice_html"]


def progress_notice_html(problem: str | None) -> str:
    """The notice for :attr:`~egtviz.lessons.ProgressStore.problem` (it names the file and says why); ``""`` when
    progress is kept."""
    if not problem:
        return ""
    return ('<div style="font-size:0.85em;padding:0.3em 0.6em;margin:0.2em 0;background:#fff4d6;'
            f'border-left:3px solid #c98a00" data-egtviz="progress-notice">{escape(problem)}</div>')
