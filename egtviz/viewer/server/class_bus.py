"""The class shared between worker processes (``egtviz serve --classroom --workers N``).

* :class:`ClassHub` runs in the supervising process: a ``multiprocessing.connection`` listener on a Unix socket
  with a random authentication key, one connection per worker. It keeps the merged class
  (:mod:`.class_patch`) and the room's newest frame, relays each worker's changes and frames to the others, and
  gives a worker that (re)starts the class as it is. A worker that ends takes its tabs out of the class.
* :class:`ClassroomBus` runs in each worker, beside its :class:`~egtviz.viewer.classroom.ClassroomHost`: it
  sends what changed in the worker's class (coalesced, at most every :data:`SYNC_S`, and every
  :data:`PERIOD_S` for what changes without an event, such as a student's own scene), merges what the others
  changed, and sends each frame the instructor's tab draws to the other workers, which show it to their own
  followers (the scene's SVG panels are drawn once, by the instructor's worker).

Messages are JSON (``send_bytes``): nothing a connection sends is unpickled.
"""

from __future__ import annotations

import collections
import json
import logging
import os
import secrets
import socket
import tempfile
import threading
import time
from collections.abc import Callable
from multiprocessing.connection import Client, Connection, Listener
from typing import TYPE_CHECKING

from ...classroom import Classroom
from .class_patch import (
    JsonObject, apply_patch, diff, empty_patch, full_patch, global_tab, is_empty, merge_into, normal, parsed_patch,
)

if TYPE_CHECKING:
    from ..classroom.follow_view import RoomFrame
    from ..classroom.host import ClassroomHost
    from ..classroom.room_sender import FrameSender

__all__ = ["PERIOD_S", "SYNC_S", "ClassHub", "ClassroomBus", "frame_message"]

_log = logging.getLogger(__name__)

#: Seconds a worker waits after a change before sending it (changes in that time go together).
SYNC_S = 0.05
#: Seconds between two looks at the whole class for changes that come without an event.
PERIOD_S = 1.0


def _send(conn: Connection, lock: threading.Lock, message: JsonObject) -> None:
    data = json.dumps(message, separators=(",", ":"), allow_nan=False).encode()
    with lock:
        conn.send_bytes(data)


class _Outbox:
    """What the hub still has to send to one worker: patches in order, and the newest frame only."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self._cond = threading.Condition()
        self._patches: collections.deque[JsonObject] = collections.deque()
        self._frame: JsonObject | None = None
        self._closed = False
        self._lock = threading.Lock()
        threading.Thread(target=self._run, name="egtviz-hub-out", daemon=True).start()

    def put(self, message: JsonObject) -> None:
        with self._cond:
            if message["kind"] == "frame":
                self._frame = message  # a worker behind on frames skips to the newest
            else:
                self._patches.append(message)
            self._cond.notify()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify()

    def _run(self) -> None:
        while True:
            with self._cond:
                while not (self._patches or self._frame or self._closed):
                    self._cond.wait()
                if self._closed:
                    return
                message: JsonObject | None
                if self._patches:
                    message = self._patches.popleft()
                else:
                    message, self._frame = self._frame, None
            if message is None:
                continue
            try:
                _send(self.conn, self._lock, message)
            except (OSError, ValueError):
                return


class ClassHub:
    """The supervising process's relay (see the module docstring). ``address`` and ``authkey`` are given to
    each worker; :meth:`close` stops it."""

    def __init__(self) -> None:
        self._folder = tempfile.mkdtemp(prefix="egtviz-hub-")
        self.address = os.path.join(self._folder, "hub")
        self.authkey = secrets.token_bytes(32)
        self._listener = Listener(self.address, family="AF_UNIX", authkey=self.authkey)
        os.chmod(self.address, 0o600)
        self._lock = threading.Lock()
        self._state = normal(_empty_state_json())
        self._tabs: dict[int, dict[str, list]] = {}
        self._outboxes: dict[int, _Outbox] = {}
        self._frame: JsonObject | None = None
        self._closed = False
        #: Messages relayed (patches and frames), for tests and benchmarks.
        self.relayed = 0
        threading.Thread(target=self._accept, name="egtviz-hub-accept", daemon=True).start()

    def _accept(self) -> None:
        while not self._closed:
            try:
                conn = self._listener.accept()
            except OSError:
                if self._closed:
                    return
                continue  # a peer without the key, or one that went away during the handshake
            except Exception:  # noqa: BLE001 - multiprocessing's AuthenticationError and the like
                continue
            threading.Thread(target=self._serve, args=(conn,), name="egtviz-hub-in", daemon=True).start()

    def _serve(self, conn: Connection) -> None:
        worker = None
        try:
            hello = json.loads(conn.recv_bytes())
            worker = int(hello["worker"])
            box = _Outbox(conn)
            with self._lock:
                old = self._outboxes.pop(worker, None)
                self._outboxes[worker] = box
                self._drop_tabs(worker)
                box.put({"kind": "patch", "patch": full_patch(self._state, self._others_tabs(worker))})
                if self._frame is not None:
                    box.put(self._frame)
            if old is not None:
                old.close()
            while True:
                self._handle(worker, json.loads(conn.recv_bytes()))
        except (EOFError, OSError, ValueError, KeyError, TypeError):
            pass
        finally:
            try:
                conn.close()
            except OSError:  # closed by close() meanwhile
                pass
            if worker is not None:
                with self._lock:
                    mine = self._outboxes.get(worker)
                    if mine is not None and mine.conn is conn:
                        del self._outboxes[worker]
                        mine.close()
                        self._drop_tabs(worker)

    def _others_tabs(self, worker: int) -> dict[str, list]:
        return {str(global_tab(w, int(t))): v for w, tabs in self._tabs.items() if w != worker for t, v in tabs.items()}

    def _drop_tabs(self, worker: int) -> None:
        """Worker ``worker``'s tabs leave the class (it ended or started again); the lock is held."""
        gone = self._tabs.pop(worker, {})
        if gone:
            patch = empty_patch()
            patch["tabs"]["del"] = [str(global_tab(worker, int(t))) for t in gone]
            self._relay(worker, {"kind": "patch", "patch": patch})

    def _relay(self, worker: int, message: JsonObject) -> None:
        for w, box in self._outboxes.items():
            if w != worker:
                box.put(message)
        self.relayed += 1

    def _handle(self, worker: int, message: JsonObject) -> None:
        kind = message.get("kind")
        with self._lock:
            if kind == "frame":
                self._frame = message
                self._relay(worker, message)
            elif kind == "patch":
                patch = message["patch"]
                tabs = patch.get("tabs", {"set": {}, "del": []})
                own = self._tabs.setdefault(worker, {})
                own.update(tabs.get("set", {}))
                for t in tabs.get("del", []):
                    own.pop(t, None)
                self._state = apply_patch(self._state, {**patch, "tabs": {}})
                out = dict(patch)
                out["tabs"] = {"set": {str(global_tab(worker, int(t))): v for t, v in tabs.get("set", {}).items()},
                               "del": [str(global_tab(worker, int(t))) for t in tabs.get("del", [])]}
                self._relay(worker, {"kind": "patch", "patch": out})

    def state(self) -> JsonObject:
        """The merged class (:func:`~.class_patch.normal` form, without tabs)."""
        with self._lock:
            return dict(self._state)

    def close(self) -> None:
        self._closed = True
        with self._lock:
            for box in self._outboxes.values():
                box.close()
                try:
                    box.conn.close()
                except OSError:
                    pass
            self._outboxes.clear()
        self._listener.close()
        try:
            os.unlink(self.address)
        except OSError:
            pass
        try:
            os.rmdir(self._folder)
        except OSError:
            pass


