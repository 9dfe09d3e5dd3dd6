"""The F/E read-out of the drawn pair, in the workbench's "Epipolar geometry" folder."""

from __future__ import annotations

from html import escape
from typing import TYPE_CHECKING

import numpy as np

from ...scene.derived import shown_value
from ...scene.shown_numbers import format_value, format_vector
from ..server.viser_adapter import assign_text
from .models import SHORT_LABELS

if TYPE_CHECKING:
    import viser

    from ...scene.derived import Derived

__all__ = ["PairReadout", "pair_html"]


def _fmt_matrix(M: np.ndarray) -> str:
    """A matrix's rows; an entry below ``ZERO_FRACTION`` of the matrix's norm is rounding and shown as 0."""
    M = np.asarray(M, float)
    norm = float(np.linalg.norm(M))
    rows = ["  ".join(" 0" if shown_value(v, norm) == 0.0 else format_value(v, " .4e") for v in row)
            for row in M.tolist()]
    return "\n".join(rows)


def _fmt_vec(v: np.ndarray | None) -> str:
    if v is None:
        return "-"
    v = np.asarray(v, float)
    if abs(v[2]) < 1e-12:
        return f"({format_vector(v[:2], '.3g')}, 0) (at infinity)"
    return f"({format_vector(v[:2] / v[2], '.1f')}) px"


def pair_html(derived: Derived) -> str:
    """The epipolar read-out of the drawn pair (HTML: cheaper for the browser than re-parsing markdown per drag step).

    Two pin-hole cameras: F (pixels, ``m2^T F m1 = 0``), its rank, E and the epipoles. Any pair with another
    camera: E between the viewing rays (``d2^T E d1 = 0``) and a note that no F relates the pixels.
    """
    p = derived.pair
    style = "font-size:0.82em;line-height:1.35"
    if p.names is None:
        return f'<div style="{style}"><b>Epipolar geometry</b>: add a second camera to see it.</div>'
    law = "<code>m2&#7488; F m1 = 0</code>" if p.F is not None else "<code>d2&#7488; E d1 = 0</code>"
    head = (f'<div style="{style}" data-egtviz="readout"><b>Drawn pair {escape(p.names[0])} &rarr; '
            f"{escape(p.names[1])}</b>&nbsp; {law}<br>")
    if p.message:
        return f'{head}<b style="color:#a00">{escape(p.message)}</b></div>'
    if p.E is None:  # set for every pair without a message
        raise ValueError("the drawn pair's read-out has neither E nor a message")
    pre = 'style="margin:2px 0;font-size:0.95em;background:#f3f3f3;padding:2px 4px"'
    if p.F is None:
        cams = derived.cameras
        curved = [n for n in p.names if cams[n].projective_calibration is None]
        who = " and ".join(f"{escape(n)} ({escape(SHORT_LABELS[cams[n].kind])})" for n in curved)
        return (f'{head}<span data-relation="essential">No F between pixels: {who} images lines as curves. '
                f"What holds is the epipolar constraint between the viewing rays, <code>d2&#7488; E d1 = 0</code> "
                f"(d1, d2 unit rays in each camera's frame); the epipolar curves are drawn in the panels.</span>"
                f"<br>E = [t]&#8339; R:<pre {pre}>{_fmt_matrix(p.E)}</pre></div>")
    return (
        f'{head}<span data-relation="fundamental">F (unit Frobenius norm), rank {p.rank}:</span>'
        f"<pre {pre}>{_fmt_matrix(p.F)}</pre>"
        f"E = [t]&#8339; R:<pre {pre}>{_fmt_matrix(p.E)}</pre>"
        f"e1 = {escape(_fmt_vec(p.e1))}<br>e2 = {escape(_fmt_vec(p.e2))}</div>"
    )


class PairReadout:
    """The read-out's HTML element and the text it last showed.

    Args:
        handle: the GUI HTML element the read-out is written into.
    """

    def __init__(self, handle: viser.GuiHtmlHandle) -> None:
        self.handle = handle
        #: The HTML last shown.
        self.text = ""

    def show(self, derived: Derived) -> None:
        """Show the drawn pair's F, E and epipoles (or why there are none)."""
        self._write(pair_html(derived))

    def fail(self, message: str) -> None:
        """Show why the scene cannot be drawn."""
        self._write(f"<b>{escape(message)}</b>")

    def _write(self, text: str) -> None:
        self.text = text
        assign_text(self.handle, "content", text)
