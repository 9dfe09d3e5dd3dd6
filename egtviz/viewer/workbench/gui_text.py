"""Small helpers the workbench's parts share: text safe to show, and GUI writes that are not user edits."""

from __future__ import annotations

from typing import Any

__all__ = ["plain", "set_value"]


def plain(text: str, limit: int = 80) -> str:
    """Text from a file or a browser, safe to show: printable characters only, at most ``limit`` of them."""
    clean = "".join(c if c.isprintable() else "?" for c in str(text))
    return clean if len(clean) <= limit else clean[:limit] + "..."


def set_value(handle: Any, value: Any) -> None:
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
    handle.value = value
