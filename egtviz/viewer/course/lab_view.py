r"""The estimation lab in a tab: its sliders, every fit side by side, their errors plotted, the inlier mask.

The numbers come from :func:`egtviz.scene.lab.run_lab`; this module only shows them:

* sliders for the pixel noise :math:`\sigma` (px), the share of outliers (%) and RANSAC's threshold
  :math:`\tau` (px), with a sentence saying what :math:`\tau` means at the current noise;
* a table of the six fits (mean Sampson error against the measured and the true pixels, px²; the
  epipole errors, px; for the robust fits the recall of the true inliers and the threshold used);
* a uPlot chart of the errors per method (their base-10 logarithms: they span many decades);
* in the image-plane panels (:meth:`LabPanel.panel_filter`, the panel filter of the tab's lesson policy): the
  measured pixels, and the epipolar lines and epipoles of the fit chosen in "fit in the panels"; a ring marks
  each correspondence a robust fit rejected (when there are at most :data:`MAX_RINGS` of them: a ring is
  numbered, and more numbers would hide the image);
* in 3D, the scene points the lab used, green when the chosen robust fit kept them, grey when it rejected them.

The settings belong to the lesson (:attr:`egtviz.lessons.LessonRun.lab`): a slider applies a ``set_lab``
change through the run (:func:`egtviz.controllers.lesson_instruments.set_lab`), so the lesson's checks see what
the lab shows; the panels through the lab are :func:`egtviz.controllers.lesson_instruments.through_lab`'s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from html import escape

import numpy as np
import viser
from viser import uplot

from ...controllers.lesson_instruments import MAX_RINGS, LessonInstruments, set_lab, through_lab
from ...scene import Derived, Scene, SceneError
from ...scene.limits import LAB_NOISE_PX, LAB_OUTLIER_PERCENT, LAB_THRESHOLD_PX
from ...scene.lab import (
    METHOD_TITLES,
    METHODS,
    ROBUST_METHODS,
    LabResult,
    run_lab,
)
from ...controllers.workbench_fields import FieldError, format_number
from ..workbench.fields import on_event

__all__ = ["LabPanel", "fits_table_html", "threshold_text"]

#: Colours of the 3D inlier mask (Okabe-Ito green; a neutral grey).
INLIER_RGB = (0, 158, 115)
REJECTED_RGB = (150, 150, 150)
#: The sliders' steps.
NOISE_STEP, OUTLIER_STEP, THRESHOLD_STEP = 0.1, 1.0, 0.05
#: The sliders offer up to these values (the lab accepts up to :data:`LAB_THRESHOLD_PX`; lessons stay below).
THRESHOLD_SLIDER_MAX = 50.0


def _num(x: float, digits: int = 3) -> str:
    return "-" if not math.isfinite(x) else f"{x:.{digits}g}"


def threshold_text(threshold_px: float, noise_px: float) -> str:
    """What RANSAC's threshold means, in pixels, at the current noise (Markdown)."""
    lo, hi = 2.0 * noise_px, 3.0 * noise_px
    return (
        f"**Threshold \u03c4 = {format_number(threshold_px)} px**: RANSAC keeps a correspondence as an inlier "
        f"when its Sampson distance from F is below \u03c4, that is, when it can be moved by less than about "
        f"\u03c4 pixels onto a pair with m\u2082\u1d40 F m\u2081 = 0. With \u03c3 = {format_number(noise_px)} px "
        f"of noise, \u03c4 = 2\u03c3 to 3\u03c3 ({format_number(lo)} to {format_number(hi)} px) keeps nearly every "
        "true inlier and rejects gross mismatches."
    )


