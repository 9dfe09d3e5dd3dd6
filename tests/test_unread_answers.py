"""An answer that cannot be read (``1,5``, ``0x0E``, ``14_85``, a vector without its brackets) is refused with a
message: it is not a wrong answer, so it is not counted as an attempt and does not open the next hint."""

from __future__ import annotations

import pytest

from egtviz.lessons import LessonRun, ProgressStore, load
from egtviz.lessons.tasks import TaskContext, parse_task
from egtviz.scene import SCENES

from _waiting import PATIENCE

INTRINSICS = "03-intrinsics"  # step 1: "focal-pixels", a number in px (800)
FRAMES = "01-frames-and-poses"


@pytest.mark.parametrize("learner", ["Ada", ""], ids=["named", "anonymous"])
def test_an_unread_number_is_refused_without_counting_an_attempt_or_opening_a_hint(tmp_path, learner):
    store = ProgressStore(tmp_path / "p.sqlite3")
    run = LessonRun(load(INTRINSICS), learner, progress=store)
    for typed, words in (("1,5", "Write the decimals after a point: 1.5, not 1,5."),
                         ("0x0E", "Type one number"), ("14_85", "Type one number")):
        attempt = run.check("focal-pixels", typed)
        assert not attempt.result.passed and attempt.result.unread and words in attempt.result.feedback
        assert attempt.hint is None and attempt.hints_shown == 0
    wrong = run.check("focal-pixels", "900")  # a number, wrong: the first attempt, the first hint
    assert not wrong.result.unread and wrong.hints_shown == 1 and "(1 of 3)" in wrong.hint
    again = run.check("focal-pixels", "800 mm")  # refused: the hint shown so far stays, no next one
    assert again.result.unread and again.hints_shown == 1 and again.hint == wrong.hint
    assert run.check("focal-pixels", "800 px").result.passed
    summary = run.summary()
    assert summary.attempts == 2 and summary.hints == 1
    if learner:
        assert store.attempts(learner, INTRINSICS, 0, "focal-pixels") == 2
        assert store.hints_shown(learner, INTRINSICS, 0, "focal-pixels") == 1
    else:
        assert store.task_records() == []


def test_an_unread_vector_is_refused_and_a_read_one_is_judged():
    run = LessonRun(load(FRAMES), "")
    step = next(i for i, s in enumerate(run.lesson.steps) if any(t.id == "xc" for t in s.tasks))
    run.go_to(step)
    refused = run.check("xc", "1, 2, 3")  # no brackets
    assert refused.result.unread and "Type 3 numbers in brackets" in refused.result.feedback
    assert refused.hints_shown == 0
    judged = run.check("xc", "[1, 2, 3]")
    assert not judged.result.unread and not judged.result.passed and judged.hints_shown == 1


def test_a_wrong_number_or_option_is_read_and_counted():
    number = parse_task({"kind": "number", "prompt": "x", "answer": 1.5, "tolerance": 0.01}, "t1")
    assert not number.check(TaskContext(SCENES["default"](), answer="2"), number.resolve(0)).unread
    assert number.check(TaskContext(SCENES["default"](), answer="1,5"), number.resolve(0)).unread


def test_the_panel_says_an_answer_was_not_read_with_no_verdict_and_keeps_the_hints_shown(tmp_path):
    import viser

    from egtviz.viewer.course.lesson_view import LessonPanel
    from egtviz.viewer.server.headless import FakeTab
    from egtviz.viewer.tabs import EgtvizApp

    store = ProgressStore(tmp_path / "p.sqlite3")
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tab = None
    try:
        app = EgtvizApp(server, field_delay=0.0, course=True, progress=store, lesson=INTRINSICS)
        tab = FakeTab(server.get_port())
        (panel,) = app.course.wait_for_tab(LessonPanel, timeout=PATIENCE)
        panel.learner.value = "Ada"
        row = panel.row("focal-pixels")
        row.answer.value = "900"
        row.button.value = True
        assert row.feedback.content.startswith("**\u2717 Not yet.** 900 px is too high.") and "(1 of 3)" in \
            row.feedback.content
        row.answer.value = "1,5"
        row.button.value = True
        content = row.feedback.content
        assert content.startswith("**Answer not read.** Write the decimals after a point: 1.5, not 1,5.")
        assert "\u2717" not in content and "(1 of 3)" in content and "(2 of 3)" not in content
        assert store.attempts("Ada", INTRINSICS, 0, "focal-pixels") == 1
    finally:
        if tab is not None:
            tab.close()
        server.stop()


def test_checking_a_choice_with_no_option_picked_is_not_an_attempt():
    run = LessonRun(load(FRAMES), "")
    run.go_to(next(i for i, s in enumerate(run.lesson.steps) if any(t.kind == "choice" for t in s.tasks)))
    task = next(t.task for t in run.tasks() if t.task.kind == "choice")
    for typed in (None, "", "(choose an answer)", str(len(task.options) + 1)):
        refused = run.check(task.id, typed)
        assert refused.result.unread and refused.result.feedback == "Pick one of the options."
        assert refused.hints_shown == 0 and refused.hint is None
    wrong = next(o for o in task.options if o != task.answer)
    judged = run.check(task.id, wrong)
    assert not judged.result.unread and not judged.result.passed and judged.hints_shown == 1


def test_egtviz_check_refuses_a_counter_example_the_check_cannot_read():
    from egtviz.lessons import LessonError
    from egtviz.lessons.format import parse_lesson
    from egtviz.lessons.proof import prove_counter_examples

    text = '''title = "T"
summary = "S"
scene = "default"

[[steps]]
title = "Step"
text = "Text."

[[steps.tasks]]
id = "rank"
kind = "number"
prompt = "Rank?"
answer = 2

[[steps.tasks.counter_examples]]
why = "a typo that proves nothing about the check"
answer = "2,0"
'''
    lesson = parse_lesson(text, source="q.toml", name="q")
    with pytest.raises(LessonError, match=r"^q.toml:15: task rank: counter-example 1 is not read as an answer: "
                                          r"Write the decimals after a point: 2.0, not 2,0. \["):
        prove_counter_examples(lesson, learners=("",))
    prove_counter_examples(parse_lesson(text.replace('"2,0"', '"3"'), source="q.toml", name="q"), learners=("",))
