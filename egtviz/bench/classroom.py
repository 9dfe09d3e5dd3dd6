"""A classroom on one server: K tabs dragging a camera at 20 Hz; server CPU per drag update, panel lag, memory.

Method (also in ``docs/benchmarks.md``):

* **Server.** The real ``egtviz serve`` server (:func:`egtviz.viewer.server.launch.start`: viser, the guards of
  :mod:`egtviz.viewer.server.guard`, the app) on a free loopback port, in this process.
* **Tabs.** K raw websocket clients (:mod:`egtviz.bench.ws_client`) in one separate process, so that
  their work is not counted as the server's. Each joins like a browser in a 1366 x 768 window (its first
  camera message, which sets the panels' layout),
  then, after a common start, drags camera 1's gizmo as a browser does: a drag start, a pose update
  every 1/20 s for the given time (tabs staggered evenly over the 50 ms), a drag end. Update ``k`` of
  tab ``j`` puts the camera at ``p0 + (k + 1) * 1 mm * x + (j + 1) * 1 mm * y``: every update is a new
  place, and the pose the server drew says which update of which tab it drew.
* **Server CPU per drag update.** The server process's CPU time (``time.process_time``: all its
  threads) over the drag, from the common start until every tab has gone quiet, divided by the
  updates the server applied (renders; the guards merge a tab's waiting updates, latest wins, so a
  saturated server applies fewer than were sent). The parts come from per-thread CPU clocks
  (``time.thread_time``): ``compute_derived`` (geometry, a clock around the scene model's reference
  to it: one call per applied update, the call ``egtviz bench core`` times; each starts with cold CPU caches
  after the tab's pause and the server's other work, as in that bench's paced row, not its back-to-back one)
  and the viewer's public timing hook (``ClientView.on_update_timed``, one
  ``UpdateTiming`` per applied update): the panels (SVGs and their assignment), the read-out and
  GUI fields, the 3D nodes, ``client.flush``, the rest of the render, the rest of the user event
  (the model: checks, the new scene, undo), and what is outside the applied events (viser: receiving,
  decoding and dispatching messages, the thread pool, gizmo events dropped as stale, serialising,
  compressing and sending the updates). One more run under ``cProfile`` (the event loop's thread and
  every callback the server submits to its executor) splits the time by library.
* **Panel lag.** For each update a tab sent, the time from its send to the arrival at that tab of the
  first panel SVG drawn from it or from a later update of the same tab (latest wins: an update merged
  into a later one is served by that one's panel). Both ends read this machine's wall clock. An update
  no panel answered before the end is counted as unserved.
* **Memory per tab.** Resident memory of the server process after the drag minus before the tabs
  joined, divided by K.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import cProfile
import dataclasses
import gc
import json
import os
import pstats
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["ClassroomRun", "classroom_record", "format_classroom", "profile_classroom", "run_classroom", "run_classroom_bench"]

#: Tab counts of ``egtviz bench classroom``.
TAB_COUNTS = (1, 5, 15, 30)
#: Drag updates per second and tab (a browser sends a gizmo's pose about this often during a drag).
RATE_HZ = 20.0
#: Seconds each tab drags.
DRAG_SECONDS = 8.0
#: Metres between successive updates of a tab (x) and between tabs (y).
STEP_M = 1e-3
#: The camera the tabs drag (the default scene's first camera) and its gizmo.
GIZMO = "/egt/cam_0"
#: Seconds without a frame after which a tab counts as quiet (the server has drawn everything).
QUIET_S = 0.5
#: The longest a tab waits for its next panel once it has sent its last update.
MAX_QUIET_S = 10.0
#: The tabs' window (CSS pixels, reported as the 3D canvas when a tab joins): a classroom laptop's screen.
WINDOW = (1366, 768)

_PANEL_REV = re.compile(rb'data-egtviz="image-plane" data-camera="[^"]*" data-rev="(\d+)"')


# -- the tabs (run in their own process) --------------------------------------------------------------------


async def _join(port: int, stack: contextlib.AsyncExitStack) -> tuple[Any, dict]:
    """Connect one tab (closed with ``stack``); returns the client and what it needs to drag (owner, start pose)."""
    from .ws_client import CAMERA, RawClient

    client = await stack.enter_async_context(RawClient.connect(port))
    camera = {**CAMERA, "image_width": WINDOW[0], "image_height": WINDOW[1]}
    await client.wait_for(("TransformControlsMessage", "GuiHtmlMessage"), timeout=60.0, camera=camera)
    deadline = time.perf_counter() + 60.0
    while time.perf_counter() < deadline:
        gizmo = [m for m in client.messages if m["type"] == "TransformControlsMessage" and m["name"] == GIZMO]
        pos = [m["position"] for m in client.messages if m["type"] == "SetPositionMessage" and m["name"] == GIZMO]
        rot = [m["wxyz"] for m in client.messages if m["type"] == "SetOrientationMessage" and m["name"] == GIZMO]
        if gizmo and pos and rot:
            return client, {"owner": gizmo[-1]["owner"], "position": pos[-1], "wxyz": rot[-1]}
        await client.read_until_quiet(0.2)
    raise AssertionError(f"the tab never got the pose of {GIZMO}")


async def _drag_and_listen(client: Any, pose: dict, j: int, tabs: int, seconds: float, rate: float,
                           t0: float) -> dict:
    """Drag as tab ``j`` from wall time ``t0`` while recording every panel revision that arrives."""
    n = round(seconds * rate)
    sends: list[tuple[int, float]] = []
    panels: list[tuple[int, float]] = []
    done = asyncio.Event()
    frames = 0
    received = 0

    async def listen() -> None:
        nonlocal frames, received
        from .ws_client import frame_payload

        last = time.time()
        # Quiet: no frame for QUIET_S, nor for twice the longest wait for a panel so far (from the first send, then
        # between two panels; MAX_QUIET_S while none came). A saturated server serves the tabs in turn: a tab may
        # wait longer than QUIET_S for its next panel, and stopping then would count its last updates unanswered
        # while they wait their turn.
        quiet = QUIET_S
        while not (done.is_set() and time.time() - last > (quiet if panels else MAX_QUIET_S)):
            try:
                frame = await asyncio.wait_for(client.ws.recv(), 0.1)
            except TimeoutError:
                continue
            last = now = time.time()
            frames += 1
            received += len(frame)
            revs = {int(r) for r in _PANEL_REV.findall(frame_payload(frame))}
            if revs:
                since = panels[-1][1] if panels else sends[0][1] if sends else None
                if since is not None:
                    quiet = max(quiet, min(2.0 * (now - since), MAX_QUIET_S))
                panels.append((max(revs), now))

    async def drag() -> None:
        x0, y0, z0 = pose["position"]
        base = {"name": GIZMO, "owner": pose["owner"]}
        start = t0 + j / (tabs * rate)
        await asyncio.sleep(max(0.0, start - time.time()))
        await client.send({"type": "TransformControlsDragStartMessage", **base})
        for k in range(n):
            await asyncio.sleep(max(0.0, start + k / rate - time.time()))
            sends.append((k, time.time()))
            await client.send({"type": "TransformControlsUpdateMessage", **base, "wxyz": pose["wxyz"],
                               "position": [x0 + STEP_M * (k + 1), y0 + STEP_M * (j + 1), z0]})
        await client.send({"type": "TransformControlsDragEndMessage", **base})
        done.set()

    await asyncio.gather(listen(), drag())
    return {"sends": sends, "panels": panels, "frames": frames, "bytes": received}


async def _tabs_main(port: int, tabs: int, seconds: float, rate: float) -> None:
    async with contextlib.AsyncExitStack() as stack:
        joined = await asyncio.gather(*(_join(port, stack) for _ in range(tabs)))
        print(json.dumps({"joined": [int(pose["owner"]) for _, pose in joined],
                          "start": [pose["position"] for _, pose in joined]}), flush=True)
        line = await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)
        t0 = float(line)
        cpu0 = time.process_time()
        results = await asyncio.gather(*(_drag_and_listen(c, pose, j, tabs, seconds, rate, t0)
                                         for j, (c, pose) in enumerate(joined)))
        print(json.dumps({"tabs": results, "cpu_s": time.process_time() - cpu0}), flush=True)
        # Stay connected until the server's side has read its figures (end of input).
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)


def tabs_main(argv: Sequence[str] | None = None) -> int:
    """The tabs' process: ``python -m egtviz.bench.classroom --tabs-of PORT K SECONDS RATE``.

    Prints one JSON line when every tab has joined, reads the common start (a wall time) on stdin,
    drags, and prints one JSON line with each tab's sends and panel arrivals.
    """
    p = argparse.ArgumentParser(prog="egtviz-classroom-tabs")
    p.add_argument("--tabs-of", nargs=4, required=True, metavar=("PORT", "K", "SECONDS", "RATE"))
    port, tabs, seconds, rate = p.parse_args(argv).tabs_of
    limit = 120.0 + 2.0 * float(seconds) + 2.0 * int(tabs)  # bounded: the process always ends
    asyncio.run(asyncio.wait_for(_tabs_main(int(port), int(tabs), float(seconds), float(rate)), limit))
    return 0


# -- the server's side ---------------------------------------------------------------------------------------


class _StageClock:
    """Per-thread CPU seconds spent inside wrapped functions, summed by stage (threads run callbacks at once)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._lock = threading.Lock()

    def wrap(self, stage: str, fn: Callable) -> Callable:
        def timed(*args: Any, **kwargs: Any) -> Any:
            c0 = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                dt = time.thread_time() - c0
                with self._lock:
                    self.seconds[stage] = self.seconds.get(stage, 0.0) + dt

        return timed

    def add(self, parts: dict[str, float]) -> None:
        """Add CPU seconds by stage (from any thread)."""
        with self._lock:
            for stage, dt in parts.items():
                self.seconds[stage] = self.seconds.get(stage, 0.0) + dt

    def reset(self) -> None:
        with self._lock:
            self.seconds = {}


