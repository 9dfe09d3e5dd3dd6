"""The servo demos' per-frame geometry (egtviz.servo.frames) against independent computations.

- the core's per-frame route (``epipolar_pair`` + ``epipolar_lines_in_first`` + clipping; ``panoramic_epipoles``;
  ``sample_biconics``): the numbers the viewer drew before the geometry left it;
- identities: every epipolar line passes through the epipole; after a pure translation every feature lies on its
  line; the bi-conics of an aligned robot pass through both visible epipoles;
- forward kinematics against roboticstoolbox's ``fkine_all`` / ``fkine``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import GeometryError
from egtviz.geometry.epipolar import (
    clipped_epipolar_lines,
    epipolar_lines_in_first,
    epipolar_pair,
)
from egtviz.geometry.panoramic_epipolar import panoramic_epipoles, sample_biconics
from egtviz.geometry.pinhole import PinholeCamera
from egtviz.geometry.poses import Pose
from egtviz.servo import ServoResult, simulate_panoramic, simulate_pinhole
from egtviz.servo.frames import (
    CONIC_SAMPLES,
    PANORAMIC_GOAL_MESSAGE,
    PINHOLE_GOAL_MESSAGE,
    DHChain,
    panoramic_frames,
    pinhole_frames,
    robot_poses,
    trail_indices,
)
from egtviz.servo.panoramic_robot import CAMERA_HEIGHT, default_camera, mirror_pose
from egtviz.servo.panoramic_robot import default_scene as panoramic_scene
from egtviz.servo.pinhole_arm import (
    CAMERA_TOOL,
    TARGET_Q,
    camera_pose_from_q,
    default_intrinsics,
    puma,
)
from egtviz.servo.pinhole_arm import default_scene as pinhole_scene


def _result(demo: str, poses: np.ndarray, features: np.ndarray, desired: np.ndarray, **extra) -> ServoResult:
    """A recorded run made of the given poses and features (the rest is filler the frames do not read)."""
    T = len(poses)
    zeros = np.zeros(T)
    return ServoResult(demo=demo, time=np.arange(T) * 0.05, camera_poses=np.asarray(poses), features=features,
                       desired_features=desired, controls={}, errors={"rotation_error_rad": zeros,
                       "translation_error": zeros}, converged=False, reason="synthetic",
                       initial_rotation_error_rad=0.0, initial_translation_error=0.0, final_rotation_error_rad=0.0,
                       final_translation_error=0.0, steps=T - 1, sim_time_s=0.05 * (T - 1), **extra)


def _rotation(axis, angle: float) -> np.ndarray:
    """Rodrigues' formula, written out here (independent of the code under test)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _unordered_close(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Two segments (2, 2) equal up to the order of their ends."""
    return bool(np.abs(a - b).max() <= tol or np.abs(a[::-1] - b).max() <= tol)


def _line_distance(p: np.ndarray, seg: np.ndarray) -> float:
    """Distance of point ``p`` from the infinite line through the segment's two ends."""
    d = seg[1] - seg[0]
    return abs(d[0] * (p[1] - seg[0, 1]) - d[1] * (p[0] - seg[0, 0])) / np.hypot(*d)


def _polyline_distance(p: np.ndarray, P: np.ndarray) -> float:
    """Distance of point ``p`` from the polyline ``P`` (k, 2)."""
    a, b = P[:-1], P[1:]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))


# ------------------------------------------------------------------------------------------------ the old route
@pytest.fixture(scope="module")
def pinhole_run() -> ServoResult:
    return simulate_pinhole(seed=3, steps=120)


@pytest.fixture(scope="module")
def panoramic_run() -> ServoResult:
    return simulate_panoramic(seed=2, steps=120)


def test_pinhole_frames_equal_the_per_frame_core_route(pinhole_run):
    """The vectorised lines and epipoles are those of ``epipolar_pair`` and ``l1 = F^T m*`` frame by frame."""
    r, intr = pinhole_run, default_intrinsics()
    target = Pose.from_matrix(r.extras["target_pose"])
    frames = pinhole_frames(r, intr, target)
    assert len(frames) == r.n_samples == 121
    checked = 0
    for k in range(r.n_samples):
        pair = epipolar_pair(PinholeCamera(Pose.from_matrix(r.camera_poses[k]), intr), PinholeCamera(target, intr))
        segs, hit = clipped_epipolar_lines(epipolar_lines_in_first(pair.F, r.desired_features), intr.width,
                                           intr.height)
        g = frames.at(k)
        assert g.message == "" and g.conics == ()
        assert np.array_equal(np.isnan(g.lines[:, 0, 0]), ~hit)
        for a, b in zip(g.lines[hit], segs[hit]):
            assert _unordered_close(a, b, 1e-7)
            checked += 1
        assert not pair.e1_at_infinity
        (label, e), = g.epipoles
        assert label == "e" and np.allclose(e, pair.e1[:2] / pair.e1[2], atol=1e-7, rtol=1e-12)
    assert checked > 100 * len(r.desired_features)


