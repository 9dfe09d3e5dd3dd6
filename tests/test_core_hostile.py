"""Hostile input to the numeric core: every public function and class refuses bad values by name, and
quantities defined up to scale give the same result at any magnitude.

The public surface is enumerated from the modules themselves (every public name defined there, every
public method of every public class), and each must appear in ``CASES`` or in ``NO_NUMERIC_INPUT``: a new
function without a hostile-input case fails ``test_every_public_callable_has_a_case``.
"""

from __future__ import annotations

import inspect
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _hostile import BAD_VALUES, all_bad_values, assert_rejects
from egtviz.geometry import DegenerateConfigurationError, GeometryError
from egtviz.geometry import _validate, catadioptric, epipolar, homogeneous, mirrors, panoramic_epipolar, pinhole, poses
from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry.epipolar import epipolar_pair
from egtviz.geometry.mirrors import HyperbolicMirror, ParabolicMirror
from egtviz.geometry.pinhole import Intrinsics, PinholeCamera
from egtviz.geometry.poses import Pose

MODULES = [homogeneous, poses, pinhole, catadioptric, mirrors, epipolar, panoramic_epipolar]

# ----------------------------------------------------------------------------------------------- fixtures

CAM1 = PinholeCamera(Pose.from_egt(np.eye(3), [0.0, -5.0, 0.0]))
CAM2 = PinholeCamera(Pose.from_egt(poses.roty(0.3), [1.0, -5.0, 0.2]))
X_PIN = np.array([[0.1, 0.2, 0.3], [-0.4, 0.5, 0.1], [0.2, -0.3, -0.2]])
F = epipolar_pair(CAM1, CAM2).F
E = epipolar_pair(CAM1, CAM2).E
K = CAM1.K
PIX = np.array([[300.0, 200.0], [350.0, 260.0]])
PAN1 = CatadioptricCamera()
PAN2 = CatadioptricCamera(Pose(np.eye(3), [3.0, 1.0, 0.0]), ParabolicMirror(1.0))
X_PAN = np.array([[4.0, 1.0, -2.0], [-3.0, 2.0, -3.0]])
DIRS = np.array([[1.0, 0.2, -0.5], [0.3, -1.0, -0.4]])
LINES = np.array([[1.0, -1.0, 10.0], [0.2, 1.0, -300.0]])
HOMOG = np.array([[3.0, 4.0, 1.0], [1.0, 2.0, 0.0]])
Q = np.array([0.9, 0.1, -0.3, 0.2])
HYP = HyperbolicMirror(3.0, 1.0)
PAR = ParabolicMirror(1.0)


@dataclass(frozen=True)
class Case:
    """A public callable with valid keyword arguments; ``objects`` are non-numeric arguments (cameras, poses)."""

    label: str
    func: Callable[..., Any]
    kwargs: dict[str, Any]
    objects: tuple[str, ...] = ()
    any_shape: tuple[str, ...] = field(default=())
    """Arguments that accept arrays of any shape (element-wise functions): wrong shapes do not apply."""
    none_ok: tuple[str, ...] = field(default=())
    """Arguments for which ``None`` is a valid value (it means "the default")."""
    nan_rows_ok: tuple[str, ...] = field(default=())
    """Arguments whose NaN rows are valid and documented (plane normals: a point on a baseline has no plane)."""


