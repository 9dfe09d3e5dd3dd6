"""The facade's one-pass check of large world point arrays (a sum of squares) accepts and refuses exactly what the
full check does, with the full check's messages."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.egt import f_perspproj, f_Rt2H
from egtviz.geometry import MAX_MAGNITUDE, GeometryError
from egtviz.geometry.poses import roty

H = f_Rt2H(roty(0.1), [0.5, 0.0, 0.2])
K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def _points(n: int = 200) -> np.ndarray:
    rng = np.random.default_rng(1)
    return rng.uniform(-5, 5, size=(3, n)) + np.array([[0.0], [20.0], [0.0]])


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (np.nan, r"Xw: contains NaN or inf"),
        (np.inf, r"Xw: contains NaN or inf"),
        (-np.inf, r"Xw: contains NaN or inf"),
        (1.0000001e100, r"Xw: magnitude 1e\+100 is too large"),
        (-1e160, r"Xw: magnitude 1e\+160 is too large"),
    ],
)
@pytest.mark.parametrize("fortran", [False, True])
def test_a_bad_entry_in_a_large_array_is_refused_by_name(bad: float, message: str, fortran: bool) -> None:
    X = np.asfortranarray(_points()) if fortran else _points()
    X[1, 137] = bad
    with pytest.raises(GeometryError, match=message):
        f_perspproj(X, H, K)


def test_many_entries_near_the_limit_are_accepted_as_before() -> None:
    # Their sum of squares is far above MAX_MAGNITUDE**2: the one-pass test says nothing, the full check accepts.
    X = np.full((3, 100), MAX_MAGNITUDE)
    X[1] = 2.0 * MAX_MAGNITUDE / 3.0
    U = f_perspproj(X, H, K)
    assert U.shape == (2, 100)
    assert np.isfinite(U).all()


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=65, max_value=400), st.floats(min_value=-3.0, max_value=3.0), st.booleans())
def test_results_are_bit_identical_to_the_camera_on_checked_points(n: int, scale: float, transposed: bool) -> None:
    from egtviz.egt._convert import pinhole

    X = _points(n) * 10.0**scale
    if transposed:
        X = np.asfortranarray(X)
    camera, _ = pinhole(H, K)
    expected = camera.project(np.ascontiguousarray(X.T)).pixels.T
    np.testing.assert_array_equal(f_perspproj(X, H, K), expected)
