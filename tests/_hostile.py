"""Hostile inputs for the numeric core, shared by the tests of every geometry module.

``BAD_VALUES`` holds values that are wrong for *any* numeric argument (scalar, vector, matrix or point
array). ``bad_values_like(valid)`` derives, from a valid value of one argument, values of the right shape
that are still wrong (a NaN entry, booleans, complex numbers, ...), so that a shape check cannot hide a
missing type check. ``assert_rejects`` calls a function with one argument replaced and checks that it
raises :class:`GeometryError` naming that argument.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from egtviz.geometry import GeometryError

#: (label, value): wrong for every numeric argument of the core.
BAD_VALUES: list[tuple[str, Any]] = [
    ("None", None),
    ("bool True", True),
    ("bool False", False),
    ("numpy bool", np.bool_(True)),
    ("complex scalar", 1.0 + 2.0j),
    ("string", "1.0"),
    ("bytes", b"\x00\x01"),
    ("NaN scalar", float("nan")),
    ("inf scalar", float("inf")),
    ("empty array", np.array([])),
    ("empty list", []),
    ("shape (2, 2, 2)", np.zeros((2, 2, 2))),
    ("shape (5, 7)", np.ones((5, 7))),
    ("shape (7,)", np.ones(7)),
    ("ragged nested list", [[1.0, 2.0, 3.0], [4.0, 5.0]]),
    ("object array", np.array([1.0, "x", None], dtype=object)),
    ("huge int", 10**400),
    ("dict", {"x": 1.0}),
]


def bad_values_like(valid: Any) -> list[tuple[str, Any]]:
    """Values shaped like ``valid`` (a number or an array) that are still wrong for it."""
    a = np.asarray(valid, dtype=np.float64)
    out: list[tuple[str, Any]] = []
    for label, poison in (("NaN entry", np.nan), ("inf entry", np.inf), ("-inf entry", -np.inf)):
        b = a.copy()
        b.reshape(-1)[0] = poison
        out.append((label, b if a.ndim else float(b)))
    out += [
        ("complex dtype", a.astype(np.complex128) + 1e-3j),
        ("bool dtype", a != 0),
        ("object dtype", a.astype(object)),
        ("string dtype", a.astype(str)),
    ]
    if a.ndim:
        nested = a.tolist()
        flat_first = nested
        while isinstance(flat_first[0], list):
            flat_first = flat_first[0]
        flat_first[0] = True  # a bool hidden in a list: numpy would read it as 1.0
        out.append(("bool inside list", nested))
        nested = a.tolist()
        flat_first = nested
        while isinstance(flat_first[0], list):
            flat_first = flat_first[0]
        flat_first[0] = None
        out.append(("None inside list", nested))
        out.append(("extra axis", a[None, None]))
    return out


def all_bad_values(valid: Any) -> Iterator[tuple[str, Any]]:
    """``BAD_VALUES`` followed by ``bad_values_like(valid)``."""
    yield from BAD_VALUES
    yield from bad_values_like(valid)


def assert_rejects(func: Callable[..., Any], kwargs: dict[str, Any], arg: str, bad: Any, *, label: str = "") -> None:
    """Call ``func(**kwargs)`` with ``kwargs[arg]`` replaced by ``bad``; assert a GeometryError naming ``arg``.

    The name must appear as a word at the start of the message or after a separator, as the core writes
    it (``"X_world: expected shape (N, 3), got (5, 7)"``).
    """
    call = dict(kwargs)
    call[arg] = bad
    try:
        func(**call)
    except GeometryError as exc:
        message = str(exc)
        assert arg in message, f"{func.__qualname__}({arg}={label}): message does not name {arg!r}: {message}"
        assert len(message) < 400, f"{func.__qualname__}({arg}={label}): message too long ({len(message)} chars)"
        return
    except Exception as exc:  # noqa: BLE001 - the point is to report any foreign exception type
        pytest.fail(f"{func.__qualname__}({arg}={label}): raised {type(exc).__name__}: {exc}")
    pytest.fail(f"{func.__qualname__}({arg}={label}): accepted the bad value")


def parameter_names(func: Callable[..., Any]) -> list[str]:
    """Names of ``func``'s parameters (without ``self``)."""
    return [p for p in inspect.signature(func).parameters if p != "self"]