def _rss_bytes() -> int:
    return int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")


class _Drawn:
    """What each tab's updates drew: ``(revision, camera 1's position)``, recorded after each update."""

    def __init__(self) -> None:
        self.by_view: dict[int, list[tuple[int, tuple[float, float, float]]]] = {}

    def hook(self, cid: int, view: Any, clock: _StageClock) -> Callable[[Any], None]:
        """The view's timing hook: the update's CPU parts to ``clock``, what it drew to the tab's log."""
        log = self.by_view.setdefault(cid, [])

        def timed(timing: Any) -> None:
            # The event's CPU, from its start to the end of its update, is the stage "callback".
            clock.add({"callback" if stage == "event" else stage: dt for stage, dt in timing.cpu.items()})
            x, y, z = view.model.scene.cameras[0].position
            log.append((timing.revision, (float(x), float(y), float(z))))

        return timed


def _instrument(app: Any, clock: _StageClock, drawn: _Drawn) -> None:
    """Hook the stage clocks to each tab's public timing hook (``ClientView.on_update_timed``)."""
    for cid, view in app.views.items():
        view.on_update_timed = drawn.hook(cid, view, clock)


@dataclasses.dataclass(frozen=True)
class ClassroomRun:
    """One classroom run.

    Attributes:
        tabs: K, the tabs dragging at once.
        seconds: how long each tab dragged.
        sent: drag updates the tabs sent.
        applied: renders the server ran during the drag (merged updates are drawn once).
        cpu_s: the server process's CPU seconds over the drag (all threads).
        wall_s: wall seconds from the common start until every tab was quiet.
        parts_ms: CPU milliseconds per applied update by stage (see the module docstring); they sum to
            :attr:`cpu_ms_per_update`.
        lag_ms: panel lag (ms) at the 50th and 99th percentile over every update sent.
        unserved: updates that no panel answered before the end.
        rss_per_tab_mb: server resident memory per tab (MB).
        tabs_cpu_s: CPU seconds of the tabs' process (to see that it kept up).
        received_mb: megabytes of frames the tabs received.
    """

    tabs: int
    seconds: float
    sent: int
    applied: int
    cpu_s: float
    wall_s: float
    parts_ms: dict[str, float]
    lag_ms: tuple[float, float]
    unserved: int
    rss_per_tab_mb: float
    tabs_cpu_s: float
    received_mb: float

    @property
    def cpu_ms_per_update(self) -> float:
        """Server CPU milliseconds per applied drag update."""
        return 1e3 * self.cpu_s / self.applied if self.applied else float("nan")


