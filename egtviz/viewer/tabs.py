"""The viewer's tab router, the top floor of :mod:`egtviz.viewer`: what each connecting browser tab shows.

:class:`EgtvizApp` gives each tab its own scene and shows it the workbench
(:class:`~egtviz.viewer.workbench.app.ClientView` over a
:class:`~egtviz.controllers.workbench.WorkbenchController`), the course's start page and lessons
(:mod:`egtviz.viewer.course`), or a visual-servoing demo (:mod:`egtviz.viewer.servo`); a class taught on the
server (:mod:`egtviz.viewer.classroom`) is asked first. It imports the floors below it; none of them imports it.
"""

from __future__ import annotations

import atexit
import gc
import threading
import time
import traceback
from typing import Any

import viser

from ..lessons import ProgressStore
from ..scene import Scene, SceneError, SceneModel, compute_derived, default_scene
from ..scene.extent import scene_extent
from .course.start_page import Course
from .render.panels import DEFAULT_WINDOW, WindowSize, framed_camera, plan_grid
from .render.svg import NORMAL, PRESENT
from .render.svg import warm_up as svg_warm_up
from .servo.servo_demo import make_servo_demo
from .servo.servo_player import ServoPlayer
from .workbench.app import FIELD_DELAY, ClientView
from .workbench.fields import Debouncer, describe_error, notify_error

__all__ = ["EgtvizApp"]