CASES = [
    # homogeneous
    Case("homogeneous", homogeneous.homogeneous, {"points": PIX}),
    Case("normalize_homogeneous", homogeneous.normalize_homogeneous, {"v": HOMOG}),
    Case("is_at_infinity", homogeneous.is_at_infinity, {"v": HOMOG}),
    Case("normalize_lines", homogeneous.normalize_lines, {"lines": LINES}),
    Case("clip_lines_to_rect", homogeneous.clip_lines_to_rect, {"lines": LINES, "width": 640, "height": 480}),
    # poses
    Case("rotx", poses.rotx, {"angle": 0.3}),
    Case("roty", poses.roty, {"angle": 0.3}),
    Case("rotz", poses.rotz, {"angle": 0.3}),
    Case("skew", poses.skew, {"v": [1.0, 2.0, 3.0]}),
    Case("Pose", Pose, {"R": poses.rotz(0.2), "t": [1.0, 2.0, 3.0]}),
    Case("Pose.from_matrix", Pose.from_matrix, {"H": Pose(poses.rotz(0.2), [1.0, 2.0, 3.0]).matrix}),
    Case("Pose.from_egt", Pose.from_egt, {"R": poses.roty(0.2), "t": [1.0, 2.0, 3.0]}),
    Case("Pose.to_local", CAM1.pose.to_local, {"X_world": X_PIN}),
    Case("Pose.to_world", CAM1.pose.to_world, {"X_local": X_PIN}),
    Case("Pose.direction_to_world", CAM1.pose.direction_to_world, {"d_local": DIRS}),
    Case("Pose.compose", CAM1.pose.compose, {"other": CAM2.pose}, objects=("other",)),
    Case("Pose.inverse", CAM1.pose.inverse, {}),
    Case("Pose.with_position", CAM1.pose.with_position, {"t": [1.0, 2.0, 3.0]}),
    Case("Pose.with_rotation", CAM1.pose.with_rotation, {"R": poses.rotz(0.1)}),
    Case("quat_wxyz_from_matrix", poses.quat_wxyz_from_matrix, {"R": poses.rotz(0.4)}),
    Case("matrix_from_quat_wxyz", poses.matrix_from_quat_wxyz, {"q": Q}),
    Case("egt_rotation_from_ypr", poses.egt_rotation_from_ypr, {"yaw": 0.1, "pitch": 0.2, "roll": 0.3}),
    Case("ypr_from_egt_rotation", poses.ypr_from_egt_rotation, {"R": poses.rotz(0.4)}),
    Case("look_at", poses.look_at, {"eye": [0.0, -5.0, 1.0], "target": [0.0, 0.0, 0.0], "up": [0.0, 0.0, 1.0]}),
    # pinhole
    Case("Intrinsics", Intrinsics, {"focal_length": 0.008, "pixels_per_metre": (1e5, 1e5),
                                    "principal_point": (320.0, 240.0), "skew": 0.0, "width": 640, "height": 480}),
    Case("Intrinsics.from_K", Intrinsics.from_K, {"K": K, "width": 640, "height": 480, "focal_length": 0.008}),
    Case("PinholeCamera", PinholeCamera, {"pose": CAM1.pose, "intrinsics": CAM1.intrinsics},
         objects=("pose", "intrinsics")),
    Case("PinholeCamera.moved", CAM1.moved, {"pose": CAM2.pose}, objects=("pose",)),
    Case("PinholeCamera.with_intrinsics", CAM1.with_intrinsics, {"intrinsics": CAM2.intrinsics},
         objects=("intrinsics",)),
    Case("PinholeCamera.project", CAM1.project, {"X_world": X_PIN}),
    Case("PinholeCamera.back_project", CAM1.back_project, {"pixels": PIX}),
    Case("PinholeCamera.from_parameters", PinholeCamera.from_parameters, {"pose": CAM1.pose, "focal_length": 0.01,
                                                                          "u0": 300.0}, objects=("pose",)),
    Case("PinholeCamera.parameters", CAM1.parameters, {}),
    Case("PinholeCamera.light_paths", CAM1.light_paths, {"X_world": X_PIN}),
    Case("PinholeCamera.baseline_images", CAM1.baseline_images, {"direction_world": [1.0, 0.2, 0.3]}),
    Case("PinholeCamera.plane_image_lines", CAM1.plane_image_lines, {"normals_world": DIRS},
         nan_rows_ok=("normals_world",)),
    Case("PinholeCamera.plane_image_conics", CAM1.plane_image_conics, {"normals_world": DIRS},
         nan_rows_ok=("normals_world",)),
    Case("PinholeCamera.plane_image_arcs", CAM1.plane_image_arcs, {"normals_world": DIRS, "n_samples": 8},
         nan_rows_ok=("normals_world",)),
    Case("PinholeCamera.rim", CAM1.rim, {"n": 8}),
    Case("PinholeCamera.frustum_corners", CAM1.frustum_corners, {"depth": 1.0}),
    Case("PinholeCamera.image_to_world", CAM1.image_to_world, {"pixels": PIX, "depth": 1.0}),
    # mirrors
    Case("HyperbolicMirror", HyperbolicMirror, {"a": 3.0, "b": 1.0, "rim_radius": 2.0}, none_ok=("rim_radius",)),
    Case("HyperbolicMirror.profile_z", HYP.profile_z, {"r": [0.0, 0.5, 1.0]}, any_shape=("r",)),
    Case("HyperbolicMirror.implicit", HYP.implicit, {"X": X_PAN}),
    Case("HyperbolicMirror.intersect", HYP.intersect, {"directions": DIRS, "rim_tol": 1e-12}),
    Case("HyperbolicMirror.surface", HYP.surface, {"n_radial": 4, "n_angular": 8}),
    Case("HyperbolicMirror.rim_points", HYP.rim_points, {"n": 16}),
    Case("ParabolicMirror", ParabolicMirror, {"h": 1.0, "rim_radius": 2.0}, none_ok=("rim_radius",)),
    Case("ParabolicMirror.profile_z", PAR.profile_z, {"r": [0.0, 0.5, 1.0]}, any_shape=("r",)),
    Case("ParabolicMirror.implicit", PAR.implicit, {"X": X_PAN}),
    Case("ParabolicMirror.intersect", PAR.intersect, {"directions": DIRS, "rim_tol": 1e-12}),
    Case("ParabolicMirror.surface", PAR.surface, {"n_radial": 4, "n_angular": 8}),
    Case("ParabolicMirror.rim_points", PAR.rim_points, {"n": 16}),
    # catadioptric
    Case("CatadioptricCamera", CatadioptricCamera,
         {"pose": PAN1.pose, "mirror": HYP, "K": PAN1.K, "width": 640, "height": 480}, objects=("pose", "mirror")),
    Case("CatadioptricCamera.moved", PAN1.moved, {"pose": PAN2.pose}, objects=("pose",)),
    Case("CatadioptricCamera.project", PAN1.project, {"X_world": X_PAN}),
    Case("CatadioptricCamera.project_directions", PAN1.project_directions, {"d_mirror": DIRS}),
    Case("CatadioptricCamera.project_unified", PAN1.project_unified, {"X_world": X_PAN}),
    Case("CatadioptricCamera.back_project", PAN1.back_project, {"pixels": PIX}),
    Case("CatadioptricCamera.from_parameters", PAN1.from_parameters, {"pose": PAN2.pose, "a": 2.0},
         objects=("pose",)),
    Case("CatadioptricKind", catadioptric.CatadioptricKind, {"kind": "hyperbolic", "PARAMETERS": ()},
         objects=("kind", "PARAMETERS")),
    Case("CatadioptricKind.from_parameters", catadioptric.PARABOLIC.from_parameters, {"pose": PAN2.pose, "h": 2.0},
         objects=("pose",)),
    Case("CatadioptricCamera.parameters", PAN1.parameters, {}),
    Case("CatadioptricCamera.light_paths", PAN1.light_paths, {"X_world": X_PAN}),
    Case("CatadioptricCamera.baseline_images", PAN1.baseline_images, {"direction_world": [1.0, 0.2, 0.3]}),
    Case("CatadioptricCamera.plane_image_lines", PAN1.plane_image_lines, {"normals_world": DIRS},
         nan_rows_ok=("normals_world",)),
    Case("CatadioptricCamera.plane_image_conics", PAN1.plane_image_conics, {"normals_world": DIRS},
         nan_rows_ok=("normals_world",)),
    Case("CatadioptricCamera.plane_image_arcs", PAN1.plane_image_arcs, {"normals_world": DIRS, "n_samples": 8},
         nan_rows_ok=("normals_world",)),
    Case("CatadioptricCamera.rim", PAN1.rim, {"n": 8}),
    Case("CatadioptricCamera.rim_image", PAN1.rim_image, {"n": 16}),
    # epipolar
    Case("relative_pose", epipolar.relative_pose, {"pose1": CAM1.pose, "pose2": CAM2.pose},
         objects=("pose1", "pose2")),
    Case("check_distinct_centres", epipolar.check_distinct_centres, {"c1": [0.0, 0.0, 0.0], "c2": [1.0, 0.0, 0.0]}),
    Case("unit_frobenius", epipolar.unit_frobenius, {"M": F}),
    Case("essential_from_poses", epipolar.essential_from_poses, {"pose1": CAM1.pose, "pose2": CAM2.pose},
         objects=("pose1", "pose2")),
    Case("essential_from_fundamental", epipolar.essential_from_fundamental, {"F": F, "K1": K, "K2": K}),
    Case("fundamental_from_essential", epipolar.fundamental_from_essential, {"E": E, "K1": K, "K2": K}),
    Case("epipolar_pair", epipolar.epipolar_pair, {"cam1": CAM1, "cam2": CAM2}, objects=("cam1", "cam2")),
    Case("epipole_of_centre", epipolar.epipole_of_centre, {"camera": CAM1, "other_centre": CAM2.center},
         objects=("camera",)),
    Case("lines_of_planes", epipolar.lines_of_planes, {"camera": CAM1, "normals_world": DIRS}, objects=("camera",)),
    Case("fundamental_from_cameras", epipolar.fundamental_from_cameras, {"cam1": CAM1, "cam2": CAM2},
         objects=("cam1", "cam2")),
    Case("epipoles_from_fundamental", epipolar.epipoles_from_fundamental, {"F": F}),
    Case("epipolar_lines", epipolar.epipolar_lines, {"F": F, "m1": PIX}),
    Case("epipolar_lines_in_first", epipolar.epipolar_lines_in_first, {"F": F, "m2": PIX}),
    Case("epipolar_constraint", epipolar.epipolar_constraint, {"F": F, "m1": PIX, "m2": PIX}),
    Case("epipolar_planes", epipolar.epipolar_planes, {"c1": CAM1.center, "c2": CAM2.center, "X_world": X_PIN}),
    Case("clipped_epipolar_lines", epipolar.clipped_epipolar_lines, {"lines": LINES, "width": 640, "height": 480}),
    # panoramic epipolar
    Case("panoramic_essential", panoramic_epipolar.panoramic_essential, {"cam1": PAN1, "cam2": PAN2},
         objects=("cam1", "cam2")),
    Case("panoramic_epipoles", panoramic_epipolar.panoramic_epipoles, {"cam1": PAN1, "cam2": PAN2},
         objects=("cam1", "cam2")),
    Case("conic_from_plane", panoramic_epipolar.conic_from_plane, {"camera": PAN1, "n_mirror": DIRS},
         objects=("camera",)),
    Case("epipolar_conics", panoramic_epipolar.epipolar_conics, {"cam1": PAN1, "cam2": PAN2, "X_world": X_PAN},
         objects=("cam1", "cam2")),
    Case("biconic_normals", panoramic_epipolar.biconic_normals, {"d_current": DIRS, "d_desired": DIRS[::-1]}),
    Case("biconic", panoramic_epipolar.biconic, {"camera": PAN1, "d_current": DIRS, "d_desired": DIRS[::-1]},
         objects=("camera",)),
    Case("sample_biconics", panoramic_epipolar.sample_biconics,
         {"camera": PAN1, "d_current": DIRS, "d_desired": DIRS[::-1], "n": 16}, objects=("camera",)),
    Case("sample_plane_conic", panoramic_epipolar.sample_plane_conic, {"camera": PAN1, "n_mirror": DIRS[0], "n": 16},
         objects=("camera",)),
    Case("sample_plane_conics", panoramic_epipolar.sample_plane_conics, {"camera": PAN1, "n_mirror": DIRS, "n": 16},
         objects=("camera",)),
    Case("sample_epipolar_conics", panoramic_epipolar.sample_epipolar_conics,
         {"cam1": PAN1, "cam2": PAN2, "X_world": X_PAN, "n": 16},
         objects=("cam1", "cam2")),
]