def _lags(tab: dict, drawn: list[tuple[int, tuple[float, float, float]]], start: tuple[float, ...],
          j: int) -> tuple[list[float], int]:
    """Seconds from each send to the first panel (arriving after it) drawn from it or a later update of tab ``j``."""
    seq_of_rev: dict[int, int] = {}
    for rev, (x, y, _z) in drawn:
        if round((y - start[1]) / STEP_M) - 1 == j:
            seq_of_rev[rev] = round((x - start[0]) / STEP_M) - 1
    arrivals = sorted((t, seq_of_rev[rev]) for rev, t in tab["panels"] if rev in seq_of_rev)
    lags, unserved = [], 0
    for k, t_send in tab["sends"]:
        t = next((t for t, seq in arrivals if seq >= k and t >= t_send), None)
        if t is None:
            unserved += 1
        else:
            lags.append(t - t_send)
    return lags, unserved


def _parts(stages: dict[str, float], cpu_s: float, applied: int) -> dict[str, float]:
    get = stages.get
    drawn = ("derived", "svg", "fields", "scene3d", "flush")
    render_rest = get("render", 0.0) - sum(get(k, 0.0) for k in drawn)
    parts = {
        "geometry": get("geometry", 0.0),
        "model": get("callback", 0.0) - get("render", 0.0) - get("geometry", 0.0),
        "svg": get("svg", 0.0),
        "panels+readout": render_rest + get("derived", 0.0),
        "fields": get("fields", 0.0),
        "scene3d": get("scene3d", 0.0),
        "flush": get("flush", 0.0),
        "viser dispatch+send": cpu_s - get("callback", 0.0),
    }
    return {k: 1e3 * v / applied for k, v in parts.items()} if applied else {k: float("nan") for k in parts}


