"""The panel of a servo demo: the image plane and the two charts of a frame, and the frame's read-out.

:class:`ServoPanel` owns a right-hand viser panel with the image plane (SVG, :mod:`egtviz.viewer.render.servo_svg`) and
two uPlot charts (the controls; the errors in % of their start value), revealed up to the frame shown, and the
read-out line under the playback controls. It formats and sends what the run's
:class:`~egtviz.servo.frames.ServoFrames` hold for a frame; it computes no geometry. Without the panel
(``show_panel=False``) the image is still drawn (:attr:`ServoPanel.svg`), only not sent.
"""

from __future__ import annotations

import math

import numpy as np
import viser
from viser import uplot

from egtviz.controllers.servo import ServoFrameImage
from egtviz.servo import ServoResult
from egtviz.servo.frames import trail_indices

from ..render.servo_svg import ServoImage, servo_image_svg, shared_zero_ranges
from ..render.svg import NORMAL, PRESENT

__all__ = ["ERRORS_TOP_PERCENT", "PANEL_INSET_PX", "PANEL_WIDTH", "PLOT_SAMPLES", "PRESENT_PANEL_WIDTH", "ServoPanel",
           "Y_TICK_SPACE"]

PANEL_WIDTH = 470
#: The panel's width in presentation mode (the image panel is drawn in :data:`egtviz.viewer.render.svg.PRESENT`).
PRESENT_PANEL_WIDTH = 600
#: The panel's width less the image's on screen (the panel's padding and scroll bar; measured in Chromium).
PANEL_INSET_PX = 32
#: Most samples per uPlot series sent per frame (the series are thinned, the newest sample kept).
PLOT_SAMPLES = 300
#: Top of the errors plot's axis (%): above 100 by enough that the "100" tick label is not cut by the frame.
ERRORS_TOP_PERCENT = 115.0
#: Least distance between the y-axis ticks of the controls plot, CSS pixels.
Y_TICK_SPACE = 16

#: ``(label, colour, scale)`` of a plotted series; scale ``v`` is the left axis, ``w`` the right one.
Series = tuple[tuple[str, str, str], ...]


