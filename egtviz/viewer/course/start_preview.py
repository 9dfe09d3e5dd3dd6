"""The start page's right-hand side: a still preview of the workbench's scene, its cameras' image planes.

The start page's lesson list is a column on the left; the rest of the window would be blank. This draws the
scene the workbench opens on, one panel per camera (the first two), with the image-plane panels' own renderer
(:func:`egtviz.viewer.render.svg.image_plane_svg`), so a learner sees what "Open the workbench" leads to. It is plain
HTML placed beside the page's column (``position:fixed``), sized from the window the tab reported; it takes no
input.
"""

from __future__ import annotations

from html import escape

from ...scene import Scene, compute_derived
from ..render.panel_view import fit_view
from ..render.panels import WindowSize, initial_view
from ..render.svg import NORMAL, PRESENT, image_plane_svg

__all__ = ["PREVIEW_CAMERAS", "PREVIEW_MIN_PX", "start_preview_html"]

#: The preview shows at most this many cameras' panels, side by side.
PREVIEW_CAMERAS = 2
#: Below this width for one panel (CSS px) there is no room for a preview: none is drawn.
PREVIEW_MIN_PX = 260.0
#: Space between the page's column and the preview, and between the panels (CSS px).
PREVIEW_GAP_PX = 24.0


def start_preview_html(scene: Scene, window: WindowSize, *, left_px: float, margin_px: float,
                       present: bool = False) -> str:
    """The preview's HTML: a heading, one line on what the panels show, and the panels; ``""`` if it cannot fit.

    Args:
        scene: the scene the workbench opens on.
        window: the tab's window (CSS px).
        left_px: where the page's column ends (CSS px from the window's left edge).
        margin_px: the window's margin on the right, top and bottom.
        present: presentation style (the panels' large type).
    """
    style = PRESENT if present else NORMAL
    cameras = [c.name for c in scene.cameras][:PREVIEW_CAMERAS]
    left = left_px + PREVIEW_GAP_PX
    room = window.width - left - margin_px
    if not cameras or room < PREVIEW_MIN_PX:
        return ""
    n = len(cameras)
    panel_px = (room - (n - 1) * PREVIEW_GAP_PX) / n
    if panel_px < PREVIEW_MIN_PX:  # one panel rather than two unreadable ones
        cameras, n, panel_px = cameras[:1], 1, room
    derived = compute_derived(scene)
    svgs = []
    for name in cameras:
        plane = derived.image_planes[name]
        view = fit_view(plane) if initial_view(plane) == "fit" else None
        svgs.append(f'<div style="flex:0 0 {panel_px:.0f}px;min-width:0"><div style="font-weight:bold;'
                    f'margin:0 0 0.3em">{escape(name)}: image plane</div>'
                    + image_plane_svg(plane, view=view, style=style, panel_px=panel_px,
                                      selected_point=scene.selected_point, show_labels=scene.options.show_labels)
                    + "</div>")
    title = escape(scene.title) if getattr(scene, "title", "") else "The workbench's scene"
    return (
        f'<div data-egtviz="start-preview" style="position:fixed;left:{left:.0f}px;top:{margin_px:.0f}px;'
        f"right:{margin_px:.0f}px;bottom:{margin_px:.0f}px;overflow:hidden;background:#fff;color:#222;"
        f'font-size:{style.status_px * 1.3:.1f}px;line-height:1.35">'
        f'<div style="font-size:1.25em;font-weight:bold;margin:0.2em 0">Preview: {title}</div>'
        f'<div style="margin:0 0 0.8em;max-width:60em">What "Open the workbench" shows: cameras and points in 3D, '
        f"and each camera's image plane, drawn here, with its epipolar lines and epipoles. Drag a camera there "
        f"and these drawings follow; every lesson starts from a scene like this one.</div>"
        f'<div style="display:flex;gap:{PREVIEW_GAP_PX:.0f}px;align-items:flex-start">{"".join(svgs)}</div></div>'
    )
