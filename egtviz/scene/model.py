"""``SceneModel``: the one mutable holder of a scene, with validation, undo and change notifications.

The viewer, the lessons and the CLI all change a scene through this small API;
each call validates, draws the new scene once (:func:`compute_derived`: compute,
then commit, so an undrawable scene is never committed), replaces the immutable
:class:`Scene` and its :class:`Derived`, and notifies the subscribers once (or
once per :meth:`SceneModel.batch`).
"""

from __future__ import annotations

import dataclasses
import math
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import GeometryError, PinholeCamera
from ..geometry.camera_model import CAMERA_MODELS
from ..geometry.poses import Pose
from .constraints import CameraRanges
from .derived import Derived, compute_derived
from .limits import COORDINATE, MAX_POINTS, Range
from .scene import Scene, SceneFileError
from .cameras import CAMERA_KINDS, spec_for_model
from .cameras.catadioptric import PanoramicSpec
from .cameras.pinhole import PinholeSpec
from .specs import DisplayOptions, SceneError, SurfaceSpec
from ._values import as_ranged as _ranged, as_triple as _triple, short_text as _short
from .surfaces import check_surface

UNDO_DEPTH = 100
def _push_undo(undo: list[Scene], scene: Scene) -> None:
    """Remember ``scene`` for undo, keeping the last ``UNDO_DEPTH``."""
    undo.append(scene)
    del undo[:-UNDO_DEPTH]


_POINT_COUNT = Range(0, MAX_POINTS, "", integer=True)
_EXTENT = Range(0.0, COORDINATE.high, "m")


def _without_point(marks: frozenset[str], index: int) -> frozenset[str]:
    """``marks`` after point ``index`` is removed: its mark goes, later indices shift down by one."""
    out = set()
    for m in marks:
        if m.startswith("point:"):
            i = int(m[6:])
            if i == index:
                continue
            if i > index:
                m = f"point:{i - 1}"
        out.add(m)
    return frozenset(out)


def _lock_refusal(old: Scene, new: Scene, change: Change) -> str | None:
    """Why ``new`` breaks a lock of ``old``: a locked camera placed elsewhere or a locked point moved (None: it
    does not). A lock holds a camera's position and orientation (what its gizmo moves), not its other fields."""
    for name in change.names:
        if name not in old.locked:
            continue
        if name.startswith("point:"):
            i = int(name[6:])
            if i < len(old.points) and i < len(new.points) and old.points[i] != new.points[i]:
                return f"point {i + 1} is locked in this step: it cannot move"
        elif name in old.camera_names:
            a = old.camera(name)
            b = new.camera(name) if name in new.camera_names else None
            if b is not None and b is not a and any(getattr(a, f) != getattr(b, f) for f in a.POSE_FIELDS):
                return f"{name}: the camera is locked in this step; its position and orientation cannot change"
    return None


def _new_camera(scene: Scene, kind: Any, name: str | None, fields: dict[str, Any]) -> Any:
    """The spec of a new camera of ``kind`` in ``scene`` (:meth:`SceneModel.add_camera`)."""
    spec_cls: Any  # a concrete spec class (the base declares no fields)
    if type(kind) is str and kind in CAMERA_MODELS:
        spec_cls, selection = spec_for_model(kind)
    elif type(kind) is str and kind in CAMERA_KINDS:
        spec_cls, selection = CAMERA_KINDS[kind], {}
    else:
        raise SceneError(f"kind: expected one of {sorted(CAMERA_MODELS)}, got {_short(kind)}")
    if name is None:
        prefix = spec_cls.NAME_PREFIX
        i = 1
        while f"{prefix}{i}" in scene.camera_names:
            i += 1
        name = f"{prefix}{i}"
    if name in scene.camera_names:
        raise SceneError(f"name: a camera named {name!r} exists already")
    if not fields:
        k = len(scene.cameras)
        angle = -np.pi / 2 + 0.6 * (k + 1) * (-1) ** k
        fields = spec_cls.placement((8.0 * np.cos(angle), 8.0 * np.sin(angle)), (0.0, 0.0))
    return spec_cls(name=name, **{**selection, **fields})


@dataclass(frozen=True)
class Change:
    """What a notification is about: ``kind`` (e.g. ``"camera"``, ``"points"``, ``"load"``) and the names touched."""

    kind: str
    names: tuple[str, ...] = ()
    in_place: bool = False
    """The change edits the named cameras or points in place (a field, a gizmo, a raw message): a lock may refuse
    it. Adding, removing, loading and undoing are not edits in place."""