def test_panoramic_frames_equal_the_per_frame_core_route(panoramic_run):
    """The bi-conic arcs are ``sample_biconics`` of the back-projected rays, the epipoles ``panoramic_epipoles``."""
    r, cam = panoramic_run, default_camera()
    target = mirror_pose(np.zeros(3))
    frames = panoramic_frames(r, cam, target)
    n = len(r.desired_features)
    assert np.allclose(frames.rim, cam.rim_image(256), atol=1e-9)
    for k in range(0, r.n_samples, 7):
        g = frames.at(k)
        d, d_star = cam.back_project(r.features[k]), cam.back_project(r.desired_features)
        expected = sample_biconics(cam, d, d_star, n=CONIC_SAMPLES)
        assert len(g.conics) == n and g.lines is None
        for got, want in zip(g.conics, expected):
            assert len(got) == len(want) >= 1
            for a, b in zip(got, want):
                assert a.shape == b.shape and np.abs(a - b).max() < 1e-7
        pe = panoramic_epipoles(cam.moved(Pose.from_matrix(r.camera_poses[k])), cam.moved(target))
        want_eps = [(lab, e[:2] / e[2]) for lab, e, vis in (("e", pe.e1, pe.e1_visible), ("e'", pe.e1p, pe.e1p_visible))
                    if vis]
        assert [lab for lab, _ in g.epipoles] == [lab for lab, _ in want_eps]
        for (_, a), (_, b) in zip(g.epipoles, want_eps):
            assert np.abs(a - b).max() < 1e-6


# ------------------------------------------------------------------------------------------------ identities
@settings(max_examples=30)
@given(
    t=st.tuples(*[st.floats(-0.3, 0.3)] * 3).filter(lambda v: np.linalg.norm(v) > 0.02),
    axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
    angle=st.floats(-0.4, 0.4),
)
def test_pinhole_lines_meet_in_the_epipole_and_hold_the_features_after_a_translation(t, axis, angle):
    """Frame 0 is turned and moved, frame 1 only moved: every line passes through e; in frame 1 (rotation
    compensated) every current feature lies on the line of its desired feature (m^T F m* = 0)."""
    intr = default_intrinsics()
    target = camera_pose_from_q(TARGET_Q)
    X = pinhole_scene(target)
    moved = Pose(target.R, target.t + np.asarray(t))
    turned = Pose(_rotation(axis, angle) @ target.R, target.t + np.asarray(t))
    poses = np.stack([turned.matrix, moved.matrix])
    feats = np.stack([PinholeCamera(p, intr).project(X).pixels for p in (turned, moved)])
    desired = PinholeCamera(target, intr).project(X).pixels
    frames = pinhole_frames(_result("pinhole", poses, feats, desired), intr, target)
    for k in (0, 1):
        g = frames.at(k)
        segs = g.lines[np.all(np.isfinite(g.lines), axis=(1, 2))]
        if g.epipoles:
            (_, e), = g.epipoles
            for seg in segs:
                assert _line_distance(e, seg) <= 1e-7 * (1.0 + np.linalg.norm(e - seg[0]))
        else:  # the baseline is parallel to the image plane: e is at infinity and the lines are parallel
            dirs = (segs[:, 1] - segs[:, 0]) / np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)[:, None]
            assert np.abs(dirs[:, 0] * dirs[0, 1] - dirs[:, 1] * dirs[0, 0]).max() < 1e-9
    g = frames.at(1)
    inside = np.all((feats[1] >= 0) & (feats[1] <= [intr.width, intr.height]), axis=1)
    assert inside.sum() >= 3
    for i in np.flatnonzero(inside):
        assert np.all(np.isfinite(g.lines[i]))  # its line crosses the image where the feature is
        assert _line_distance(feats[1, i], g.lines[i]) < 1e-6


