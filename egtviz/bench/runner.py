"""``egtviz bench``: run the suites and print one table (``classroom``: its own report)."""

from __future__ import annotations

import platform
import sys


def _suites(name: str, repeats: int):
    if name in ("core", "all"):
        from .core import run_projection_bench
        from .estimation import run_estimation_bench
        from .panoramic import bench_conics

        yield "core", lambda: run_projection_bench(repeats=repeats) + bench_conics() + run_estimation_bench(repeats=repeats)
    if name in ("viewer", "all"):
        from .viewer import run_viewer_bench

        yield "viewer", run_viewer_bench
    if name in ("servo", "all"):
        from .servo import run_servo_bench

        yield "servo", run_servo_bench
    if name == "progress":  # the start page's read of a large progress database (builds it first: about a minute)
        from .progress import progress_rows

        yield "progress", lambda: progress_rows(repeats=repeats)
    if name == "figures":  # EGT's figures: plots at up to a million points, drawing loops with tabs open
        from .figures import run_figures_bench

        yield "figures", run_figures_bench


def format_table(rows: list[dict]) -> str:
    head = f"{'case':<58} {'ours ms':>9} {'OpenCV ms':>10} {'ratio':>7}  note"
    lines = [head, "-" * len(head)]
    for r in rows:
        cv = "" if r.get("opencv_ms") is None else f"{r['opencv_ms']:.3f}"
        ratio = "" if r.get("ratio") is None else f"{r['ratio']:.2f}"
        lines.append(f"{r['case']:<58} {r['ours_ms']:>9.3f} {cv:>10} {ratio:>7}  {r.get('note', '')}")
    return "\n".join(lines)


def run(suite: str = "all", repeats: int = 20, *, json_path: str | None = None, scene: str | None = None,
        points: int | None = None, workers: int | None = None, followers: int | None = None) -> int:
    print(f"egtviz bench {suite}: Python {platform.python_version()}, {platform.machine()}, one run, medians", flush=True)
    if suite != "classroom" and (json_path, scene, points, workers, followers) != (None,) * 5:
        print("egtviz bench: --json, --scene, --points, --workers and --followers are options of the classroom "
              "suite only", file=sys.stderr)
        return 2
    if suite == "classroom" and (workers, followers) != (None, None):  # served by worker processes
        if points is not None:
            print("egtviz bench: --points is not an option of the --workers/--followers runs", file=sys.stderr)
            return 2
        from .classroom_room import run_room_bench

        print(run_room_bench(workers or 1, followers, scene=scene, json_path=json_path), flush=True)
        return 0
    if suite == "classroom":  # many tabs on one server: not part of "all" (about two minutes)
        from .classroom import run_classroom_bench

        print(run_classroom_bench(json_path=json_path, scene=scene, points=points), flush=True)
        return 0
    for name, fn in _suites(suite, repeats):
        print(f"\n[{name}]", flush=True)
        print(format_table(fn()), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(run(sys.argv[1] if len(sys.argv) > 1 else "all"))
