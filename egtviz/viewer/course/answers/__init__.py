"""The answer widgets of the lesson panel, one skin module per widget a task may declare.

A task says which widget it needs (:attr:`~egtviz.lessons.tasks.Task.needs`); :func:`answer_widget` builds
the skin registered under that name. A new widget (say a 3 x 3 grid for a computed matrix) is its declaration
in :mod:`egtviz.lessons.tasks.needs` and one module here that registers its skin with
:func:`~egtviz.viewer.course.answers.registry.skin`.
"""

from __future__ import annotations

import importlib
import pkgutil

import viser

from ....lessons.tasks import AnswerNeeds
from .registry import SKINS, AnswerSkin, AnswerWidget

__all__ = ["SKINS", "AnswerSkin", "AnswerWidget", "answer_widget"]

# Each skin module registers itself when imported: a new widget is then one new file, with no list to extend.
for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")


def answer_widget(gui: viser.GuiApi, label: str, needs: AnswerNeeds) -> AnswerWidget:
    """The widget ``needs`` asks for, built under ``label`` in ``gui``.

    Raises:
        KeyError: naming the widget, when no skin is registered for it.
    """
    build = SKINS.get(needs.widget)
    if build is None:
        raise KeyError(f"widget: no skin for the answer widget {needs.widget!r} (have {sorted(SKINS)})")
    return build(gui, label, needs)
