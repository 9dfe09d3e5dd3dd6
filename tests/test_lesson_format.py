"""Lesson files: every malformed file is refused with its file, the right line and a reason; never a traceback.

Also the Markdown/MathML rendering (nothing but MathML becomes HTML) and ``egtviz check`` on lesson and
scene files.
"""

from __future__ import annotations

import argparse
import json
import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from egtviz.lessons import LessonError, load_lesson, parse_lesson
from egtviz.lessons.cli import add_check_arguments, check_file, run_check
from egtviz.lessons.locate import json_locator, scene_entry_path, toml_locator
from egtviz.lessons.markup import MarkupError, render_markdown

GOOD = """\
title = "A lesson"
summary = "For the tests."
scene = "default"

[[steps]]
title = "First"
text = '''
The constraint $m_2^T F m_1 = 0$.
'''

[[steps]]
title = "Second"
text = "Move it."

[[steps.changes]]
do = "move"
camera = "cam2"
position = [3, -7, 2]

[[steps.tasks]]
id = "pinned"
kind = "epipole_near"
prompt = "Put e1 at ({u}, {v})."
camera = "cam1"
target = { u = [100, 540], v = [80, 400] }
within_px = 3
"""


def parse(text: str, name: str = "01-test"):
    return parse_lesson(text.encode(), source="t.toml", name=name, known_lessons=frozenset({"00-first"}))


def refused(text: str) -> LessonError:
    with pytest.raises(LessonError) as info:
        parse(text)
    return info.value


def line_of(text: str, fragment: str, occurrence: int = 1) -> int:
    """1-based line of the ``occurrence``-th line containing ``fragment``: the expected line, counted by hand."""
    hits = [i for i, line in enumerate(text.splitlines(), 1) if fragment in line]
    return hits[occurrence - 1]


def test_a_good_lesson_parses_with_its_steps_changes_and_tasks():
    lesson = parse(GOOD)
    assert lesson.title == "A lesson" and len(lesson.steps) == 2
    assert "<math" in lesson.steps[0].html and "$" not in lesson.steps[0].html
    (change,) = lesson.steps[1].changes
    assert change.camera == "cam2" and change.position == (3.0, -7.0, 2.0)
    (task,) = lesson.steps[1].tasks
    assert task.kind == "epipole_near" and task.id == "pinned"
    assert parse("\ufeff" + GOOD).title == "A lesson"  # a byte-order mark is not an error


def test_bad_toml_names_the_line_of_the_syntax_error():
    text = GOOD.replace('title = "Second"', 'title = "Second')
    err = refused(text)
    assert err.line == line_of(text, 'title = "Second') and "not valid TOML" in err.reason
    assert str(err).startswith(f"t.toml:{err.line}: ")


def test_unknown_task_kind_points_at_its_kind_key():
    text = GOOD.replace('kind = "epipole_near"', 'kind = "telepathy"')
    err = refused(text)
    assert err.line == line_of(text, 'kind = "telepathy"')
    assert "unknown task kind 'telepathy'" in err.reason and "epipole_near" in err.reason


def test_a_change_naming_a_missing_camera_points_at_the_camera_key():
    text = GOOD.replace('camera = "cam2"', 'camera = "cam9"')
    err = refused(text)
    assert err.line == line_of(text, 'camera = "cam9"')
    assert "no camera named 'cam9'" in err.reason and "steps[1].changes[0]" in err.reason


def test_a_task_naming_a_missing_camera_points_at_the_task_key():
    text = GOOD.replace('camera = "cam1"', 'camera = "nobody"')
    err = refused(text)
    assert err.line == line_of(text, 'camera = "nobody"') and "no camera named 'nobody'" in err.reason


def test_a_task_naming_a_missing_point_is_refused():
    text = GOOD + '\n[[steps.tasks]]\nid = "p"\nkind = "point_in_image"\nprompt = "x"\npoint = 8\ncamera = "cam1"\n'
    err = refused(text)
    assert err.line == line_of(text, "point = 8") and "no point 8" in err.reason


