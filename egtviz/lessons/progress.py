"""Learners' progress in SQLite: the current step of each lesson, the tasks passed and the attempts.

One database file in the user's data folder (:func:`default_database_path`), keyed by the name the learner
types (:func:`learner_key`), so a reload, a new tab or a restarted server resumes where they were. The
schema is versioned with ``PRAGMA user_version`` and upgraded by :func:`migrate`. Every call opens its own
connection (``sqlite3`` connections are not shared between threads) and writes in one transaction, so
several threads, or several server processes, may use one file.
"""

from __future__ import annotations

import os
import sqlite3
import threading
import time
import unicodedata
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

__all__ = ["SCHEMA_VERSION", "LearnerNameError", "ProgressRow", "ProgressStore", "default_database_path", "learner_key"]

SCHEMA_VERSION = 1
MAX_LEARNER_NAME = 40
"""Characters of a learner's name (after trimming)."""
_TIMEOUT_S = 10.0

_MIGRATIONS = {
    1: (
        """CREATE TABLE learners (
               name TEXT PRIMARY KEY,
               created REAL NOT NULL)""",
        """CREATE TABLE lesson_state (
               learner TEXT NOT NULL REFERENCES learners(name),
               lesson TEXT NOT NULL,
               step INTEGER NOT NULL,
               updated REAL NOT NULL,
               PRIMARY KEY (learner, lesson))""",
        """CREATE TABLE task_state (
               learner TEXT NOT NULL REFERENCES learners(name),
               lesson TEXT NOT NULL,
               step INTEGER NOT NULL,
               task TEXT NOT NULL,
               attempts INTEGER NOT NULL,
               passed INTEGER NOT NULL,
               updated REAL NOT NULL,
               PRIMARY KEY (learner, lesson, step, task))""",
    ),
}
"""Statements that take the schema from version ``n - 1`` to ``n``."""


class LearnerNameError(ValueError):
    """A learner name that cannot be used (empty, too long, control characters)."""


def learner_key(name: object) -> str:
    """The name a learner typed as the key of their progress: NFC-normalised, trimmed, inner runs of spaces
    made one; 1 to :data:`MAX_LEARNER_NAME` characters, no control characters.

    Raises:
        LearnerNameError: naming what is wrong.
    """
    if not isinstance(name, str):
        raise LearnerNameError(f"name: expected text, got {type(name).__name__}")
    key = " ".join(unicodedata.normalize("NFC", name).split())
    if not key:
        raise LearnerNameError("name: expected a name (it is empty)")
    if len(key) > MAX_LEARNER_NAME:
        raise LearnerNameError(f"name: at most {MAX_LEARNER_NAME} characters, got {len(key)}")
    if any(unicodedata.category(c)[0] == "C" for c in key):
        raise LearnerNameError("name: control characters are not allowed")
    return key


def default_database_path() -> Path:
    """``$EGTVIZ_DATA_DIR/progress.sqlite3``, else ``$XDG_DATA_HOME/egtviz/...``, else ``~/.local/share/egtviz/...``."""
    folder = os.environ.get("EGTVIZ_DATA_DIR")
    if not folder:
        xdg = os.environ.get("XDG_DATA_HOME")
        home = os.path.join(os.path.expanduser("~"), ".local", "share")
        folder = os.path.join(xdg or home, "egtviz")
    return Path(folder) / "progress.sqlite3"


def migrate(conn: sqlite3.Connection) -> int:
    """Bring the schema of ``conn`` to :data:`SCHEMA_VERSION`; returns the version found.

    Raises:
        sqlite3.DatabaseError: a database written by a newer egtviz (its version is higher).
    """
    found = conn.execute("PRAGMA user_version").fetchone()[0]
    if found > SCHEMA_VERSION:
        raise sqlite3.DatabaseError(f"progress database of schema version {found}; this egtviz reads {SCHEMA_VERSION}")
    for version in range(found + 1, SCHEMA_VERSION + 1):
        with conn:
            for statement in _MIGRATIONS[version]:
                conn.execute(statement)
            conn.execute(f"PRAGMA user_version = {version}")
    return found


@dataclass(frozen=True)
class ProgressRow:
    """One line of ``egtviz progress``."""

    learner: str
    lesson: str
    step: int
    """Current step (0-based)."""
    tasks_passed: int
    attempts: int