#: Public callables that take no numeric input from a caller: result records built by the core, type
#: aliases. Each with the reason. (Constants are not callables and are not enumerated.)
NO_NUMERIC_INPUT = {
    "Mirror": "type alias of the two mirror classes",
    "MirrorHit": "result record (a NamedTuple) returned by intersect",
    "PinholeProjection": "result record returned by PinholeCamera.project",
    "PanoramicProjection": "result record returned by CatadioptricCamera.project",
    "EpipolarPair": "result record returned by epipolar_pair",
    "PanoramicEpipoles": "result record returned by panoramic_epipoles",
}


def _public_surface() -> set[str]:
    """Every public function, class and public method defined in the modules (``Class.method``)."""
    names: set[str] = set()
    for module in MODULES:
        for name, obj in vars(module).items():
            if name.startswith("_") or getattr(obj, "__module__", module.__name__) != module.__name__:
                continue
            if not callable(obj) or inspect.ismodule(obj):
                continue  # constants
            names.add(name)
            if inspect.isclass(obj) and name not in NO_NUMERIC_INPUT:
                for attr, member in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    if isinstance(member, classmethod | staticmethod) or inspect.isfunction(member):
                        names.add(f"{name}.{attr}")
    return names


def test_every_public_callable_has_a_case():
    covered = {c.label for c in CASES} | set(NO_NUMERIC_INPUT)
    missing = sorted(_public_surface() - covered)
    assert not missing, f"public names without a hostile-input case: {missing}"


