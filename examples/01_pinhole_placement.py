"""Example 1 of the EGT paper: placing a pin-hole camera and projecting a panel.

The camera is panned by 45 degrees (``rotoy(pi/4)``, EGT's camera-axes
convention of ``f_Rt2H``) and placed at (-10, -5, 0); ``K = I``. The four
corners of a panel at y = 3 are projected; with the figure front-end the
camera, its frame, the numbered points and the image plane are drawn.
"""

import numpy as np

from egtviz.egt import eye, f_perspproj, f_Rt2H, pi, rotoy


def main() -> np.ndarray:
    H = f_Rt2H(rotoy(pi / 4), [-10, -5, 0])
    P = np.array([[-3, 3, 3, -3], [3, 3, 3, 3], [-3, -3, 3, 3]], float)
    U = f_perspproj(P, H, eye(3), 1)  # 1: plot the points in the image plane
    for i, (u, v) in enumerate(U.T, start=1):
        print(f"point {i}: u = {u:.6f}, v = {v:.6f}")
    return U


if __name__ == "__main__":
    main()
