"""Small helpers the workbench's parts share: text safe to show, and GUI writes that are not user edits."""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import viser

__all__ = ["plain", "set_value"]


def plain(text: str, limit: int = 80) -> str:
    """Text from a file or a browser, safe to show: printable characters only, at most ``limit`` of them."""
    clean = "".join(c if c.isprintable() else "?" for c in str(text))
    return clean if len(clean) <= limit else clean[:limit] + "..."


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
