"""Example 1 of the EGT paper: placing a pin-hole camera and projecting a panel.

The camera is panned by 45 degrees (``rotoy(pi/4)``, EGT's camera-axes
convention of ``f_Rt2H``) and placed at (-10, -5, 0); ``K = I``. The four
corners of a panel at y = 3 are projected. The figure shows the world frame,
the camera and its frame, the numbered points, and the image plane as the plot
``Figure 1`` (run it: the URL is printed; ``EGTVIZ_FIGURE=off`` draws nothing).
"""

import numpy as np

from egtviz.egt import clf, eye, f_3Dcamera, f_3Dframe, f_3Dwf, f_3Dwfenum, f_perspproj, f_Rt2H, pi, rotoy, show


def main() -> np.ndarray:
    clf()  # start from an empty figure, as a MATLAB script with clf
    H = f_Rt2H(rotoy(pi / 4), [-10, -5, 0])
    P = np.array([[-3, 3, 3, -3], [3, 3, 3, 3], [-3, -3, 3, 3]], float)
    f_3Dwf("k", 2)
    f_3Dframe(H, "g", 4, "_{cam}")
    f_3Dcamera(H, "g", 1)
    f_3Dwfenum(P, "k", 0.5)
    U = f_perspproj(P, H, eye(3), 1)  # 1: plot the points in the image plane
    for i, (u, v) in enumerate(U.T, start=1):
        print(f"point {i}: u = {u:.6f}, v = {v:.6f}")
    return U


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
