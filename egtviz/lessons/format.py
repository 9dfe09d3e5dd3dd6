"""Lesson files: TOML, one lesson per file, parsed and validated into a frozen :class:`Lesson`.

A file has ``title``, ``summary``, ``prerequisites`` (names of other lessons), ``scene`` (the name of a
built-in scene, or a ``[scene]`` table in the scene file's vocabulary, checked by the scene layer exactly
like a scene file), and ``[[steps]]``, each with ``title``, ``text`` (Markdown with ``$...$`` formulas),
``[[steps.changes]]`` (:mod:`egtviz.lessons.changes`) and ``[[steps.tasks]]`` (:mod:`egtviz.lessons.tasks`).
The format is described for authors in ``docs/lessons.md``.

Loading validates everything a runner will need: every step's changes are applied, in order, to a
headless :class:`~egtviz.scene.SceneModel` (a change naming a missing camera, or moving one out of range,
is refused as the viewer would refuse it), every task is checked against the scene of its step, and every
task's ``solution`` is applied to a copy. Each refusal is one :class:`LessonError` ``file:line: reason``.
"""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ..files import FileSafetyError, printable, read_limited, too_large
from ..scene import SCENES, Scene, SceneError, SceneFileError, SceneModel
from ..scene.io import scene_from_dict
from ..scene.lab import LabSettings, make_correspondences
from ..scene.lens import LensToggles
from ..scene.limits import (
    MAX_CHANGES,
    MAX_LESSON_FILE_BYTES,
    MAX_LESSON_SERVO_STEPS,
    MAX_PREREQUISITES,
    MAX_STEPS,
    MAX_TASKS,
)
from . import fields
from .bounds import check_lesson_work, check_toml_text
from .changes import Change, OpenDemo, SetField, SetLens, parse_change
from .changes import apply as apply_change
from .errors import EntryError, LessonError
from .images import LessonImages
from .locate import Locator, scene_entry_path, toml_locator
from .display import KEYS as DISPLAY_KEYS
from .display import PanelDisplay, parse_display
from .markup import (PANEL_WIDTH_PX, MarkupError, displayed_formulas, formula_to_mathml, formula_width_px,
                     render_markdown)
from .tasks import (
    ChoiceTask,
    InliersRecallTask,
    SampsonBelowTask,
    ServoNumberTask,
    Task,
    parse_task,
)

__all__ = ["MAX_COUNTER_EXAMPLES", "CounterExample", "Lesson", "Step", "load_lesson", "parse_lesson"]

_TOP = ("title", "summary", "prerequisites", "scene", "steps")
_STEP = ("title", "text", "changes", "tasks", *DISPLAY_KEYS)
_LESSON_NAME = re.compile(r"[a-z0-9][a-z0-9-]{0,79}")
_COUNTER = ("why", "changes", "answer", "mistake")
MAX_COUNTER_EXAMPLES = 5
"""Counter-examples of one task."""


@dataclass(frozen=True)
class CounterExample:
    """A wrong answer a careless learner would give, which its task must refuse (``[[steps.tasks.counter_examples]]``).

    ``egtviz check`` applies ``changes`` from the step's start (a scene task) or types ``answer`` (a question)
    and refuses the lesson if the task passes (:mod:`egtviz.lessons.proof`).
    """

    why: str
    """The mistake, in a few words (e.g. "the loose threshold")."""
    changes: tuple[Change, ...] = ()
    answer: str | None = None
    mistake: str | None = None
    """A computed task's counter-example: the named classic mistake's value in the learner's scene is typed
    (:meth:`~egtviz.lessons.tasks.computed.ComputedTask.mistake_text`)."""
    line: int = 1
    """The line of the counter-example's table in the lesson file."""


@dataclass(frozen=True)
class Step:
    """One screen of a lesson."""

    title: str
    text: str
    """Markdown as written, formulas in ``$...$``."""
    html: str
    """The text as shown: Markdown with the formulas rendered to MathML (:func:`render_markdown`)."""
    changes: tuple[Change, ...] = ()
    tasks: tuple[Task, ...] = ()
    counter_examples: tuple[tuple[CounterExample, ...], ...] = ()
    """Per task (in the order of :attr:`tasks`), the wrong answers ``egtviz check`` proves it refuses."""
    display: PanelDisplay = PanelDisplay()
    """What the panels show in this step (``max_lines``, ``labels``, ``view``)."""

    def counter_examples_of(self, task_id: str) -> tuple[CounterExample, ...]:
        """The counter-examples of the task ``task_id`` (none if it has none)."""
        for task, examples in zip(self.tasks, self.counter_examples, strict=False):
            if task.id == task_id:
                return examples
        return ()