class EgtvizApp:
    """The egtviz viewer on a viser server: each connecting browser tab gets its own scene.

    Args:
        server: the viser server to serve on.
        scene: the scene every new tab starts from (default: :func:`default_scene`).
        demo: open this servo demo (``"pinhole"`` or ``"panoramic"``) in every new tab instead of the workbench.
        field_delay: seconds a text field must stay unchanged before it is judged (tests use 0: at once).
        present: every new tab starts in presentation mode (``egtviz --present``).
        course: every new tab starts on the course's start page (:mod:`egtviz.viewer.course.start_page`): the lessons,
            the learner's name, and the workbench one click away.
        lesson: every new tab opens this lesson (``egtviz lesson NAME``), with the course one click away.
        progress: where learners' progress is kept (a :class:`~egtviz.lessons.ProgressStore`; default: the
            user's data folder).

    A tab whose workbench cannot be built on ``scene`` (it cannot be drawn) gets
    the default scene and a notification saying why; a tab is never left half-built.
    """

    def __init__(self, server: viser.ViserServer, scene: Scene | None = None, *, demo: str | None = None,
                 field_delay: float = FIELD_DELAY, present: bool = False, course: bool = False,
                 lesson: str | None = None, progress: ProgressStore | None = None) -> None:
        if demo not in (None, "pinhole", "panoramic"):
            raise ValueError(f"demo: expected None, 'pinhole' or 'panoramic', got {demo!r}")
        Debouncer(field_delay)  # checks the value now rather than in every tab
        self.field_delay = field_delay
        self.server = server
        self.initial_scene = scene if scene is not None else default_scene()
        #: Open this servo demo in every new tab instead of the workbench.
        self.demo = demo
        #: New tabs start in presentation mode.
        self.present = bool(present)
        self.views: dict[int, ClientView] = {}
        #: The servo demo shown in a tab (``egtviz.viewer.servo.servo_demo.ServoDemo``), by client id.
        self.demos: dict[int, ServoPlayer] = {}
        self._models: dict[int, SceneModel] = {}
        #: Each tab's window as its last workbench estimated it (a servo demo narrows the canvas it reports).
        self._windows: dict[int, tuple[WindowSize, float]] = {}
        self._lock = threading.Lock()
        self._gone: set[int] = set()
        #: The course (start page, lessons) that new tabs open in; None: the workbench or ``demo``.
        self.course: Course | None = None
        #: A class being taught (:class:`egtviz.viewer.classroom.ClassroomHost`): it is asked first what a new tab
        #: shows, told when a tab leaves or is cleared; None: no class.
        # Untyped, not a protocol: the server's command line hands it on as a ClassroomHost, and naming that class here
        # would close a circle of imports (the host names this module).
        self.classroom: Any = None
        if course or lesson is not None:
            self.course = Course(self, lesson=lesson, progress=progress)  # LessonError: no such lesson
        self._frame_view(self.initial_scene)
        svg_warm_up()
        # The long-lived objects (numpy, scipy, trimesh, viser, the scene) are never garbage: a full
        # collection walking them all would stall a drag update for tens of milliseconds.
        gc.collect()
        gc.freeze()
        atexit.register(gc.unfreeze)  # let the interpreter's last collection reach them at exit
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)

    def _frame_view(self, scene: Scene) -> None:
        """Start the browser's view camera on every camera and point, in the canvas a common window leaves free.

        Each tab then frames its own view for its window
        (:meth:`~egtviz.viewer.workbench.panel_dock.PanelDock.frame_camera`).
        """
        extent = scene_extent(scene, compute_derived(scene))
        grid = plan_grid([(c.name, float(c.width), float(c.height)) for c in scene.cameras], DEFAULT_WINDOW,
                         style=PRESENT if self.present else NORMAL)
        framed = framed_camera(extent.points, max(grid.canvas_px, 120.0) / DEFAULT_WINDOW.height, pad=extent.glyph,
                               min_radius=3.0 * extent.glyph)
        cam = self.server.initial_camera
        cam.look_at = framed.look_at
        cam.position = framed.position
        cam.up = (0.0, 0.0, 1.0)
        cam.fov = framed.fov

    def show_scene(self, scene: Scene) -> None:
        """Show ``scene`` in every open workbench tab and start new tabs on it (the EGT figure front-end).

        Each tab loads it as a new scene (undoable); new tabs' view camera is framed on it.
        """
        if not isinstance(scene, Scene):
            raise SceneError(f"scene: expected a Scene, got {type(scene).__name__}")
        self.initial_scene = scene
        self._frame_view(scene)
        with self._lock:
            views = list(self.views.values())
        for view in views:
            view.model.load_scene(scene)

    def _connect(self, client: viser.ClientHandle) -> None:
        if self.classroom is not None and self.classroom.open(client):
            return
        if self.course is not None:
            self.course.open(client)
            return
        if self.demo is not None:
            self.open_demo(client, self.demo)
            return
        view = self._build_view(client, None)
        with self._lock:
            if client.client_id in self._gone:  # it left while we were building its view
                self._gone.discard(client.client_id)
                view.close()
                return
            self.views[client.client_id] = view

    def _build_view(self, client: viser.ClientHandle, model: SceneModel | None) -> ClientView:
        """The tab's workbench on ``model`` (None: a new model of the initial scene).

        If that fails (a scene that cannot be drawn), the tab is cleared and
        gets the default scene, with a notification giving the reason.
        """
        def open_demo(kind: str, /, **options: object) -> ServoPlayer | None:
            return self.open_demo(client, kind, **options)

        window = self._windows.get(client.client_id)
        try:
            view = ClientView(client, model or SceneModel(self.initial_scene), open_demo=open_demo,
                              field_delay=self.field_delay, present=self.present, window=window)
        except Exception as exc:  # noqa: BLE001 - the tab must come up whatever the scene holds
            title, body = describe_error(exc)
            if title == "Something went wrong":

                traceback.print_exception(exc)
            client.gui.reset()
            client.scene.reset()
            view = ClientView(client, SceneModel(default_scene()), open_demo=open_demo, field_delay=self.field_delay,
                              present=self.present, window=window)
            client.add_notification("Showing the default scene instead",
                                    f"The scene could not be drawn: {body}", color="red", auto_close_seconds=None)
        if self.classroom is not None:
            self.classroom.built(client, view)
        return view

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            view = self.views.pop(client.client_id, None)
            demo = self.demos.pop(client.client_id, None)
            self._models.pop(client.client_id, None)
            self._windows.pop(client.client_id, None)
            if view is None and demo is None:
                self._gone.add(client.client_id)
        if view is not None:
            view.close()
        if demo is not None:
            demo.close(client_gone=True)
        if self.course is not None:
            self.course.forget(client.client_id)
        if self.classroom is not None:
            self.classroom.forget(client.client_id)

    # -- visual-servoing demos (egtviz.viewer.servo.servo_demo) ---------------------------------

    def open_demo(self, client: viser.ClientHandle, kind: str, **options: object) -> ServoPlayer | None:
        """Replace the tab's workbench by a servo demo (its scene is kept for the way back); ``options``: the
        demo's run fields (``seed``, ``beta``, ...: ``make_servo_demo``)."""

        cid = client.client_id
        with self._lock:
            view = self.views.pop(cid, None)
            old = self.demos.pop(cid, None)
        if view is not None:
            view.close()
            self._models[cid] = view.model
            self._windows[cid] = view.window
        if old is not None:
            old.close()
        client.gui.reset()
        client.scene.reset()
        present = view.present if view is not None else self.present  # the tab's own choice, if it made one
        try:
            demo = make_servo_demo(client, kind, on_back=lambda: self.close_demo(client),
                                   field_delay=self.field_delay, present=present, **options)
        except Exception as exc:  # noqa: BLE001 - back to a working workbench, with the reason

            traceback.print_exception(exc)
            self.close_demo(client)
            notify_error(client, exc, title="Could not open the demo")
            return None
        with self._lock:
            if cid in self._gone:
                self._gone.discard(cid)
                demo.close()
                return None
            self.demos[cid] = demo
        return demo

    def close_demo(self, client: viser.ClientHandle) -> ClientView | None:
        """Close the tab's servo demo and bring its workbench back."""
        cid = client.client_id
        with self._lock:
            demo = self.demos.pop(cid, None)
            model = self._models.pop(cid, None)
        if demo is not None:
            demo.close()
        client.gui.reset()
        client.scene.reset()
        view = self._build_view(client, model)
        with self._lock:
            if cid in self._gone:
                self._gone.discard(cid)
                view.close()
                return None
            self.views[cid] = view
        if self.course is not None:  # the lesson (or the way back to the course) the tab had before the demo
            self.course.restore(client, view)
        return view

    def show_workbench(self, client: viser.ClientHandle, model: SceneModel | None = None) -> ClientView | None:
        """Replace what the tab shows by a workbench on ``model`` (None: a new model of the initial scene).

        Returns the tab's view, or None if the tab left meanwhile.
        """
        self.clear_tab(client)
        view = self._build_view(client, model)
        with self._lock:
            if client.client_id in self._gone:
                self._gone.discard(client.client_id)
                view.close()
                return None
            self.views[client.client_id] = view
        return view

    def remember_window(self, client_id: int, window: tuple[WindowSize, float]) -> None:
        """The tab's window (CSS pixels, device pixels per CSS pixel) as a view it showed measured it: the tab's
        next workbench lays its panels out for it (the canvas it reports meanwhile is narrowed by what is docked)."""
        with self._lock:
            self._windows[client_id] = window

    def clear_tab(self, client: viser.ClientHandle) -> None:
        """Close the tab's workbench or servo demo and empty its GUI and 3D scene."""
        cid = client.client_id
        with self._lock:
            view = self.views.pop(cid, None)
            demo = self.demos.pop(cid, None)
        if view is not None:
            view.close()
        if demo is not None:
            demo.close()
        client.gui.reset()
        client.scene.reset()
        if self.classroom is not None:
            self.classroom.cleared(client)

    def wait_for_view(self, timeout: float = 10.0, count: int = 1) -> list[ClientView]:
        """Block until at least ``count`` tabs are connected (tests, benchmark)."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self._lock:
                if len(self.views) >= count:
                    return list(self.views.values())
            time.sleep(0.02)
        raise TimeoutError(f"fewer than {count} viewer tabs connected after {timeout} s")

    def wait_for_demo(self, timeout: float = 10.0, count: int = 1) -> list[ServoPlayer]:
        """Block until at least ``count`` tabs show a servo demo (tests)."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self._lock:
                if len(self.demos) >= count:
                    return list(self.demos.values())
            time.sleep(0.02)
        raise TimeoutError(f"fewer than {count} servo demos open after {timeout} s")