def test_cases_run_on_their_valid_arguments():
    for case in CASES:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            case.func(**case.kwargs)


def _numeric_args() -> list[tuple[str, str]]:
    return [(c.label, arg) for c in CASES for arg in c.kwargs if arg not in c.objects]


def _object_args() -> list[tuple[str, str]]:
    return [(c.label, arg) for c in CASES for arg in c.objects]


_BY_LABEL = {c.label: c for c in CASES}


@pytest.mark.parametrize(("label", "arg"), _numeric_args())
def test_bad_numeric_values_are_refused_by_name(label, arg):
    case = _BY_LABEL[label]
    for bad_label, bad in all_bad_values(case.kwargs[arg]):
        if bad is None and arg in case.none_ok:
            continue
        if bad_label == "NaN entry" and arg in case.nan_rows_ok:
            continue
        if arg in case.any_shape and (bad_label.startswith("shape") or bad_label == "extra axis"):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert_rejects(case.func, case.kwargs, arg, bad, label=bad_label)


@pytest.mark.parametrize(("label", "arg"), _object_args())
def test_bad_objects_are_refused_by_name(label, arg):
    case = _BY_LABEL[label]
    for bad_label, bad in [*BAD_VALUES, ("a number", 1.0), ("an array", np.eye(3))]:
        assert_rejects(case.func, case.kwargs, arg, bad, label=bad_label)


