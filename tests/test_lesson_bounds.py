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
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import egtviz.lessons.format as lesson_format
import egtviz.lessons.servo_runs as servo_runs
from egtviz.lessons import LessonError, parse_lesson
from egtviz.lessons.bounds import TomlShape, check_lesson_work, check_toml_text, toml_shape
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


# -- the scan follows TOML --------------------------------------------------------------------------------

_TEXT = list("ab1 []{}#=.,:")


def _basic(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


_STRING = st.one_of(
    st.text(st.sampled_from(_TEXT + ["'", '"', "\\"]), max_size=6).map(_basic),
    st.text(st.sampled_from(_TEXT + ['"', "\\"]), max_size=6).map(lambda s: f"'{s}'"),
    st.text(st.sampled_from(_TEXT + ["\n", "'", '"']), max_size=10).map(
        lambda s: '"""' + s.replace('"', '\\"') + '"""'),
    st.text(st.sampled_from(_TEXT + ["\n", '"']), max_size=10).map(lambda s: f"'''{s}'''"),
)
_SCALAR = st.one_of(
    st.integers(-10**6, 10**6).map(str), st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.sampled_from(["true", "false", "1979-05-27T07:32:00Z", "1979-05-27 07:32:00", "07:32:00", "0x1F", "1_000"]),
    _STRING,
)


def _key(first: str) -> st.SearchStrategy:
    """A dotted key whose first part is ``first`` (unique where it is used): (text, parts)."""
    part = st.one_of(st.from_regex(r"[A-Za-z0-9_-]{1,5}", fullmatch=True),
                     st.text(st.sampled_from(_TEXT), max_size=5).map(_basic),
                     st.text(st.sampled_from(_TEXT), max_size=5).map(lambda s: f"'{s}'"))
    return st.tuples(st.lists(part, max_size=3), st.sampled_from([".", " . "])).map(
        lambda t: (t[1].join([first, *t[0]]), 1 + len(t[0])))


def _arrays(children: st.SearchStrategy) -> st.SearchStrategy:
    def build(items: list, multiline: bool) -> tuple:
        sep, end = (",  # a comment [ {\n  ", ",\n]") if multiline else (", ", "]")
        text = "[" + ("\n  " if multiline else "") + sep.join(i[0] for i in items) + (end if items else "]")
        return (text, 1 + max((i[1] for i in items), default=0), max((i[2] for i in items), default=0),
                sum(i[3] for i in items))

    return st.builds(build, st.lists(children, max_size=3), st.booleans())


def _tables(children: st.SearchStrategy) -> st.SearchStrategy:
    def build(pairs: list) -> tuple:
        text = "{" + ", ".join(f"{k[0]} = {v[0]}" for k, v in pairs) + "}"
        return (text, 1 + max((v[1] for _, v in pairs), default=0),
                max([k[1] for k, _ in pairs] + [v[2] for _, v in pairs], default=0),
                len(pairs) + sum(v[3] for _, v in pairs))

    return st.integers(0, 3).flatmap(
        lambda n: st.tuples(*[st.tuples(_key(f"i{j}"), children) for j in range(n)]).map(list)).map(build)


_VALUE = st.recursive(_SCALAR.map(lambda s: (s, 0, 0, 0)), lambda ch: st.one_of(_arrays(ch), _tables(ch)),
                      max_leaves=8)


@st.composite
def _documents(draw) -> tuple[str, TomlShape]:
    lines, keys, parts, nesting = [], 0, 0, 0
    for i in range(draw(st.integers(1, 6))):
        kind = draw(st.sampled_from(["key", "key", "table", "array", "comment"]))
        if kind == "comment":
            lines.append("# a comment with [brackets] and = signs")
            continue
        if kind in ("table", "array"):
            key, n = draw(_key(f"t{i}"))
            lines.append(f"[{key}]" if kind == "table" else f"[[{key}]]  # a comment")
            keys, parts = keys + 1, max(parts, n)
            continue
        (key, n), value = draw(_key(f"k{i}")), draw(_VALUE)
        lines.append(f"{key} = {value[0]}")
        keys, parts, nesting = keys + 1 + value[3], max(parts, n, value[2]), max(nesting, value[1])
    return "\n".join(lines) + "\n", TomlShape(keys, parts, nesting, complete=True)


@settings(max_examples=200, suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow])
@given(_documents())
def test_the_scan_measures_any_toml_text_exactly_as_it_is_written(document):
    """Strings, comments, multi-line arrays, inline tables, dotted and quoted keys, dates: whatever TOML the
    parser accepts, the scan follows to its end (else the bounds would not hold) and counts what was written."""
    text, shape = document
    try:
        tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        assume(False)
    assert toml_shape(text) == shape
