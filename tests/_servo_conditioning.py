"""Tolerances for a servo run's key values, derived from the closed loop's own conditioning.

Why not bit-exact: each step feeds the next, so another BLAS/LAPACK kernel's last-bit differences (sums in another
order, solves blocked differently) are carried and amplified along the run. One step amplifies them by itself:
the panoramic rotation estimate is the argmin of a flat eigenvalue curve refined on a ~3e-5 rad grid, so a few
ulps in the curve move it by 1e-11 to 1e-9 rad, whatever their size: ~1e-8 of the 0.02 rad final error.

Model: another build changes every step by rounding only. Its effect is measured, not guessed, by *twin runs*:
the same run with every step's measured pixels (the control law's input) perturbed by random signs times
:data:`STEP_ROUNDING` relative, the stated bound on one step's rounding (sums of at most a dozen terms, 12 u;
the worst solve, the arm's J J^T, has a condition number up to ~500 here: a few hundred ulps of the values
involved). A twin's deviation is then (a) the loop's sensitivity times that bound, accumulated over the steps,
plus (b) the error of the self-amplifying steps drawn anew, since every operation is re-rounded, as another
kernel does.

Tolerance per value: :data:`SAFETY` times its largest deviation over :data:`TWINS` twins (a build draws (b)
again: builds and spare twins landed up to ~4x the largest of three), never below rtol :data:`RTOL_FLOOR`. The
pin-hole runs are bit-stable to ~1e-11 across kernels and mostly get that floor (at most ~1e-8 on the
near-zero epipolar distances); the panoramic ones get up to ~2e-7 relative on their small final values. A real
change is far above: a gain off by 1e-6 relative moves the final rotation errors by 7e-7 to 5e-6 relative, and
the golden test checks that it, and any golden value nudged by 1e-6 relative, fails the comparison.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any
from unittest import mock

import numpy as np

from egtviz.servo import panoramic_robot, pinhole_arm

#: Relative size of the per-step perturbation of a twin run: 256 ulps (2**-44, about 5.7e-14).
STEP_ROUNDING = 256 * float(np.finfo(float).eps)

#: Twin runs per run (each with its own random signs): the largest deviation of the three is kept.
TWINS = 3

#: A tolerance is this many times the largest twin deviation (a build draws the rounding error anew).
SAFETY = 10.0

#: The floor of every tolerance, relative to the value: what a bit-stable run is compared at.
RTOL_FLOOR = 1e-9

#: The summary's final errors, which the reason prints.
FINAL_ERRORS = ("final_rotation_error_rad", "final_translation_error")

#: A number in a reason: integers, decimals and exponent forms ("30", "0.001", "2.41e-01").
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]\d+)?")


@contextmanager
def rounding_twin(seed: int) -> Iterator[None]:
    """Within: every simulation step's measured pixels are perturbed by ``+-STEP_ROUNDING`` relative.

    The observation functions are the loops' module globals, so patching them reaches every step (step 0 too,
    which a perturbed start would miss) without touching the random stream of the image noise.
    """
    signs = np.random.default_rng(seed)

    def jitter(m: np.ndarray) -> np.ndarray:
        return m * (1.0 + STEP_ROUNDING * signs.choice([-1.0, 1.0], size=m.shape))

    observe_panoramic, observe_features = panoramic_robot.observe_panoramic, pinhole_arm.observe_features

    def panoramic(*args: Any) -> tuple[Any, np.ndarray]:
        proj, m = observe_panoramic(*args)
        return proj, jitter(m)

    def pinhole(*args: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        m, m_true, visible = observe_features(*args)
        return jitter(m), m_true, visible

    with (
        mock.patch.object(panoramic_robot, "observe_panoramic", panoramic),
        mock.patch.object(pinhole_arm, "observe_features", pinhole),
    ):
        yield


def words(reason: str) -> str:
    """``reason`` with each number replaced by ``#``: its structure."""
    return NUMBER.sub("#", reason)


def is_float_value(value: Any) -> bool:
    """Whether a key value is compared numerically (floats and lists of them; not counts, flags or text)."""
    return isinstance(value, list) or (isinstance(value, float) and not isinstance(value, bool))


