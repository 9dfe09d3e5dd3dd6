r"""The convention lens in a tab: its five toggles, the live residuals, and the panels drawn through it.

The numbers come from :func:`egtviz.scene.lens.lens_view`; this module only shows them. With a toggle on,
the image-plane panels draw the epipoles and the epipolar lines the mistaken code would compute
(:meth:`LensPanel.panel_filter`, the panel filter of the tab's lesson policy), and the lens's folder lists, per
point seen in both images, the residual

.. math:: r_i = m_{2i}^T F m_{1i}

with ``F`` as shown (unit Frobenius norm), and the distance of each point from its own epipolar line in
image 2, :math:`|l_{2i} \cdot m_{2i}|` with :math:`l_{2i} = F m_{1i}` scaled to :math:`a^2 + b^2 = 1`.
A working lens gives residuals near zero; a broken one does not.

The toggles belong to the lesson (:attr:`egtviz.lessons.LessonRun.lens`): a click applies a ``set_lens``
change through the run (:func:`egtviz.controllers.lesson_instruments.toggle_lens`), so the lesson's checks see
what the panels show.

A step that asks which mistake is on (a task that declares a possible diagnosis, while its lens has a mistake
on) hides the lens's settings (:func:`egtviz.controllers.lesson_instruments.hidden_lens`): the panels show the
mistake's effect, and each box shows whether the learner switched that step of the computation since the step
began, not whether the mistake is on (:meth:`~egtviz.scene.lens.LensToggles.switched`). Ticking the box of the
hidden mistake repairs the lens.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import fields
from html import escape

import numpy as np
import viser

from ...controllers.lesson_instruments import LessonInstruments, hidden_lens, lens_shown, through_lens, toggle_lens
from ...scene import Derived, Scene, SceneError
from ...scene.lens import LensToggles, LensView, lens_view
from ..workbench.fields import on_event

__all__ = ["HIDDEN_NOTE", "LENS_LABELS", "LensPanel", "residual_table_html"]

#: Each toggle of :class:`~egtviz.scene.lens.LensToggles` as the GUI names it (the mistake it applies).
LENS_LABELS: dict[str, str] = {
    "f_transposed": "F in place of F\u1d40",
    "wrong_singular_vector": "epipoles from the wrong singular vector",
    "r_tx": "E = R [t]\u2093 (for [t]\u2093 R)",
    "k_transposed": "K\u2082\u207b\u1d40 E K\u2081\u1d40 (for K\u2082\u207b\u1d40 E K\u2081\u207b\u00b9)",
    "opengl_axes": "OpenGL camera axes (for OpenCV's)",
}
#: Rows of the residual table (the selected point is always listed first).
MAX_RESIDUAL_ROWS = 12
#: What the lens says while it hides the step's mistake (:func:`hidden_lens`).
HIDDEN_NOTE = ("<small><b>A mistake is hidden in this step.</b> A ticked box is a step of the computation you "
               "switched, not a mistake that is on: find the switch that repairs the geometry.</small>")


def _num(x: float, digits: int = 3) -> str:
    return "-" if not math.isfinite(x) else f"{x:.{digits}g}"


def residual_table_html(view: LensView, selected: int | None) -> str:
    """The lens's read-out: per point seen in both images, :math:`m_2^T F m_1` and the point-to-line distance."""
    both = np.flatnonzero(np.isfinite(view.residuals))
    order = [i for i in ([selected] if selected is not None else []) if i in set(both.tolist())]
    order += [int(i) for i in both if i != selected][: MAX_RESIDUAL_ROWS - len(order)]
    rows = "".join(
        f'<tr data-point="{i}"{" style=font-weight:bold" if i == selected else ""}><td>{i + 1}</td>'
        f'<td data-kind="residual">{view.residuals[i]: .2e}</td><td data-kind="distance2">'
        f"{_num(view.distances2_px[i])}</td><td>{_num(view.distances1_px[i])}</td></tr>"
        for i in order
    )
    worst = float(np.nanmax(np.abs(view.residuals))) if len(both) else math.nan
    more = f"<br>({len(both) - len(order)} more points not listed)" if len(both) > len(order) else ""
    return (
        '<div style="font-size:0.8em" data-egtviz="lens-readout">'
        f"<b>m\u2082\u1d40 F m\u2081</b> with F as the panels use it (unit norm); distance of each point from its "
        f"line, px. Largest |m\u2082\u1d40 F m\u2081|: <b data-kind=\"worst\">{_num(worst)}</b>"
        '<table style="width:100%;text-align:right"><tr><th>point</th><th>m\u2082\u1d40 F m\u2081</th>'
        f"<th>in {escape(view.names[1])}</th><th>in {escape(view.names[0])}</th></tr>{rows}</table>{more}</div>"
    )


