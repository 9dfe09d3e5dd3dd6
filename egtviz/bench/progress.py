"""The start page's progress read at classroom scale: one render's lesson lines for one learner.

``python -m egtviz.bench.progress [--learners N ...]`` builds a progress database of N learners (each in three
lessons, three tasks checked in each) in a temporary folder, then times one render's read of the course's
statuses (:func:`~egtviz.viewer.course.start_page.course_statuses`: one indexed query) against the read the page did
before (three queries per lesson, one of them the whole table's summary), timed in the same run. Prints
medians in milliseconds and their ratio.
"""

from __future__ import annotations

import argparse
import random
import sqlite3
import statistics
import tempfile
import time
from pathlib import Path

from ..lessons import ProgressStore, list_lessons, load
from ..lessons.progress import migrate

__all__ = ["build_database", "progress_rows", "run_progress_bench"]


def build_database(path: Path, learners: int, lessons: list[str], seed: int = 0) -> None:
    """A progress database of ``learners`` learners, each at a step of three lessons with three tasks checked."""
    rng = random.Random(seed)
    conn = sqlite3.connect(path)
    try:
        migrate(conn)
        with conn:
            conn.executemany("INSERT INTO learners (name, created) VALUES (?, 0.0)",
                             ((f"learner {i}",) for i in range(learners)))
            for i in range(learners):
                for lesson in rng.sample(lessons, 3):
                    conn.execute("INSERT INTO lesson_state (learner, lesson, step, updated) VALUES (?, ?, ?, 0.0)",
                                 (f"learner {i}", lesson, rng.randrange(3)))
                    conn.executemany("INSERT INTO task_state (learner, lesson, step, task, attempts, passed, updated) "
                                     "VALUES (?, ?, ?, ?, 2, ?, 0.0)",
                                     ((f"learner {i}", lesson, t, f"task-{t}", rng.randrange(2)) for t in range(3)))
    finally:
        conn.close()


def _old_render(store: ProgressStore, learner: str, lessons: dict) -> None:
    """What one render read before: per lesson the passed tasks, the step, and the whole table's summary."""
    for name in lessons:
        store.passed_tasks(learner, name)
        store.current_step(learner, name)
        any(r.learner == learner and r.lesson == name for r in store.summary())


def _median_ms(action, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        action()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def run_progress_bench(learners: list[int], repeats: int = 20, baseline_repeats: int = 1) -> list[dict]:
    """Rows ``{learners, new_ms, old_ms, ratio}`` for each database size."""
    from ..viewer.course.start_page import course_statuses

    lessons = {info.name: load(info.name) for info in list_lessons()}
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for n in learners:
            path = Path(folder) / f"progress-{n}.sqlite3"
            build_database(path, n, list(lessons))
            store = ProgressStore(path)
            who = f"learner {n // 2}"
            new = _median_ms(lambda: course_statuses(store, who, lessons), repeats)
            old = _median_ms(lambda: _old_render(store, who, lessons), baseline_repeats)
            rows.append({"learners": n, "new_ms": new, "old_ms": old, "ratio": old / new})
    return rows


def progress_rows(learners: tuple[int, ...] = (20_000, 100_000), repeats: int = 20) -> list[dict]:
    """The bench table's rows (``egtviz bench progress``): one render's read, the ratio to the read before."""
    return [{"case": f"start page progress read, {r['learners']:,} learners", "ours_ms": r["new_ms"],
             "opencv_ms": None, "ratio": None,
             "note": f"the page's read before this change, 3 queries a lesson: {r['old_ms']:.1f} ms "
                     f"({r['ratio']:,.0f} times as long)"}
            for r in run_progress_bench(list(learners), repeats)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m egtviz.bench.progress", description=__doc__.splitlines()[0])
    parser.add_argument("--learners", type=int, nargs="+", default=[20_000, 100_000])
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args(argv)
    print(f"{'learners':>9} {'one query ms':>13} {'before ms':>10} {'ratio':>8}")
    for r in run_progress_bench(args.learners, args.repeats):
        print(f"{r['learners']:>9} {r['new_ms']:>13.3f} {r['old_ms']:>10.1f} {r['ratio']:>8.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
