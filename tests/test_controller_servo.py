"""The servo demo's controller (egtviz.controllers.servo) driven with no server: typed intents in, typed state out.

Its field checks say what the tab's notification says, its runs equal egtviz.servo's simulations with the same
settings, its playback lands on the frames the page draws, and the server's frame budget can refuse a run.
"""

from __future__ import annotations

import numpy as np
import pytest

from egtviz.controllers.servo import NOT_CONVERGED_MESSAGE, ServoController
from egtviz.controllers.servo_budget import ServoBudget
from egtviz.controllers.servo_demos import PanoramicServoModel
from egtviz.controllers.workbench_fields import FieldError
from egtviz.servo import simulate_panoramic, simulate_pinhole

STEPS = 30


def test_a_refused_field_says_why_and_keeps_the_last_valid_value():
    c = ServoController("pinhole", steps=STEPS, budget=ServoBudget(100))
    before = c.params()
    for key, text, message in (("beta", "-1", "beta must be between 0 and 100, got -1"),
                               ("seed", "1.5", "seed must be a whole number, got 1.5"),
                               ("noise_px", "abc", "noise: expected a number, got 'abc'"),
                               ("steps", "1e9", "max steps must be between 1 and 10000, got 1000000000")):
        with pytest.raises(FieldError) as refused:
            c.set_text(key, text)
        assert str(refused.value) == message
    with pytest.raises(FieldError, match="F estimator: expected one of true, linear, normalized, sampson"):
        c.choose("estimator", "exact")
    assert c.params() == before
    c.set_text("beta", "0.5")
    c.choose("estimator", "sampson")
    assert c.params() == {**before, "beta": 0.5, "f_algorithm": 3} and c.shown("beta") == "0.5"


def test_unknown_demos_and_parameters_are_refused():
    with pytest.raises(ValueError, match="kind: expected one of 'pinhole', 'panoramic'"):
        ServoController("stereo")
    with pytest.raises(ValueError, match="beta: not a parameter of the panoramic demo"):
        ServoController("panoramic", beta=0.5)
    c = ServoController("panoramic")
    with pytest.raises(FieldError):
        c.set_params(seed=3, noise_px=-1.0)
    assert c.values["seed"] == 0  # all or nothing


@pytest.mark.parametrize("kind", ["pinhole", "panoramic"])
def test_a_run_equals_the_simulation_with_the_same_settings(kind):
    c = ServoController(kind, steps=STEPS, seed=5, budget=ServoBudget(100))
    c.set_text("noise_px", "0.5")
    outcome = c.run()
    assert outcome.error == "" and outcome.busy == "" and c.result is outcome.result and c.frames is not None
    extra = {"camera": c.model.camera} if isinstance(c.model, PanoramicServoModel) else {}
    expected = (simulate_pinhole if kind == "pinhole" else simulate_panoramic)(**c.params(), **extra)
    assert c.result.n_samples == expected.n_samples == STEPS + 1
    assert np.array_equal(c.result.features, expected.features, equal_nan=True)
    assert np.array_equal(c.result.time, expected.time)
    assert c.status is not None and c.status.level == "warn" and c.status.text.startswith("Did not converge")
    assert c.budget.held(c) == STEPS + 1 and not c.running and c.frame == 0


def test_seeking_and_stepping_land_on_the_frames_of_the_run():
    c = ServoController("pinhole", steps=STEPS, budget=ServoBudget(100))
    assert c.seek(3) is None and c.play() is None and not c.playing  # nothing to show before a run
    c.run()
    assert (c.seek(10), c.step(3), c.step(-2), c.step(-100)) == (10, 13, 11, 0)
    assert c.seek(10_000) == STEPS and c.time == pytest.approx(c.result.time[-1])
    assert c.seek_time(1.0) == 20 and c.frame == 20  # dt = 0.05 s
    assert c.frame_at(0.52) == 10 and c.frame == 20  # the scrubber's frame, not yet shown
    with pytest.raises(FieldError, match="time: expected a number of seconds"):
        c.frame_at(float("nan"))
    c.seek(STEPS)
    assert c.play() == 0 and c.playing and c.frame == 0  # at the end: plays from the start
    c.choose("speed", "2x")
    position, k = c.advance(0.0, 0.5)  # 0.5 s at 2x: 1 simulated second, 20 frames
    assert (position, k) == (pytest.approx(20.0), 20) and c.playing
    position, k = c.advance(position, 10.0)
    assert k == STEPS and not c.playing and c.frame == 0  # stops at the last frame, which the page then shows
    assert c.seek(k) == STEPS and c.step(1) == STEPS and c.pause() is False


def test_the_image_of_a_frame_is_what_the_page_draws():
    c = ServoController("panoramic", steps=STEPS, budget=ServoBudget(100))
    c.run()
    first, last = c.image(0), c.image(STEPS)
    assert first.frame == 0 and first.caption.startswith("t = 0.00 s  step 1: rotation")
    assert np.array_equal(first.current, c.result.features[0], equal_nan=True) and first.rim is not None
    assert last.message == NOT_CONVERGED_MESSAGE and len(last.trails) > len(first.trails)


def test_the_budget_refuses_a_run_that_does_not_fit():
    c = ServoController("pinhole", steps=40, budget=ServoBudget(10, queue_seconds=0))
    outcome = c.run()
    assert outcome.result is None and c.result is None and not c.running
    assert outcome.busy == ("The server is busy with 0 other servo runs (0 of its 10 frames); this run needs up "
                            "to 41. Try again in a moment, or with fewer max steps.")
    assert c.status is not None and (c.status.level, c.status.text) == ("warn", outcome.busy)


def test_a_failing_simulation_is_said_in_words(monkeypatch):
    from egtviz.controllers import servo_demos

    def refuse(**kw):
        raise ValueError("beta: the simulation refused it")

    monkeypatch.setattr(servo_demos, "simulate_pinhole", refuse)
    budget = ServoBudget(100)
    c = ServoController("pinhole", steps=STEPS, budget=budget)
    outcome = c.run()
    assert c.error == outcome.error == "Bad parameters: beta: the simulation refused it"
    assert c.status is not None and c.status.level == "error" and budget.held(c) == 0