@pytest.mark.parametrize(
    ("old", "new", "fragment", "words"),
    [
        ("within_px = 3", "within_px = 1e9", "within_px = 1e9", "within_px: expected a number in 0.001..10000 px"),
        ("position = [3, -7, 2]", "position = [3, -7, 2e7]", "position = [3, -7, 2e7]", "-10000..10000 m"),
        ("u = [100, 540]", "u = [100, 5e9]", "target = ", "-100000..100000 px"),
        ("within_px = 3", "within_px = true", "within_px = true", "got True"),
        ("within_px = 3", "within_px = 99999999999999999999999999999999", "within_px = 9999", "expected a number"),
    ],
)
def test_absurd_values_are_refused_through_the_shared_limits(old, new, fragment, words):
    text = GOOD.replace(old, new)
    err = refused(text)
    assert err.line == line_of(text, fragment)
    assert words in err.reason


def test_absurd_values_in_a_scene_table_are_refused_by_the_scene_layer_at_their_line():
    text = GOOD.replace('scene = "default"', """[scene]
title = "two cameras"
points = [[0, 0, 1], [1, 0, 1]]

[[scene.cameras]]
kind = "pinhole"
name = "cam1"

[[scene.cameras]]
kind = "pinhole"
name = "cam2"
position = [1, -5, 1]
focal_length = 50
""")
    err = refused(text)
    assert err.line == line_of(text, "focal_length = 50")
    assert "cameras[1]: camera 'cam2': focal_length: expected 0.0001..10 m, got 50" in err.reason


def test_a_scene_table_with_an_unknown_entry_is_refused():
    text = GOOD.replace('scene = "default"', '[scene]\ntitle = "x"\ncolour = "red"\n')
    err = refused(text)
    assert err.line == line_of(text, "colour") and "colour: unknown entry" in err.reason


def test_an_unknown_built_in_scene_is_refused():
    err = refused(GOOD.replace('scene = "default"', 'scene = "nowhere"'))
    assert err.line == 3 and "built-in scene" in err.reason and "example1" in err.reason


@pytest.mark.parametrize(
    ("old", "new", "fragment", "words"),
    [
        ('title = "A lesson"', 'title = "A lesson"\nauthor = "me"', "author", "author: unknown key for a lesson"),
        ('text = "Move it."', 'text = "Move it."\nvideo = "x"', "video", "video: unknown key for a step"),
        ('position = [3, -7, 2]', 'position = [3, -7, 2]\nspeed = 1', "speed", "speed: unknown key for a 'move' change"),
        ('do = "move"', 'do = "teleport"', 'do = "teleport"', "do: expected one of show, hide, move"),
        ('within_px = 3', 'within_px = 3\nwithin_deg = 3', "within_deg", "within_deg: unknown key for a 'epipole_near'"),
        ('prompt = "Put e1 at ({u}, {v})."', 'prompt = "Put e1 at ({u.__class__})."', "prompt =", "placeholder {u.__class__}"),
        ('prompt = "Put e1 at ({u}, {v})."', 'prompt = "Put e1 at ({w})."', "prompt =", "placeholder {w}: expected one of {u}, {v}"),
        # A formula is refused at its own line inside a multi-line text, not at the text's key.
        ("The constraint $m_2^T F m_1 = 0$.", "The constraint $\\nonsense x$.", "nonsense", "unknown LaTeX command"),
        ("The constraint $m_2^T F m_1 = 0$.", "It costs $5.", "It costs", "never closed"),
    ],
)
def test_unknown_keys_kinds_placeholders_and_formulas_are_refused_at_their_line(old, new, fragment, words):
    text = GOOD.replace(old, new)
    assert text != GOOD
    err = refused(text)
    assert words in err.reason
    assert err.line == line_of(text, fragment)