def test_a_huge_bad_value_is_quoted_by_a_short_prefix():
    with pytest.raises(GeometryError) as info:
        PAN1.project(np.full((100_000, 3), "x"))
    assert "X_world" in str(info.value) and len(str(info.value)) < 300
    with pytest.raises(GeometryError) as info:
        poses.rotx(10**5000)
    assert "angle" in str(info.value) and len(str(info.value)) < 300


def test_fractional_counts_and_sizes_are_refused():
    with pytest.raises(GeometryError, match="n: "):
        HYP.rim_points(2.5)
    with pytest.raises(GeometryError, match="width: "):
        Intrinsics(width=640.5)
    with pytest.raises(GeometryError, match="height: "):
        CatadioptricCamera(height=480.5)


# ------------------------------------------------------------------------------------ calibration matrices


@pytest.mark.parametrize("entry", [(1, 0), (2, 0), (2, 1)])
def test_a_calibration_with_a_lower_triangle_is_refused_everywhere(entry):
    bad = K.copy()
    bad[entry] = 50.0 if entry == (1, 0) else 1e-3
    with pytest.raises(GeometryError, match=r"K: expected an upper-triangular"):
        Intrinsics.from_K(bad)
    with pytest.raises(GeometryError, match=r"K: expected an upper-triangular"):
        CatadioptricCamera(K=bad)
    with pytest.raises(GeometryError, match=r"K1: expected an upper-triangular"):
        epipolar.essential_from_fundamental(F, bad, K)
    with pytest.raises(GeometryError, match=r"K2: expected an upper-triangular"):
        epipolar.fundamental_from_essential(E, K, bad)