def twin_deviation(nominal: dict[str, Any], twins: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Per float key and entry: the largest ``|twin - nominal|`` over the twins.

    Raises:
        AssertionError: a twin changed what the run means (steps, outcome, reason, counts) or where it is NaN:
            rounding must not, or the run is unfit for a golden comparison.
    """
    out: dict[str, np.ndarray] = {}
    for key, value in nominal.items():
        if not is_float_value(value):
            for twin in twins:
                same = words(twin[key]) == words(value) if isinstance(value, str) else twin[key] == value
                assert same, f"{key}: a rounding-level twin changes it ({twin[key]!r} vs {value!r})"
            continue
        nom = np.asarray(value, dtype=float)
        copies = [np.asarray(twin[key], dtype=float) for twin in twins]
        for twin_value in copies:
            assert np.array_equal(np.isnan(twin_value), np.isnan(nom)), f"{key}: a twin is NaN elsewhere"
        # NaN in the run and its twins alike (no epipole yet, say) is compared as NaN: no deviation to measure.
        out[key] = np.nan_to_num(np.max([np.abs(c - nom) for c in copies], axis=0))
    return out


def tolerances(expected: dict[str, Any], deviation: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Absolute tolerance per float key and entry: ``max(SAFETY * deviation, RTOL_FLOOR * |expected|)``."""
    out = {}
    for key, dev in deviation.items():
        floor = RTOL_FLOOR * np.abs(np.asarray(expected[key], dtype=float))
        out[key] = np.maximum(SAFETY * dev, np.nan_to_num(floor))
    return out


def float_mismatches(actual: Any, expected: Any, tol: np.ndarray, where: str) -> list[str]:
    """The entries of ``actual`` farther than ``tol`` from ``expected`` (NaN equals NaN), as messages."""
    a, e = np.atleast_1d(np.asarray(actual, dtype=float)), np.atleast_1d(np.asarray(expected, dtype=float))
    if a.shape != e.shape:
        return [f"{where}: shape {a.shape} != {e.shape}"]
    t = np.broadcast_to(tol, e.shape)
    bad = ~((np.abs(a - e) <= t) | (np.isnan(a) & np.isnan(e)))
    return [
        f"{where}{[int(j) for j in i]}: {a[i]!r} != {e[i]!r} (|diff| {abs(a[i] - e[i]):.3g} > tol {t[i]:.3g})"
        for i in zip(*np.nonzero(bad), strict=True)
    ]


def mismatches(
    actual: dict[str, Any], expected: dict[str, Any], tol: dict[str, np.ndarray], keys: list[str]
) -> list[str]:
    """Where ``actual`` differs from ``expected`` on ``keys``: floats at ``tol``, the reason by
    :func:`reason_mismatches`, counts and flags exactly."""
    out = []
    for key in keys:
        got, want = actual[key], expected[key]
        if key == "reason":
            finals = {k: expected[k] for k in FINAL_ERRORS}
            out += reason_mismatches(got, want, finals, {k: float(tol[k]) for k in FINAL_ERRORS})
        elif is_float_value(want):
            out += float_mismatches(got, want, tol[key], key)
        elif got != want or type(got) is not type(want):
            out.append(f"{key}: {got!r} != {want!r}")
    return out


def reason_mismatches(actual: str, expected: str, values: dict[str, float], tol: dict[str, float]) -> list[str]:
    """Where reason ``actual`` differs from ``expected``: its words exactly, its numbers numerically.

    A number printed from one of ``values`` (``"2.41e-01"`` for a final error) stands for that value to half a
    unit of its last digit: the printed ``actual`` must be within that half unit plus the value's tolerance of
    the value (a value within tolerance of a rounding boundary may print either neighbour). Other numbers
    (steps, tolerances of the settings) must be equal.
    """
    if words(actual) != words(expected):
        return [f"reason: {actual!r} != {expected!r}"]
    out = []
    for got, want in zip(NUMBER.findall(actual), NUMBER.findall(expected), strict=True):
        printed = [k for k, v in values.items() if "e" in want and f"{v:.{_digits(want)}e}" == want]
        if not printed:
            if float(got) != float(want):
                out.append(f"reason: {got} != {want} in {actual!r}")
            continue
        key = printed[0]
        half_unit = 0.5 * 10.0 ** (int(want.split("e")[1]) - _digits(want))
        if abs(float(got) - values[key]) > half_unit + tol[key]:
            out.append(f"reason: {got} is not {key} = {values[key]!r} printed (tol {tol[key]:.3g})")
    return out


def _digits(printed: str) -> int:
    """Digits after the point of a number printed as ``d.ddde+xx``."""
    mantissa = printed.split("e", maxsplit=1)[0]
    return len(mantissa.split(".")[1]) if "." in mantissa else 0


def derived_tolerances(
    run_once: Callable[[], dict[str, Any]], expected: dict[str, Any]
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The nominal key values of ``run_once`` and the tolerance of each float key from :data:`TWINS` twins."""
    nominal = run_once()
    twins = []
    for seed in range(TWINS):
        with rounding_twin(seed):
            twins.append(run_once())
    return nominal, tolerances(expected, twin_deviation(nominal, twins))
