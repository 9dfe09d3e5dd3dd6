"""PNG downloads rendered in a worker process: one tab's PNG never holds up another tab.

resvg (:func:`egtviz.viewer.render.figure_export.svg_to_png`) keeps Python's GIL for
the whole render, seconds for a panel of 2,000 points. Run in the server's
process it would stop every thread meanwhile, the websocket loop included, so
that every other tab's edits waited for it. Here the render runs in a separate,
long-lived Python process (``python -m egtviz.viewer.render.png_worker``) started at
the first PNG; the server's thread only waits on a pipe, without the GIL.

A plain subprocess rather than :mod:`multiprocessing`: its "spawn" start runs
the parent's main script again in the child, and an EGT figure script starts a
server at its top level.

Three parts:

- :class:`WorkerProcess`: one worker process and its pipe protocol; a render
  that takes longer than :data:`RENDER_TIMEOUT_S` is stopped.
- :class:`PngRenderer`: the queue in front of the workers (one per server
  process: :func:`shared_renderer`). Per tab at most one render runs and one
  waits; a new request replaces the waiting one (latest wins), and tabs take
  turns, so that one tab's clicks cannot queue unbounded work or starve
  another tab's download.
- :class:`PngDownloads`: one tab's PNG button. It refuses a figure above the
  limits (:func:`~egtviz.viewer.render.figure_export.png_refusal`, with the reason),
  shows "Rendering PNG..." while it waits, then sends the file, or a
  notification saying why not.

The workers end with the server process (their pipe closes; :func:`shutdown`
also runs at exit), and an idle worker ends after :data:`IDLE_S` seconds.
"""

from __future__ import annotations

import atexit
import os
import struct
import subprocess
import sys
import threading
import traceback
from collections import deque
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import IO, TYPE_CHECKING, Protocol

if TYPE_CHECKING:  # only named: the worker process, and the SVG builders, run without viser
    import viser

__all__ = [
    "IDLE_S",
    "RENDER_TIMEOUT_S",
    "PngDownloads",
    "PngJob",
    "PngRenderError",
    "PngRenderer",
    "WorkerProcess",
    "shared_renderer",
    "shutdown",
]

#: Seconds a render may take before its worker is stopped (the limits keep a render to seconds).
RENDER_TIMEOUT_S = 60.0
#: Seconds without a render after which a worker process ends (the next PNG starts one again).
IDLE_S = 300.0
#: The worker's scheduling priority (``nice``): the server's event loop comes first on a busy machine.
WORKER_NICENESS = 10
#: Request: scale (float64), SVG length in bytes (uint32), then the UTF-8 SVG.
_REQUEST = struct.Struct(">dI")
#: Reply: status (0 done, 1 failed), payload length (uint32), then the PNG or a UTF-8 message.
_REPLY = struct.Struct(">BI")
_DONE, _FAILED = 0, 1


class PngRenderError(RuntimeError):
    """A render that did not give a PNG; the message is written for the tab (no traceback, no server path)."""


def _read_exact(stream: IO[bytes], n: int) -> bytes:
    """``n`` bytes from ``stream``; EOFError if it ends first."""
    chunks, missing = [], n
    while missing:
        chunk = stream.read(missing)
        if not chunk:
            raise EOFError(f"the stream ended {missing} bytes short")
        chunks.append(chunk)
        missing -= len(chunk)
    return b"".join(chunks)