def fits_table_html(result: LabResult, drawn: str) -> str:
    """Every fit of ``result`` side by side (the one drawn in the panels in bold)."""
    rows = []
    for f in result.fits:
        weight = "font-weight:bold;" if f.method == drawn else ""
        if f.F is None:
            rows.append(f'<tr data-method="{f.method}" style="{weight}"><td>{escape(f.title)}</td>'
                        f'<td colspan="4">failed: {escape(str(f.message))[:80]}</td></tr>')
            continue
        e1, e2 = f.epipole_error_px
        robust = f.method in ROBUST_METHODS
        recall = f"{100 * f.inlier_recall:.0f}%" if robust and math.isfinite(f.inlier_recall) else "-"
        thr = _num(f.threshold_px) if robust else "-"
        rows.append(
            f'<tr data-method="{f.method}" style="{weight}"><td>{escape(f.title)}</td>'
            f'<td data-kind="sampson-true">{_num(f.sampson_true)}</td><td>{_num(f.sampson_noisy)}</td>'
            f"<td>{_num(max(e1, e2) if math.isfinite(e1) and math.isfinite(e2) else math.nan)}</td>"
            f'<td data-kind="recall">{recall}</td><td>{thr}</td></tr>'
        )
    n = len(result.data.outlier)
    shown = result.fit(drawn)
    note = f"In the panels: the {escape(shown.title)} fit's epipolar lines and epipoles."
    if shown.inliers is not None:
        rejected = int(np.count_nonzero(~shown.inliers))
        note += (f" It rejected {rejected} correspondences: " + ("ringed in the panels; " if rejected <= MAX_RINGS
                 else "too many to ring; ") + "grey in 3D, its inliers green.")
    return (
        '<div style="font-size:0.72em" data-egtviz="lab-table">'
        f"{n} correspondences, {int(result.data.outlier.sum())} outliers. Mean Sampson error (px\u00b2) against "
        "the <b>true</b> and the <b>measured</b> pixels of the true inliers; the larger epipole error (px); the "
        "share of true inliers kept; the threshold used (px)."
        '<table style="width:100%;text-align:right"><tr><th style="text-align:left">fit</th><th>true</th>'
        f"<th>meas.</th><th>epip.</th><th>kept</th><th>\u03c4</th></tr>{''.join(rows)}</table>"
        f'<span data-kind="panels-note">{note}</span></div>'
    )