class _Server:
    """The egtviz server with stage clocks on ``compute_derived`` (the model's reference to it)."""

    def __init__(self, scene: str | None) -> None:
        from ..scene import model as scene_model
        from ..viewer.server.launch import start

        self.clock = _StageClock()
        self._model_module = scene_model
        self._compute = scene_model.compute_derived
        scene_model.compute_derived = self.clock.wrap("geometry", self._compute)
        try:
            self.server, self.app = start("127.0.0.1", 0, scene)
        except BaseException:
            scene_model.compute_derived = self._compute
            raise

    def stop(self) -> None:
        self.server.stop()
        self._model_module.compute_derived = self._compute


def _spawn_tabs(port: int, tabs: int, seconds: float, rate: float) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "egtviz.bench.classroom", "--tabs-of", str(port), str(tabs), str(seconds), str(rate)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )


def _read_json(proc: subprocess.Popen, what: str) -> dict:
    line = proc.stdout.readline() if proc.stdout is not None else ""
    if not line:
        proc.wait(30)
        raise RuntimeError(f"the tabs' process ended (status {proc.returncode}) before {what}")
    return json.loads(line)


def _cpu_profile() -> cProfile.Profile:
    """A profiler that counts the thread's CPU time (a wall clock would count the event loop's idle waits)."""
    return cProfile.Profile(time.thread_time_ns, 1e-9)


