"""Example 2 of the EGT paper: a panoramic (hyperbolic mirror) camera and the image of one point.

The mirror (a = 3, b = 1) is turned by 45 degrees about the vertical and
placed at (-5, -5, 0); the CCD has ``K = [1e3, 0, 320; 0, 1e3, 240; 0, 0, 1]``.
The point (0, 0, 4) is seen through the mirror point ``Xh`` at the pixel ``m``
(the paper prints u = 410.48). The figure shows the world frame, the
panoramic camera and its mirror frame, the point, its mirror point and ray.
"""

import numpy as np

from egtviz.egt import clf, f_3Dframe, f_3Dpanoramic, f_3Dwf, f_panproj, pi, rotoz, show


def main() -> tuple[np.ndarray, np.ndarray]:
    clf()  # start from an empty figure, as a MATLAB script with clf
    H = np.eye(4)
    H[:3, :3] = rotoz(pi / 4)
    H[:3, 3] = [-5, -5, 0]
    K = np.array([[1e3, 0, 320], [0, 1e3, 240], [0, 0, 1]])
    f_3Dwf("k", 2)
    f_3Dpanoramic(H, "b", 1, 3, 1)
    f_3Dframe(H, "b", 2, "_{m}")
    m, Xh = f_panproj([0, 0, 4], H, K, 3, 1, 1, "r")  # 'r': draw the point, its mirror point and ray
    print(f"m = ({m[0, 0]:.2f}, {m[1, 0]:.2f})")
    print(f"Xh = ({Xh[0, 0]:.6f}, {Xh[1, 0]:.6f}, {Xh[2, 0]:.6f})")
    return m, Xh


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
