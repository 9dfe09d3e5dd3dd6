"""Projection benchmark: the core's pin-hole and catadioptric projection against a bare numpy product."""

from __future__ import annotations

import time

import numpy as np


def median_ms(fn, repeats: int = 20) -> float:
    """Median wall time of ``fn()`` in milliseconds (one warm-up call first)."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def paired_median_ms(fn_a, fn_b, repeats: int = 20) -> tuple[float, float]:
    """Median ms of two functions timed alternately, after a few warm-up calls of each.

    Alternating keeps both under the same allocator and cache state: large
    temporaries make glibc's malloc switch between fresh mmaps (page faults)
    and a warm heap, which would otherwise favour whichever runs second.
    """
    for _ in range(3):
        fn_a()
        fn_b()
    ta, tb = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn_a()
        t1 = time.perf_counter()
        fn_b()
        t2 = time.perf_counter()
        ta.append(t1 - t0)
        tb.append(t2 - t1)
    return 1e3 * float(np.median(ta)), 1e3 * float(np.median(tb))


def run_projection_bench(n: int = 100_000, repeats: int = 20) -> list[dict]:
    from ..geometry import Intrinsics, PinholeCamera
    from ..geometry.poses import look_at

    rng = np.random.default_rng(0)
    X = rng.uniform(-5, 5, size=(n, 3)) + [0.0, 20.0, 0.0]
    cam = PinholeCamera(look_at([0, 0, 0], [0, 20, 0]), Intrinsics())
    P = cam.P
    Xh = np.column_stack([X, np.ones(n)])

    def bare() -> np.ndarray:
        # The floor: one homogeneous product and the perspective division, no checks, no mask.
        m = Xh @ P.T
        return m[:, :2] / m[:, 2:3]

    ours, base = paired_median_ms(lambda: cam.project(X), bare, repeats)
    return [
        {
            "case": f"pin-hole projection, N={n}",
            "ours_ms": ours,
            "opencv_ms": None,
            "ratio": ours / base,
            "note": f"ratio against a bare numpy P @ X + division ({base:.2f} ms); target <= 2",
        }
    ]
