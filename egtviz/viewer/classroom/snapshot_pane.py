"""A student's anonymised snapshot shown to the room: its image planes drawn once, in a floating panel of
every tab of the class (the instructor's and the students'), beside the scene the tab shows."""

from __future__ import annotations

from html import escape

import viser

from ...classroom import Snapshot
from ...scene import compute_derived
from ..render.panels import initial_view
from ..render.svg import NORMAL, PRESENT, image_plane_svg

__all__ = ["RenderedSnapshot", "SnapshotPane", "render_snapshot"]

#: Width of the floating panel (CSS pixels).
PANE_WIDTH_PX = 420


class RenderedSnapshot:
    """A snapshot's label and each camera's panel SVG (made once, shown in every tab)."""

    def __init__(self, label: str, panels: tuple[tuple[str, str], ...]) -> None:
        self.label = label
        self.panels = panels


def render_snapshot(snapshot: Snapshot, *, present: bool = False) -> RenderedSnapshot:
    """Draw ``snapshot``'s image planes (an :class:`egtviz.classroom.Snapshot`), each fitted as a new panel is."""
    scene = snapshot.scene
    derived = compute_derived(scene)
    style = PRESENT if present else NORMAL
    panels = []
    for spec in scene.cameras:
        plane = derived.image_planes.get(spec.name)
        if plane is None:
            continue
        from ..render.panels import PanelView

        view = PanelView(initial_view(plane)).resolve(plane)
        svg = image_plane_svg(plane, selected_point=scene.selected_point, show_labels=scene.options.show_labels,
                              view=view, style=style, panel_px=PANE_WIDTH_PX)
        panels.append((spec.name, svg))
    return RenderedSnapshot(snapshot.label, tuple(panels))


class SnapshotPane:
    """The snapshot's floating panel in one tab; :meth:`remove` takes it away."""

    def __init__(self, client: viser.ClientHandle, rendered: RenderedSnapshot) -> None:
        gui = client.gui
        with client.atomic():
            self.panel = gui.add_panel()
            for name, svg in rendered.panels:
                with self.panel.add_tab(f"{rendered.label}: {name}"):
                    gui.add_html(f'<div data-egtviz="snapshot" data-label="{escape(rendered.label)}">'
                                 f"<b>{escape(rendered.label)}</b>{svg}</div>")
            try:
                self.panel.float(x=16, y=-16, width=PANE_WIDTH_PX)
            except Exception:  # noqa: BLE001 - placement is cosmetic
                pass

    def remove(self) -> None:
        try:
            self.panel.remove()
        except Exception:  # noqa: BLE001 - gone with a cleared tab
            pass


class RoomSnapshots:
    """The snapshot shown to the room (drawn once) and its pane in each tab of the class."""

    def __init__(self) -> None:
        self._shown: RenderedSnapshot | None = None
        self._panes: dict[int, SnapshotPane] = {}

    def set(self, snapshot: Snapshot | None, *, present: bool) -> None:
        """The snapshot to show (None: none); call :meth:`show_in` for each tab then."""
        self._shown = None if snapshot is None else render_snapshot(snapshot, present=present)

    def forget(self, client_id: int) -> None:
        """The tab was cleared or left: its pane is gone with it."""
        self._panes.pop(client_id, None)

    def show_in(self, client: viser.ClientHandle) -> None:
        """Show the room's snapshot in this tab, or take it away."""
        old = self._panes.pop(client.client_id, None)
        if old is not None:
            old.remove()
        if self._shown is not None:
            self._panes[client.client_id] = SnapshotPane(client, self._shown)
