"""RANSAC's two-stage pre-emptive scoring and its reweighted final fit never lose the true model on exact data."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import egtviz.geometry.robust as robust
from egtviz.bench.estimation import _scene
from egtviz.geometry.error_metrics import sampson_distance, sampson_distances_normalized
from egtviz.geometry.fundamental import seven_point_candidates


def _normalised_truth(s: dict, threshold: float = 1.0):
    At, T1, T2, scorer, _ = robust._prepare(s["U1"], s["U2"], "ransac", threshold, (0.999, 2000, 0))
    Fn = np.linalg.inv(T2).T @ s["F"] @ np.linalg.inv(T1)
    return At, T1[0, 0], T2[0, 0], scorer, Fn / np.linalg.norm(Fn)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), count=st.integers(1, 300), outliers=st.sampled_from([0.0, 0.3, 0.5]))
def test_the_pretest_never_rejects_the_true_model_on_noise_free_data(seed: int, count: int, outliers: float) -> None:
    s = _scene(400, 0.0, outliers, seed)
    At, s1, s2, scorer, Fn = _normalised_truth(s)
    rng = np.random.default_rng(seed)
    # Rival hypotheses from random 7-point samples (most of them contaminated), the truth among them.
    rivals = seven_point_candidates(At.T[robust._sample(rng, At.shape[1], count)])
    cand = np.insert(rivals, rng.integers(0, rivals.shape[0] + 1), Fn, axis=0)
    At_sub = At[:, rng.choice(At.shape[1], robust._SUBSET, replace=False)]
    kept = robust._preempt(cand, At_sub, s1, s2, scorer)
    assert kept.shape[0] == min(robust._KEEP, cand.shape[0])
    # The truth, or a rival from an all-inlier sample that is the truth to rounding (either sign).
    assert any(min(np.abs(k - Fn).max(), np.abs(k + Fn).max()) < 1e-9 for k in kept)


def test_the_first_stage_prunes_and_keeps_the_best_on_the_first_points() -> None:
    s = _scene(400, 0.0, 0.3, 5)
    At, s1, s2, scorer, Fn = _normalised_truth(s)
    rng = np.random.default_rng(5)
    rivals = seven_point_candidates(At.T[robust._sample(rng, At.shape[1], 200)])
    assert rivals.shape[0] > robust._PREEMPT_KEEP
    At_sub = At[:, rng.choice(At.shape[1], robust._SUBSET, replace=False)]
    cost_first = scorer.cost(sampson_distances_normalized(rivals, At_sub[:, : robust._SUBSET_FIRST], s1, s2))
    cost_sub = scorer.cost(sampson_distances_normalized(rivals, At_sub, s1, s2))
    kept = robust._preempt(rivals, At_sub, s1, s2, scorer)
    survivors = np.argsort(cost_first, kind="stable")[: robust._PREEMPT_KEEP]
    best_survivor = survivors[np.argmin(cost_sub[survivors])]
    np.testing.assert_array_equal(kept[0], rivals[best_survivor])
    # A rival outside the first stage's survivors is never kept, however it scores on the whole subset.
    pruned = np.setdiff1d(np.arange(rivals.shape[0]), survivors)
    assert not any(np.array_equal(k, rivals[i]) for k in kept for i in pruned)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), outliers=st.sampled_from([0.0, 0.3]))
def test_ransac_recovers_the_true_model_and_inliers_on_noise_free_data(seed: int, outliers: float) -> None:
    s = _scene(300, 0.0, outliers, seed)
    est = robust.fundamental_ransac(s["U1"], s["U2"])
    F = s["F"] / np.linalg.norm(s["F"])
    F = F * np.sign(F.flat[np.argmax(np.abs(F))])
    # The final fit uses the band d < (1.5 tau)^2: exact unless a random outlier falls in it (then it pulls
    # F by about 1e-5 here, as the Levenberg-Marquardt refinement before did).
    out = ~s["inl"]
    near = sampson_distance(s["F"], s["U1"][out], s["U2"][out]) < 1.5**2 if out.any() else np.zeros(0, bool)
    np.testing.assert_allclose(est.F, F, rtol=0, atol=1e-3 if near.any() else 1e-9)
    # Random outliers can fall on their epipolar line: every true inlier is found, and no more than a few others.
    assert np.all(est.inliers[s["inl"]])
    assert int(est.inliers[~s["inl"]].sum()) <= max(3, int(0.02 * (~s["inl"]).sum()))


def test_the_first_batch_meets_the_adaptive_bound_of_the_answer() -> None:
    s = _scene(1000, 0.5, 0.3, 0)
    est = robust.fundamental_ransac(s["U1"], s["U2"])
    assert est.iterations == robust._BATCH_FIRST
    assert est.iterations >= robust._iteration_bound(float(est.inliers.mean()), 0.999)