class _PoolProfiler:
    """cProfile on the event loop's thread and on every pool thread (each thread its own profiler)."""

    def __init__(self, server: Any) -> None:
        from ..viewer.server.viser_adapter import callback_pool, event_loop

        self._loop = event_loop(server)
        self._pool = callback_pool(server)
        self._submit = self._pool.submit
        self._local = threading.local()
        self.profiles: list[cProfile.Profile] = []
        self._loop_profile = _cpu_profile()
        self.profiles.append(self._loop_profile)
        lock = threading.Lock()

        def profiled(fn: Callable) -> Callable:
            def run(*args: Any, **kwargs: Any) -> Any:
                prof = getattr(self._local, "prof", None)
                if prof is None:
                    prof = self._local.prof = _cpu_profile()
                    with lock:
                        self.profiles.append(prof)
                prof.enable()
                try:
                    return fn(*args, **kwargs)
                finally:
                    prof.disable()

            return run

        def submit(fn: Callable[..., Any], /, *a: Any, **k: Any) -> Future[Any]:
            return self._submit(profiled(fn), *a, **k)

        # On the pool object itself: viser submits every callback through this pool's submit.
        self._pool.submit = submit  # type: ignore[method-assign]
        ready = threading.Event()

        def start() -> None:
            self._loop_profile.enable()
            ready.set()

        self._loop.call_soon_threadsafe(start)
        ready.wait(5)

    def stop(self) -> pstats.Stats:
        done = threading.Event()

        def finish() -> None:
            self._loop_profile.disable()
            done.set()

        self._loop.call_soon_threadsafe(finish)
        done.wait(5)
        self._pool.submit = self._submit  # type: ignore[method-assign]  # the pool's own method back
        stats = pstats.Stats(self.profiles[0])
        for prof in self.profiles[1:]:
            stats.add(prof)
        return stats


def run_classroom(tabs: int, *, seconds: float = DRAG_SECONDS, rate: float = RATE_HZ, scene: str | None = None,
                  profile: bool = False) -> tuple[ClassroomRun, pstats.Stats | None]:
    """One run with ``tabs`` tabs dragging camera 1 of ``scene`` (a built-in name or file; None: the default).

    Returns the run and, with ``profile``, the cProfile statistics of the server's threads over the drag
    (profiling slows the server: its :class:`ClassroomRun` figures are then not the unprofiled ones).

    Raises:
        ValueError: ``tabs`` is not a positive integer, or ``seconds``/``rate`` not positive.
        RuntimeError: the tabs' process failed (the server is stopped all the same).
    """
    if isinstance(tabs, bool) or not isinstance(tabs, int) or tabs < 1:
        raise ValueError(f"tabs: expected a positive integer, got {tabs!r}")
    if not (seconds > 0 and rate > 0):
        raise ValueError(f"seconds, rate: expected positive numbers, got {seconds!r}, {rate!r}")
    srv = _Server(scene)
    proc = None
    try:
        gc.collect()
        rss0 = _rss_bytes()
        proc = _spawn_tabs(srv.server.get_port(), tabs, seconds, rate)
        joined = _read_json(proc, "every tab joined")
        srv.app.wait_for_view(count=tabs, timeout=60.0)
        drawn = _Drawn()
        _instrument(srv.app, srv.clock, drawn)
        views = dict(srv.app.views)  # the tabs leave at the end: keep their views
        by_owner = {cid: drawn.by_view[cid] for cid in views}
        revs0 = {cid: v.revision for cid, v in views.items()}
        time.sleep(0.5)  # let the joins' last messages go before the clocks start
        srv.clock.reset()
        for log in drawn.by_view.values():
            log.clear()
        profiler = _PoolProfiler(srv.server) if profile else None
        t0 = time.time() + 0.2
        cpu0 = time.process_time()
        if proc.stdin is None:  # _spawn_tabs opens it as a pipe
            raise RuntimeError("the tabs' process has no input pipe")
        proc.stdin.write(f"{t0!r}\n")
        proc.stdin.flush()
        result = _read_json(proc, "the drag ended")
        cpu_s = time.process_time() - cpu0
        wall_s = time.time() - t0
        stats = profiler.stop() if profiler is not None else None
        stages = dict(srv.clock.seconds)
        applied = sum(v.revision - revs0[cid] for cid, v in views.items())
        rss1 = _rss_bytes()
        proc.stdin.close()
        proc.wait(30)
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait(10)
        srv.stop()
    lags: list[float] = []
    unserved = 0
    for j, (owner, start, tab) in enumerate(zip(joined["joined"], joined["start"], result["tabs"])):
        tab_lags, tab_unserved = _lags(tab, by_owner.get(owner, []), start, j)
        lags += tab_lags
        unserved += tab_unserved
    lag = (float(np.percentile(lags, 50) * 1e3), float(np.percentile(lags, 99) * 1e3)) if lags else (
        float("nan"), float("nan"))
    run = ClassroomRun(
        tabs=tabs, seconds=seconds, sent=sum(len(t["sends"]) for t in result["tabs"]), applied=applied,
        cpu_s=cpu_s, wall_s=wall_s, parts_ms=_parts(stages, cpu_s, applied), lag_ms=lag, unserved=unserved,
        rss_per_tab_mb=(rss1 - rss0) / tabs / 2**20, tabs_cpu_s=float(result["cpu_s"]),
        received_mb=sum(t["bytes"] for t in result["tabs"]) / 2**20,
    )
    return run, stats


