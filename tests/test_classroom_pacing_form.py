"""The instructor's "up to step" is a step of the chosen lesson or blank: a number beyond the lesson's steps (999)
is refused naming how many steps it has, not taken as "every step" without a word; text, zero, negative numbers
and an overflowing exponent are refused naming the field. The panel says "up to step k of n"."""

from __future__ import annotations

import pytest

from egtviz.controllers.class_state import pacing_view
from egtviz.controllers.class_text import ClassRefusal, paced_step
from egtviz.viewer.classroom.instructor_panel import InstructorPanel
from egtviz.viewer.classroom.room_html import pacing_html

from _waiting import wait_for
from test_classroom_pacing_start import OPEN, classroom  # noqa: F401 - the fixture

STEPS = 6


@pytest.mark.parametrize("text, want", [("", None), ("  ", None), ("1", 0), (" 2 ", 1), ("+3", 2), ("6", 5)])
def test_a_step_of_the_lesson_or_blank_is_taken(text, want):
    assert paced_step(text, "03-intrinsics", STEPS) == want


@pytest.mark.parametrize("text, reason", [
    ("7", "03-intrinsics has 6 steps: type 1 to 6, or leave it blank for every step"),
    ("999", "03-intrinsics has 6 steps: type 1 to 6"),
    ("9" * 5000, "03-intrinsics has 6 steps"),
    ("0", "steps count from 1: type 1 to 6"),
    ("-3", "steps count from 1"),
    ("abc", "expected a step number or blank, got 'abc'"),
    ("1e400", "expected a step number or blank, got '1e400'"),
    ("2.5", "expected a step number or blank"),
    ("nan", "expected a step number or blank"),
])
def test_anything_else_is_refused_naming_the_field(text, reason):
    with pytest.raises(ClassRefusal) as caught:
        paced_step(text, "03-intrinsics", STEPS)
    assert str(caught.value).startswith("up to step: ") and reason in str(caught.value)


def test_the_pacing_says_of_how_many_steps():
    html = pacing_html(pacing_view(frozenset({"03-intrinsics"}), {"03-intrinsics": 1}, {"03-intrinsics": 6}))
    assert "03-intrinsics: up to step 2 of 6" in html and html.count("<br>") == 1


def test_the_panel_refuses_a_step_beyond_the_lesson_and_keeps_the_pacing(classroom):  # noqa: F811
    app, host, _, join = classroom
    cid, fake = join("Ada")
    refused: list[BaseException] = []
    panel = InstructorPanel(app.views[cid].client, host, refused.append)  # the panel only reads and calls the class
    steps = len(app.course.lessons[OPEN].steps)
    host.room.pace(OPEN, 0)
    for field, value in ((panel.lesson, OPEN), (panel.max_step, "999"), (panel.apply_pacing, True)):
        fake.send("GuiUpdateMessage", uuid=field._impl.uuid, updates={"value": value})
    wait_for(lambda: refused, "the panel to refuse step 999")
    assert str(refused[-1]) == (f"up to step: {OPEN} has {steps} steps: type 1 to {steps}, "
                                "or leave it blank for every step")
    assert host.room.pacing() == (None, {OPEN: 0})  # as it was: not silently "every step"
    for field, value in ((panel.max_step, str(steps)), (panel.apply_pacing, True)):
        fake.send("GuiUpdateMessage", uuid=field._impl.uuid, updates={"value": value})
    wait_for(lambda: host.room.pacing() == (None, {OPEN: steps - 1}), f"the class to be paced up to step {steps}")
    panel.refresh()
    assert f"{OPEN}: up to step {steps} of {steps}" in panel.pacing.content
