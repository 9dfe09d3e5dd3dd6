"""Checked at the edge, fast inside: the core's ``check=False`` paths give the checked results, and a drag
validates only the dragged pose.

- every ``check=False`` method of each camera model, ``epipolar_curves``, ``essential_from_poses``,
  ``fundamental_from_essential`` and ``image_to_world`` against the checked call, on random valid input;
- ``compute_derived`` (the fast path) against ``compute_derived(check=True)`` (the core's checked calls), to
  1e-12, for random poses of pin-hole, panoramic, unified and mixed pairs;
- the checked converters of ``egtviz.geometry._validate`` are called once per drag update in the viewer (the
  gizmo's quaternion), and not at all by the model's update.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.geometry import _validate
from egtviz.geometry.epipolar import essential_from_poses, fundamental_from_essential
from egtviz.geometry.epipolar_curves import epipolar_curves
from egtviz.scene import (
    PanoramicSpec,
    PinholeSpec,
    Scene,
    SceneModel,
    UnifiedSpec,
    compute_derived,
    default_scene,
    panoramic_scene,
)

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def _scenes() -> dict[str, Scene]:
    pin, pan = default_scene(), panoramic_scene()
    uni = UnifiedSpec("uni", (2.0, -6.0, 1.5), (-15.0, -5.0, 0.0), xi=0.7)
    flat = UnifiedSpec("flat", (-2.0, -6.0, 1.5), (15.0, -5.0, 0.0), xi=0.0)
    para = PanoramicSpec("para", (0.5, 0.5, 0.5), mirror="parabolic", a=1.0)
    return {
        "pinhole": pin,
        "panoramic": pan,
        "unified-pinhole": Scene(cameras=(uni, pin.cameras[0]), points=pin.points),
        "flat-unified-pinhole": Scene(cameras=(pin.cameras[0], flat), points=pin.points),
        "pinhole-parabolic": Scene(cameras=(pin.cameras[1], para), points=pin.points),
    }


SCENES = _scenes()


def _moved(scene: Scene, rng: np.random.Generator, n_points: int) -> Scene:
    """The first camera moved and turned at random, ``n_points`` random points (one on the baseline)."""
    c0, c1 = scene.cameras[:2]
    c0 = dataclasses.replace(c0, position=tuple(np.array(c0.position) + rng.normal(0, 1.0, 3)),
                             ypr_deg=tuple(np.array(c0.ypr_deg) + rng.normal(0, 25, 3)))
    X = rng.normal(size=(n_points, 3)) * 2 + scene.points_array().mean(axis=0)
    X[0] = (np.array(c0.position) + np.array(c1.position)) / 2
    return scene.replace(cameras=(c0, c1) + scene.cameras[2:], points=tuple(map(tuple, X)),
                         selected_point=n_points - 1)


def _close(a, b, what: str) -> None:
    if a is None or b is None:
        assert a is None and b is None, what
        return
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype, what
    if a.dtype == bool:
        np.testing.assert_array_equal(a, b, err_msg=what)
    else:
        scale = max(1.0, float(np.nanmax(np.abs(b)))) if np.isfinite(b).any() else 1.0
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * scale, equal_nan=True, err_msg=what)


def _same_derived(fast, ref) -> None:
    assert fast.image_planes.keys() == ref.image_planes.keys()
    for name, p in fast.image_planes.items():
        q = ref.image_planes[name]
        for field in ("points", "visible", "in_image", "lines", "line_coefficients", "rim"):
            _close(getattr(p, field), getattr(q, field), f"{name}.{field}")
        assert (p.n_hidden, p.message, p.in_pair, p.no_image) == (q.n_hidden, q.message, q.in_pair, q.no_image)
        assert [e.label for e in p.epipoles] == [e.label for e in q.epipoles]
        for e, f in zip(p.epipoles, q.epipoles, strict=True):
            assert (e.at_infinity, e.inside) == (f.at_infinity, f.inside)
            _close(e.xy, f.xy, f"{name}.{e.label}.xy")
            _close(e.direction, f.direction, f"{name}.{e.label}.direction")
        for arcs_p, arcs_q in ((p.horizon, q.horizon),) + tuple(zip(p.conics or (), q.conics or (), strict=True)):
            assert len(arcs_p) == len(arcs_q)
            for a, b in zip(arcs_p, arcs_q, strict=True):
                _close(a, b, f"{name} arc")
        _close(fast.rays[name], ref.rays[name], f"{name} rays")
        for a, b in zip(fast.poses[name], ref.poses[name], strict=True):
            _close(a, b, f"{name} pose")
    for field in ("F", "E", "e1", "e2"):
        _close(getattr(fast.pair, field), getattr(ref.pair, field), f"pair.{field}")
    assert (fast.pair.names, fast.pair.rank, fast.pair.message) == (ref.pair.names, ref.pair.rank, ref.pair.message)
    for field in ("epipolar_plane", "selected_normal", "baseline"):
        _close(getattr(fast, field), getattr(ref, field), field)


@settings(max_examples=30, deadline=None)
@given(seed=seeds, which=st.sampled_from(sorted(SCENES)), n_points=st.sampled_from([1, 8, 40]))
def test_the_fast_derived_scene_is_the_checked_one(seed, which, n_points):
    scene = _moved(SCENES[which], np.random.default_rng(seed), n_points)
    _same_derived(compute_derived(scene), compute_derived(scene, check=True))


def test_coincident_centres_give_the_same_message_on_both_paths():
    scene = SCENES["pinhole"]
    c0, c1 = scene.cameras[:2]
    scene = scene.replace(cameras=(dataclasses.replace(c0, position=c1.position), c1))
    _same_derived(compute_derived(scene), compute_derived(scene, check=True))


@settings(max_examples=30, deadline=None)
@given(seed=seeds, which=st.sampled_from(sorted(SCENES)))
def test_every_unchecked_core_call_is_the_checked_call(seed, which):
    rng = np.random.default_rng(seed)
    scene = _moved(SCENES[which], rng, 12)
    c1, c2 = (s.camera() for s in scene.cameras[:2])
    X = scene.points_array()
    normals = rng.normal(size=(12, 3)) * rng.choice([1e-3, 1.0, 1e3], size=(12, 1))
    normals[3] = np.nan  # a point on a baseline has no plane
    normals[4] = 0.0
    for cam in (c1, c2):
        p, q = cam.project(X, check=False), cam.project(X)
        for field in ("pixels", "visible", "in_image"):
            np.testing.assert_array_equal(getattr(p, field), getattr(q, field))
        np.testing.assert_array_equal(cam.light_paths(X, check=False), cam.light_paths(X))
        d = c2.centre - c1.centre
        a, b = cam.baseline_images(d, check=False), cam.baseline_images(d)
        np.testing.assert_array_equal(a.points, b.points)
        np.testing.assert_array_equal(a.visible, b.visible)
        _close(cam.plane_image_lines(normals, check=False), cam.plane_image_lines(normals), "lines")
        _close(cam.plane_image_conics(normals, check=False), cam.plane_image_conics(normals), "conics")
        arcs_a, arcs_b = cam.plane_image_arcs(normals, 24, check=False), cam.plane_image_arcs(normals, 24)
        assert [len(x) for x in arcs_a] == [len(x) for x in arcs_b]
        for x, y in zip(arcs_a, arcs_b, strict=True):
            for u, v in zip(x, y, strict=True):
                _close(u, v, "arc")
        np.testing.assert_array_equal(cam.pose.to_local(X, check=False), cam.pose.to_local(X))
        if hasattr(cam, "sphere_points"):  # the unified camera's 3D drawing
            np.testing.assert_array_equal(cam.sphere_points(X[1], 0.5, check=False), cam.sphere_points(X[1], 0.5))
            np.testing.assert_array_equal(cam.projection_centre(0.5, check=False), cam.projection_centre(0.5))
            n = normals[0] / np.linalg.norm(normals[0])
            np.testing.assert_array_equal(cam.great_circle(n, 48, 0.5, check=False), cam.great_circle(n, 48, 0.5))
        if hasattr(cam, "image_to_world"):
            px = rng.uniform(0, 640, size=(5, 2))
            np.testing.assert_array_equal(cam.image_to_world(px, 0.3, check=False), cam.image_to_world(px, 0.3))
    fast = epipolar_curves(c1, c2, X, n_samples=24, check=False)
    ref = epipolar_curves(c1, c2, X, n_samples=24)
    _close(fast.normals, ref.normals, "normals")
    for a, b in ((fast.first, ref.first), (fast.second, ref.second)):
        for field in ("conics", "lines", "epipoles", "epipoles_visible"):
            _close(getattr(a, field), getattr(b, field), field)
    E = essential_from_poses(c1.pose, c2.pose, check=False)
    np.testing.assert_array_equal(E, essential_from_poses(c1.pose, c2.pose))
    K1, K2 = c1.projective_calibration, c2.projective_calibration
    if K1 is not None and K2 is not None:
        np.testing.assert_array_equal(fundamental_from_essential(E, K1, K2, check=False),
                                      fundamental_from_essential(E, K1, K2))


class _Counter:
    """Counts the calls of the checked converters of ``egtviz.geometry._validate``."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.calls: list[str] = []
        for name in ("to_float64", "_refuse_non_finite_or_huge"):
            real = getattr(_validate, name)
            monkeypatch.setattr(_validate, name, self._counted(name, real))

    def _counted(self, name, real):
        def counted(*args, **kwargs):
            self.calls.append(name)
            return real(*args, **kwargs)
        return counted

    def count(self, name: str) -> int:
        return self.calls.count(name)