#: Where a profiled function's time is counted: (area, substrings of its file or name), first match wins.
PROFILE_AREAS = (
    ("geometry (egtviz.geometry)", ("egtviz/geometry/",)),
    ("scene model + compute_derived", ("egtviz/scene/",)),
    ("SVG: label placement (egtviz.viewer.render.panel_view)", ("egtviz/viewer/render/panel_view.py",)),
    ("SVG: the rest (egtviz.viewer.render.svg)", ("egtviz/viewer/render/svg.py", "egtviz/viewer/render/plot_svg.py")),
    ("3D nodes (egtviz.viewer.workbench.scene3d, models)", ("egtviz/viewer/workbench/scene3d.py", "egtviz/viewer/workbench/models/",
                                                 "egtviz/viewer/server/viser_adapter.py", "egtviz/viewer/workbench/annotations3d.py")),
    ("guards (egtviz.viewer.server.guard)", ("egtviz/viewer/server/guard.py",)),
    ("viewer app (egtviz.viewer)", ("egtviz/viewer/", "egtviz/bench/classroom.py")),
    ("viser property handling (handles, props, GUI)", ("viser/_scene_handles.py", "viser/_gui_handles.py",
                                                       "viser/_assignable_props_api.py", "viser/_gui_api.py",
                                                       "viser/_scene_api.py", "viser/_viser.py")),
    ("viser messages + transport (infra)", ("viser/infra/", "viser/_messages.py", "viser/")),
    ("msgpack encode/decode (msgspec)", ("msgspec",)),
    ("zstd compression", ("zstd", "Zstd")),
    ("websockets", ("websockets/",)),
    ("asyncio, sockets, threads", ("asyncio/", "selectors.py", "socket", "threading.py", "concurrent/", "queue.py",
                                   "select", "_thread", "sleep")),
    ("numpy", ("numpy",)),
)


def _area(path: str, name: str) -> str:
    key = f"{path}:{name}"
    return next((a for a, needles in PROFILE_AREAS if any(n in key for n in needles)), "other")


def profile_areas(stats: pstats.Stats) -> list[tuple[str, float]]:
    """Own time (tottime, seconds) by :data:`PROFILE_AREAS`, largest first; ``"other"`` for the rest.

    A C function (``max``, ``str.join``, a numpy reduction) has no file of its own: its time goes to the
    areas of the Python functions that called it, in proportion to the time each call site spent in it.
    """
    out: dict[str, float] = {}
    for (path, _line, name), (_cc, _nc, tottime, _ct, callers) in stats.stats.items():  # type: ignore[attr-defined]
        area = _area(path, name)
        if path == "~" and area == "other" and callers:
            for (cpath, _cline, cname), site in callers.items():
                caller_area = _area(cpath, cname)
                out[caller_area] = out.get(caller_area, 0.0) + site[2]
            continue
        out[area] = out.get(area, 0.0) + tottime
    return sorted(out.items(), key=lambda kv: -kv[1])


