"""A class on an :class:`~egtviz.viewer.tabs.EgtvizApp`: which tab is the instructor's, what each
student's tab shows, and the room's scene sent to every follower.

* **Who is who.** The instructor opens ``/egtviz-instructor/<token>`` (:mod:`.links`); the token is read from
  the tab's websocket handshake and checked by the classroom (rate limited; a wrong one gets a page saying the
  link is not valid, and nothing else). Every other tab is a student's: it joins under a name, kept in the
  browser so that a reconnecting tab comes back as the same student, with their own scene.
* **Follow me.** Each drawn update of the instructor's tab becomes one :class:`~.follow_view.RoomFrame` (the
  scene, its derived geometry and the panels' SVG strings, all made once); one sender thread gives the newest
  frame to every follower (a slow follower never holds up the instructor, and a follower that falls behind
  skips to the newest frame).
* **Released.** A student not following works on their own scene (a workbench), or, released to the tasks,
  on the instructor's lesson step if the pacing allows it.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, TypeVar

import viser

from ...classroom import (
    AnswersChanged, CamerasLocked, Classroom, Event, FollowChanged, Mode, ModeChanged, NamesShown, PacingChanged,
    PauseChanged, QuestionAsked, RosterChanged, SharedChanged, SnapshotShown,
)
from ...controllers.class_member import StudentController
from ...controllers.class_text import lesson_steps, typed_name
from ...scene import SceneModel
from ..server.guard import handshake_of, serve_page_under
from ..workbench.fields import notify_error, on_event
from .camera_lock import CameraLock
from .follow_view import FollowView
from .links import INSTRUCTOR_PREFIX, token_from_path
from .course_gate import CourseGate
from .room_html import step_caption
from .room_sender import FrameSender, RoomSender, frame_from_scene, frame_of
from .snapshot_pane import RoomSnapshots
from .student_bar import JoinPage, StudentBar, notify_refusal, stored_name
from .instructor_panel import InstructorPanel

if TYPE_CHECKING:
    from ...lessons import LessonRun
    from ..tabs import EgtvizApp
    from ..workbench.app import ClientView

__all__ = ["NAME_KEY", "ClassroomHost"]

#: The browser's local storage key under which a student's name is kept (a reconnecting tab rejoins with it).
NAME_KEY = "egtviz-classroom-name"
#: Seconds a new tab is given to say whether it holds a name.
NAME_TIMEOUT = 3.0
#: Seconds to wait for the instructor's own frame of a scene published on another process before drawing it here.
SHARED_GRACE_S = 0.2
_T = TypeVar("_T")
_REFUSED_PAGE = ('<div data-egtviz="refused" style="padding:0.6em;font-size:1.2em">This link is not valid.</div>')


class ClassroomHost:
    """The class taught on ``app``'s server.

    Args:
        app: the viewer app (its ``classroom`` hook is set to this host).
        room: the class's state (default: a new :class:`~egtviz.classroom.Classroom` on the course's progress).
        student_url: the URL students open (shown with its QR code in the instructor's panel).
    """

    def __init__(self, app: EgtvizApp, room: Classroom | None = None, *, student_url: str = "") -> None:
        self.app = app
        progress = getattr(app.course, "progress", None)
        self.room = room if room is not None else Classroom(progress)
        self.student_url = student_url
        self._lock = threading.RLock()
        self._clients: dict[int, viser.ClientHandle] = {}
        self._roles: dict[int, str] = {}
        self._fresh: set[int] = set()
        self.followers: dict[int, FollowView] = {}
        self.bars: dict[int, StudentBar] = {}
        self.panels: dict[int, InstructorPanel] = {}
        self.snapshots = RoomSnapshots()
        self._models: dict[str, SceneModel] = {}
        self._tab_locks: dict[int, threading.RLock] = {}
        self._publishing = threading.local()
        self._routes = ThreadPoolExecutor(max_workers=2, thread_name_prefix="egtviz-class-route")
        #: Sends the room's frames to this process's followers (a relay between processes may wrap it).
        self._own_sender = RoomSender(lambda: list(self._copy(self.followers).values()))
        self.sender: FrameSender = self._own_sender
        self.cameras = CameraLock(self.room, lambda: self._copy(self.followers),
                                  released=lambda: (self._copy(self._roles), dict(self.app.views)))
        self._refresh = _Throttled(self._refresh_panels, 0.25)
        self.gate = CourseGate(self.room, app.course, own_model=self._own_model)  # paced pages, own workbench
        serve_page_under(app.server, INSTRUCTOR_PREFIX)
        # Whatever logs a request path (websockets, viser, a handler added later to the root) shortens the token.
        self._log_filter = self.room.log_filter()
        self._log_handlers = _filter_logs(self._log_filter)
        self._unsubscribe = self.room.subscribe(self._on_event)
        app.classroom = self

    def _copy(self, tabs: dict[int, _T]) -> dict[int, _T]:
        """A copy of one of the tab registries, taken under the lock (routing threads change them)."""
        with self._lock:
            return dict(tabs)

    # -- the app's hooks ------------------------------------------------------------------------------

    def open(self, client: viser.ClientHandle) -> bool:
        """A new tab: the instructor's (a workbench with the instructor's panel on top), a student's (their
        name first), or a refused one. True: this host showed the tab."""
        cid = client.client_id
        shake = handshake_of(self.app.server, cid)
        candidate = token_from_path(shake.path) if shake is not None else None
        with self._lock:
            self._clients[cid] = client
            self._tab_locks[cid] = threading.RLock()
        if candidate is not None:
            if self.room.check_token(candidate, shake.peer if shake is not None else ""):
                with self._lock:
                    self._roles[cid] = "instructor"
                self.room.instructor_join(cid)
                on_event(client.camera.on_update, self.cameras.instructor_moved, lambda exc: notify_error(client, exc))
                self._open_instructor(client)
                return True
            with self._lock:
                self._roles[cid] = "refused"
            client.gui.add_html(_REFUSED_PAGE)
            return True
        with self._lock:
            self._roles[cid] = "joining"
        name = stored_name(client, NAME_KEY, NAME_TIMEOUT)
        if name:
            try:
                self.join(client, name)
                return True
            except Exception:  # noqa: BLE001 - a name the class refuses now: ask again
                pass
        JoinPage(client, lambda typed: self.join(client, typed), lambda exc: notify_refusal(client, exc),
                 present=bool(getattr(self.app, "present", False)))
        return True

    def _open_instructor(self, client: viser.ClientHandle) -> None:
        """The instructor's workbench (the course one click away), on the room's scene if the class has one: an
        instructor who reconnects carries on where the room is."""
        shared = self.room.shared().scene  # read first: the new workbench, drawn, would publish its own scene
        opener = self.app.course.open_workbench if self.app.course is not None else self.app.show_workbench
        opener(client, SceneModel(shared) if shared is not None else None)

    def cleared(self, client: viser.ClientHandle) -> None:
        """The app emptied the tab: put the instructor's panel or the student's bar back on top."""
        cid = client.client_id
        with self._lock:
            role = self._roles.get(cid)
            self._fresh.add(cid)
        self.snapshots.forget(cid)
        if role == "instructor":
            self._build_panel(client)
        elif role == "student":
            self._build_bar(client)
        self.snapshots.show_in(client)

    def built(self, client: viser.ClientHandle, view: ClientView) -> None:
        """The app built a workbench in the tab: the instructor's feeds the room, a student's keeps their scene."""
        cid = client.client_id
        with self._lock:
            role = self._roles.get(cid)
            fresh = cid in self._fresh
            self._fresh.discard(cid)
        if role == "instructor":
            view.on_rendered = self._instructor_rendered
            if not fresh:
                self._build_panel(client)
                self.snapshots.show_in(client)
            self._instructor_rendered(view)
        elif role == "student":
            view.on_rendered = self._student_rendered
            if not fresh:
                self._build_bar(client)
                self.snapshots.show_in(client)
            self._student_rendered(view)

    def forget(self, client_id: int) -> None:
        """The tab left: the class keeps the student's scene and progress."""
        with self._lock:
            role = self._roles.pop(client_id, None)
            self._clients.pop(client_id, None)
            self._fresh.discard(client_id)
            follower = self.followers.pop(client_id, None)
            self.bars.pop(client_id, None)
            self.panels.pop(client_id, None)
            self.snapshots.forget(client_id)
            self._tab_locks.pop(client_id, None)
        if follower is not None:
            follower.close()
        if role == "instructor":
            self.room.instructor_leave(client_id)
        elif role == "student":
            self.room.leave(client_id)

    # -- students ---------------------------------------------------------------------------------------

    def join(self, client: viser.ClientHandle, name: object) -> None:
        """The student on ``client`` joins the class as ``name`` (refused names raise, and the tab says why)."""
        typed = typed_name(name)  # refused before the tab is taken for a student's
        cid = client.client_id
        with self._lock:
            if self._roles.get(cid) not in ("joining", "student"):
                return
            self._roles[cid] = "student"
        try:
            StudentController(self.room, cid).join(typed)  # FollowChanged routes the tab
        except Exception:
            with self._lock:
                self._roles[cid] = "joining"
            raise
        try:
            client.local_storage.set_item(NAME_KEY, typed)
        except Exception:  # noqa: BLE001 - storage refused: the student types their name again next time
            pass

    def _route(self, cid: int) -> None:
        """Show the student's tab as the class says: the room's scene, their own, or the lesson's tasks."""
        with self._lock:
            client = self._clients.get(cid)
            lock = self._tab_locks.get(cid)
        if client is None or lock is None:
            return
        with lock:
            try:
                if self.room.is_following(cid):
                    self._show_following(client)
                else:
                    self._show_own(client)
            except Exception as exc:  # noqa: BLE001 - a tab that cannot be shown says why; the others carry on
                notify_error(client, exc)

    def _show_following(self, client: viser.ClientHandle) -> None:
        cid = client.client_id
        with self._lock:
            if cid in self.followers or cid not in self._clients:
                return
        own = self.app.views.get(cid)
        window = own.window if own is not None else None
        self.app.clear_tab(client)
        view = FollowView(client, self.sender.latest, present=bool(getattr(self.app, "present", False)),
                          window=window)
        with self._lock:
            if cid not in self._clients:
                view.close()
                return
            self.followers[cid] = view
        # A frame the sender posted while the view was being built went to the followers it knew then, not to
        # this one: show the newest now (a frame no newer than the one shown is ignored).
        latest = self.sender.latest
        if latest is not None:
            view.show(latest)
        self._sync_bar(cid)
        on_event(client.camera.on_update, lambda cam: self.cameras.follower_moved(cid),
                 lambda exc: notify_error(client, exc))
        self.cameras.hold(view)

    def _show_own(self, client: viser.ClientHandle) -> None:
        cid = client.client_id
        with self._lock:
            follower = self.followers.pop(cid, None)
        name = self.room.name_of(cid)
        if name is None:
            return
        shared = self.room.shared()
        tasks = (self.room.mode is Mode.TASKS and self.app.course is not None and shared.lesson is not None
                 and self.room.may_open(shared.lesson, shared.step or 0))
        view = self.app.views.get(cid)
        if follower is None and view is not None and (self._lesson_run(cid, view) is not None) == tasks:
            self._sync_bar(cid)
            self.cameras.released(view, shown=False)
            return  # already where the class wants them: their scene, or the lesson's tasks
        if follower is not None:
            follower.close()
            self.app.remember_window(cid, (follower.window, follower.pixel_ratio))
        if tasks:
            assert shared.lesson is not None and self.app.course is not None
            panel = self.app.course.open_lesson(client, shared.lesson, name)
            if panel is not None:
                panel.may_enter = self.room.may_open
                if shared.step is not None and panel.run.step_index != shared.step:
                    panel.go_to(shared.step)
        else:
            self.app.show_workbench(client, self._own_model(name))
        self._sync_bar(cid)
        self.cameras.released(self.app.views.get(cid), shown=True)  # its cameras locked with the class's

    def _own_model(self, name: str) -> SceneModel:
        """The student's own scene: kept in this process, else the class's copy, else the room's scene."""
        with self._lock:
            model = self._models.get(name)
        if model is None:
            scene = self.room.own_scene(name) or self.room.shared().scene or self.app.initial_scene
            model = SceneModel(scene)
            with self._lock:
                model = self._models.setdefault(name, model)
        return model

    def _student_rendered(self, view: ClientView) -> None:
        """A student's own view drew: keep their scene for a reconnect, and tell the roster where they are."""
        cid = view.client.client_id
        name = self.room.name_of(cid)
        if name is None:
            return
        run = self._lesson_run(cid, view)
        if run is not None:  # a lesson's scene is the lesson's: their own scene stays as they left it
            self.room.report_step(cid, run.lesson.name, run.step_index)
        else:
            self.room.keep_scene(name, self.cameras.scenes.without_class_locks(view.model, view.model.scene))
            self.room.report_step(cid, None, None)

    def _build_bar(self, client: viser.ClientHandle) -> None:
        cid = client.client_id
        bar = StudentBar(client, StudentController(self.room, cid), report=lambda exc: notify_refusal(client, exc))
        with self._lock:
            self.bars[cid] = bar
        state = bar.student.state()
        bar.show(state)
        bar.set_paused(state.paused)

    def _sync_bar(self, cid: int) -> None:
        bar = self.bars.get(cid)
        if bar is not None:
            bar.show(bar.student.state())

    # -- the instructor ---------------------------------------------------------------------------------

    def _build_panel(self, client: viser.ClientHandle) -> None:
        panel = InstructorPanel(client, self, lambda exc: notify_refusal(client, exc))
        with self._lock:
            self.panels[client.client_id] = panel

    def _instructor_rendered(self, view: ClientView) -> None:
        """The instructor's tab drew an update: while students follow, it is the room's new frame."""
        if self.room.mode is not Mode.FOLLOW:
            return
        run = self._lesson_run(view.client.client_id, view)
        lesson, step = (run.lesson.name, run.step_index) if run is not None else (None, None)
        self._publishing.on = True
        try:
            version = self.room.publish(view.model.scene, lesson=lesson, step=step)
        finally:
            self._publishing.on = False
        self.sender.post(frame_of(view, version, self.sender.next_number(), step_caption(run)))

    def _lesson_run(self, cid: int, view: ClientView) -> LessonRun | None:
        """The lesson run the tab's view shows (None: the workbench)."""
        tab = self.app.course.tabs.get(cid) if self.app.course is not None else None
        run = getattr(tab, "run", None)
        return run if run is not None and getattr(run, "model", None) is view.model else None

    def publish(self, client: viser.ClientHandle) -> None:
        """The room follows the instructor's tab on ``client`` now: its scene becomes the room's."""
        view = self.app.views.get(client.client_id)
        if view is not None:
            with view.lock:
                self._instructor_rendered(view)

    def lesson_steps(self) -> dict[str, int]:
        """The course's lessons, in its order, and how many steps each has (``{}``: no course)."""
        return lesson_steps(self.app.course.lessons if self.app.course is not None else None)

    def student_tabs(self) -> dict[str, int]:
        """Connected students' names and one tab of each (the snapshot's choices)."""
        with self._lock:
            cids = [cid for cid, role in self._roles.items() if role == "student"]
        out: dict[str, int] = {}
        for cid in cids:
            name = self.room.name_of(cid)
            if name is not None:
                out.setdefault(name, cid)
        return out

    # -- the classroom's events --------------------------------------------------------------------------

    def _on_event(self, event: Event) -> None:
        if isinstance(event, FollowChanged):
            self._routes.submit(self._route, event.tab)
        elif isinstance(event, ModeChanged):
            if event.mode is not Mode.FOLLOW:
                self.sender.clear_pending()
            # Released students move too (explore <-> tasks): no FollowChanged tells them.
            with self._lock:
                students = [cid for cid, role in self._roles.items() if role == "student"]
            for cid in students:
                self._routes.submit(self._route, cid)
        elif isinstance(event, PauseChanged):
            for bar in self._copy(self.bars).values():
                bar.set_paused(event.message)
        elif isinstance(event, CamerasLocked):  # on every server process, as it adopts the class's state
            self._routes.submit(self.cameras.class_changed)  # many scenes redrawn: not on the sender's thread
        elif isinstance(event, SnapshotShown):
            self._snapshot_changed()
        elif isinstance(event, SharedChanged):
            self._shared_changed(event.version)
        elif isinstance(event, QuestionAsked):
            for cid in self._copy(self.bars):
                self._sync_bar(cid)
        if isinstance(event, (RosterChanged, AnswersChanged, ModeChanged, PauseChanged, PacingChanged,
                              CamerasLocked, SharedChanged, QuestionAsked, NamesShown)):
            self._refresh.mark()

    def _shared_changed(self, version: int) -> None:
        """A scene published by an instructor on another server process (the class's state was adopted): unless
        that instructor's own frame of it arrives within :data:`SHARED_GRACE_S` (a relay of frames between
        processes), draw it here, once, for this process's followers only."""
        if getattr(self._publishing, "on", False):
            return  # this process's instructor tab: it sends its own frames
        timer = threading.Timer(SHARED_GRACE_S, self._draw_shared, args=(version,))
        timer.daemon = True
        timer.start()

    def _draw_shared(self, version: int) -> None:
        sender = self._own_sender  # never a relay: a frame drawn here is this process's
        latest, shared = sender.latest, self.room.shared()
        if shared.scene is None or shared.version != version or (latest is not None and latest.version >= version):
            return
        present = bool(getattr(self.app, "present", False))
        sender.post(frame_from_scene(shared.scene, version, sender.next_number(), present=present))

    def _refresh_panels(self) -> None:
        for panel in self._copy(self.panels).values():
            try:
                panel.refresh()
            except Exception as exc:  # noqa: BLE001 - shown in that tab; the other panels still refresh
                notify_error(panel.client, exc)

    def _snapshot_changed(self) -> None:
        self.snapshots.set(self.room.shown_snapshot(), present=bool(getattr(self.app, "present", False)))
        with self._lock:
            clients = [self._clients[cid] for cid, role in self._roles.items()
                       if role in ("instructor", "student") and cid in self._clients]
        for client in clients:
            self.snapshots.show_in(client)

    def close(self) -> None:
        """Stop the sender and the routing threads (the server is stopping)."""
        self._unsubscribe()
        self.gate.close()
        for handler in self._log_handlers:
            handler.removeFilter(self._log_filter)
        self.sender.close()
        self._refresh.close()
        self._routes.shutdown(wait=False, cancel_futures=True)


def _filter_logs(log_filter: logging.Filter) -> list[logging.Handler]:
    """Add ``log_filter`` to the root logger's handlers and to logging's last resort; returns them (to take it off
    again)."""
    handlers = [h for h in (*logging.getLogger().handlers, logging.lastResort) if h is not None]
    for handler in handlers:
        handler.addFilter(log_filter)
    return handlers


class _Throttled:
    """Runs ``action`` at most once per ``interval`` seconds after :meth:`mark` (on a timer thread)."""

    def __init__(self, action: Callable[[], None], interval: float) -> None:
        self._action = action
        self._interval = interval
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._closed = False

    def mark(self) -> None:
        with self._lock:
            if self._timer is not None or self._closed:
                return
            self._timer = threading.Timer(self._interval, self._run)
            self._timer.daemon = True
            self._timer.start()

    def now(self) -> None:
        self._run()

    def _run(self) -> None:
        with self._lock:
            self._timer = None
            if self._closed:
                return
        self._action()

    def close(self) -> None:
        with self._lock:
            self._closed = True
            if self._timer is not None:
                self._timer.cancel()