def test_the_second_of_two_tasks_with_one_id_is_refused_at_its_table():
    text = GOOD + '\n[[steps.tasks]]\nid = "pinned"\nkind = "number"\nprompt = "x"\nanswer = 1\n'
    err = refused(text)
    assert err.line == line_of(text, 'id = "pinned"', 2) and "another task of this step has the id 'pinned'" in err.reason


def test_a_solution_that_does_not_apply_is_refused():
    text = GOOD + (
        '\n[[steps.tasks]]\nid = "s"\nkind = "point_in_image"\nprompt = "x"\npoint = 1\ncamera = "cam1"\n'
        'solution = [{ do = "move", camera = "cam7", position = [0, 0, 0] }]\n'
    )
    err = refused(text)
    assert err.line == line_of(text, "solution =") and "no camera named 'cam7'" in err.reason


def test_prerequisites_must_name_known_lessons():
    text = GOOD.replace('scene = "default"', 'scene = "default"\nprerequisites = ["00-first", "99-missing"]')
    err = refused(text)
    assert err.line == line_of(text, "prerequisites") and "no lesson named '99-missing'" in err.reason
    assert parse(GOOD.replace('scene = "default"', 'scene = "default"\nprerequisites = ["00-first"]')).prerequisites == ("00-first",)


def test_lab_tasks_need_a_pinhole_pair_with_enough_points():
    text = GOOD.replace('scene = "default"', 'scene = "panoramic"').replace('camera = "cam2"', 'camera = "pano2"')
    text = text.replace('camera = "cam1"', 'camera = "pano1"')
    text += '\n[[steps.tasks]]\nid = "lab"\nkind = "sampson_below"\nprompt = "x"\nmethod = "ransac"\nbelow_px2 = 1\n'
    err = refused(text)
    assert err.line == line_of(text, 'id = "lab"') - 1 and "pin-hole" in err.reason


def test_files_that_are_not_utf8_or_too_large_are_refused(tmp_path):
    bad = tmp_path / "02-bytes.toml"
    bad.write_bytes(b'title = "x"\nsummary = "\xff"\n')
    with pytest.raises(LessonError, match=r"02-bytes.toml:2: not UTF-8 text"):
        load_lesson(bad)
    big = tmp_path / "03-big.toml"
    big.write_bytes(b"#" * 1_000_001)
    with pytest.raises(LessonError, match=r"03-big.toml:1: .*limit"):
        load_lesson(big)
    with pytest.raises(LessonError, match=r"04-none.toml:1: no such file"):
        load_lesson(tmp_path / "04-none.toml")


def test_a_lesson_without_steps_or_scene_is_refused():
    assert "steps: expected 1 to" in refused('title = "x"\nsummary = "y"\nscene = "default"\n').reason
    assert "scene: missing" in refused('title = "x"\nsummary = "y"\n[[steps]]\ntitle = "a"\ntext = "b"\n').reason


# -- locating ------------------------------------------------------------------------------------------


def test_the_toml_locator_counts_arrays_of_tables_per_parent_and_skips_multiline_strings():
    text = "a = 1\n[[steps]]\ntext = '''\n[[steps]]\nx = 1\n'''\n[[steps.tasks]]\nk = 1\n[[steps]]\n[[steps.tasks]]\n[[steps.tasks]]\nk = 2\n"
    where = toml_locator(text)
    assert where.line("a") == 1
    assert where.line("steps", 0) == 2 and where.line("steps", 0, "text") == 3
    assert where.line("steps", 0, "tasks", 0, "k") == 8
    assert where.line("steps", 1) == 9 and where.line("steps", 1, "tasks", 1, "k") == 12
    assert where.line("steps", 1, "tasks", 1, "missing") == 11  # falls back to the table
    assert where.line("nowhere") == 1


def test_the_json_locator_and_scene_entry_paths():
    text = '{\n "cameras": [\n  {"kind": "pinhole",\n   "focal_length": 3}],\n "points": [[1, 2, 3],\n  [4, 5, 6]]\n}'
    where = json_locator(text)
    assert where.line("cameras", 0, "focal_length") == 4
    assert where.line("points", 1) == 6
    assert scene_entry_path("cameras[1]: camera 'c': focal_length: expected") == ("cameras", 1, "focal_length")
    assert scene_entry_path("points[3]: expected three numbers") == ("points", 3)
    assert scene_entry_path("cameras[0].kind: expected one of") == ("cameras", 0, "kind")


