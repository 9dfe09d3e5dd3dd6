r"""Tasks a lesson step asks for, from a fixed vocabulary: each kind a frozen record with a ``check``.

Nothing in a lesson file is ever run as code: a ``[[steps.tasks]]`` table names its ``kind`` and the
parameters of that kind, and :meth:`Task.check` measures the scene (through :func:`egtviz.scene.compute_derived`
and the numeric core, never the viewer). Every check returns a :class:`TaskResult` with feedback that says
what was measured; the runner shows the task's ``hint`` after a failed attempt.

Randomised tasks: a parameter written as ``[low, high]`` (whole numbers: a whole number is drawn) is drawn
per learner with ``numpy.random.default_rng(seed)``, the seed derived from (learner, lesson, step, task)
by :func:`task_seed`; the prompt shows the drawn values through ``{name}`` placeholders
(:meth:`Task.prompt_for`).

The kinds, their keys and when they pass are listed in ``docs/lessons.md`` and in each class's docstring
(:data:`TASK_KINDS` maps the names to the classes).

A check on a scene that no longer has what the task names (a camera removed, another scene opened) fails
with what is missing and :data:`RESET_ADVICE` (:meth:`Task.missing`), never an exception; a typed number is
read strictly (:func:`egtviz.lessons.answers.read_number`).

Every task also has ``id`` (unique in its step), ``prompt``, ``hint`` and optional ``solution`` (a list of
changes, as in ``[[steps.changes]]``, that solves it from the step's starting scene).

Each task declares what the lesson page needs for it (:attr:`Task.needs`, a :class:`TaskNeeds`: its answer
widget, the lab or lens it is judged on), so that the page never asks which kind a task is.

One job per module: :mod:`.base` (the :class:`Task` base, its context and result, per-learner draws),
:mod:`.needs` (what a task needs of the page),
:mod:`.common` (ranges and scene checks several kinds share), one module per family of kinds
(:mod:`.questions`, :mod:`.servo`, :mod:`.epipolar`, :mod:`.lens`, :mod:`.cameras`, :mod:`.estimation`) and
:mod:`.registry` (:data:`TASK_KINDS`, :func:`parse_task`). This package's names below are its public
surface: import them from ``egtviz.lessons.tasks``.
"""

from .base import RESET_ADVICE as RESET_ADVICE
from .base import Param as Param
from .base import Task as Task
from .base import TaskContext as TaskContext
from .base import TaskResult as TaskResult
from .base import Uniform as Uniform
from .base import task_seed as task_seed
from .cameras import CameraFieldTask as CameraFieldTask
from .cameras import SameOrientationTask as SameOrientationTask
from .cameras import XiBetweenTask as XiBetweenTask
from .cameras import camera_xi as camera_xi
from .cameras import rotation_angle_deg as rotation_angle_deg
from .common import point_label as point_label
from .epipolar import EpipoleNearTask as EpipoleNearTask
from .epipolar import LinesParallelTask as LinesParallelTask
from .epipolar import PointInImageTask as PointInImageTask
from .epipolar import direction_spread_deg as direction_spread_deg
from .estimation import InliersRecallTask as InliersRecallTask
from .estimation import SampsonBelowTask as SampsonBelowTask
from .estimation import TriangulationErrorTask as TriangulationErrorTask
from .estimation import triangulation_rms as triangulation_rms
from .lens import PointOnLineTask as PointOnLineTask
from .needs import ANSWER_WIDGETS as ANSWER_WIDGETS
from .needs import CHOICE as CHOICE
from .needs import NO_ANSWER as NO_ANSWER
from .needs import NUMBER as NUMBER
from .needs import TEXT as TEXT
from .needs import AnswerNeeds as AnswerNeeds
from .needs import LabNeeds as LabNeeds
from .needs import TaskNeeds as TaskNeeds
from .needs import number_answer as number_answer
from .questions import ChoiceTask as ChoiceTask
from .questions import NumberTask as NumberTask
from .registry import TASK_KINDS as TASK_KINDS
from .registry import parse_task as parse_task
from .servo import ServoNumberTask as ServoNumberTask

__all__ = [
    "ANSWER_WIDGETS",
    "CHOICE",
    "NO_ANSWER",
    "NUMBER",
    "RESET_ADVICE",
    "TASK_KINDS",
    "TEXT",
    "AnswerNeeds",
    "CameraFieldTask",
    "ChoiceTask",
    "EpipoleNearTask",
    "InliersRecallTask",
    "LabNeeds",
    "LinesParallelTask",
    "NumberTask",
    "Param",
    "PointInImageTask",
    "PointOnLineTask",
    "SampsonBelowTask",
    "SameOrientationTask",
    "ServoNumberTask",
    "Task",
    "TaskContext",
    "TaskNeeds",
    "TaskResult",
    "TriangulationErrorTask",
    "Uniform",
    "XiBetweenTask",
    "camera_xi",
    "direction_spread_deg",
    "number_answer",
    "parse_task",
    "point_label",
    "rotation_angle_deg",
    "task_seed",
    "triangulation_rms",
]
