"""The lesson's instruments, headless: the estimation lab's and the convention lens's settings, and the panels drawn
through them.

The settings belong to the lesson (:attr:`egtviz.lessons.LessonRun.lab`, :attr:`~egtviz.lessons.LessonRun.lens`):
a slider or a checkbox applies a ``set_lab`` or ``set_lens`` change through the run (:func:`set_lab`,
:func:`toggle_lens`), so the lesson's checks see what the instruments show.

A step that asks which mistake is on (a task that declares a possible diagnosis, while its lens has a mistake
on) hides the lens's settings (:func:`hidden_lens`): the panels show the mistake's effect, and each box shows
whether the learner switched that step of the computation since the step began (:func:`lens_shown`), not
whether the mistake is on. Ticking the box of the hidden mistake repairs the lens.

The panels through an instrument (:func:`through_lab`, :func:`through_lens`) replace the drawn pair's epipolar
lines and epipoles (and, for the lab, its pixels) in the derived geometry the image-plane panels draw; the 3D
view and the read-out keep the true geometry.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..lessons import Lesson, instruments
from ..lessons.changes import Change, SetLab, SetLens
from ..lessons.instruments import lesson_needs
from ..scene import Derived
from ..scene.derived import with_pair_lines
from ..scene.lab import LabResult, LabSettings
from ..scene.lens import LensToggles, LensView

__all__ = ["MAX_RINGS", "LessonInstruments", "hidden_lens", "lens_shown", "lesson_instruments", "set_lab",
           "through_lab", "through_lens", "toggle_lens"]

#: Most rejected correspondences ringed in the panels (a ring is numbered, and more numbers would hide the image).
MAX_RINGS = 40


class LessonInstruments(Protocol):
    """What the lab and the lens read and change: a :class:`~egtviz.lessons.LessonRun`."""

    lab: LabSettings
    lens: LensToggles

    def apply(self, change: Change) -> None: ...


def lesson_instruments(lesson: Lesson) -> tuple[bool, bool]:
    """``(lab, lens)``: whether the lesson uses the estimation lab, the convention lens (its changes or tasks)."""
    needs = lesson_needs(lesson)
    return needs.lab, needs.lens


def set_lab(run: LessonInstruments, key: str, value: float) -> None:
    """Set the lab's ``key`` (``noise_px``, ``outlier_percent``, ``threshold_px``) to ``value`` through the run.

    Raises:
        SceneError: outside the lab's range (:class:`~egtviz.scene.lab.LabSettings` checks it).
    """
    if getattr(run.lab, key) != float(value):
        run.apply(SetLab(((key, float(value)),)))


def hidden_lens(run: LessonInstruments) -> LensToggles | None:
    """The lens the current step set, when the step hides it (:func:`egtviz.lessons.instruments.hidden_lens`);
    None when the lens shows its settings. A run without a lesson hides nothing."""
    lesson, index = getattr(run, "lesson", None), getattr(run, "step_index", None)
    if lesson is None or not isinstance(index, int):
        return None
    return instruments.hidden_lens(lesson, index)


def lens_shown(run: LessonInstruments) -> LensToggles:
    """What the lens's boxes show: the run's toggles, or what was switched since the step hid its mistake."""
    hidden = hidden_lens(run)
    return run.lens if hidden is None else hidden.switched(run.lens)


def toggle_lens(run: LessonInstruments, key: str, shown: bool) -> None:
    """The box of the lens's ``key`` now shows ``shown``: the lens changes through the run (while the step hides
    its lens, the box is a switch of that step of the computation, and ticking the hidden mistake repairs it)."""
    hidden = hidden_lens(run)
    wanted = shown if hidden is None else getattr(hidden, key) != shown
    if getattr(run.lens, key) != wanted:
        run.apply(SetLens(((key, wanted),)))


def through_lens(derived: Derived, view: LensView) -> Derived:
    """The panels through the lens: its epipoles and lines in the drawn pair."""
    return with_pair_lines(derived, view.names, lines1=view.lines1, lines2=view.lines2, e1=view.e1, e2=view.e2)


def through_lab(derived: Derived, result: LabResult, drawn: str, points: int) -> tuple[Derived, frozenset[int]]:
    """The panels through the lab: the measured pixels, the ``drawn`` fit's lines and epipoles, and the
    correspondences it rejected (to ring, when at most :data:`MAX_RINGS`); ``points``: the scene's point count.
    A failed fit leaves the panels as they are."""
    fit = result.fit(drawn)
    if fit.F is None or fit.e1 is None or fit.e2 is None:  # a fit's epipoles come with its F
        return derived, frozenset()
    data = result.data
    pixels = [np.full((points, 2), np.nan), np.full((points, 2), np.nan)]
    pixels[0][data.point_indices] = data.measured1
    pixels[1][data.point_indices] = data.measured2
    lines1, lines2 = np.full((points, 3), np.nan), np.full((points, 3), np.nan)
    lines1[data.point_indices] = fit.lines1
    lines2[data.point_indices] = fit.lines2
    ringed: frozenset[int] = frozenset()
    if fit.inliers is not None and np.count_nonzero(~fit.inliers) <= MAX_RINGS:
        ringed = frozenset(int(i) for i in data.point_indices[~fit.inliers])
    planes = with_pair_lines(derived, result.names, lines1=lines1, lines2=lines2, e1=fit.e1, e2=fit.e2,
                             points=(pixels[0], pixels[1]), no_image="not used by the lab")
    return planes, ringed
