"""A check's own proof that the step's locks held: the locked cameras and points are where the step put them.

The scene model refuses an edit of a locked camera or point; a check does not rely on that alone. A route
round the model (a camera removed and added again under its name, a lock lifted) would let a task measure
a pair the step did not set, so :func:`lock_breach` compares the scene checked with the step's start.
"""

from __future__ import annotations

from ..scene import Scene

__all__ = ["lock_breach"]


def lock_breach(start: Scene, now: Scene) -> str | None:
    """Why ``now`` does not keep the locks of the step that started at ``start`` (None: it keeps them).

    A locked camera still there must have the same position and orientation (its other fields may change, as
    the model allows; one that has gone is the task's to report); a locked point (``point:<i>``) must still be
    at the same place.
    """
    for name in sorted(start.locked):
        if name.startswith("point:"):
            i = int(name[6:])
            if i < len(start.points) and (i >= len(now.points) or now.points[i] != start.points[i]):
                return f"point {i + 1} is locked in this step but has moved"
            continue
        if name not in start.camera_names or name not in now.camera_names:
            continue  # a camera that has gone: the task itself says so (Task.missing)
        a, b = start.camera(name), now.camera(name)
        if a.position != b.position or a.ypr_deg != b.ypr_deg:
            return f"{name} is locked in this step but has moved"
    return None
