"""The one place where egtviz relies on viser's private handle internals (viser 1.1.1).

Assigning a node property through viser's public API (``handle.points = array``) casts the value, checks it against
the property's type hints and compares it with the old value before queueing the update: tens of microseconds per
property, on every drag step, for arrays this layer has just compared itself. :func:`assign_array` does what that
assignment does for a changed array of the node's own dtype, and nothing more; everything else goes the public way.

The benchmarks reach viser's server and gizmos through here too (:func:`event_loop`, :func:`callback_pool`,
:func:`gizmo_moved_by_client`): their private names are in :data:`SERVER_PRIVATE_NAMES` and
:data:`GIZMO_PRIVATE_NAMES`, checked by :func:`missing_server_internals` and :func:`missing_gizmo_internals`.

The private names used are listed in :data:`PRIVATE_NAMES` and checked by :func:`missing_internals`; the test
``tests/test_viser_adapter.py`` fails when the installed viser no longer has them or no longer sends what the public
assignment sends, so an upgrade of viser is noticed at once (then fall back to the public path: ``FAST_PATH = False``).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Mapping
from typing import Protocol, TypeVar

import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import viser

_props_setattr: Callable[[object, str, object], None] | None
try:  # what a handle's public assignment runs
    from viser._assignable_props_api import props_setattr as _props_setattr
except ImportError:  # pragma: no cover - another viser: the public path only
    _props_setattr = None

#: Private members of a viser scene-node handle this module reads or calls.
PRIVATE_NAMES = ("_impl", "_impl.props", "_impl.removed", "_queue_update", "_on_prop_assigned", "_prop_hints")
#: Use the fast path when the installed viser has every private name (set False to always go the public way).
FAST_PATH = _props_setattr is not None

_MISSING = object()
_T = TypeVar("_T")


class _HandleState(Protocol):
    """A viser handle's private state (its ``_impl``), as this module reads it."""

    @property
    def props(self) -> object: ...

    @property
    def removed(self) -> bool: ...


class PropsHandle(Protocol):
    """A viser handle whose properties this module assigns by viser's private path: a scene node's
    (:class:`viser.SceneNodeHandle`) or a GUI element's (its private names are :data:`PRIVATE_NAMES`)."""

    @property
    def _impl(self) -> _HandleState: ...

    @property
    def _prop_hints(self) -> Mapping[str, object]: ...

    def _queue_update(self, name: str, value: object) -> None: ...

    def _on_prop_assigned(self, name: str) -> None: ...


def missing_internals(handle: object) -> list[str]:
    """The names of :data:`PRIVATE_NAMES` that ``handle`` (a viser scene-node handle) lacks; empty when all exist."""
    missing: list[str] = []
    if _props_setattr is None:
        missing.append("viser._assignable_props_api.props_setattr")
    impl = getattr(handle, "_impl", _MISSING)
    if impl is _MISSING:
        return [*missing, *PRIVATE_NAMES]
    for name in ("props", "removed"):
        if not hasattr(impl, name):
            missing.append(f"_impl.{name}")
    for name in ("_queue_update", "_on_prop_assigned"):
        if not callable(getattr(handle, name, None)):
            missing.append(name)
    if not isinstance(getattr(handle, "_prop_hints", None), dict):
        missing.append("_prop_hints")
    return missing


def current_value(handle: PropsHandle, prop: str) -> object:
    """What the node holds for ``prop`` (its stored value, without a copy)."""
    return getattr(handle._impl.props, prop)


def assign_array(handle: PropsHandle, prop: str, value: np.ndarray) -> bool:
    """Assign an array property (points, colours, vertices) unless the node holds the same bytes; True: sent.

    When ``value`` has the node's dtype (a float array is first given the node's float type, as viser would store
    it), this stores a private copy, queues another copy and runs the handle's assignment hook, as viser's
    ``props_setattr`` does for a changed array, without its cast, its type-hint checks and its second comparison;
    otherwise (an unexpected handle or dtype) it assigns the public way.
    """
    impl = handle._impl
    current = getattr(impl.props, prop)
    if type(current) is np.ndarray and current.dtype != value.dtype and current.dtype.kind == value.dtype.kind == "f":
        value = value.astype(current.dtype)  # as viser would store it (a point cloud keeps float16 points)
    if (
        type(current) is np.ndarray
        and current.dtype == value.dtype
        and current.shape == value.shape
        and current.tobytes() == value.tobytes()
    ):
        return False
    if (
        FAST_PATH
        and type(handle).__setattr__ is _props_setattr
        and not impl.removed
        and type(current) is np.ndarray
        and current.dtype == value.dtype
        and prop in handle._prop_hints
    ):
        setattr(impl.props, prop, np.array(value, copy=True))
        handle._queue_update(prop, np.array(value, copy=True))
        handle._on_prop_assigned(prop)
    else:
        setattr(handle, prop, value)
    return True


