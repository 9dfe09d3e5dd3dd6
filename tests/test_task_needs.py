"""Each task declares what the lesson page needs for it (``Task.needs``), and the viewer reads only that.

The viewer never names a task class nor tests a task's kind (an AST scan of ``egtviz/viewer``); every shipped
task declares its needs and each declared answer widget has a skin; a new widget is one declaration and one
skin; and the lessons' instruments, read from the declarations, are what the task kinds used to decide."""

from __future__ import annotations

import ast
import dataclasses
import types
from pathlib import Path

import pytest

import egtviz.viewer
from egtviz.lessons import list_lessons, load
from egtviz.lessons.changes import SetLab, SetLens
from egtviz.lessons.instruments import DEFAULT_LAB_FIT, hidden_lens, lesson_needs
from egtviz.lessons.tasks import (
    ANSWER_WIDGETS,
    CHOICE,
    NO_ANSWER,
    TASK_KINDS,
    AnswerNeeds,
    TaskNeeds,
)
from egtviz.scene.lens import LensToggles
from egtviz.viewer.course.answers import SKINS, answer_widget
from egtviz.viewer.course.answers.choice import CHOOSE
from egtviz.viewer.course.answers.registry import skin
from egtviz.viewer.course.lesson_view import TaskRow
from egtviz.controllers.workbench_fields import FieldError

VIEWER = Path(egtviz.viewer.__file__).parent
#: Names the viewer must not use: every task class and the registry of kinds.
TASK_NAMES = frozenset({cls.__name__ for cls in TASK_KINDS.values()} | {"TASK_KINDS"})


#: Kinds the viewer may compare that are no task's, as written: a scene model change's (what the model did).
NOT_A_TASKS_KIND = frozenset({"getattr(change, 'kind', None)"})


def _is_kind(node: ast.AST) -> bool:
    """``x.kind`` or ``getattr(x, "kind")``, but not a numpy dtype's kind (``a.dtype.kind``) nor one of
    :data:`NOT_A_TASKS_KIND`."""
    if isinstance(node, ast.Attribute) and node.attr == "kind":
        return not (isinstance(node.value, ast.Attribute) and node.value.attr == "dtype")
    return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr"
            and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) and node.args[1].value == "kind"
            and ast.unparse(node) not in NOT_A_TASKS_KIND)


