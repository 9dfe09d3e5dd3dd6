"""Hints in tiers: the idea, a pointer, the answer, one more shown after each failed attempt of a task, counted
per learner, lesson, step and task in the progress database; ``hint`` as one text or a list of up to three, and
the lesson's summary at its last step (tasks passed, attempts, hints used, the next lesson)."""

from __future__ import annotations

import tomllib

import pytest

from egtviz.lessons import LessonError, LessonRun, ProgressStore, parse_lesson
from egtviz.lessons.catalog import lessons_folder
from egtviz.lessons.cli import check_file
from egtviz.lessons.runner import next_lesson_title

SHORT = """\
title = "Short"
summary = "For the tests."
scene = "default"

[[steps]]
title = "One"
text = "Count."

[[steps.tasks]]
id = "two"
kind = "number"
prompt = "How many cameras are there?"
hint = ["IDEA: look at the scene.", "POINTER: count the frustums.", "ANSWER: 2."]
answer = 2
tolerance = 0.01

[[steps]]
title = "Two"
text = "Again."

[[steps.tasks]]
id = "five"
kind = "number"
prompt = "Five?"
hint = "ONLY: five."
answer = 5
tolerance = 0.01

[[steps.tasks]]
id = "pick"
kind = "choice"
prompt = "Pick y."
options = ["x", "y"]
answer = "y"
"""


def short(text: str = SHORT):
    return parse_lesson(text.encode(), source="t.toml", name="01-short")


def test_a_hint_is_one_text_or_a_list_of_up_to_three():
    lesson = short()
    assert lesson.steps[0].tasks[0].hint == ("IDEA: look at the scene.", "POINTER: count the frustums.", "ANSWER: 2.")
    assert lesson.steps[1].tasks[0].hint == ("ONLY: five.",)
    assert lesson.steps[1].tasks[1].hint == ()


@pytest.mark.parametrize("bad, words", [
    ('["a", "b", "c", "d"]', "hint: expected a text or a list of 1 to 3 texts"),
    ("[]", "hint: expected a text or a list of 1 to 3 texts"),
    ('["a", 3]', "hint: tier 2: expected text, got 3"),
    ('["a", " "]', "hint: tier 2: expected text (it is empty)"),
    ('["a", "$\\\\frac{1}{$"]', "hint:"),
])
def test_egtviz_check_refuses_a_bad_hint_list_at_its_line(tmp_path, bad, words):
    text = SHORT.replace('["IDEA: look at the scene.", "POINTER: count the frustums.", "ANSWER: 2."]', bad)
    path = tmp_path / "01-short.toml"
    path.write_text(text)
    line = next(i for i, row in enumerate(text.splitlines(), 1) if row.startswith("hint = " + bad[:2]))
    message = check_file(str(path))
    assert message is not None and message.startswith(f"{path}:{line}: ") and words in message, message
    with pytest.raises(LessonError):
        short(text)


def test_one_more_tier_after_each_failed_attempt_counted_in_the_database(tmp_path):
    path = tmp_path / "progress.sqlite3"
    run = LessonRun(short(), "Ada", progress=ProgressStore(path))
    first = run.check("two", "1")
    assert first.hints_shown == 1 and "IDEA" in first.hint and "POINTER" not in first.hint
    assert "(1 of 3)" in first.hint
    second = run.check("two", "3")
    assert second.hints_shown == 2 and "IDEA" in second.hint and "POINTER" in second.hint
    assert "ANSWER" not in second.hint
    assert ProgressStore(path).hints_shown("Ada", "01-short", 0, "two") == 2
    # A reload (a new run on the same file): the tiers already earned stay shown, the next failure adds the last.
    again = LessonRun(short(), "Ada", progress=ProgressStore(path))
    third = again.check("two", "0")
    assert third.hints_shown == 3 and "ANSWER: 2." in third.hint
    fourth = again.check("two", "7")
    assert fourth.hints_shown == 3 and fourth.hint.count("**Hint:**") == 3  # no tier past the last
    passed = again.check("two", "2")
    assert passed.result.passed and passed.hint is None and passed.hints_shown == 3
    store = ProgressStore(path)
    assert store.hints_shown("Ada", "01-short", 0, "two") == 3 and store.attempts("Ada", "01-short", 0, "two") == 5


def test_an_anonymous_learner_gets_the_tiers_too_and_nothing_is_recorded(tmp_path):
    store = ProgressStore(tmp_path / "progress.sqlite3")
    run = LessonRun(short(), "", progress=store)
    assert "POINTER" not in run.check("two", "1").hint
    assert "POINTER" in run.check("two", "1").hint
    assert store.task_records() == []


