"""Everything a class holds, as plain data that can be written as JSON and read back (so several server
processes can share one class). Not thread-safe: :class:`~egtviz.classroom.room.Classroom` guards it.

Not in it: the instructor token (each process is given it), listeners, and the rate limits' clocks.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from ..lessons.progress import learner_key
from ..scene import Scene
from ..scene.io import scene_from_dict, scene_to_dict
from .answers import MAX_QUESTION_LENGTH, AnswerBook
from .events import Mode
from .snapshots import Snapshot
from .text import ClassroomError, plain_text

__all__ = ["STATE_FORMAT", "ClassState", "SharedState", "TabState"]

STATE_FORMAT = "egtviz-classroom"
STATE_VERSION = 1


@dataclass(frozen=True)
class SharedState:
    """What the instructor last published: every follower shows this one scene."""

    version: int = 0
    """0 until the first publish, then one more per publish."""
    scene: Scene | None = None
    lesson: str | None = None
    step: int | None = None
    """The lesson step it belongs to (0-based), if any."""


@dataclass
class TabState:
    """One open browser tab: an instructor's (``name`` None) or a student's."""

    name: str | None
    following: bool = False
    lesson: str | None = None
    step: int | None = None

    @property
    def instructor(self) -> bool:
        return self.name is None


@dataclass
class ClassState:
    """The class: tabs, students, the shared scene, mode, pacing, answers and snapshots."""

    tabs: dict[int, TabState] = field(default_factory=dict)
    students: dict[str, None] = field(default_factory=dict)
    """Every student who joined (learner keys, in order of joining): the roster keeps those who left."""
    scenes: dict[str, Scene] = field(default_factory=dict)
    """Each student's own scene (by learner key), given back when they reconnect."""
    shared: SharedState = field(default_factory=SharedState)
    mode: Mode = Mode.FOLLOW
    cameras_locked: bool = False
    pause: str | None = None
    paced: dict[str, int | None] = field(default_factory=dict)
    """Per lesson, the last step students may open (None: all)."""
    allowed: frozenset[str] | None = None
    """Lessons students may open; None: all."""
    answers: AnswerBook = field(default_factory=AnswerBook)
    labels: dict[str, str] = field(default_factory=dict)
    """Each student's snapshot label (``Student A``...), by learner key."""
    snapshots_taken: int = 0
    shown: Snapshot | None = None
    names_shown: bool = False
    """Whether the projector shows students' names (hidden until the instructor shows them)."""
    question: str | None = None
    """The question the instructor is asking now."""

    def to_dict(self) -> dict[str, Any]:
        """The state as plain JSON data."""
        shared = self.shared
        shown = self.shown
        return {
            "format": STATE_FORMAT, "version": STATE_VERSION,
            "tabs": [[tab, t.name, t.following, t.lesson, t.step] for tab, t in self.tabs.items()],
            "students": list(self.students),
            "scenes": {name: scene_to_dict(s) for name, s in self.scenes.items()},
            "shared": {"version": shared.version, "lesson": shared.lesson, "step": shared.step,
                       "scene": None if shared.scene is None else scene_to_dict(shared.scene)},
            "mode": self.mode.value, "cameras_locked": self.cameras_locked, "pause": self.pause,
            "paced": dict(self.paced), "allowed": None if self.allowed is None else sorted(self.allowed),
            "answers": self.answers.to_dict(), "labels": dict(self.labels), "snapshots_taken": self.snapshots_taken,
            "names_shown": self.names_shown, "question": self.question,
            "shown": None if shown is None else {"label": shown.label, "number": shown.number,
                                                 "scene": scene_to_dict(shown.scene)},
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, ensure_ascii=False, separators=(",", ":"))

    @classmethod
    def from_dict(cls, data: Any) -> ClassState:
        """A state from :meth:`to_dict`'s data.

        Raises:
            ClassroomError: data that is not a classroom state of this version (naming what is wrong).
        """
        if not isinstance(data, dict) or data.get("format") != STATE_FORMAT or data.get("version") != STATE_VERSION:
            raise ClassroomError(f"state: expected {STATE_FORMAT} version {STATE_VERSION}")
        try:
            return cls._read(data)
        except ClassroomError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise ClassroomError(f"state: {type(exc).__name__}: {exc}") from None

    @classmethod
    def _read(cls, data: dict[str, Any]) -> ClassState:
        tabs = {int(tab): TabState(None if name is None else learner_key(name), bool(following),
                                   None if lesson is None else str(lesson), None if step is None else int(step))
                for tab, name, following, lesson, step in data["tabs"]}
        shared = data["shared"]
        shown = data["shown"]
        allowed = data["allowed"]
        return cls(
            tabs=tabs,
            students={learner_key(n): None for n in data["students"]},
            scenes={learner_key(n): scene_from_dict(s, "state") for n, s in data["scenes"].items()},
            shared=SharedState(int(shared["version"]),
                               None if shared["scene"] is None else scene_from_dict(shared["scene"], "state"),
                               shared["lesson"], shared["step"]),
            mode=Mode(data["mode"]), cameras_locked=bool(data["cameras_locked"]), pause=data["pause"],
            paced={str(k): None if v is None else int(v) for k, v in data["paced"].items()},
            allowed=None if allowed is None else frozenset(str(a) for a in allowed),
            answers=AnswerBook.from_dict(data["answers"]),
            labels={learner_key(k): str(v) for k, v in data["labels"].items()},
            snapshots_taken=int(data["snapshots_taken"]), names_shown=bool(data["names_shown"]),
            question=None if data["question"] is None else plain_text(data["question"], "question",
                                                                      MAX_QUESTION_LENGTH),
            shown=None if shown is None else Snapshot(str(shown["label"]), scene_from_dict(shown["scene"], "state"),
                                                      int(shown["number"])),
        )

    @classmethod
    def from_json(cls, text: str | bytes) -> ClassState:
        try:
            data = json.loads(text)
        except ValueError as exc:
            raise ClassroomError(f"state: not JSON ({exc})") from None
        return cls.from_dict(data)
