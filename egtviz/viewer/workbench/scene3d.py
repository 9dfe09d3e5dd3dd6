"""The 3D half of a client's view: viser scene nodes drawn from a ``Scene`` and its ``Derived``.

Nothing here computes geometry: positions, rays, planes, meshes and image
content come from :func:`egtviz.scene.compute_derived`. This module only turns
arrays into nodes, keeps the nodes between updates (so a drag re-sends only what
changed) and wires the gizmos.

What is drawn, and what is skipped, to keep a frame cheap:

* projection rays, and the epipolar lines on a frustum's image plane, of every
  point while there are at most :data:`MAX_RAY_POINTS` points; above that only
  the selected point's (none when no point is selected): hundreds of fat
  segments cost a software-WebGL browser over 100 ms a frame, and read as a
  blur anyway. Likewise, above :data:`MAX_POINT_GIZMOS` points only the
  selected point has a gizmo;
* a node property is assigned only when its value changed: arrays from
  ``compute_derived`` that are the same objects as last time (an unchanged
  camera's) are skipped by identity, other arrays by comparing them with what
  the node holds; small values through a per-node cache (viser's own check
  runs only after a cast that costs tens of microseconds per property);
* the camera being dragged keeps its gizmo pose (the browser moves it).

* above :data:`MAX_LABELLED_POINTS` points only the selected and highlighted points keep their 3D numbers, as
  the panels do.

Each camera's body is drawn by its model's drawing module (``egtviz.viewer.workbench.models``: a frustum, a mirror over its
CCD, a sphere); this module knows no camera kind. Writes to viser's private handle internals are all in
``viser_adapter``. A camera's nodes, and the scene-wide ones drawn from the derived geometry, are grouped in
``scene3d_nodes``.

Scene tree (per client)::

    /egt/grid, /egt/world            ground grid (1 m cells) and world axes
    /egt/cam_<k>                     a camera's gizmo; children move with it:
        /axes, /label, and its drawing's body (/frustum; /ccd, /mirror; /sphere, /projection_centre)
    /egt/img3d_<k>_pts, _lines       pin-hole image content on the frustum's image plane
    /egt/sphere_point_<k>, /egt/great_circle_<k>   the unified camera's selected ray and epipolar great circle
    /egt/rays_<k>                    projection rays of camera k
    /egt/points, /egt/plabel_<i>     scene points and their numbers (1-based, like f_3Dwfenum)
    /egt/pgizmo_<i>                  point gizmos
    /egt/baseline, /egt/epiplane     the drawn pair's baseline, the selected point's epipolar plane
    /egt/surfaces                    sampled surfaces
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Literal

import numpy as np
import numpy.typing as npt
import viser

from .fields import on_event
from .models import DrawContext, drawing_class
from .models.common import EMPTY_PTS as _EMPTY_PTS
from .models.common import EMPTY_SEG as _EMPTY_SEG
from .models.common import colours as _colours
from .models.common import pair_colours as _pair_colours
from .models.common import segments as _segments
from .models.shared import SHARED, frozen
from ..render.palette import CAMERA_COLOURS, hex_to_rgb, point_rgb
from ..render.svg import MAX_NUMBERED_POINTS
from ..server.viser_adapter import assign as _put
from ..server.viser_adapter import assign_array as _put_array
from .scene3d_nodes import CameraNodes, WorldNodes

if TYPE_CHECKING:
    from ...scene import CameraSpec, Scene
    from ...scene.derived import Derived

#: Above this many points only the selected point gets a gizmo (200 gizmos hide the scene).
MAX_POINT_GIZMOS = 16
#: Above this many points only the selected point's projection rays are drawn (see the module docstring).
MAX_RAY_POINTS = 30
#: Above this many points only the selected and highlighted points keep their 3D labels (the panels' rule).
MAX_LABELLED_POINTS = MAX_NUMBERED_POINTS


def point_colours(n: int) -> np.ndarray:
    """(n, 3) uint8 colours of points 0..n-1."""
    return _colours(n).copy()


def _moved(current: npt.ArrayLike, new: npt.ArrayLike, tol: float = 1e-9) -> bool:
    """Any coordinate differs by more than ``tol`` (plain floats: this runs for every camera on every frame)."""
    return any(abs(a - b) > tol for a, b in zip(np.asarray(current, float).tolist(), np.asarray(new, float).tolist()))


def _quat_moved(current: npt.ArrayLike, new: npt.ArrayLike, tol: float = 1e-9) -> bool:
    """The orientation differs (``q`` and ``-q`` are the same rotation)."""
    c = np.asarray(current, float).tolist()
    n = np.asarray(new, float).tolist()
    return any(abs(a - b) > tol for a, b in zip(c, n)) and any(abs(a + b) > tol for a, b in zip(c, n))


HIGHLIGHT_RGB = (230, 159, 0)


def _slug(k: int) -> str:
    return f"/egt/cam_{k}"


def _ray_segments(rays: np.ndarray, rows: tuple[int, ...] | None, n: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Read-only float32 (S, 2, 3) segments and colours of the drawn rows of a camera's rays; None: none."""
    seg, point = _segments(rays, rows)
    return (frozen(seg), frozen(_pair_colours(n)[point])) if len(seg) else None