class WorkerProcess:
    """One worker process (started at the first :meth:`render`, again after it ended) and its pipe.

    Not thread-safe: one :class:`PngRenderer` thread owns it.

    Args:
        timeout: seconds one render may take; then the process is killed and the render fails.
    """

    def __init__(self, *, timeout: float = RENDER_TIMEOUT_S) -> None:
        self.timeout = float(timeout)
        self._proc: subprocess.Popen[bytes] | None = None

    @property
    def pid(self) -> int | None:
        """The running worker's process id (None: none running)."""
        return self._proc.pid if self._proc is not None and self._proc.poll() is None else None

    def _started(self) -> subprocess.Popen[bytes]:
        if self._proc is not None and self._proc.poll() is None:
            return self._proc
        self.close()
        env = dict(os.environ)
        # The package as this process imported it (a checkout works without an install).
        root = str(Path(__file__).resolve().parents[2])
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH", "")) if p)
        # A session of its own: Ctrl-C stops the server, whose exit closes the pipe and so ends the worker.
        self._proc = subprocess.Popen([sys.executable, "-m", "egtviz.viewer.render.png_worker"], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, env=env, start_new_session=True)
        return self._proc

    def render(self, svg: str, scale: float) -> bytes:
        """The PNG of ``svg`` at ``scale`` device pixels per CSS pixel, rendered by the worker.

        Raises:
            PngRenderError: resvg refused the SVG (its message), the render timed out, or the worker died.
        """
        proc = self._started()
        assert proc.stdin is not None and proc.stdout is not None
        data = svg.encode("utf-8")
        expired = threading.Event()

        def expire() -> None:
            expired.set()
            proc.kill()

        timer = threading.Timer(self.timeout, expire)
        timer.daemon = True
        timer.start()
        try:
            proc.stdin.write(_REQUEST.pack(float(scale), len(data)) + data)
            proc.stdin.flush()
            status, n = _REPLY.unpack(_read_exact(proc.stdout, _REPLY.size))
            payload = _read_exact(proc.stdout, n)
        except (OSError, EOFError, ValueError) as exc:
            self.close()
            if expired.is_set():
                raise PngRenderError(f"the render took longer than {self.timeout:g} s and was stopped") from exc
            raise PngRenderError("the PNG renderer stopped unexpectedly; try again") from exc
        finally:
            timer.cancel()
        if status != _DONE:
            raise PngRenderError(f"the renderer could not draw the figure: {payload.decode('utf-8', 'replace')}")
        return payload

    def close(self) -> None:
        """End the worker: close its pipe (it exits on end of input); kill it if it does not within 2 s."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        for stream in (proc.stdin, proc.stdout):
            try:
                if stream is not None:
                    stream.close()
            except OSError:
                pass
        try:
            proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


class PngWorker(Protocol):
    """What a :class:`PngRenderer` thread renders with: a :class:`WorkerProcess`, or a test's stand-in."""

    @property
    def pid(self) -> int | None: ...

    def render(self, svg: str, scale: float) -> bytes: ...

    def close(self) -> None: ...


@dataclass(frozen=True)
class PngJob:
    """One requested render."""

    svg: str
    """The standalone SVG document."""
    scale: float
    """Device pixels per CSS pixel."""
    deliver: Callable[[bytes | None, BaseException | None], None]
    """Called once from a renderer thread with ``(png, None)`` or ``(None, error)``; not called for a job that a
    newer request replaced or that :meth:`PngRenderer.forget` dropped."""


def default_workers() -> int:
    """Worker processes for this machine: one core stays free for the server (1 on two cores, at most 2)."""
    return max(1, min(2, (os.cpu_count() or 1) - 1))


