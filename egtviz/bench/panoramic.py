"""Timings of the panoramic (catadioptric) core: epipolar conics and projection.

Run ``python -m egtviz.bench.panoramic``. OpenCV has no central catadioptric
epipolar conics, so the comparison columns are ``None``.
"""

from __future__ import annotations


import numpy as np

from .core import median_ms

from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry.mirrors import HyperbolicMirror
from egtviz.geometry.panoramic_epipolar import epipolar_conics
from egtviz.geometry.poses import Pose, rotz


def bench_conics(n: int = 1000, *, n_project: int = 100_000, repeats: int = 20, seed: int = 0) -> list[dict]:
    """Median timings (ms) of ``epipolar_conics`` for ``n`` points and of projecting ``n_project`` points.

    Returns:
        Rows ``{"case", "ours_ms", "opencv_ms", "ratio", "note"}``.
    """
    rng = np.random.default_rng(seed)
    mirror = HyperbolicMirror(3.0, 1.0)
    cam1 = CatadioptricCamera(Pose(rotz(np.pi / 4), [-5.0, -5.0, 0.0]), mirror)
    cam2 = CatadioptricCamera(Pose(np.eye(3), [0.0, 0.0, 0.0]), mirror)
    X = rng.uniform([-10, -10, -3], [10, 10, 3], size=(n, 3))
    Xp = rng.uniform([-10, -10, -3], [10, 10, 3], size=(n_project, 3))
    conic_ms = median_ms(lambda: epipolar_conics(cam1, cam2, X), repeats)
    project_ms = median_ms(lambda: cam1.project(Xp), max(3, repeats // 4))
    return [
        {
            "case": f"epipolar_conics, {n} points, both images",
            "ours_ms": conic_ms,
            "opencv_ms": None,
            "ratio": None,
            "note": f"median of {repeats}; target < 5 ms for 1000 points; no OpenCV equivalent",
        },
        {
            "case": f"CatadioptricCamera.project, {n_project} points (hyperbolic)",
            "ours_ms": project_ms,
            "opencv_ms": None,
            "ratio": None,
            "note": f"median of {max(3, repeats // 4)}; cv2.omnidir uses the unified model only",
        },
    ]


if __name__ == "__main__":
    for row in bench_conics():
        print(f"{row['case']}: {row['ours_ms']:.3f} ms ({row['note']})")
