"""The workbench's controller: one tab's scene model and every intent its user can express, without a browser.

The viewer's workbench (:mod:`egtviz.viewer.workbench`) maps each widget to one intent of
:class:`WorkbenchController` and draws :attr:`WorkbenchController.scene`; tests drive the controller directly. An
intent judges what the user sent the way the page words it (a field's text in its own units, a drop-down's label, a
gizmo's pose) and either changes the scene model or raises :class:`~egtviz.scene.SceneError` (a
:class:`~egtviz.controllers.workbench_fields.FieldError` for a refused value) with the message the user reads; a
refused intent leaves the scene as it was.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import GeometryError
from ..geometry.poses import Pose, matrix_from_quat_wxyz
from ..scene import (
    SCENES,
    CameraSpec,
    Scene,
    SceneError,
    SceneFileError,
    SceneModel,
    SurfaceSpec,
    limits,
    scene_from_bytes,
    scene_to_bytes,
)
from ..scene.cameras import model_choices
from ..scene.derived import Derived
from ..scene.specs import OutOfRangeError
from .workbench_cameras import field_rules, restated, spec_fields, spec_values
from .workbench_choices import file_name, pair_choices, point_choices, surface_choices
from .workbench_fields import FieldError, NumberRule, format_number, parse_numbers, plain

__all__ = ["POINTS_RULE", "FieldGuard", "SavedScene", "WorkbenchController"]

#: ``field_guard(camera, spec_fields) -> refusal message or None``: a lesson's say over a typed value.
FieldGuard = Callable[[str, dict[str, object]], str | None]
#: The "how many points" field: what the page offers is what the server accepts.
POINTS_RULE = (NumberRule("how many points", "", 0, limits.MAX_POINTS, integer=True),)


@dataclass(frozen=True)
class SavedScene:
    """A scene file to hand to the user: its file name (from the scene's title) and its bytes."""

    name: str
    content: bytes


def _allclose(a: np.ndarray, b: np.ndarray, atol: float) -> bool:
    """``np.allclose(a, b, atol=atol)`` (rtol 1e-5) without its per-call overhead (runs on every drag event)."""
    return bool((np.abs(a - b) <= atol + 1e-5 * np.abs(b)).all())


def _unmoved(current: Pose, allowed: Pose) -> bool:
    """Whether a gizmo's pose, as the model allows it, is where the camera is (the gizmo resends it rounded)."""
    return _allclose(current.t, allowed.t, 1e-9) and _allclose(current.R, allowed.R, 1e-9)


def _position(position: ArrayLike, who: str) -> tuple[float, ...]:
    """A gizmo's position as 3 finite numbers (a raw client can send anything)."""
    xyz = np.asarray(position, float)
    if xyz.shape != (3,) or not np.isfinite(xyz).all():
        raise SceneError(f"{who}: the gizmo sent a position that is not 3 finite numbers")
    return tuple(xyz)


class WorkbenchController:
    """One workbench tab's scene and what its user may do to it.

    State the skin draws: :attr:`scene` and :attr:`derived` (the model's), :meth:`field_values`, the drop-downs'
    options (:meth:`pair_choices`, :meth:`point_choices`, :attr:`surfaces`, :attr:`builtin_scenes`), the last valid
    point count (:attr:`point_count_text`) and whether undo does anything (:attr:`undo_enabled`).

    Args:
        model: the tab's scene model (the controller is its one writer for the tab's user).
        field_guard: asked before a camera field's new value is committed (a lesson's ranges); its refusal is the
            message of the :class:`FieldError` raised. None: the model alone decides.
    """

    def __init__(self, model: SceneModel, *, field_guard: FieldGuard | None = None) -> None:
        self.model = model
        self.field_guard = field_guard
        #: The surfaces the "surface" drop-down offers, by label.
        self.surfaces = surface_choices()
        #: The built-in scenes the "built-in scene" drop-down offers.
        self.builtin_scenes = tuple(SCENES)
        #: The last point count the user typed that was valid: a refused one reverts to it.
        self.point_count_text = "8"
        self._drags = 0

    # -- state ------------------------------------------------------------------------------------------

    @property
    def scene(self) -> Scene:
        """The tab's scene now."""
        return self.model.scene

    @property
    def derived(self) -> Derived:
        """The scene's derived quantities (computed once, when the model committed it)."""
        return self.model.derived

    @property
    def undo_enabled(self) -> bool:
        """Whether the undo button does something: undo a change, or say why not at a lesson step's start."""
        return self.model.can_undo or self.model.undo_barrier_note is not None

    def field_values(self, camera: str) -> dict[str, tuple[float, ...]]:
        """Camera ``camera``'s values as its fields show them, by field key."""
        return spec_values(self.scene.camera(camera))

    def pair_choices(self) -> dict[str, tuple[str, str]]:
        """The "drawn pair" drop-down's options, by label."""
        return pair_choices(self.scene)

    def point_choices(self) -> dict[str, int | None]:
        """The "selected point" drop-down's options, by label."""
        return point_choices(len(self.scene.points))

    # -- a camera's fields ------------------------------------------------------------------------------

    def _spec(self, camera: str) -> CameraSpec | None:
        """The camera's current spec, or None once it was removed (the user may still be typing)."""
        scene = self.scene
        return scene.camera(camera) if camera in scene.camera_names else None

    def set_field(self, camera: str, field: str, text: object) -> None:
        """The user typed ``text`` in ``camera``'s field ``field``: parse and check it in the field's units, and
        commit it. A number left as shown keeps the model's full precision (``1.23457`` shown for 1.234567 stays
        1.234567). A camera removed meanwhile ignores it.

        Raises:
            FieldError: the text is not the field's count of numbers in its ranges, the lesson refuses it, or the
                camera cannot hold the value (a limit across fields, said in the field's words and units).
        """
        spec = self._spec(camera)
        if spec is None:
            return
        values = parse_numbers(text, field_rules(spec, field), owner=camera)
        current = spec_values(spec).get(field)
        if current is None:
            raise FieldError(f"{camera}: no field {field!r} on a {spec.model.label.lower()}")
        values = tuple(c if format_number(v) == format_number(c) else v for v, c in zip(values, current))
        if values == current:
            return  # nothing edited (e.g. the skin's own write-back, or the same text again)
        self._update(spec, spec_fields(spec, field, values))

    def slide(self, camera: str, field: str, value: object) -> None:
        """The user moved ``camera``'s slider ``field`` to ``value``: check and commit it (one slide, however many
        steps, is one undo step)."""
        spec = self._spec(camera)
        if spec is None:
            return
        (rule,) = field_rules(spec, field)
        if isinstance(value, bool) or not isinstance(value, (int, float)):  # a raw client can send anything
            raise FieldError(f"{camera}: {rule.label} must be a number, got {plain(repr(value), 40)}")
        x = (rule.check(float(value), owner=camera),)
        if x == spec_values(spec).get(field):
            return
        self._update(spec, spec_fields(spec, field, x), merge_key=("slider", camera, field))

    def _update(self, spec: CameraSpec, fields: dict[str, object], merge_key: Hashable = None) -> None:
        name = spec.name
        if all(getattr(spec, k) == v for k, v in fields.items()):
            return
        refusal = None if self.field_guard is None else self.field_guard(name, fields)
        if refusal is not None:
            raise FieldError(refusal)
        try:
            self.model.update_camera(name, merge_key=merge_key, **fields)
        except OutOfRangeError as exc:  # a limit across fields (e.g. focal length in pixels): say it in UI terms
            raise restated(exc, name, spec.model_kind) from exc
        except SceneError as exc:
            if str(exc).startswith(f"{name}:"):
                raise
            raise SceneError(f"{name}: {exc}") from exc

    def choose_model(self, camera: str, key: str, value: object) -> None:
        """Switch ``camera`` among the models its spec builds (``key``: a mirror's shape); the spec adapts its
        parameters. Only the offered values exist."""
        spec = self._spec(camera)
        if spec is None:
            return
        options = model_choices(type(spec)).get(key, ())
        if value not in options:  # a raw client can send any string
            raise FieldError(f"{camera}: {key} must be one of {', '.join(options)}, got {plain(repr(value), 40)}")
        if getattr(spec, key) != value:
            self.model.update_camera(camera, **{key: value})

    def add_camera(self, kind: str) -> str:
        """Add a camera of the registered model ``kind`` where it sees the points; returns its name."""
        return self.model.add_camera(kind)

    def remove_camera(self, camera: str) -> None:
        self.model.remove_camera(camera)

    # -- gizmos -----------------------------------------------------------------------------------------

    def start_drag(self) -> int:
        """A new drag's id: the steps of one drag, given its id, are one undo step."""
        self._drags += 1
        return self._drags

    def drag_camera(self, camera: str, position: ArrayLike, wxyz: ArrayLike, drag_id: int | None = None, *,
                    last: bool = False) -> bool:
        """A step of a camera gizmo's drag (``last``: its end) to ``position`` and unit quaternion ``wxyz``.

        The pose goes to the scene model as sent: the model's constraints (a lesson's ranges) decide where the
        camera goes, and may stop it short of the pointer. Returns whether the camera moved; a pose that rounds to
        where the camera is commits nothing.

        Raises:
            SceneError: a locked camera's drag ended (the gizmo is to go back), or the gizmo sent an orientation
                that is not a rotation or a position that is not 3 finite numbers.
        """
        scene = self.scene
        if camera not in scene.camera_names:
            return False
        if camera in scene.locked:  # a lesson's lock: the drag is undone when it ends
            if last:
                raise SceneError(f"{camera} is locked: its gizmo cannot move it now")
            return False
        try:
            R = matrix_from_quat_wxyz(wxyz)
        except GeometryError as exc:
            raise SceneError(f"{camera}: the gizmo sent an orientation that is not a rotation ({exc})") from exc
        return self.model.set_camera_pose(camera, _position(position, camera), R, drag_id=drag_id, unmoved=_unmoved)

    def start_point_drag(self, index: int) -> int:
        """Point ``index``'s gizmo is grabbed: the point becomes the selected one; returns the drag's id."""
        scene = self.scene
        drag_id = self.start_drag()
        if scene.selected_point != index and index < len(scene.points):
            self.model.select_point(index)
        return drag_id

    def drag_point(self, index: int, position: ArrayLike, drag_id: int | None = None) -> None:
        """A step of point ``index``'s drag to ``position`` (a point removed meanwhile ignores it)."""
        if index < len(self.scene.points):
            self.model.set_point(index, _position(position, f"point {index + 1}"), drag_id=drag_id)

    # -- the controls -----------------------------------------------------------------------------------

    def set_pair(self, label: object) -> None:
        """Draw the pair the "drawn pair" drop-down calls ``label`` (``"cam1 & cam2"``)."""
        pair = self.pair_choices().get(label) if isinstance(label, str) else None
        if pair is None:
            raise FieldError(f"drawn pair: no pair {plain(repr(label), 40)}")
        if pair != self.scene.drawn_pair:
            self.model.set_pair(*pair)

    def select_point(self, label: object) -> None:
        """Select the point the "selected point" drop-down calls ``label`` (``"point 3"``, or ``"none"``)."""
        options = self.point_choices()
        if not isinstance(label, str) or label not in options:
            raise FieldError(f"selected point: no {plain(repr(label), 40)} (have {len(self.scene.points)} points)")
        index = options[label]
        if index != self.scene.selected_point:
            self.model.select_point(index)

    def set_option(self, option: str, value: object) -> None:
        """Turn a display option (``show_rays``, ``show_planes``, ...) on or off."""
        if not isinstance(value, bool):
            raise FieldError(f"{option}: expected true or false, got {plain(repr(value), 40)}")
        if getattr(self.scene.options, option) != value:
            self.model.set_option(option, value)

    def set_point_count(self, text: object) -> None:
        """The user typed a point count: remember it if valid (:attr:`point_count_text`), else refuse it."""
        parse_numbers(text, POINTS_RULE)
        if isinstance(text, str):  # parse_numbers refuses anything else
            self.point_count_text = text

    def _centre(self) -> tuple[float, float, float]:
        """Where new points and surfaces go: the points' centroid, or 1 m above the origin without points."""
        X = self.scene.points_array()
        if not len(X):
            return (0.0, 0.0, 1.0)
        x, y, z = X.mean(axis=0)
        return (x, y, z)

    def randomise_points(self, count: object) -> None:
        """Replace the points by ``count`` (the field's text) random points in a 4 m cube about their centre."""
        (n,) = parse_numbers(count, POINTS_RULE)
        self.model.randomize_points(int(n), center=self._centre(), extent=2.0)

    def add_point(self) -> int:
        """Add a point 1 m above the origin; returns its index."""
        return self.model.add_point((0.0, 0.0, 1.0))

    def remove_point(self) -> None:
        """Remove the selected point, or the last one when none is selected."""
        scene = self.scene
        if not scene.points:
            raise SceneError("no points to remove")
        self.model.remove_point(scene.selected_point if scene.selected_point is not None else len(scene.points) - 1)

    def add_surface(self, label: object) -> None:
        """Add the surface the "surface" drop-down calls ``label``, centred under the points."""
        choice = self.surfaces.get(label) if isinstance(label, str) else None
        if choice is None:  # a raw client can send any string: only the listed surfaces exist
            raise FieldError(f"surface: no surface {plain(repr(label), 40)}")
        kind, mesh = choice
        centre = self._centre()
        if kind == "mesh":
            # A mesh of the package's own, standing on the ground under the points.
            self.model.add_surface(
                SurfaceSpec(kind="mesh", center=(centre[0], centre[1], 0.0), size=2.0, samples=300, path=mesh)
            )
            return
        size = 1.0 if kind == "sphere" else 3.0
        self.model.add_surface(SurfaceSpec(kind=kind, center=centre, size=size, samples=200))

    # -- history and files ------------------------------------------------------------------------------

    def undo(self) -> str | None:
        """Undo one change. Returns None, or what to tell the user when a lesson step's start stops undo."""
        if not self.model.undo():
            return self.model.undo_barrier_note
        return None

    def reset(self) -> None:
        """Back to the tab's first scene (or the lesson step's start); undoable."""
        self.model.reset()

    def open_builtin(self, name: object) -> None:
        """Replace the scene by the built-in scene ``name`` (undoable); only the listed scenes exist."""
        if not isinstance(name, str) or name not in SCENES:  # a raw client can send any string
            raise FieldError(f"built-in scene: no scene {plain(repr(name), 40)}; "
                             f"the built-in scenes are {', '.join(SCENES)}")
        self.model.load_scene(SCENES[name]())

    def save(self) -> SavedScene:
        """The scene as a file to download, named after its title."""
        scene = self.scene
        return SavedScene(file_name(scene.title or "scene"), scene_to_bytes(scene))

    def load(self, name: str, content: object) -> None:
        """Replace the scene by an uploaded file's (undoable), checked as ``egtviz scene check`` checks one.

        Args:
            name: the file's name as the browser gave it (only quoted in messages; no file is read by name).
            content: the file's bytes.

        Raises:
            SceneFileError: no bytes, more than ``MAX_SCENE_FILE_BYTES`` (refused unread), or a bad scene file;
                the message names the file, the entry and the reason.
        """
        shown = plain(name or "the upload", 60)
        if not isinstance(content, bytes):
            raise SceneFileError(f"{shown}: the upload holds no file")
        if len(content) > limits.MAX_SCENE_FILE_BYTES:  # before parsing: a big file is refused unread
            raise SceneFileError(f"{shown}: the file has {len(content)} bytes; a scene file has at most "
                                 f"{limits.MAX_SCENE_FILE_BYTES} bytes")
        self.model.load_scene(scene_from_bytes(content, source=shown))
