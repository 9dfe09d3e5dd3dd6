"""Learners' progress in SQLite: the current step of each lesson, the tasks passed, the attempts and the hints.

One database file in the user's data folder (:func:`default_database_path`), keyed by the name the learner
types (:func:`learner_key`), so a reload, a new tab or a restarted server resumes where they were. The
schema is versioned with ``PRAGMA user_version`` and upgraded by :func:`migrate` (version 2 added the hints a
learner was shown per task; a version-1 file keeps all it held, its tasks at 0 hints). Every call opens its own
connection (``sqlite3`` connections are not shared between threads) and writes in one transaction, so
several threads, or several server processes, may use one file.

A file that cannot be used never stops the course: a folder, a FIFO, bytes that are no SQLite database, a
database of a newer egtviz, a read-only folder, a full disk. The store then keeps this session's progress
in memory, says why once (:attr:`ProgressStore.problem`, naming the file, and a warning on the terminal)
and leaves the file exactly as it was: nothing is written, no journal is made, no schema is migrated. A file
that stops being writable while the server runs (the disk fills, the file is replaced) is handled the same
way from the first write that fails; what the file held is carried over when it can still be read.
"""

from __future__ import annotations

import logging
import os
import sqlite3
import stat
import threading
import time
import unicodedata
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar
from urllib.parse import quote

__all__ = [
    "SCHEMA_VERSION", "LearnerNameError", "LessonProgress", "ProgressRow", "ProgressStore", "TaskRecord",
    "default_database_path", "learner_key",
]

SCHEMA_VERSION = 2
MAX_LEARNER_NAME = 40
"""Characters of a learner's name (after trimming)."""
_TIMEOUT_S = 10.0
#: Uses of a file that stays locked by another connection (each waiting up to :data:`_TIMEOUT_S`) before it counts
#: as failed.
_BUSY_TRIES = 6
_log = logging.getLogger(__name__)
_T = TypeVar("_T")

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
    2: ("ALTER TABLE task_state ADD COLUMN hints INTEGER NOT NULL DEFAULT 0",),
}
"""Statements that take the schema from version ``n - 1`` to ``n``. The primary keys lead with the learner:
every per-learner read (the start page's, the runner's) is an index search, not a scan of the table."""

_TABLES = frozenset({"learners", "lesson_state", "task_state"})
#: Joiners that shape what is around them (an emoji family, a Persian word): allowed between two visible
#: characters. Every other format character (bidi overrides and isolates, zero-width spaces, tags) is refused.
_JOINERS = frozenset("\u200c\u200d")
_FILE_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
               (stat.S_ISCHR, "a device"), (stat.S_ISBLK, "a device"))


class LearnerNameError(ValueError):
    """A learner name that cannot be used (empty, too long, control characters)."""


def learner_key(name: object) -> str:
    """The name a learner typed as the key of their progress: NFC-normalised, trimmed, inner runs of spaces
    made one; 1 to :data:`MAX_LEARNER_NAME` characters, no control or format characters except a zero-width
    joiner or non-joiner between two visible characters (emoji sequences such as a family, joined scripts).
    Variation selectors (emoji or text presentation) are marks and are kept.

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
    for i, c in enumerate(key):
        if unicodedata.category(c)[0] != "C":
            continue
        if c in _JOINERS and 0 < i < len(key) - 1 and _visible(key[i - 1]) and _visible(key[i + 1]):
            continue
        raise LearnerNameError(f"name: control characters are not allowed (U+{ord(c):04X})")
    return key


def _visible(c: str) -> bool:
    return not c.isspace() and unicodedata.category(c)[0] != "C"


def default_database_path() -> Path:
    """``$EGTVIZ_DATA_DIR/progress.sqlite3``, else ``$XDG_DATA_HOME/egtviz/...``, else ``~/.local/share/egtviz/...``."""
    folder = os.environ.get("EGTVIZ_DATA_DIR")
    if not folder:
        xdg = os.environ.get("XDG_DATA_HOME")
        home = os.path.join(os.path.expanduser("~"), ".local", "share")
        folder = os.path.join(xdg or home, "egtviz")
    return Path(folder) / "progress.sqlite3"


def migrate(conn: sqlite3.Connection, to: int = SCHEMA_VERSION) -> int:
    """Bring the schema of ``conn`` to version ``to`` (default :data:`SCHEMA_VERSION`); returns the version found.

    Raises:
        sqlite3.DatabaseError: a database written by a newer egtviz (its version is higher).
    """
    found = conn.execute("PRAGMA user_version").fetchone()[0]
    if found > SCHEMA_VERSION:
        raise sqlite3.DatabaseError(f"progress database of schema version {found}; this egtviz reads {SCHEMA_VERSION}")
    for version in range(found + 1, to + 1):
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


@dataclass(frozen=True)
class TaskRecord:
    """What one learner did at one task (a line of ``egtviz progress --csv``)."""

    learner: str
    lesson: str
    step: int
    """The task's step (0-based)."""
    task: str
    passed: bool
    attempts: int
    hints: int
    """How many of the task's hints were shown (one more after each failed attempt, up to the task's tiers)."""
    updated: float
    """When the last attempt was checked (seconds since the epoch)."""


