"""EGT 2.0's pin-hole demo: the actual and desired cameras, their epipoles and epipolar lines.

The desired camera is at the origin (``Rd = I``), the actual one turned by
-30 degrees (``rotoy(-pi/6)``) at (-5, -5, 0); ``K = I``. The fundamental
matrix estimated from twelve projected points (normalized 8-point, EGT's
algorithm 2) equals the one computed from the poses. The figure shows both
cameras and the points in 3D and the two images as the plots ``Figure 2``
(actual) and ``Figure 3`` (desired), with the epipolar lines.
"""

import numpy as np

from egtviz.egt import (
    clf,
    eye,
    f_3Dcamera,
    f_3Dframe,
    f_3Dwf,
    f_epipline,
    f_epipole,
    f_Festim,
    f_perspproj,
    f_Rt2H,
    f_scenepnt,
    pi,
    rotoy,
    show,
)


def main() -> float:
    clf()  # start from an empty figure, as a MATLAB script with clf
    Hd = f_Rt2H(eye(3), [0, 0, 0])
    Ha = f_Rt2H(rotoy(-pi / 6), [-5, -5, 0])
    P = np.array([[0, 10, 10], [5, 4, -3]], float).T
    f_3Dwf("k", 2)
    for H, colour, name in ((Hd, "g", "desired"), (Ha, "r", "actual")):
        f_3Dframe(H, colour, 2, "_{" + name[0] + "}")
        f_3Dcamera(H, colour, 1, 1, name)
    f_scenepnt(P, "k*", 1)
    Ud = f_perspproj(P, Hd, eye(3))
    Ua = f_perspproj(P, Ha, eye(3))
    ea, ed, F = f_epipole(Ha, Hd, eye(3), eye(3))
    la, ld = f_epipline(Ua, Ud, F, 1, 2, 3, "r")
    print(f"ea = ({ea[0]:.6f}, {ea[1]:.6f}), ed = ({ed[0]:.6f}, {ed[1]:.6f})")
    rng = np.random.default_rng(0)
    cloud = np.vstack([rng.uniform(-4, 4, 12), rng.uniform(6, 14, 12), rng.uniform(-3, 3, 12)])
    Fe = f_Festim(f_perspproj(cloud, Ha, eye(3)), f_perspproj(cloud, Hd, eye(3)), 2)
    err = min(np.linalg.norm(Fe - F), np.linalg.norm(Fe + F))
    print(f"|F_estimated - F| = {err:.1e}")
    return err


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
