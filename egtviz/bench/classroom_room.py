"""A classroom served by N worker processes: K tabs dragging at once, and one instructor with M followers.

``egtviz bench classroom --workers N [--followers M] [--json FILE]``. Method (also in ``docs/benchmarks.md``):

* **Server.** The real ``egtviz serve --workers N`` (:class:`egtviz.viewer.server.workers.Supervisor`: N worker
  processes on one port, the kernel sharing the connections; with followers, ``--classroom`` and its hub). Each
  worker is the ordinary server with the benchmark's instruments (this module's worker): on ``instrument`` it
  hooks every tab's public timing hook (``ClientView.on_update_timed``) to log what each update drew (the
  revision and camera 1's position), on ``report`` it sends that log, its CPU seconds and its memory.
* **Tabs.** Raw websocket clients (:mod:`egtviz.bench.ws_client`'s protocol) in one separate process; which
  worker holds each tab is read from ``/proc``. As in ``egtviz bench classroom``, update ``k`` of tab ``j`` puts
  camera 1 at ``p0 + (k + 1) * 1 mm * x + (j + 1) * 1 mm * y``, so the position drawn says which update drew.
* **Drag.** K tabs (default 30) each drag camera 1 at 20 Hz for the given time. Lag of an update: from its send
  to the arrival at its tab of the first panel drawn from it or from a later update of that tab; an update that
  no panel answered before the tabs went quiet is *unanswered*.
* **Followers.** One instructor tab drags at 20 Hz; M students follow. Lag at a follower: from the instructor's
  send to the arrival at that follower of the first panel (the instructor's own SVG, with its revision) drawn
  from that update or a later one; unanswered as above, per follower.
* **Memory.** Resident memory of every worker and of the supervising process after the run, summed.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import gc
import json
import os
import re
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["RoomRun", "format_room", "room_record", "run_drag", "run_followers", "run_room_bench"]

#: Tabs that drag at once in the drag run.
DRAG_TABS = 30
RATE_HZ = 20.0
DRAG_SECONDS = 8.0
STEP_M = 1e-3
GIZMO = "/egt/cam_0"
WINDOW = (1366, 768)
#: Seconds without a panel after the last send before a tab stops listening.
QUIET_S = 1.5
_PANEL_REV = re.compile(rb'data-egtviz="image-plane" data-camera="[^"]*" data-rev="(\d+)"')


# -- the instrumented worker -----------------------------------------------------------------------------------


def _rss_bytes(pid: int | str = "self") -> int:
    try:
        return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:
        return 0


def bench_worker_main() -> int:
    """A worker of the benchmark: the ordinary worker (:func:`~egtviz.viewer.server.workers.start_worker`) that
    also answers ``instrument`` and ``report`` on its input (each reply one line)."""
    from ..viewer.server.workers import REPLY, start_worker

    config = json.loads(sys.stdin.readline())
    server, app, host, bus = start_worker(config)
    print("egtviz-worker-ready " + json.dumps({"index": config["index"], "pid": os.getpid()}), flush=True)
    logs: dict[int, list] = {}
    revs0: dict[int, int] = {}
    views: dict[int, Any] = {}
    cpu0 = time.process_time()
    for line in sys.stdin:
        command = line.strip()
        if command == "instrument":
            views = dict(app.views)
            logs = {cid: [] for cid in views}
            for cid, view in views.items():
                view.on_update_timed = _logger(view, logs[cid])
            revs0 = {cid: v.revision for cid, v in views.items()}
            gc.collect()
            cpu0 = time.process_time()
            reply: dict[str, Any] = {"views": len(views)}
        elif command == "report":
            reply = {"cpu_s": time.process_time() - cpu0, "rss": _rss_bytes(),
                     "applied": sum(v.revision - revs0[cid] for cid, v in views.items()),
                     "drawn": {str(cid): log for cid, log in logs.items()},
                     "relayed": None if bus is None else bus.received}
        else:
            reply = {"error": f"unknown command {command!r}"}
        print(REPLY + json.dumps(reply), flush=True)
    if bus is not None:
        bus.close()
    if host is not None:
        host.close()
    server.stop()
    return 0


def _logger(view: Any, log: list) -> Any:
    def timed(timing: Any) -> None:
        x, y, z = view.model.scene.cameras[0].position
        log.append((timing.revision, float(x), float(y)))

    return timed


# -- the tabs (their own process) ------------------------------------------------------------------------------


class _Tab:
    """A raw tab: answers the class's name question, keeps its gizmo's pose, logs panel revisions."""

    def __init__(self, ws: Any, name: str | None) -> None:
        self.ws, self.name = ws, name
        self.pose: dict[str, Any] = {}
        self.panels: list[tuple[int, float]] = []
        self.sends: list[tuple[int, float]] = []

    async def send(self, message: dict) -> None:
        import msgspec.msgpack

        await self.ws.send(msgspec.msgpack.encode(message))

    async def take(self, frame: bytes, now: float) -> None:
        from .ws_client import decode_frame, frame_payload

        payload = frame_payload(frame)
        revs = [int(r) for r in _PANEL_REV.findall(payload)]
        if revs:
            self.panels.append((max(revs), now))
        if b"LocalStorage" in payload or (b"/egt/cam_0" in payload and "wxyz" not in self.pose):
            for m in decode_frame(frame):
                if m["type"] == "LocalStorageGetItemRequestMessage":
                    await self.send({"type": "LocalStorageGetItemResponseMessage", "value": self.name,
                                     "error": None, "request_uuid": m["request_uuid"]})
                elif m.get("name") == GIZMO and m["type"] == "TransformControlsMessage":
                    self.pose["owner"] = m["owner"]
                elif m.get("name") == GIZMO and m["type"] == "SetPositionMessage":
                    self.pose["position"] = m["position"]
                elif m.get("name") == GIZMO and m["type"] == "SetOrientationMessage":
                    self.pose["wxyz"] = m["wxyz"]

    async def listen(self, until: Any) -> None:
        """Read frames until ``until()`` says stop (checked every 0.1 s)."""
        while not until(self):
            try:
                frame = await asyncio.wait_for(self.ws.recv(decode=False), 0.1)
            except TimeoutError:
                continue
            await self.take(frame, time.time())


async def _open(stack: contextlib.AsyncExitStack, port: int, path: str, name: str | None) -> _Tab:
    import viser
    import websockets.asyncio.client
    from websockets.typing import Subprotocol

    from .ws_client import CAMERA

    ws = await stack.enter_async_context(websockets.asyncio.client.connect(
        f"ws://127.0.0.1:{port}{path}", subprotocols=[Subprotocol(f"viser-v{viser.__version__}")], max_size=None,
        open_timeout=60))
    tab = _Tab(ws, name)
    await tab.send({**CAMERA, "image_width": WINDOW[0], "image_height": WINDOW[1]})
    return tab


async def _until_ready(tab: _Tab, need_pose: bool, timeout: float = 90.0) -> None:
    deadline = time.monotonic() + timeout

    def ready(t: _Tab) -> bool:
        if time.monotonic() > deadline:
            raise TimeoutError("a tab was not ready in time")
        return (len(t.pose) == 3) if need_pose else bool(t.panels)

    await tab.listen(ready)


async def _drag(tab: _Tab, j: int, tabs: int, seconds: float, rate: float, t0: float) -> None:
    x0, y0, z0 = tab.pose["position"]
    base = {"name": GIZMO, "owner": tab.pose["owner"]}
    start = t0 + j / (tabs * rate)
    await asyncio.sleep(max(0.0, start - time.time()))
    await tab.send({"type": "TransformControlsDragStartMessage", **base})
    for k in range(round(seconds * rate)):
        await asyncio.sleep(max(0.0, start + k / rate - time.time()))
        tab.sends.append((k, time.time()))
        await tab.send({"type": "TransformControlsUpdateMessage", **base, "wxyz": tab.pose["wxyz"],
                        "position": [x0 + STEP_M * (k + 1), y0 + STEP_M * (j + 1), z0]})
    await tab.send({"type": "TransformControlsDragEndMessage", **base})


def _quiet_after(done: asyncio.Event, quiet_s: float) -> Any:
    def until(tab: _Tab) -> bool:
        last = tab.panels[-1][1] if tab.panels else 0.0
        return done.is_set() and time.time() - max(last, tab.sends[-1][1] if tab.sends else 0.0) > quiet_s

    return until


async def _tabs_main(config: dict[str, Any]) -> None:
    port, mode, seconds, rate = config["port"], config["mode"], config["seconds"], config["rate"]
    async with contextlib.AsyncExitStack() as stack:
        # Each tab listens from the moment it is open: a student's tab is asked its name at once, and the class
        # gives up waiting for the answer after a few seconds (the tab would then never join).
        waits = []
        if mode == "drag":
            draggers = []
            for _ in range(config["tabs"]):
                draggers.append(await _open(stack, port, "", None))
                waits.append(asyncio.create_task(_until_ready(draggers[-1], True)))
            followers: list[_Tab] = []
        else:
            draggers = [await _open(stack, port, f"/egtviz-instructor/{config['token']}", None)]
            await _until_ready(draggers[0], True)
            followers = []
            for i in range(config["followers"]):
                followers.append(await _open(stack, port, "", f"student {i}"))
                waits.append(asyncio.create_task(_until_ready(followers[-1], False)))
        await asyncio.gather(*waits)
        everyone = draggers + followers
        print(json.dumps({"ports": [t.ws.local_address[1] for t in everyone],
                          "owners": [t.pose.get("owner") for t in draggers],
                          "starts": [t.pose["position"] for t in draggers]}), flush=True)
        t0 = float(await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline))
        cpu0 = time.process_time()
        for t in everyone:
            t.panels.clear()
        done = asyncio.Event()

        async def drag_all() -> None:
            await asyncio.gather(*(_drag(t, j, len(draggers), seconds, rate, t0) for j, t in enumerate(draggers)))
            done.set()

        until = _quiet_after(done, config.get("quiet_s", QUIET_S))
        for t in followers:
            t.sends = draggers[0].sends  # a follower answers the instructor's sends
        await asyncio.gather(drag_all(), *(t.listen(until) for t in everyone))
        print(json.dumps({"tabs": [{"sends": t.sends, "panels": t.panels} for t in everyone],
                          "cpu_s": time.process_time() - cpu0}), flush=True)
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)


def tabs_main() -> int:
    """The tabs' process: its configuration is one JSON line on standard input (the token is never an argument)."""
    config = json.loads(sys.stdin.readline())
    limit = 300.0 + 2.0 * config["seconds"] + config.get("tabs", 0) + config.get("followers", 0)
    asyncio.run(asyncio.wait_for(_tabs_main(config), limit))
    return 0