class PngRenderer:
    """Renders :class:`PngJob` s in worker processes, per requester at most one running and one waiting.

    Requesters are any hashable keys (:class:`PngDownloads` uses itself: one per tab). A request while the key's
    job waits replaces it (latest wins), keeping its place in the line; when a key's render ends, its waiting job
    goes to the back of the line. So keys take turns: however fast one key requests, another key's job waits
    for at most one render of each other key.

    Args:
        workers: worker processes (threads that each own one); None: :func:`default_workers`.
        timeout: seconds one render may take (:class:`WorkerProcess`).
        idle: seconds without work after which a worker process ends.
        worker_factory: makes each thread's worker (``render(svg, scale) -> bytes``, ``close()``, ``pid``); tests
            pass a stand-in to hold a render while they queue requests.
    """

    def __init__(self, workers: int | None = None, *, timeout: float = RENDER_TIMEOUT_S, idle: float = IDLE_S,
                 worker_factory: Callable[..., PngWorker] = WorkerProcess) -> None:
        self.workers = default_workers() if workers is None else int(workers)
        if self.workers < 1:
            raise ValueError(f"workers: expected at least 1, got {workers}")
        self.timeout = float(timeout)
        self.idle = float(idle)
        self._worker_factory = worker_factory
        self._cond = threading.Condition()
        self._pending: dict[Hashable, PngJob] = {}
        self._running: set[Hashable] = set()
        self._threads: list[threading.Thread] = []
        self._worker_processes: list[PngWorker] = []
        self._closed = False
        #: ``id(key)`` of the latest renders started, oldest first (tests read it; ids keep no tab alive).
        self.started: deque[int] = deque(maxlen=100)
        #: Renders started since this renderer was made.
        self.renders = 0

    def request(self, key: Hashable, job: PngJob) -> None:
        """Queue ``job`` for ``key``, replacing the job of ``key`` that has not started yet, if any.

        Raises:
            PngRenderError: the renderer is shut down.
        """
        with self._cond:
            if self._closed:
                raise PngRenderError("the server is shutting down")
            self._pending[key] = job  # an existing key keeps its place in the dict's order: its turn
            if not self._threads:
                self._start_threads()
            self._cond.notify_all()

    def forget(self, key: Hashable) -> None:
        """Drop ``key``'s waiting job (its tab closed); a running one finishes and is delivered."""
        with self._cond:
            self._pending.pop(key, None)

    def busy(self, key: Hashable) -> bool:
        """Whether ``key`` has a job running or waiting."""
        with self._cond:
            return key in self._running or key in self._pending

    def idle_now(self) -> bool:
        """Whether no job runs or waits (tests wait for it)."""
        with self._cond:
            return not self._running and not self._pending

    def worker_pids(self) -> list[int]:
        """Process ids of the running worker processes."""
        return [pid for w in self._worker_processes if (pid := w.pid) is not None]

    def close(self) -> None:
        """Drop waiting jobs, let running ones finish, end the threads and the worker processes."""
        with self._cond:
            self._closed = True
            self._pending.clear()
            self._cond.notify_all()
            threads = list(self._threads)
        for t in threads:
            if t is not threading.current_thread():
                t.join(timeout=self.timeout + 5.0)

    def _start_threads(self) -> None:
        for k in range(self.workers):
            worker = self._worker_factory(timeout=self.timeout)
            self._worker_processes.append(worker)
            t = threading.Thread(target=self._serve, args=(worker,), name=f"egtviz-png-{k}", daemon=True)
            self._threads.append(t)
            t.start()

    def _take(self) -> tuple[Hashable, PngJob] | None:
        """The oldest waiting job whose key has none running, taken off the queue (called under the lock)."""
        for key in self._pending:
            if key not in self._running:
                return key, self._pending.pop(key)
        return None

    def _next(self, worker: PngWorker) -> tuple[Hashable, PngJob] | None:
        """Wait for a job and mark it running; None once the renderer is closed."""
        while True:
            with self._cond:
                if self._closed:
                    return None
                item = self._take()
                if item is not None:
                    self._running.add(item[0])
                    self.started.append(id(item[0]))
                    self.renders += 1
                    return item
                if self._cond.wait(timeout=self.idle):
                    continue
            worker.close()  # idle: give its memory back (outside the lock: it may wait); the next job starts one

    def _serve(self, worker: PngWorker) -> None:
        try:
            while (item := self._next(worker)) is not None:
                key, job = item
                png: bytes | None = None
                error: BaseException | None = None
                try:
                    png = worker.render(job.svg, job.scale)
                except Exception as exc:  # noqa: BLE001 - every failure goes to the requester
                    error = exc
                with self._cond:
                    self._running.discard(key)
                    if key in self._pending:  # its next job waits behind the keys that waited meanwhile
                        self._pending[key] = self._pending.pop(key)
                    self._cond.notify_all()
                try:
                    job.deliver(png, error)
                except Exception:  # noqa: BLE001 - a requester's fault must not stop the renders of others
                    traceback.print_exc()
        finally:
            worker.close()


_shared: PngRenderer | None = None
_shared_lock = threading.Lock()


