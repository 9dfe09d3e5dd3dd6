"""The progress database with many writers: worker processes of one server recording at once lose nothing.

Four processes each record attempts as fast as they can into one file while reading it back (as the roster
does); every attempt must be in the file at the end and no process may have given up on the file.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from egtviz.lessons.progress import ProgressStore

from _subprocesses import Printed
from _waiting import wait_for

_WRITER = r"""
import json, sys
from egtviz.lessons.progress import ProgressStore
path, who, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
store = ProgressStore(path)
print("ready", flush=True)
sys.stdin.readline()  # "go": every writer is imported and ready before the first write
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
    procs = [subprocess.Popen([sys.executable, "-c", _WRITER, str(path), f"w{i}", str(ATTEMPTS)],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i in range(PROCESSES)]
    printed = [Printed(p) for p in procs]
    try:
        wait_for(lambda: all(p.out for p in printed), f"the {PROCESSES} writers to be ready")
        for p in procs:  # all at once
            p.stdin.write("go\n")
            p.stdin.flush()
        outs = [json.loads(p.finish(f"writer {i} to record its {ATTEMPTS} attempts")[0].splitlines()[-1])
                for i, p in enumerate(printed)]
    finally:
        for p in printed:
            p.kill()
    assert all(p.returncode == 0 for p in procs), [p.said() for p in printed]
    assert outs == [{"problem": None, "persistent": True}] * PROCESSES  # no process fell back to memory
    records = ProgressStore(path, read_only=True).task_records()
    assert sum(r.attempts for r in records) == PROCESSES * ATTEMPTS
    assert len({(r.learner, r.step, r.task) for r in records}) == len(records)


def test_a_file_locked_past_the_busy_timeout_is_tried_again_not_given_up(tmp_path: Path, monkeypatch) -> None:
    import sqlite3

    from egtviz.lessons import progress

    monkeypatch.setattr(progress, "_TIMEOUT_S", 0.2)
    path = tmp_path / "progress.sqlite3"
    store = ProgressStore(path)
    other = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
    other.execute("BEGIN EXCLUSIVE")  # another worker's long transaction
    told_busy = []
    busy = progress._busy

    def busy_then_released(exc: BaseException) -> bool:
        # The other worker ends its transaction once the store has waited its whole busy timeout and been told
        # the file is locked (an event, not a time that a busy machine might overrun).
        said = busy(exc)
        if said and not told_busy:
            told_busy.append(exc)
            other.execute("COMMIT")
        return said

    monkeypatch.setattr(progress, "_busy", busy_then_released)
    try:
        store.record_attempt("Ada", "01_pinhole", 0, "task", passed=True)
    finally:
        other.close()
    assert told_busy, "the store never found the file locked"
    assert store.problem is None and store.persistent
    assert store.attempts("Ada", "01_pinhole", 0, "task") == 1
    assert [r.attempts for r in ProgressStore(path, read_only=True).task_records()] == [1]