class Scene3D:
    """Owns one client's 3D nodes; :meth:`draw` brings them up to date with a scene snapshot."""

    def __init__(
        self,
        api: viser.SceneApi,
        on_camera_gizmo: Callable[[str, viser.TransformControlsEvent], None],
        on_point_gizmo: Callable[[int, viser.TransformControlsEvent], None],
        *,
        report: Callable[[BaseException], None] | None = None,
    ) -> None:
        self.api = api
        #: Receives whatever a gizmo callback raises (the tab shows it; see ``fields.on_event``); None: the
        #: server's log only.
        self._report = report if report is not None else (lambda exc: None)
        self._force = False
        self._on_camera_gizmo = on_camera_gizmo
        self._on_point_gizmo = on_point_gizmo
        self._cam_ids: dict[str, int] = {}
        self._next_id = 0
        self._cams: dict[str, CameraNodes] = {}
        self._rays: dict[str, viser.LineSegmentsHandle] = {}
        self._point_gizmos: dict[int, viser.TransformControlsHandle] = {}
        self._point_labels: list[viser.LabelHandle] = []
        #: Every label's handle and its size at scale 1 (presentation mode multiplies them: :meth:`set_label_scale`).
        self._labels: dict[str, tuple[viser.LabelHandle, float]] = {}
        self.label_scale = 1.0
        #: The length gizmos, axes and point marks are drawn at (metres: the scene's size, :meth:`set_glyph`).
        self.glyph = 1.0
        #: What the point nodes were last drawn for (None: draw them all again, labels included).
        self._points_key: tuple[bool, int | None, frozenset[str], frozenset[str]] | None = None
        self._points_prev = np.zeros((0, 3))
        self._static()
        self.points = api.add_point_cloud(
            "/egt/points", _EMPTY_PTS, (0, 0, 0), point_size=0.12, point_shape="circle", visible=False
        )
        self.selected = api.add_icosphere("/egt/selected", radius=0.16, color=(0, 0, 0), opacity=0.35, visible=False)
        #: The drawn pair's baseline, the epipolar plane and the surfaces, with what each last showed.
        self._scene_wide = WorldNodes(api)
        from .annotations3d import Annotations3D

        self.annotations = Annotations3D(api)

    @property
    def baseline(self) -> viser.LineSegmentsHandle:
        """The drawn pair's baseline."""
        return self._scene_wide.baseline

    @property
    def epiplane(self) -> viser.MeshHandle:
        """The selected point's epipolar plane."""
        return self._scene_wide.epiplane

    @property
    def surfaces(self) -> viser.PointCloudHandle:
        """The sampled surfaces."""
        return self._scene_wide.surfaces

    # -- static scaffolding ------------------------------------------------------

    def _static(self) -> None:
        api = self.api
        # Shadows add nothing to lines, points and frustums, and cost most of a frame in software WebGL.
        api.configure_default_lights(enabled=True, cast_shadow=False)
        api.add_grid("/egt/grid", width=20.0, height=20.0, plane="xy", cell_size=1.0, section_size=5.0)
        self._world = api.add_frame("/egt/world", axes_length=1.0, axes_radius=0.03, origin_radius=0.06)
        self._label("/egt/world/x", "x", 0.9, position=(1.15, 0.0, 0.0))
        self._label("/egt/world/y", "y", 0.9, position=(0.0, 1.15, 0.0))
        self._label("/egt/world/z", "z", 0.9, position=(0.0, 0.0, 1.15))
        self._label("/egt/grid_units", "grid: 1 m squares (world frame, z up)", 0.8, position=(-4.0, -3.0, 0.0))

    def _label(self, path: str, text: str, size: float, *, position: tuple[float, float, float] | np.ndarray,
               anchor: Literal["top-left", "bottom-left", "bottom-center"] = "top-left") -> viser.LabelHandle:
        """A screen-sized label whose size follows :attr:`label_scale` (``anchor``: viser's default unless given)."""
        handle = self.api.add_label(path, text, font_screen_scale=size * self.label_scale, position=position,
                                    anchor=anchor)
        self._labels[path] = (handle, size)
        return handle

    def set_glyph(self, glyph: float) -> None:
        """Draw the gizmos, axes and point marks ``glyph`` metres long (``egtviz.scene.extent``: a table-top scene
        of 0.4 m mirrors gets small ones, a room of cameras 10 m apart 1 m ones); labels follow their marks."""
        g = float(glyph)
        if g == self.glyph or not g > 0:
            return
        self.glyph = g
        for key, value in (("axes_length", g), ("axes_radius", 0.03 * g), ("origin_radius", 0.06 * g)):
            _put(self._world, key, value)
        for axis, k in (("x", 0), ("y", 1), ("z", 2)):
            _put(self._labels[f"/egt/world/{axis}"][0], "position", tuple(1.15 * g * (np.arange(3) == k)))
        for nodes in self._cams.values():
            self._size_camera(nodes.gizmo, nodes.axes, nodes.label)
        _put(self.points, "point_size", 0.12 * g)
        _put(self.selected, "radius", 0.16 * g)
        for gizmo in self._point_gizmos.values():
            _put(gizmo, "scale", 0.35 * g)
        self._points_key = None  # the next draw moves the point labels to the new offset

    def _size_camera(self, gizmo: viser.TransformControlsHandle, axes: viser.FrameHandle,
                     label: viser.LabelHandle) -> None:
        g = self.glyph
        _put(gizmo, "scale", g)
        for key, value in (("axes_length", 0.5 * g), ("axes_radius", 0.015 * g), ("origin_radius", 0.03 * g)):
            _put(axes, key, value)
        _put(label, "position", (0.0, -0.35 * g, 0.0))

    def set_label_scale(self, scale: float) -> None:
        """Every label at ``scale`` times its size (presentation mode: larger, to read from the back of a room)."""
        if scale == self.label_scale:
            return
        self.label_scale = scale
        for handle, size in self._labels.values():
            handle.font_screen_scale = size * scale

    # -- cameras ---------------------------------------------------------------

    def gizmo(self, name: str) -> viser.TransformControlsHandle:
        """Camera ``name``'s gizmo handle (benchmarks drive a drag through it). KeyError: no such camera."""
        return self._cams[name].gizmo

    def every_camera_nodes(self) -> dict[str, CameraNodes]:
        """Each camera's nodes by camera name (a copy of the registry)."""
        return dict(self._cams)

    def camera_nodes(self, name: str) -> CameraNodes:
        """Camera ``name``'s nodes in the 3D view (``camera_nodes(name)["frustum"]``: one by name). KeyError: no
        such camera."""
        return self._cams[name]

    def _cam_id(self, name: str) -> int:
        if name not in self._cam_ids:
            self._cam_ids[name] = self._next_id
            self._next_id += 1
        return self._cam_ids[name]

    def _build_camera(self, spec: CameraSpec, k: int, colour: tuple[int, int, int]) -> CameraNodes:
        api = self.api
        root = _slug(k)
        gizmo = api.add_transform_controls(root, scale=1.0, line_width=2.0, depth_test=False, opacity=0.85)
        name = spec.name

        def _cb(event: viser.TransformControlsEvent, name: str = name) -> None:
            self._on_camera_gizmo(name, event)

        on_event(gizmo.on_update, _cb, self._report)
        axes = api.add_frame(f"{root}/axes", axes_length=0.5, axes_radius=0.015, origin_radius=0.03)
        label = self._label(f"{root}/label", name, 1.1, position=(0.0, -0.35, 0.0), anchor="bottom-center")
        drawing = drawing_class(spec.model_kind)(api, root, k, colour)
        if self.glyph != 1.0:
            self._size_camera(gizmo, axes, label)
        self._rays[name] = api.add_line_segments(f"/egt/rays_{k}", _EMPTY_SEG, (0, 0, 0), thickness=0.008,
                                                 visible=False)
        return CameraNodes((spec.model_kind,), colour, gizmo, axes, label, drawing)

    def _sync_cameras(self, scene: Scene) -> None:
        wanted = {spec.name: spec for spec in scene.cameras}
        for name in list(self._cams):
            if name not in wanted or self._cams[name].signature != (wanted[name].model_kind,):
                self._drop_camera(name)
        for i, spec in enumerate(scene.cameras):
            if spec.name not in self._cams:
                k = self._cam_id(spec.name)
                colour = hex_to_rgb(CAMERA_COLOURS[k % len(CAMERA_COLOURS)])
                self._cams[spec.name] = self._build_camera(spec, k, colour)

    def _drop_camera(self, name: str) -> None:
        nodes = self._cams.pop(name, None)
        if nodes is not None:
            nodes.drawing.remove()
            nodes.gizmo.remove()  # removes its children
            self._labels.pop(nodes.label.name, None)
        ray = self._rays.pop(name, None)
        if ray is not None:
            ray.remove()
        self._cam_ids.pop(name, None)

    # -- points ------------------------------------------------------------------

    def _sync_points(self, scene: Scene) -> None:
        X = scene.points_array()
        n = len(X)
        opts = scene.options
        prev = self._points_prev
        key = (opts.show_labels, scene.selected_point, frozenset(k for k in scene.locked if k.startswith("point:")),
               frozenset(k for k in scene.highlighted if k.startswith("point:")))
        if key == self._points_key and (X is prev or (X.shape == prev.shape and X.tobytes() == prev.tobytes())):
            return  # a camera moved: nothing about the points changed
        relabel = self._points_key is None  # first draw, or the glyph size changed: every label moves
        self._points_key, self._points_prev = key, X
        if n:
            _put_array(self.points, "points", X.astype(np.float32))
            _put_array(self.points, "colors", np.array(_colours(n)))
        _put(self.points, "visible", n > 0)
        # Labels: one per point, 1-based.
        while len(self._point_labels) > n:
            label = self._point_labels.pop()
            self._labels.pop(label.name, None)
            label.remove()
        for i in range(len(self._point_labels), n):
            self._point_labels.append(
                self._label(f"/egt/plabel_{i}", str(i + 1), 1.0, position=tuple(X[i]), anchor="bottom-left")
            )
        # Over MAX_LABELLED_POINTS points only the selected and highlighted ones keep their numbers.
        labelled = None if n <= MAX_LABELLED_POINTS else {scene.selected_point} | {
            int(k[6:]) for k in scene.highlighted if k.startswith("point:")}
        for i, h in enumerate(self._point_labels):
            if relabel or i >= len(prev) or not np.array_equal(prev[i], X[i]):
                _put(h, "position", X[i] + 0.08 * self.glyph * np.array([1.0, 0.0, 1.0]))
            _put(h, "visible", opts.show_labels and (labelled is None or i in labelled))
        # Gizmos: every point while there are few, else only the selected one.
        sel = scene.selected_point
        want = set(range(n)) if n <= MAX_POINT_GIZMOS else ({sel} if sel is not None else set())
        for i in list(self._point_gizmos):
            if i not in want:
                self._point_gizmos.pop(i).remove()
        for i in sorted(want):
            g = self._point_gizmos.get(i)
            if g is None:
                g = self.api.add_transform_controls(
                    f"/egt/pgizmo_{i}", scale=0.35 * self.glyph, line_width=1.5, disable_rotations=True, depth_test=False,
                    opacity=0.7, position=tuple(X[i]),
                )

                def _cb(event: viser.TransformControlsEvent, i: int = i) -> None:
                    self._on_point_gizmo(i, event)

                on_event(g.on_update, _cb, self._report)
                self._point_gizmos[i] = g
            elif self._force or _moved(g.position, X[i]):
                g.position = X[i]
            locked = f"point:{i}" in scene.locked
            _put(g, "disable_axes", locked)
            _put(g, "disable_sliders", locked)
        if sel is not None and sel < n:
            _put(self.selected, "position", X[sel])
            _put(self.selected, "color", point_rgb(sel))
            _put(self.selected, "visible", True)
        else:
            _put(self.selected, "visible", False)

    # -- everything ---------------------------------------------------------------

    def draw(self, scene: Scene, derived: Derived, moving: str | None = None, *, force: bool = False) -> None:
        """Bring every node up to date. ``moving``: the camera whose gizmo the user is dragging (not re-posed).

        ``force``: put every gizmo back where the scene has it, even if its live pose cannot be compared (a
        refused drag may have left NaN there).
        """
        self._force = force
        if force:
            self._points_key = None
        try:
            self._draw(scene, derived, moving)
        finally:
            self._force = False

    def _draw(self, scene: Scene, derived: Derived, moving: str | None) -> None:
        opts = scene.options
        self.annotations.draw(scene.annotations, show_labels=opts.show_labels)  # frames, lines, mirrors (figures)
        self._sync_cameras(scene)
        X = scene.points_array()
        n = len(X)
        sel = scene.selected_point
        # Rays of every point while there are few, else only the selected point's (see the module docstring).
        ray_rows = None if n <= MAX_RAY_POINTS else ((sel,) if sel is not None and sel < n else ())
        for spec in scene.cameras:
            name = spec.name
            nodes = self._cams[name]
            wxyz, position = derived.poses[name]
            gizmo = nodes.gizmo
            if name != moving:
                # Compare with the gizmo's live pose (a drag changes it), never with a cache.
                if self._force or _moved(gizmo.position, position):
                    gizmo.position = position
                if self._force or _quat_moved(gizmo.wxyz, wxyz):
                    gizmo.wxyz = wxyz
            drawing = nodes.drawing
            look = (name in scene.locked, opts.show_frames, opts.show_labels, name in scene.highlighted)
            if nodes.look != look:
                locked, show_frames, show_labels, highlighted = look
                _put(gizmo, "disable_axes", locked)
                _put(gizmo, "disable_sliders", locked)
                _put(gizmo, "disable_rotations", locked)
                _put(nodes.axes, "visible", show_frames)
                _put(nodes.label, "visible", show_labels)
                # A camera a lesson highlights is drawn in orange.
                _put(drawing.body, "color", HIGHLIGHT_RGB if highlighted else nodes.colour)
                nodes.look = look
            plane = derived.image_planes[name]
            drawing.update(derived.cameras[name], plane, DrawContext(
                points=X, line_rows=ray_rows, selected_point=sel, selected_normal=derived.selected_normal,
                in_pair=plane.in_pair,
            ))
            rays = self._rays[name]
            src = derived.rays.get(name)
            # An unchanged camera brings the same array, hence the same prepared segments: the node is not touched.
            seg = None if src is None else SHARED.get("scene3d.rays", (src,), (ray_rows, n),
                                                      lambda: _ray_segments(src, ray_rows, n))
            if nodes.rays_seg is not seg:  # NOT_SENT before the first draw
                if seg is not None:
                    _put_array(rays, "points", seg[0])
                    _put_array(rays, "colors", seg[1])
                nodes.rays_seg = seg
            _put(rays, "visible", opts.show_rays and seg is not None)

        self._sync_points(scene)
        self._scene_wide.draw(scene, derived)

    def remove_all(self) -> None:
        """Remove every node (client teardown)."""
        self.annotations.clear()
        for name in list(self._cams):
            self._drop_camera(name)
        for g in self._point_gizmos.values():
            g.remove()
        self._point_gizmos.clear()
        for h in self._point_labels:
            h.remove()
        self._point_labels.clear()
