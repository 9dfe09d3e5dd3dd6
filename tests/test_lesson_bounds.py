"""A small lesson or scene file cannot make ``egtviz check`` (or the server loading it) work for minutes.

Each bound is checked before the work it bounds: the TOML text is scanned before ``tomllib`` parses it, the
changes are counted before any is applied, a servo run is counted before it is simulated, a JSON scene's nesting
is read before ``json`` parses it. The tests make the expensive step fail if it is reached; no test is timed.
"""

from __future__ import annotations

import glob
import json
import tomllib
from pathlib import Path

import pytest

import egtviz.lessons.format as lesson_format
import egtviz.lessons.servo_runs as servo_runs
from egtviz.lessons import LessonError, parse_lesson
from egtviz.lessons.bounds import check_lesson_work, check_toml_text
from egtviz.lessons.cli import check_file
from egtviz.lessons.locate import toml_locator
from egtviz.scene import SceneFileError, scene_from_bytes
from egtviz.scene.limits import (
    MAX_CHANGES,
    MAX_LESSON_CHANGES,
    MAX_LESSON_KEY_PARTS,
    MAX_LESSON_KEYS,
    MAX_LESSON_NESTING,
    MAX_LESSON_POINTS,
    MAX_LESSON_SERVO_STEPS,
)

LESSONS = sorted(glob.glob(str(Path(__file__).resolve().parent.parent / "lessons" / "*.toml")))

HEAD = 'title = "Bounds"\nsummary = "For the tests."\nscene = "default"\n'


def step(body: str = "", title: str = "S") -> str:
    return f'\n[[steps]]\ntitle = "{title}"\ntext = "Look."\n{body}'


@pytest.fixture
def no_parsing(monkeypatch):
    """tomllib must not be reached: the scan refuses the text first."""

    def fail(*args, **kwargs):
        raise AssertionError("tomllib.loads was called")

    monkeypatch.setattr(lesson_format.tomllib, "loads", fail)


@pytest.fixture
def no_loading(monkeypatch):
    """No change may be applied and no servo run simulated: the counts refuse the lesson first."""

    def fail(*args, **kwargs):
        raise AssertionError("the lesson was loaded")

    monkeypatch.setattr(lesson_format, "apply_change", fail)
    monkeypatch.setattr(servo_runs, "simulate_pinhole", fail)
    monkeypatch.setattr(servo_runs, "simulate_panoramic", fail)


def refused(text: str) -> LessonError:
    with pytest.raises(LessonError) as info:
        parse_lesson(text.encode(), source="b.toml", name="01-bounds")
    return info.value


# -- before parsing -----------------------------------------------------------------------------------


def test_a_dotted_key_of_thousands_of_parts_is_refused_before_it_is_parsed(no_parsing):
    text = HEAD + "x" + ".a" * 30_000 + " = 1\n" + step()  # 60 kB: minutes and gigabytes in tomllib
    err = refused(text)
    assert (err.line, err.reason) == (4, f"a dotted key of more than {MAX_LESSON_KEY_PARTS} parts "
                                         f"(a lesson's keys have at most {MAX_LESSON_KEY_PARTS})")


def test_a_deep_table_header_is_refused_before_it_is_parsed(no_parsing):
    err = refused(HEAD + step() + "\n[[" + ".".join(["steps"] + ["a"] * 9) + "]]\n")
    assert err.line == 9 and err.reason.startswith(f"a table header of more than {MAX_LESSON_KEY_PARTS} parts")


@pytest.mark.parametrize("value", ["[" * 9 + "]" * 9, "{a = " * 9 + "1" + "}" * 9, "[{a = [{b = [[[[[1]]]]]}]}]"])
def test_values_nested_too_deeply_are_refused_before_they_are_parsed(value, no_parsing):
    err = refused(HEAD + "deep = " + value + "\n" + step())
    assert (err.line, err.reason) == (4, f"arrays and inline tables nested more than {MAX_LESSON_NESTING} levels deep")


def test_inline_tables_keys_are_bounded_too(no_parsing):
    err = refused(HEAD + "x = { " + ".".join("k" * 9) + " = 1 }\n" + step())
    assert err.line == 4 and "dotted key of more than" in err.reason


