"""The scene layer through the camera-model interface: every registered kind in one scene, every pair drawn, the
unified camera as a scene camera, mirror switches that keep the image, the read-out of mixed pairs, one source for
the parameter ranges, and no camera kind tested outside the registry."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np
import pytest

from egtviz.geometry import PinholeCamera
from egtviz.geometry.camera_model import CAMERA_MODELS
from egtviz.geometry.unified import UnifiedCamera
from egtviz.scene import (
    FisheyeSpec,
    OutOfRangeError,
    PanoramicSpec,
    PinholeSpec,
    Scene,
    SceneError,
    SceneModel,
    UnifiedSpec,
    compute_derived,
    limits,
    panoramic_scene,
)
from egtviz.scene.derived import ZERO_FRACTION, shown_value
from egtviz.scene.io import scene_from_dict

ROOT = Path(__file__).resolve().parents[1]


def distance_to_polyline(p: np.ndarray, P: np.ndarray) -> float:
    a, b = P[:-1], P[1:]
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


def every_kind_scene() -> Scene:
    """One camera of each registered kind around a cloud of points near the origin."""
    rng = np.random.default_rng(7)
    X = rng.uniform(-1.0, 1.0, (12, 3)) + (0.0, 0.0, 1.0)
    return Scene(
        cameras=(
            PinholeSpec("pin", (-3.0, -8.0, 1.5), (20.0, -3.0, 0.0)),
            PanoramicSpec("hyp", (4.0, -4.0, 0.5), focal_pixels=300.0),
            PanoramicSpec("par", (-5.0, 3.0, 0.5), mirror="parabolic", a=0.1, focal_pixels=1000.0),
            UnifiedSpec("uni", (6.0, 3.0, 1.5), (-120.0, -5.0, 0.0), xi=0.6),
            FisheyeSpec("fish", (-6.0, -2.0, 1.5), (70.0, -5.0, 0.0), field_of_view=170.0),
        ),
        points=tuple(map(tuple, X)),
    )


def test_a_scene_with_every_kind_draws_every_pair():
    scene = every_kind_scene()
    assert {c.model_kind for c in scene.cameras} == set(CAMERA_MODELS)
    for a, b in itertools.permutations(scene.camera_names, 2):
        d = compute_derived(scene.replace(pair=(a, b)))
        both_linear = all(d.cameras[n].projective_calibration is not None for n in (a, b))
        assert (d.pair.F is not None) == both_linear and d.pair.E is not None
        for name in (a, b):
            ip = d.image_planes[name]
            assert ip.in_pair and ip.epipoles, (a, b, name)
            curves = ip.lines if ip.lines is not None else ip.conics
            assert curves is not None and len(curves) == len(scene.points)
            drawn = 0
            for i in np.flatnonzero(ip.visible):
                # The point's own image lies on its epipolar curve (a line segment or the arcs of a conic).
                pieces = [ip.lines[i]] if ip.lines is not None else list(ip.conics[i])
                pieces = [P for P in pieces if np.isfinite(P).all()]
                if pieces:
                    drawn += 1
                    assert min(distance_to_polyline(ip.points[i], P) for P in pieces) < 1.0, (a, b, name, i)
            assert drawn > 0, (a, b, name)


def test_the_unified_camera_at_xi_0_is_the_pinhole_with_its_K():
    # Independent of the sphere formulas: a pin-hole spec with ku f = 500 px and the same pose and principal point.
    pin = PinholeSpec("p", (1.0, -7.0, 1.2), (10.0, -4.0, 3.0), focal_length=0.005, pixels_per_metre=(1e5, 1e5),
                      principal_point=(300.0, 250.0))
    uni = UnifiedSpec("u", pin.position, pin.ypr_deg, xi=0.0, focal_pixels=500.0, principal_point=(300.0, 250.0))
    X = np.random.default_rng(2).uniform(-1.0, 1.0, (20, 3))
    d = compute_derived(Scene(cameras=(pin, uni, PinholeSpec("q", (3.0, -6.0, 1.0), (-20.0, 0.0, 0.0))),
                              points=tuple(map(tuple, X)), pair=("p", "q")))
    np.testing.assert_allclose(d.image_planes["u"].points, d.image_planes["p"].points, atol=1e-9, equal_nan=True)
    d2 = compute_derived(Scene(cameras=(uni, PinholeSpec("q", (3.0, -6.0, 1.0), (-20.0, 0.0, 0.0))),
                               points=tuple(map(tuple, X))))
    assert d2.pair.F is not None and d2.pair.rank == 2  # a pin-hole after all: F between pixels


def test_switching_the_mirror_keeps_the_image_populated():
    model = SceneModel(panoramic_scene())
    name = model.scene.cameras[0].name
    before = model.derived.image_planes[name]
    radius = np.hypot(*(np.vstack(before.horizon) - (320.0, 240.0)).T).max()
    for mirror in ("parabolic", "hyperbolic", "parabolic"):
        model.update_camera(name, mirror=mirror)
        ip = model.derived.image_planes[name]
        assert model.scene.camera(name).model_kind == mirror
        # The horizon images at the radius it had (to rounding), so the points stay spread over the image.
        np.testing.assert_allclose(np.hypot(*(np.vstack(ip.horizon) - (320.0, 240.0)).T).max(), radius, rtol=1e-3)
        # Every point the new mirror sees lands in the image (a parabola's rim, at 2 h, shows less above the
        # horizon than this hyperbola: 5 of the 8 points), and every epipolar conic is drawn.
        assert ip.in_image.sum() == ip.visible.sum() >= (8 if mirror == "hyperbolic" else 5)
        assert ip.conics is not None and all(len(a) > 0 for a in ip.conics)
    # Without the adaptation a = 3 read as the parabola's h would put the rim 6000 px out: every point outside.
    plain = PanoramicSpec("x", mirror="parabolic", a=3.0)
    rim = plain.camera().rim(32)
    assert np.hypot(*(rim - (320.0, 240.0)).T).max() == pytest.approx(6000.0)
    # Given explicitly, the mirror's parameters are taken as they are.
    model.update_camera(name, mirror="hyperbolic", a=2.0, b=1.5)
    assert (model.scene.camera(name).a, model.scene.camera(name).b) == (2.0, 1.5)


@pytest.mark.parametrize("kind", list(CAMERA_MODELS) + ["panoramic"])
def test_add_camera_of_every_registered_kind(kind):
    model = SceneModel(panoramic_scene())
    name = model.add_camera(kind)
    spec = model.scene.camera(name)
    assert spec.model_kind == ("hyperbolic" if kind == "panoramic" else kind)
    assert type(spec.camera()) is type(CAMERA_MODELS[spec.model_kind].build(spec.pose))
    ip = model.derived.image_planes[name]
    assert ip.visible.sum() > 0  # placed where it sees the points
    with pytest.raises(SceneError, match=r"kind: expected one of \['fisheye', 'hyperbolic', 'parabolic', 'pinhole', "
                                         r"'unified'\]"):
        model.add_camera("orthographic")


def test_a_unified_camera_survives_the_file_format_and_its_ranges_are_the_models():
    scene = every_kind_scene()
    again = scene_from_dict(scene.to_dict())
    assert again == scene
    entry = scene.to_dict()["cameras"][3]
    assert entry["kind"] == "unified" and entry["xi"] == 0.6
    with pytest.raises(OutOfRangeError, match=r"camera 'u': xi: expected 0..1, got 1.5"):
        UnifiedSpec("u", xi=1.5)
    with pytest.raises(OutOfRangeError, match=r"focal_pixels: expected 1..1e\+06 px, got 0.5"):
        UnifiedSpec("u", focal_pixels=0.5)


def test_the_ranges_have_one_source_the_models_parameter_specs():
    for kind, name, limit in (("pinhole", "focal_length", limits.FOCAL_LENGTH), ("pinhole", "ku", limits.PIXELS_PER_METRE),
                              ("pinhole", "u0", limits.PRINCIPAL_POINT), ("pinhole", "width", limits.IMAGE_SIZE),
                              ("hyperbolic", "a", limits.MIRROR_PARAMETER), ("parabolic", "h", limits.MIRROR_PARAMETER),
                              ("hyperbolic", "focal_pixels", limits.PANORAMIC_FOCAL_PIXELS),
                              ("unified", "xi", limits.XI), ("unified", "height", limits.IMAGE_SIZE)):
        p = CAMERA_MODELS[kind].parameter(name)
        assert (p.min, p.max, p.unit, p.integer) == (limit.low, limit.high, limit.unit, limit.integer)
    # The documented values (docs/limits.md): 0.1 mm..10 m, 1..8192 px, 0.001..100 m.
    assert (limits.FOCAL_LENGTH.low, limits.FOCAL_LENGTH.high) == (1e-4, 10.0)
    assert (limits.IMAGE_SIZE.low, limits.IMAGE_SIZE.high) == (1, 8192)
    assert (limits.MIRROR_PARAMETER.low, limits.MIRROR_PARAMETER.high) == (1e-3, 100.0)


def test_a_mixed_pair_reads_out_E_between_the_rays_and_no_F():
    scene = every_kind_scene()
    X = scene.points_array()
    for pair in (("pin", "hyp"), ("uni", "par"), ("hyp", "uni")):
        d = compute_derived(scene.replace(pair=pair))
        assert d.pair.F is None and d.pair.rank is None
        c1, c2 = (d.cameras[n] for n in pair)
        # d_i: the rays to X in each camera's model frame, d2^T E d1 = 0 (up to rounding).
        d1 = (X - c1.centre) @ c1.pose.R
        d2 = (X - c2.centre) @ c2.pose.R
        d1 /= np.linalg.norm(d1, axis=1, keepdims=True)
        d2 /= np.linalg.norm(d2, axis=1, keepdims=True)
        assert np.abs(np.einsum("ni,ij,nj->n", d2, d.pair.E, d1)).max() < 1e-12
        assert np.linalg.norm(d.pair.E) == pytest.approx(1.0)


def test_values_below_1e_12_of_the_norm_are_shown_as_0():
    assert ZERO_FRACTION == 1e-12
    assert shown_value(3e-13, 1.0) == 0.0 and shown_value(-3e-13, 1.0) == 0.0
    assert shown_value(2e-12, 1.0) == 2e-12 and shown_value(3e-13, 1e-3) == 3e-13


# ---------------------------------------------------------------------------------------- no kind strings

#: The modules that handle cameras of any kind: none may test a camera's kind or name one.
GENERIC_MODULES = [
    "egtviz/scene/derived.py",
    "egtviz/scene/model.py",
    "egtviz/scene/scene.py",
    "egtviz/scene/limits.py",
    "egtviz/geometry/epipolar_curves.py",
    "egtviz/viewer/workbench/scene3d.py",
    "egtviz/viewer/render/svg.py",
    "egtviz/controllers/workbench_cameras.py",
    "egtviz/controllers/workbench.py",
    "egtviz/viewer/server/viser_adapter.py",
    "egtviz/viewer/workbench/models/pinhole.py",
    "egtviz/viewer/workbench/models/catadioptric.py",
    "egtviz/viewer/workbench/models/unified.py",
    "egtviz/viewer/workbench/models/common.py",
    "egtviz/viewer/workbench/models/__init__.py",
    "egtviz/viewer/workbench/camera_settings.py",
    "egtviz/scene/cameras/__init__.py",
    "egtviz/scene/camera_entry.py",
    "egtviz/scene/io.py",
]
KIND_NAMES = re.compile(r"""["'](pinhole|panoramic|hyperbolic|parabolic|unified|fisheye)["']""")
KIND_TEST = re.compile(r"""(?<!dtype)\.(model_)?kind\s*(==|!=|in\b|not in\b)|isinstance\([^)]*(PinholeCamera|CatadioptricCamera|UnifiedCamera|"""
                       r"""PinholeSpec|PanoramicSpec|UnifiedSpec|FisheyeCamera|FisheyeSpec)""")


def _code_lines(path: Path) -> list[tuple[int, str]]:
    """The lines of a module outside docstrings and comments (a docstring may name a kind as an example)."""
    out, in_doc = [], False
    for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        stripped = line.strip()
        quotes = stripped.count('"""') + stripped.count("'''")
        if in_doc:
            in_doc = quotes % 2 == 0
            continue
        if stripped.startswith(('"""', "'''", 'r"""')):
            in_doc = quotes % 2 == 1
            continue
        out.append((k, line.split("#", 1)[0]))
    return out


@pytest.mark.parametrize("module", GENERIC_MODULES)
def test_no_camera_kind_is_tested_or_named_outside_the_registry(module):
    bad = [f"{module}:{k}: {line.strip()}" for k, line in _code_lines(ROOT / module)
           if KIND_NAMES.search(line) or KIND_TEST.search(line)]
    assert not bad, "\n".join(bad)


def test_the_registries_name_each_kind_once_and_agree():
    from egtviz.scene.camera_entry import MeshBody
    from egtviz.scene.cameras import CAMERA_ENTRIES
    from egtviz.viewer.workbench.models import DRAWINGS, SHORT_LABELS, MeshDrawing, drawing_class

    assert list(DRAWINGS) == list(CAMERA_MODELS) == list(SHORT_LABELS) == list(CAMERA_ENTRIES)
    for kind in CAMERA_MODELS:
        factory = drawing_class(kind)
        if isinstance(DRAWINGS[kind], MeshBody):
            assert factory.func is MeshDrawing  # type: ignore[attr-defined]
        else:
            assert factory.__module__.startswith("egtviz.viewer.workbench.models.")
    # The scene file's kinds: only in the spec classes (file format), each spec building registered models.
    from egtviz.scene.cameras import CAMERA_KINDS, spec_for_model

    assert set(CAMERA_KINDS) == {"pinhole", "panoramic", "unified", "fisheye"}
    assert {spec_for_model(k)[0] for k in CAMERA_MODELS} == set(CAMERA_KINDS.values())
    assert PinholeCamera.kind in CAMERA_MODELS and UnifiedCamera.kind in CAMERA_MODELS


def test_a_file_may_name_the_model_and_old_panoramic_files_still_load():
    scene = every_kind_scene()
    data = scene.to_dict()
    # Written as before: a catadioptric camera is a "panoramic" entry with its mirror (old readers read it).
    assert [c["kind"] for c in data["cameras"]] == ["pinhole", "panoramic", "panoramic", "unified", "fisheye"]
    assert [data["cameras"][k]["mirror"] for k in (1, 2)] == ["hyperbolic", "parabolic"]
    assert scene_from_dict(data) == scene
    # Read by the models' own kinds too: "hyperbolic" and "parabolic" select the mirror.
    for k, kind in ((1, "hyperbolic"), (2, "parabolic")):
        entry = {key: v for key, v in data["cameras"][k].items() if key != "mirror"}
        data["cameras"][k] = {**entry, "kind": kind}
    again = scene_from_dict(data)
    assert again == scene and [c.model_kind for c in again.cameras][1:3] == ["hyperbolic", "parabolic"]
    data["cameras"][2]["mirror"] = "hyperbolic"
    with pytest.raises(SceneError, match=r"cameras\[2\]\.mirror: a parabolic camera has mirror 'parabolic'"):
        scene_from_dict(data)
