"""The drag path's copy of an image plane with some fields changed is ``dataclasses.replace``'s, field by field."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from egtviz.scene import compute_derived, default_scene
from egtviz.scene import derived as D


def _fields(plane: D.ImagePlane) -> dict:
    return {f.name: getattr(plane, f.name) for f in dataclasses.fields(plane)}


def test_replaced_is_dataclasses_replace():
    plane = next(iter(compute_derived(default_scene()).image_planes.values()))
    before = _fields(plane)
    lines = np.zeros((8, 2, 2))
    changes = {"in_pair": True, "epipoles": (), "lines": lines, "message": "m"}
    ours, theirs = D._replaced(plane, **changes), dataclasses.replace(plane, **changes)
    assert type(ours) is D.ImagePlane and ours is not plane
    assert _fields(ours).keys() == _fields(theirs).keys()
    for name, value in _fields(theirs).items():
        assert getattr(ours, name) is value, name  # the same objects, as replace keeps them
    assert _fields(plane) == before  # the original is untouched
    with pytest.raises(dataclasses.FrozenInstanceError):
        ours.width = 3  # type: ignore[misc]


def test_replaced_refuses_a_field_the_plane_does_not_have():
    plane = next(iter(compute_derived(default_scene()).image_planes.values()))
    with pytest.raises(TypeError, match="no field 'colour'"):
        D._replaced(plane, colour=1)


def test_the_copy_shortcut_still_holds_for_image_planes():
    # The shortcut copies __dict__: it is replace() only while ImagePlane has no __post_init__ and no slots.
    assert not hasattr(D.ImagePlane, "__post_init__") and not hasattr(D.ImagePlane, "__slots__")