def test_a_calibration_is_read_up_to_scale_and_rounding_below_the_diagonal_is_cleared():
    # K scaled by 2 (K[2,2] = 2) is the same calibration; an entry 1e-14 below the diagonal is rounding.
    scaled = 2.0 * K
    scaled[1, 0] = 1e-14
    cam = CatadioptricCamera(K=scaled)
    np.testing.assert_array_equal(cam.K, np.triu(cam.K))
    np.testing.assert_allclose(cam.K, K, rtol=1e-15)
    np.testing.assert_allclose(Intrinsics.from_K(scaled, focal_length=0.008).K, K, rtol=1e-12)


# --------------------------------------------------------------------------------- magnitudes, up to scale

powers = st.integers(min_value=-200, max_value=200)


def _quiet(func: Callable[[], Any]) -> Any:
    """Run ``func`` with every warning an error (numpy's default: overflow, division by zero and invalid
    operations warn, underflow to zero is silent and harmless)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(divide="warn", over="warn", invalid="warn", under="ignore"):
            return func()


@settings(max_examples=80)
@given(k=powers)
def test_quantities_defined_up_to_scale_give_the_same_result_at_any_magnitude(k):
    s = 10.0**k
    same = dict(rtol=1e-12, atol=1e-14)

    def check(f, pair):
        scaled, plain = pair
        a, b = _quiet(lambda: f(*scaled)), _quiet(lambda: f(*plain))
        for x, y in zip(a if isinstance(a, tuple) else (a,), b if isinstance(b, tuple) else (b,)):
            np.testing.assert_allclose(x, y, **same)

    check(epipolar.epipoles_from_fundamental, ((F * s,), (F,)))
    check(epipolar.unit_frobenius, ((F * s,), (F,)))
    check(epipolar.essential_from_fundamental, ((F * s, K, K), (F, K, K)))
    check(epipolar.fundamental_from_essential, ((E * s, K * s, K), (E, K, K)))
    check(epipolar.epipolar_lines, ((F * s, PIX), (F, PIX)))
    check(epipolar.epipolar_lines_in_first, ((F * s, PIX), (F, PIX)))
    check(epipolar.epipolar_constraint, ((F * s, PIX, PIX + 1), (F, PIX, PIX + 1)))
    check(homogeneous.normalize_homogeneous, ((HOMOG * s,), (HOMOG,)))
    check(homogeneous.is_at_infinity, ((HOMOG * s,), (HOMOG,)))
    check(homogeneous.normalize_lines, ((LINES * s,), (LINES,)))
    check(homogeneous.clip_lines_to_rect, ((LINES * s, 640, 480), (LINES, 640, 480)))
    check(poses.matrix_from_quat_wxyz, ((Q * s,), (Q,)))
    check(epipolar.lines_of_planes, ((CAM1, DIRS * s), (CAM1, DIRS)))
    check(panoramic_epipolar.conic_from_plane, ((PAN1, DIRS * s), (PAN1, DIRS)))
    check(panoramic_epipolar.biconic, ((PAN1, DIRS * s, DIRS[::-1]), (PAN1, DIRS, DIRS[::-1])))
    check(lambda d: PAN1.project_directions(d).pixels, ((DIRS * s,), (DIRS,)))
    check(lambda d: HYP.intersect(d).hit, ((DIRS * s,), (DIRS,)))
    # X_h = lam d: the ray parameter of a direction scaled by s is 1/s times that of the direction.
    np.testing.assert_allclose(_quiet(lambda: PAR.intersect(DIRS * s).lam) * s, PAR.intersect(DIRS).lam, **same)
    np.testing.assert_allclose(_quiet(lambda: HYP.intersect(DIRS * s).lam) * s, HYP.intersect(DIRS).lam, **same)
    a = _quiet(lambda: panoramic_epipolar.sample_plane_conic(PAN1, DIRS[0] * s, 16))
    b = panoramic_epipolar.sample_plane_conic(PAN1, DIRS[0], 16)
    assert len(a) == len(b) and all(np.allclose(x, y, rtol=1e-12) for x, y in zip(a, b))


def test_all_zero_quantities_defined_up_to_scale_are_refused():
    for call, name in [
        (lambda: epipolar.epipoles_from_fundamental(np.zeros((3, 3))), "F"),
        (lambda: epipolar.unit_frobenius(np.zeros((3, 3))), "M"),
        (lambda: epipolar.epipolar_lines(np.zeros((3, 3)), PIX), "F"),
        (lambda: epipolar.fundamental_from_essential(np.zeros((3, 3)), K, K), "E"),
        (lambda: poses.matrix_from_quat_wxyz(np.zeros(4)), "q"),
        (lambda: homogeneous.normalize_homogeneous(np.zeros(3)), "v"),
        (lambda: homogeneous.normalize_lines([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]), "lines"),
        (lambda: panoramic_epipolar.sample_plane_conic(PAN1, np.zeros(3)), "n_mirror"),
    ]:
        with pytest.raises(GeometryError, match=f"{name}: "):
            call()


@settings(max_examples=60)
@given(k=st.integers(min_value=-120, max_value=120), seed=st.integers(0, 2**31))
def test_large_or_small_worlds_give_the_scaled_result_or_a_clear_error(k, seed):
    """A whole scene scaled by 10^k (positions, mirror sizes) images to the same pixels; beyond what the core
    can compute with, a GeometryError names the argument. Never another exception, never a warning."""
    rng = np.random.default_rng(seed)
    s = 10.0**k
    X = rng.uniform(-1.0, 1.0, size=(5, 3)) + [0.0, 0.0, 4.0]
    pin = PinholeCamera(Pose(poses.rotz(0.1), [0.1, -0.2, 0.0]))
    try:
        big = _quiet(lambda: PinholeCamera(Pose(pin.pose.R, pin.pose.t * s)).project(X * s))
    except GeometryError as exc:
        assert str(exc).split(":")[0] in ("t", "X_world"), str(exc)
        assert abs(k) > 90  # within 1e90 every coordinate here is computable
    else:
        np.testing.assert_allclose(big.pixels, pin.project(X).pixels, rtol=1e-9)
    # F depends on the baseline's direction only; centres closer than 1e-9 scene units (the scale of a unit
    # scene) coincide by definition and are refused as degenerate.
    other = PinholeCamera(Pose(poses.roty(0.2), [1.0, 0.3, -0.1]))
    try:
        F_big = _quiet(lambda: epipolar.epipolar_pair(PinholeCamera(Pose(pin.pose.R, pin.pose.t * s)),
                                                      PinholeCamera(Pose(other.pose.R, other.pose.t * s))).F)
    except DegenerateConfigurationError as exc:
        assert "centres coincide" in str(exc) and k < -8
    except GeometryError as exc:
        assert str(exc).split(":")[0] == "t" and abs(k) > 90, str(exc)
    else:
        np.testing.assert_allclose(F_big, epipolar.epipolar_pair(pin, other).F, rtol=1e-9, atol=1e-12)
    Xp = rng.uniform(-1.0, 1.0, size=(5, 3)) * [3.0, 3.0, 0.5] + [0.0, 0.0, -2.0]
    plain = CatadioptricCamera(Pose(np.eye(3), [0.2, 0.1, 0.0]), HyperbolicMirror(0.3, 0.1))
    try:
        scaled = _quiet(lambda: CatadioptricCamera(Pose(np.eye(3), plain.pose.t * s),
                                                   HyperbolicMirror(0.3 * s, 0.1 * s)).project(Xp * s))
    except GeometryError as exc:
        assert str(exc).split(":")[0] in ("t", "X_world", "a", "b"), str(exc)
        assert abs(k) > 90
    else:
        ref = plain.project(Xp)
        np.testing.assert_array_equal(scaled.visible, ref.visible)
        np.testing.assert_allclose(scaled.pixels, ref.pixels, rtol=1e-9)


@pytest.mark.parametrize("magnitude", [1e101, 1e200, 1e308])
def test_unsolvable_world_magnitudes_are_refused_with_a_clear_message(magnitude):
    with pytest.raises(GeometryError, match="X_world: magnitude .* too large"):
        CAM1.project([[0.0, magnitude, 0.0]])
    with pytest.raises(GeometryError, match="X_world: magnitude .* too large"):
        PAN1.project([[magnitude, 0.0, -1.0]])
    with pytest.raises(GeometryError, match="t: magnitude .* too large"):
        Pose(np.eye(3), [magnitude, 0.0, 0.0])
    with pytest.raises(GeometryError, match="pixels: magnitude .* too large"):
        CAM1.back_project([[magnitude, 0.0]])


def test_no_lapack_or_numpy_output_on_degenerate_up_to_scale_input(capfd):
    for s in (1e-300, 1e-200, 1e200, 1e300):
        epipolar.epipoles_from_fundamental(F * s)
        poses.matrix_from_quat_wxyz(Q * s)
        homogeneous.normalize_homogeneous(HOMOG * s)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_validate_helpers_keep_their_names():
    for name in ("as_array", "as_points", "as_matrix", "as_vector", "as_positive", "as_rotation", "as_calibration",
                 "as_up_to_scale", "as_up_to_scale_rows", "as_scalar", "as_count", "short_repr"):
        assert callable(getattr(_validate, name)), name


def test_short_repr_and_conversion_messages():
    assert len(_validate.short_repr(10**5000)) < 60 and "digits" in _validate.short_repr(10**5000)
    assert len(_validate.short_repr(np.zeros(10**6))) <= 60
    assert len(_validate.short_repr("x" * 10**6)) <= 60
    with pytest.raises(GeometryError, match="X: .* beyond 64 bits"):
        _validate.as_array([1, 10**30, 0], "X")
    nested: list = [1.0]
    for _ in range(100):
        nested = [nested]
    with pytest.raises(GeometryError, match="X: nested more than 32 levels"):
        _validate.as_array(nested, "X")
    with pytest.raises(GeometryError, match="n: expected a whole number"):
        _validate.as_count(2.5, "n")
    assert _validate.as_count(3.0, "n") == 3
    with pytest.raises(GeometryError, match="a: .* too small"):
        HyperbolicMirror(1e-200, 1.0)
    np.testing.assert_array_equal(_validate.as_up_to_scale([0.0, -4.0, 2.0], "q", (3,)), [0.0, -1.0, 0.5])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"focal_length": 1e-300}, "focal_length, pixels_per_metre, skew: .* cannot be inverted"),
        ({"skew": 1e20}, "focal_length, pixels_per_metre, skew: .* cannot be inverted"),
        ({"pixels_per_metre": (1e-290, 1e5)}, "focal_length, pixels_per_metre, skew: .* cannot be inverted"),
        ({"width": 10**8}, "width: expected a whole number at least 1 and at most 10000000"),
    ],
)
def test_intrinsics_that_make_no_usable_camera_are_refused(kwargs, match):
    # Each value is a finite positive number on its own; together they give a K that cannot be inverted
    # (back-projection would raise LinAlgError or return inf), or an image no array could hold.
    with pytest.raises(GeometryError, match=match):
        Intrinsics(**kwargs)
