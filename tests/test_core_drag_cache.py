"""A drag reuses the unmoved cameras' derived content, found by identity: no spec is hashed or compared, so the
cost of a drag does not depend on what a spec's hash covers (specs that hash alike once made each lookup compare
up to 64 cached specs, field by field)."""

from __future__ import annotations

import numpy as np

from egtviz.scene import compute_derived, default_scene
from egtviz.scene import derived as derived_module


def _drags(count: int):
    scene = default_scene()
    spec = scene.cameras[0]
    x, y, z = spec.position
    R = spec.pose.R
    return [scene.replace(cameras=(spec.with_world_pose((x + 1e-3 * k, y, z), R),) + scene.cameras[1:])
            for k in range(count)]


def test_a_drag_computes_only_the_moved_camera_and_compares_no_spec(monkeypatch):
    scenes = _drags(80)
    compute_derived(scenes[0])
    spec_type = type(scenes[0].cameras[0])
    calls = {"eq": 0, "hash": 0, "blocks": 0}
    real_eq, real_hash, real_block = spec_type.__eq__, spec_type.__hash__, derived_module._new_camera_block

    def eq(self, other):
        calls["eq"] += 1
        return real_eq(self, other)

    def hash_(self):
        calls["hash"] += 1
        return 0  # every spec alike: a cache keyed on the spec's value would compare every entry

    def block(spec, points, check):
        calls["blocks"] += 1
        return real_block(spec, points, check)

    monkeypatch.setattr(spec_type, "__eq__", eq)
    monkeypatch.setattr(spec_type, "__hash__", hash_)
    monkeypatch.setattr(derived_module, "_new_camera_block", block)
    for scene in scenes[1:]:
        d = compute_derived(scene)
        np.testing.assert_array_equal(d.image_planes["cam1"].points, scene.cameras[0].camera().project(
            scene.points_array()).pixels)
    assert calls == {"eq": 0, "hash": 0, "blocks": len(scenes) - 1}


def test_the_cache_is_bounded_and_clears():
    derived_module._camera_block.cache_clear()
    for scene in _drags(200):
        compute_derived(scene)
    assert len(derived_module._camera_block._entries) <= 64
    derived_module._camera_block.cache_clear()
    assert not derived_module._camera_block._entries
