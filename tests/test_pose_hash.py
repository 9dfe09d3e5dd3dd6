"""A Pose hashes by value, so specs (frozen dataclasses holding one) that differ only in pose hash apart."""

import dataclasses

import numpy as np
from hypothesis import given, strategies as st

from egtviz.geometry.poses import Pose
from egtviz.scene.examples import default_scene

coords = st.floats(-1e3, 1e3, allow_nan=False)


@given(st.tuples(coords, coords, coords))
def test_equal_poses_hash_alike_even_with_signed_zeros(t):
    a = Pose(np.eye(3), t)
    b = Pose(np.eye(3), [x if x != 0.0 else -x for x in t])
    assert a == b and hash(a) == hash(b)


def test_specs_differing_only_in_pose_hash_apart():
    cam = default_scene().cameras[0]
    moved = [dataclasses.replace(cam, pose=Pose(cam.pose.R, cam.pose.t + [0.01 * k, 0.0, 0.0])) for k in range(1, 51)]
    assert len({hash(c) for c in moved}) == 50
    assert len(set(moved)) == 50
