"""The progress database with many writers: worker processes of one server recording at once lose nothing.

Four processes each record attempts as fast as they can into one file while reading it back (as the roster
does); every attempt must be in the file at the end and no process may have given up on the file.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

from egtviz.lessons.progress import ProgressStore

_WRITER = r"""
import json, sys, time
from egtviz.lessons.progress import ProgressStore
path, who, n, start = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
store = ProgressStore(path)
time.sleep(max(0.0, start - time.time()))
for k in range(n):
    store.record_attempt(f"{who} {k % 7}", "01_pinhole", k % 3, f"task{k % 5}", passed=(k % 11 == 0), hint_tiers=2)
    if k % 50 == 0:
        store.set_step(f"{who} {k % 7}", "01_pinhole", k % 3)
        store.summary()
print(json.dumps({"problem": store.problem, "persistent": store.persistent}))
"""

PROCESSES = 4
ATTEMPTS = 500


def test_four_processes_writing_at_once_lose_no_attempt(tmp_path: Path) -> None:
    path = tmp_path / "progress.sqlite3"
    ProgressStore(path)  # made once, as the supervising process's first worker would
    start = time.time() + 3.0  # every writer imported and ready before the first write
    procs = [subprocess.Popen([sys.executable, "-c", _WRITER, str(path), f"w{i}", str(ATTEMPTS), repr(start)],
                              stdout=subprocess.PIPE, text=True) for i in range(PROCESSES)]
    outs = [json.loads(p.communicate(timeout=120)[0]) for p in procs]
    assert all(p.returncode == 0 for p in procs)
    assert outs == [{"problem": None, "persistent": True}] * PROCESSES  # no process fell back to memory
    records = ProgressStore(path, read_only=True).task_records()
    assert sum(r.attempts for r in records) == PROCESSES * ATTEMPTS
    assert len({(r.learner, r.step, r.task) for r in records}) == len(records)


def test_a_file_locked_past_the_busy_timeout_is_tried_again_not_given_up(tmp_path: Path, monkeypatch) -> None:
    import sqlite3
    import threading

    from egtviz.lessons import progress

    monkeypatch.setattr(progress, "_TIMEOUT_S", 0.2)
    path = tmp_path / "progress.sqlite3"
    store = ProgressStore(path)
    other = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
    other.execute("BEGIN EXCLUSIVE")  # another worker's long transaction
    release = threading.Timer(0.5, lambda: other.execute("COMMIT"))
    release.start()
    try:
        store.record_attempt("Ada", "01_pinhole", 0, "task", passed=True)
    finally:
        release.join()
        other.close()
    assert store.problem is None and store.persistent
    assert store.attempts("Ada", "01_pinhole", 0, "task") == 1
    assert [r.attempts for r in ProgressStore(path, read_only=True).task_records()] == [1]
