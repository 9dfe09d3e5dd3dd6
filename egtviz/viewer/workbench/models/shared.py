"""Node arrays prepared once per derived geometry and shared by every tab that draws it.

A classroom's followers all draw the instructor's very ``Derived`` objects: the arrays a node needs (a pin-hole
image on its frustum's image plane, a camera's rays as segments, their colours) are the same for every follower,
so they are computed by the first tab that draws them (the instructor's) and handed to the others as they are.
An entry is found by the identity of the derived objects it was made from (they are never changed in place; the
entry keeps them alive, so an identity cannot be taken by a new object while it is stored) and by a small
hashable key (the drawn rows). The arrays handed out are read-only: no tab can change another's.
"""

from __future__ import annotations

import operator
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any, TypeVar

import numpy as np

__all__ = ["SHARED", "SharedArrays", "frozen"]

T = TypeVar("T")

#: Entries kept: a few per camera of every scene drawn at once (thirty students dragging their own scenes
#: each keep one per camera and node kind warm).
CAPACITY = 512


def frozen(array: np.ndarray) -> np.ndarray:
    """``array`` made read-only (returned): it is handed to every tab."""
    array.setflags(write=False)
    return array


class SharedArrays:
    """A small least-recently-used store of prepared arrays, safe to use from any thread.

    Args:
        capacity: entries kept; the oldest goes first.
    """

    def __init__(self, capacity: int = CAPACITY) -> None:
        self._capacity = capacity
        # Each entry's value is whatever its ``make`` returned: ``get``'s type variable gives it back its type.
        self._entries: OrderedDict[tuple, tuple[tuple[object, ...], Any]] = OrderedDict()
        self._lock = threading.Lock()
        #: Lookups answered from the store, and those that made their value (tests read these).
        self.hits = 0
        self.misses = 0

    def get(self, kind: str, sources: tuple[object, ...], key: Hashable, make: Callable[[], T]) -> T:
        """The value made by ``make()`` for these very ``sources`` (by identity) and ``key``, made now if absent.

        ``kind`` names what is made (two drawings may prepare different things from the same sources).
        """
        ident = (kind, tuple(map(id, sources)), key)
        with self._lock:
            entry = self._entries.get(ident)
            if entry is not None and all(map(operator.is_, entry[0], sources)):
                self._entries.move_to_end(ident)
                self.hits += 1
                return entry[1]
        value = make()  # outside the lock: two tabs may both make it once, never wait for each other
        with self._lock:
            self.misses += 1
            self._entries[ident] = (sources, value)
            self._entries.move_to_end(ident)
            while len(self._entries) > self._capacity:
                self._entries.popitem(last=False)
        return value

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()


#: The process's store: every tab's drawings look here first.
SHARED = SharedArrays()