def profile_classroom(tabs: int = 5, seconds: float = 5.0,
                      scene: str | None = None) -> tuple[ClassroomRun, pstats.Stats]:
    """A run under cProfile (see :func:`run_classroom`)."""
    run, stats = run_classroom(tabs, seconds=seconds, scene=scene, profile=True)
    assert stats is not None
    return run, stats


def format_classroom(runs: Sequence[ClassroomRun]) -> str:
    """The runs as a text table: CPU per update and its parts, lag, memory."""
    keys = list(runs[0].parts_ms) if runs else []
    head = (f"{'tabs':>4} {'sent':>6} {'applied':>7} {'CPU ms/upd':>10} " + " ".join(f"{k:>12}" for k in keys)
            + f" {'lag p50':>8} {'lag p99':>8} {'unserved':>8} {'MB/tab':>7} {'tabs CPU %':>10}")
    lines = [head, "-" * len(head)]
    for r in runs:
        lines.append(
            f"{r.tabs:>4} {r.sent:>6} {r.applied:>7} {r.cpu_ms_per_update:>10.2f} "
            + " ".join(f"{r.parts_ms[k]:>12.3f}" for k in keys)
            + f" {r.lag_ms[0]:>8.1f} {r.lag_ms[1]:>8.1f} {r.unserved:>8} {r.rss_per_tab_mb:>7.2f}"
            f" {100 * r.tabs_cpu_s / r.wall_s:>10.0f}"
        )
    return "\n".join(lines)


def _scene_with_points(scene: str | None, points: int, folder: str) -> str:
    """A scene file: ``scene`` (None: the default) with ``points`` random points (seed 0) in a cube of side 4 m
    around its points' centre (as ``egtviz bench viewer`` places its 200 points); returns the file's path."""
    from ..scene import SceneModel, save_scene_file, scene_from_argument

    model = SceneModel(scene_from_argument(scene) if scene is not None else None)
    X = model.scene.points_array()
    model.randomize_points(points, seed=0, center=tuple(X.mean(axis=0)), extent=2.0)
    path = Path(folder) / f"classroom-{points}-points.json"
    save_scene_file(model.scene, path)
    return str(path)


def _machine() -> dict[str, Any]:
    import platform

    return {"python": platform.python_version(), "machine": platform.machine(), "cpus": os.cpu_count(),
            "load_average": list(os.getloadavg())}


def _json_safe(value: Any) -> Any:
    """``value`` with every NaN or infinite float as None (strict JSON has neither)."""
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