def assign_text(handle: PropsHandle, prop: str, text: str) -> bool:
    """Assign a text property (an HTML element's ``content``) unless the handle holds the same text; True: sent.

    As :func:`assign_array` for arrays: a changed text is stored, queued and the handle's assignment hook run, as
    viser's ``props_setattr`` does for a plain value, without its type-hint casts (some 40 us: a drag step assigns
    two panels and the read-out); a handle whose property is a Python property, a removed handle or an unexpected
    value goes the public way.
    """
    impl = getattr(handle, "_impl", None)
    current = getattr(getattr(impl, "props", None), prop, _MISSING)
    if type(current) is str and type(text) is str and current == text:
        return False
    if (
        FAST_PATH
        and impl is not None
        and type(handle).__setattr__ is _props_setattr
        and not impl.removed
        and type(current) is str
        and type(text) is str
        and prop in handle._prop_hints
        and not isinstance(getattr(type(handle), prop, None), property)
    ):
        setattr(impl.props, prop, text)
        handle._queue_update(prop, text)
        handle._on_prop_assigned(prop)
    else:
        setattr(handle, prop, text)
    return True


def _same(a: object, b: object) -> bool:
    if type(a) is np.ndarray or type(b) is np.ndarray:
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and bool(np.array_equal(a, b))
    return bool(a == b)


def assign(handle: object, prop: str, value: object) -> None:
    """Assign a node property unless it already holds ``value`` (for small values: flags, colours, poses).

    viser would skip an equal value too, but only after casting it (tens of microseconds per property); a cache
    of what was last assigned (an attribute of egtviz's own, ``_egt_cache``, on the handle object; it goes with
    the handle) makes an unchanged node free.
    """
    cache = handle.__dict__.get("_egt_cache")
    if cache is None:
        cache = handle.__dict__["_egt_cache"] = {}
    old = cache.get(prop, _MISSING)
    if old is not _MISSING and _same(old, value):
        return
    setattr(handle, prop, value)
    cache[prop] = value.copy() if isinstance(value, np.ndarray) else value


# -- what the benchmarks need from viser's server and gizmos ---------------------------------------------------

#: Private members of a :class:`viser.ViserServer` the benchmarks reach (the event loop and the callbacks' pool).
SERVER_PRIVATE_NAMES = ("_websock_server._background_event_loop", "_thread_executor")
#: Private members of a transform-controls (gizmo) handle that a client's gizmo message sets.
GIZMO_PRIVATE_NAMES = ("_impl.position", "_impl_aux.last_updated")
#: Private members of a GUI input handle that a client's update message sets.
INPUT_PRIVATE_NAMES = ("_impl.value", "_impl.update_cb")


def _missing(obj: object, dotted_names: tuple[str, ...]) -> list[str]:
    missing = []
    for dotted in dotted_names:
        target = obj
        for part in dotted.split("."):
            target = getattr(target, part, _MISSING)
            if target is _MISSING:
                missing.append(dotted)
                break
    return missing


def missing_server_internals(server: object) -> list[str]:
    """The names of :data:`SERVER_PRIVATE_NAMES` that ``server`` lacks; empty when all exist."""
    return _missing(server, SERVER_PRIVATE_NAMES)


def missing_gizmo_internals(gizmo: object) -> list[str]:
    """The names of :data:`GIZMO_PRIVATE_NAMES` that ``gizmo`` lacks; empty when all exist."""
    return _missing(gizmo, GIZMO_PRIVATE_NAMES)


def missing_input_internals(handle: object) -> list[str]:
    """The names of :data:`INPUT_PRIVATE_NAMES` that ``handle`` (a GUI input) lacks; empty when all exist."""
    return _missing(handle, INPUT_PRIVATE_NAMES)


def event_loop(server: viser.ViserServer) -> asyncio.AbstractEventLoop:
    """The asyncio event loop on which ``server`` receives and sends websocket messages.

    Raises:
        RuntimeError: the server has no loop (viser starts it before its constructor returns: never in practice).
    """
    loop = server._websock_server._background_event_loop
    if loop is None:
        raise RuntimeError("the viser server has no event loop: it was never started")
    return loop


def callback_pool(server: viser.ViserServer) -> ThreadPoolExecutor:
    """The executor ``server`` submits GUI and scene callbacks to (viser's thread pool, or egtviz's fair
    executor over it when the guards of :mod:`egtviz.viewer.server.guard` are on): each ``submit`` runs a callback."""
    return server._thread_executor


def gizmo_moved_by_client(gizmo: viser.TransformControlsHandle, position: np.ndarray) -> None:
    """Put ``gizmo`` where a client's gizmo message would, before viser calls its callbacks (benchmarks, tests)."""
    gizmo._impl.position = np.asarray(position, float)
    gizmo._impl_aux.last_updated = time.time()


def value_sent_by_client(handle: viser.GuiInputHandle[_T], value: _T) -> list[Callable[[viser.GuiEvent], object]]:
    """Give GUI input ``handle`` the value a client's update message carries, as viser does before it submits the
    handle's callbacks to its pool; returns those callbacks (tests run them later, to order events across threads)."""
    handle._impl.value = value
    return list(handle._impl.update_cb)
