"""``egtviz serve --workers N``: N worker processes behind the one URL, restarted when one dies.

How connections reach the workers: each worker runs the ordinary server (viser, the guards, the app). The
supervising process reserves the port after checking that nobody holds it, listens on it, and hands each new
connection to the worker that holds the fewest (:mod:`.balance`; a tab's websocket then lives on that worker, the
page's static files are the same in every worker). With ``balance=False`` the workers instead bind the port with
``SO_REUSEPORT`` and the kernel picks a worker by a hash of each connection's addresses (the supervising process's
socket then never listens, so no connection goes to it), which split rooms unevenly (9 / 21 tabs in one run).

The supervising process starts the workers, restarts one that ends (a tab of it reconnects by itself, to a live
worker; its progress is in the SQLite database, its class in the hub), and with ``--classroom`` runs the
:class:`~.class_bus.ClassHub` that shares the class between them (:mod:`.class_bus`). Secrets (the instructor
token, the hub's key) go to a worker on its standard input, never on its command line.
"""

from __future__ import annotations

import dataclasses
import errno
import json
import os
import queue
import socket
import subprocess
import sys
import threading
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import viser

    from ..classroom import ClassroomHost
    from ..tabs import EgtvizApp
    from .class_bus import ClassroomBus
    from .class_patch import JsonObject

__all__ = ["MAX_WORKERS", "REPLY", "Supervisor", "WorkerOptions", "enable_reuse_port", "reserve_port",
           "serve_workers", "start_worker", "worker_main", "worker_of_connection"]

#: The most workers ``--workers`` accepts.
MAX_WORKERS = 64
#: Seconds a worker is given to start (import, bind, build the app).
START_TIMEOUT = 60.0
#: A worker that lived this long before dying is restarted at once; one that died sooner waits, longer each time.
HEALTHY_S = 30.0
MAX_BACKOFF_S = 10.0
_READY = "egtviz-worker-ready "
#: A worker's answer to a command on its input (benchmarks' workers answer ``instrument`` and ``report``).
REPLY = "egtviz-worker-reply "


def enable_reuse_port() -> None:
    """Make every websockets server this process starts bind with ``SO_REUSEPORT`` (the workers' one port).

    viser 1.1.1 calls ``websockets.asyncio.server.serve(handler, host, port, ...)`` and passes no socket option;
    ``serve`` hands unknown keywords to asyncio's ``create_server``, whose ``reuse_port`` this sets. Called only
    in a worker process (this is process-wide).
    """
    import inspect

    import viser.infra._infra as infra
    import websockets.asyncio.server as ws_server

    if getattr(ws_server.serve, "egtviz_reuse_port", False):
        return
    if "websockets.asyncio.server.serve(" not in inspect.getsource(infra.WebsockServer._background_worker):
        raise RuntimeError(f"viser {viser_version()} no longer starts its server with websockets.asyncio.server.serve: "
                           "the workers cannot share one port (run without --workers)")
    base = ws_server.serve

    class serve(base):  # type: ignore[valid-type,misc]  # noqa: N801 - it replaces websockets' ``serve``
        egtviz_reuse_port = True

        def __init__(self, *args: object, **kwargs: object) -> None:
            kwargs.setdefault("reuse_port", True)
            super().__init__(*args, **kwargs)

    ws_server.serve = serve  # type: ignore[misc]


def viser_version() -> str:
    import viser

    return str(viser.__version__)


def _addresses(host: str, port: int) -> list[tuple]:
    return socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)


def _bind_all(host: str, port: int, *, reuse_port: bool) -> list[socket.socket]:
    """Sockets bound to every address of ``host`` at ``port`` (closed again on failure)."""
    socks: list[socket.socket] = []
    try:
        for family, kind, proto, _name, sockaddr in _addresses(host, port):
            sock = socket.socket(family, kind, proto)
            socks.append(sock)
            # The probe as asyncio's servers bind (a port in TIME_WAIT is free); the holder without SO_REUSEADDR,
            # which on Linux would let anyone bind beside a socket that does not listen.
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT if reuse_port else socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6:
                sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            sock.bind(sockaddr)
            port = port or sock.getsockname()[1]  # one port for every address
    except BaseException:
        for sock in socks:
            sock.close()
        raise
    return socks