def offences(source: str, *, skin_of_lessons: bool) -> list[str]:
    """What ``source`` does that a viewer module must not: name a task class, compare a kind; in the lesson skin
    (``skin_of_lessons``: ``egtviz/viewer/course``) read a kind at all."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            found += [f"line {node.lineno}: imports {a.name}" for a in node.names if a.name in TASK_NAMES]
        elif isinstance(node, ast.Name) and node.id in TASK_NAMES:
            found.append(f"line {node.lineno}: names {node.id}")
        elif isinstance(node, ast.Attribute) and node.attr in TASK_NAMES:
            found.append(f"line {node.lineno}: names {node.attr}")
        elif isinstance(node, ast.Compare) and any(_is_kind(n) for n in (node.left, *node.comparators)):
            found.append(f"line {node.lineno}: compares a kind")
        elif skin_of_lessons and _is_kind(node) and not isinstance(node, ast.Compare):
            found.append(f"line {node.lineno}: reads a kind")
    return found


def test_no_viewer_module_names_a_task_class_or_tests_a_kind():
    found = {}
    for path in sorted(VIEWER.rglob("*.py")):
        rel = path.relative_to(VIEWER)
        bad = offences(path.read_text(encoding="utf-8"), skin_of_lessons=rel.parts[0] == "course")
        if bad:
            found[str(rel)] = bad
    assert found == {}


@pytest.mark.parametrize("source, expected", [
    ("from egtviz.lessons.tasks import ChoiceTask\n", "imports ChoiceTask"),
    ("from egtviz.lessons import tasks\nok = isinstance(t, tasks.ChoiceTask)\n", "names ChoiceTask"),
    ("ok = any(t.kind == 'choice' for t in step.tasks)\n", "compares a kind"),
    ("ok = getattr(t, 'kind', None) in {'sampson_below'}\n", "compares a kind"),
    ("kinds = {t.kind for t in step.tasks}\n", "reads a kind"),
])
def test_the_scan_finds_each_offence(source, expected):
    assert any(expected in line for line in offences(source, skin_of_lessons=True)), source
    assert offences("ok = a.dtype.kind == 'f'\n", skin_of_lessons=True) == []


def shipped_tasks() -> list:
    return [(info.name, task) for info in list_lessons() for step in load(info.name).steps for task in step.tasks]


def test_every_shipped_task_declares_its_needs_and_each_declared_widget_has_a_skin():
    tasks = shipped_tasks()
    assert {task.kind for _, task in tasks} == set(TASK_KINDS), "a task kind no shipped lesson uses: not checked"
    for lesson, task in tasks:
        needs = task.needs
        where = f"{lesson}: {task.id} ({task.kind})"
        assert type(needs) is TaskNeeds and type(needs.answer) is AnswerNeeds, where
        with pytest.raises(dataclasses.FrozenInstanceError):
            needs.lens = not needs.lens  # type: ignore[misc]
        assert needs.answer.widget in SKINS, where
        assert task.question == (needs.answer.widget != NO_ANSWER), where
        assert (needs.answer.widget == CHOICE) == bool(needs.answer.options), where
    assert set(ANSWER_WIDGETS) <= set(SKINS)


class FakeHandle:
    def __init__(self, call: str, label: str, value=None, **extra) -> None:
        self.call, self.label, self.value = call, label, value
        self.__dict__.update(extra)


class FakeGui:
    """Records what a skin or a task row adds to the control panel."""

    def __init__(self) -> None:
        self.added: list[FakeHandle] = []

    def _add(self, call, label, value=None, **extra) -> FakeHandle:
        self.added.append(FakeHandle(call, label, value, **extra))
        return self.added[-1]

    def add_text(self, label, initial_value, hint=None):
        return self._add("text", label, initial_value, hint=hint)

    def add_dropdown(self, label, options, initial_value=None):
        return self._add("dropdown", label, initial_value, options=tuple(options))

    def add_markdown(self, content):
        return self._add("markdown", content)

    def add_button(self, label):
        return self._add("button", label)


def test_each_skin_builds_the_widget_its_task_declares():
    for _, task in shipped_tasks():
        answer = task.needs.answer
        gui = FakeGui()
        widget = answer_widget(gui, "answer 2", answer)
        if answer.widget == NO_ANSWER:
            assert widget.field is None and gui.added == [] and widget.text() is None
        elif answer.widget == CHOICE:
            assert (widget.field.call, widget.field.options) == ("dropdown", (CHOOSE, *task.options))
            assert widget.text() == ""  # nothing chosen yet: no answer
            widget.field.value = task.options[-1]
            assert widget.text() == task.options[-1]
            widget.field.value = "an option it does not offer"
            with pytest.raises(FieldError, match="answer 2: not one of the options"):
                widget.text()
        else:
            unit = f" ({answer.unit})" if answer.unit else ""
            assert (widget.field.call, widget.field.label, widget.field.hint) == ("text", f"answer 2{unit}", answer.hint)
            assert answer.hint
            widget.field.value = "1.5"
            assert widget.text() == "1.5"
            widget.field.value = 3
            with pytest.raises(FieldError, match="answer 2: expected text, got int"):
                widget.text()


def test_a_new_widget_is_one_declaration_and_one_skin():
    @skin("grid")
    class GridAnswer:  # what a 3 x 3 grid skin would be: its own fields, the answer read from them
        def __init__(self, gui, label, needs):
            self.field = gui.add_text(label, "", hint=needs.hint)

        def text(self):
            return f"[{self.field.value}]"

    try:
        task = types.SimpleNamespace(id="F", needs=TaskNeeds(AnswerNeeds("grid", hint="F, row by row")))
        gui = FakeGui()
        row = TaskRow(gui, 3, types.SimpleNamespace(task=task, prompt_html="F of your pair"), passed_before=False)
        assert isinstance(row.widget, GridAnswer) and row.answer is row.widget.field
        row.answer.value = "1, 0, 0; 0, 1, 0; 0, 0, 1"
        assert row.answer_text() == "[1, 0, 0; 0, 1, 0; 0, 0, 1]"
        with pytest.raises(ValueError, match="'grid' has a skin already"):
            skin("grid")(GridAnswer)
    finally:
        SKINS.pop("grid", None)
    with pytest.raises(KeyError, match="no skin for the answer widget 'grid'"):
        answer_widget(FakeGui(), "answer 1", AnswerNeeds("grid"))


def test_an_answer_declaration_is_checked():
    with pytest.raises(ValueError, match="a choice has options"):
        AnswerNeeds(CHOICE)
    with pytest.raises(ValueError, match="only a choice has them"):
        AnswerNeeds("number", options=("a", "b"))
    with pytest.raises(ValueError, match="widget: expected a name"):
        AnswerNeeds("3 x 3 grid")


@pytest.mark.parametrize("name", [info.name for info in list_lessons()])
def test_the_instruments_read_from_the_declarations_are_what_the_kinds_decided(name):
    # The rule the viewer used to apply to task kinds, kept here as the reference the declarations must meet.
    lesson = load(name)
    changes = [c for s in lesson.steps for c in s.changes]
    kinds = {t.kind for s in lesson.steps for t in s.tasks}
    needs = lesson_needs(lesson)
    assert needs.lab == (any(isinstance(c, SetLab) for c in changes) or bool(kinds & {"sampson_below", "inliers_recall"}))
    assert needs.lens == (any(isinstance(c, SetLens) for c in changes) or "point_on_line" in kinds)
    assert needs.lab_draws == ("ransac" if "inliers_recall" in kinds else DEFAULT_LAB_FIT)
    lens = LensToggles()
    for index, step in enumerate(lesson.steps):
        for change in step.changes:
            if isinstance(change, SetLens):
                lens = change.applied_to(lens)
        diagnosis = any(t.kind == "choice" for t in step.tasks) and lens.any
        assert hidden_lens(lesson, index) == (lens if diagnosis else None), (name, index)
    assert hidden_lens(lesson, len(lesson.steps)) is None