def classroom_record(runs: Sequence[ClassroomRun], floors: Sequence[Any], *, scene: str | None,
                     points: int | None, areas: Sequence[tuple[str, float]] = (), profiled: ClassroomRun | None = None
                     ) -> dict[str, Any]:
    """The runs as the JSON record of ``egtviz bench classroom --json FILE``.

    Args:
        runs: one run per tab count.
        floors: the bare-viser floor (:class:`~egtviz.bench.viser_floor.FloorRun`) measured just before each run,
            at that run's rate (tabs x :data:`RATE_HZ` updates a second).
        scene: the scene dragged (None: the default).
        points: the points it was given (None: its own).
        areas: the profiled run's own time by area (:func:`profile_areas`), if any.
        profiled: that run.
    """
    rows = []
    for r, f in zip(runs, floors, strict=True):
        floor = f.cpu_ms_per_update
        rows.append({
            "tabs": r.tabs, "rate_hz": RATE_HZ * r.tabs, "seconds": r.seconds, "sent": r.sent, "applied": r.applied,
            "cpu_ms_per_update": r.cpu_ms_per_update, "floor_ms_per_update": floor,
            "floor_callbacks": f.callbacks, "ratio_to_floor": r.cpu_ms_per_update / floor if floor > 0 else None,
            "parts_ms": dict(r.parts_ms), "lag_ms": {"p50": r.lag_ms[0], "p99": r.lag_ms[1]},
            "unserved": r.unserved, "rss_per_tab_mb": r.rss_per_tab_mb, "received_mb": r.received_mb,
            "tabs_cpu_share": r.tabs_cpu_s / r.wall_s if r.wall_s > 0 else None,
        })
    total = sum(t for _, t in areas)
    profile = None
    if profiled is not None and total > 0:
        profile = {"tabs": profiled.tabs, "applied": profiled.applied,
                   "areas": [{"area": a, "ms_per_update": 1e3 * t / max(profiled.applied, 1), "share": t / total}
                             for a, t in areas]}
    return {"bench": "classroom", "scene": scene or "default", "points": points, "machine": _machine(),
            "runs": rows, "profile": profile}


def run_classroom_bench(tab_counts: Sequence[int] = TAB_COUNTS, *, seconds: float = DRAG_SECONDS,
                        scene: str | None = None, profile: bool = True, json_path: str | None = None,
                        points: int | None = None) -> str:
    """``egtviz bench classroom``: a run per tab count, each just after the bare-viser floor at its rate (tabs x
    :data:`RATE_HZ`), then (``profile``) one profiled run; the report as text, and with ``json_path`` the same
    figures as JSON (:func:`classroom_record`) in that file. ``points``: the scene gets that many random points."""
    import tempfile

    from .viser_floor import format_floor, viser_floor

    with tempfile.TemporaryDirectory() as folder:
        drawn_scene = _scene_with_points(scene, points, folder) if points is not None else scene
        runs, floors = [], []
        for k in tab_counts:
            floors.append(viser_floor(RATE_HZ * k, min(seconds, 5.0)))
            runs.append(run_classroom(k, seconds=seconds, scene=drawn_scene)[0])
        prun, stats = profile_classroom(scene=drawn_scene) if profile else (None, None)
    title = (f"{len(tab_counts)} runs, {RATE_HZ:g} Hz per tab, {seconds:g} s; CPU ms per applied update by part; "
             "lag ms from a send to its panel")
    out = [title, format_classroom(runs), "", format_floor(floors),
           "  ratio to the floor at the same rate: " + ", ".join(
               f"{r.tabs} tabs {r.cpu_ms_per_update / f.cpu_ms_per_update:.2f}x" for r, f in zip(runs, floors))]
    areas = profile_areas(stats) if stats is not None else []
    if prun is not None and stats is not None:
        total = sum(t for _, t in areas)
        out.append(f"\ncProfile, {prun.tabs} tabs, {prun.applied} updates applied (profiled, so slower): own time "
                   "by area, ms per update and share")
        for area, t in areas:
            out.append(f"  {area:<48} {1e3 * t / max(prun.applied, 1):>7.3f}  {100 * t / total:>5.1f} %")
        out.append("\nTop functions by own time:")
        import io

        buf = io.StringIO()
        stats.stream = buf  # type: ignore[attr-defined]
        stats.sort_stats("tottime").print_stats(25)
        lines = buf.getvalue().splitlines()
        head = next((i for i, line in enumerate(lines) if "ncalls" in line), 0)
        out.append("\n".join(lines[head:]))
    if json_path is not None:
        record = classroom_record(runs, floors, scene=scene, points=points, areas=areas, profiled=prun)
        Path(json_path).write_text(json.dumps(_json_safe(record), indent=1, allow_nan=False) + "\n")
    return "\n".join(out)


if __name__ == "__main__":
    if "--tabs-of" in sys.argv:
        raise SystemExit(tabs_main(sys.argv[1:]))
    print(run_classroom_bench())