def reserve_port(host: str, port: int, *, tries: int = 100) -> tuple[int, list[socket.socket]]:
    """The port the workers share: ``port`` or the next free one (0: any free one), and the sockets that hold it.

    A port counts as free when a socket without ``SO_REUSEPORT`` can bind it (so nobody holds it, not even
    another program that set ``SO_REUSEPORT``); it is then held by sockets with ``SO_REUSEPORT`` that never
    listen, until the caller closes them.

    Raises:
        OSError: no free port in ``tries`` attempts, or binding is refused for another reason.
    """
    for attempt in range(tries):
        want = port + attempt if port else 0
        try:
            probes = _bind_all(host, want, reuse_port=False)
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE and port:
                continue
            raise
        chosen = probes[0].getsockname()[1]
        for sock in probes:
            sock.close()
        try:
            return chosen, _bind_all(host, chosen, reuse_port=True)
        except OSError as exc:  # taken between the probe and now
            if exc.errno != errno.EADDRINUSE:
                raise
    raise OSError(errno.EADDRINUSE, f"no free port from {port} in {tries} tries")


@dataclasses.dataclass(frozen=True)
class WorkerOptions:
    """What every worker serves (as for :func:`egtviz.viewer.server.launch.start`)."""

    host: str = "127.0.0.1"
    scene: str | None = None
    demo: str | None = None
    lesson: str | None = None
    present: bool = False
    course: bool = False
    allow_hosts: tuple[str, ...] = ()
    classroom: bool = False


def _socket_inodes(pid: int) -> set[str]:
    out: set[str] = set()
    try:
        fds = os.listdir(f"/proc/{pid}/fd")
    except OSError:
        return out
    for fd in fds:
        try:
            link = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue
        if link.startswith("socket:["):
            out.add(link[8:-1])
    return out


def worker_of_connection(server_port: int, client_port: int, pids: list[int]) -> int | None:
    """Which of ``pids`` holds the server side of the IPv4 connection from local port ``client_port`` to
    ``server_port`` (read from Linux's ``/proc``; None if not found): tests and benchmarks see where a tab went."""
    inode = None
    try:
        lines = open("/proc/net/tcp").read().splitlines()[1:]
    except OSError:
        return None
    for line in lines:
        parts = line.split()
        if int(parts[1].split(":")[1], 16) == server_port and int(parts[2].split(":")[1], 16) == client_port:
            inode = parts[9]
    if inode is None:
        return None
    return next((pid for pid in pids if inode in _socket_inodes(pid)), None)


# -- a worker ----------------------------------------------------------------------------------------------


def start_worker(config: JsonObject) -> tuple[viser.ViserServer, EgtvizApp, ClassroomHost | None,
                                                    ClassroomBus | None]:
    """Start the server in this process as ``config`` says; returns ``(server, app, host, bus)``."""
    from .launch import start, student_url

    o = config["options"]
    channel = config.get("channel")
    if channel is None:  # the kernel balances: bind the shared port beside the other workers
        enable_reuse_port()
    else:  # handed connections by the supervising process: this worker's own socket stays on loopback, unused
        from .balance import capture_serve

        capture_serve(reuse_port=False)
    server, app = start(o["host"] if channel is None else "127.0.0.1", config["port"] if channel is None else 0,
                        o["scene"], demo=o["demo"], present=o["present"], lesson=o["lesson"], course=o["course"],
                        allow_hosts=tuple(o["allow_hosts"]))
    if channel is None and server.get_port() != config["port"]:
        server.stop()
        raise OSError(f"worker {config['index']}: bound port {server.get_port()}, not the shared {config['port']}")
    if channel is not None:
        from .balance import adopt_connections, served
        from .viser_adapter import event_loop

        try:
            adopt_connections(socket.socket(fileno=int(channel)), served()[-1], event_loop(server))
        except (RuntimeError, IndexError):
            server.stop()
            raise
    host = bus = None
    if o["classroom"]:
        from ...classroom import Classroom
        from ..classroom import ClassroomHost
        from .class_bus import ClassroomBus

        room = Classroom(getattr(app.course, "progress", None), token=config["token"])
        host = ClassroomHost(app, room, student_url=student_url(o["host"], config["port"]))
        bus = ClassroomBus(config["hub"], bytes.fromhex(config["authkey"]), config["index"])
        bus.attach(host)
        bus.wait_welcomed(10.0)
    return server, app, host, bus


def worker_main() -> int:
    """A worker process: its configuration is one JSON line on standard input; it serves until that input ends
    (the supervising process closed it, or ended)."""
    config = json.loads(sys.stdin.readline())
    server, _app, host, bus = start_worker(config)
    print(_READY + json.dumps({"index": config["index"], "pid": os.getpid(), "port": config["port"]}), flush=True)
    try:
        sys.stdin.read()
    except KeyboardInterrupt:  # the terminal's Ctrl-C reaches every process of the group: the supervisor stops us
        sys.stdin.read()
    finally:
        if bus is not None:
            bus.close()
        if host is not None:
            host.close()
        server.stop()
    return 0


# -- the supervising process -------------------------------------------------------------------------------


class _Slot:
    """One worker's place: its process now, and how its restarts have gone."""

    def __init__(self, index: int) -> None:
        self.index = index
        self.proc: subprocess.Popen | None = None
        self.started = 0.0
        self.ready = threading.Event()
        self.pid: int | None = None
        self.failures = 0
        self.restarts = 0
        self.retry_at = 0.0
        self.replies: queue.Queue[dict] = queue.Queue()