@dataclass(frozen=True)
class Lesson:
    """A validated lesson."""

    name: str
    """The file name without ``.toml`` (e.g. ``06-pinhole-epipolar``)."""
    title: str
    summary: str
    prerequisites: tuple[str, ...]
    scene: Scene
    """The starting scene."""
    steps: tuple[Step, ...]
    source: str = ""
    """Where the lesson was read from (for messages)."""

    @property
    def task_count(self) -> int:
        """Tasks in all steps."""
        return sum(len(s.tasks) for s in self.steps)


def load_lesson(path: str | os.PathLike, *, known_lessons: frozenset[str] | None = None) -> Lesson:
    """Read and validate a lesson file (a regular file of at most :data:`MAX_LESSON_FILE_BYTES`).

    Args:
        path: the ``.toml`` file; its name without the suffix is the lesson's name.
        known_lessons: names a prerequisite may take; default: the ``.toml`` files next to ``path``.

    Raises:
        LessonError: ``file:line: reason`` for the first problem found.
    """
    shown = printable(os.fspath(path))
    try:
        data = read_limited(path, MAX_LESSON_FILE_BYTES)
    except FileSafetyError as exc:
        raise LessonError(shown, 1, str(exc).removeprefix(f"{shown}: ")) from None
    if known_lessons is None:
        folder = Path(path).parent
        try:
            known_lessons = frozenset(p.stem for p in folder.iterdir() if p.suffix.lower() == ".toml")
        except OSError:
            known_lessons = frozenset()
    return parse_lesson(data, source=shown, name=Path(path).stem, known_lessons=known_lessons,
                        folder=Path(path).parent)


def parse_lesson(data: bytes | str, *, source: str, name: str, known_lessons: frozenset[str] | None = None,
                 folder: Path | None = None) -> Lesson:
    """A lesson from the text of a lesson file (see :func:`load_lesson`).

    Args:
        data: the file's bytes (UTF-8), or its text.
        source: what to call the file in messages.
        name: the lesson's name.
        known_lessons: names a prerequisite may take (None: any).
        folder: the lesson file's folder, where its texts' images are (None: only the package's assets).

    Raises:
        LessonError: ``file:line: reason``.
    """
    source = printable(source)
    if isinstance(data, (bytes, bytearray)):
        if len(data) > MAX_LESSON_FILE_BYTES:
            raise LessonError(source, 1, too_large(len(data), MAX_LESSON_FILE_BYTES))
        try:
            text = bytes(data).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise LessonError(source, bytes(data)[: exc.start].count(b"\n") + 1, "not UTF-8 text") from None
    else:
        text = data
        # A character is at least one byte: only a text short enough in characters is measured in bytes.
        size = len(text) if len(text) > MAX_LESSON_FILE_BYTES else len(text.encode("utf-8", "surrogatepass"))
        if size > MAX_LESSON_FILE_BYTES:
            raise LessonError(source, 1, too_large(size, MAX_LESSON_FILE_BYTES))
    text = text.removeprefix("\ufeff")  # a byte-order mark some editors write
    if not _LESSON_NAME.fullmatch(name):
        raise LessonError(source, 1, f"lesson name '{printable(name)}': expected lower-case letters, digits and '-'")
    check_toml_text(text, source)
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        line = int(m.group(1)) if m else 1
        reason = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc)) or "invalid TOML"
        raise LessonError(source, line, f"not valid TOML: {reason}") from None
    except RecursionError:
        raise LessonError(source, 1, "not valid TOML: nested too deeply") from None
    reader = _Reader(source, name, toml_locator(text), known_lessons, LessonImages(folder), text.splitlines())
    return reader.lesson(doc)


