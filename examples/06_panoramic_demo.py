"""EGT 2.0's panoramic demo (its ex3): two parabolic-mirror cameras looking down at a box.

Parabolic mirrors (``h = 0.03`` m, EGT's ``quadric = 2``) with orthographic
CCDs, ``K`` centred at (640, 480); the current camera is turned by 45
degrees and moved 0.2 m along x. Both mirrors face down
(``rotox(-pi)``). The eight corners of a box are projected, and each image
gets its two epipoles. The figure shows both mirrors, their frames and the
box in 3D, and each camera's image in its panel.
"""

import numpy as np

from egtviz.egt import (
    clf,
    f_3Dframe,
    f_3Dpanoramic,
    f_3Dwf,
    f_panepipoles,
    f_panproj,
    f_scenepnt,
    pi,
    rotox,
    rotoz,
    show,
)


def main() -> np.ndarray:
    clf()  # start from an empty figure, as a MATLAB script with clf
    quadric, a, b = 2, 0.03, 1.0
    K = np.array([[1e3, 0, 640], [0, 1e3, 480], [0, 0, 1]])
    Hc = np.eye(4)
    Hc[:3, :3] = rotoz(pi / 4) @ rotox(-pi)
    Hc[:3, 3] = [0.2, 0, 0]
    Hd = np.eye(4)
    Hd[:3, :3] = rotox(-pi)
    P = 1e-2 * np.array(
        [[-5, 5, 5, -5, -5, 5, 5, -5], [10, 10, 10, 10, 20, 20, 20, 20], [5, 5, 15, 15, 5, 5, 15, 15]], float
    )
    f_3Dwf("k", 0.1)
    for H, colour in ((Hd, "g"), (Hc, "b")):
        f_3Dpanoramic(H, colour, quadric, a, b)
        f_3Dframe(H, colour, 0.06, "_{m}")
    f_scenepnt(P, "r*", 1)
    qd, _ = f_panproj(P, Hd, K, a, b, quadric, "g:")
    qc, _ = f_panproj(P, Hc, K, a, b, quadric, "b:")
    ed, edp, ec, ecp = f_panepipoles(Hd, Hc, K, a, b, quadric)
    print(f"desired image: {int(np.isfinite(qd[0]).sum())} of 8 points seen")
    print(f"current image: {int(np.isfinite(qc[0]).sum())} of 8 points seen")
    print(f"desired epipoles: ({ed[0]:.2f}, {ed[1]:.2f}) and ({edp[0]:.2f}, {edp[1]:.2f})")
    print(f"current epipoles: ({ec[0]:.2f}, {ec[1]:.2f}) and ({ecp[0]:.2f}, {ecp[1]:.2f})")
    return qd


if __name__ == "__main__":
    main()
    show()  # keep the figure in the browser until Ctrl-C (``--no-wait``: return at once)