class ProgressStore:
    """The progress database at ``path`` (created with its folder on first use)."""

    def __init__(self, path: str | os.PathLike | None = None) -> None:
        self.path = Path(path) if path is not None else default_database_path()
        self._lock = threading.Lock()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self._connect() as conn:
            migrate(conn)

    @contextmanager
    def _connect(self) -> Iterator[sqlite3.Connection]:
        conn = sqlite3.connect(self.path, timeout=_TIMEOUT_S)
        try:
            conn.execute("PRAGMA foreign_keys = ON")
            yield conn
        finally:
            conn.close()

    @contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        with self._lock, self._connect() as conn, conn:
            yield conn

    def _learner(self, conn: sqlite3.Connection, name: str) -> str:
        key = learner_key(name)
        conn.execute("INSERT OR IGNORE INTO learners (name, created) VALUES (?, ?)", (key, time.time()))
        return key

    def set_step(self, learner: str, lesson: str, step: int) -> None:
        """Remember that ``learner`` is at ``step`` of ``lesson``."""
        with self._write() as conn:
            key = self._learner(conn, learner)
            conn.execute(
                "INSERT INTO lesson_state (learner, lesson, step, updated) VALUES (?, ?, ?, ?) "
                "ON CONFLICT (learner, lesson) DO UPDATE SET step = excluded.step, updated = excluded.updated",
                (key, lesson, int(step), time.time()),
            )

    def current_step(self, learner: str, lesson: str) -> int:
        """The step ``learner`` was last at in ``lesson`` (0 if never started)."""
        with self._connect() as conn:
            row = conn.execute("SELECT step FROM lesson_state WHERE learner = ? AND lesson = ?",
                               (learner_key(learner), lesson)).fetchone()
        return int(row[0]) if row else 0

    def record_attempt(self, learner: str, lesson: str, step: int, task: str, passed: bool) -> None:
        """Count one attempt at a task; once passed, a task stays passed."""
        with self._write() as conn:
            key = self._learner(conn, learner)
            conn.execute(
                "INSERT INTO task_state (learner, lesson, step, task, attempts, passed, updated) "
                "VALUES (?, ?, ?, ?, 1, ?, ?) ON CONFLICT (learner, lesson, step, task) DO UPDATE SET "
                "attempts = attempts + 1, passed = max(passed, excluded.passed), updated = excluded.updated",
                (key, lesson, int(step), task, int(bool(passed)), time.time()),
            )

    def passed_tasks(self, learner: str, lesson: str) -> frozenset[tuple[int, str]]:
        """``(step, task id)`` of the tasks ``learner`` has passed in ``lesson``."""
        with self._connect() as conn:
            rows = conn.execute("SELECT step, task FROM task_state WHERE learner = ? AND lesson = ? AND passed = 1",
                                (learner_key(learner), lesson)).fetchall()
        return frozenset((int(s), t) for s, t in rows)

    def attempts(self, learner: str, lesson: str, step: int, task: str) -> int:
        """How many times ``learner`` checked that task (0 if never)."""
        with self._connect() as conn:
            row = conn.execute(
                "SELECT attempts FROM task_state WHERE learner = ? AND lesson = ? AND step = ? AND task = ?",
                (learner_key(learner), lesson, int(step), task),
            ).fetchone()
        return int(row[0]) if row else 0

    def learners(self) -> list[str]:
        """Every learner who has made progress, sorted."""
        with self._connect() as conn:
            return [r[0] for r in conn.execute("SELECT name FROM learners ORDER BY name")]

    def summary(self) -> list[ProgressRow]:
        """One row per learner and lesson started, sorted by learner then lesson."""
        with self._connect() as conn:
            rows = conn.execute(
                """SELECT l.learner, l.lesson, l.step,
                          COALESCE(SUM(t.passed), 0), COALESCE(SUM(t.attempts), 0)
                   FROM (SELECT learner, lesson, step FROM lesson_state
                         UNION SELECT learner, lesson, 0 FROM task_state
                         WHERE (learner, lesson) NOT IN (SELECT learner, lesson FROM lesson_state)) AS l
                   LEFT JOIN task_state t ON t.learner = l.learner AND t.lesson = l.lesson
                   GROUP BY l.learner, l.lesson ORDER BY l.learner, l.lesson"""
            ).fetchall()
        return [ProgressRow(a, b, int(c), int(d), int(e)) for a, b, c, d, e in rows]
