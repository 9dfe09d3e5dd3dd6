"""GUI writes that are not user edits (text safe to show is :func:`egtviz.controllers.workbench_fields.plain`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import viser

__all__ = ["set_value"]


T = TypeVar("T")


def set_value(handle: viser.GuiInputHandle[T], value: T) -> None:
    """Assign a GUI value only if it differs (viser also fires callbacks on assignment)."""
    current = handle.value
    if isinstance(value, tuple) and isinstance(current, tuple):
        if len(value) == len(current) and all(
            (isinstance(a, str) and a == b) or (not isinstance(a, str) and abs(float(a) - float(b)) <= 1e-9)
            for a, b in zip(value, current)
        ):
            return
    elif current == value:
        return
    # viser declares the value's setter apart from its getter, which mypy reads as a read-only property.
    handle.value = value  # type: ignore[misc]
