"""The robust estimators' final Sampson refinement stops far below the noise: the answer is a tight refinement's."""

from __future__ import annotations

import numpy as np
import pytest

import egtviz.geometry.robust as robust
from egtviz.bench.estimation import _accuracy, _scene


@pytest.mark.parametrize("estimator", ["fundamental_ransac", "fundamental_lmeds", "fundamental_mapsac"])
@pytest.mark.parametrize("seed", [0, 1, 3])
def test_the_final_refinement_gives_a_tight_refinements_answer(monkeypatch, estimator: str, seed: int) -> None:
    s = _scene(600, 0.5, 0.3, seed)
    fit = getattr(robust, estimator)
    loose = fit(s["U1"], s["U2"])
    monkeypatch.setattr(robust, "_REFINE_TOL", 1e-10)
    tight = fit(s["U1"], s["U2"])
    np.testing.assert_array_equal(loose.inliers, tight.inliers)
    np.testing.assert_allclose(loose.F, tight.F, rtol=0, atol=1e-6)
    assert _accuracy(loose.F, s) <= _accuracy(tight.F, s) + 1e-4  # pixels