# -- the run ----------------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class RoomRun:
    """One run. ``kind``: ``drag`` (K tabs dragging) or ``follow`` (one instructor, M followers).

    Attributes:
        kind, workers, tabs: what ran (``tabs``: dragging tabs, or followers).
        sent: drag updates sent (by every dragging tab).
        applied: updates the workers drew.
        lag_ms: p50 and p99 (ms) of the lag (see the module docstring).
        unanswered: sends (per tab or per follower) no panel answered before the end.
        per_worker: tabs each worker held.
        cpu_s: CPU seconds of each worker over the run.
        rss_mb: resident memory (MB) of the workers and the supervising process, summed, after the run.
        tabs_cpu_share: the tabs' process's CPU over the run's wall time (near 1: the client was the limit).
        p99_by_worker_ms: the lag's p99 at the tabs of each worker.
    """

    kind: str
    workers: int
    tabs: int
    seconds: float
    sent: int
    applied: int
    lag_ms: tuple[float, float]
    unanswered: int
    per_worker: tuple[int, ...]
    cpu_s: tuple[float, ...]
    rss_mb: float
    tabs_cpu_share: float
    p99_by_worker_ms: tuple[float, ...] = ()


def _seq_of_rev(drawn: list, start: Sequence[float], j: int) -> dict[int, int]:
    out = {}
    for rev, x, y in drawn:
        if round((y - start[1]) / STEP_M) - 1 == j:
            out[int(rev)] = round((x - start[0]) / STEP_M) - 1
    return out