def test_a_models_drag_update_calls_no_checked_converter(monkeypatch):
    model = SceneModel(default_scene())
    spec = model.scene.camera("cam1")
    R = spec.camera().pose.R
    model.set_camera_pose("cam1", (0.3, -6.0, 1.5), R, drag_id=1)  # warm: the camera models and their caches
    counter = _Counter(monkeypatch)
    model.set_camera_pose("cam1", (0.35, -6.1, 1.5), R, drag_id=1)
    assert model.scene.camera("cam1").position == (0.35, -6.1, 1.5)
    assert counter.calls == []  # the pose was checked by the scene (the spec); the core trusts it
    compute_derived(model.scene, check=True)  # the counter sees the checked path
    assert counter.count("_refuse_non_finite_or_huge") > 10


def test_a_viewer_drag_update_checks_only_the_dragged_pose(monkeypatch):
    from egtviz.bench.viewer import _drag_event
    from egtviz.viewer.server.headless import start_headless

    server, _app, fakes, views = start_headless(default_scene())
    try:
        view = views[0]
        gizmo = view.scene3d.camera_nodes("cam1")["gizmo"]
        start = np.array(gizmo.position, float)
        view.drag.camera_event("cam1", _drag_event(gizmo, start + [0.002, 0.0, 0.0]))  # warm
        before = view.model.scene.camera("cam1").position
        counter = _Counter(monkeypatch)
        view.drag.camera_event("cam1", _drag_event(gizmo, start + [0.004, 0.0, 0.0]))
        assert view.model.scene.camera("cam1").position != before  # the drag was applied and drawn
        # One conversion of each kind: the gizmo's quaternion from the browser (matrix_from_quat_wxyz).
        assert counter.count("to_float64") == 1 and counter.count("_refuse_non_finite_or_huge") == 1
    finally:
        for f in fakes:
            f.close()
        server.stop()


def test_an_overflowing_camera_is_refused_once_named(monkeypatch):
    from egtviz.geometry import pinhole
    from egtviz.scene import SceneError
    from egtviz.scene import derived as derived_module

    real = pinhole.PinholeCamera._project

    def overflowing(self, X):
        proj = real(self, X)
        proj.pixels[0, 0] = np.inf
        return proj

    monkeypatch.setattr(pinhole.PinholeCamera, "_project", overflowing)
    derived_module._camera_block.cache_clear()
    try:
        with pytest.raises(SceneError, match=r"^cannot be drawn: camera 'cam1': image coordinates overflow$"):
            compute_derived(_moved(SCENES["pinhole"], np.random.default_rng(1), 8))
    finally:
        derived_module._camera_block.cache_clear()
