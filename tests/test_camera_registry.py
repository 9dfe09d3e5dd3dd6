"""One entry per camera model, and a camera spec that stores its pose.

- A model above the core is its model file (``egtviz/scene/cameras/<module>.py``: spec, fields, drawing) and its
  core file, registered by one line: the fisheye is named nowhere else in the package.
- Every registered model has a complete entry; the scene layer imports and reads a fisheye scene without the viewer.
- A spec holds a ``Pose``; ``position`` and ``ypr_deg`` are views. A gizmo drag places the pose itself (no angles on
  the way), later edits keep it bit for bit, and scene files read and write the same text as before.
"""

from __future__ import annotations

import dataclasses
import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import egtviz
from egtviz.geometry import Pose
from egtviz.geometry.camera_model import CAMERA_MODELS
from egtviz.geometry.poses import matrix_from_quat_wxyz
from egtviz.scene import PinholeSpec, SceneModel, compute_derived, default_scene, panoramic_scene
from egtviz.scene.camera_entry import CameraEntry, MeshBody
from egtviz.scene.cameras import CAMERA_ENTRIES, CAMERA_KINDS, spec_for_model
from egtviz.scene.io import scene_from_bytes, scene_to_bytes

from _subprocesses import run

PACKAGE = Path(egtviz.__file__).parent

# -- one entry per model ------------------------------------------------------------------------------


def _files_naming(word: str) -> dict[str, list[str]]:
    """Every file of the package (any text file) that names ``word`` (any case), with the lines that do."""
    pattern = re.compile(word, re.IGNORECASE)
    found: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*")):
        if not path.is_file() or "__pycache__" in path.parts:
            continue
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        lines = [line.strip() for line in text.splitlines() if pattern.search(line)]
        if lines:
            found[path.relative_to(PACKAGE).as_posix()] = lines
    return found


def test_the_fisheye_is_two_files_and_one_registry_line():
    found = _files_naming("fisheye")
    model_files = {"geometry/fisheye.py", "scene/cameras/fisheye.py"}
    assert model_files <= set(found)
    rest = {path: lines for path, lines in found.items() if path not in model_files}
    assert list(rest) == ["geometry/camera_model.py"], rest
    (line,) = rest["geometry/camera_model.py"]
    assert line.startswith('_register("fisheye",'), line


def test_the_scan_sees_a_name_outside_the_model_files(tmp_path, monkeypatch):
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "camera_model.py").write_text('_register("fisheye", "x", "y")\n', encoding="utf-8")
    (tmp_path / "viewer.py").write_text("from .fisheye import FisheyeDrawing\n", encoding="utf-8")
    monkeypatch.setattr(sys.modules[__name__], "PACKAGE", tmp_path)
    assert set(_files_naming("fisheye")) == {"geometry/camera_model.py", "viewer.py"}


@pytest.mark.parametrize("kind", list(CAMERA_MODELS))
def test_every_registered_model_has_a_complete_entry(kind):
    entry = CAMERA_ENTRIES[kind]
    assert isinstance(entry, CameraEntry) and entry.model == kind and entry.info is CAMERA_MODELS[kind]
    assert entry.spec in CAMERA_KINDS.values() and spec_for_model(kind) == (entry.spec, dict(entry.selection))
    spec = entry.spec(name="c", **entry.selection)
    assert spec.model_kind == kind
    # The GUI fields show every parameter exactly once, each number within the parameter's range.
    shown = [p for field in entry.camera_fields() for p in field.parameters]
    assert sorted(shown) == sorted(p.name for p in entry.parameters)
    specs = {p.name: p for p in entry.parameters}
    values = spec.model_values()
    for field in entry.camera_fields():
        for number, limit in zip(field.shown(values), field.ranges(specs)):
            assert limit.lo - 1e-9 * abs(limit.lo) <= number <= limit.hi + 1e-9 * abs(limit.hi), (kind, field.key)
    assert entry.short_label and (isinstance(entry.drawing, MeshBody) or ":" in entry.drawing)


