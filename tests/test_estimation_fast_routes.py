"""The estimators' fast routes decide exactly as the checked ones: the rank-2 step's sign on a tie, Hartley's
checks skipped only where they pass, the robust estimators' plain options and the order of their errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from egtviz.bench.estimation import _scene
from egtviz.geometry import MAX_MAGNITUDE, GeometryError
from egtviz.geometry import fundamental, robust
from egtviz.geometry.matrices import hartley_scales


@pytest.mark.parametrize("diagonal", [(1.0, -1.0, 0.0), (-1.0, 1.0, 0.0), (0.0, 1.0, -1.0), (0.0, -1.0, 1.0)])
def test_rank2_step_takes_the_first_of_two_tied_largest_entries_as_positive(diagonal) -> None:
    # F has +v and -v as its largest entries: the sign rule (largest-magnitude entry positive) picks the first of
    # them, as F / F.flat[argmax |F|] does, whichever of the two is negative.
    F = np.diag(diagonal)
    got = fundamental._rank2_denormalize_canonical(F.ravel(), (1.0, 0.0, 0.0, 1.0, 0.0, 0.0))
    expected = F / F.flat[np.argmax(np.abs(F))]
    np.testing.assert_array_equal(got, expected / np.linalg.norm(expected))


def test_hartley_checks_are_skipped_only_inside_their_own_bounds() -> None:
    # The 8-point kernel decides spreads above _SURE_SPREAD and magnitudes below _SURE_MAGNITUDE without
    # hartley_scales: both must be values that hartley_scales accepts.
    spread = fundamental._SURE_SPREAD
    assert hartley_scales([0j], [spread], 4, [np.zeros((4, 2))], ["U"]) == [math.sqrt(2.0) / spread]
    assert fundamental._SURE_MAGNITUDE <= MAX_MAGNITUDE
    # Just below the sure spread, the full check still decides (and a spread of 1e-60 is accepted there).
    s = _scene(20, 0.5, 0.0, 4)
    F = fundamental.fundamental_normalized_8point(s["U1"], s["U2"])
    tiny = fundamental.fundamental_normalized_8point(s["U1"] * 1e-60, s["U2"] * 1e-60)
    # The same F in the scaled pixels: diag(1e60, 1e60, 1) F diag(1e60, 1e60, 1), up to scale.
    S = np.diag([1e60, 1e60, 1.0])
    assert np.all(np.isfinite(tiny))
    def unit(G):
        return G / G.flat[np.argmax(np.abs(G))]

    np.testing.assert_allclose(unit(tiny), unit(S @ F @ S), atol=1e-9)


def test_the_8point_kernel_gives_the_checked_scales() -> None:
    s = _scene(200, 0.5, 0.0, 2)
    _, t = fundamental._normalized_design_floats(s["U1"], s["U2"])
    _, T1, T2 = fundamental.normalized_design(s["U1"], s["U2"])
    c1, c2 = s["U1"].mean(axis=0), s["U2"].mean(axis=0)
    scales = hartley_scales(
        [complex(*c1), complex(*c2)],
        [float(np.mean(np.hypot(*(s["U1"] - c1).T))), float(np.mean(np.hypot(*(s["U2"] - c2).T)))],
        200, [s["U1"], s["U2"]], ["U1", "U2"],
    )
    np.testing.assert_allclose([t[0], t[3]], scales, rtol=1e-14)
    assert (T1[0, 0], T2[0, 0]) == (t[0], t[3])


@pytest.mark.parametrize("options", [(0.999, 2000, 0), (0.5, 1, None), (1e-9, 2**53, 7)])
def test_plain_robust_options_are_returned_as_the_checked_route_returns_them(options) -> None:
    fast = robust._check_robust_args(*options)
    checked = robust._check_robust_args(np.float64(options[0]), float(options[1]), options[2])
    assert fast == checked and type(fast[1]) is int


@pytest.mark.parametrize("options, message", [
    ((1.0, 2000, 0), "confidence"), ((0.9, 0, 0), "max_iterations"), ((0.9, 10, -1), "seed"), ((0.9, 10, True), "seed"),
    ((0.9, 2.5, 0), "max_iterations"), ((float("nan"), 10, 0), "confidence"),
])
def test_bad_robust_options_are_still_named(options, message) -> None:
    with pytest.raises(GeometryError, match=message):
        robust._check_robust_args(*options)


def test_a_bad_point_is_named_before_a_bad_option() -> None:
    # The robust estimators check the points (shapes, then values) before their options, as before the fast route.
    s = _scene(50, 0.5, 0.3, 1)
    U2 = s["U2"].copy()
    U2[3, 1] = np.nan
    with pytest.raises(GeometryError, match="U2"):
        robust.fundamental_ransac(s["U1"], U2, confidence=2.0)
    with pytest.raises(GeometryError, match="U1"):
        robust.fundamental_lmeds(s["U1"][:, :1], s["U2"], confidence=2.0)