class ServoPanel:
    """What one demo's tab shows of a frame, beside the 3D view.

    Args:
        client: the tab.
        demo: the demo's name (``data-demo`` of its image).
        size: the image's ``(width, height)``, pixels.
        n_points: how many features the image has.
        rim: the mirror's rim in the image (``None``: no mirror).
        present: presentation mode (the image in :data:`~egtviz.viewer.render.svg.PRESENT`, a wider panel).
        control_title: the controls chart's title.
        control_key: the ``result.controls`` series plotted.
        control_series: ``(label, colour, scale)`` per control component.
        dashed_rates: draw the right-axis (angular) series dashed.
        feature_error_label: the errors chart's name of the feature error.
    """

    def __init__(self, client: viser.ClientHandle, *, demo: str, size: tuple[int, int], n_points: int,
                 rim: np.ndarray | None, present: bool, control_title: str, control_key: str, control_series: Series,
                 dashed_rates: bool, feature_error_label: str) -> None:
        self.client, self.demo, self.n_points, self.rim, self.present = client, demo, n_points, rim, present
        self.width, self.height = size
        self.control_title, self.control_key, self.control_series = control_title, control_key, control_series
        self.dashed_rates = dashed_rates
        self.error_series: Series = (("rotation", "#D55E00", "e"), ("translation", "#0072B2", "e"),
                                     (feature_error_label, "#CC79A7", "e"))
        self.panel_width = PRESENT_PANEL_WIDTH if present else PANEL_WIDTH
        self.panel: viser.PanelHandle | None = None
        self.image_html: viser.GuiHtmlHandle | None = None
        self.plot_controls: viser.GuiUplotHandle | None = None
        self.plot_errors: viser.GuiUplotHandle | None = None
        self.readout: viser.GuiHtmlHandle | None = None
        #: The SVG of the image panel as last drawn.
        self.svg = ""
        self.revision = 0

    # -- GUI ----------------------------------------------------------------------------

    def build(self) -> None:
        """Add the right-hand panel: the image and the two charts."""
        gui = self.client.gui
        self.panel = gui.add_panel()
        with self.panel.add_tab("Image and plots"):
            self.image_html = gui.add_html("")
            self.plot_controls = self._uplot(self.control_title, self.control_series, dual=True)
            self.plot_errors = self._uplot("Errors, % of their start value", self.error_series, dual=False)
        self.panel.dock_right()
        self.panel.set_width(self.panel_width)

    def build_readout(self) -> None:
        """Add the frame's read-out line (in the side panel, where it is built)."""
        self.readout = self.client.gui.add_html("")

    def remove(self) -> None:
        """Take the read-out and the right-hand panel out of the tab (the player closes)."""
        for h in (self.readout, self.panel):
            if h is not None:
                h.remove()

    def _uplot(self, title: str, series: Series, *, dual: bool, t_end: float = 1.0) -> viser.GuiUplotHandle:
        ser = [uplot.Series(label="t (s)")]
        for label, colour, scale in series:
            s = uplot.Series(label=label, stroke=colour, width=1.6, scale=scale)
            if scale == "w" and self.dashed_rates:
                s["dash"] = (6, 4)
            ser.append(s)
        axes: tuple[uplot.Axis, ...]
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

    # -- a new run ----------------------------------------------------------------------

    def install(self, r: ServoResult, t_end: float) -> None:
        """Fit the charts to run ``r`` (time axis ``[0, t_end]``; the errors' 100 % named in the legend)."""
        if self.plot_errors is not None:
            e = r.errors
            starts = (f"{math.degrees(e['rotation_error_rad'][0]):.3g}°", f"{100 * e['translation_error'][0]:.3g} cm",
                      f"{e['feature_error_px'][0]:.3g} px")
            ser = list(self.plot_errors.series)
            for j, ((label, _, _), s0) in enumerate(zip(self.error_series, starts)):
                ser[j + 1] = {**ser[j + 1], "label": f"{label} (100% = {s0})"}
            self.plot_errors.series = tuple(ser)
        for plot in (self.plot_controls, self.plot_errors):
            if plot is not None:
                scales = dict(plot.scales or {})  # set when the plot was added
                scales["x"] = {"time": False, "auto": False, "range": (0.0, t_end)}
                if plot is self.plot_controls:
                    scales.update(self.control_scales(r.controls[self.control_key]))
                plot.scales = scales

    def control_scales(self, u: np.ndarray) -> dict[str, uplot.Scale]:
        """Fixed ranges of the two y-axes of the controls plot over the whole run, with 0 at the same height on
        both (``shared_zero_ranges``), so that the curves of the two axes can be compared against zero."""
        spans = []
        for axis in ("v", "w"):
            x = u[:, [j for j, (_, _, scale) in enumerate(self.control_series) if scale == axis]]
            x = x[np.isfinite(x)]
            spans.append((float(x.min()), float(x.max())) if x.size else (0.0, 0.0))
        rv, rw = shared_zero_ranges(spans[0], spans[1], pad=0.15)  # room for a tick label at either end
        return {"v": {"auto": False, "range": rv}, "w": {"auto": False, "range": rw}}

    # -- drawing ------------------------------------------------------------------------

    def idle(self, message: str, colour: str = "#555") -> None:
        """An image with no run: the rim (if any) and ``message``."""
        n = self.n_points
        self.send(ServoImage(demo=self.demo, width=self.width, height=self.height, frame=0,
                             current=np.full((n, 2), np.nan), desired=np.full((n, 2), np.nan),
                             trails=np.zeros((0, n, 2)), rim=self.rim, message=message, message_colour=colour))

    def send(self, img: ServoImage) -> None:
        self.revision += 1
        # Drawn for the width it is shown at, never shrunk to a height (its text would go under the style's sizes):
        # in a short window the plots are under it, a scroll away.
        self.svg = servo_image_svg(img, revision=self.revision, style=PRESENT if self.present else NORMAL,
                                   panel_px=self.panel_width - PANEL_INSET_PX)
        if self.image_html is not None:
            self.image_html.content = self.svg

    def draw_image(self, image: ServoFrameImage) -> None:
        """The image plane at a frame: features, goals, trails and the frame's epipolar geometry."""
        self.send(ServoImage(demo=self.demo, width=self.width, height=self.height, frame=image.frame,
                             current=image.current, desired=image.desired, trails=image.trails, lines=image.lines,
                             conics=list(image.conics), epipoles=image.epipoles, rim=image.rim, caption=image.caption,
                             message=image.message))

    def draw_plots(self, k: int, r: ServoResult) -> None:
        """Both charts revealed up to frame ``k``."""
        if self.plot_controls is None or self.plot_errors is None:
            return
        idx = trail_indices(k, PLOT_SAMPLES)
        t = r.time[idx]
        u = r.controls[self.control_key][idx]
        self.plot_controls.data = (t, *[u[:, j] for j in range(u.shape[1])])
        e = r.errors

        def pct(x: np.ndarray) -> np.ndarray:
            x0 = float(x[0]) if np.isfinite(x[0]) and x[0] > 0 else 1.0
            return 100.0 * x[idx] / x0

        self.plot_errors.data = (t, pct(e["rotation_error_rad"]), pct(e["translation_error"]),
                                 pct(e["feature_error_px"]))

    def show_readout(self, k: int, r: ServoResult) -> None:
        """Frame ``k``'s number, time and errors in words."""
        if self.readout is None:
            return
        e = r.errors
        self.readout.content = (
            f'<div style="font-size:0.82em" data-egtviz="servo-readout">frame {k + 1} / {r.n_samples}, '
            f"t = {r.time[k]:.2f} s<br>rotation error {math.degrees(e['rotation_error_rad'][k]):.3g} deg, "
            f"translation error {100 * e['translation_error'][k]:.3g} cm, "
            f"feature error {e['feature_error_px'][k]:.3g} px</div>")
