"""The normalised 8-point algorithm's fused kernel gives the textbook algorithm's F, whatever the memory layout."""

from __future__ import annotations

import numpy as np
import pytest

from egtviz.bench.estimation import _scene
from egtviz.geometry.fundamental import fundamental_normalized_8point
from egtviz.geometry.matrices import hartley_normalization, hartley_scales


def _textbook_normalised_8point(U1: np.ndarray, U2: np.ndarray) -> np.ndarray:
    """H&Z Algorithm 11.1 written plainly: normalise, SVD of A, rank 2 by SVD, denormalise, canonical sign and scale."""
    (n1, T1), (n2, T2) = hartley_normalization(U1), hartley_normalization(U2)
    h1, h2 = np.c_[n1, np.ones(len(n1))], np.c_[n2, np.ones(len(n2))]
    A = np.einsum("ni,nj->nij", h2, h1).reshape(-1, 9)
    Fn = np.linalg.svd(A)[2][-1].reshape(3, 3)
    U, s, Vt = np.linalg.svd(Fn)
    F = T2.T @ (U @ np.diag([s[0], s[1], 0.0]) @ Vt) @ T1
    F = F / F.flat[np.argmax(np.abs(F))]
    return F / np.linalg.norm(F)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("n", [8, 30, 1000])
def test_the_fast_normalised_8point_is_the_textbook_algorithm(seed: int, n: int) -> None:
    s = _scene(n, 0.5, 0.3 if seed % 2 else 0.0, seed)
    F = fundamental_normalized_8point(s["U1"], s["U2"])
    np.testing.assert_allclose(F, _textbook_normalised_8point(s["U1"], s["U2"]), rtol=0, atol=1e-9)


def test_any_memory_layout_gives_the_same_f() -> None:
    # Fortran-ordered and strided float64 arrays take the fast route too: the answer must not depend on layout
    # (a complex view of them is impossible, so the kernel copies them first).
    s = _scene(50, 0.5, 0.0, 3)
    F = fundamental_normalized_8point(s["U1"], s["U2"])
    fortran = fundamental_normalized_8point(np.asfortranarray(s["U1"]), np.asfortranarray(s["U2"]))
    np.testing.assert_array_equal(fortran, F)
    wide1, wide2 = np.repeat(s["U1"], 2, axis=1), np.repeat(s["U2"], 2, axis=1)
    np.testing.assert_array_equal(fundamental_normalized_8point(wide1[:, ::2], wide2[:, ::2]), F)


def test_hartley_scales_are_sqrt2_over_the_mean_distance_and_check_spread() -> None:
    pts = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 4.0], [0.0, -4.0]])
    assert hartley_scales([0j], [2.5], 4, [pts], ["U"]) == [np.sqrt(2.0) / 2.5]
    with pytest.raises(Exception, match="U: all points coincide"):
        hartley_scales([5 + 7j], [0.0], 4, [np.tile([5.0, 7.0], (4, 1))], ["U"])