# -- markup --------------------------------------------------------------------------------------------


def test_html_in_a_step_is_written_as_text_and_formulas_become_mathml():
    out = render_markdown("a <script>alert(1)</script> & $x < y$ and `a<b`")
    assert "<script>" not in out and "&lt;script&gt;" in out and "&amp;" in out
    assert re.search(r"<math[^>]*display=\"inline\"[^>]*><mrow><mi>x</mi><mo>&lt;</mo><mi>y</mi></mrow></math>", out)
    # Code is an element whose text is all character references: neither HTML nor Markdown syntax.
    assert "<code>a&#60;b</code>" in out


def test_display_formulas_and_escaped_dollars():
    out = render_markdown("cost \\$5\n\n$$E = [t]_\\times R$$")
    assert "\\$5" in out and 'display="block"' in out and "<mo>×</mo>" in out


@pytest.mark.parametrize("bad", ["$\\text{<b>x</b>}$", "$\\unknowncommand{x}$", "one $ only"])
def test_formulas_that_could_inject_html_or_do_not_render_are_refused(bad):
    with pytest.raises(MarkupError):
        render_markdown(bad)


# -- egtviz check ----------------------------------------------------------------------------------------


def check(paths, capsys):
    parser = argparse.ArgumentParser()
    add_check_arguments(parser)
    status = run_check(parser.parse_args([str(p) for p in paths]))
    return status, capsys.readouterr().out


def test_check_accepts_a_good_lesson_and_a_good_scene(tmp_path, capsys):
    lesson = tmp_path / "01-good.toml"
    lesson.write_text(GOOD)
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"cameras": [{"kind": "pinhole", "name": "c"}], "points": [[0, 5, 0]]}))
    status, out = check([lesson, scene], capsys)
    assert status == 0 and out.splitlines() == [f"{lesson}: ok", f"{scene}: ok"]


def test_check_prints_file_line_reason_for_each_bad_file_and_exits_2(tmp_path, capsys):
    lesson = tmp_path / "01-bad.toml"
    lesson.write_text(GOOD.replace('kind = "epipole_near"', 'kind = "telepathy"'))
    scene = tmp_path / "bad.json"
    scene.write_text('{\n  "cameras": [\n    {"kind": "pinhole", "name": "c"},\n'
                     '    {"kind": "pinhole", "name": "d",\n     "focal_length": 50}\n  ]\n}\n')
    broken = tmp_path / "broken.json"
    broken.write_text('{\n  "cameras": [\n}\n')
    status, out = check([lesson, scene, broken], capsys)
    lines = out.splitlines()
    assert status == 2 and len(lines) == 3
    assert lines[0].startswith(f"{lesson}:{line_of(lesson.read_text(), 'telepathy')}: ")
    assert lines[1] == f"{scene}:5: cameras[1]: camera 'd': focal_length: expected 0.0001..10 m, got 50"
    assert lines[2].startswith(f"{broken}:3: ") and "not valid JSON" in lines[2]
    assert "Traceback" not in out


def test_check_file_refuses_a_directory_without_a_traceback(tmp_path):
    message = check_file(str(tmp_path))
    assert message is not None and message.startswith(f"{tmp_path}:1: ") and "not a regular file" in message


_TOML_VALUES = st.sampled_from([
    "0", "-1", "1e308", "1e-320", "nan", "inf", "-inf", "99999999999999999999999999", "true", '""', '"cam1"',
    '"point:99"', '"\\u001b[31m"', "[]", "[1, 2]", "[1, 2, 3]", '["cam1", "cam1"]', "[[1, 2, 3]]", "{}",
    "{ u = 1 }", "1979-05-27T07:32:00Z", '"$x$"', '"$"', '"{u.__class__}"', "[true, false]",
])


