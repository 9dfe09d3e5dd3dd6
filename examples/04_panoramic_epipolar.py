"""Example 4 of the EGT paper: the epipolar geometry of two panoramic cameras.

Two hyperbolic-mirror cameras placed as in Example 3 look at the eight
corners of a box. Each image has two epipoles (the baseline meets each
mirror twice) and one epipolar conic per point; every conic passes through
both epipoles of its image and through the image of its point. The figure
shows both mirrors, their frames, the box's corners and, in each camera's
panel, the points, the epipoles and the conics.
"""

import numpy as np

from egtviz.egt import (
    DEFAULT_PANORAMIC_K,
    clf,
    f_3Dframe,
    f_3Dpanoramic,
    f_3Dwf,
    f_epipconics,
    f_panepipoles,
    f_panproj,
    f_scenepnt,
    pi,
    rotoz,
    show,
)


def main() -> tuple[np.ndarray, np.ndarray]:
    clf()  # start from an empty figure, as a MATLAB script with clf
    K = DEFAULT_PANORAMIC_K
    H1 = np.eye(4)
    H1[:3, :3] = rotoz(pi / 4)
    H1[:3, 3] = [-10, -10, 0]
    H2 = np.eye(4)
    corners = np.array([[x, y, z] for x in (-6, -2) for y in (-6, -2) for z in (-3, 1)], float).T
    f_3Dwf("k", 3)
    for H, colour in ((H1, "b"), (H2, "g")):
        f_3Dpanoramic(H, colour, 1, 3, 1)
        f_3Dframe(H, colour, 3, "_{m}")
    f_scenepnt(corners, "r*", 1)
    m1, _ = f_panproj(corners, H1, K, 3, 1, 1, "b")
    m2, _ = f_panproj(corners, H2, K, 3, 1, 1, "g")
    e1, e1p, e2, e2p = f_panepipoles(H1, H2, K)
    C1, C2 = f_epipconics(corners, H1, H2, K)
    print(f"e1 = ({e1[0]:.3f}, {e1[1]:.3f}), e1' = ({e1p[0]:.3f}, {e1p[1]:.3f})")
    print(f"e2 = ({e2[0]:.3f}, {e2[1]:.3f}), e2' = ({e2p[0]:.3f}, {e2p[1]:.3f})")
    worst = 0.0
    for C, m, ea, eb in ((C1, m1, e1, e1p), (C2, m2, e2, e2p)):
        for i in range(C.shape[0]):
            for p in (m[:, i], ea, eb):
                if np.all(np.isfinite(p)):
                    worst = max(worst, abs(p @ C[i] @ p) / (p @ p))
    print(f"conics: {C1.shape[0]} per image, worst |m' C m| / |m|^2 = {worst:.1e}")
    return C1, C2


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