Listener = Callable[[Scene, Change], None]


class SceneModel:
    """Holds a :class:`Scene`; every mutation validates first and leaves the scene unchanged on error."""

    def __init__(self, scene: Scene | None = None) -> None:
        from .examples import default_scene

        self._initial = scene if scene is not None else default_scene()
        if not isinstance(self._initial, Scene):
            raise SceneError(f"scene: expected a Scene, got {_short(self._initial)}")
        self._scene = self._initial
        self._derived = compute_derived(self._initial)
        self._undo: list[Scene] = []
        self._listeners: list[Listener] = []
        self._lock = threading.RLock()
        self._batch_depth = 0
        self._batch_changes: list[Change] = []
        self._batch_start: Scene | None = None
        self._merge_key: object = None
        self._barrier: tuple[Scene, str] | None = None
        self._authority: tuple[int, int] | None = None  # (thread, depth) inside :meth:`lesson_step`
        self._ranges: CameraRanges | None = None

    # -- reading ---------------------------------------------------------------

    @property
    def scene(self) -> Scene:
        return self._scene

    @property
    def derived(self) -> Derived:
        """What the viewer draws for :attr:`scene`, computed when the scene was committed (read it, do not
        call ``compute_derived`` again). Read inside a listener, it belongs to the notified scene."""
        return self._derived

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(scene, change)`` after each change; returns the function that unsubscribes."""
        with self._lock:
            self._listeners.append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._listeners:
                    self._listeners.remove(listener)

        return unsubscribe

    # -- the core of every mutation ---------------------------------------------

    def _commit(self, new: Scene, change: Change, *, undoable: bool = True, merge_key: object = None) -> None:
        with self._lock:
            # Every edit of a camera or a point passes here, whatever sent it (a field, a gizmo, a raw message).
            if change.in_place and not self._has_authority():
                refusal = _lock_refusal(self._scene, new, change)
                if refusal is not None:
                    raise SceneError(refusal)
            if self._batch_depth:  # drawn once, when the batch ends
                self._scene = new
                self._batch_changes.append(change)
                return
            derived = compute_derived(new)  # SceneError: not drawable, nothing committed
            # Consecutive changes with the same merge key (one gizmo drag) make one undo step.
            if undoable and (merge_key is None or merge_key != self._merge_key):
                _push_undo(self._undo, self._scene)
            self._merge_key = merge_key if undoable else None
            self._scene = new
            self._derived = derived
            listeners = list(self._listeners)
        for listener in listeners:
            listener(new, change)

    def _has_authority(self) -> bool:
        """The calling thread applies a lesson step (:meth:`lesson_step`): locks and ranges do not hold."""
        return self._authority is not None and self._authority[0] == threading.get_ident()

    def set_constraints(self, ranges: CameraRanges | None) -> None:
        """Ranges of camera fields that every later edit in place must respect (None: none), whatever sent it; a
        lesson step's own changes are not judged (:mod:`egtviz.scene.constraints`)."""
        if ranges is not None and not isinstance(ranges, CameraRanges):
            raise SceneError(f"ranges: expected CameraRanges or None, got {_short(ranges)}")
        self._ranges = ranges

    def _replace(self, change: Change, merge_key: object = None, **fields: Any) -> None:
        try:
            new = self._scene.replace(**fields)
        except (GeometryError, TypeError) as exc:
            raise SceneError(str(exc)) from exc
        self._commit(new, change, merge_key=merge_key)

    @contextmanager
    def batch(self, kind: str = "batch", *, barrier: str | None = None) -> Iterator[None]:
        """Group changes: one undo step and one notification at the end; all or nothing on error. With ``barrier``
        the outermost batch ends at an undo barrier (:meth:`set_undo_barrier`), set before the listeners hear."""
        with self._lock:
            if self._batch_depth == 0:
                self._batch_start = self._scene
                self._batch_changes = []
            self._batch_depth += 1
        try:
            yield
        except BaseException:
            with self._lock:
                self._batch_depth -= 1
                if self._batch_depth == 0:
                    self._scene = self._batch_start  # type: ignore[assignment]
            raise
        with self._lock:
            self._batch_depth -= 1
            if self._batch_depth:
                return
            changes, start = self._batch_changes, self._batch_start
            if changes:
                try:
                    derived = compute_derived(self._scene)
                except SceneError:
                    self._scene = start  # type: ignore[assignment]
                    raise
                self._derived = derived
                _push_undo(self._undo, start)  # type: ignore[arg-type]
                self._merge_key = None
            if barrier is not None:
                self.set_undo_barrier(barrier)
            if not changes:
                return
            names = tuple(dict.fromkeys(n for c in changes for n in c.names))
            new = self._scene
            listeners = list(self._listeners)
        change = changes[0] if len(changes) == 1 else Change(kind, names)
        for listener in listeners:
            listener(new, change)

    @contextmanager
    def lesson_step(self, note: str) -> Iterator[None]:
        """Apply a lesson step's own changes: one :meth:`batch` in which locks do not hold (the lesson may move
        what it locked), then an undo barrier (``note``: what undo says there, :meth:`set_undo_barrier`).

        Only the calling thread has that authority; an edit from another thread meanwhile is judged as usual.
        """
        me = threading.get_ident()
        with self._lock:
            if self._authority is not None and self._authority[0] != me:
                raise SceneError("a lesson step is being applied to this scene already")
            depth = 0 if self._authority is None else self._authority[1]
            self._authority = (me, depth + 1)
        try:
            with self.batch("lesson", barrier=note):
                yield
        finally:
            with self._lock:
                self._authority = None if depth == 0 else (me, depth)

    # -- cameras ---------------------------------------------------------------

    def update_camera(self, name: str, /, *, merge_key: object = None, **fields: Any) -> None:
        """Change fields of a camera spec (e.g. ``focal_length=0.01``); ``name=`` renames it.

        A change that alters nothing is not committed (no undo step, no notification).
        """
        spec = self._scene.camera(name)
        drag = fields.keys() <= spec.POSE_FIELDS
        try:
            new_spec = spec.with_pose(**fields) if drag else spec.with_fields(**fields)
        except (TypeError, GeometryError) as exc:
            raise SceneError(f"camera {name!r}: {exc}") from exc
        self._place(spec, self._allowed(spec, new_spec, drag), merge_key)

    def set_camera_pose(self, name: str, position: Any, R_world: Any, *, drag_id: object = None,
                        unmoved: Callable[[Pose, Pose], bool] | None = None) -> bool:
        """Place a camera at a world pose (a gizmo drag) as the model's ranges allow it; returns whether it moved.

        The spec holds that pose (its fields show its angles). Calls with the same non-None ``drag_id`` (one drag)
        are one undo step. Nothing is committed when ``unmoved(current, allowed)`` (a gizmo resends its pose,
        rounded)."""
        spec = self._scene.camera(name)
        R = np.asarray(R_world, dtype=np.float64)
        if R.shape != (3, 3) or (not math.isfinite(R.sum()) and not np.isfinite(R).all()):
            raise SceneError("R_world: expected a finite 3x3 rotation")
        new_spec = spec.with_world_pose(_triple(position, "position"), R)  # GeometryError: not a rotation
        new_spec = self._allowed(spec, new_spec, True)
        if unmoved is not None and unmoved(spec.pose, new_spec.pose):
            return False
        return self._place(spec, new_spec, None if drag_id is None else ("camera", name, drag_id))

    def _allowed(self, spec: Any, new_spec: Any, drag: bool) -> Any:
        """``new_spec`` in place of ``spec`` as the model's ranges allow it (they do not bind a lesson step)."""
        ranges = None if self._has_authority() else self._ranges
        return new_spec if ranges is None else ranges.judge(spec, new_spec, drag=drag)

    def _place(self, spec: Any, new_spec: Any, merge_key: object) -> bool:
        """Commit ``new_spec``, already allowed, in place of ``spec`` (an edit in place); False: nothing changed."""
        scene, name = self._scene, spec.name
        if new_spec == spec:
            return False
        cameras = tuple(new_spec if c.name == name else c for c in scene.cameras)
        pair = scene.pair
        if new_spec.name == name:
            self._replace(Change("camera", (name,), in_place=True), merge_key, cameras=cameras, pair=pair)
            return True
        rename = {name: new_spec.name}
        self._replace(
            Change("camera", (name, new_spec.name), in_place=True), merge_key, cameras=cameras,
            pair=tuple(rename.get(n, n) for n in pair) if pair else pair,
            locked=frozenset(rename.get(m, m) for m in scene.locked),
            highlighted=frozenset(rename.get(m, m) for m in scene.highlighted),
        )
        return True

    def add_camera(self, kind: str = PinholeCamera.kind, name: str | None = None, **fields: Any) -> str:
        """Add a camera of a registered model ``kind`` (``egtviz.geometry.CAMERA_MODELS``, e.g. ``"unified"``; a
        scene file's kind, e.g. ``"panoramic"``, is read too); returns its name.

        Without ``fields`` the newcomer is placed where it sees the points, away from the others.
        """
        scene = self._scene
        spec = _new_camera(scene, kind, name, fields)
        self._replace(Change("add_camera", (spec.name,)), cameras=scene.cameras + (spec,))
        return spec.name

    def remove_camera(self, name: str) -> None:
        scene = self._scene
        scene.camera(name)
        cameras = tuple(c for c in scene.cameras if c.name != name)
        pair = scene.pair if scene.pair and name not in scene.pair else None
        self._replace(
            Change("remove_camera", (name,)),
            cameras=cameras,
            pair=pair,
            locked=scene.locked - {name},
            highlighted=scene.highlighted - {name},
        )

    def set_pair(self, name1: str, name2: str) -> None:
        """Choose the two cameras whose epipolar geometry is drawn."""
        self._replace(Change("pair", (name1, name2)), pair=(name1, name2))

    # -- points and surfaces -------------------------------------------------------

    def set_point(self, index: int, xyz: Any, *, drag_id: object = None) -> None:
        """Move point ``index``; successive calls with the same non-None ``drag_id`` are one undo step."""
        scene = self._scene
        points = scene.points
        if not 0 <= index < len(points):
            raise SceneError(f"index: no point {index} (have {len(points)})")
        p = _triple(xyz, f"point {index}")
        if p == points[index]:
            return
        merge = None if drag_id is None else ("point", index, drag_id)
        self._commit(scene.with_point(index, p), Change("points", (f"point:{index}",), in_place=True), merge_key=merge)

    def set_points(self, points: Any) -> None:
        """Replace all points at once ((N, 3) numbers, N at most ``MAX_POINTS``); point locks and highlights go."""
        if not isinstance(points, (np.ndarray, list, tuple)):
            raise SceneError(f"points: expected (N, 3) numbers, got {_short(points)}")
        if len(points) > MAX_POINTS:
            raise SceneError(f"points: at most {MAX_POINTS}, got {len(points)}")
        scene = self._scene
        self._replace(
            Change("points"), points=points, selected_point=None,
            locked=frozenset(m for m in scene.locked if not m.startswith("point:")),
            highlighted=frozenset(m for m in scene.highlighted if not m.startswith("point:")),
        )

    def add_point(self, xyz: Any) -> int:
        p = _triple(xyz, "point")
        self._replace(Change("add_point"), points=self._scene.points + (p,))
        return len(self._scene.points) - 1

    def remove_point(self, index: int) -> None:
        scene = self._scene
        if not 0 <= index < len(scene.points):
            raise SceneError(f"index: no point {index} (have {len(scene.points)})")
        points = scene.points[:index] + scene.points[index + 1 :]
        sel = scene.selected_point
        sel = None if sel == index else (sel - 1 if sel is not None and sel > index else sel)
        self._replace(
            Change("remove_point", (f"point:{index}",)), points=points, selected_point=sel,
            locked=_without_point(scene.locked, index), highlighted=_without_point(scene.highlighted, index),
        )

    def randomize_points(self, n: int = 8, seed: int | None = None, *, center=(0.0, 0.0, 1.0), extent: float = 2.0) -> None:
        """Replace the points with ``n`` uniform random points in a cube of side ``2 * extent``.

        ``n`` is a whole number in ``0..MAX_POINTS``; the cube must lie inside the coordinate limits.
        """
        count = int(_ranged(n, _POINT_COUNT, "n"))
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
            raise SceneError(f"seed: expected null or a whole number >= 0, got {_short(seed)}")
        c = _triple(center, "center")
        half = _ranged(extent, _EXTENT, "extent")
        rng = np.random.default_rng(seed)
        self.set_points(np.asarray(c) + rng.uniform(-half, half, size=(count, 3)))

    def add_surface(self, spec: SurfaceSpec) -> None:
        if not isinstance(spec, SurfaceSpec):
            raise SceneError(f"spec: expected a SurfaceSpec, got {type(spec).__name__}")
        check_surface(spec)  # a mesh surface's mesh: found in the assets, loaded, checked
        self._replace(Change("surfaces"), surfaces=self._scene.surfaces + (spec,))

    def remove_surface(self, index: int) -> None:
        s = self._scene.surfaces
        if not 0 <= index < len(s):
            raise SceneError(f"index: no surface {index} (have {len(s)})")
        self._replace(Change("surfaces"), surfaces=s[:index] + s[index + 1 :])

    # -- display, selection, lessons' controls -------------------------------------

    def select_point(self, index: int | None) -> None:
        self._replace(Change("selection"), selected_point=index)

    def set_option(self, name: str, value: bool) -> None:
        opts = self._scene.options
        if name not in {f.name for f in dataclasses.fields(DisplayOptions)}:
            raise SceneError(f"option: unknown display option {name!r}")
        if not isinstance(value, (bool, np.bool_)):
            raise SceneError(f"options: {name}: expected true or false, got {_short(value)}")
        self._replace(Change("options", (name,)), options=dataclasses.replace(opts, **{name: bool(value)}))

    def lock(self, name: str, locked: bool = True, *, undoable: bool = True) -> None:
        """Lock (or unlock) a gizmo: a camera name or ``"point:<i>"``. ``undoable=False``: a lock the learner's
        undo must not lift (the class's), kept out of the undo history."""
        if type(name) is not str:
            raise SceneError(f"locked: expected a camera name or 'point:<i>', got {_short(name)}")
        new = self._scene.locked | {name} if locked else self._scene.locked - {name}
        if undoable:
            self._replace(Change("lock", (name,)), locked=new)
            return
        self._commit(self._scene.replace(locked=new), Change("lock", (name,)), undoable=False)

    def highlight(self, names: Any) -> None:
        """Draw attention to these camera names and ``"point:<i>"`` (a list; replaces the previous ones)."""
        if isinstance(names, (str, bytes)) or not isinstance(names, (list, tuple, set, frozenset)):
            raise SceneError(f"highlighted: expected a list of names, got {_short(names)}")
        self._replace(Change("highlight", tuple(sorted(map(str, names)))), highlighted=names)

    # -- history and files -------------------------------------------------------

    def undo(self) -> bool:
        """Go back one change; False when there is nothing to undo (or only what an undo barrier holds)."""
        with self._lock:
            if not self._undo:
                return False
            previous = self._undo.pop()
        self._commit(previous, Change("undo"), undoable=False)
        return True

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    def forget_undo(self) -> None:
        """The changes made so far can no longer be undone; an undo barrier, if set, stays. A classroom's camera
        lock calls it, so that undo cannot put a locked camera back where the student had it before the lock."""
        with self._lock:
            self._undo.clear()
            self._merge_key = None

    def set_undo_barrier(self, note: str) -> None:
        """Undo stops here and :meth:`reset` comes back here: a lesson sets one as a step is entered, so the
        learner cannot undo its changes (a lock, a value it sets). ``note``: what undo says there."""
        if type(note) is not str or not note:
            raise SceneError(f"note: expected a sentence, got {_short(note)}")
        with self._lock:
            self._undo.clear()
            self._merge_key = None
            self._barrier = (self._scene, note)

    @property
    def undo_barrier_note(self) -> str | None:
        """What undo says when it stops at the barrier (None: no barrier is set)."""
        return None if self._barrier is None else self._barrier[1]

    @property
    def barrier_scene(self) -> Scene | None:
        """The scene at the undo barrier (a lesson step's start), or None."""
        return None if self._barrier is None else self._barrier[0]

    def reset(self, scene: Scene | None = None) -> None:
        """Back to ``scene``, else to the undo barrier's scene (a lesson step's start), else to the scene the model
        started with; undoable."""
        barrier = self._barrier
        target = scene if scene is not None else (barrier[0] if barrier is not None else self._initial)
        self._commit(target, Change("reset"))

    def load_scene(self, scene: Scene) -> None:
        """Replace the scene with ``scene`` (e.g. from :func:`egtviz.scene.scene_from_bytes`); undoable."""
        if not isinstance(scene, Scene):
            raise SceneError(f"scene: expected a Scene, got {_short(scene)}")
        self._commit(scene, Change("load"))

    def save(self, path: str | Path) -> None:
        """Write the scene file ``path`` (:func:`egtviz.scene.save_scene_file`; for scripts and the CLI)."""
        from .io import save_scene_file

        save_scene_file(self._scene, path)

    def load(self, path: str | Path) -> None:
        """Replace the scene with a file's (:func:`egtviz.scene.load_scene_file`); on error nothing changes."""
        from .io import load_scene_file

        self.load_scene(load_scene_file(path))


__all__ = [
    "Change",
    "PanoramicSpec",
    "PinholeSpec",
    "SceneError",
    "SceneFileError",
    "SceneModel",
]