class _Reader:
    """Turns the parsed TOML into a :class:`Lesson`, every error located."""

    def __init__(self, source: str, name: str, where: Locator, known: frozenset[str] | None,
                 images: LessonImages, lines: list[str]) -> None:
        self.source = source
        self.images = images
        self.lines = lines
        self.name = name
        self.where = where
        self.known = known
        self.demo: OpenDemo | None = None
        """The servo run the steps read so far offer (the last ``open_demo``), for ``servo_number`` tasks."""
        self.lens = LensToggles()
        """The convention lens as the steps read so far leave it: a ``choice`` task while it has a mistake on
        is a diagnosis, and each of its options needs ``feedback``."""
        self.simulated: set[OpenDemo] = set()
        self.servo_steps = 0
        """Steps of the distinct runs in :attr:`simulated`."""

    def error(self, path: tuple, reason: str) -> LessonError:
        return LessonError(self.source, self.where.line(*path), reason)

    def entry(self, path: tuple, exc: EntryError, what: str) -> LessonError:
        key = (exc.key,) if exc.key else ()
        return self.error(path + key, f"{what}: {exc}")

    def lesson(self, doc: dict) -> Lesson:
        try:
            fields.refuse_unknown(doc, _TOP, "a lesson")
            title = fields.text(doc, "title")
            summary = fields.text(doc, "summary", limit=2000, multiline=True)
            prerequisites = fields.name_list(doc, "prerequisites", required=False, limit=MAX_PREREQUISITES)
        except EntryError as exc:
            raise self.entry((), exc, "lesson") from None
        for p in prerequisites:
            if self.known is not None and p not in self.known:
                raise self.error(("prerequisites",), f"prerequisites: no lesson named '{printable(p)}'")
            if p == self.name:
                raise self.error(("prerequisites",), "prerequisites: a lesson cannot require itself")
        scene = self.scene(doc.get("scene"))
        steps_data = doc.get("steps")
        if not isinstance(steps_data, list) or not steps_data or len(steps_data) > MAX_STEPS:
            raise self.error(("steps",), f"steps: expected 1 to {MAX_STEPS} [[steps]] tables")
        check_lesson_work(steps_data, self.source, self.where)
        model = SceneModel(scene)
        steps = tuple(self.step(i, s, model) for i, s in enumerate(steps_data))
        return Lesson(self.name, title, summary, prerequisites, scene, steps, self.source)

    def scene(self, value: object) -> Scene:
        if value is None:
            raise self.error((), f"scene: missing (a built-in name: {', '.join(SCENES)}; or a [scene] table)")
        if isinstance(value, str):
            if value not in SCENES:
                raise self.error(("scene",), f"scene: expected a built-in scene ({', '.join(SCENES)}) or a "
                                             f"[scene] table, got {fields.short(value)}")
            return SCENES[value]()
        if not isinstance(value, dict):
            raise self.error(("scene",), f"scene: expected a name or a table, got {fields.short(value)}")
        try:
            return scene_from_dict(value, "scene")
        except SceneFileError as exc:
            reason = str(exc).removeprefix("scene: ")
            raise self.error(("scene", *scene_entry_path(reason)), f"scene: {reason}") from None

    def step(self, i: int, data: object, model: SceneModel) -> Step:
        at = ("steps", i)
        if not isinstance(data, dict):
            raise self.error(at, f"steps[{i}]: expected a table")
        try:
            fields.refuse_unknown(data, _STEP, "a step")
            title = fields.text(data, "title")
            text = fields.text(data, "text", limit=fields.MAX_TEXT, multiline=True)
        except EntryError as exc:
            raise self.entry(at, exc, f"steps[{i}]") from None
        try:
            html = render_markdown(text, self.images.data_url)
        except MarkupError as exc:
            raise LessonError(self.source, self.text_line(at, text, exc.offset), f"steps[{i}].text: {exc}") from None
        self.formulas_fit(at, text)
        changes = self.changes(at, data.get("changes", []), model)
        tasks, counter = self.tasks(at, data.get("tasks", []), model)
        try:
            display = parse_display(data, frozenset(c.name for c in model.scene.cameras))
        except EntryError as exc:
            raise self.entry(at, exc, f"steps[{i}]") from None
        return Step(title, text, html, changes, tasks, counter, display)

    def formulas_fit(self, at: tuple, text: str) -> None:
        """Refuses a displayed formula wider than the control panel (it would be cut at the panel's edge)."""
        for offset, latex in displayed_formulas(text):
            wide = formula_width_px(formula_to_mathml(latex, display=True))
            if wide > PANEL_WIDTH_PX:
                raise LessonError(self.source, self.text_line(at, text, offset),
                                  f"formula is {wide:.0f} px wide, the panel shows {PANEL_WIDTH_PX:.0f} px "
                                  f"(break it into two displayed lines, or shorten it)")

    def text_line(self, at: tuple, text: str, offset: int) -> int:
        """The line of character ``offset`` of a step's ``text``: counted from its key in a multi-line string."""
        line = self.where.line(*at, "text")
        value = self.lines[line - 1].partition("=")[2].strip() if line <= len(self.lines) else ""
        if value[:3] not in ('"""', "'''"):
            return line
        first = line + 1 if value == value[:3] else line  # TOML drops a newline right after the opening quotes
        return first + text.count("\n", 0, offset)

    def changes(self, at: tuple, value: object, model: SceneModel) -> tuple[Change, ...]:
        if not isinstance(value, list) or len(value) > MAX_CHANGES:
            raise self.error(at + ("changes",), f"changes: expected at most {MAX_CHANGES} [[steps.changes]] tables")
        out = []
        for j, table in enumerate(value):
            here = at + ("changes", j)
            what = f"steps[{at[1]}].changes[{j}]"
            try:
                change = parse_change(table)
            except EntryError as exc:
                raise self.entry(here, exc, what) from None
            self.apply(model, change, here, what, table)
            if isinstance(change, OpenDemo):
                self.demo = change
            elif isinstance(change, SetLens):
                self.lens = change.applied_to(self.lens)
            out.append(change)
        return tuple(out)

    def apply(self, model: SceneModel, change: Change, here: tuple, what: str, table: object) -> None:
        try:
            apply_change(model, change)
        except EntryError as exc:
            raise self.entry(here, exc, what) from None
        except SceneError as exc:
            raise self.error(here + _offending_key(change, table, str(exc)), f"{what}: {exc}") from None

    def budget_run(self, here: tuple, what: str) -> None:
        """Count the servo run a ``servo_number`` task measures (simulated once per distinct run) before it is
        simulated: all of a lesson's runs together take at most :data:`MAX_LESSON_SERVO_STEPS` steps."""
        if self.demo is None or self.demo in self.simulated:
            return
        self.simulated.add(self.demo)
        self.servo_steps += int(self.demo.simulation_kwargs()["steps"])
        if self.servo_steps > MAX_LESSON_SERVO_STEPS:
            raise self.error(here, f"{what}: the lesson's servo_number tasks measure runs of {self.servo_steps:,} "
                                   f"steps in all, more than the {MAX_LESSON_SERVO_STEPS:,} simulated when a lesson "
                                   "is loaded (fewer steps, or fewer different runs)")

    def tasks(self, at: tuple, value: object,
              model: SceneModel) -> tuple[tuple[Task, ...], tuple[tuple[CounterExample, ...], ...]]:
        if not isinstance(value, list) or len(value) > MAX_TASKS:
            raise self.error(at + ("tasks",), f"tasks: expected at most {MAX_TASKS} [[steps.tasks]] tables")
        out: list[Task] = []
        counter: list[tuple[CounterExample, ...]] = []
        for j, table in enumerate(value):
            here = at + ("tasks", j)
            what = f"steps[{at[1]}].tasks[{j}]"
            if isinstance(table, dict) and "counter_examples" in table:
                table = {k: v for k, v in table.items() if k != "counter_examples"}
                counter.append(self.counter_examples(here, what, value[j]["counter_examples"]))
            else:
                counter.append(())
            try:
                task = parse_task(table, default_id=f"task{j + 1}")
                if any(t.id == task.id for t in out):
                    raise EntryError("id", f"another task of this step has the id {task.id!r}")
                task.validate(model.scene)
                if isinstance(task, ServoNumberTask):
                    self.budget_run(here, what)
                    task.validate_run(self.demo)
            except EntryError as exc:
                raise self.entry(here, exc, what) from None
            if isinstance(task, ChoiceTask) and self.lens.any and task.options_without_feedback:
                raise self.error(here + (("feedback",) if task.feedback else ()),
                                 f"{what}: a diagnosis (a choice while the lens has a mistake on) needs feedback "
                                 f"for every option; none for {', '.join(map(repr, task.options_without_feedback))}")
            if isinstance(task, (SampsonBelowTask, InliersRecallTask)):
                try:
                    make_correspondences(model.scene, LabSettings())
                except SceneError as exc:
                    raise self.error(here, f"{what}: {exc}") from None
            trial = SceneModel(model.scene)
            for change in task.solution:
                self.apply(trial, change, here + ("solution",), f"{what}.solution", {})
            if task.question and any(c.answer is None and c.mistake is None for c in counter[-1]):
                raise self.error(here + ("counter_examples",), f"{what}.counter_examples: a question's "
                                 "counter-example is a wrong answer: expected 'answer'")
            if any(c.mistake is not None for c in counter[-1]):
                self.mistakes(here, what, task, counter[-1])
            if not task.question and any(c.answer is not None or not c.changes for c in counter[-1]):
                raise self.error(here + ("counter_examples",), f"{what}.counter_examples: a scene task's "
                                 "counter-example is what a learner does: expected 'changes' and no 'answer'")
            out.append(task)
        return tuple(out), tuple(counter)

    def mistakes(self, here: tuple, what: str, task: Task, examples: tuple[CounterExample, ...]) -> None:
        """Refuse a ``mistake`` counter-example on a task that has no such computed mistake."""
        names = {m.name for m in getattr(getattr(task, "spec", None), "mistakes", ())}
        for k, example in enumerate(examples):
            if example.mistake is not None and example.mistake not in names:
                raise self.error(here + ("counter_examples", k), f"{what}.counter_examples[{k}].mistake: expected "
                                 f"one of {', '.join(sorted(names)) or 'none (not a computed task)'}, got "
                                 f"{fields.short(example.mistake)}")

    def counter_examples(self, here: tuple, what: str, value: object) -> tuple[CounterExample, ...]:
        """A task's ``[[steps.tasks.counter_examples]]``: ``why``, and ``changes`` (a list of changes, as in a
        ``solution``) or ``answer`` (a question's typed answer); applied and checked by ``egtviz check``."""
        if not isinstance(value, list) or not 1 <= len(value) <= MAX_COUNTER_EXAMPLES:
            raise self.error(here + ("counter_examples",), f"{what}.counter_examples: expected 1 to "
                             f"{MAX_COUNTER_EXAMPLES} [[steps.tasks.counter_examples]] tables")
        out = []
        for k, table in enumerate(value):
            at = here + ("counter_examples", k)
            name = f"{what}.counter_examples[{k}]"
            if not isinstance(table, dict):
                raise self.error(at, f"{name}: expected a table, got {fields.short(table)}")
            try:
                fields.refuse_unknown(table, _COUNTER, "a counter-example")
                why = fields.text(table, "why")
                changes = table.get("changes", [])
                if not isinstance(changes, list) or len(changes) > MAX_CHANGES:
                    raise EntryError("changes", f"expected a list of at most {MAX_CHANGES} changes, "
                                                f"got {fields.short(changes)}")
                try:
                    parsed = tuple(parse_change(c) for c in changes)
                except EntryError as exc:
                    raise EntryError("changes", f"change: {exc}") from None
                answer = table.get("answer")
                if answer is not None and (type(answer) not in (str, int, float)):
                    raise EntryError("answer", f"expected the typed text or a number, got {fields.short(answer)}")
                if isinstance(answer, str):
                    answer = fields.text(table, "answer")
                mistake = fields.text(table, "mistake", required=False) or None
                if mistake is not None and answer is not None:
                    raise EntryError("mistake", "expected 'answer' or 'mistake', not both")
            except EntryError as exc:
                raise self.entry(at, exc, name) from None
            shown = None if answer is None else answer if isinstance(answer, str) else f"{answer:g}"
            out.append(CounterExample(why, parsed, shown, mistake, self.where.line(*at)))
        return tuple(out)


def _offending_key(change: Change, table: object, message: str) -> tuple[str, ...]:
    """The key of a change's table that a scene-layer refusal is about (empty: the table itself)."""
    keys = [k for k in (table if isinstance(table, dict) else ()) if k != "do"]
    if "no camera named" in message and "camera" in keys:
        return ("camera",)
    if isinstance(change, SetField) and "value" in keys:
        return ("value",)
    named = [k for k in keys if f"{k}:" in message] or [k for k in keys if k in message]
    return tuple(named[:1])
