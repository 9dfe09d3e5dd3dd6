"""The registry of camera models above the core: one :class:`~egtviz.scene.camera_entry.CameraEntry` per model.

A model is registered once, by its line in the core's registry (``egtviz/geometry/camera_model.py``, naming its
core module ``egtviz/geometry/<module>.py``). Its entry above the core is declared in its model file, the module of
this package with the same name, ``egtviz/scene/cameras/<module>.py``: the spec class that stores a camera of it
(the scene file's ``kind``), the GUI fields of its parameters, its 3D drawing. This module collects those entries,
in the core registry's order; nothing else in egtviz names a model. How to add a model: ``docs/camera_models.md``.
"""

from __future__ import annotations

import importlib
from typing import Any

from ...geometry.camera_model import CAMERA_MODELS
from .._values import SceneError, short_text
from ..camera_entry import CameraEntry
from ..specs import CameraSpecBase

__all__ = ["CAMERA_ENTRIES", "CAMERA_KINDS", "SPEC_CLASSES", "camera_entry", "model_choices", "spec_for_model"]


def _entries() -> dict[str, CameraEntry]:
    """Every core model's entry, from the model file named like its core module (imported here, once)."""
    found: dict[str, CameraEntry] = {}
    for kind, info in CAMERA_MODELS.items():
        module = info.target.partition(":")[0].rpartition(".")[2]
        try:
            entries = importlib.import_module(f"{__name__}.{module}").ENTRIES
        except ModuleNotFoundError as exc:
            raise ImportError(f"camera model {kind!r}: no model file {__name__}.{module} ({exc})") from exc
        for entry in entries:
            found.setdefault(entry.model, entry)
        if kind not in found:
            raise ImportError(f"camera model {kind!r}: {__name__}.{module} declares no entry for it")
    return {kind: found[kind] for kind in CAMERA_MODELS}


CAMERA_ENTRIES: dict[str, CameraEntry] = _entries()
"""Every camera model's entry by the core registry's kind, in its order."""
SPEC_CLASSES: tuple[type[CameraSpecBase], ...] = tuple(dict.fromkeys(e.spec for e in CAMERA_ENTRIES.values()))
"""Every camera spec class, once each (one spec may store several models: a mirror's shapes)."""
CAMERA_KINDS: dict[str, type[CameraSpecBase]] = {cls.kind: cls for cls in SPEC_CLASSES}
"""The scene file's camera entries: ``kind`` -> spec class (a ``panoramic`` entry is a hyperbolic or parabolic
camera, as its ``mirror`` says)."""


def camera_entry(model_kind: str) -> CameraEntry:
    """The entry of the registered model ``model_kind``.

    Raises:
        SceneError: for a kind that is not registered.
    """
    found = CAMERA_ENTRIES.get(model_kind) if type(model_kind) is str else None
    if found is None:
        raise SceneError(f"kind: expected one of {sorted(CAMERA_MODELS)}, got {short_text(model_kind)}")
    return found


def spec_for_model(model_kind: str) -> tuple[type[CameraSpecBase], dict[str, Any]]:
    """The spec class that builds the registered model ``model_kind``, and the fields that select it.

    Raises:
        SceneError: for a kind no spec builds.
    """
    entry = camera_entry(model_kind)
    return entry.spec, dict(entry.selection)


def model_choices(spec_cls: type) -> dict[str, tuple[str, ...]]:
    """The fields of ``spec_cls`` that choose among the models it builds, and their values (``{"mirror":
    ("hyperbolic", "parabolic")}`` for the catadioptric spec; empty for a spec of one model)."""
    out: dict[str, list[str]] = {}
    for entry in CAMERA_ENTRIES.values():
        if entry.spec is spec_cls:
            for key, value in entry.selection.items():
                out.setdefault(key, []).append(value)
    return {key: tuple(values) for key, values in out.items()}