def test_a_single_text_hint_is_one_tier_shown_after_the_first_failure():
    run = LessonRun(short(), "")
    run.next()
    attempt = run.check("five", "4")
    assert attempt.hints_shown == 1 and attempt.hint == "**Hint:** ONLY: five."
    assert run.check("pick", "x").hint is None and run.check("pick", "x").hints_shown == 0  # no hint, none counted


@pytest.mark.parametrize("learner", ["Ada", ""])
def test_the_summary_after_a_scripted_walk(tmp_path, learner):
    run = LessonRun(short(), learner, progress=ProgressStore(tmp_path / "p.sqlite3"))
    assert not run.on_last_step
    for answer in ("1", "3", "2"):  # two failures (two hints), then passed
        run.check("two", answer)
    run.next()
    assert run.on_last_step
    summary = run.summary()
    assert (summary.tasks, summary.passed, summary.attempts, summary.hints) == (3, 1, 3, 2)
    run.check("five", "4")
    run.check("five", "5")
    run.check("pick", "y")
    summary = run.summary()
    assert (summary.tasks, summary.passed, summary.attempts, summary.hints) == (3, 3, 6, 3)
    assert summary.next_title is None  # not a shipped lesson: nothing follows it
    assert summary.markdown() == ("**End of the lesson.** Tasks passed: 3 of 3; attempts: 6; hints used: 3; "
                                  "this was the last lesson.")


def test_the_next_lesson_is_the_next_shipped_file_and_the_last_has_none():
    names = sorted(p.stem for p in lessons_folder().glob("*.toml"))
    title = tomllib.loads((lessons_folder() / f"{names[6]}.toml").read_text())["title"]
    assert next_lesson_title(names[5]) == title
    assert next_lesson_title(names[-1]) is None


def _numbers(value) -> list[float]:
    if isinstance(value, bool):
        return []
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, (list, tuple)):
        return [x for v in value for x in _numbers(v)]
    if isinstance(value, dict):
        return [x for v in value.values() for x in _numbers(v)]
    return []


def _given_away(number: float, tier: str, prompt: str) -> bool:
    """Whether ``number`` is written in ``tier`` as a number of its own, and not already in the prompt."""
    import re

    forms = {f"{number:g}", f"{number:.1f}", f"{number:.2f}"} | ({str(int(number))} if number == int(number) else set())
    for form in forms:
        token = re.compile(rf"(?<![\w.]){re.escape(form)}(?![\w]|\.\d)")
        if token.search(tier) and not token.search(prompt):
            return True
    return False


def test_every_shipped_task_has_three_tiers_and_the_first_gives_nothing_away():
    """Read from the files, so the answers and solutions are the ones the author wrote."""
    checked = 0
    for path in sorted(lessons_folder().glob("*.toml")):
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        for step in doc["steps"]:
            for task in step.get("tasks", []):
                where = f"{path.name}: {task.get('id')}"
                hint, prompt = task.get("hint"), task["prompt"]
                assert isinstance(hint, list) and len(hint) == 3, where
                idea = hint[0]
                answer = task.get("answer")
                if isinstance(answer, str):
                    assert answer.lower() not in idea.lower(), where
                elif answer is not None:
                    assert not _given_away(float(answer), idea, prompt), where
                for change in task.get("solution", []):
                    values = {k: v for k, v in change.items() if k not in ("do", "camera", "point", "names", "seed")}
                    assert not any(_given_away(x, idea, prompt) for x in _numbers(values)), (where, change)
                    word = values.get("value")
                    if isinstance(word, str) and word.lower() not in prompt.lower():
                        assert word.lower() not in idea.lower(), (where, change)
                checked += 1
    assert checked >= 80


@pytest.mark.parametrize("lesson, task, words", [
    ("01-frames-and-poses", "roll", "between"),
    ("05-unified-sphere", "horizon-400", "between"),
    ("05-unified-sphere", "xi-zero", "{low}"),
    ("05-unified-sphere", "xi-one", "{high}"),
    ("12-visual-servoing", "reach-x", "{low}"),
    ("13-panoramic-servoing", "drive-y", "{low}"),
])
def test_a_prompt_does_not_write_the_answers_range(lesson, task, words):
    doc = tomllib.loads((lessons_folder() / f"{lesson}.toml").read_text(encoding="utf-8"))
    (prompt,) = [t["prompt"] for s in doc["steps"] for t in s.get("tasks", []) if t.get("id") == task]
    assert words not in prompt
