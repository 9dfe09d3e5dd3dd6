"""The notice a tab shows when learners' progress is not being kept (the progress database cannot be used)."""

from __future__ import annotations

from html import escape

import viser

__all__ = ["progress_notice_html", "show_name_in_use"]


def progress_notice_html(problem: str | None) -> str:
    """The notice for :attr:`~egtviz.lessons.ProgressStore.problem` (it names the file and says why); ``""`` when
    progress is kept."""
    if not problem:
        return ""
    return ('<div style="font-size:0.85em;padding:0.3em 0.6em;margin:0.2em 0;background:#fff4d6;'
            f'border-left:3px solid #c98a00" data-egtviz="progress-notice">{escape(problem)}</div>')


def show_name_in_use(field: viser.GuiTextHandle, name: str) -> None:
    """After a refused name: ``field`` (a *your name* text field) shows the name still in use, not the refused
    text (the notification says why it was refused). A field a raw client gave a value of another type (a
    number) cannot hold text again: it is left as it is."""
    try:
        # viser's value setter sits apart from its getter: mypy takes the property as read-only.
        field.value = name  # type: ignore[misc]
    except (TypeError, ValueError):
        pass