class Supervisor:
    """N workers on one port, restarted when they end; with ``options.classroom``, the hub of their class.

    Args:
        workers: N (1..:data:`MAX_WORKERS`).
        port: the port asked for (0: any free one); :attr:`port` is the one served.
        options: what each worker serves.
        token: the instructor's token (default: a random one; :attr:`token`).
        worker_module: the module each worker runs (``python -m``; a benchmark's instrumented worker).
        balance: hand each connection to the worker with the fewest (:mod:`.balance`); False: the kernel's hash.
    """

    def __init__(self, workers: int, port: int, options: WorkerOptions, *, token: str | None = None,
                 worker_module: str = "egtviz.viewer.server.workers", balance: bool = True) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= MAX_WORKERS:
            raise ValueError(f"workers: expected a whole number 1 to {MAX_WORKERS}, got {workers!r}")
        self.options = options
        self.port, self._reserved = reserve_port(options.host, port)
        self.dispatcher = None
        if balance:
            from .balance import Dispatcher

            self.dispatcher = Dispatcher(self._reserved)
        self.hub = None
        self.token = None
        if options.classroom:
            from ...classroom import TokenGuard
            from .class_bus import ClassHub

            self.token = TokenGuard(token).token
            self.hub = ClassHub()
        self.slots = [_Slot(i) for i in range(workers)]
        self.worker_module = worker_module
        self._lock = threading.Lock()
        self._stopping = False
        self.log = lambda text: print(f"egtviz: {text}", file=sys.stderr, flush=True)

    def _config(self, index: int, channel: int | None = None) -> str:
        config = {"index": index, "port": self.port, "options": dataclasses.asdict(self.options),
                  "token": self.token, "hub": self.hub.address if self.hub else None,
                  "authkey": self.hub.authkey.hex() if self.hub else None, "channel": channel}
        return json.dumps(config) + "\n"

    def _spawn(self, slot: _Slot) -> None:
        slot.ready.clear()
        slot.started = time.monotonic()
        theirs = self.dispatcher.channel_for(slot.index) if self.dispatcher is not None else None
        fd = None if theirs is None else theirs.fileno()  # the same number in the worker (pass_fds)
        try:
            proc = subprocess.Popen([sys.executable, "-m", self.worker_module], stdin=subprocess.PIPE,
                                    stdout=subprocess.PIPE, text=True, pass_fds=() if fd is None else (fd,))
        finally:
            if theirs is not None:
                theirs.close()  # the worker has its copy
        slot.proc = proc
        assert proc.stdin is not None
        proc.stdin.write(self._config(slot.index, fd))
        proc.stdin.flush()
        threading.Thread(target=self._read_output, args=(slot, proc), daemon=True,
                         name=f"egtviz-worker-{slot.index}-out").start()

    def _read_output(self, slot: _Slot, proc: subprocess.Popen) -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            if line.startswith(_READY):
                slot.pid = int(json.loads(line[len(_READY):])["pid"])
                slot.ready.set()
                if self.dispatcher is not None:
                    self.dispatcher.mark_ready(slot.index)
            elif line.startswith(REPLY):
                slot.replies.put(json.loads(line[len(REPLY):]))
            elif "(viser)" not in line and not line.startswith(("\u256d", "\u2502", "\u2570")):
                # viser's banner and "server stopped" (every worker prints them) are the supervisor's to say
                sys.stdout.write(line)
                sys.stdout.flush()

    def start(self, timeout: float = START_TIMEOUT) -> None:
        """Start every worker and wait until each serves.

        Raises:
            RuntimeError: a worker ended or did not serve within ``timeout`` (every worker is stopped).
        """
        for slot in self.slots:
            self._spawn(slot)
        deadline = time.monotonic() + timeout
        for slot in self.slots:
            while not slot.ready.wait(0.1):
                assert slot.proc is not None
                if slot.proc.poll() is not None or time.monotonic() > deadline:
                    status = slot.proc.poll()
                    self.stop()
                    why = f"it ended with status {status}" if status is not None else f"not serving after {timeout:g} s"
                    raise RuntimeError(f"worker {slot.index} did not start ({why})")
        threading.Thread(target=self._watch, name="egtviz-supervisor", daemon=True).start()

    def _watch(self) -> None:
        while not self._stopping:
            time.sleep(0.2)
            for slot in self.slots:
                with self._lock:
                    if self._stopping or slot.proc is None or slot.proc.poll() is None:
                        continue
                    now = time.monotonic()
                    if slot.retry_at == 0.0:
                        lived = now - slot.started
                        slot.failures = 0 if lived > HEALTHY_S else slot.failures + 1
                        delay = 0.0 if slot.failures == 0 else min(0.5 * 2 ** (slot.failures - 1), MAX_BACKOFF_S)
                        slot.retry_at = now + delay
                        self.log(f"worker {slot.index} (pid {slot.pid}) ended with status {slot.proc.returncode}; "
                                 f"restarting it{'' if delay == 0 else f' in {delay:g} s'}")
                    if now >= slot.retry_at:
                        slot.retry_at = 0.0
                        slot.restarts += 1
                        self._spawn(slot)

    def ask(self, index: int, command: str, timeout: float = 60.0) -> dict:
        """Send ``command`` (one line) to worker ``index`` and wait for its reply (a worker that answers
        commands: :mod:`egtviz.bench.classroom_room`'s)."""
        slot = self.slots[index]
        assert slot.proc is not None and slot.proc.stdin is not None
        slot.proc.stdin.write(command + "\n")
        slot.proc.stdin.flush()
        return slot.replies.get(timeout=timeout)

    def pids(self) -> list[int | None]:
        """The workers' process ids now (None: one is starting)."""
        return [s.pid if s.proc is not None and s.proc.poll() is None and s.ready.is_set() else None
                for s in self.slots]

    def wait_ready(self, timeout: float = START_TIMEOUT) -> bool:
        """Wait until every worker serves (after a restart); False if one does not within ``timeout``."""
        deadline = time.monotonic() + timeout
        while None in self.pids():  # a worker that has died counts as not ready before it is restarted
            if time.monotonic() > deadline:
                return False
            time.sleep(0.05)
        return True

    def stop(self, timeout: float = 10.0) -> None:
        """Stop every worker (their input is closed; one that does not end in ``timeout`` s is killed)."""
        with self._lock:
            self._stopping = True
        procs = [s.proc for s in self.slots if s.proc is not None]
        for proc in procs:
            try:
                if proc.stdin is not None:
                    proc.stdin.close()
            except OSError:
                pass
        deadline = time.monotonic() + timeout
        for proc in procs:
            try:
                proc.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
        if self.dispatcher is not None:
            self.dispatcher.close()
        for sock in self._reserved:
            sock.close()
        if self.hub is not None:
            self.hub.close()