def test_a_mesh_body_is_triangles_over_its_vertices():
    bodies = [e.drawing for e in CAMERA_ENTRIES.values() if isinstance(e.drawing, MeshBody)]
    assert bodies  # the fisheye's lens
    for entry in CAMERA_ENTRIES.values():
        if isinstance(entry.drawing, MeshBody):
            vertices, faces = entry.drawing.mesh({p.name: p.default for p in entry.parameters})
            assert vertices.ndim == 2 and vertices.shape[1] == 3 and np.isfinite(vertices).all()
            assert faces.ndim == 2 and faces.shape[1] == 3 and faces.min() == 0 and faces.max() == len(vertices) - 1


def test_the_scene_layer_reads_a_fisheye_scene_without_the_viewer():
    scene = {"format": "egtviz-scene", "version": 1, "points": [[0, 0, 1], [1, 0, 1.5], [0, 1, 0.5]],
             "cameras": [{"kind": "pinhole", "name": "cam1", "position": [-3, -8, 1.5], "ypr_deg": [20, -3, 0]},
                         {"kind": "fisheye", "name": "fish1", "position": [4, -6, 1.2], "ypr_deg": [-35, -4, 0],
                          "field_of_view": 170}]}
    code = (
        "import json, sys\n"
        "from egtviz.scene import scene_from_bytes, compute_derived\n"
        f"scene = scene_from_bytes(json.dumps({scene!r}).encode(), 'x')\n"
        "d = compute_derived(scene)\n"
        "assert d.image_planes['fish1'].conics and d.image_planes['fish1'].rim is not None\n"
        "print(sorted(m for m in sys.modules if m.startswith(('egtviz.viewer', 'viser', 'trimesh'))))\n"
    )
    out = run([sys.executable, "-c", code], "a Python that reads a fisheye scene to exit", check=True)
    assert out.stdout.strip() == "[]"


# -- a pose that stays a pose -------------------------------------------------------------------------


def _gizmo_rotation(rng: np.random.Generator) -> np.ndarray:
    """The rotation of a quaternion as a gizmo sends it (unit, float64)."""
    q = rng.normal(size=4)
    return matrix_from_quat_wxyz(q / np.linalg.norm(q))


def test_a_spec_stores_its_pose_and_shows_position_and_angles_as_views():
    names = [f.name for f in dataclasses.fields(PinholeSpec)]
    assert "pose" in names and "position" not in names and "ypr_deg" not in names
    assert PinholeSpec.field_names()[:3] == ("name", "position", "ypr_deg")
    spec = PinholeSpec("c", (1.0, 2.0, 3.0), (10.0, -20.0, 5.0))
    assert spec.position == (1.0, 2.0, 3.0) and spec.ypr_deg == (10.0, -20.0, 5.0)  # as given
    again = PinholeSpec("c", pose=spec.pose)
    assert again == spec and again.pose is spec.pose
    np.testing.assert_allclose(again.ypr_deg, (10.0, -20.0, 5.0), atol=1e-12)  # computed from the rotation


@pytest.mark.parametrize("make", [default_scene, panoramic_scene])
def test_a_drag_places_the_pose_itself_and_computes_no_angles(make, monkeypatch):
    model = SceneModel(make())
    name = model.scene.cameras[0].name
    cls = type(model.scene.camera(name))

    def refuse(*args, **kwargs):
        raise AssertionError("a drag step went through yaw, pitch, roll")

    monkeypatch.setattr(cls, "ypr_from_world_rotation", staticmethod(refuse))
    monkeypatch.setattr(cls, "rotation_from_ypr", staticmethod(refuse), raising=False)
    rng = np.random.default_rng(3)
    for _ in range(5):
        R = _gizmo_rotation(rng)
        position = tuple(rng.uniform(-5.0, 5.0, 3).tolist())
        model.set_camera_pose(name, position, R, drag_id=1)
        spec = model.scene.camera(name)
        np.testing.assert_array_equal(spec.pose.R, R)
        assert spec.position == position
        wxyz, centre = model.derived.poses[name]
        np.testing.assert_allclose(matrix_from_quat_wxyz(wxyz), R, atol=1e-15)


