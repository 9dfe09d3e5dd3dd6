"""The class's camera lock on released students' own scenes: while the class locks cameras, every camera of each
watched :class:`~egtviz.scene.SceneModel` is locked by the model itself, so no route (a gizmo drag, a camera field,
a raw message) can move it; when the class unlocks, only the locks the class added go (a lesson step's stay).

The class's locks are kept out of the learner's undo history (undo cannot lift them); a camera that comes back
unlocked (undo, a loaded scene, a new camera) is locked again, just after the change is drawn.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from typing import Any

from ...scene import Scene, SceneModel

__all__ = ["LOCKED_TITLE", "SceneLocks"]

#: What a released student's tab is told when the class locks (or has locked) the cameras.
LOCKED_TITLE = "The instructor has locked the cameras"


class _Held:
    """One watched model: the camera names the class locked in it (its listener is not kept here: the
    unsubscribe function holds the model, which would then never leave the weak registry)."""

    def __init__(self) -> None:
        self.added: set[str] = set()


class SceneLocks:
    """Locks every camera of the watched models while ``locked()`` says the class locks cameras.

    Args:
        locked: whether the class locks cameras now.
    """

    def __init__(self, locked: Callable[[], bool]) -> None:
        self._locked = locked
        self._lock = threading.RLock()
        self._held: weakref.WeakKeyDictionary[SceneModel, _Held] = weakref.WeakKeyDictionary()

    def watch(self, model: SceneModel) -> None:
        """Keep ``model``'s cameras locked while the class locks them (from now on, and now if it does)."""
        with self._lock:
            new = model not in self._held
            if new:
                self._held[model] = _Held()
        if new:
            ref = weakref.ref(model)
            model.subscribe(lambda scene, change: self._changed(ref, scene))
        if self._locked():
            self._apply(model)

    def set_locked(self, locked: bool) -> None:
        """The class locked (True) or unlocked the cameras: lock, or release, every watched model's."""
        with self._lock:
            models = list(self._held.keys())
        failed: Exception | None = None
        for model in models:
            try:
                self._apply(model) if locked else self._release(model)
            except Exception as exc:  # noqa: BLE001 - the other scenes are still locked (or released)
                failed = failed or exc
        if failed is not None:
            raise failed

    def class_locks(self, model: SceneModel) -> frozenset[str]:
        """The camera names the class locked in ``model`` (none while the class does not lock)."""
        with self._lock:
            held = self._held.get(model)
            return frozenset(held.added) if held is not None else frozenset()

    def without_class_locks(self, model: SceneModel, scene: Scene) -> Scene:
        """``scene`` (``model``'s) without the class's locks: the scene the student keeps for a reconnect."""
        added = self.class_locks(model) & scene.locked
        return scene.replace(locked=scene.locked - added) if added else scene

    # The model is changed outside this registry's lock: its listeners (a view drawing under its own lock) may
    # read the registry meanwhile.
    def _apply(self, model: SceneModel, *, forget: bool = True) -> None:
        with self._lock:
            held = self._held.get(model)
            if held is None:
                return
            held.added &= set(model.scene.camera_names)  # a camera removed since: its lock went with it
        for name in model.scene.camera_names:
            if name not in model.scene.locked:
                with self._lock:
                    held.added.add(name)  # first: a reader never keeps a class lock as the student's
                model.lock(name, True, undoable=False)
        if forget:
            model.forget_undo()  # undo swaps whole scenes: it must not put a camera back where it was before the lock

    def _release(self, model: SceneModel) -> None:
        with self._lock:
            held = self._held.get(model)
            if held is None:
                return
            names = sorted(held.added)
        barrier = model.barrier_scene  # a lesson step's start: its locks are the step's, not the class's
        keep = barrier.locked if barrier is not None else frozenset()
        for name in names:
            if name in model.scene.locked and name not in keep:
                model.lock(name, False, undoable=False)
            with self._lock:
                held.added.discard(name)

    def _changed(self, ref: weakref.ref[SceneModel], scene: Scene) -> None:
        """A watched model changed: a camera now unlocked while the class locks them is locked again, on another
        thread (a commit inside a listener would reach the other listeners before this change does)."""
        if not self._locked() or all(name in scene.locked for name in scene.camera_names):
            return
        model = ref()
        if model is None:
            return
        threading.Thread(target=self._relock, args=(model,), daemon=True, name="egtviz-class-relock").start()

    def _relock(self, model: SceneModel) -> None:
        try:
            if self._locked():
                self._apply(model, forget=False)  # a camera added or loaded since the lock: the history stays
        except Exception:  # noqa: BLE001 - a scene the model refuses to lock now: the next change tries again
            pass
