"""EGT 2.0's planar-mirror demo: one camera, two mirrors, and the epipolar geometry of the reflections.

Two plane mirrors through the origin (normals (0, -1, 0) and at 45 degrees
from it) show a camera two reflected views of twenty random points. Each
reflection is what a *virtual* camera (the camera reflected in that mirror)
sees; the fundamental matrix estimated from the two reflected images equals
the one of the two virtual cameras, and so do their epipoles. The figure
shows the mirrors, the camera, both virtual cameras (left-handed frames,
labelled ``mirrored``), the points and where the camera sees them on each
mirror, and the two reflected images as the plots ``Figure 1`` and ``Figure 2``.
"""

import numpy as np

from egtviz.egt import (
    clf,
    f_3Dcamera,
    f_3Dframe,
    f_3Dplane,
    f_3Drandpoint,
    f_3Dwf,
    f_3Dwfenum,
    f_epipole,
    f_Festim,
    f_perspproj,
    f_reflcamera,
    f_reflpersproj,
    f_Rt2H,
    f_scenepnt,
    pi,
    rotoy,
    show,
)


def main() -> tuple[float, float]:
    clf()  # start from an empty figure, as a MATLAB script with clf
    P = f_3Drandpoint(20, [0.5, -1.0, 0.0], 0.5, rng=0)
    n1, ds1 = np.array([0.0, -1.0, 0.0]), 0.0
    n2, ds2 = np.array([np.sin(pi / 4), -np.cos(pi / 4), 0.0]), 0.0
    K = np.array([[700, 0, 640], [0, 700, 480], [0, 0, 1]], float)
    H = f_Rt2H(rotoy(-23 * pi / 180), [0.6, -2.8, -1.0])
    f_3Dplane(n1, ds1, [0, 3], [0, 2], [-1.5, 1.5])
    f_3Dplane(n2, ds2, [-8, -2], [0, -2], [-1.5, 1.5])
    f_3Dwf("k", 1.5)
    f_3Dwfenum(P, "k", 0.03)
    f_3Dframe(H, "r", 1, "_{d}")
    f_3Dcamera(H, "r", 0.3, 2, "camera")
    Hv1 = f_reflcamera(n1, ds1, H, 1, "g", 1, 0.3, "v1")
    Hv2 = f_reflcamera(n2, ds2, H, 1, "g", 1, 0.3, "v2")
    U1, M1 = f_reflpersproj(n1, ds1, H, K, P)
    U2, M2 = f_reflpersproj(n2, ds2, H, K, P)
    f_scenepnt(M1, "g*", 1)
    f_scenepnt(M2, "r*", 1)
    f_perspproj(P, Hv1, K, 1)  # the reflected images, as the camera sees them in each mirror
    f_perspproj(P, Hv2, K, 1)
    seen = np.isfinite(U1[0]) & np.isfinite(U2[0])
    e1_gt, e2_gt, F_gt = f_epipole(Hv1, Hv2, K, K)
    F = f_Festim(U1[:, seen], U2[:, seen], 2)
    e1 = np.linalg.svd(F)[2][-1]
    e2 = np.linalg.svd(F)[0][:, -1]
    err1 = float(np.linalg.norm(e1 / e1[2] - e1_gt))
    err2 = float(np.linalg.norm(e2 / e2[2] - e2_gt))
    print(f"points seen in both mirrors: {int(seen.sum())} of 20")
    print(f"epipole_e1_error = {err1:.1e}")
    print(f"epipole_e2_error = {err2:.1e}")
    return err1, err2


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
