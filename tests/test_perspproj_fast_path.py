"""f_perspproj checks its points once and builds a camera it has checked once: the same pixels, the same refusals."""

from __future__ import annotations

import numpy as np
import pytest

from egtviz.egt import _convert, f_perspproj, f_reflcamera, f_Rt2H
from egtviz.geometry import _validate
from egtviz.geometry._validate import GeometryError
from egtviz.geometry.poses import roty

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def _points(n: int = 500) -> np.ndarray:
    rng = np.random.default_rng(3)
    return rng.uniform(-5, 5, size=(3, n)) + np.array([[0.0], [20.0], [0.0]])


def test_the_points_are_checked_in_one_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    X = _points()
    seen: list[int] = []
    check = _validate._refuse_non_finite_or_huge

    def counting(arr: np.ndarray, name: str, max_abs: float | None) -> None:
        seen.append(arr.size)
        check(arr, name, max_abs)

    # The facade's one-pass test (a sum of squares) counts as a pass too; only when it fails does the full check run.
    one_pass = _convert._plainly_in_range

    def counting_one_pass(arr: object) -> bool:
        seen.append(arr.size if isinstance(arr, np.ndarray) else -1)
        return one_pass(arr)

    monkeypatch.setattr(_validate, "_refuse_non_finite_or_huge", counting)
    monkeypatch.setattr(_convert, "_plainly_in_range", counting_one_pass)
    f_perspproj(X, f_Rt2H(roty(0.1), [0.5, 0.0, 0.2]), K)
    assert seen.count(X.size) == 1


def test_repeated_and_list_cameras_give_the_same_pixels() -> None:
    X = _points()
    H = f_Rt2H(roty(0.1), [0.5, 0.0, 0.2])
    first = f_perspproj(X, H, K)
    again = f_perspproj(X, H.copy(), K.copy())
    from_lists = f_perspproj(X, H.tolist(), K.tolist())
    np.testing.assert_array_equal(first, again)
    np.testing.assert_array_equal(first, from_lists)
    virtual = f_reflcamera([0.0, 1.0, 0.0], 30.0, H)
    np.testing.assert_array_equal(f_perspproj(X, virtual, K), f_perspproj(X, virtual.tolist(), K.tolist()))


def test_a_bad_camera_is_refused_every_time() -> None:
    X = _points(10)
    H = f_Rt2H(roty(0.1), [0.5, 0.0, 0.2])
    f_perspproj(X, H, K)
    bad = H.copy()
    bad[0, 0] += 0.5  # not orthonormal
    for _ in range(2):
        with pytest.raises(GeometryError, match="H"):
            f_perspproj(X, bad, K)
    singular = K.copy()
    singular[1, 1] = 0.0
    for _ in range(2):
        with pytest.raises(GeometryError, match="K"):
            f_perspproj(X, H, singular)


def test_homogeneous_points_that_leave_the_range_are_refused() -> None:
    Xh = np.array([[1e99], [1.0], [1.0], [1e-3]])
    with pytest.raises(GeometryError, match="Xw"):
        f_perspproj(Xh, f_Rt2H(np.eye(3), [0.0, 0.0, 0.0]), K)
