"""The tutorial's Examples 1-4 (EGT reference, section 8) through the EGT facade, as golden tests.

Each expected value is derived independently inside the test, from the
geometric description rather than from egtviz's code path, and the resulting
literal numbers are asserted too (so a silent change of both routes shows).
"""

import runpy
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from egtviz.egt import (
    f_epipconics,
    f_epipline,
    f_epipole,
    f_Festim,
    f_panepipoles,
    f_panproj,
    f_perspproj,
    f_Rt2H,
    rotoy,
    rotoz,
)
from egtviz.geometry import GeometryError

K_PAN = np.array([[1e3, 0, 320], [0, 1e3, 240], [0, 0, 1]])


def by_hand_pinhole(X, centre, z_axis, y_axis, K):
    """Project with camera axes written out by hand: u along x = y cross z."""
    z = np.asarray(z_axis, float) / np.linalg.norm(z_axis)
    y = np.asarray(y_axis, float) / np.linalg.norm(y_axis)
    x = np.cross(y, z)
    d = np.asarray(X, float) - centre
    m = K @ np.array([d @ x, d @ y, d @ z])
    return m[:2] / m[2]


def test_example_1_pinhole_placement():
    H = f_Rt2H(rotoy(np.pi / 4), [-10, -5, 0])
    Xw = np.array([[-3, 3, 3, -3], [3, 3, 3, 3], [-3, -3, 3, 3]], float)
    u, v = f_perspproj(Xw, H, np.eye(3))
    # By hand: a pan of 45 degrees from +y towards +x: optical axis (1, 1, 0)/sqrt2, image v down (-z).
    expected = np.array([by_hand_pinhole(X, [-10, -5, 0], [1, 1, 0], [0, 0, -1], np.eye(3)) for X in Xw.T])
    np.testing.assert_allclose(np.column_stack([u, v]), expected, atol=1e-12)
    np.testing.assert_allclose(
        np.column_stack([u, v]),
        [[-1 / 15, 0.28284271247461906], [5 / 21, 0.20203050891044214], [5 / 21, -0.20203050891044214], [-1 / 15, -0.28284271247461906]],
        atol=1e-12,
    )


def test_example_2_panoramic_placement():
    H = np.eye(4)
    H[:3, :3] = rotoz(np.pi / 4)
    H[:3, 3] = [-5, -5, 0]
    m, Xh = f_panproj([0, 0, 4], H, K_PAN)
    # By hand: the point in the mirror frame, then the root of the hyperbola along the ray (brentq),
    # then the CCD pin-hole 2e below the focus.
    a, b = 3.0, 1.0
    e = np.hypot(a, b)
    X = rotoz(np.pi / 4).T @ (np.array([0, 0, 4.0]) - [-5, -5, 0])
    on_sheet = lambda lam: (lam * X[2] + e) / a - np.sqrt(1 + (lam * np.hypot(*X[:2]) / b) ** 2)  # noqa: E731
    lam = brentq(on_sheet, 1e-6, 0.3)
    Xh_hand = lam * X
    m_hand = K_PAN @ (Xh_hand + [0, 0, 2 * e])
    np.testing.assert_allclose(Xh[:, 0], Xh_hand, atol=1e-12)
    np.testing.assert_allclose(m[:, 0], m_hand / m_hand[2], atol=1e-9)
    np.testing.assert_allclose(m[:, 0], [410.48906145334, 240.0, 1.0], atol=1e-8)
    assert m.shape == (3, 1) and Xh.shape == (3, 1)


