"""Shared helpers of the catadioptric tests: the tutorial's K, hypothesis strategies, random mirrors."""

import numpy as np
from hypothesis import strategies as st

from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror

K_EGT = np.array([[1e3, 0.0, 320.0], [0.0, 1e3, 240.0], [0.0, 0.0, 1.0]])

seeds = st.integers(min_value=0, max_value=2**32 - 1)
kinds = st.sampled_from(["hyperbolic", "parabolic"])


def random_mirror(rng: np.random.Generator, kind: str):
    if kind == "hyperbolic":
        b = rng.uniform(0.3, 2.0)
        return HyperbolicMirror(a=rng.uniform(0.5, 4.0), b=b, rim_radius=b * rng.uniform(1.0, 3.0))
    h = rng.uniform(0.3, 2.0)
    return ParabolicMirror(h=h, rim_radius=h * rng.uniform(1.0, 3.0))
