"""A browser tab's workbench: its ``SceneModel``, its ``WorkbenchController`` and the ``ClientView`` that draws them.

Data flow (one direction)::

    GUI field / gizmo  ->  an intent of the tab's WorkbenchController (judges it)  ->  SceneModel  ->  notification
        ->  model.derived (computed once, at commit)  ->  one `client.atomic()` update of the 3D
            scene, every image-plane panel, the F/E read-out and the fields.

Each browser tab has its own model: edits in one tab never reach another.
A tab's :class:`ClientView` is a small coordinator (the lock, the model
subscription, the render) over parts with one job each: the control panel and
scene actions (:mod:`~egtviz.viewer.workbench.workbench_controls`), one settings folder per
camera (:mod:`~egtviz.viewer.workbench.camera_settings`), gizmo input
(:mod:`~egtviz.viewer.workbench.drag_input`), the panels (:mod:`~egtviz.viewer.workbench.panel_dock`),
the F/E read-out (:mod:`~egtviz.viewer.workbench.readout`), and what a lesson allows
(:mod:`~egtviz.viewer.workbench.lesson_policy`).
Every event handler and every render runs under the view's lock, and a render
always draws the model's *current* scene, so an event that arrives late (viser
runs callbacks in a thread pool) cannot overwrite a newer state. GUI fields are
written back under a guard so that the write does not look like a user edit.

Every input is judged on the server, by the tab's headless controller
(:class:`~egtviz.controllers.workbench.WorkbenchController`): number fields are text fields whose raw
text is parsed and range-checked in the field's own units
(:mod:`egtviz.controllers.workbench_fields`, ranges from :mod:`egtviz.scene.limits`), once the
user stops typing; drop-down values are checked against the options offered,
since a hand-written client can send any string. Every callback is attached
through :func:`~egtviz.viewer.workbench.fields.on_event`: whatever it raises reaches the
tab as a notification, and the fields and gizmos go back to the model's values.
Scene files travel through the browser (download and upload), never by a
server path.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, TypeVar

import viser

from ...controllers.workbench import WorkbenchController
from ...scene import Scene, SceneModel
from .camera_settings import CameraSettings
from .drag_input import DragInput
from .fields import Debouncer, describe_error, notify_error, on_event
from .lesson_policy import ALLOW_ALL, LessonPolicy, PanelFilter
from .panel_dock import PRESENT_LABEL_SCALE, PanelDock, plot_key
from ..render.panels import PanelGrid, WindowSize
from .readout import PairReadout, pair_html
from .scene3d import Scene3D
from ..render.svg import PRESENT, empty_svg
from .tab_context import TabContext
from .workbench_controls import WorkbenchControls
from ..server.viser_adapter import assign_text

if TYPE_CHECKING:
    from ...scene.derived import Derived
    from ...scene.model import Change
    from ..render.png_worker import PngDownloads

__all__ = ["ClientView", "FIELD_DELAY", "PRESENT_LABEL_SCALE", "UpdateTiming", "pair_html"]

#: Changes after which a tab's 3D view is framed on the scene again (what it holds changed, not just a pose).
REFRAME_CHANGES = frozenset({"add_camera", "load"})
#: Seconds a text field must stay unchanged before its value is judged (see :class:`Debouncer`).
FIELD_DELAY = 0.6

#: The event a viser handle passes its callbacks.
E = TypeVar("E")
#: What a text field sent.
T = TypeVar("T")


class OpenDemo(Protocol):
    """``open_demo(kind, **run_fields)``: the tab replaced by a visual-servoing demo."""

    def __call__(self, kind: str, /, **options: object) -> object:
        ...


@dataclass(frozen=True)
class UpdateTiming:
    """What one applied update of a tab cost, by part (the tab's public timing hook, for benchmarks).

    Attributes:
        revision: the tab's revision the update drew.
        wall: wall seconds by part: ``model`` (from the user event to the render's start: the scene model's
            commit and its derived quantities), ``derived``, ``svg`` (the panels), ``fields`` (the read-out and
            the GUI fields), ``scene3d`` and ``flush``.
        cpu: CPU seconds of the rendering thread by part: ``derived``, ``svg``, ``fields``, ``scene3d``,
            ``flush``, ``render`` (their sum and the bookkeeping between them) and ``event`` (from the user
            event's start to the end of the update; 0 for a redraw no event started).
    """

    revision: int
    wall: Mapping[str, float]
    cpu: Mapping[str, float]


class ClientView:
    """One browser tab: the coordinator of its workbench.

    It holds the tab's :attr:`controller` (the scene model and the user's intents), the lock every event and render
    runs under, the model subscription, and the render; the parts it owns map their widgets to the controller's
    intents: :attr:`controls` (the control panel and scene actions), :attr:`cameras` (one
    :class:`~egtviz.viewer.workbench.camera_settings.CameraSettings` per camera folder), :attr:`drag` (gizmo input),
    :attr:`dock` (the panels) and :attr:`pair_readout` (the F/E read-out). A lesson view sets :attr:`policy`.
    The parts get :attr:`context` (a :class:`~egtviz.viewer.workbench.tab_context.TabContext`), never the view.

    Every callback is attached through :func:`egtviz.viewer.workbench.fields.on_event`:
    whatever it raises reaches this tab as a notification, and the fields and
    gizmos go back to the model's values.

    Timing hook: :attr:`on_update_timed` (None, or a callable) is called under the lock after each applied update
    with its :class:`UpdateTiming`; :attr:`timings`, :attr:`breakdown` and :attr:`last_update_wall` keep the last
    ones.

    Args:
        client: a :class:`viser.ClientHandle` (its ``scene``, ``gui``, ``atomic()``
            and ``add_notification`` are used).
        model: the tab's own :class:`SceneModel`.
        open_demo: ``open_demo(kind)`` opens a visual-servoing demo in this tab; None: no such folder.
        field_delay: seconds a text field must stay unchanged before it is judged (0: at once).
        present: start in presentation mode (large type, thick lines: see :data:`egtviz.viewer.render.svg.PRESENT`).
        window: the tab's window and device pixel ratio as a previous workbench measured them (None: ask the tab).
    """

    def __init__(self, client: viser.ClientHandle, model: SceneModel, *, open_demo: OpenDemo | None = None,
                 field_delay: float = FIELD_DELAY, present: bool = False,
                 window: tuple[WindowSize, float] | None = None) -> None:
        self.client = client
        #: The tab's headless controller (its scene model and every intent of the parts); it asks :attr:`policy`
        #: about a typed value (a lesson view may replace the policy after the parts are built).
        self.controller = WorkbenchController(model, field_guard=lambda camera, fields: self.policy.refusal(camera,
                                                                                                            fields))
        #: ``open_demo(kind, **run_fields)`` replaces this tab by a servo demo (the app passes it); None: no demos.
        self.open_demo = open_demo
        self.lock = threading.RLock()
        self.closed = False
        self.revision = 0
        self._syncing = False
        self._typing = Debouncer(field_delay)
        #: Seconds from a user event (field, button, gizmo) to the end of its atomic update (benchmark).
        self.timings: deque[float] = deque(maxlen=5000)
        #: Wall seconds spent in each part of the last update.
        self.breakdown: dict[str, float] = {}
        self.last_update_wall: float = 0.0
        #: Called with each applied update's :class:`UpdateTiming` (under the lock; keep it short).
        self.on_update_timed: Callable[[UpdateTiming], None] | None = None
        #: Called with this view under the lock after each drawn update (its :attr:`svgs` and read-out are then
        #: the ones sent): a classroom sends the very same panels to every follower.
        self.on_rendered: Callable[[ClientView], None] | None = None
        #: Wall and thread-CPU seconds at the start of the user event the next update answers (None: no event).
        self._event_start: tuple[float, float] | None = None
        self.svgs: dict[str, str] = {}
        #: What a lesson allows in this tab (its panel filter and ranges); the workbench allows everything.
        self.policy: LessonPolicy = ALLOW_ALL
        #: Each camera's settings folder, by camera name.
        self.cameras: dict[str, CameraSettings] = {}
        self._camera_sig: tuple = ()
        #: What the parts get of this tab (they never see the view itself).
        self.context = TabContext(
            client=client, controller=self.controller, lock=self.lock, report=self.report, on=self._on,
            user_event=self.user_event, text_event=self.text_event, event_started=self.event_started,
            is_closed=lambda: self.closed, redraw_now=self.redraw_now, policy=lambda: self.policy,
        )
        self.drag = DragInput(self.context)
        self.controls = WorkbenchControls(self.context, open_demo=open_demo)
        with self.lock, client.atomic():
            self.scene3d = Scene3D(client.scene, self.drag.camera_event, self.drag.point_event, report=self.report)
            self.dock = PanelDock(self.context, self.scene3d, present=present, window=window)
            self.scene3d.set_label_scale(PRESENT_LABEL_SCALE if self.present else 1.0)
            self.controls.build(present=self.present)
            self.pair_readout = PairReadout(self.controls.readout_md)
            self.dock.build_controls()
            self._render(self.model.scene, None)
            self.dock.frame_camera()
        self._on(client.camera.on_update, self._on_canvas)
        self._unsubscribe = model.subscribe(self._on_change)

    # -- what the lesson views and the classroom read of the tab ------------------------------------------

    @property
    def model(self) -> SceneModel:
        """The tab's own scene model (its controller's)."""
        return self.controller.model

    @property
    def present(self) -> bool:
        """Whether the tab is in presentation mode."""
        return self.dock.present

    @property
    def window(self) -> tuple[WindowSize, float]:
        """The tab's window in CSS pixels and its device pixels per CSS pixel, as this view estimated them."""
        return self.dock.window, self.dock.pixel_ratio

    @property
    def grid(self) -> PanelGrid | None:
        """Where the panels are; None before the first layout."""
        return self.dock.grid

    @property
    def panel_buttons(self) -> dict[str, dict[str, viser.GuiButtonGroupHandle]]:
        """Each camera's panel buttons (button groups by label)."""
        return self.dock.buttons

    @property
    def present_checkbox(self) -> viser.GuiCheckboxHandle:
        """The "presentation mode" checkbox."""
        return self.dock.present_checkbox

    @property
    def png(self) -> PngDownloads:
        """The panels' PNG downloads (:class:`~egtviz.viewer.render.png_worker.PngDownloads`)."""
        return self.dock.png

    @png.setter
    def png(self, downloads: PngDownloads) -> None:
        self.dock.png = downloads

    @property
    def readout(self) -> str:
        """The F/E read-out's HTML as last shown."""
        return self.pair_readout.text

    @property
    def panel_filter(self) -> PanelFilter | None:
        """The lesson policy's panel filter (None: the panels draw the model's geometry)."""
        return self.policy.panel_filter

    # -- user events ----------------------------------------------------------------

    def _on(self, register: Callable[[Callable[[E], None]], object], callback: Callable[[E], object]) -> None:
        """Attach ``callback`` to a handle's event (``handle.on_update`` ...): errors reach this tab."""
        on_event(register, callback, self.report)

    def event_started(self, t0: float, c0: float) -> None:
        """Mark the start of a user event (wall ``t0``, thread CPU ``c0``); its update's timing counts from it."""
        self._event_start = (t0, c0)

    def user_event(self, action: Callable[[], object]) -> None:
        """Run a user's action under the lock (ignored while fields are written back or after the tab left).

        Errors propagate to :meth:`report` through the callback wrapper.
        """
        t0, c0 = time.perf_counter(), time.thread_time()
        with self.lock:
            if self.closed or self._syncing:
                return
            self.event_started(t0, c0)
            action()

    def text_event(self, key: Hashable, apply: Callable[[T], object], text: T) -> None:
        """A text field changed: judge its text once the user stopped typing (latest text wins)."""
        with self.lock:
            if self.closed or self._syncing:
                return  # our own write-back, or the tab is gone

        def judge() -> None:
            try:
                self.user_event(lambda: apply(text))
            except Exception as exc:  # noqa: BLE001 - from a timer thread: no callback wrapper above us
                self.report(exc)

        self._typing.submit(key, judge)

    def report(self, exc: BaseException) -> None:
        """Tell this tab what went wrong and put every field and gizmo back to the model's values."""
        with self.lock:
            if self.closed:
                return
            notify_error(self.client, exc)
            self.resync()

    def resync(self) -> None:
        """Rewrite every field and put every gizmo back to the model's scene (after a refusal or a failure).

        The panels are left alone: the scene they show has not changed.
        """
        with self.lock:
            scene = self.model.scene
            try:
                with self.client.atomic():
                    self._sync_fields(scene, force=True)
                    self.scene3d.draw(scene, self.model.derived, force=True)
            except Exception:  # noqa: BLE001 - a half-built tab: draw it all again, or show why not
                self._render(scene, None, force_fields=True)

    def _on_canvas(self, camera: viser.CameraHandle) -> None:
        with self.lock:
            if not self.closed:
                self.dock.on_canvas(camera)

    # -- rendering ----------------------------------------------------------------

    def _on_change(self, scene: Scene, change: Change) -> None:
        with self.lock:
            if self.closed:
                return
            # Draw the model's current scene, not the notified one: a late notification never wins.
            self._render(self.model.scene, change)
            if getattr(change, "kind", None) in REFRAME_CHANGES:
                with self.client.atomic():
                    self.dock.frame_camera()  # a new camera or scene: in view, beside the panels it docked

    def redraw(self) -> None:
        """Draw the model's scene again (after something the panels depend on changed outside the model)."""
        with self.lock:
            if not self.closed:
                self._render(self.model.scene, None)

    def redraw_now(self) -> None:
        """Draw the model's scene again; the caller holds the lock (a part's action: a view button, a layout)."""
        self._render(self.model.scene, None)

    def _render(self, scene: Scene, change: Change | None, *, force_fields: bool = False) -> None:
        """Draw ``scene`` (the model's current one) with the model's derived quantities, in one atomic update."""
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            # The model computed (and checked) these when it committed the scene: never computed twice.
            derived = self.model.derived
            if scene is not self.model.scene:
                raise RuntimeError("render: the scene is not the model's current scene")
        except Exception as exc:  # noqa: BLE001 - a bug below must not take the tab down
            self._render_failure(scene, exc)
            return
        wall, cpu = [t0, time.perf_counter()], [c0, time.thread_time()]
        self.revision += 1
        with self.client.atomic():
            # Panels first: within the atomic batch the browser then updates the SVGs before the 3D view.
            self._draw_panels(scene, derived)
            wall.append(time.perf_counter())
            cpu.append(time.thread_time())
            self.pair_readout.show(derived)
            self._sync_fields(scene, force=force_fields)
            wall.append(time.perf_counter())
            cpu.append(time.thread_time())
            self.scene3d.draw(scene, derived, moving=self.drag.moving, force=force_fields)
            wall.append(time.perf_counter())
            cpu.append(time.thread_time())
        # Send now: viser otherwise holds a finished atomic batch for up to one 1/60 s window.
        self.client.flush()
        wall.append(time.perf_counter())
        cpu.append(time.thread_time())
        self._record(wall, cpu)
        if self.on_rendered is not None:
            self.on_rendered(self)

    def _draw_panels(self, scene: Scene, derived: Derived) -> None:
        """Every camera's image-plane panel and every figure plot, as the lesson policy filters them."""
        self._sync_panels(scene)
        highlighted = {int(h.split(":")[1]) for h in scene.highlighted if h.startswith("point:")}
        panel_derived, ringed = self._filtered(scene, derived)
        for spec in scene.cameras:
            plane = panel_derived.image_planes.get(spec.name)
            if plane is not None:
                self._show_panel(spec.name, self.dock.panel_svg(spec.name, plane, scene, highlighted,
                                                                revision=self.revision, drag_step=self.drag.step,
                                                                ringed=ringed))
        for plot in scene.annotations.plots:  # a figure's 2D plots
            key = plot_key(plot.number)
            self._show_panel(key, self.dock.plot_panel_svg(key, plot, revision=self.revision))

    def _show_panel(self, name: str, svg: str) -> None:
        self.svgs[name] = svg
        assign_text(self.dock.html[name], "content", svg)  # the same text is not sent again

    def _record(self, wall: list[float], cpu: list[float]) -> None:
        """Keep the update's timing and hand it to :attr:`on_update_timed`."""
        self.last_update_wall = time.time()
        names = ("derived", "svg", "fields", "scene3d", "flush")
        start = self._event_start
        self.breakdown = {"model": wall[0] - start[0] if start is not None else 0.0}
        self.breakdown.update({k: wall[i + 1] - wall[i] for i, k in enumerate(names)})
        if start is not None:
            self.timings.append(wall[-1] - start[0])
            self._event_start = None
        if self.on_update_timed is not None:
            parts = {k: cpu[i + 1] - cpu[i] for i, k in enumerate(names)}
            parts["render"] = cpu[-1] - cpu[0]
            parts["event"] = cpu[-1] - start[1] if start is not None else 0.0
            self.on_update_timed(UpdateTiming(self.revision, dict(self.breakdown), parts))

    def _filtered(self, scene: Scene, derived: Derived) -> tuple[Derived, frozenset[int]]:
        """What the panels draw: ``derived``, or what the lesson policy makes of it (its failure is reported)."""
        try:
            return self.policy.panels(scene, derived)
        except Exception as exc:  # noqa: BLE001 - the panels then show the model's geometry, and the tab says why
            import traceback

            traceback.print_exception(exc)
            notify_error(self.client, exc)
            return derived, frozenset()

    def _render_failure(self, scene: Scene, exc: BaseException) -> None:
        """Show what failed in every panel and as a notification; fields still follow the model."""
        import traceback

        traceback.print_exception(exc)
        self.revision += 1
        msg = f"cannot draw this scene: {describe_error(exc)[1]}"
        with self.client.atomic():
            self._sync_panels(scene)
            for spec in scene.cameras:
                self._show_panel(spec.name, empty_svg(spec.name, spec.width, spec.height, msg))
            self.pair_readout.fail(msg)
            self._sync_fields(scene)
        notify_error(self.client, exc)

    def _sync_panels(self, scene: Scene) -> None:
        """(Re)build the camera folders when the set of cameras changes, and the panels when their grid does."""
        sig = tuple((c.name, c.model_kind) for c in scene.cameras)
        if sig != self._camera_sig:
            for settings in self.cameras.values():
                settings.remove()
            self.cameras = {}
            self.dock.buttons.clear()
            for spec in scene.cameras:
                # The first two cameras (the drawn pair, usually) start open: their fields are what a lesson edits.
                settings = CameraSettings(self.context, spec, self.controls.cameras_folder,
                                          expand=len(self.cameras) < 2)
                self.cameras[spec.name] = settings
                self.dock.build_buttons(spec.name, settings.folder, settings.fields)
            self._camera_sig = sig
        self.dock.layout(scene)

    def _sync_fields(self, scene: Scene, *, force: bool = True) -> None:
        """Write the model's values into the GUI (guarded: these writes are not user edits).

        ``force=False`` (a render): a camera whose spec is the very object last written is skipped.
        """
        self._syncing = True
        try:
            for spec in scene.cameras:
                settings = self.cameras.get(spec.name)
                if settings is not None:
                    settings.sync(spec, force=force)
            self.controls.sync(scene, force=force)
        finally:
            self._syncing = False

    # -- teardown -------------------------------------------------------------------

    def close(self) -> None:
        """Stop listening; later events for this tab are ignored. The model is dropped."""
        with self.lock:
            if self.closed:
                return
            self.closed = True
            self._typing.close()
            self.dock.close()
            self._unsubscribe()
