"""Timing of the servo simulations: a 1,000-step run of each demo (no OpenCV counterpart)."""

from __future__ import annotations

import time


def run_servo_bench(repeats: int = 3) -> list[dict]:
    """Rows ``{"case", "ours_ms", "opencv_ms": None, "ratio": None, "note"}``: best of ``repeats`` 1,000-step runs.

    Early stopping is disabled (``stop_px=0``) so each run really takes 1,000 steps.
    """
    from egtviz.servo.panoramic_robot import simulate_panoramic
    from egtviz.servo.pinhole_arm import puma, simulate_pinhole

    puma()  # build and cache the robot outside the timing
    cases = [
        ("servo pinhole, 1000 steps, true F", lambda: simulate_pinhole(seed=0, steps=1000, stop_px=0.0)),
        (
            "servo pinhole, 1000 steps, normalized 8-point F, 0.5 px",
            lambda: simulate_pinhole(seed=0, steps=1000, noise_px=0.5, f_algorithm=2),
        ),
        ("servo panoramic, 1000 steps", lambda: simulate_panoramic(seed=0, steps=1000, stop_px=0.0)),
    ]
    rows = []
    for name, fn in cases:
        best = float("inf")
        cpu = float("inf")
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            res = fn()
            best = min(best, time.perf_counter() - t0)
            cpu = min(cpu, time.process_time() - c0)
        rows.append(
            {
                "case": name,
                "ours_ms": round(best * 1e3, 1),
                "opencv_ms": None,
                "ratio": None,
                "note": f"{res.steps} steps, CPU {cpu * 1e3:.0f} ms, no OpenCV equivalent",
            }
        )
    return rows


if __name__ == "__main__":
    for row in run_servo_bench():
        print(row)