def test_edits_after_a_drag_keep_the_dragged_pose_bit_for_bit():
    model = SceneModel(default_scene())
    R = _gizmo_rotation(np.random.default_rng(5))
    model.set_camera_pose("cam1", (0.5, -7.0, 1.25), R)
    model.update_camera("cam1", focal_length=0.01)
    np.testing.assert_array_equal(model.scene.camera("cam1").pose.R, R)
    model.update_camera("cam1", position=(1.0, -7.0, 1.25))
    spec = model.scene.camera("cam1")
    np.testing.assert_array_equal(spec.pose.R, R)
    np.testing.assert_array_equal(spec.pose.t, (1.0, -7.0, 1.25))
    model.update_camera("cam1", name="left")
    np.testing.assert_array_equal(model.scene.camera("left").pose.R, R)


def test_a_typed_angle_turns_the_camera_and_is_shown_as_typed():
    model = SceneModel(default_scene())
    model.update_camera("cam1", ypr_deg=(17.35, -3.41, 0.0))
    spec = model.scene.camera("cam1")
    assert spec.ypr_deg == (17.35, -3.41, 0.0)
    np.testing.assert_allclose(spec.pose.R, PinholeSpec("x", ypr_deg=(17.35, -3.41, 0.0)).pose.R, atol=0)
    model.update_camera("cam1", focal_length=0.012)  # another field: the angles stay as typed
    assert model.scene.camera("cam1").ypr_deg == (17.35, -3.41, 0.0)


def test_a_scene_file_reads_and_writes_the_same_text():
    text = json.dumps({
        "format": "egtviz-scene", "version": 1, "points": [[0.0, 0.0, 1.0]],
        "cameras": [
            {"kind": "pinhole", "name": "cam1", "position": [-9.0, -6.0, 1.5], "ypr_deg": [17.35, -3.41, 0.0]},
            {"kind": "panoramic", "name": "pano1", "position": [3.5, -7.5, 2.5], "ypr_deg": [-25.017, -10.273, 0.1],
             "mirror": "parabolic", "a": 0.1},
            {"kind": "unified", "name": "uni1", "position": [0.1, 0.2, 0.3], "ypr_deg": [0.1, 0.2, 0.3]},
        ]})
    scene = scene_from_bytes(text.encode(), "x")
    written = scene_to_bytes(scene)
    assert scene_to_bytes(scene_from_bytes(written, "x")) == written
    cameras = json.loads(written)["cameras"]
    assert [c["ypr_deg"] for c in cameras] == [[17.35, -3.41, 0.0], [-25.017, -10.273, 0.1], [0.1, 0.2, 0.3]]
    assert [list(c)[:4] for c in cameras] == [["kind", "name", "position", "ypr_deg"]] * 3


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(sorted(CAMERA_KINDS)))
def test_a_dragged_pose_saved_and_read_back_is_the_same_to_rounding(seed, kind):
    rng = np.random.default_rng(seed)
    spec = CAMERA_KINDS[kind](name="c")
    R = Rotation.random(random_state=rng).as_matrix()
    dragged = spec.with_world_pose(tuple(rng.uniform(-50.0, 50.0, 3).tolist()), R)
    model = SceneModel(default_scene())
    model.load_scene(model.scene.replace(cameras=(dragged, *model.scene.cameras[1:]),
                                         pair=(dragged.name, model.scene.cameras[1].name)))
    back = scene_from_bytes(scene_to_bytes(model.scene), "x").camera("c")
    np.testing.assert_allclose(back.pose.R, dragged.pose.R, atol=1e-12)
    np.testing.assert_array_equal(back.pose.t, dragged.pose.t)
    before, after = compute_derived(model.scene), compute_derived(scene_from_bytes(scene_to_bytes(model.scene), "x"))
    for name in model.scene.camera_names:
        a, b = before.image_planes[name].points, after.image_planes[name].points
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-7)


def test_a_pose_argument_must_be_a_pose():
    from egtviz.scene import SceneError

    with pytest.raises(SceneError, match=r"camera 'c': pose: expected a Pose"):
        PinholeSpec("c", pose=np.eye(4))  # type: ignore[arg-type]
    with pytest.raises(SceneError, match=r"position"):
        PinholeSpec("c", pose=Pose(np.eye(3), (1e9, 0.0, 0.0)))