class LabPanel:
    """The estimation lab's folder in a lesson tab.

    Args:
        client: the tab's viser client (its ``gui`` and ``scene``).
        run: the lesson run whose ``lab`` settings are shown and changed.
        redraw: redraws the tab (the panels pass through :meth:`panel_filter` again).
        report: receives what a callback raises (the tab's notification).
        order: the folder's place in the control panel.
        drawn: the fit first drawn in the panels.
    """

    def __init__(self, client: viser.ClientHandle, run: LessonInstruments, *, redraw: Callable[[], None],
                 report: Callable[[BaseException], None], order: float, drawn: str = "normalized") -> None:
        self.client = client
        self.run = run
        self._redraw = redraw
        self._syncing = False
        self.drawn = drawn
        #: The last lab result shown (None: the lab cannot run on this scene).
        self.result: LabResult | None = None
        self._shown: tuple | None = None
        gui = client.gui
        lab = run.lab
        self.folder = gui.add_folder("Estimation lab", order=order, expand_by_default=True)
        with self.folder:
            self.noise = gui.add_slider("noise \u03c3 (px)", min=LAB_NOISE_PX.low, max=LAB_NOISE_PX.high,
                                        step=NOISE_STEP, initial_value=lab.noise_px,
                                        hint="Standard deviation of the Gaussian noise added to every pixel.")
            self.outliers = gui.add_slider("outliers (%)", min=LAB_OUTLIER_PERCENT.low, max=LAB_OUTLIER_PERCENT.high,
                                           step=OUTLIER_STEP, initial_value=lab.outlier_percent,
                                           hint="Share of the correspondences whose image-2 pixel is random.")
            self.threshold = gui.add_slider("threshold \u03c4 (px)", min=LAB_THRESHOLD_PX.low,
                                            max=max(THRESHOLD_SLIDER_MAX, lab.threshold_px), step=THRESHOLD_STEP,
                                            initial_value=lab.threshold_px, hint="RANSAC's inlier threshold.")
            self.meaning = gui.add_markdown(threshold_text(lab.threshold_px, lab.noise_px))
            self.fit_dropdown = gui.add_dropdown("fit in the panels", tuple(METHOD_TITLES[m] for m in METHODS),
                                                 initial_value=METHOD_TITLES[drawn])
            self.table = gui.add_html("")
            x = np.arange(1.0, len(METHODS) + 1.0)
            nan = np.full(len(METHODS), np.nan)
            self.plot = gui.add_uplot(
                (x, nan, nan.copy()),
                (uplot.Series(label="fit"),
                 uplot.Series(label="vs true", stroke="#0072B2", width=1.5, points={"show": True, "size": 7}),
                 uplot.Series(label="vs measured", stroke="#D55E00", width=1.5, points={"show": True, "size": 7})),
                title="log\u2081\u2080 of the mean Sampson error (px\u00b2)",
                scales={"x": uplot.Scale(time=False, auto=False, range=(0.5, len(METHODS) + 0.5))},
                axes=(uplot.Axis(label="fit (the table's order)"), uplot.Axis(label="log\u2081\u2080 px\u00b2")),
                legend=uplot.Legend(show=True), height=170, aspect=1.6, padding=(12, 16, 0, 0),
            )
        for slider, key in ((self.noise, "noise_px"), (self.outliers, "outlier_percent"),
                            (self.threshold, "threshold_px")):
            on_event(slider.on_update, self._setter(key), report)
        on_event(self.fit_dropdown.on_update, lambda e: self._choose(e.target.value), report)

    # -- events ---------------------------------------------------------------------------

    def _setter(self, key: str) -> Callable[[viser.GuiEvent[viser.GuiSliderHandle[float]]], None]:
        """The update callback of the slider for setting ``key``."""
        return lambda event: self._set(key, event.target.value)

    def _set(self, key: str, value: object) -> None:
        if self._syncing:
            return
        if isinstance(value, bool) or not isinstance(value, (int, float)):  # a raw client can send anything
            raise FieldError(f"estimation lab: {key} must be a number, got {str(value)[:40]!r}")
        set_lab(self.run, key, float(value))
        self._redraw()

    def _choose(self, title: object) -> None:
        if self._syncing:
            return
        methods = {METHOD_TITLES[m]: m for m in METHODS}
        if title not in methods:
            raise FieldError(f"fit in the panels: expected one of {', '.join(methods)}, got {str(title)[:40]!r}")
        self.drawn = methods[title]
        self._redraw()

    def sync(self) -> None:
        """Show the run's settings (after a step changed them)."""
        lab = self.run.lab
        self._syncing = True
        try:
            self.threshold.max = max(self.threshold.max, lab.threshold_px)
            for handle, value in ((self.noise, lab.noise_px), (self.outliers, lab.outlier_percent),
                                  (self.threshold, lab.threshold_px)):
                if handle.value != value:
                    # viser's value setter sits apart from its getter: mypy takes the property as read-only.
                    handle.value = value  # type: ignore[misc]
        finally:
            self._syncing = False

    # -- drawing ----------------------------------------------------------------------------

    def _show(self, result: LabResult) -> None:
        lab = result.settings
        self.meaning.content = threshold_text(lab.threshold_px, lab.noise_px)
        self.table.content = fits_table_html(result, self.drawn)
        by = {f.method: f for f in result.fits}
        true = np.array([by[m].sampson_true if m in by else np.nan for m in METHODS])
        noisy = np.array([by[m].sampson_noisy if m in by else np.nan for m in METHODS])
        # The logarithm of 0: a perfect fit is drawn at a floor far below any noise.
        floor = 1e-12
        self.plot.data = (np.arange(1.0, len(METHODS) + 1.0), np.log10(np.maximum(true, floor)),
                          np.log10(np.maximum(noisy, floor)))

    def _mask_3d(self, scene: Scene, result: LabResult | None) -> None:
        fit = result.fit(self.drawn) if result is not None else None
        if result is None or fit is None or fit.inliers is None:
            self.client.scene.add_point_cloud("/lab/inliers", points=np.zeros((0, 3)), colors=(0, 0, 0),
                                              point_size=0.12, visible=False)
            return
        X = scene.points_array()[result.data.point_indices]
        colours = np.where(fit.inliers[:, None], np.array(INLIER_RGB), np.array(REJECTED_RGB)).astype(np.uint8)
        self.client.scene.add_point_cloud("/lab/inliers", points=X.astype(np.float32), colors=colours,
                                          point_size=0.12, point_shape="circle")

    def panel_filter(self, scene: Scene, derived: Derived) -> tuple[Derived, frozenset[int]]:
        """The panels through the lab: measured pixels, the chosen fit's lines and epipoles, its rejects ringed."""
        # The scene is immutable: the same object with the same settings needs no new run (a re-render).
        key = (scene, self.run.lab, self.drawn)
        try:
            if self.result is None or self._shown is None or self._shown[0] is not scene or self._shown[1:] != key[1:]:
                result = run_lab(scene, self.run.lab, derived=derived)
                self.result, self._shown = result, key
                self._show(result)
                self._mask_3d(scene, result)
            result = self.result
        except SceneError as exc:
            self.result, self._shown = None, None
            self.table.content = f'<div style="font-size:0.8em">The lab cannot run here: {escape(str(exc))}</div>'
            self._mask_3d(scene, None)
            return derived, frozenset()
        return through_lab(derived, result, self.drawn, len(scene.points))
