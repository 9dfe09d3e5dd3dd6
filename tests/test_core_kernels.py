"""Kernels rewritten for speed give what the straightforward numpy formulas they replaced give (kept here as the
references): the 7-point pencil members (bit for bit), the drag's grown epipolar-plane triangle (bit for bit) and
the clip of lines to the image (to rounding, checked and unchecked)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import fundamental
from egtviz.geometry.homogeneous import clip_lines_to_rect
from egtviz.scene import derived

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def reference_det3(M):
    """Determinants of a stack of 3x3 matrices (..., 3, 3), written out on strided views (the former kernel)."""
    return (
        M[..., 0, 0] * (M[..., 1, 1] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 1])
        - M[..., 0, 1] * (M[..., 1, 0] * M[..., 2, 2] - M[..., 1, 2] * M[..., 2, 0])
        + M[..., 0, 2] * (M[..., 1, 0] * M[..., 2, 1] - M[..., 1, 1] * M[..., 2, 0])
    )


def reference_cubic_roots(a, b, c):
    """The real roots of x^3 + a x^2 + b x + c as the solver computed them before (one array per operation)."""
    p = b - a * a / 3.0
    q = 2.0 * a**3 / 27.0 - a * b / 3.0 + c
    disc = (q / 2.0) ** 2 + (p / 3.0) ** 3
    one = disc > 0.0
    sq = np.sqrt(np.where(one, disc, 0.0))
    y1 = np.cbrt(-q / 2.0 + sq) + np.cbrt(-q / 2.0 - sq)
    pn = np.where(one | (p >= 0.0), -1.0, p)
    m = 2.0 * np.sqrt(-pn / 3.0)
    arg = np.clip(3.0 * q / (pn * m), -1.0, 1.0)
    phi = np.arccos(arg) / 3.0
    k = np.arange(3) * (2.0 * np.pi / 3.0)
    y3 = m[:, None] * np.cos(phi[:, None] - k)
    y3 = np.where((p >= 0.0)[:, None], 0.0, y3)
    y = np.where(one[:, None], y1[:, None], y3)
    x = y - (a / 3.0)[:, None]
    for _ in range(2):
        f = ((x + a[:, None]) * x + b[:, None]) * x + c[:, None]
        df = (3.0 * x + 2.0 * a[:, None]) * x + b[:, None]
        step = np.where(df != 0.0, f / np.where(df != 0.0, df, 1.0), 0.0)
        x = np.where(np.isfinite(step), x - step, x)
    valid = np.ones(x.shape, bool)
    valid[:, 1:] = ~one[:, None]
    return x, valid


def reference_pencil_members(F1, F2):
    """The members as the solver built them before: both branches on (K, 3, 3, 3) blocks, then the real ones."""
    k3, k0, pp, pm = reference_det3(np.stack((F1, F2, F1 + F2, F1 - F2)))
    k2 = 0.5 * (pp - pm) - k0
    k1 = 0.5 * (pp + pm) - k3
    first = np.abs(k3) >= np.abs(k0)
    lead = np.where(first, k3, k0)
    lead = np.where(lead == 0.0, 1e-300, lead)
    with np.errstate(over="ignore", invalid="ignore"):
        roots, real = reference_cubic_roots(
            np.where(first, k2, k1) / lead, np.where(first, k1, k2) / lead, np.where(first, k0, k3) / lead
        )
    r = roots[:, :, None, None]
    cand = np.where(first[:, None, None, None], r * F1[:, None] + F2[:, None], F1[:, None] + r * F2[:, None])
    return cand[real & np.isfinite(roots)]


@settings(max_examples=60, deadline=None)
@given(seed=seeds, k=st.sampled_from([1, 7, 128]), scale=st.sampled_from([1e-3, 1.0, 1e3]))
def test_pencil_members_are_the_reference_bit_for_bit(seed, k, scale):
    rng = np.random.default_rng(seed)
    F1, F2 = rng.normal(size=(2, k, 3, 3)) * scale
    F2[: k // 3] = F1[: k // 3] * 0.5  # degenerate pencils: a constant determinant ratio
    np.testing.assert_array_equal(fundamental._cubic_solutions(F1, F2), reference_pencil_members(F1, F2))


@settings(max_examples=60, deadline=None)
@given(seed=seeds, k=st.sampled_from([1, 7, 128]), scale=st.sampled_from([1e-6, 1.0, 1e6]))
def test_cubic_roots_are_the_reference_bit_for_bit(seed, k, scale):
    rng = np.random.default_rng(seed)
    a, b, c = rng.normal(size=(3, k)) * scale
    b[: k // 3] = a[: k // 3] ** 2 / 3.0  # p = 0: the triple-root branch
    c[k // 2 :: 4] = 0.0  # a root at 0
    with np.errstate(all="ignore"):
        x, valid = fundamental._real_cubic_roots(a, b, c)
        x_ref, valid_ref = reference_cubic_roots(a, b, c)
    np.testing.assert_array_equal(valid, valid_ref)
    np.testing.assert_array_equal(x, x_ref)


@settings(max_examples=60, deadline=None)
@given(seed=seeds)
def test_seven_point_candidates_are_unit_and_fit_the_sample(seed):
    rng = np.random.default_rng(seed)
    A7 = rng.normal(size=(16, 7, 9))
    cand = fundamental.seven_point_candidates(A7)
    assert len(cand) >= 16
    np.testing.assert_allclose(np.linalg.norm(cand.reshape(-1, 9), axis=1), 1.0, rtol=1e-12)
    # Each candidate satisfies the seven equations of one sample.
    resid = np.abs(np.einsum("kij,mj->mki", A7, cand.reshape(-1, 9))).max(axis=2)
    assert np.all(resid.min(axis=1) < 1e-9)


@settings(max_examples=60, deadline=None)
@given(seed=seeds, scale=st.sampled_from([1e-3, 1.0, 50.0]))
def test_grown_triangle_is_the_numpy_formula_bit_for_bit(seed, scale):
    a, b, c = np.random.default_rng(seed).normal(size=(3, 3)) * scale
    tri = np.array([a, b, c])
    centroid = (tri[0] + tri[1] + tri[2]) / 3.0
    np.testing.assert_array_equal(derived._grown_triangle(a, b, c), centroid + derived.PLANE_MARGIN * (tri - centroid))


@settings(max_examples=60, deadline=None)
@given(seed=seeds, size=st.sampled_from([(640, 480), (1, 1), (7, 1e4)]))
def test_clip_endpoints_lie_on_their_lines_inside_the_image(seed, size):
    """The clip on random lines through the image: each end on its line and on the border, the segment the
    chord of the line (the checked and unchecked calls are the same bits, ``test_drag_fast_paths``)."""
    rng = np.random.default_rng(seed)
    w, h = size
    p = rng.uniform([0, 0], [w, h], size=(40, 2))
    theta = rng.uniform(0, np.pi, 40)
    n = np.column_stack([np.cos(theta), np.sin(theta)])
    lines = np.column_stack([n, -(n * p).sum(axis=1)]) * rng.uniform(1e-3, 1e3, size=(40, 1))
    seg, hit = clip_lines_to_rect(lines, w, h, check=False)
    assert hit.all()
    tol = 1e-9 * max(w, h)
    ends = seg.reshape(-1, 2)
    unit = lines / np.hypot(lines[:, 0], lines[:, 1])[:, None]
    dist = np.abs((seg * unit[:, None, :2]).sum(axis=2) + unit[:, None, 2])
    assert dist.max() < tol
    on_border = np.minimum.reduce([ends[:, 0], w - ends[:, 0], ends[:, 1], h - ends[:, 1]])
    assert np.all(np.abs(on_border) < tol)


@settings(max_examples=60, deadline=None)
@given(seed=seeds, size=st.sampled_from([(640, 480), (1, 1), (8192, 3)]))
def test_in_image_is_the_per_coordinate_test(seed, size):
    from egtviz.geometry.pinhole import PinholeProjection

    rng = np.random.default_rng(seed)
    w, h = size
    px = rng.uniform(-0.5, 1.5, size=(50, 2)) * [w, h]
    px[:6] = [[0, 0], [w, h], [w, 0], [0, h], [np.nextafter(w, np.inf), 1e-3], [-0.0, np.nextafter(h, 0)]]
    px[6] = np.nan  # behind the camera
    proj = PinholeProjection(px, np.ones(50), np.ones(50, bool), (w, h))
    u, v = px[:, 0], px[:, 1]
    with np.errstate(invalid="ignore"):
        expected = (u >= 0) & (u <= w) & (v >= 0) & (v <= h)
    np.testing.assert_array_equal(proj.in_image, expected)
