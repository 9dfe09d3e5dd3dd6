"""Lessons: the course's files, their task vocabulary and checks, progress, and a headless runner.

Layer 3 of egtviz beside :mod:`egtviz.scene` (it uses the scene layer and the numeric core, never viser).
The format for authors: ``docs/lessons.md``.
"""

from .catalog import LessonInfo as LessonInfo
from .catalog import list_lessons as list_lessons
from .catalog import load as load
from .changes import apply as apply_change
from .errors import LessonError as LessonError
from .format import Lesson as Lesson
from .format import Step as Step
from .format import load_lesson as load_lesson
from .format import parse_lesson as parse_lesson
from .progress import ProgressStore as ProgressStore
from .runner import LessonRun as LessonRun
from .tasks import TaskContext as TaskContext
from .tasks import TaskResult as TaskResult

__all__ = [
    "Lesson",
    "LessonError",
    "LessonInfo",
    "LessonRun",
    "ProgressStore",
    "Step",
    "TaskContext",
    "TaskResult",
    "apply_change",
    "list_lessons",
    "load",
    "load_lesson",
    "parse_lesson",
]