def test_too_many_keys_are_refused_before_the_file_is_parsed(no_parsing):
    keys = "".join(f"k{i} = {i}\n" for i in range(MAX_LESSON_KEYS))
    err = refused(HEAD + keys)  # the head's three keys come first
    assert err.line == 3 + MAX_LESSON_KEYS - 2
    assert err.reason == f"more than {MAX_LESSON_KEYS} keys and tables in the file"


def test_keys_in_strings_and_comments_are_not_counted():
    """The scan follows TOML's strings: what looks like a deep key or a bracket inside one is text."""
    deep = "a" + ".a" * 20 + " = [[[[[[[[[[[[[["
    text = (HEAD + f"# {deep}\n" + step().replace('text = "Look."', f"text = '''\n{deep}\n'''")
            + f'\n[[steps.tasks]]\nkind = "number"\nprompt = "{deep}"\nanswer = 1\nhint = """{deep}\\""""\n')
    check_toml_text(text, "s.toml")  # no refusal
    assert tomllib.loads(text)["steps"][0]["tasks"][0]["hint"] == deep + '"'


def test_text_that_is_not_toml_is_left_to_the_parser_to_report():
    err = refused(HEAD + "x = [1, 2\n" + step())
    assert err.reason.startswith("not valid TOML")


# -- before loading -------------------------------------------------------------------------------------


def test_a_solution_of_thousands_of_changes_is_refused_before_one_is_applied(no_loading):
    solution = ", ".join(['{ do = "show", what = "rays" }'] * 2000)
    task = f'\n[[steps.tasks]]\nkind = "number"\nprompt = "How many?"\nanswer = 1\nsolution = [{solution}]\n'
    text = HEAD + step(task)
    err = refused(text)
    assert err.line == text.splitlines().index(f"solution = [{solution}]") + 1
    assert err.reason == (f"steps[0].tasks[0].solution: 2000 changes, more than the {MAX_CHANGES} one solution "
                          "may make")


def test_a_step_of_too_many_changes_is_refused_at_the_first_change_too_many(no_loading):
    change = '\n[[steps.changes]]\ndo = "show"\nwhat = "rays"\n'
    text = HEAD + step(change * (MAX_CHANGES + 1))
    err = refused(text)
    assert err.line == [i for i, s in enumerate(text.splitlines(), 1) if s == "[[steps.changes]]"][MAX_CHANGES]
    assert err.reason == f"steps[0].changes: {MAX_CHANGES + 1} changes, more than the {MAX_CHANGES} one step may make"


def test_the_points_a_lesson_places_are_bounded_before_any_is_placed(no_loading):
    """60 steps of 100 `random_points n = 2000` (35 kB) took 105 s to load."""
    change = '\n[[steps.changes]]\ndo = "random_points"\nn = 2000\n'
    text = HEAD + "".join(step(change * 100, title=f"S{i}") for i in range(60))
    err = refused(text)
    headers = [i for i, s in enumerate(text.splitlines(), 1) if s == "[[steps.changes]]"]
    first_over = MAX_LESSON_POINTS // 2000  # 0-based: the change that brings the total above the limit
    assert err.line == headers[first_over]
    assert err.reason == (f"steps[0].changes[{first_over}]: the lesson's changes place more than "
                          f"{MAX_LESSON_POINTS} points in all ({(first_over + 1) * 2000} so far)")


def test_the_changes_of_a_whole_lesson_are_bounded_solutions_included(no_loading):
    change = '\n[[steps.changes]]\ndo = "show"\nwhat = "rays"\n'
    steps = MAX_LESSON_CHANGES // MAX_CHANGES
    text = HEAD + "".join(step(change * MAX_CHANGES, title=f"S{i}") for i in range(steps))
    text += step('\n[[steps.tasks]]\nkind = "number"\nprompt = "?"\nanswer = 1\n'
                 'solution = [{ do = "show", what = "rays" }]\n')
    err = refused(text)
    assert err.line == text.splitlines().index('solution = [{ do = "show", what = "rays" }]') + 1
    assert err.reason == (f"steps[{steps}].tasks[0].solution[0]: more than {MAX_LESSON_CHANGES} changes in the lesson "
                          "(its steps' changes and its tasks' solutions)")