def _empty_state_json() -> str:
    from ...classroom import ClassState

    return ClassState().to_json()


def frame_message(frame: RoomFrame) -> JsonObject:
    """A :class:`~egtviz.viewer.classroom.follow_view.RoomFrame` as a bus message (its derived geometry is
    computed again where it arrives: it is the scene's)."""
    from ...scene.io import scene_to_dict

    return {"kind": "frame", "version": frame.version, "scene": scene_to_dict(frame.scene),
            "panels": [list(p) for p in frame.panels], "readout": frame.readout, "present": frame.present,
            "caption": str(getattr(frame, "caption", ""))}


class _RelaySender:
    """The host's room sender, which also hands every frame it is posted to the bus."""

    def __init__(self, inner: FrameSender, publish: Callable[[RoomFrame], None]) -> None:
        self._inner = inner
        self._publish = publish

    @property
    def latest(self) -> RoomFrame | None:
        return self._inner.latest

    def next_number(self) -> int:
        return self._inner.next_number()

    def post(self, frame: RoomFrame) -> None:
        self._inner.post(frame)
        self._publish(frame)

    def clear_pending(self) -> None:
        self._inner.clear_pending()

    def close(self) -> None:
        self._inner.close()


class ClassroomBus:
    """A worker's end of the hub (see the module docstring).

    Args:
        address, authkey: the hub's (:class:`ClassHub`).
        worker: this worker's number (0..N-1; a restarted worker has its old number).
    """

    def __init__(self, address: str, authkey: bytes, worker: int) -> None:
        self.worker = int(worker)
        self._conn = Client(address, family="AF_UNIX", authkey=authkey)
        self._send_lock = threading.Lock()
        self._sync_lock = threading.Lock()
        self._wake = threading.Event()
        self._closed = False
        self._room: Classroom | None = None
        self._last: JsonObject | None = None
        self._state_callbacks: list[Callable[[JsonObject], None]] = []
        self._frame_callbacks: list[Callable[[JsonObject], None]] = []
        self._welcomed = threading.Event()
        #: Patches and frames received from the other workers.
        self.received = {"patch": 0, "frame": 0}
        _send(self._conn, self._send_lock, {"kind": "hello", "worker": self.worker})

    def start(self) -> None:
        """Start hearing the other workers (:meth:`attach` does; the hub's first message, the class as it is,
        waits in the connection until then)."""
        threading.Thread(target=self._read, name="egtviz-bus-in", daemon=True).start()

    # -- the small interface the viewer side may call ---------------------------------------------------

    def publish(self, state_json: str | Callable[[], str]) -> None:
        """Send what changed in this worker's class, given its state (:meth:`Classroom.to_json`, or a function
        returning it: then read while no other worker's change is being merged)."""
        with self._sync_lock:
            cur = normal(state_json() if callable(state_json) else state_json)
            patch = diff(self._last or normal(_empty_state_json()), cur)
            self._last = cur
        if not is_empty(patch):
            _send(self._conn, self._send_lock, {"kind": "patch", "patch": patch})

    def publish_frame(self, frame: RoomFrame) -> None:
        """Send a room frame drawn here to the other workers' followers."""
        try:
            _send(self._conn, self._send_lock, frame_message(frame))
        except (OSError, ValueError) as exc:
            _log.warning("egtviz worker %d: a room frame was not relayed (%s)", self.worker, exc)

    def on_state(self, callback: Callable[[JsonObject], None]) -> None:
        """Call ``callback(patch)`` (in the bus's thread) with each change another worker made."""
        self._state_callbacks.append(callback)

    def on_frame(self, callback: Callable[[JsonObject], None]) -> None:
        """Call ``callback(message)`` (in the bus's thread) with each frame another worker drew."""
        self._frame_callbacks.append(callback)

    # -- wiring to a ClassroomHost ----------------------------------------------------------------------

    def attach(self, host: ClassroomHost) -> None:
        """Share ``host``'s class with the other workers and show their frames to its followers."""
        room = self._room = host.room
        self._host = host
        inner = host.sender
        host.sender = _RelaySender(inner, self.publish_frame)
        self._inner_sender = inner
        self.on_frame(self._show_frame)
        self._unsubscribe = room.subscribe(lambda _event: self._wake.set())
        threading.Thread(target=self._sync_loop, args=(room,), name="egtviz-bus-sync", daemon=True).start()
        self.start()

    def wait_welcomed(self, timeout: float = 10.0) -> bool:
        """Wait until the hub has given this worker the class as it is; False if it did not in time."""
        return self._welcomed.wait(timeout)

    def _sync_loop(self, room: Classroom) -> None:
        while not self._closed:
            self._wake.wait(PERIOD_S)
            if self._closed:
                return
            time.sleep(SYNC_S)  # let a burst of changes go together
            self._wake.clear()
            try:
                self.publish(room.to_json)
            except (OSError, ValueError) as exc:
                if not self._closed:
                    _log.warning("egtviz worker %d: the class could not be shared (%s)", self.worker, exc)
                return

    def _apply(self, patch: JsonObject) -> None:
        if self._room is None:
            return
        parsed = parsed_patch(patch)
        with self._sync_lock:
            self._room.update(lambda old: merge_into(old, patch, parsed))
            self._last = apply_patch(self._last or normal(_empty_state_json()), patch)

    def _show_frame(self, message: JsonObject) -> None:
        from ...scene import SceneModel
        from ...scene.io import scene_from_dict
        from ..classroom.follow_view import RoomFrame

        scene = scene_from_dict(message["scene"], "room frame")
        derived = SceneModel(scene).derived
        sender = self._inner_sender
        sender.post(RoomFrame(sender.next_number(), int(message["version"]), scene, derived,
                              tuple((str(k), str(t), str(s)) for k, t, s in message["panels"]),
                              str(message["readout"]), bool(message["present"]), str(message.get("caption", ""))))

    def _read(self) -> None:
        while not self._closed:
            try:
                message = json.loads(self._conn.recv_bytes())
            except (EOFError, OSError, ValueError, TypeError):  # TypeError: the connection closed under recv
                if not self._closed:
                    _log.warning("egtviz worker %d: the supervising process's hub went away", self.worker)
                return
            kind = message.get("kind")
            try:
                if kind == "patch":
                    self._apply(message["patch"])
                    self._welcomed.set()
                    for callback in self._state_callbacks:
                        callback(message["patch"])
                elif kind == "frame":
                    for callback in self._frame_callbacks:
                        callback(message)
                self.received[kind] = self.received.get(kind, 0) + 1
            except Exception:  # noqa: BLE001 - one bad message must not stop the worker's share of the class
                _log.exception("egtviz worker %d: a %s from the hub could not be applied", self.worker, kind)

    def close(self) -> None:
        self._closed = True
        self._wake.set()
        unsubscribe = getattr(self, "_unsubscribe", None)
        if unsubscribe is not None:
            unsubscribe()
        try:
            # Shut the socket down first: closing it alone leaves the reading thread's recv waiting, and the
            # hub would not hear that this worker went.
            with socket.socket(fileno=os.dup(self._conn.fileno())) as sock:
                sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        try:
            self._conn.close()
        except OSError:
            pass
