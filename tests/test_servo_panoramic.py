"""Panoramic camera on a holonomic robot: bi-conic rotation step, translation step, failures."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from egtviz.servo import ServoResult, simulate_panoramic
from egtviz.servo import cli as servo_cli
from egtviz.servo.panoramic_robot import (
    default_camera,
    default_scene,
    estimate_rotation,
    mirror_pose,
    rotation_measure,
    step_state,
)

SEEDS = range(20)


@pytest.fixture(scope="module")
def runs() -> list[ServoResult]:
    return [simulate_panoramic(seed=s) for s in SEEDS]


def test_seeded_starts_cover_the_ranges_and_converge(runs):
    ok = [r.converged and r.final_rotation_error_rad < 1e-3 and r.final_translation_error < 1e-3 for r in runs]
    assert sum(ok) >= 19, [(r.params["seed"], r.reason) for r in runs if not r.converged]
    rot0 = np.degrees([r.initial_rotation_error_rad for r in runs])
    tr0 = np.array([r.initial_translation_error for r in runs])
    assert np.all((rot0 >= 30 - 1e-6) & (rot0 <= 120 + 1e-6))
    assert np.all((tr0 >= 1 - 1e-9) & (tr0 <= 3 + 1e-9))


def test_two_steps_rotation_then_translation(runs):
    for r in runs:
        rot, tr = r.errors["rotation_error_rad"], r.errors["translation_error"]
        k = int(np.argmax(rot < 1e-2))
        assert rot[k] < 1e-2 and tr[k] > 0.5 * tr[0]
        u = r.controls["robot_velocity"]
        phase = r.extras["phase"]
        assert np.allclose(u[phase == 1, :2], 0.0)  # step 1 only turns
        assert phase[-1] == 2
        assert r.extras["s_px"][-1] < 1e-2 < r.extras["s_px"][0]


def test_biconics_share_two_points_once_rotation_is_compensated(runs):
    r = runs[0]
    measure = r.extras["biconic_measure"]
    assert measure[0] > 1e3 * measure[int(np.argmax(r.extras["phase"] == 2))]
    C = r.extras["biconics"]
    steps = r.extras["biconic_steps"]
    assert C.shape[1:] == (r.features.shape[1], 3, 3) and len(C) == len(steps)
    # every bi-conic passes through its current feature (the plane contains the current ray)
    m = np.column_stack([r.features[steps[0]], np.ones(r.features.shape[1])])
    res = np.einsum("ni,nij,nj->n", m, C[0], m)
    assert np.all(np.abs(res) < 1e-6)


def test_rotation_estimate_is_exact_without_noise():
    cam = default_camera()
    X = default_scene()
    cur, des = np.array([0.7, -1.2, 0.9]), np.array([0.0, 0.0, 0.0])
    d = cam.moved(mirror_pose(cur)).pose.to_local(X)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ds = X - [0, 0, 0.5]
    ds /= np.linalg.norm(ds, axis=1, keepdims=True)
    assert abs(estimate_rotation(d, ds) - (des[2] - cur[2])) < 1e-6
    assert rotation_measure(d, ds, des[2] - cur[2]) < 1e-10 < rotation_measure(d, ds, 0.0)


def test_state_update_exact_on_se2():
    s = step_state(np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, np.pi]), 1.0)
    np.testing.assert_allclose(s[:2], [0.0, 2.0 / np.pi], atol=1e-12)  # half a circle of radius 1/pi
    assert np.isclose(np.cos(s[2]), -1.0)


def test_noise_still_converges_roughly():
    r = simulate_panoramic(seed=0, noise_px=0.5, steps=800)
    assert r.final_rotation_error_rad < 1e-2
    assert r.final_translation_error < 0.1 * r.initial_translation_error


def test_features_leaving_the_field_of_view():
    X = default_scene()
    X = np.vstack([X, [[0.2, 0.0, 2.0]]])  # steeply above the target: in the mirror's blind cone there
    r = simulate_panoramic(seed=0, points=X)
    assert not r.converged and "field of view" in r.reason
    r = simulate_panoramic(seed=0, points=X[:3])
    assert not r.converged and "at least 4 features" in r.reason


@pytest.mark.parametrize(("kwargs", "match"), [({"noise_px": -0.1}, "noise_px"), ({"noise_px": float("nan")}, "noise_px"),
                                               ({"steps": 0}, "steps"), ({"k_v": -1.0}, "k_v")])
def test_invalid_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate_panoramic(**kwargs)


def test_full_length_run_and_json(tmp_path, capsys):
    # Speed is measured by `egtviz bench servo`, not asserted here.
    r = simulate_panoramic(seed=1, steps=1000, stop_px=0.0)
    assert r.steps == 1000
    d = json.loads(json.dumps(r.to_json_dict(), allow_nan=False))
    assert len(d["controls"]["robot_velocity"]) == 1001 and len(d["extras"]["biconics"][0][0]) == 3
    parser = argparse.ArgumentParser()
    servo_cli.add_parser(parser.add_subparsers(dest="cmd"))
    args = parser.parse_args(["servo", "panoramic", "--seed", "2", "--json", str(tmp_path / "p.json")])
    assert servo_cli.run(args) == 0
    assert "panoramic servo" in capsys.readouterr().out
