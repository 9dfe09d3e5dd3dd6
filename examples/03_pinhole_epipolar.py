"""Example 3 of the EGT paper: the epipolar geometry of two pin-hole cameras.

Camera 1 is rolled by 45 degrees about its optical axis (``rotoz(pi/4)``, EGT's camera-axes convention) and
placed at (-10, -10, 0), camera 2 sits at the origin; ``K = I``. The two
points' images, the epipoles and the epipolar lines: every line passes
through its image's epipole. The figure shows both cameras, their frames and
the points in 3D, and the two image planes as the plots ``Figure 1`` and
``Figure 2`` (points, epipole, epipolar lines).
"""

import numpy as np

from egtviz.egt import (
    clf,
    eye,
    f_3Dcamera,
    f_3Dframe,
    f_3Dwf,
    f_3Dwfenum,
    f_epipline,
    f_epipole,
    f_perspproj,
    f_Rt2H,
    pi,
    rotoz,
    show,
)


def main() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    clf()  # start from an empty figure, as a MATLAB script with clf
    H1 = f_Rt2H(rotoz(pi / 4), [-10, -10, 0])
    H2 = f_Rt2H(eye(3), [0, 0, 0])
    P = np.array([[0, 10, 10], [-10, 5, 5]], float).T
    f_3Dwf("k", 3)
    for H, colour, name in ((H1, "b", "cam1"), (H2, "r", "cam2")):
        f_3Dframe(H, colour, 3, "_{" + name + "}")
        f_3Dcamera(H, colour, 1, 1, name)
    f_3Dwfenum(P, "k", 0.5)
    U1 = f_perspproj(P, H1, eye(3), 1)
    U2 = f_perspproj(P, H2, eye(3), 1)
    e1, e2, F = f_epipole(H1, H2, eye(3), eye(3))
    l1, l2 = f_epipline(U1, U2, F, 1, 1, 2, "b:")  # draw the lines in figures 1 and 2, blue dotted
    print(f"e1 = ({e1[0]:.6f}, {e1[1]:.6f}, {e1[2]:.0f})")
    print(f"e2 = ({e2[0]:.6f}, {e2[1]:.6f}, {e2[2]:.0f})")
    print(f"lines through e1: max |l1 . e1| = {np.abs(l1.T @ e1).max():.1e}")
    print(f"lines through e2: max |l2 . e2| = {np.abs(l2.T @ e2).max():.1e}")
    return e1, e2, F


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