@settings(max_examples=20)
@given(x=st.floats(-2.5, 2.5), y=st.floats(-2.5, 2.5), theta=st.floats(-1.5, 1.5))
def test_biconics_of_an_aligned_robot_pass_through_both_visible_epipoles(x, y, theta):
    """Same heading as the target, any position: every bi-conic plane holds the baseline, so its image passes
    through e and e' (within the chord error of 96 samples per circle, well under a pixel)."""
    if math.hypot(x, y) < 0.3:
        x += 0.5
    cam, X = default_camera(), panoramic_scene()
    target = mirror_pose((0.0, 0.0, theta))
    current = mirror_pose((x, y, theta))
    feats = cam.moved(current).project(X).pixels
    desired = cam.moved(target).project(X).pixels
    r = _result("panoramic", current.matrix[None], feats[None], desired, states=np.array([[x, y, theta]]))
    g = panoramic_frames(r, cam, target).at(0)
    assert [lab for lab, _ in g.epipoles] == ["e", "e'"]  # the baseline is horizontal: both rays hit the mirror
    drawn = [arcs for arcs in g.conics if arcs]
    assert len(drawn) == len(X)
    for _, e in g.epipoles:
        for arcs in drawn:
            assert min(_polyline_distance(e, a) for a in arcs) < 0.3


def test_at_the_goal_the_frame_says_why_nothing_is_drawn():
    intr = default_intrinsics()
    target = camera_pose_from_q(TARGET_Q)
    X = pinhole_scene(target)
    m = PinholeCamera(target, intr).project(X).pixels
    away = Pose(target.R, target.t + [0.1, 0.0, 0.0])
    poses = np.stack([away.matrix, target.matrix])
    frames = pinhole_frames(_result("pinhole", poses, np.stack([m, m]), m), intr, target)
    assert frames.at(0).message == "" and len(frames.at(0).epipoles) == 1
    g = frames.at(1)
    assert g.message == PINHOLE_GOAL_MESSAGE and g.epipoles == () and np.isnan(g.lines).all()
    assert frames.at(99).message == PINHOLE_GOAL_MESSAGE  # clipped to the last frame

    cam = default_camera()
    goal = mirror_pose(np.zeros(3))
    mp = cam.moved(goal).project(panoramic_scene()).pixels
    r = _result("panoramic", goal.matrix[None], mp[None], mp, states=np.zeros((1, 3)))
    g = panoramic_frames(r, cam, goal).at(0)
    assert g.message == PANORAMIC_GOAL_MESSAGE and g.epipoles == ()
    assert all(arcs == () for arcs in g.conics)  # current and desired rays coincide: no bi-conic plane


def test_features_without_an_image_get_no_curve():
    intr = default_intrinsics()
    target = camera_pose_from_q(TARGET_Q)
    X = pinhole_scene(target)
    moved = Pose(target.R, target.t + [0.05, 0.02, -0.1])
    feats = PinholeCamera(moved, intr).project(X).pixels
    desired = PinholeCamera(target, intr).project(X).pixels
    desired[2] = np.nan
    frames = pinhole_frames(_result("pinhole", moved.matrix[None], feats[None], desired), intr, target)
    lines = frames.at(0).lines
    assert np.isnan(lines[2]).all() and np.isfinite(np.delete(lines, 2, axis=0)).all()

    cam = default_camera()
    goal, here = mirror_pose(np.zeros(3)), mirror_pose((1.0, 0.5, 0.3))
    Xp = panoramic_scene()
    fp = cam.moved(here).project(Xp).pixels
    fp[4] = np.nan
    r = _result("panoramic", here.matrix[None], fp[None], cam.moved(goal).project(Xp).pixels,
                states=np.array([[1.0, 0.5, 0.3]]))
    conics = panoramic_frames(r, cam, goal).at(0).conics
    assert conics[4] == () and all(conics[i] for i in range(len(Xp)) if i != 4)


# ------------------------------------------------------------------------------------------------ the 3D side
@settings(max_examples=25)
@given(q=st.lists(st.floats(-math.pi, math.pi), min_size=6, max_size=6))
def test_link_poses_equal_roboticstoolbox_fkine_all(q):
    robot = puma()[0]
    chain = DHChain.of_robot(robot)
    got = chain.link_poses(q)
    assert got.shape == (1, 7, 4, 4)
    want = np.asarray(robot.fkine_all(np.asarray(q)).A)  # base, then links 1..6 (tool not included)
    assert np.allclose(got[0], want, atol=1e-12)
    assert np.allclose(got[0, -1] @ CAMERA_TOOL, robot.fkine(np.asarray(q)).A, atol=1e-12)