def shared_renderer() -> PngRenderer:
    """The server process's renderer, made at the first call (its workers start at the first render)."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = PngRenderer()
            atexit.register(shutdown)
        return _shared


def shutdown() -> None:
    """Close the shared renderer and its worker processes (at exit; a later PNG makes a new one)."""
    global _shared
    with _shared_lock:
        renderer, _shared = _shared, None
    if renderer is not None:
        renderer.close()


class PngDownloads:
    """One tab's PNG downloads: refusal above the limits, progress while waiting, the file or the reason.

    Args:
        client: the tab's ``viser.ClientHandle`` (``add_notification`` and ``send_file_download`` are used).
        renderer: the renderer to queue on; None: :func:`shared_renderer`, at the first request.
        scale: device pixels per CSS pixel of the PNG (2: sharp on slides).
    """

    def __init__(self, client: viser.ClientHandle, renderer: PngRenderer | None = None, *, scale: float = 2.0) -> None:
        self.client = client
        self._renderer = renderer
        self.scale = float(scale)
        self._lock = threading.Lock()
        self._note: viser.NotificationHandle | None = None
        self._closed = False

    @property
    def renderer(self) -> PngRenderer:
        """The renderer this tab queues on."""
        if self._renderer is None:
            self._renderer = shared_renderer()
        return self._renderer

    def request(self, filename: str, svg: str) -> bool:
        """Render ``svg`` and send it to the tab as ``filename``; False if refused (the tab was told why)."""
        # Not at the top: this module is also the worker process, which imports the renderer only once its
        # standard output no longer carries the replies (see main).
        from .figure_export import png_refusal

        refusal = png_refusal(svg, scale=self.scale)
        renderer = self.renderer
        with self._lock:
            if self._closed:
                return False
            if refusal is not None:
                self._notify("PNG not made: the figure is too large", f"{filename}: {refusal}")
                return False
            self._show_progress(f"{filename}: the download starts when it is ready.")
            try:
                renderer.request(self, PngJob(svg, self.scale, partial(self._deliver, filename)))
            except PngRenderError as exc:
                self._clear_progress()
                self._notify("Could not make the PNG", f"{filename}: {exc}")
                return False
        return True

    def close(self) -> None:
        """The tab left: drop its waiting render and ignore the result of a running one."""
        with self._lock:
            self._closed = True
        if self._renderer is not None:
            self._renderer.forget(self)

    def _deliver(self, filename: str, png: bytes | None, error: BaseException | None) -> None:
        with self._lock:
            if self._closed:
                return
            if not self.renderer.busy(self):
                self._clear_progress()
            if error is not None:
                if not isinstance(error, PngRenderError):
                    traceback.print_exception(error, file=sys.stderr)
                    error = PngRenderError(f"{type(error).__name__} (the details are in the server's log)")
                reason = str(error).rstrip(". ")
                self._notify("Could not make the PNG", f"{filename}: {reason}. The SVG download still works.")
                return
            try:
                assert png is not None  # a job delivers a PNG whenever it delivers no error
                self.client.send_file_download(filename, png, save_immediately=True)
            except Exception:  # noqa: BLE001 - the tab may have gone meanwhile
                traceback.print_exc()

    def _show_progress(self, body: str) -> None:
        """Show (or update) the tab's one "Rendering PNG..." notification (called under the lock)."""
        if self._note is not None:
            self._note.body = body
            return
        self._note = self.client.add_notification("Rendering PNG...", body, loading=True, with_close_button=False,
                                                  auto_close_seconds=None)

    def _clear_progress(self) -> None:
        note, self._note = self._note, None
        if note is not None:
            try:
                note.remove()
            except Exception:  # noqa: BLE001 - the tab may be gone
                pass

    def _notify(self, title: str, body: str) -> None:
        try:
            self.client.add_notification(title, body, color="red", auto_close_seconds=12.0)
        except Exception:  # noqa: BLE001 - the tab may be gone
            pass


def main() -> int:
    """The worker process: render each request from standard input, reply on standard output, until end of input."""
    reply = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # whatever a library prints goes to the server's log, not into the replies
    try:
        os.nice(WORKER_NICENESS)
    except (AttributeError, OSError):
        pass
    from .figure_export import svg_to_png  # only now: anything it prints on import goes to the log

    requests = sys.stdin.buffer
    try:
        while len(head := requests.read(_REQUEST.size)) == _REQUEST.size:
            scale, n = _REQUEST.unpack(head)
            svg = _read_exact(requests, n).decode("utf-8", "replace")
            try:
                payload, status = svg_to_png(svg, scale=scale), _DONE
            except Exception as exc:  # noqa: BLE001 - the reason goes back to the tab
                payload, status = " ".join(str(exc).split())[:300].encode("utf-8"), _FAILED
            reply.write(_REPLY.pack(status, len(payload)) + payload)
            reply.flush()
    except (EOFError, BrokenPipeError, KeyboardInterrupt):
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
