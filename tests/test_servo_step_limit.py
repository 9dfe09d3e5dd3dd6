"""The servo step limits live in ``egtviz.scene.limits``; the command line, the browser demos and a lesson's
``open_demo`` read them, and a count outside is refused with the range in the message."""

from __future__ import annotations

from pathlib import Path

import pytest

from egtviz.cli import build_parser, main
from egtviz.lessons.errors import EntryError
from egtviz.lessons.servo_runs import parse_run_fields
from egtviz.scene import limits
from egtviz.controllers.workbench_fields import FieldError, parse_numbers
from egtviz.controllers.servo_demos import RUN_RULES

DOCS = Path(__file__).resolve().parents[1] / "docs" / "limits.md"


def test_the_two_step_limits_are_declared_side_by_side_and_documented():
    assert limits.SERVO_HEADLESS_STEPS == limits.Range(1, 100_000, "", integer=True)
    assert limits.SERVO_DEMO_STEPS == limits.Range(1, 10_000, "", integer=True)
    text = DOCS.read_text(encoding="utf-8")
    assert "| `SERVO_HEADLESS_STEPS` | 1..100000, whole |" in text
    assert "| `SERVO_DEMO_STEPS` | 1..10000, whole |" in text


def test_the_command_line_takes_its_whole_range_and_names_it_when_refusing(capsys, monkeypatch):
    import egtviz.servo.cli as servo_cli

    high = int(limits.SERVO_HEADLESS_STEPS.high)
    assert build_parser().parse_args(["servo", "pinhole", "--steps", str(high)]).steps == high
    assert build_parser().parse_args(["servo", "panoramic", "--steps", "1"]).steps == 1
    monkeypatch.setattr(servo_cli, "_simulate", lambda *a: pytest.fail("the simulation must not start"))
    for bad in (0, high + 1):
        assert main(["servo", "pinhole", "--steps", str(bad)]) == 2
        assert f"--steps: expected a whole number in 1..100000, got {bad}" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        build_parser().parse_args(["servo", "--help"])
    assert "maximum number of steps, 1..100000" in " ".join(capsys.readouterr().out.split())


def test_the_demos_max_steps_field_takes_its_whole_range_and_names_it_when_refusing():
    rule = RUN_RULES["steps"]
    assert (rule.lo, rule.hi, rule.integer) == (1, 10_000, True)
    assert parse_numbers("10000", (rule,)) == (10_000,)
    with pytest.raises(FieldError, match="max steps must be between 1 and 10000, got 10001"):
        parse_numbers("10001", (rule,))


def test_a_lessons_open_demo_takes_the_demos_range():
    # A lesson's run is played by the same demo, so it may ask for what the demo's field accepts, not more.
    high = int(limits.SERVO_DEMO_STEPS.high)
    for demo in ("pinhole", "panoramic"):
        assert dict(parse_run_fields({"steps": high}, demo))["steps"] == high
        with pytest.raises(EntryError, match="1..10000"):
            parse_run_fields({"steps": high + 1}, demo)