class LensPanel:
    """The convention lens's folder in a lesson tab.

    Args:
        gui: the tab's ``client.gui``.
        run: the lesson run whose ``lens`` toggles are shown and changed.
        redraw: redraws the tab (the panels pass through :meth:`panel_filter` again).
        report: receives what a callback raises (the tab's notification).
        order: the folder's place in the control panel.
    """

    def __init__(self, gui: viser.GuiApi, run: LessonInstruments, *, redraw: Callable[[], None],
                 report: Callable[[BaseException], None], order: float) -> None:
        self.run = run
        self._redraw = redraw
        self._syncing = False
        #: The last lens view drawn (None: the lens could not be applied to the scene).
        self.view: LensView | None = None
        self.folder = gui.add_folder("Convention lens", order=order, expand_by_default=True)
        with self.folder:
            gui.add_markdown("<small>Each toggle applies a mistake people make; the panels draw what the "
                             "mistaken code computes.</small>")
            self.note = gui.add_markdown("")
            self.toggles: dict[str, viser.GuiCheckboxHandle] = {}
            shown = lens_shown(run)
            for f in fields(LensToggles):
                box = gui.add_checkbox(LENS_LABELS[f.name], getattr(shown, f.name))
                on_event(box.on_update, self._toggler(f.name), report)
                self.toggles[f.name] = box
            self.readout = gui.add_html("")
        self.note.content = HIDDEN_NOTE if hidden_lens(run) is not None else ""

    def _toggler(self, key: str) -> Callable[[viser.GuiEvent[viser.GuiCheckboxHandle]], None]:
        """The update callback of the checkbox for the lens toggle ``key``."""
        return lambda event: self._toggle(key, event.target.value)

    def _toggle(self, key: str, value: object) -> None:
        if self._syncing:
            return
        if not isinstance(value, bool):  # a raw client can send anything
            raise SceneError(f"{LENS_LABELS[key]}: expected true or false, got {str(value)[:40]!r}")
        toggle_lens(self.run, key, value)
        self._redraw()

    def sync(self) -> None:
        """Show the run's toggles (after a step changed them), or what was switched while a step hides its lens."""
        self._syncing = True
        try:
            shown = lens_shown(self.run)
            self.note.content = HIDDEN_NOTE if hidden_lens(self.run) is not None else ""
            for key, box in self.toggles.items():
                if box.value != getattr(shown, key):
                    # viser's value setter sits apart from its getter: mypy takes the property as read-only.
                    box.value = getattr(shown, key)  # type: ignore[misc]
        finally:
            self._syncing = False

    def panel_filter(self, scene: Scene, derived: Derived) -> tuple[Derived, frozenset[int]]:
        """The panels through the lens: its epipoles and lines in the drawn pair (unchanged if it cannot apply)."""
        try:
            view = lens_view(scene, self.run.lens, derived)
        except SceneError as exc:
            self.view = None
            self.readout.content = f'<div style="font-size:0.8em">The lens is off: {escape(str(exc))}</div>'
            return derived, frozenset()
        self.view = view
        self.readout.content = residual_table_html(view, scene.selected_point)
        return through_lens(derived, view), frozenset()
