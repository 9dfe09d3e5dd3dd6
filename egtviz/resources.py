"""Data folders shipped with egtviz: the lessons and the meshes.

In a checkout (and an editable install) they are the repository's top-level ``lessons/`` and ``assets/``;
an installed wheel carries them inside the package as ``egtviz/_lessons`` and ``egtviz/_assets``
(``pyproject.toml``, ``force-include``).
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def shipped_folder(name: str) -> Path:
    """The folder ``name`` (``"lessons"`` or ``"assets"``): the checkout's, else the installed package's copy."""
    checkout = _PACKAGE.parent / name
    if checkout.is_dir() and (_PACKAGE.parent / "pyproject.toml").is_file():
        return checkout
    return _PACKAGE / f"_{name}"
