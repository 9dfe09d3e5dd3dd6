"""What every visual-servoing demo in the browser shares: its run fields, its playback and its panel.

:class:`ServoPlayer` owns everything a demo shows in one viser client (browser tab) except what is particular to
the demo (its robot in 3D, its extra run fields, its simulation); each demo is a subclass
(:mod:`egtviz.viewer.servo_pinhole_demo`, :mod:`egtviz.viewer.servo_panoramic_demo`):

* GUI: a *Run* folder (seed, the demo's own fields, noise, max steps, Run), a *Playback* folder (Play/Pause,
  step back/forward, speed, time scrubber) and a status line that shows a failed or non-converged run in words;
  every field is validated (:mod:`egtviz.viewer.fields`): a refused value gets a notification and the field
  shows the last valid one;
* 3D nodes under ``/servo/...``: the scene points with their numbers, the viewing rays and the path, drawn from
  the run's :class:`~egtviz.servo.frames.ServoFrames`;
* a panel on the right: the image plane (SVG, :mod:`egtviz.viewer.servo_svg`) and two uPlot charts (controls;
  errors) revealed up to the current time.

The simulation runs in a background thread when *Run* is pressed, and the per-frame geometry
(:mod:`egtviz.servo.frames`) is derived there too: playback only formats and sends. A playback thread advances
the frame at the chosen speed and redraws inside ``client.atomic()``. :meth:`ServoPlayer.close` stops both
threads and removes the demo's nodes and GUI.

A subclass sets the class attributes (``kind``, titles, plots, ``DEFAULT_STEPS``, ``RULES`` and ``CHOICES`` for its
extra run parameters) and implements ``_setup_model``, ``_build_scene``, ``_add_run_fields``, ``_simulate_run``,
``_derive_frames`` and, if it adds parameters, ``_simulation_kwargs``.
"""

from __future__ import annotations

import math
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from html import escape
from typing import Any, ClassVar

import numpy as np
import viser

from egtviz.geometry.poses import quat_wxyz_from_matrix
from egtviz.scene.limits import SERVO_DEMO_STEPS
from egtviz.servo import ServoResult
from egtviz.servo.frames import ServoFrames, trail_indices

from .fields import (
    Debouncer,
    FieldError,
    NumberRule,
    format_number,
    notify_error,
    on_event,
    parse_numbers,
)
from .palette import PRESENT_GUI_CSS, hex_to_rgb, point_colour
from .panels import CONTROL_PX
from .servo_budget import SERVER_BUDGET, ServoBudget, ServoBusy, notify_busy
from .servo_svg import ServoImage, servo_image_svg, shared_zero_ranges
from .svg import NORMAL, PRESENT

__all__ = ["FIELD_DELAY", "PANEL_WIDTH", "RUN_RULES", "SPEEDS", "ServoPlayer"]

SPEEDS = ("0.25x", "0.5x", "1x", "2x", "4x")
PANEL_WIDTH = 470
#: The panel's width in presentation mode (the image panel is drawn in :data:`egtviz.viewer.svg.PRESENT`).
PRESENT_PANEL_WIDTH = 600
#: The panel's width less the image's on screen (the panel's padding and scroll bar; measured in Chromium).
PANEL_INSET_PX = 32
FPS = 15.0
#: Most samples per uPlot series sent per frame (the series are thinned, the newest sample kept).
PLOT_SAMPLES = 300
#: Top of the errors plot's axis (%): above 100 by enough that the "100" tick label is not cut by the frame.
ERRORS_TOP_PERCENT = 115.0
#: What the run fields of every demo accept; a refused value gets a notification and the field shows the last
#: valid one. A demo adds its own (``ServoPlayer.RULES``).
RUN_RULES = {
    "seed": NumberRule("seed", "", 0, 2**32 - 1, integer=True),
    "noise_px": NumberRule("noise", "px", 0.0, 50.0),
    "steps": NumberRule("max steps", "", SERVO_DEMO_STEPS.low, SERVO_DEMO_STEPS.high, integer=True),
}
#: Least distance between the y-axis ticks of the controls plot, CSS pixels.
Y_TICK_SPACE = 16
#: Seconds a run field must stay unchanged before it is judged (see ``fields.Debouncer``).
FIELD_DELAY = 0.6