def _options_problem(options: WorkerOptions) -> str | None:
    """What is wrong with ``options`` (as ``egtviz serve`` says it, before any worker starts), None if nothing."""
    from ...lessons import LessonError, load
    from ...scene import SceneFileError, scene_from_argument
    from .guard import allowed_hosts

    try:
        allowed_hosts(options.allow_hosts)
    except ValueError as exc:
        return f"cannot use {exc}"
    try:
        if options.scene is not None:
            scene_from_argument(options.scene)
        if options.lesson is not None:
            load(options.lesson)
    except SceneFileError as exc:
        return f"cannot read the scene file: {exc}"
    except LessonError as exc:
        return f"cannot open the lesson: {exc}"
    return None


def serve_workers(workers: int, port: int, options: WorkerOptions, *,
                  stop_event: threading.Event | None = None) -> int:
    """``egtviz serve --workers N``: start the workers, print the URLs, supervise until Ctrl-C (or
    ``stop_event``); returns the exit status (1: the port or a worker could not be started)."""
    from .launch import is_wildcard, reachable_urls, student_url, terminate_as_interrupt

    problem = _options_problem(options)
    if problem is not None:
        print(f"egtviz: {problem}", file=sys.stderr)
        return 2
    try:
        sup = Supervisor(workers, port, options)
        sup.start()
    except (OSError, RuntimeError) as exc:
        print(f"egtviz: cannot start the server: {exc}", file=sys.stderr)
        return 1
    if port and sup.port != port:
        print(f"egtviz: port {port} is busy on {options.host}; using {sup.port}", file=sys.stderr, flush=True)
    stop = stop_event or threading.Event()
    try:
        terminate_as_interrupt()
        if is_wildcard(options.host):
            print(f"egtviz: warning: --host {options.host} opens the app to the network: anyone who can reach this "
                  "machine can use it (each tab has its own scene; see docs/server.md)", file=sys.stderr, flush=True)
        print(f"egtviz running at {' '.join(reachable_urls(options.host, sup.port))} ({workers} worker{'' if workers == 1 else 's'})", flush=True)
        if sup.token is not None:
            from ..classroom import instructor_url, qr_terminal

            url = student_url(options.host, sup.port)
            print(f"egtviz classroom: students open {url}", flush=True)
            print(qr_terminal(url), end="", flush=True)
            print("egtviz classroom: instructor (keep this secret) "
                  f"{instructor_url(reachable_urls(options.host, sup.port)[0], sup.token)}", flush=True)
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        print("egtviz: stopped", flush=True)
    finally:
        sup.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(worker_main())