def test_the_arm_carries_the_camera_in_every_frame(pinhole_run):
    r = pinhole_run
    frames = pinhole_frames(r, default_intrinsics(), Pose.from_matrix(r.extras["target_pose"]),
                            chain=DHChain.of_robot(puma()[0]))
    assert frames.links.shape == (r.n_samples, 7, 4, 4)
    assert np.allclose(frames.links[:, -1] @ CAMERA_TOOL, r.camera_poses, atol=1e-12)
    assert np.allclose(frames.body_poses, r.camera_poses) and np.allclose(frames.centres, r.camera_poses[:, :3, 3])


def test_the_robot_carries_the_mirror(panoramic_run):
    r = panoramic_run
    frames = panoramic_frames(r, default_camera(), mirror_pose(np.zeros(3)))
    H = frames.body_poses
    # The mirror focus is CAMERA_HEIGHT above the robot's origin, turned with it.
    assert np.allclose(H[:, :3, 3] + [0.0, 0.0, CAMERA_HEIGHT], frames.centres, atol=1e-12)
    assert np.allclose(H[:, :3, :3], r.camera_poses[:, :3, :3], atol=1e-12)
    assert np.allclose(frames.path[:, :2], r.states[:, :2]) and np.all(frames.path[:, 2] > 0)
    assert np.allclose(robot_poses([[1.0, 2.0, math.pi / 2]])[0],
                       [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 0], [0, 0, 0, 1]], atol=1e-15)


def test_rays_paths_and_trails(pinhole_run):
    r = pinhole_run
    frames = pinhole_frames(r, default_intrinsics(), Pose.from_matrix(r.extras["target_pose"]))
    X = pinhole_scene(Pose.from_matrix(r.extras["target_pose"]))
    segs, idx = frames.ray_segments(10, X)
    assert list(idx) == list(range(len(X))) and np.allclose(segs[:, 0], r.camera_poses[10][:3, 3])
    assert np.allclose(segs[:, 1], X)
    # Each ray points where the camera sees the point: the projection of its far end is the feature.
    cam = PinholeCamera(Pose.from_matrix(r.camera_poses[10]), default_intrinsics())
    assert np.allclose(cam.project(segs[:, 1]).pixels, r.features[10], atol=1e-9)
    with pytest.raises(GeometryError, match="points"):
        frames.ray_segments(0, X[:3])
    assert frames.path_segments(0).shape == (0, 2, 3)
    P = frames.path_segments(5)
    assert P.shape == (5, 2, 3) and np.allclose(P[:, 1], r.camera_poses[1:6, :3, 3])
    assert frames.trail(5).shape == (6, len(X), 2) and np.allclose(frames.trail(5), r.features[:6])
    assert frames.path_segments(120, limit=10).shape[0] <= 10


def test_trail_indices_thin_and_keep_both_ends():
    assert list(trail_indices(3)) == [0, 1, 2, 3]
    idx = trail_indices(999, 160)
    assert len(idx) <= 161 and idx[0] == 0 and idx[-1] == 999 and np.all(np.diff(idx) > 0)


def test_stop_abandons_the_work(pinhole_run, panoramic_run):
    r = pinhole_run
    assert pinhole_frames(r, default_intrinsics(), camera_pose_from_q(TARGET_Q), stop=lambda: True) is None
    assert panoramic_frames(panoramic_run, default_camera(), mirror_pose(np.zeros(3)), stop=lambda: True) is None


def test_bad_chains_and_joint_angles_are_named():
    with pytest.raises(GeometryError, match="a, d, alpha, offset"):
        DHChain(np.zeros(3), np.zeros(2), np.zeros(3), np.zeros(3), np.eye(4))
    with pytest.raises(GeometryError, match="base"):
        DHChain(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.eye(3))
    chain = DHChain.of_robot(puma()[0])
    with pytest.raises(GeometryError, match=r"q: .*\(T, 6\)"):
        chain.link_poses(np.zeros(5))
    with pytest.raises(GeometryError, match="q"):
        chain.link_poses([0, 0, 0, 0, 0, np.nan])


def test_frames_are_read_only_and_leave_the_run_writable(pinhole_run):
    r = pinhole_run
    frames = pinhole_frames(r, default_intrinsics(), Pose.from_matrix(r.extras["target_pose"]))
    with pytest.raises(ValueError, match="read-only"):
        frames.lines[0, 0, 0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        frames.features[0, 0, 0] = 1.0
    assert r.features.flags.writeable and r.camera_poses.flags.writeable