@settings(max_examples=150)
@given(st.data())
def test_any_single_bad_value_gives_a_lesson_error_never_a_traceback(data):
    lines = GOOD.splitlines()
    keyed = [i for i, line in enumerate(lines) if re.match(r"\w+ = ", line)]
    i = data.draw(st.sampled_from(keyed))
    key = lines[i].split(" = ", 1)[0]
    lines[i] = f"{key} = {data.draw(_TOML_VALUES)}"
    text = "\n".join(lines) + "\n"
    try:
        parse(text)
    except LessonError as err:
        assert err.line >= 1 and err.reason and str(err).startswith(f"t.toml:{err.line}: ")


SERVO = GOOD + """
[[steps]]
title = "The demo"
text = "Open it."

[[steps.changes]]
do = "open_demo"
demo = "pinhole"
seed = 0
beta = 0

[[steps.tasks]]
id = "when"
kind = "servo_number"
prompt = "When?"
measure = "rotation_below_time"
below = 0.1
tolerance = 0.1
"""


def test_a_servo_step_parses_with_its_demo_and_task():
    lesson = parse(SERVO)
    (opened,) = lesson.steps[2].changes
    assert opened.demo == "pinhole" and opened.options() == {"beta": 0.0, "seed": 0}
    (t,) = lesson.steps[2].tasks
    assert t.kind == "servo_number" and t.question and t.answer_for(opened) > 0


@pytest.mark.parametrize(
    ("old", "new", "fragment", "words"),
    [
        ('demo = "pinhole"', 'demo = "drone"', 'demo = "drone"', "demo: expected one of pinhole, panoramic"),
        ("beta = 0", "beta = -1", "beta = -1", "beta: expected a number in 0..100"),
        ('demo = "pinhole"', 'demo = "panoramic"', "beta = 0", "beta: unknown key for an 'open_demo' change"),
        ('measure = "rotation_below_time"', 'measure = "joy"', 'measure = "joy"', "measure: expected one of steps"),
        ("below = 0.1", "below = 0.1\nunit = 's'", "unit = 's'", "unit: unknown key for a 'servo_number' task"),
        ('measure = "rotation_below_time"', 'measure = "translation_phase_time"', "below = 0.1",
         "below: 'translation_phase_time' takes no 'below'"),
        # beta = 0 leaves the translation alone: the run never comes within 1 cm.
        ('measure = "rotation_below_time"\nbelow = 0.1', 'measure = "translation_below_time"\nbelow = 1',
         "below = 1", "never gets there"),
        ('do = "open_demo"\ndemo = "pinhole"\nseed = 0\nbeta = 0', 'do = "hide"\nwhat = "rays"', ("[[steps.tasks]]", 2),
         "a servo_number task needs an open_demo change in its step or an earlier one"),
    ],
)
def test_malformed_servo_steps_are_refused_at_their_line(old, new, fragment, words):
    text = SERVO.replace(old, new)
    assert text != SERVO
    err = refused(text)
    assert words in err.reason, err.reason
    at = fragment if isinstance(fragment, tuple) else (fragment,)
    assert err.line == line_of(text, *at), (err.line, err.reason)


def test_markdown_syntax_inside_formulas_is_quoted_so_the_markdown_cannot_break_them():
    """Two \\tilde (or two '*', '_') in a paragraph would otherwise be read by the viewer's Markdown as a
    strike-through (an emphasis) across the MathML tags."""
    from html import unescape

    html = render_markdown(r"Then $\tilde X_w = H \tilde X_c$ and $a * b * c$, $x_{\_}$.")
    texts = re.findall(r">([^<]+)<", html)
    assert not any(c in t for t in texts for c in "~*_")
    assert "&#126;" in html and "&#42;" in html and "&#95;" in html
    assert unescape("".join(texts)).count("~") == 2 and unescape("".join(texts)).count("*") == 2