def test_the_servo_runs_a_lesson_measures_are_bounded_before_they_are_simulated(monkeypatch):
    simulated = []
    real = servo_runs.simulate_pinhole
    monkeypatch.setattr(servo_runs, "simulate_pinhole", lambda **kw: simulated.append(kw) or real(**kw))
    servo_runs.simulate.cache_clear()
    run_steps = MAX_LESSON_SERVO_STEPS // 2 + 1

    def servo_step(seed: int) -> str:
        return step(f'\n[[steps.changes]]\ndo = "open_demo"\ndemo = "pinhole"\nseed = {seed}\nsteps = {run_steps}\n'
                    '\n[[steps.tasks]]\nkind = "servo_number"\nprompt = "How long?"\nmeasure = "sim_time"\n')

    text = HEAD + servo_step(1) + servo_step(2)
    try:
        err = refused(text)
    finally:
        servo_runs.simulate.cache_clear()
    assert [kw["seed"] for kw in simulated] == [1]  # the second run was refused, not simulated
    assert err.line == [i for i, s in enumerate(text.splitlines(), 1) if s == "[[steps.tasks]]"][1]
    assert err.reason.startswith(f"steps[1].tasks[0]: the lesson's servo_number tasks measure runs of "
                                 f"{2 * run_steps:,} steps in all, more than the {MAX_LESSON_SERVO_STEPS:,}")


@pytest.mark.parametrize("path", LESSONS, ids=lambda p: Path(p).stem)
def test_the_course_stays_well_inside_every_bound(path, monkeypatch):
    """Each of the course's lessons passes with every bound cut to a fifth (the bounds leave room to write)."""
    import egtviz.lessons.bounds as bounds

    text = Path(path).read_text(encoding="utf-8")
    for name in ("MAX_LESSON_KEYS", "MAX_LESSON_CHANGES", "MAX_LESSON_POINTS", "MAX_CHANGES"):
        monkeypatch.setattr(bounds, name, getattr(bounds, name) // 5)
    monkeypatch.setattr(bounds, "MAX_LESSON_KEY_PARTS", 2)
    monkeypatch.setattr(bounds, "MAX_LESSON_NESTING", 3)
    monkeypatch.setattr(lesson_format, "MAX_LESSON_SERVO_STEPS", MAX_LESSON_SERVO_STEPS // 5)
    check_toml_text(text, path)
    check_lesson_work(tomllib.loads(text)["steps"], path, toml_locator(text))
    assert check_file(path) is None


# -- scene files ----------------------------------------------------------------------------------------


def test_a_scene_file_nested_too_deeply_is_refused_before_json_parses_it(monkeypatch, tmp_path):
    import egtviz.scene.io as scene_io

    def fail(*args, **kwargs):
        raise AssertionError("json.loads was called")

    monkeypatch.setattr(scene_io.json, "loads", fail)
    data = b'{\n  "title": "[[[[[[[[[[ in a string \\" [[[[[[[[[[",\n  "points":\n    ' + b"[" * 9 + b"]" * 9 + b"\n}"
    with pytest.raises(SceneFileError, match=r"^s\.json: line 4: lists or objects nested more than 8 levels deep$"):
        scene_from_bytes(data, "s.json")
    f = tmp_path / "deep.json"
    f.write_bytes(data)
    assert check_file(str(f)) == f"{f}:4: line 4: lists or objects nested more than 8 levels deep"


def test_brackets_in_a_scene_files_strings_do_not_count(monkeypatch):
    text = json.dumps({"title": "[[[[[[[[[[ \\\" {{{{{{{{{{", "cameras": [{"kind": "pinhole", "name": "c"}],
                       "points": [[0, 5, 0]]})
    assert scene_from_bytes(text.encode(), "ok.json").title == "[[[[[[[[[[ \\\" {{{{{{{{{{"
