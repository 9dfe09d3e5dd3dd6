"""The lock-free cached attribute of the core's immutable values, and the drag's read-out tolerance arithmetic."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from egtviz.geometry import Pose
from egtviz.geometry._shared import cached_value
from egtviz.geometry.pinhole import Intrinsics, PinholeCamera


@dataclass(frozen=True)
class _Counted:
    x: float
    calls: list

    @cached_value
    def doubled(self) -> float:
        """Twice x."""
        self.calls.append(1)
        return 2.0 * self.x


def test_computed_once_per_instance_and_stored_on_it():
    a, b = _Counted(1.5, []), _Counted(4.0, [])
    assert (a.doubled, a.doubled, b.doubled) == (3.0, 3.0, 8.0)
    assert (len(a.calls), len(b.calls)) == (1, 1)
    assert a.__dict__["doubled"] == 3.0
    assert "doubled" not in vars(_Counted(2.0, []))  # nothing computed before the first read


def test_class_access_gives_the_descriptor_with_its_doc():
    descriptor = _Counted.doubled
    assert isinstance(descriptor, cached_value)
    assert descriptor.name == "doubled" and descriptor.__doc__ == "Twice x."


def test_threads_reading_a_new_value_at_once_get_equal_values():
    obj = _Counted(0.25, [])
    barrier = threading.Barrier(8)
    seen: list[float] = []

    def read() -> None:
        barrier.wait()
        seen.append(obj.doubled)

    threads = [threading.Thread(target=read) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert seen == [0.5] * 8


def test_a_pinhole_cameras_matrices_are_built_once_and_read_only():
    cam = PinholeCamera(Pose(np.eye(3), np.array([1.0, -2.0, 0.5])), Intrinsics())
    assert cam.K_Rt is cam.K_Rt and cam.plane_to_line is cam.plane_to_line
    np.testing.assert_array_equal(cam.K_Rt, cam.K @ cam.pose.R.T)
    np.testing.assert_array_equal(cam.plane_to_line, (cam.pose.R @ cam.K_inv).T)
    for a in (cam.K_Rt, cam.plane_to_line, cam.R_K_inv, cam.K, cam.K_inv):
        assert not a.flags.writeable


@settings(max_examples=300, deadline=None)
@given(arrays(np.float64, (3, 3), elements=st.floats(-1e6, 1e6, allow_nan=False)))
def test_the_readouts_rank_tolerance_is_np_linalg_norm_to_the_bit(F):
    # compute_derived's pin-hole read-out takes |F| as sqrt(x . x) of the raveled F: np.linalg.norm's arithmetic.
    x = F.ravel()
    assert math.sqrt(x.dot(x)) == float(np.linalg.norm(F))
