"""What every visual-servoing demo in the browser shares: its run fields, its playback and its panel.

:class:`ServoPlayer` owns everything a demo shows in one viser client (browser tab) except what is particular to
the demo (its robot in 3D, its extra run fields, its simulation); each demo is a subclass
(:mod:`egtviz.viewer.servo.servo_pinhole_demo`, :mod:`egtviz.viewer.servo.servo_panoramic_demo`). The player is a small
coordinator (the tab's lock, the run shown, the 3D nodes) over three parts, each in its own module:

* the run form (:class:`~egtviz.viewer.servo.servo_run_form.ServoRunForm`): a *Run* folder (seed, the demo's own fields,
  noise, max steps, Run) and a status line that shows a failed or non-converged run in words; every field's text is
  judged by the controller (:mod:`egtviz.controllers.servo_run`): a refused value gets a notification and the field
  shows the last valid one. *Run* simulates in a background thread, within the server's frame budget
  (:mod:`egtviz.controllers.servo_budget`), and derives the per-frame geometry (:mod:`egtviz.servo.frames`) there too:
  playback only formats and sends;
* the playback clock (:class:`~egtviz.viewer.servo.servo_clock.ServoClock`): a *Playback* folder (Play/Pause, step
  back/forward, speed, time scrubber) and a playback thread that advances the frame at the chosen speed;
* the panel (:class:`~egtviz.viewer.servo.servo_panel.ServoPanel`): on the right, the image plane (SVG,
  :mod:`egtviz.viewer.render.servo_svg`) and two uPlot charts (controls; errors) revealed up to the current time, and the
  frame's read-out.

What the demo is (its run values, its last run, the frame shown, playing or not) is its headless
:class:`~egtviz.controllers.servo.ServoController` (:attr:`ServoPlayer.controller`), with the demo's model
(:mod:`egtviz.controllers.servo_demos`): the parts map widgets to its intents and draw its state.

The player draws the 3D nodes under ``/servo/...`` (:class:`~egtviz.viewer.servo.servo_nodes.ServoNodes`: the
moving body, the scene points with their numbers, the viewing rays and the path) from the run's
:class:`~egtviz.servo.frames.ServoFrames`, and each frame everywhere inside ``client.atomic()``. The GUI handles
belong to the part that adds them (``form.fields``, ``form.status``, ``clock.slider``, ``display.plot_controls``,
...). :meth:`ServoPlayer.close` stops both threads and removes the demo's nodes and GUI.

A subclass passes its model (whose ``RULES`` and ``CHOICES`` hold its extra run parameters), sets the class
attributes (titles, plots) and implements ``_build_scene`` and ``_add_run_fields``.
"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import ClassVar

import numpy as np
import viser

from egtviz.controllers.servo import ServoController
from egtviz.controllers.servo_budget import ServoBudget
from egtviz.controllers.servo_demos import ServoDemoModel, SimulationKwargs
from egtviz.servo import ServoResult
from egtviz.servo.frames import ServoFrames

from ..workbench.fields import notify_error, on_event
from ..render.palette import PRESENT_GUI_CSS
from ..render.panels import CONTROL_PX
from .servo_clock import FPS, ServoClock
from .servo_nodes import ServoNodes, add_common_nodes, look_from, pose_node
from .servo_panel import PANEL_WIDTH, PRESENT_PANEL_WIDTH, ServoPanel
from .servo_run_form import RunField, RunHooks, ServoRunForm

__all__ = ["FIELD_DELAY", "FPS", "PANEL_WIDTH", "PRESENT_PANEL_WIDTH", "ServoPlayer"]

#: Seconds a run field must stay unchanged before it is judged (see ``fields.Debouncer``).
FIELD_DELAY = 0.6


class ServoPlayer(ABC):
    """One servo demo in one browser tab: its scene, its controls and its playback (the shared part).

    Lessons and tests drive a demo through the player's methods; its GUI handles are its parts'
    (:attr:`form`, :attr:`clock`, :attr:`display`), the run fields also :attr:`fields`.

    Args:
        client: the viser client (tab) to draw in.
        model: the demo's model (its camera, scene, run parameters and simulation).
        seed: start pose / noise seed.
        noise_px: image noise, pixels.
        steps: maximum number of simulation steps (``None``: the demo's ``DEFAULT_STEPS``).
        speed: playback speed, one of :data:`~egtviz.controllers.servo_demos.SPEEDS`.
        autorun: start a run at once (in the background).
        autoplay: play each run as soon as it is ready.
        on_back: if given, a "Back" button calls it (the app uses it to return to the workbench).
        show_panel: add the right-hand panel (image plane and plots).
        field_delay: seconds a run field must stay unchanged before it is judged (0: at once).
        budget: the server's frame budget this demo's runs reserve from (:mod:`egtviz.controllers.servo_budget`).
        present: presentation mode: large type in the GUI and the image panel (``egtviz serve --present``).
        **params: the demo's own run parameters (its model's ``RULES`` and ``CHOICES``).

    Raises:
        ValueError: a parameter the demo does not have, or a value its rule or choices refuse.
    """

    TITLE: ClassVar[str]
    INTRO: ClassVar[str]
    """The demo's title and one paragraph (markdown) at the top of the side panel."""
    CONTROL_TITLE: ClassVar[str]
    CONTROL_KEY: ClassVar[str]
    """The ``result.controls`` series plotted."""
    CONTROL_SERIES: ClassVar[tuple[tuple[str, str, str], ...]]
    """``(label, colour, scale)`` per control component; scale ``v`` is the left axis, ``w`` the right one."""
    DASHED_RATES: ClassVar[bool] = False
    """Draw the right-axis (angular) series dashed."""
    FEATURE_ERROR_LABEL: ClassVar[str] = "features"

    def __init__(
        self,
        client: viser.ClientHandle,
        model: ServoDemoModel,
        *,
        seed: int = 0,
        noise_px: float = 0.0,
        steps: int | None = None,
        speed: str = "1x",
        autorun: bool = True,
        autoplay: bool = True,
        on_back: Callable[[], None] | None = None,
        show_panel: bool = True,
        field_delay: float = FIELD_DELAY,
        budget: ServoBudget | None = None,
        present: bool = False,
        **params: object,
    ) -> None:
        #: The demo without its page: run values, run, frame shown (:mod:`egtviz.controllers.servo`).
        self.controller = ServoController(model, seed=seed, noise_px=noise_px, steps=steps, speed=speed,
                                          budget=budget, owner=self, **params)
        self.client = client
        self.autoplay = autoplay
        self.present = bool(present)
        self.lock = threading.RLock()
        self._closed = threading.Event()
        self._listeners: list[Callable[[ServoResult], None]] = []
        self._on_back = on_back
        hooks = RunHooks(report=self.report, land=self._land, finished=self._finished, before_run=self.pause)
        #: The run fields and the Run action (:mod:`egtviz.viewer.servo.servo_run_form`).
        self.form = ServoRunForm(self.controller, client=client, field_delay=field_delay, lock=self.lock,
                                 closed=self._closed, hooks=hooks)
        #: The *Playback* folder and thread (:mod:`egtviz.viewer.servo.servo_clock`).
        self.clock = ServoClock(self.controller, lock=self.lock, closed=self._closed, show=self._show,
                                name=f"servo-play-{self.kind}")
        #: The image plane, the charts and the read-out (:mod:`egtviz.viewer.servo.servo_panel`).
        self.display = ServoPanel(client, demo=self.kind, size=(model.width, model.height),
                                  n_points=len(model.points), rim=model.rim, present=self.present, control_title=self.CONTROL_TITLE,
                                  control_key=self.CONTROL_KEY, control_series=self.CONTROL_SERIES,
                                  dashed_rates=self.DASHED_RATES, feature_error_label=self.FEATURE_ERROR_LABEL)
        with self.lock, client.atomic():
            #: The 3D nodes posed at every frame.
            self.nodes: ServoNodes = self._build_scene()
            self._build_gui()
            if show_panel:
                self.display.build()
            self.display.idle("press Run to simulate")
        if autorun:
            self.run()

    # -- what each demo provides ---------------------------------------------------------

    @abstractmethod
    def _build_scene(self) -> ServoNodes:
        """Add the demo's 3D nodes; the shared ones last, with ``_add_common_nodes`` (its ``body`` is posed at
        ``frames.body_poses[k]``)."""
        raise NotImplementedError

    def _add_run_fields(self) -> None:
        """Add the demo's own run fields (between seed and noise) with ``form.add_number_field`` and
        ``form.add_choice_field``."""

    def _draw_body(self, k: int) -> None:
        """Pose the moving body at frame ``k`` (a demo with an arm also poses the arm)."""
        assert self.frames is not None
        pose_node(self.nodes.body, self.frames.body_poses[k])

    # -- shared 3D nodes -------------------------------------------------------------------

    def _add_common_nodes(self, body: viser.SceneNodeHandle, **sizes: float) -> ServoNodes:
        """The numbered scene points, the path and the viewing rays; with ``body``, the nodes posed at every frame
        (``servo_nodes.add_common_nodes``)."""
        return add_common_nodes(self.client.scene, self.controller.model.points, body, **sizes)

    def _view(self, look_at: np.ndarray, position: np.ndarray) -> None:
        look_from(self.client, look_at, position)

    # -- GUI ----------------------------------------------------------------------------

    def _build_gui(self) -> None:
        gui = self.client.gui
        gui.configure_theme(dark_mode=False, show_logo=False)
        try:
            gui.main_panel.dock_left()
            gui.main_panel.set_width(CONTROL_PX["present" if self.present else "normal"])
        except Exception:  # noqa: BLE001 - placement is cosmetic
            pass
        if self.present:
            gui.add_html(PRESENT_GUI_CSS)
        self.title_md = gui.add_markdown(f"**{self.TITLE}**  \n{self.INTRO}")
        self.btn_back: viser.GuiButtonHandle | None
        if self._on_back is not None:
            self.btn_back = gui.add_button("Back to the epipolar workbench", icon=viser.Icon.ARROW_LEFT)
            on_event(self.btn_back.on_click, lambda _: self._back(), self.report)
        else:
            self.btn_back = None
        self.form.build(self._add_run_fields)
        self.clock.build(gui, self.report,
                         lambda: self.form.add_choice_field("speed", "speed", "Simulated seconds per real second."))
        self.display.build_readout()

    def report(self, exc: BaseException) -> None:
        """Tell this tab what went wrong and show the last valid value in every run field."""
        with self.lock:
            if self._closed.is_set():
                return
            notify_error(self.client, exc)
            self.form.sync()
            self.clock.sync()

    # -- public control ------------------------------------------------------------------

    def on_result(self, callback: Callable[[ServoResult], None]) -> None:
        """Call ``callback(result)`` after every finished run (lessons check their tasks here)."""
        self._listeners.append(callback)

    def set_params(self, **params: object) -> None:
        """Set run parameters (and their fields): ``seed``, ``noise_px``, ``steps``, ``speed`` and the demo's own.

        Raises:
            ValueError: an unknown parameter or one the demo does not use, or a value its rule refuses; nothing
                is changed then.
        """
        with self.lock:
            self.form.set_params(**params)
            self.clock.sync()

    def params(self) -> SimulationKwargs:
        """The run parameters the next run uses (the keyword arguments of the simulation)."""
        return self.controller.params()

    def run(self, *, wait: bool = False, timeout: float = 60.0) -> bool:
        """Start a simulation with the GUI's parameters in a background thread; ``False`` if one is running.

        With ``wait`` the call blocks until the run is drawn (or failed).
        """
        if not self.form.run():
            return False
        if wait:
            return self.wait(timeout)
        return True

    def wait(self, timeout: float = 60.0) -> bool:
        """Block until no run is in progress; ``True`` if it finished in time."""
        return self.form.wait(timeout)

    def play(self) -> None:
        """Play from the current frame (from the start if at the end)."""
        self.clock.play()

    def pause(self) -> None:
        self.clock.pause()

    def toggle_play(self) -> None:
        self.clock.toggle_play()

    def step(self, n: int = 1) -> None:
        """Pause and move ``n`` frames (negative: back)."""
        self.clock.step(n)

    def seek(self, frame: int) -> None:
        """Show frame ``frame`` (clipped to the run)."""
        self.clock.seek(frame)

    def seek_time(self, t: float) -> None:
        """Show the frame at simulated time ``t`` (the nearest sample)."""
        self.clock.seek_time(t)

    def close(self, *, client_gone: bool = False) -> None:
        """Stop the threads and remove the demo's 3D nodes and GUI (not when the tab is gone). Idempotent."""
        with self.lock:
            if self._closed.is_set():
                return
            self._closed.set()
            sim_thread = self.form.cancel()
            self.clock.halt()
        for t in (self.clock.thread, sim_thread):
            if t is not None and t is not threading.current_thread():
                t.join(2.0)
        if client_gone:
            return  # nothing to remove in a page that no longer exists
        try:
            with self.client.atomic():
                self.client.scene.remove_by_name("/servo")
                self.title_md.remove()
                if self.btn_back is not None:
                    self.btn_back.remove()
                self.form.remove()
                self.clock.remove()
                self.display.remove()
        except Exception:  # noqa: BLE001 - the client may be gone already
            pass

    # -- state of the parts ---------------------------------------------------------------

    @property
    def kind(self) -> str:
        """The demo's name (``data-demo`` of its image, the thread names)."""
        return self.controller.kind

    @property
    def closed(self) -> bool:
        return self._closed.is_set()

    @property
    def result(self) -> ServoResult | None:
        """The last finished run (``None`` before the first one or after a failed one)."""
        return self.controller.result

    @property
    def frames(self) -> ServoFrames | None:
        """The last run's per-frame geometry."""
        return self.controller.frames

    @property
    def fields(self) -> dict[str, RunField]:
        """The run fields by parameter name (numbers and drop-downs; speed is in the Playback folder)."""
        return self.form.fields

    @property
    def n_frames(self) -> int:
        return self.controller.n_frames

    @property
    def time(self) -> float:
        """Simulated time of the frame shown."""
        return self.controller.time

    @property
    def frame(self) -> int:
        """The frame shown (index into ``result.time``)."""
        return self.controller.frame

    @property
    def playing(self) -> bool:
        return self.controller.playing

    @property
    def running(self) -> bool:
        """A run is being simulated (or waits for frames)."""
        return self.controller.running

    @property
    def error(self) -> str:
        """The last error message of a run that raised (bad parameters), else ""."""
        return self.controller.error

    @property
    def svg(self) -> str:
        """The SVG of the image panel as last drawn."""
        return self.display.svg

    @property
    def revision(self) -> int:
        return self.display.revision

    @property
    def _play_thread(self) -> threading.Thread | None:
        return self.clock.thread

    # -- a run ends, a frame is drawn ------------------------------------------------------

    def _land(self) -> None:
        """The controller took its run's outcome (the lock held, in one atomic update): show it, or the error."""
        result = self.controller.result
        if result is None:
            self.display.idle(self.controller.error, colour="#a00")
            return
        t_end, dt = self.controller.time_span()
        self.clock.rewind(t_end, dt)
        self.display.install(result, t_end)
        self.form.show_status()
        self._show(0)

    def _finished(self, result: ServoResult) -> None:
        """A good run was drawn: tell the listeners (a lesson's checks), then play it if asked to."""
        for cb in list(self._listeners):
            try:
                cb(result)
            except Exception as exc:  # noqa: BLE001 - a lesson's callback must not kill the demo
                self.form.say("error", f"lesson check failed: {exc}")
        if self.autoplay:
            self.play()

    def _back(self) -> None:
        cb = self._on_back
        if cb is not None:
            cb()

    def _show(self, k: int) -> None:
        """Draw frame ``k`` (the controller's) everywhere, in one atomic update (call with the lock held)."""
        r, frames = self.result, self.frames
        if r is None or frames is None or self._closed.is_set():
            return
        with self.client.atomic():
            self.display.draw_image(self.controller.image(k))
            self._draw_3d(k)
            self.display.draw_plots(k, r)
            self.clock.show_time(r.time[k])
            self.display.show_readout(k, r)

    def _draw_3d(self, k: int) -> None:
        assert self.frames is not None
        self._draw_body(k)
        self.nodes.draw_path_and_rays(self.frames, k, self.controller.model.points)