#: A choice field: its label in messages and its options.
Choice = tuple[str, tuple[str, ...]]


class ServoPlayer(ABC):
    """One servo demo in one browser tab: its scene, its controls and its playback (the shared part).

    Args:
        client: the viser client (tab) to draw in.
        seed: start pose / noise seed.
        noise_px: image noise, pixels.
        steps: maximum number of simulation steps (``None``: the demo's ``DEFAULT_STEPS``).
        speed: playback speed, one of :data:`SPEEDS`.
        autorun: start a run at once (in the background).
        autoplay: play each run as soon as it is ready.
        on_back: if given, a "Back" button calls it (the app uses it to return to the workbench).
        show_panel: add the right-hand panel (image plane and plots).
        field_delay: seconds a run field must stay unchanged before it is judged (0: at once).
        **params: the demo's own run parameters (its ``RULES`` and ``CHOICES``).

    Raises:
        ValueError: a parameter the demo does not have, or a value its rule or choices refuse.
    """

    kind: ClassVar[str]
    """The demo's name (``data-demo`` of its image, the thread names)."""
    TITLE: ClassVar[str]
    INTRO: ClassVar[str]
    """The demo's title and one paragraph (markdown) at the top of the side panel."""
    DEFAULT_STEPS: ClassVar[int]
    RULES: ClassVar[dict[str, NumberRule]] = RUN_RULES
    """Every numeric run parameter and what its field accepts."""
    CHOICES: ClassVar[dict[str, Choice]] = {"speed": ("speed", SPEEDS)}
    """Every drop-down parameter: its label and options."""
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
        **params: Any,
    ) -> None:
        given = {"seed": seed, "noise_px": noise_px, "steps": self.DEFAULT_STEPS if steps is None else steps,
                 "speed": speed, **params}
        #: The last valid value of each run field (what Run uses), in the fields' units.
        self._values: dict[str, Any] = {key: self._checked(key, value) for key, value in given.items()}
        self._typing = Debouncer(field_delay)
        self.client = client
        self.autoplay = autoplay
        #: Presentation mode: large type in the GUI and the image panel (``egtviz serve --present``).
        self.present = bool(present)
        self.panel_width = PRESENT_PANEL_WIDTH if self.present else PANEL_WIDTH
        self.lock = threading.RLock()
        self._closed = threading.Event()
        self._syncing = False
        self._sim_gen = 0
        self._play_gen = 0
        self._sim_thread: threading.Thread | None = None
        self._play_thread: threading.Thread | None = None
        self._listeners: list[Callable[[ServoResult], None]] = []
        self._on_back = on_back
        #: The server's frame budget this demo's runs reserve from (:mod:`egtviz.viewer.servo_budget`).
        self.budget = SERVER_BUDGET if budget is None else budget
        #: The last finished run (``None`` before the first one or after a failed one).
        self.result: ServoResult | None = None
        #: Its per-frame geometry.
        self.frames: ServoFrames | None = None
        #: The frame shown (index into ``result.time``).
        self.frame = 0
        self.playing = False
        self.running = False
        #: The last error message of a run that raised (bad parameters), else "".
        self.error = ""
        #: The SVG of the image panel as last sent.
        self.svg = ""
        self.revision = 0
        #: The run fields by parameter name (numbers and drop-downs; speed is in the Playback folder).
        self.fields: dict[str, Any] = {}
        #: 3D node handles by name.
        self.nodes: dict[str, Any] = {}
        self.rim: np.ndarray | None = None
        self._setup_model()
        with self.lock, client.atomic():
            self._build_scene()
            self._build_gui()
            if show_panel:
                self._build_panel()
            else:
                self.panel = None
                self.image_html = None
                self.plot_controls = None
                self.plot_errors = None
            self._draw_idle("press Run to simulate")
        if autorun:
            self.run()

    # -- what each demo provides ---------------------------------------------------------

    @abstractmethod
    def _setup_model(self) -> None:
        """Set ``points`` (N, 3), ``width``, ``height``, ``target_pose`` and (a mirror) ``rim``."""
        raise NotImplementedError

    @abstractmethod
    def _build_scene(self) -> None:
        """Add the demo's 3D nodes (with ``_add_common_nodes``); ``nodes["body"]`` is posed at
        ``frames.body_poses[k]``."""
        raise NotImplementedError

    def _add_run_fields(self) -> None:
        """Add the demo's own run fields (between seed and noise) with ``_add_number_field``/``_add_choice_field``."""

    @abstractmethod
    def _simulate_run(self, kw: dict[str, Any], progress: Callable[[int, int], None]) -> ServoResult:
        """Run the simulation with the keyword arguments of :meth:`params`."""
        raise NotImplementedError

    @abstractmethod
    def _derive_frames(self, result: ServoResult, stop: Callable[[], bool]) -> ServoFrames | None:
        """The run's per-frame geometry (None if ``stop()`` became True)."""
        raise NotImplementedError

    def _simulation_kwargs(self, values: dict[str, Any]) -> dict[str, Any]:
        """The demo's own simulation keywords from its run values (beside seed, noise and steps)."""
        return {}

    def _caption(self, k: int) -> str:
        """The image caption at frame ``k``."""
        assert self.result is not None
        return f"t = {self.result.time[k]:.2f} s"

    def _draw_body(self, k: int) -> None:
        """Pose the moving body at frame ``k`` (a demo with an arm also poses the arm)."""
        assert self.frames is not None
        H = self.frames.body_poses[k]
        body = self.nodes["body"]
        body.position = H[:3, 3]
        body.wxyz = quat_wxyz_from_matrix(H[:3, :3])

    # -- shared 3D nodes -------------------------------------------------------------------

    def _add_common_nodes(self, *, point_size: float, label_lift: float, label_scale: float, path_width: float,
                          ray_width: float) -> None:
        """The numbered scene points, the path and the viewing rays."""
        api = self.client.scene
        cols = np.array([hex_to_rgb(point_colour(i)) for i in range(len(self.points))], np.uint8)
        self.nodes["points"] = api.add_point_cloud("/servo/points", self.points.astype(np.float32), cols,
                                                   point_size=point_size, point_shape="circle")
        for i, X in enumerate(self.points):
            api.add_label(f"/servo/point_labels/{i}", str(i + 1), position=tuple(X + [0, 0, label_lift]),
                          font_screen_scale=label_scale)
        self.nodes["path"] = api.add_line_segments("/servo/path", np.zeros((1, 2, 3), np.float32), (20, 20, 20),
                                                   thickness=path_width)
        self.nodes["rays"] = api.add_line_segments("/servo/rays", np.zeros((1, 2, 3), np.float32), (120, 120, 120),
                                                   thickness=ray_width)

    def _view(self, look_at: np.ndarray, position: np.ndarray) -> None:
        try:
            cam = self.client.camera
            cam.up_direction = (0.0, 0.0, 1.0)
            cam.position = tuple(float(x) for x in position)
            cam.look_at = tuple(float(x) for x in look_at)
        except Exception:  # noqa: BLE001 - camera placement is cosmetic
            pass

    # -- GUI ----------------------------------------------------------------------------

    def _on(self, register: Any, callback: Any) -> None:
        """Attach ``callback`` to a handle's event: whatever it raises reaches this tab (``fields.on_event``)."""
        on_event(register, callback, self.report)

    def _add_number_field(self, key: str, label: str, hint: str) -> None:
        handle = self.client.gui.add_text(label, format_number(self._values[key]), hint=hint)
        self._on(handle.on_update, lambda e: self._text_event(key, e.target.value))
        self.fields[key] = handle

    def _add_choice_field(self, key: str, label: str, hint: str) -> None:
        handle = self.client.gui.add_dropdown(label, self.CHOICES[key][1], initial_value=self._values[key], hint=hint)
        self._on(handle.on_update, lambda e: self._choice_event(key, e.target.value))
        self.fields[key] = handle

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
        if self._on_back is not None:
            self.btn_back = gui.add_button("Back to the epipolar workbench", icon=viser.Icon.ARROW_LEFT)
            self._on(self.btn_back.on_click, lambda _: self._back())
        else:
            self.btn_back = None
        self.folder_run = gui.add_folder("Run", expand_by_default=True)
        with self.folder_run:
            self._add_number_field("seed", "seed", "Draws the start pose and the image noise: a whole number >= 0.")
            self._add_run_fields()
            self._add_number_field("noise_px", "noise (px)", "Standard deviation of the Gaussian pixel noise, >= 0.")
            self._add_number_field("steps", "max steps",
                                   f"{SERVO_DEMO_STEPS.low:g} to {SERVO_DEMO_STEPS.high:g}; the run stops earlier "
                                   "once the features reach their goal.")
            self.btn_run = gui.add_button("Run", icon=viser.Icon.PLAYER_PLAY)
            self._on(self.btn_run.on_click, lambda _: self.run())
            self.progress = gui.add_progress_bar(0.0, visible=False, animated=True)
        self.status = gui.add_html("")
        self.folder_play = gui.add_folder("Playback", expand_by_default=True)
        with self.folder_play:
            self.btn_play = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY)
            self._on(self.btn_play.on_click, lambda _: self.toggle_play())
            self.btn_step_back = gui.add_button("Step back", icon=viser.Icon.PLAYER_TRACK_PREV)
            self._on(self.btn_step_back.on_click, lambda _: self.step(-1))
            self.btn_step = gui.add_button("Step", icon=viser.Icon.PLAYER_TRACK_NEXT)
            self._on(self.btn_step.on_click, lambda _: self.step(1))
            self._add_choice_field("speed", "speed", "Simulated seconds per real second.")
            self.slider = gui.add_slider("time (s)", min=0.0, max=1.0, step=0.05, initial_value=0.0,
                                         hint="Drag to any time of the run.")
            self._on(self.slider.on_update, self._slider_event)
        self.readout = gui.add_html("")

    # -- field events ----------------------------------------------------------------------

    def _checked(self, key: str, value: Any) -> Any:
        """A run parameter given in code (a number or a field's text, or a choice), checked by its rule."""
        if key in self.CHOICES:
            label, options = self.CHOICES[key]
            if value not in options:
                shown = "".join(c if c.isprintable() else "?" for c in repr(value))[:40]
                raise FieldError(f"{label}: expected one of {', '.join(options)}, got {shown}")
            return value
        rule = self.RULES.get(key)
        if rule is None:
            raise ValueError(f"{key}: not a parameter of the {self.kind} demo")
        if isinstance(value, str):
            (number,) = parse_numbers(value, (rule,))
        elif isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise FieldError(f"{rule.label}: expected a number, got {type(value).__name__}")
        else:
            number = rule.check(float(value))
        return int(number) if rule.integer else float(number)

    def _text_event(self, key: str, text: Any) -> None:
        """A run field changed: judge its text once the user stopped typing (latest text wins)."""
        if self._syncing or self._closed.is_set():
            return

        def judge() -> None:
            try:
                with self.lock:
                    if self._syncing or self._closed.is_set():
                        return
                    (value,) = parse_numbers(text, (self.RULES[key],))
                    self._values[key] = int(value) if self.RULES[key].integer else value
            except Exception as exc:  # noqa: BLE001 - from a timer thread: no callback wrapper above us
                self.report(exc)

        self._typing.submit(key, judge)

    def _choice_event(self, key: str, value: Any) -> None:
        with self.lock:
            if self._syncing or self._closed.is_set():
                return
            self._values[key] = self._checked(key, value)  # a raw client can send any string

    def report(self, exc: BaseException) -> None:
        """Tell this tab what went wrong and show the last valid value in every run field."""
        with self.lock:
            if self._closed.is_set():
                return
            notify_error(self.client, exc)
            self._sync_fields()

    def _sync_fields(self) -> None:
        """Write the last valid run parameters into the fields (not user edits)."""
        self._syncing = True
        try:
            for key, handle in self.fields.items():
                shown = format_number(self._values[key]) if key in self.RULES else self._values[key]
                if handle.value != shown:
                    handle.value = shown
            shown_t = float(min(self.time, self.slider.max))
            if self.slider.value != shown_t:
                self.slider.value = shown_t
        finally:
            self._syncing = False

    # -- the panel -------------------------------------------------------------------------

    def _build_panel(self) -> None:
        gui = self.client.gui
        self.panel = gui.add_panel()
        with self.panel.add_tab("Image and plots"):
            self.image_html = gui.add_html("")
            self.plot_controls = self._uplot(self.CONTROL_TITLE, self.CONTROL_SERIES, dual=True)
            self._error_series = (("rotation", "#D55E00", "e"), ("translation", "#0072B2", "e"),
                                  (self.FEATURE_ERROR_LABEL, "#CC79A7", "e"))
            self.plot_errors = self._uplot("Errors, % of their start value", self._error_series, dual=False)
        self.panel.dock_right()
        self.panel.set_width(self.panel_width)

    def _uplot(self, title: str, series: tuple[tuple[str, str, str], ...], *, dual: bool, t_end: float = 1.0):
        from viser import uplot

        ser = [uplot.Series(label="t (s)")]
        for label, colour, scale in series:
            s = uplot.Series(label=label, stroke=colour, width=1.6, scale=scale)
            if scale == "w" and self.DASHED_RATES:
                s["dash"] = [6, 4]
            ser.append(s)
        if dual:
            scales = {"x": uplot.Scale(time=False, auto=False, range=(0.0, t_end)), "v": uplot.Scale(auto=True),
                      "w": uplot.Scale(auto=True)}
            # Both y-axes span their data on either side of the shared zero: ticks 16 px apart (uPlot's default
            # 30 px leaves only the zero labelled on a 140 px plot).
            axes = (uplot.Axis(label="t (s)"), uplot.Axis(scale="v", label="v (m/s)", space=Y_TICK_SPACE),
                    uplot.Axis(scale="w", side=1, label="ω (rad/s)", grid={"show": False}, space=Y_TICK_SPACE))
        else:
            scales = {"x": uplot.Scale(time=False, auto=False, range=(0.0, t_end)),
                      "e": uplot.Scale(auto=False, range=(0.0, ERRORS_TOP_PERCENT))}
            axes = (uplot.Axis(label="t (s)"), uplot.Axis(scale="e", label="%"))
        data = tuple([np.zeros(1)] + [np.full(1, np.nan) for _ in series])
        return self.client.gui.add_uplot(data, tuple(ser), title=title, scales=scales, axes=axes, height=140,
                                         legend=uplot.Legend(show=True), aspect=2.0)

    # -- public control ------------------------------------------------------------------

    def on_result(self, callback: Callable[[ServoResult], None]) -> None:
        """Call ``callback(result)`` after every finished run (lessons check their tasks here)."""
        self._listeners.append(callback)

    def set_params(self, **params: Any) -> None:
        """Set run parameters (and their fields): ``seed``, ``noise_px``, ``steps``, ``speed`` and the demo's own.

        Raises:
            ValueError: an unknown parameter or one the demo does not use, or a value its rule refuses; nothing
                is changed then.
        """
        new = dict(self._values)
        for key, value in params.items():
            new[key] = self._checked(key, value)
        with self.lock:
            self._values = new
            self._sync_fields()

    def params(self) -> dict[str, Any]:
        """The run parameters the next run uses (the keyword arguments of the simulation)."""
        v = self._values
        return {"seed": int(v["seed"]), "noise_px": float(v["noise_px"]), "steps": int(v["steps"]),
                **self._simulation_kwargs(v)}

    @property
    def n_frames(self) -> int:
        return 0 if self.result is None else self.result.n_samples

    @property
    def time(self) -> float:
        """Simulated time of the frame shown."""
        return 0.0 if self.result is None else float(self.result.time[self.frame])

    def run(self, *, wait: bool = False, timeout: float = 60.0) -> bool:
        """Start a simulation with the GUI's parameters in a background thread; ``False`` if one is running.

        With ``wait`` the call blocks until the run is drawn (or failed).
        """
        with self.lock:
            if self._closed.is_set() or self.running:
                return False
            self.pause()
            self.running = True
            self._sim_gen += 1
            gen = self._sim_gen
            kw = self.params()
            self.btn_run.disabled = True
            self.progress.value = 0.0
            self.progress.visible = True
            self.status.content = self._status_html("running", "Simulating ...")
        self._sim_thread = threading.Thread(target=self._simulate, args=(gen, kw), daemon=True,
                                            name=f"servo-sim-{self.kind}")
        self._sim_thread.start()
        if wait:
            return self.wait(timeout)
        return True

    def wait(self, timeout: float = 60.0) -> bool:
        """Block until no run is in progress; ``True`` if it finished in time."""
        t = self._sim_thread
        if t is not None:
            t.join(timeout)
            return not t.is_alive()
        return True

    def play(self) -> None:
        """Play from the current frame (from the start if at the end)."""
        with self.lock:
            if self._closed.is_set() or self.result is None or self.playing:
                return
            if self.frame >= self.n_frames - 1:
                self._show(0)
            self.playing = True
            self._play_gen += 1
            gen = self._play_gen
            self.btn_play.label = "Pause"
            self.btn_play.icon = viser.Icon.PLAYER_PAUSE
        self._play_thread = threading.Thread(target=self._loop, args=(gen,), daemon=True,
                                             name=f"servo-play-{self.kind}")
        self._play_thread.start()

    def pause(self) -> None:
        with self.lock:
            self._play_gen += 1
            if self.playing:
                self.playing = False
                if not self._closed.is_set():
                    self.btn_play.label = "Play"
                    self.btn_play.icon = viser.Icon.PLAYER_PLAY

    def toggle_play(self) -> None:
        with self.lock:
            if self.playing:
                self.pause()
            else:
                self.play()

    def step(self, n: int = 1) -> None:
        """Pause and move ``n`` frames (negative: back)."""
        with self.lock:
            self.pause()
            if self.result is not None:
                self._show(int(np.clip(self.frame + n, 0, self.n_frames - 1)))

    def seek(self, frame: int) -> None:
        """Show frame ``frame`` (clipped to the run)."""
        with self.lock:
            if self.result is not None:
                self._show(int(np.clip(frame, 0, self.n_frames - 1)))

    def seek_time(self, t: float) -> None:
        """Show the frame at simulated time ``t`` (the nearest sample)."""
        with self.lock:
            if self.result is not None:
                self._show(int(np.argmin(np.abs(self.result.time - float(t)))))

    def close(self, *, client_gone: bool = False) -> None:
        """Stop the threads and remove the demo's 3D nodes and GUI (not when the tab is gone). Idempotent."""
        with self.lock:
            if self._closed.is_set():
                return
            self._closed.set()
            self.budget.release(self)
            self._typing.close()
            self._play_gen += 1
            self._sim_gen += 1
            self.playing = False
        for t in (self._play_thread, self._sim_thread):
            if t is not None and t is not threading.current_thread():
                t.join(2.0)
        if client_gone:
            return  # nothing to remove in a page that no longer exists
        try:
            with self.client.atomic():
                self.client.scene.remove_by_name("/servo")
                for h in (self.title_md, self.btn_back, self.folder_run, self.status, self.folder_play,
                          self.readout, self.panel):
                    if h is not None:
                        h.remove()
        except Exception:  # noqa: BLE001 - the client may be gone already
            pass

    @property
    def closed(self) -> bool:
        return self._closed.is_set()

    # -- background work ---------------------------------------------------------------

    def _simulate(self, gen: int, kw: dict[str, Any]) -> None:
        stale = lambda: self._closed.is_set() or gen != self._sim_gen

        def progress(step: int, steps: int) -> None:
            if not stale():
                self.progress.value = float(min(100.0, 100.0 * step / max(steps, 1)))

        result = frames = None
        error = ""
        try:
            self.budget.reserve(self, kw["steps"] + 1, cancelled=stale,
                                waiting=lambda why: self._say(gen, "warn", f"Queued: {why}"))
        except ServoBusy as exc:
            self._say(gen, "warn", str(exc), running=False)
            notify_busy(self.client, exc)
            return
        self._say(gen, "running", "Simulating ...")
        try:
            result = self._simulate_run(kw, progress)
            frames = self._derive_frames(result, stale)
        except (ValueError, TypeError) as exc:
            error = f"Bad parameters: {exc}"
        except Exception as exc:  # noqa: BLE001 - shown in the UI, never a traceback
            error = f"The simulation failed: {type(exc).__name__}: {exc}"
        with self.lock:
            if stale():
                return
            self.running = False
            with self.client.atomic():
                self.btn_run.disabled = False
                self.progress.visible = False
                if error:
                    self.budget.release(self)
                    self.error = error
                    self.result = None
                    self.frames = None
                    self.status.content = self._status_html("error", error)
                    self._draw_idle(error, colour="#a00")
                else:
                    self.error = ""
                    self.result, self.frames = result, frames
                    self.budget.shrink(self, result.n_samples)
                    self._install_result()
            if error:
                try:
                    self.client.add_notification("Servo run failed", error, color="red", auto_close_seconds=8.0)
                except Exception:  # noqa: BLE001 - the client may be gone
                    pass
                return
        for cb in list(self._listeners):
            try:
                cb(result)
            except Exception as exc:  # noqa: BLE001 - a lesson's callback must not kill the demo
                self.status.content = self._status_html("error", f"lesson check failed: {exc}")
        if self.autoplay:
            self.play()

    def _say(self, gen: int, level: str, text: str, *, running: bool = True) -> None:
        """Show ``text`` in the status line while run ``gen`` is the tab's; ``running=False`` ends the run."""
        with self.lock:
            if self._closed.is_set() or gen != self._sim_gen:
                return
            self.status.content = self._status_html(level, text)
            if not running:
                self.running = False
                self.btn_run.disabled = False
                self.progress.visible = False

    def _install_result(self) -> None:
        r = self.result
        assert r is not None
        t_end = float(r.time[-1]) if r.n_samples > 1 else 1.0
        self._syncing = True
        try:
            self.slider.max = max(t_end, float(r.params.get("dt", 0.05)))
            self.slider.step = float(r.params.get("dt", 0.05))
            self.slider.value = 0.0
        finally:
            self._syncing = False
        if self.plot_errors is not None:
            e = r.errors
            starts = (f"{math.degrees(e['rotation_error_rad'][0]):.3g}°", f"{100 * e['translation_error'][0]:.3g} cm",
                      f"{e['feature_error_px'][0]:.3g} px")
            ser = list(self.plot_errors.series)
            for j, ((label, _, _), s0) in enumerate(zip(self._error_series, starts)):
                ser[j + 1] = {**ser[j + 1], "label": f"{label} (100% = {s0})"}
            self.plot_errors.series = tuple(ser)
        for plot in (self.plot_controls, self.plot_errors):
            if plot is not None:
                scales = dict(plot.scales)
                scales["x"] = {"time": False, "auto": False, "range": (0.0, t_end)}
                if plot is self.plot_controls:
                    scales.update(self._control_scales(r.controls[self.CONTROL_KEY]))
                plot.scales = scales
        if r.converged:
            msg = (f"Converged in {r.sim_time_s:.2f} s ({r.steps} steps): rotation error "
                   f"{math.degrees(r.final_rotation_error_rad):.3g} deg, translation error "
                   f"{100 * r.final_translation_error:.3g} cm.")
            self.status.content = self._status_html("ok", msg)
        else:
            self.status.content = self._status_html("warn", f"Did not converge: {r.reason}")
        self._show(0)

    def _control_scales(self, u: np.ndarray) -> dict[str, dict[str, Any]]:
        """Fixed ranges of the two y-axes of the controls plot over the whole run, with 0 at the same height on
        both (``shared_zero_ranges``), so that the curves of the two axes can be compared against zero."""
        spans = []
        for axis in ("v", "w"):
            x = u[:, [j for j, (_, _, scale) in enumerate(self.CONTROL_SERIES) if scale == axis]]
            x = x[np.isfinite(x)]
            spans.append((float(x.min()), float(x.max())) if x.size else (0.0, 0.0))
        rv, rw = shared_zero_ranges(spans[0], spans[1], pad=0.15)  # room for a tick label at either end
        return {"v": {"auto": False, "range": rv}, "w": {"auto": False, "range": rw}}

    def _loop(self, gen: int) -> None:
        t_last = time.perf_counter()
        with self.lock:
            pos = float(self.frame)
        while not self._closed.wait(1.0 / FPS):
            with self.lock:
                if gen != self._play_gen or not self.playing or self.result is None:
                    return
                now = time.perf_counter()
                dt = float(self.result.params.get("dt", 0.05))
                speed = float(self._values["speed"].rstrip("x"))
                pos += (now - t_last) * speed / dt
                t_last = now
                last = self.n_frames - 1
                k = min(int(pos), last)
                if k != self.frame:
                    self._show(k)
                if k >= last:
                    self.playing = False
                    self.btn_play.label = "Play"
                    self.btn_play.icon = viser.Icon.PLAYER_PLAY
                    return

    def _slider_event(self, event: Any) -> None:
        with self.lock:
            if self._syncing or self._closed.is_set() or self.result is None:
                return
            t = self.slider.value
            if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
                raise FieldError(f"time: expected a number of seconds, got {repr(t)[:40]}")
            self.pause()
            k = int(np.argmin(np.abs(self.result.time - float(t))))
            if k != self.frame:
                self._show(k)

    def _back(self) -> None:
        cb = self._on_back
        if cb is not None:
            cb()

    # -- drawing ------------------------------------------------------------------------

    @staticmethod
    def _status_html(level: str, text: str) -> str:
        colour = {"ok": "#1a7f37", "warn": "#b35900", "error": "#b00020", "running": "#555"}[level]
        return (f'<div data-egtviz="servo-status" data-level="{level}" style="font-size:0.85em;color:{colour};'
                f'padding:2px 0"><b>{escape(text)}</b></div>')

    def _draw_idle(self, message: str, colour: str = "#555") -> None:
        n = len(self.points)
        img = ServoImage(demo=self.kind, width=self.width, height=self.height, frame=0,
                         current=np.full((n, 2), np.nan), desired=np.full((n, 2), np.nan),
                         trails=np.zeros((0, n, 2)), rim=self.rim, message=message, message_colour=colour)
        self._send_svg(img)

    def _send_svg(self, img: ServoImage) -> None:
        self.revision += 1
        # Drawn for the width it is shown at, never shrunk to a height (its text would go under the style's sizes):
        # in a short window the plots are under it, a scroll away.
        self.svg = servo_image_svg(img, revision=self.revision, style=PRESENT if self.present else NORMAL,
                                   panel_px=self.panel_width - PANEL_INSET_PX)
        if self.image_html is not None:
            self.image_html.content = self.svg

    def _show(self, k: int) -> None:
        """Draw frame ``k`` everywhere, in one atomic update (call with the lock held)."""
        r, frames = self.result, self.frames
        if r is None or frames is None or self._closed.is_set():
            return
        self.frame = k
        g = frames.at(k)
        message = g.message
        if k == r.n_samples - 1 and not r.converged:
            message = "did not converge (see the status on the left)"
        img = ServoImage(demo=self.kind, width=self.width, height=self.height, frame=k, current=r.features[k],
                         desired=r.desired_features, trails=frames.trail(k), lines=g.lines, conics=list(g.conics),
                         epipoles=list(g.epipoles), rim=frames.rim, caption=self._caption(k), message=message)
        with self.client.atomic():
            self._send_svg(img)
            self._draw_3d(k)
            self._draw_plots(k)
            self._syncing = True
            try:
                self.slider.value = float(min(r.time[k], self.slider.max))
            finally:
                self._syncing = False
            e = r.errors
            self.readout.content = (
                f'<div style="font-size:0.82em" data-egtviz="servo-readout">frame {k + 1} / {r.n_samples}, '
                f"t = {r.time[k]:.2f} s<br>rotation error {math.degrees(e['rotation_error_rad'][k]):.3g} deg, "
                f"translation error {100 * e['translation_error'][k]:.3g} cm, "
                f"feature error {e['feature_error_px'][k]:.3g} px</div>")

    def _draw_3d(self, k: int) -> None:
        frames = self.frames
        assert frames is not None
        n = self.nodes
        self._draw_body(k)
        path = frames.path_segments(k)
        n["path"].points = path.astype(np.float32) if len(path) else np.zeros((1, 2, 3), np.float32)
        segs, seen = frames.ray_segments(k, self.points)
        if len(seen):
            cols = np.array([hex_to_rgb(point_colour(i)) for i in seen], np.uint8)
            n["rays"].points = segs.astype(np.float32)
            n["rays"].colors = np.repeat(cols[:, None, :], 2, axis=1)
        else:
            n["rays"].points = np.zeros((1, 2, 3), np.float32)

    def _draw_plots(self, k: int) -> None:
        if self.plot_controls is None:
            return
        r = self.result
        idx = trail_indices(k, PLOT_SAMPLES)
        t = r.time[idx]
        u = r.controls[self.CONTROL_KEY][idx]
        self.plot_controls.data = (t, *[u[:, j] for j in range(u.shape[1])])
        e = r.errors

        def pct(x: np.ndarray) -> np.ndarray:
            x0 = float(x[0]) if np.isfinite(x[0]) and x[0] > 0 else 1.0
            return 100.0 * x[idx] / x0

        self.plot_errors.data = (t, pct(e["rotation_error_rad"]), pct(e["translation_error"]),
                                 pct(e["feature_error_px"]))