@dataclass(frozen=True)
class LessonProgress:
    """What one learner did in one lesson (the start page's line for it)."""

    step: int
    """The step they were last at (0-based; 0 if they only checked tasks)."""
    passed: frozenset[tuple[int, str]]
    """``(step, task id)`` of the tasks passed."""


class _Unusable(Exception):
    """The file cannot hold progress: ``reason`` (naming it) and, when it can still be read, a read-only
    connection to carry its progress over into memory."""

    def __init__(self, reason: str, seed: sqlite3.Connection | None = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.seed = seed


def _shown(path: Path | str) -> str:
    """A path as a message shows it: no control characters."""
    text = os.fspath(path)
    return "".join(c if c.isprintable() else f"\\u{ord(c):04x}" for c in text)


def _uri(path: Path, mode: str) -> str:
    return f"file:{quote(os.path.abspath(path))}?mode={mode}"


def _file_problem(path: Path) -> str | None:
    """Why ``path`` cannot be a database file (a folder, a FIFO...), None if it is a regular file or absent.

    Raises:
        _Unusable: its folder is not a folder.
    """
    folder = path.parent
    if folder.exists() and not folder.is_dir():
        raise _Unusable(f"the data folder {_shown(folder)} is a file, not a folder")
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return None
    except NotADirectoryError as exc:
        raise _Unusable(f"the data folder {_shown(folder)} cannot be made (a part of its path is a file)") from exc
    except OSError as exc:
        raise _Unusable(f"{_shown(path)} cannot be read ({exc.strerror})") from exc
    for test, kind in _FILE_KINDS:
        if test(mode):
            return f"{_shown(path)} is {kind}, not a progress database"
    return None


def _read_only(path: Path) -> sqlite3.Connection:
    """A read-only connection to the progress database ``path`` (it never writes, creates or journals).

    Raises:
        _Unusable: it is not a progress database of a version this egtviz reads.
    """
    conn = sqlite3.connect(_uri(path, "ro"), uri=True, timeout=_TIMEOUT_S, check_same_thread=False)
    try:
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    except sqlite3.OperationalError as exc:  # locked by another program, or not readable: not a wrong file
        conn.close()
        raise _Unusable(f"{_shown(path)} cannot be read ({exc})") from exc
    except sqlite3.DatabaseError as exc:
        conn.close()
        raise _Unusable(f"{_shown(path)} is not a progress database ({exc})") from exc
    if version > SCHEMA_VERSION:
        conn.close()
        raise _Unusable(f"{_shown(path)} was written by a newer egtviz (schema version {version}; this one "
                        f"reads {SCHEMA_VERSION})")
    if (version == 0 and tables) or (version > 0 and not _TABLES <= tables):
        conn.close()
        raise _Unusable(f"{_shown(path)} is not a progress database (it holds other tables)")
    return conn


def _writable(path: Path) -> str | None:
    """Why the database ``path`` (or the journal next to it) cannot be written, None if it can."""
    folder = path.parent
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"{_shown(path)} cannot be written: its folder is read-only"
    if path.exists() and not os.access(path, os.W_OK):
        return f"{_shown(path)} is read-only"
    return None


class ProgressStore:
    """The progress database at ``path`` (created with its folder on first use).

    Args:
        path: the database file (default :func:`default_database_path`).
        read_only: only read the file (opened ``mode=ro``: never written, created or journalled), e.g. for a
            report; a path that does not exist reads as no progress.
        max_pages: at most this many pages in the file (SQLite's ``max_page_count``): a quota; a write past it
            is handled like a full disk.

    Nothing here raises for the file: a file that cannot be used leaves :attr:`problem` saying why, and the
    progress is then kept in memory for as long as this store lives.
    """

    def __init__(self, path: str | os.PathLike | None = None, *, read_only: bool = False,
                 max_pages: int | None = None) -> None:
        self.path = Path(path) if path is not None else default_database_path()
        self.read_only = bool(read_only)
        self.max_pages = max_pages
        self._lock = threading.RLock()
        self._memory: sqlite3.Connection | None = None
        #: Why the file cannot be used (naming it), None while it can.
        self.fault: str | None = None
        try:
            self._open()
        except _Unusable as exc:
            self._fall_back(exc.reason, exc.seed)
        except (OSError, sqlite3.Error) as exc:
            self._fall_back(f"{_shown(self.path)} cannot be used ({_why(exc)})", None)

    @property
    def problem(self) -> str | None:
        """Why progress is not being kept in the file, as the course says it (a sentence naming the file), None
        while it is."""
        if self.fault is None:
            return None
        return (f"Progress is not being kept: {self.fault}. This session's progress is kept in memory until the "
                "server stops.")

    @property
    def persistent(self) -> bool:
        """Whether what is recorded goes to the file (False: into memory, until this store is dropped)."""
        return self._memory is None

    def _open(self) -> None:
        """Check the file and bring it to the current schema (read-only: only check it).

        Raises:
            _Unusable: why the file cannot be used.
        """
        kind = _file_problem(self.path)
        if kind is not None:
            raise _Unusable(kind)
        if not self.path.exists():
            if self.read_only:  # no progress yet; nothing is made
                self._memory = self._empty_memory()
            else:
                self._create()
            return
        seed = _read_only(self.path)
        if self.read_only:
            version = seed.execute("PRAGMA user_version").fetchone()[0]
            if version == 0:  # an empty file, or an empty SQLite database: a report does not make it one
                seed.close()
                raise _Unusable(f"{_shown(self.path)} is not a progress database (it holds no progress tables)")
            if version < SCHEMA_VERSION:  # an older schema is read through a copy upgraded in memory, not in place
                self._memory = self._upgraded_copy(seed)
            seed.close()
            return
        try:
            version = seed.execute("PRAGMA user_version").fetchone()[0]
            refusal = _writable(self.path)
            if refusal is not None:
                raise _Unusable(refusal, seed)
            if version < SCHEMA_VERSION:
                with self._connect() as conn:
                    migrate(conn)
        except (OSError, sqlite3.Error) as exc:
            raise _Unusable(f"{_shown(self.path)} cannot be written ({_why(exc)})", seed) from exc
        seed.close()

    def _create(self) -> None:
        """A new database file (and its folder)."""
        folder = self.path.parent
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise _Unusable(f"the data folder {_shown(folder)} cannot be made ({_why(exc)})") from exc
        refusal = _writable(self.path)
        if refusal is not None:
            raise _Unusable(refusal)
        conn = sqlite3.connect(_uri(self.path, "rwc"), uri=True, timeout=_TIMEOUT_S)
        try:
            self._limit(conn)
            migrate(conn)
        except sqlite3.Error as exc:
            conn.close()
            if self.path.is_file() and self.path.stat().st_size == 0:
                self.path.unlink()  # the empty file this call made: nothing of it is left behind
            raise _Unusable(f"{_shown(self.path)} cannot be made ({_why(exc)})") from exc
        conn.close()

    def _limit(self, conn: sqlite3.Connection) -> None:
        conn.execute("PRAGMA foreign_keys = ON")
        if self.max_pages is not None:
            conn.execute(f"PRAGMA max_page_count = {int(self.max_pages)}")

    @contextmanager
    def _connect(self) -> Iterator[sqlite3.Connection]:
        """A connection to the file; it must exist (``mode=rw``: a file removed meanwhile is not made again)."""
        conn = sqlite3.connect(_uri(self.path, "ro" if self.read_only else "rw"), uri=True, timeout=_TIMEOUT_S)
        try:
            self._limit(conn)
            yield conn
        finally:
            conn.close()

    @staticmethod
    def _upgraded_copy(seed: sqlite3.Connection) -> sqlite3.Connection:
        """What ``seed`` holds, copied into memory and brought to the current schema."""
        memory = sqlite3.connect(":memory:", check_same_thread=False)
        seed.backup(memory)
        migrate(memory)
        return memory

    @staticmethod
    def _empty_memory() -> sqlite3.Connection:
        memory = sqlite3.connect(":memory:", check_same_thread=False)
        migrate(memory)
        memory.execute("PRAGMA foreign_keys = ON")
        return memory

    def _fall_back(self, reason: str, seed: sqlite3.Connection | None) -> None:
        """Keep progress in memory from now on (a copy of what ``seed`` can still read, else nothing) and say
        why, once: :attr:`problem`, and a warning on the terminal (not for a read-only store: its caller says)."""
        memory = sqlite3.connect(":memory:", check_same_thread=False)
        try:
            if seed is not None:
                seed.backup(memory)
            migrate(memory)
            memory.execute("PRAGMA foreign_keys = ON")
        except sqlite3.Error:
            memory.close()
            memory = self._empty_memory()
        finally:
            if seed is not None:
                seed.close()
        self._memory = memory
        self.fault = reason
        if not self.read_only:
            _log.warning("egtviz: %s", self.problem)

    def _degrade(self, exc: BaseException) -> None:
        """A use of the file failed: progress goes to memory from now on (once; later calls find it there)."""
        with self._lock:
            if self._memory is not None:
                return
            try:
                seed = sqlite3.connect(_uri(self.path, "ro"), uri=True, check_same_thread=False)
            except sqlite3.Error:
                seed = None
            self._fall_back(f"{_shown(self.path)} could not be used any more ({_why(exc)})", seed)

    def _run(self, work: Callable[[sqlite3.Connection], _T], *, write: bool) -> _T:
        """``work`` on the file (a write: one transaction, under the lock), or in memory once the file failed.

        A file another process holds locked past the busy timeout (several server processes share it) is
        tried again, :data:`_BUSY_TRIES` times in all, before it counts as failed: a busy file is not a broken one.
        """
        tries = 0
        while self._memory is None:
            try:
                if not write:
                    with self._connect() as conn:
                        return work(conn)
                with self._lock:
                    if self._memory is None:
                        with self._connect() as conn, conn:
                            return work(conn)
            except (sqlite3.DatabaseError, OSError) as exc:
                if isinstance(exc, (sqlite3.IntegrityError, sqlite3.ProgrammingError)):
                    raise  # a fault of this code, not of the file
                tries += 1
                if _busy(exc) and tries < _BUSY_TRIES:
                    time.sleep(0.05 * tries)
                    continue
                self._degrade(exc)
        with self._lock:
            return self._in_memory(work)

    def _in_memory(self, work: Callable[[sqlite3.Connection], _T]) -> _T:
        memory = self._memory
        assert memory is not None
        with memory:
            return work(memory)

    @staticmethod
    def _learner(conn: sqlite3.Connection, key: str) -> None:
        conn.execute("INSERT OR IGNORE INTO learners (name, created) VALUES (?, ?)", (key, time.time()))

    def set_step(self, learner: str, lesson: str, step: int) -> None:
        """Remember that ``learner`` is at ``step`` of ``lesson``."""
        key = learner_key(learner)

        def work(conn: sqlite3.Connection) -> None:
            self._learner(conn, key)
            conn.execute(
                "INSERT INTO lesson_state (learner, lesson, step, updated) VALUES (?, ?, ?, ?) "
                "ON CONFLICT (learner, lesson) DO UPDATE SET step = excluded.step, updated = excluded.updated",
                (key, lesson, int(step), time.time()),
            )

        self._run(work, write=True)

    def record_attempt(self, learner: str, lesson: str, step: int, task: str, passed: bool, *,
                       hint_tiers: int = 0) -> int:
        """Count one attempt at a task; once passed, a task stays passed. A failed attempt shows one more of the
        task's ``hint_tiers`` hints (none past the last); returns how many of them the learner has now been shown.
        """
        key = learner_key(learner)
        tiers = max(int(hint_tiers), 0)
        more = 0 if passed else 1

        def work(conn: sqlite3.Connection) -> int:
            self._learner(conn, key)
            conn.execute(
                "INSERT INTO task_state (learner, lesson, step, task, attempts, passed, updated, hints) "
                "VALUES (?, ?, ?, ?, 1, ?, ?, min(?, ?)) ON CONFLICT (learner, lesson, step, task) DO UPDATE SET "
                "attempts = attempts + 1, passed = max(passed, excluded.passed), updated = excluded.updated, "
                "hints = max(hints, min(hints + ?, ?))",
                (key, lesson, int(step), task, int(bool(passed)), time.time(), more, tiers, more, tiers),
            )
            row = conn.execute("SELECT hints FROM task_state WHERE learner = ? AND lesson = ? AND step = ? "
                               "AND task = ?", (key, lesson, int(step), task)).fetchone()
            return int(row[0])

        return self._run(work, write=True)

    def current_step(self, learner: str, lesson: str) -> int:
        """The step ``learner`` was last at in ``lesson`` (0 if never started)."""
        row = self._run(lambda conn: conn.execute("SELECT step FROM lesson_state WHERE learner = ? AND lesson = ?",
                                                  (learner_key(learner), lesson)).fetchone(), write=False)
        return int(row[0]) if row else 0

    def passed_tasks(self, learner: str, lesson: str) -> frozenset[tuple[int, str]]:
        """``(step, task id)`` of the tasks ``learner`` has passed in ``lesson``."""
        rows = self._run(lambda conn: conn.execute(
            "SELECT step, task FROM task_state WHERE learner = ? AND lesson = ? AND passed = 1",
            (learner_key(learner), lesson)).fetchall(), write=False)
        return frozenset((int(s), t) for s, t in rows)

    def attempts(self, learner: str, lesson: str, step: int, task: str) -> int:
        """How many times ``learner`` checked that task (0 if never)."""
        row = self._run(lambda conn: conn.execute(
            "SELECT attempts FROM task_state WHERE learner = ? AND lesson = ? AND step = ? AND task = ?",
            (learner_key(learner), lesson, int(step), task)).fetchone(), write=False)
        return int(row[0]) if row else 0

    def hints_shown(self, learner: str, lesson: str, step: int, task: str) -> int:
        """How many of that task's hints ``learner`` has been shown (0 if never)."""
        row = self._run(lambda conn: conn.execute(
            "SELECT hints FROM task_state WHERE learner = ? AND lesson = ? AND step = ? AND task = ?",
            (learner_key(learner), lesson, int(step), task)).fetchone(), write=False)
        return int(row[0]) if row else 0

    def task_records(self, learner: str | None = None, lesson: str | None = None) -> list[TaskRecord]:
        """Every task a learner checked (``learner``: only theirs; ``lesson``: only that lesson's), sorted by
        learner, lesson, step and task."""
        where, args = [], []
        if learner is not None:
            where.append("learner = ?")
            args.append(learner_key(learner))
        if lesson is not None:
            where.append("lesson = ?")
            args.append(lesson)
        sql = ("SELECT learner, lesson, step, task, passed, attempts, hints, updated FROM task_state"
               + (" WHERE " + " AND ".join(where) if where else "") + " ORDER BY learner, lesson, step, task")
        rows = self._run(lambda conn: conn.execute(sql, args).fetchall(), write=False)
        return [TaskRecord(a, b, int(c), d, bool(e), int(f), int(g), float(h)) for a, b, c, d, e, f, g, h in rows]

    def lessons_of(self, learner: str) -> dict[str, LessonProgress]:
        """Every lesson ``learner`` started (moved in it or checked a task), in one indexed query."""
        key = learner_key(learner)
        rows = self._run(lambda conn: conn.execute(
            "SELECT lesson, step, NULL, 0 FROM lesson_state WHERE learner = ? "
            "UNION ALL SELECT lesson, step, task, passed FROM task_state WHERE learner = ?", (key, key)).fetchall(),
            write=False)
        steps: dict[str, int] = {}
        passed: dict[str, set[tuple[int, str]]] = {}
        for lesson, step, task, ok in rows:
            passed.setdefault(lesson, set())
            if task is None:
                steps[lesson] = int(step)
            elif ok:
                passed[lesson].add((int(step), task))
        return {lesson: LessonProgress(steps.get(lesson, 0), frozenset(done)) for lesson, done in passed.items()}

    def learners(self) -> list[str]:
        """Every learner who has made progress, sorted."""
        return self._run(lambda conn: [r[0] for r in conn.execute("SELECT name FROM learners ORDER BY name")],
                         write=False)

    def summary(self) -> list[ProgressRow]:
        """One row per learner and lesson started, sorted by learner then lesson."""
        rows = self._run(lambda conn: conn.execute(
            """SELECT l.learner, l.lesson, l.step,
                      COALESCE(SUM(t.passed), 0), COALESCE(SUM(t.attempts), 0)
               FROM (SELECT learner, lesson, step FROM lesson_state
                     UNION SELECT learner, lesson, 0 FROM task_state
                     WHERE (learner, lesson) NOT IN (SELECT learner, lesson FROM lesson_state)) AS l
               LEFT JOIN task_state t ON t.learner = l.learner AND t.lesson = l.lesson
               GROUP BY l.learner, l.lesson ORDER BY l.learner, l.lesson""").fetchall(), write=False)
        return [ProgressRow(a, b, int(c), int(d), int(e)) for a, b, c, d, e in rows]


def _busy(exc: BaseException) -> bool:
    """Whether ``exc`` says the file is locked by another connection (it will be free again)."""
    code = getattr(exc, "sqlite_errorcode", None)
    if code is not None:
        return code & 0xFF in (sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED)
    return isinstance(exc, sqlite3.OperationalError) and "locked" in str(exc)


def _why(exc: BaseException) -> str:
    """An error as a message shows it: the OS's words for an OSError, SQLite's for the rest."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc)