def _lags(sends: list, panels: list, seq_of_rev: dict[int, int]) -> tuple[list[float], int]:
    arrivals = sorted((t, seq_of_rev[rev]) for rev, t in panels if rev in seq_of_rev)
    lags, unanswered = [], 0
    for k, t_send in sends:
        t = next((t for t, seq in arrivals if seq >= k and t >= t_send), None)
        if t is None:
            unanswered += 1
        else:
            lags.append(t - t_send)
    return lags, unanswered


def _spawn_tabs(config: dict[str, Any]) -> subprocess.Popen:
    proc = subprocess.Popen([sys.executable, "-m", "egtviz.bench.classroom_room", "--tabs"], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdin is not None
    proc.stdin.write(json.dumps(config) + "\n")
    proc.stdin.flush()
    return proc


def _line(proc: subprocess.Popen, what: str) -> dict:
    line = proc.stdout.readline() if proc.stdout is not None else ""
    if not line:
        raise RuntimeError(f"the tabs' process ended (status {proc.poll()}) before {what}")
    return json.loads(line)


def _run(kind: str, workers: int, count: int, seconds: float, rate: float, scene: str | None,
         quiet_s: float = QUIET_S) -> RoomRun:
    from ..viewer.server.workers import Supervisor, WorkerOptions, worker_of_connection

    sup = Supervisor(workers, 0, WorkerOptions(scene=scene, classroom=kind == "follow"),
                     worker_module="egtviz.bench.classroom_room")
    proc = None
    try:
        sup.start()
        config = {"port": sup.port, "mode": kind, "seconds": seconds, "rate": rate, "token": sup.token,
                  "quiet_s": quiet_s,
                  "tabs": count if kind == "drag" else 1, "followers": count if kind == "follow" else 0}
        proc = _spawn_tabs(config)
        joined = _line(proc, "every tab joined")
        pids = [p for p in sup.pids() if p is not None]
        where = [worker_of_connection(sup.port, port, pids) for port in joined["ports"]]
        for i in range(workers):
            sup.ask(i, "instrument")
        time.sleep(0.5)
        t0 = time.time() + 0.3
        assert proc.stdin is not None
        proc.stdin.write(f"{t0!r}\n")
        proc.stdin.flush()
        result = _line(proc, "the drag ended")
        wall = time.time() - t0
        reports = [sup.ask(i, "report") for i in range(workers)]
        rss = sum(r["rss"] for r in reports) + _rss_bytes()
        proc.stdin.close()
        proc.wait(60)
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait(10)
        sup.stop()
    lag, unanswered, by_worker = _lag_summary(kind, result["tabs"], joined, where, pids, reports)
    draggers = len(joined["owners"])
    per_worker = tuple(sum(1 for pid in where if pid == p) for p in pids)
    return RoomRun(kind, workers, count, seconds, sum(len(t["sends"]) for t in result["tabs"][:draggers]),
                   sum(r["applied"] for r in reports), lag, unanswered, per_worker,
                   tuple(r["cpu_s"] for r in reports), rss / 2**20, result["cpu_s"] / wall if wall > 0 else 0.0,
                   by_worker)


def _p(lags: list[float], q: float) -> float:
    return float(np.percentile(lags, q) * 1e3) if lags else float("nan")


def _lag_summary(kind: str, tabs: list[dict], joined: dict, where: list[int | None], pids: list[int],
                 reports: list[dict]) -> tuple[tuple[float, float], int, tuple[float, ...]]:
    """``((p50, p99) ms, unanswered, p99 ms of the tabs of each worker)`` over the dragging tabs (or followers)."""
    index = {pid: i for i, pid in enumerate(pids)}
    draggers = len(joined["owners"])
    lags: list[float] = []
    by_worker: dict[int | None, list[float]] = {pid: [] for pid in pids}
    unanswered = 0
    for n, tab in enumerate(tabs):
        j = n if n < draggers else 0  # a follower answers the instructor's (tab 0's) sends
        pid = where[j]
        w = index.get(pid) if pid is not None else None
        drawn = reports[w]["drawn"].get(str(joined["owners"][j]), []) if w is not None else []
        tab_lags, tab_unanswered = _lags(tab["sends"], tab["panels"], _seq_of_rev(drawn, joined["starts"][j], j))
        if kind == "follow" and n == 0:
            continue  # the instructor's own tab: not a follower
        lags += tab_lags
        by_worker.setdefault(where[n], []).extend(tab_lags)
        unanswered += tab_unanswered
    return (_p(lags, 50), _p(lags, 99)), unanswered, tuple(_p(by_worker[pid], 99) for pid in pids)


def run_drag(workers: int, tabs: int = DRAG_TABS, *, seconds: float = DRAG_SECONDS, rate: float = RATE_HZ,
             scene: str | None = None, quiet_s: float = QUIET_S) -> RoomRun:
    """``tabs`` tabs each dragging camera 1 at ``rate`` Hz on ``workers`` workers; a tab stops listening
    ``quiet_s`` seconds after its last panel (a test on a busy machine gives it longer)."""
    return _run("drag", workers, tabs, seconds, rate, scene, quiet_s)


def run_followers(workers: int, followers: int, *, seconds: float = DRAG_SECONDS, rate: float = RATE_HZ,
                  scene: str | None = None, quiet_s: float = QUIET_S) -> RoomRun:
    """One instructor dragging camera 1 at ``rate`` Hz, ``followers`` students following, on ``workers`` workers;
    ``quiet_s`` as :func:`run_drag`."""
    return _run("follow", workers, followers, seconds, rate, scene, quiet_s)


def format_room(runs: Sequence[RoomRun]) -> str:
    head = (f"{'run':<7} {'workers':>7} {'tabs':>5} {'sent':>6} {'drawn':>6} {'lag p50':>8} {'lag p99':>8} "
            f"{'unanswered':>10} {'per worker':>12} {'p99 by worker':>14} {'worker CPU s':>14} {'RSS MB':>7} "
            f"{'tabs CPU %':>10}")
    lines = [head, "-" * len(head)]
    for r in runs:
        lines.append(f"{r.kind:<7} {r.workers:>7} {r.tabs:>5} {r.sent:>6} {r.applied:>6} {r.lag_ms[0]:>8.1f} "
                     f"{r.lag_ms[1]:>8.1f} {r.unanswered:>10} {'/'.join(map(str, r.per_worker)):>12} "
                     f"{'/'.join(f'{p:.0f}' for p in r.p99_by_worker_ms):>14} "
                     f"{'/'.join(f'{c:.1f}' for c in r.cpu_s):>14} {r.rss_mb:>7.0f} {100 * r.tabs_cpu_share:>10.0f}")
    return "\n".join(lines)


def room_record(runs: Sequence[RoomRun], *, scene: str | None) -> dict[str, Any]:
    """The runs as JSON data (``--json FILE``)."""
    import platform

    def safe(v: Any) -> Any:
        return v if not isinstance(v, float) or np.isfinite(v) else None

    return {"bench": "classroom-workers", "scene": scene or "default",
            "machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                        "load_average": list(os.getloadavg())},
            "runs": [{k: safe(v) if not isinstance(v, tuple) else [safe(x) for x in v]
                      for k, v in dataclasses.asdict(r).items()} for r in runs]}


def run_room_bench(workers: int = 1, followers: int | None = None, *, tabs: int = DRAG_TABS,
                   seconds: float = DRAG_SECONDS, scene: str | None = None, json_path: str | None = None) -> str:
    """``egtviz bench classroom --workers N [--followers M]``: the drag run (``tabs`` tabs) on N workers and,
    with ``followers``, the follower run; the report as text, and with ``json_path`` as JSON in that file."""
    runs = [run_drag(workers, tabs, seconds=seconds, scene=scene)]
    if followers is not None:
        runs.append(run_followers(workers, followers, seconds=seconds, scene=scene))
    if json_path is not None:
        Path(json_path).write_text(json.dumps(room_record(runs, scene=scene), indent=1, allow_nan=False) + "\n")
    title = (f"classroom on {workers} worker process(es): {RATE_HZ:g} Hz per dragging tab, {seconds:g} s; lag ms "
             "from a send to its panel (at the followers for the follow run); load average "
             f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    return title + "\n" + format_room(runs)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="egtviz-bench-classroom-room")
    p.add_argument("--tabs", action="store_true", help=argparse.SUPPRESS)
    args, _ = p.parse_known_args(argv)
    return tabs_main() if args.tabs else bench_worker_main()


if __name__ == "__main__":
    raise SystemExit(main())
