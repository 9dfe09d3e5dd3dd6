"""The room's frames: made once from the instructor's drawn update, sent by one thread to every follower.

:func:`frame_of` takes what the instructor's tab has just sent to its own browser (its panels' SVG strings, its
read-out, its scene and derived geometry): nothing is computed again. :class:`RoomSender` gives the newest
frame to each follower in turn; a frame that arrives while it is sending replaces the one waiting (latest
wins), so a room of followers costs the instructor nothing but handing over a reference.
"""

from __future__ import annotations

import itertools
import logging
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

from ...scene import Scene
from .follow_view import FollowView, RoomFrame

if TYPE_CHECKING:
    from ..workbench.app import ClientView

__all__ = ["FrameSender", "RoomSender", "frame_from_scene", "frame_of", "panel_titles"]

_log = logging.getLogger(__name__)


def panel_titles(scene: Scene) -> dict[str, str]:
    """The tab title of each panel key of ``scene``: ``"<camera>: image plane"``, a figure plot's title."""
    from ..workbench.panel_dock import plot_key

    titles = {c.name: f"{c.name}: image plane" for c in scene.cameras}
    titles.update({plot_key(p.number): p.title for p in scene.annotations.plots})
    return titles


def frame_of(view: ClientView, version: int, number: int, caption: str = "") -> RoomFrame:
    """The room's frame of the instructor's :class:`~egtviz.viewer.workbench.app.ClientView` as just drawn
    (``caption``: the lesson step's title and text, HTML)."""
    scene = view.model.scene
    titles = panel_titles(scene)
    panels = tuple((key, titles[key], svg) for key, svg in view.svgs.items() if key in titles)
    return RoomFrame(number, version, scene, view.model.derived, panels, view.readout, bool(view.present), caption)


def frame_from_scene(scene: Scene, version: int, number: int, *, present: bool = False) -> RoomFrame:
    """The room's frame of a shared scene that no tab of this process drew (the instructor works on another
    server process): its derived geometry and panels made here, once, each panel fitted as a new one is, for a
    window of the default size."""
    from ...scene import compute_derived
    from ..render.panels import DEFAULT_WINDOW, PanelView, initial_view, plan_grid
    from ..render.svg import NORMAL, PRESENT, image_plane_svg
    from ..workbench.readout import pair_html

    derived = compute_derived(scene)
    style = PRESENT if present else NORMAL
    grid = plan_grid([(c.name, float(c.width), float(c.height)) for c in scene.cameras], DEFAULT_WINDOW, style=style)
    titles = panel_titles(scene)
    marked = {int(h.split(":")[1]) for h in scene.highlighted if h.startswith("point:")}
    panels = []
    for spec in scene.cameras:
        plane = derived.image_planes.get(spec.name)
        if plane is None:
            continue
        svg = image_plane_svg(plane, selected_point=scene.selected_point, highlighted=marked,
                              show_labels=scene.options.show_labels, revision=version,
                              view=PanelView(initial_view(plane)).resolve(plane), style=style,
                              panel_px=grid.column_px if grid.columns else None,
                              max_height=f"{grid.svg_max_height_px(spec.name):.0f}px" if grid.columns else None)
        panels.append((spec.name, titles[spec.name], svg))
    return RoomFrame(number, version, scene, derived, tuple(panels), pair_html(derived), present)


class FrameSender(Protocol):
    """What sends the room's frames to the followers: a :class:`RoomSender`, or a relay between server processes
    that wraps one (:mod:`egtviz.viewer.server.class_bus`)."""

    @property
    def latest(self) -> RoomFrame | None:
        """The newest frame posted (None before the first)."""

    def next_number(self) -> int:
        """The number of the next frame made."""

    def post(self, frame: RoomFrame) -> None:
        """Make ``frame`` the newest."""

    def clear_pending(self) -> None:
        """A frame waiting need not be sent."""

    def close(self) -> None:
        """Stop sending."""


class RoomSender:
    """One thread that shows the newest :class:`RoomFrame` in every follower.

    Args:
        followers: returns the followers' views now (called once per frame sent).
    """

    def __init__(self, followers: Callable[[], list[FollowView]]) -> None:
        self._followers = followers
        self._cond = threading.Condition()
        self._numbers = itertools.count(1)
        #: The newest frame posted (a new follower starts from it); None before the first.
        self.latest: RoomFrame | None = None
        self._pending = False
        self._closed = False
        #: Frames sent to all followers (each follower shown each frame at most once).
        self.sent = 0
        self._thread = threading.Thread(target=self._run, name="egtviz-room-sender", daemon=True)
        self._thread.start()

    def next_number(self) -> int:
        return next(self._numbers)

    def post(self, frame: RoomFrame) -> None:
        """Make ``frame`` the newest; the sender shows it to every follower as soon as it is free."""
        with self._cond:
            if self.latest is not None and frame.number <= self.latest.number:
                return
            self.latest = frame
            self._pending = True
            self._cond.notify()

    def clear_pending(self) -> None:
        """Students no longer follow: a frame waiting need not be sent."""
        with self._cond:
            self._pending = False

    def _run(self) -> None:
        while True:
            with self._cond:
                while not self._pending and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return
                self._pending = False
                frame = self.latest
            if frame is None:
                continue
            for view in self._followers():
                with self._cond:
                    newer = self.latest
                try:
                    view.show(newer if newer is not None else frame)
                except Exception:  # noqa: BLE001 - one follower's broken tab must not stop the room
                    _log.exception("egtviz classroom: a follower could not be shown the room's scene")
            self.sent += 1

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify()
