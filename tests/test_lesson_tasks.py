"""The task vocabulary and the change vocabulary, each checked against values derived by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from egtviz.lessons.changes import (
    Highlight,
    Lock,
    MoveCamera,
    MovePoint,
    OpenDemo,
    Select,
    SetField,
    SetLab,
    SetLens,
    SetPair,
    SetRange,
    Show,
    apply,
    parse_change,
)
from egtviz.lessons.errors import EntryError
from egtviz.lessons.tasks import (
    TaskContext,
    Uniform,
    direction_spread_deg,
    parse_task,
    task_seed,
)
from egtviz.scene import SCENES, PinholeSpec, Scene, SceneError, SceneModel
from egtviz.scene.lab import LabSettings
from egtviz.scene.lens import LensToggles


def task(**table):
    table.setdefault("prompt", "x")
    return parse_task(table, "t1")


def ctx(scene, **kw):
    return TaskContext(scene, **kw)


def check(t, c):
    return t.check(c, t.resolve(0))


# Hand-built rotations for the pin-hole convention (docs/conventions.md), independent of the core.
def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def world_rotation(ypr_deg):
    yaw, pitch, roll = np.radians(ypr_deg)
    return rx(-np.pi / 2) @ ry(yaw) @ rx(pitch) @ rz(roll)


# -- questions ---------------------------------------------------------------------------------------------


def test_number_answers_within_tolerance_pass_and_say_too_high_or_low():
    t = task(kind="number", answer=800, tolerance=0.5, unit="px")
    scene = Scene()
    assert check(t, ctx(scene, answer="800.5 px")).passed
    assert check(t, ctx(scene, answer=" 799.6")).passed
    high = check(t, ctx(scene, answer="801"))
    assert not high.passed and "too high" in high.feedback
    assert "too low" in check(t, ctx(scene, answer="-8e2")).feedback
    assert check(t, ctx(scene, answer="eight hundred")).feedback == (
        "Type one number, e.g. 2.5 (in px: 2.5 or 2.5 px); got 'eight hundred'.")
    assert not check(t, ctx(scene, answer=None)).passed


def test_choice_accepts_the_option_or_its_number():
    t = task(kind="choice", options=["a", "b", "c"], answer="b")
    assert check(t, ctx(Scene(), answer="b")).passed
    assert check(t, ctx(Scene(), answer="2")).passed
    assert not check(t, ctx(Scene(), answer="3")).passed
    assert check(t, ctx(Scene(), answer="zzz")).feedback == "Pick one of the options."
    with pytest.raises(EntryError, match="answer: expected one of the options"):
        task(kind="choice", options=["a", "b"], answer="c")


# -- scene goals ---------------------------------------------------------------------------------------


def test_epipole_near_measures_the_image_of_the_other_centre():
    scene = SCENES["default"]()
    c1, c2 = scene.cameras
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])  # f = 8 mm at 1e5 px/m, principal point (320, 240)
    e = K @ world_rotation(c1.ypr_deg).T @ (np.array(c2.position) - np.array(c1.position))
    u, v = e[:2] / e[2]
    hit = task(kind="epipole_near", camera="cam1", target={"u": float(u), "v": float(v)}, within_px=0.01)
    assert check(hit, ctx(scene)).passed
    miss = task(kind="epipole_near", camera="cam1", target={"u": float(u) + 6, "v": float(v) + 8}, within_px=9.9)
    result = check(miss, ctx(scene))
    assert not result.passed and "10.0 px from" in result.feedback
    assert check(task(kind="epipole_near", camera="cam1", target={"u": float(u) + 6, "v": float(v) + 8},
                      within_px=10.01), ctx(scene)).passed


def test_same_orientation_is_the_angle_of_the_relative_rotation():
    scene = Scene(cameras=(PinholeSpec("a", (0, -5, 1), (10, 0, 0)), PinholeSpec("b", (1, -5, 1), (40, 0, 0))))
    # Both rotations are yaws about one axis: the relative rotation is the 30-degree difference.
    assert not check(task(kind="same_orientation", cameras=["a", "b"], within_deg=29.9), ctx(scene)).passed
    ok = check(task(kind="same_orientation", cameras=["a", "b"], within_deg=30.1), ctx(scene))
    assert ok.passed and "30.0 degrees" in ok.feedback


def test_lines_parallel_passes_when_the_baseline_is_parallel_to_the_image():
    pts = [(0, 0, 1), (1, 1, 0), (-1, 2, 2), (0.5, -1, 1.5)]
    scene = Scene(cameras=(PinholeSpec("a", (0, -8, 1)), PinholeSpec("b", (2, -8, 1))), points=pts)
    t = task(kind="lines_parallel", camera="b", within_deg=0.01)
    assert check(t, ctx(scene)).passed  # baseline along both cameras' x axes: epipole at infinity
    turned = scene.replace(cameras=(scene.cameras[0], PinholeSpec("b", (2, -8, 1), (10, 0, 0))))
    result = check(task(kind="lines_parallel", camera="b", within_deg=1), ctx(turned))
    assert not result.passed and "spread over" in result.feedback


@given(st.floats(0, 180), st.lists(st.floats(0, 80), min_size=2, max_size=12))
def test_direction_spread_of_lines_within_a_right_angle_is_their_largest_minus_smallest_angle(start, offsets):
    angles = np.radians(start + np.array(offsets))
    lines = np.column_stack([np.sin(angles), -np.cos(angles), np.ones_like(angles)])  # direction (cos, sin)
    lines[::2] *= -1.0  # a line's sign does not change its direction
    assert direction_spread_deg(lines) == pytest.approx(max(offsets) - min(offsets), abs=1e-6)


def test_point_on_line_reads_the_f_the_lens_shows():
    scene = SCENES["default"]()
    t = task(kind="point_on_line", point=1, camera="cam2", within_px=0.001)
    assert check(t, ctx(scene)).passed
    broken = check(t, ctx(scene, lens=LensToggles(f_transposed=True)))
    assert not broken.passed and "px from its epipolar line in cam2" in broken.feedback


def lab_scene(n=100, seed=5):
    model = SceneModel(SCENES["default"]())
    model.randomize_points(n, seed=seed)
    return model.scene


def test_inliers_recall_and_its_minimum_outliers():
    scene = lab_scene()
    t = task(kind="inliers_recall", method="ransac", at_least=0.9, min_outlier_percent=20)
    good = LabSettings(noise_px=0.5, outlier_percent=20, threshold_px=1.5)
    assert check(t, ctx(scene, lab=good)).passed
    assert not check(t, ctx(scene, lab=LabSettings(noise_px=0.5, outlier_percent=20, threshold_px=0.1))).passed
    few = check(t, ctx(scene, lab=LabSettings(noise_px=0.5, outlier_percent=10, threshold_px=1.5)))
    assert not few.passed and few.feedback.startswith("Keep the outliers at 20 %")


def test_sampson_below_against_the_true_points():
    scene = lab_scene()
    t = task(kind="sampson_below", method="ransac", below_px2=0.2, min_noise_px=0.5)
    assert check(t, ctx(scene, lab=LabSettings(noise_px=0.5, outlier_percent=30, threshold_px=1.5))).passed
    assert not check(t, ctx(scene, lab=LabSettings(noise_px=0.5, outlier_percent=30, threshold_px=30))).passed
    quiet = check(t, ctx(scene, lab=LabSettings(noise_px=0.0)))
    assert not quiet.passed and "Keep the noise at 0.5 px" in quiet.feedback
    # Without noise every estimator recovers F: the mean Sampson error of the true points is ~0.
    exact = task(kind="sampson_below", method="normalized", below_px2=1e-6)
    assert check(exact, ctx(scene, lab=LabSettings(noise_px=0.0))).passed


def test_point_in_image_and_camera_field():
    scene = SCENES["example1"]()  # point 1 projects to (0.238, 0.202), inside the 2 x 2 image; point 0 to u < 0
    assert check(task(kind="point_in_image", point=1, camera="cam"), ctx(scene)).passed
    assert "outside the 2 x 2 image" in check(task(kind="point_in_image", point=0, camera="cam"), ctx(scene)).feedback
    default = SCENES["default"]()
    assert check(task(kind="camera_field", camera="cam1", field="focal_length", low=0.0079, high=0.0081),
                 ctx(default)).passed
    assert not check(task(kind="camera_field", camera="cam1", field="position", component=2, low=2, high=3),
                     ctx(default)).passed  # cam1 is at z = 1.5
    with pytest.raises(EntryError, match="component"):
        task(kind="camera_field", camera="cam1", field="position", low=0, high=1).validate(default)


def test_xi_between_uses_the_mirror_formula():
    scene = SCENES["example2"]()  # a = 3, b = 1: xi = 2 a e / (2 a^2 + b^2) = 6 sqrt(10) / 19 = 0.998614
    assert check(task(kind="xi_between", camera="pano", low=0.99861, high=0.99862), ctx(scene)).passed
    assert not check(task(kind="xi_between", camera="pano", low=0.5, high=0.9), ctx(scene)).passed
    pin = SCENES["default"]()
    assert check(task(kind="xi_between", camera="cam1", low=0, high=0), ctx(pin)).passed


def test_triangulation_error_follows_the_stereo_depth_formula():
    # Parallel cameras 1 m apart, f = 800 px, a point 8 m ahead: dZ = Z^2 / (f b) dd with dd of std sqrt(2) px.
    scene = Scene(cameras=(PinholeSpec("a", (0, 0, 0)), PinholeSpec("b", (1, 0, 0))), points=[(0.5, 8, 0)])
    predicted = 8.0**2 / (800 * 1.0) * math.sqrt(2.0)
    assert check(task(kind="triangulation_error", point=0, noise_px=1, at_most=predicted * 1.15), ctx(scene)).passed
    assert not check(task(kind="triangulation_error", point=0, noise_px=1, at_most=predicted * 0.85), ctx(scene)).passed
    assert check(task(kind="triangulation_error", point=0, noise_px=0, at_most=1e-6), ctx(scene)).passed


# -- randomised parameters ------------------------------------------------------------------------------


def test_seeds_are_stable_per_learner_and_draws_stay_in_range():
    t = task(kind="epipole_near", camera="cam1", target={"u": [100, 540], "v": [80.5, 400]}, within_px=3,
             prompt="Put it at ({u}, {v}) within {within_px} px.")
    assert t.u == Uniform(100, 540, integer=True) and not t.v.integer
    s1 = task_seed("Ada", "06-x", 1, "t1")
    assert s1 == task_seed("Ada", "06-x", 1, "t1") and s1 != task_seed("Bob", "06-x", 1, "t1")
    draws = [t.resolve(task_seed(f"learner {i}", "06-x", 1, "t1")) for i in range(50)]
    assert all(100 <= d["u"] <= 540 and d["u"].is_integer() and 80.5 <= d["v"] <= 400 for d in draws)
    assert len({d["u"] for d in draws}) > 25
    p = draws[0]
    assert t.prompt_for(p) == f"Put it at ({p['u']:g}, {p['v']:g}) within 3 px."
    rounded = task(kind="epipole_near", camera="cam1", target={"u": 100.25, "v": 80}, within_px=3,
                   prompt="({u:.1f}, {v})")
    assert rounded.prompt_for(rounded.resolve(0)) == "(100.2, 80)"


@pytest.mark.parametrize("bad", ["{u:.1000000f}", "{u:>{v}}", "{u!r}", "{0}", "{}", "{u.real}", "{u[0]}", "{x"])
def test_prompt_placeholders_are_plain_names_or_a_rounding(bad):
    with pytest.raises(EntryError, match="prompt: (placeholder|bad placeholder)"):
        task(kind="epipole_near", camera="cam1", target={"u": 1, "v": 2}, within_px=3, prompt="at " + bad)


# -- changes -------------------------------------------------------------------------------------------


def change(**table):
    return parse_change(table)


def test_scene_changes_apply_through_the_model():
    model = SceneModel(SCENES["default"]())
    assert apply(model, change(do="hide", what="rays")) is None and not model.scene.options.show_rays
    apply(model, change(do="move", camera="cam2", position=[1, -6, 2], ypr_deg=[5, 0, 0]))
    assert model.scene.camera("cam2").position == (1.0, -6.0, 2.0) and model.scene.camera("cam2").ypr_deg == (5, 0, 0)
    apply(model, change(do="move", point=2, to=[0, 0, 3]))
    assert model.scene.points[2] == (0.0, 0.0, 3.0)
    apply(model, change(do="highlight", names=["cam1", "point:2"]))
    assert model.scene.highlighted == {"cam1", "point:2"}
    apply(model, change(do="lock", names=["cam1", "point:0"]))
    assert model.scene.locked == {"cam1", "point:0"}
    apply(model, change(do="unlock", names=["cam1"]))
    assert model.scene.locked == {"point:0"}
    apply(model, change(do="select", point=3))
    assert model.scene.selected_point == 3
    apply(model, change(do="select"))
    assert model.scene.selected_point is None
    apply(model, change(do="set_pair", cameras=["cam2", "cam1"]))
    assert model.scene.pair == ("cam2", "cam1")
    apply(model, change(do="set_field", camera="cam1", field="principal_point", value=[300, 200]))
    assert model.scene.camera("cam1").principal_point == (300.0, 200.0)
    apply(model, change(do="set_points", points=[[0, 0, 0], [1, 1, 1]]))
    assert model.scene.points == ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    apply(model, change(do="random_points", n=20, seed=1))
    assert len(model.scene.points) == 20


def test_records_leave_the_scene_alone():
    model = SceneModel(SCENES["default"]())
    before = model.scene
    rng = change(do="set_range", camera="cam1", field="focal_length", low=0.002, high=0.05)
    assert apply(model, rng) == SetRange("cam1", "focal_length", 0.002, 0.05)
    lab = apply(model, change(do="set_lab", noise_px=2, threshold_px=3))
    assert isinstance(lab, SetLab) and lab.applied_to(LabSettings()) == LabSettings(noise_px=2.0, threshold_px=3.0)
    lens = apply(model, change(do="set_lens", r_tx=True))
    assert isinstance(lens, SetLens) and lens.applied_to(LensToggles()) == LensToggles(r_tx=True)
    assert model.scene is before


@pytest.mark.parametrize(
    ("table", "words"),
    [
        ({"do": "show", "what": "ghosts"}, "what: expected one of rays"),
        ({"do": "move", "camera": "cam1"}, "needs 'position', 'ypr_deg' or both"),
        ({"do": "move", "point": 1, "camera": "cam1", "to": [0, 0, 0]}, "not both"),
        ({"do": "set_pair", "cameras": ["cam1", "cam1"]}, "two different camera names"),
        ({"do": "set_range", "camera": "cam1", "field": "focal_length", "low": 0.01, "high": 0.001}, "high > low"),
        ({"do": "set_range", "camera": "cam1", "field": "focal_length", "low": 0.001, "high": 50}, "0.0001..10 m"),
        ({"do": "set_lab", "noise_px": 500}, "noise_px: expected a number in 0..20 px"),
        ({"do": "set_lens", "r_tx": 1}, "r_tx: expected true or false"),
        ({"do": "random_points", "n": 10_000}, "n: expected a whole number in 8..2000"),
        ({"do": "set_field", "camera": "cam1", "field": "name", "value": "x"}, "field: expected one of"),
    ],
)
def test_bad_changes_name_the_key(table, words):
    with pytest.raises(EntryError, match=None) as info:
        parse_change(table)
    assert words in str(info.value)


def test_changes_naming_what_the_scene_lacks_leave_the_model_unchanged():
    model = SceneModel(SCENES["default"]())
    before = model.scene
    for c in (MoveCamera("cam9", position=(0, 0, 0)), MovePoint(40, (0, 0, 0)), Lock(("cam1", "cam9")),
              Lock(("point:99",), locked=False), Select(50), SetPair(("cam1", "cam9")),
              SetField("cam1", "focal_length", 20.0), Highlight(("nobody",))):
        with pytest.raises(SceneError):
            apply(model, c)
        assert model.scene is before
    with pytest.raises(EntryError, match="no field 'mirror'"):
        apply(model, SetRange("cam1", "mirror", 0, 1))
    assert apply(model, Show("rays", False)) is None and not model.scene.options.show_rays


# -- servo runs: open_demo and servo_number ------------------------------------------------------------


def first_time_below(time, values, below):
    """The first sample time with ``values < below``, by a plain scan (NaN if never): the reference here."""
    for t, v in zip(time, values):
        if v < below:
            return float(t)
    return math.nan


def test_open_demo_is_a_record_with_the_demos_run_fields():
    model = SceneModel(SCENES["default"]())
    before = model.scene
    opened = apply(model, change(do="open_demo", demo="pinhole", seed=3, beta=0, estimator="normalized"))
    assert isinstance(opened, OpenDemo) and model.scene is before
    assert opened.options() == {"beta": 0.0, "estimator": "normalized", "seed": 3}
    # The keywords the pin-hole demo passes to simulate_pinhole (its Run folder's defaults for the rest).
    assert opened.simulation_kwargs() == {"seed": 3, "noise_px": 0.0, "steps": 1000, "beta": 0.0, "f_algorithm": 2}
    assert OpenDemo("panoramic").simulation_kwargs() == {"seed": 0, "noise_px": 0.0, "steps": 1500}
    assert opened.describe() == "beta 0, estimator normalized, seed 3"


@pytest.mark.parametrize(
    ("table", "words"),
    [
        ({"do": "open_demo", "demo": "planar"}, "demo: expected one of pinhole, panoramic"),
        ({"do": "open_demo"}, "demo: missing"),
        ({"do": "open_demo", "demo": "panoramic", "beta": 1},
         "beta: unknown key for an 'open_demo' change of the panoramic demo"),
        ({"do": "open_demo", "demo": "pinhole", "gain": 1}, "gain: unknown key"),
        ({"do": "open_demo", "demo": "pinhole", "seed": -1}, "seed: expected a whole number in 0.."),
        ({"do": "open_demo", "demo": "pinhole", "seed": 1.5}, "seed: expected a whole number"),
        ({"do": "open_demo", "demo": "pinhole", "beta": 1e9}, "beta: expected a number in 0..100"),
        ({"do": "open_demo", "demo": "pinhole", "noise_px": 51}, "noise_px: expected a number in 0..50 px"),
        ({"do": "open_demo", "demo": "pinhole", "steps": 0}, "steps: expected a whole number in 1..10000"),
        ({"do": "open_demo", "demo": "pinhole", "estimator": "ransac"}, "estimator: expected one of true, linear"),
    ],
)
def test_bad_open_demo_changes_name_the_key(table, words):
    with pytest.raises(EntryError) as info:
        parse_change(table)
    assert words in str(info.value)


def test_servo_number_reads_the_steps_run_as_the_simulation_gives_it():
    from egtviz.servo import simulate_pinhole

    run = OpenDemo("pinhole", (("beta", 0.0), ("seed", 0)))
    result = simulate_pinhole(seed=0, beta=0.0)  # what the pin-hole demo runs with seed 0, beta 0
    expected = first_time_below(result.time, np.degrees(result.errors["rotation_error_rad"]), 0.1)
    assert math.isfinite(expected) and expected > 0
    t = task(kind="servo_number", measure="rotation_below_time", below=0.1, tolerance=0.1,
             prompt="below {below} deg, within {tolerance} s")
    assert t.unit == "s" and t.prompt_for(t.resolve(0)) == "below 0.1 deg, within 0.1 s"
    assert t.answer_for(run) == pytest.approx(expected, abs=1e-12)
    assert check(t, ctx(SCENES["default"](), answer=f"{expected + 0.09:g} s", demo=run)).passed
    high = check(t, ctx(SCENES["default"](), answer=f"{expected + 0.2:g}", demo=run))
    assert not high.passed and high.feedback.endswith("s is too high.")
    assert not check(t, ctx(SCENES["default"](), answer="soon", demo=run)).passed
    unopened = check(t, ctx(SCENES["default"](), answer=f"{expected:g}"))
    assert not unopened.passed and "opens no servo demo" in unopened.feedback
    steps = task(kind="servo_number", measure="steps")
    assert steps.answer_for(run) == result.steps == len(result.time) - 1
    final = task(kind="servo_number", measure="final_translation_error", tolerance=0.5)
    assert final.unit == "cm" and final.answer_for(run) == pytest.approx(100 * result.errors["translation_error"][-1])


def test_servo_number_on_the_panoramic_run_finds_the_start_of_step_2():
    from egtviz.servo import simulate_panoramic

    run = OpenDemo("panoramic", (("seed", 0),))
    result = simulate_panoramic(seed=0)
    phase = result.extras["phase"]
    k = next(i for i, p in enumerate(phase) if p == 2)
    assert all(p == 1 for p in phase[:k])  # the rotation comes first
    t = task(kind="servo_number", measure="translation_phase_time", tolerance=0.1)
    assert t.answer_for(run) == pytest.approx(float(result.time[k]))
    start = task(kind="servo_number", measure="initial_rotation_error", tolerance=0.5)
    assert start.unit == "deg" and start.answer_for(run) == pytest.approx(math.degrees(result.initial_rotation_error_rad))


@pytest.mark.parametrize(
    ("table", "words"),
    [
        ({"measure": "speed"}, "measure: expected one of steps, sim_time"),
        ({"measure": "rotation_below_time"}, "below: 'rotation_below_time' needs 'below' (in deg)"),
        ({"measure": "steps", "below": 1}, "below: 'steps' takes no 'below'"),
        ({"measure": "rotation_below_time", "below": 200}, "below: expected a number in 1e-06..180 deg"),
        ({"measure": "steps", "tolerance": -1}, "tolerance: expected a number"),
        ({"measure": "steps", "unit": "s"}, "unit: unknown key for a 'servo_number' task"),
    ],
)
def test_bad_servo_number_tasks_name_the_key(table, words):
    with pytest.raises(EntryError) as info:
        task(kind="servo_number", **table)
    assert words in str(info.value)


def test_servo_number_needs_a_run_that_gets_where_it_asks():
    t = task(kind="servo_number", measure="translation_below_time", below=1)
    with pytest.raises(EntryError, match="needs an open_demo change"):
        t.validate_run(None)
    with pytest.raises(EntryError, match=r"below: the pinhole run \(beta 0, seed 0\) never gets there"):
        t.validate_run(OpenDemo("pinhole", (("beta", 0.0), ("seed", 0))))  # beta = 0: the translation stays
    with pytest.raises(EntryError, match="measure: the pinhole demo has no 'translation_phase_time'"):
        task(kind="servo_number", measure="translation_phase_time").validate_run(OpenDemo("pinhole"))


def test_prompts_and_feedback_name_points_by_the_viewers_number():
    """The viewer labels point index i as i + 1 (panels, 3D, the point list): prompts and feedback do too."""
    scene = SCENES["example1"]()  # index 1 projects to (0.238, 0.202), inside the 2 x 2 image
    t = task(kind="point_in_image", point=1, camera="cam", prompt="Bring point {point} into the image.")
    assert t.prompt_for(t.resolve(0)) == "Bring point 2 into the image."
    assert check(t, ctx(scene)).feedback.startswith("Done: point 2 is at (0.2381")
    tri = task(kind="triangulation_error", point=6, noise_px=1, at_most=1, prompt="point {point}")
    assert tri.prompt_for(tri.resolve(0)) == "point 7"
