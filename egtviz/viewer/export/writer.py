"""Writing an export: check the input and the folder first, then the page, the recorded scene and the marker."""

from __future__ import annotations

import json
import os
import stat
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING

from ... import __version__
from ...files import FileSafetyError, printable, write_atomic
from .page import SCENE_FRAME, markdown_to_html, page_html

if TYPE_CHECKING:  # only named: the scene layer is imported when a scene is read
    from ...scene import Scene

__all__ = ["MARKER", "ExportError", "ExportFailed", "export_lesson", "export_scene"]

#: The file that marks a folder as an egtviz export (a later export may replace its files).
MARKER = "egtviz-export.json"
#: The files an export writes.
PAGE = "index.html"


class ExportError(ValueError):
    """An export refused for its input (lesson, step, scene, folder); one line naming the argument and the reason."""


class ExportFailed(RuntimeError):
    """An export that was begun and could not be finished (a file not written, the scene not recorded); one line."""


def _check_out(out: str | os.PathLike) -> Path:
    """``out`` as a folder an export may write into: absent (it is made), empty, or an earlier export."""
    path = Path(out)
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return path
    except OSError as exc:
        raise ExportError(f"--out {printable(path)}: {exc.strerror or exc}") from None
    if stat.S_ISLNK(info.st_mode):
        raise ExportError(f"--out {printable(path)}: a symbolic link (give the folder itself)")
    if not stat.S_ISDIR(info.st_mode):
        raise ExportError(f"--out {printable(path)}: not a folder")
    try:
        entries = os.listdir(path)
    except OSError as exc:
        raise ExportError(f"--out {printable(path)}: {exc.strerror or exc}") from None
    if entries and not os.path.isfile(path / MARKER):
        raise ExportError(f"--out {printable(path)}: not empty and not an egtviz export (no {MARKER}); "
                          "give a new or empty folder")
    return path


def _write(out: Path, page: str, scene_page: str, marker: dict[str, object]) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
        write_atomic(out / SCENE_FRAME, scene_page.encode("utf-8"))
        write_atomic(out / PAGE, page.encode("utf-8"))
        write_atomic(out / MARKER, (json.dumps(marker, indent=2) + "\n").encode("utf-8"))
    except FileSafetyError as exc:
        raise ExportFailed(str(exc)) from None
    except OSError as exc:
        raise ExportFailed(f"--out {printable(out)}: {exc.strerror or exc}") from None


def _recorded(scene: Scene) -> str:
    """:func:`.recording.scene_page`, its failures (viser's client page missing, say) as :class:`ExportFailed`."""
    from .recording import scene_page

    try:
        return scene_page(scene)
    except OSError as exc:
        raise ExportFailed(f"cannot record the 3D scene: {printable(exc)}") from None


def export_lesson(name: str, step: int, out: str | os.PathLike) -> Path:
    """Export step ``step`` (1-based) of lesson ``name`` to the folder ``out``; returns the page's path.

    The scene is the step's as a learner entering it sees it (the lesson's scene with the changes of every
    step up to this one), drawn for an anonymous learner.

    Raises:
        ExportError: no such lesson, a step out of range, or a folder that may not be written into (one line).
        ExportFailed: the scene could not be recorded or a file not written (one line).
    """
    from ...lessons import LessonError, LessonRun, load
    try:
        lesson = load(name)
    except LessonError as exc:
        raise ExportError(f"--lesson: {exc}") from None
    n = len(lesson.steps)
    if isinstance(step, bool) or not isinstance(step, int) or not 1 <= step <= n:
        raise ExportError(f"--step {printable(step)}: lesson {printable(lesson.name)} has steps 1 to {n}")
    path = _check_out(out)
    run = LessonRun(lesson)
    run.go_to(step - 1)
    page = page_html(
        title=f"{lesson.title}: step {step} of {n}", subtitle=lesson.title,
        heading=f"Step {step} of {n}: {run.step.title}", body_html=markdown_to_html(run.step.html),
        tasks_html=[markdown_to_html(t.prompt_html) for t in run.tasks()],
        how=f"A picture of the step, without a server. To try it live: egtviz lesson {lesson.name}",
    )
    _write(path, page, _recorded(run.model.scene),
           {"egtviz": __version__, "kind": "lesson", "lesson": lesson.name, "step": step})
    return path / PAGE


def _scene_description(scene: Scene) -> str:
    cameras = "".join(f"<li>{escape(c.name)} ({escape(c.kind)})</li>" for c in scene.cameras)
    return (f"<p>{len(scene.cameras)} cameras, {len(scene.points)} points.</p>"
            + (f"<ul>{cameras}</ul>" if cameras else ""))


def export_scene(argument: str, out: str | os.PathLike) -> Path:
    """Export a scene (a scene file, or a built-in scene's name) to the folder ``out``; returns the page's path.

    Raises:
        ExportError: a scene that cannot be read, or a folder that may not be written into (one line).
        ExportFailed: the scene could not be recorded or a file not written (one line).
    """
    from ...scene import SceneFileError, scene_from_argument
    try:
        scene = scene_from_argument(argument)
    except SceneFileError as exc:
        raise ExportError(f"--scene: {exc}") from None
    path = _check_out(out)
    title = scene.title or Path(argument).name
    page = page_html(title=title, subtitle="egtviz scene", heading=title, body_html=_scene_description(scene),
                     how="A picture of the scene, without a server. To work with it live: egtviz --scene FILE")
    _write(path, page, _recorded(scene), {"egtviz": __version__, "kind": "scene", "scene": Path(argument).name})
    return path / PAGE