def test_example_3_pinhole_epipolar_geometry():
    H1 = f_Rt2H(rotoz(np.pi / 4), [-10, -10, 0])
    H2 = f_Rt2H(np.eye(3), [0, 0, 0])
    K = np.eye(3)
    e1, e2, F = f_epipole(H1, H2, K, K)
    Xw = np.array([[0, 10, 10], [-10, 5, 5]], float).T
    u1, v1 = f_perspproj(Xw, H1, K)
    u2, v2 = f_perspproj(Xw, H2, K)
    m1 = np.vstack([u1, v1, np.ones(2)])
    m2 = np.vstack([u2, v2, np.ones(2)])
    # Independent F: H&Z (9.1), F = [e2]_x P2 P1^+, with P = K [R^T | -R^T t] built from H.
    P = [np.hstack([H[:3, :3].T, (-H[:3, :3].T @ H[:3, 3])[:, None]]) for H in (H1, H2)]
    C1 = np.append(H1[:3, 3], 1.0)
    e2_hand = P[1] @ C1
    ex = np.array([[0, -e2_hand[2], e2_hand[1]], [e2_hand[2], 0, -e2_hand[0]], [-e2_hand[1], e2_hand[0], 0]])
    F_hand = ex @ P[1] @ np.linalg.pinv(P[0])
    F_hand /= np.linalg.norm(F_hand)
    assert min(np.linalg.norm(F - F_hand), np.linalg.norm(F + F_hand)) < 1e-12
    # Literal values (K = I): the epipoles and the projections.
    np.testing.assert_allclose(e1, [np.sqrt(0.5), -np.sqrt(0.5), 1.0], atol=1e-12)
    np.testing.assert_allclose(e2, [1.0, 0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(m1[:2].T, [[0.0, -np.sqrt(0.5)], [-np.sqrt(2) / 6, -np.sqrt(2) / 6]], atol=1e-12)
    np.testing.assert_allclose(m2[:2].T, [[0.0, -1.0], [-2.0, -1.0]], atol=1e-12)
    # Epipolar lines pass through the matched points and meet at the epipoles.
    l1, l2 = f_epipline(m1, m2, F)
    assert l1.shape == (3, 2) and l2.shape == (3, 2)
    np.testing.assert_allclose(np.einsum("in,in->n", l1, m1), 0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("in,in->n", l2, m2), 0, atol=1e-12)
    np.testing.assert_allclose(l1.T @ e1, 0, atol=1e-12)
    np.testing.assert_allclose(l2.T @ e2, 0, atol=1e-12)


def test_example_4_panoramic_epipolar_geometry():
    H1 = np.eye(4)
    H1[:3, :3] = rotoz(np.pi / 4)
    H1[:3, 3] = [-10, -10, 0]
    H2 = np.eye(4)
    rng = np.random.default_rng(4)
    Xw = np.column_stack([rng.uniform(-8, 2, 8), rng.uniform(-8, 2, 8), rng.uniform(-4, 2, 8)]).T
    e1, e1p, e2, e2p = f_panepipoles(H1, H2, K_PAN)
    C1, C2 = f_epipconics(Xw, H1, H2, K_PAN)
    assert C1.shape == (8, 3, 3) and C2.shape == (8, 3, 3)
    m1, _ = f_panproj(Xw, H1, K_PAN)
    m2, _ = f_panproj(Xw, H2, K_PAN)
    # The epipoles by hand: along the baseline from each focus, the hyperbola root (brentq) and the CCD.
    a, b = 3.0, 1.0
    e = np.hypot(a, b)

    def image_of_direction(R, d):
        d = R.T @ d
        f = lambda lam: (lam * d[2] + e) / a - np.sqrt(1 + (lam * np.hypot(*d[:2]) / b) ** 2)  # noqa: E731
        lam = brentq(f, 1e-9, 1e3)
        m = K_PAN @ (lam * d + [0, 0, 2 * e])
        return m / m[2]

    base = H2[:3, 3] - H1[:3, 3]
    np.testing.assert_allclose(e1, image_of_direction(H1[:3, :3], base), atol=1e-8)
    np.testing.assert_allclose(e1p, image_of_direction(H1[:3, :3], -base), atol=1e-8)
    np.testing.assert_allclose(e2, image_of_direction(H2[:3, :3], -base), atol=1e-8)
    np.testing.assert_allclose(e2p, image_of_direction(H2[:3, :3], base), atol=1e-8)
    # Each conic passes through its point's image and both epipoles of its image.
    for C, m, ea, eb in ((C1, m1, e1, e1p), (C2, m2, e2, e2p)):
        for i in range(8):
            Ci = C[i] / np.linalg.norm(C[i])
            for p in (m[:, i], ea, eb):
                if np.all(np.isfinite(p)):
                    assert abs(p @ Ci @ p) < 1e-9 * (p @ p)


def test_festim_recovers_example_3_F_from_noise_free_points():
    H1 = f_Rt2H(rotoz(np.pi / 4), [-10, -10, 0])
    H2 = f_Rt2H(np.eye(3), [0, 0, 0])
    K = np.array([[800, 0, 320], [0, 800, 240], [0, 0, 1.0]])
    _, _, F = f_epipole(H1, H2, K, K)
    rng = np.random.default_rng(0)
    Xw = np.column_stack([rng.uniform(-5, 5, 20), rng.uniform(8, 16, 20), rng.uniform(-3, 3, 20)]).T
    U1 = np.vstack(f_perspproj(Xw, H1, K))
    U2 = np.vstack(f_perspproj(Xw, H2, K))
    for algorithm in (1, 2, 3, 4, 5, 6, 7, "ransac"):
        Fe = f_Festim(U1, U2, algorithm)
        assert min(np.linalg.norm(Fe - F), np.linalg.norm(Fe + F)) < 1e-6, algorithm


def test_facade_errors_name_the_argument():
    H = f_Rt2H(np.eye(3), [0, 0, 0])
    with pytest.raises(GeometryError, match=r"Xw: expected shape \(3, N\)"):
        f_perspproj(np.zeros((5, 2)), H, np.eye(3))
    with pytest.raises(GeometryError, match="Xw: a homogeneous point has last coordinate 0"):
        f_perspproj(np.zeros((4, 2)), H, np.eye(3))
    with pytest.raises(GeometryError, match="K: calibration matrix is (singular|not invertible)"):
        f_perspproj([0, 1, 0], H, np.zeros((3, 3)) + np.diag([0, 0, 1.0]))
    with pytest.raises(GeometryError, match="a: expected a positive"):
        f_panproj([0, 0, 4], np.eye(4), None, a=-1.0)
    with pytest.raises(GeometryError, match="centres coincide"):
        f_epipole(H, H, np.eye(3), np.eye(3))
    with pytest.raises(GeometryError, match="algorithm"):
        f_Festim(np.zeros((2, 8)), np.zeros((2, 8)), 9)


def test_point_behind_camera_gives_nan_not_a_pixel():
    H = f_Rt2H(np.eye(3), [0, 0, 0])
    u, v = f_perspproj(np.array([[0, -5, 0], [1, 5, 0]], float).T, H, np.eye(3))
    assert np.isnan(u[0]) and np.isnan(v[0])
    np.testing.assert_allclose([u[1], v[1]], [0.2, 0.0])


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize(
    "script, expected",
    [
        # Example 1's first corner: u = -1/15, v = 0.2828... (test_example_1 derives them by hand).
        ("01_pinhole_placement.py", "point 1: u = -0.066667, v = 0.282843"),
        # The paper's printed Example 2 pixel, u = 410.48 (brentq root in test_example_2).
        ("02_panoramic_placement.py", "m = (410.49, 240.00)"),
        # Example 3's epipoles by hand: e1 = (sqrt(1/2), -sqrt(1/2)), e2 = (1, 0).
        ("03_pinhole_epipolar.py", "e1 = (0.707107, -0.707107, 1)"),
        # Horizontal baseline, mirror a=3, b=1: the epipole is 1000 (1/3) / (2 sqrt 10) = 52.705 px off centre.
        ("04_panoramic_epipolar.py", "e1 = (372.705, 240.000), e1' = (267.295, 240.000)"),
        # Desired camera's epipole: the actual centre (-5, -5, 0) seen from the origin looking along +y: (1, 0).
        ("05_pinhole_demo.py", "ed = (1.000000, "),
        # Parabola h = 0.03 m, horizontal baseline: the epipoles are h * 1000 = 30 px from (640, 480).
        ("06_panoramic_demo.py", "desired epipoles: (670.00, 480.00) and (610.00, 480.00)"),
        ("07_planar_mirror_demo.py", "points seen in both mirrors: 20 of 20"),
    ],
)
def test_example_scripts_run_headless_and_print_their_results(script, expected, capsys):
    runpy.run_path(str(EXAMPLES / script), run_name="__main__")
    out = capsys.readouterr().out
    assert expected in out, out


def test_planar_mirror_demo_recovers_the_virtual_epipoles(capsys):
    runpy.run_path(str(EXAMPLES / "07_planar_mirror_demo.py"), run_name="__main__")
    errors = [float(line.split("=")[1]) for line in capsys.readouterr().out.splitlines() if "epipole_e" in line]
    assert len(errors) == 2 and max(errors) < 1e-6


def test_readme_snippet_runs():
    ns: dict = {}
    exec("from egtviz.egt import *\nimport numpy as np\n" + README_SNIPPET, ns)
    np.testing.assert_allclose(ns["u"], [-1 / 15, 5 / 21, 5 / 21, -1 / 15], atol=1e-12)
    # e2: camera 1's centre (-10, -5, 0) in camera 2 (x right = world x, y down = world -z, z = world y):
    # (-10, 0, -5), i.e. the homogeneous pixel (2, 0, 1).
    np.testing.assert_allclose(ns["e2"], [2.0, 0.0, 1.0], atol=1e-12)


README_SNIPPET = """
H = f_Rt2H(rotoy(pi / 4), [-10, -5, 0])                                    # Example 1
u, v = f_perspproj(np.array([[-3, 3, 3, -3], [3, 3, 3, 3], [-3, -3, 3, 3]]), H, eye(3))
e1, e2, F = f_epipole(H, f_Rt2H(eye(3), [0, 0, 0]), eye(3), eye(3))      # m2' F m1 = 0
"""
