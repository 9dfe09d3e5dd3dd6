"""Node groups of a client's 3D view (:mod:`~egtviz.viewer.workbench.scene3d`): one camera's nodes, and the
scene-wide nodes drawn from the derived geometry (the drawn pair's baseline, the selected point's epipolar plane,
the sampled surfaces).

Each group keeps what it last sent, so that a drag re-sends only what changed (see ``scene3d``'s docstring).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .models.common import EMPTY_PTS, EMPTY_SEG
from .models.shared import SHARED, frozen
from ..render.palette import BASELINE_COLOUR, hex_to_rgb, point_rgb
from ..server.viser_adapter import assign as _put
from ..server.viser_adapter import assign_array as _put_array

if TYPE_CHECKING:
    import viser

    from ...scene import Scene
    from ...scene.derived import Derived
    from .models import CameraDrawing

__all__ = ["CameraNodes", "NOT_SENT", "WorldNodes"]

#: What a camera's rays node holds before its first segments are prepared (None means: no rays to draw).
NOT_SENT = object()


@dataclass(eq=False)
class CameraNodes:
    """One camera's nodes in the 3D view, and what they were last given.

    Attributes:
        signature: what the nodes were built for, ``(model kind,)`` (another: the camera is built again).
        colour: the camera's colour (RGB).
        gizmo: the camera's gizmo; its children move with it.
        axes: the camera's frame, a child of the gizmo.
        label: the camera's name, a child of the gizmo.
        drawing: the camera's body (``egtviz.viewer.workbench.models``).
        look: ``(locked, show_frames, show_labels, highlighted)`` as last drawn; None: not drawn yet.
        rays_seg: the prepared ray segments last assigned, compared by identity (:data:`NOT_SENT`: none yet).
    """

    signature: tuple[str]
    colour: tuple[int, int, int]
    gizmo: viser.TransformControlsHandle
    axes: viser.FrameHandle
    label: viser.LabelHandle
    drawing: CameraDrawing
    look: tuple[bool, bool, bool, bool] | None = None
    rays_seg: object = NOT_SENT

    def __getitem__(self, key: str) -> viser.SceneNodeHandle:
        """A node by name: ``gizmo``, ``axes``, ``label``, or one of the drawing's (``frustum``, ``ccd``, ...).

        Raises:
            KeyError: no node of that name.
        """
        own: dict[str, viser.SceneNodeHandle] = {"gizmo": self.gizmo, "axes": self.axes, "label": self.label}
        return own[key] if key in own else self.drawing.named_nodes()[key]


@lru_cache(maxsize=8)
def _fan(k: int) -> np.ndarray:
    """Faces (k - 2, 3) uint32 of a convex polygon of ``k`` vertices, fanned from vertex 0."""
    out = np.array([[0, i, i + 1] for i in range(1, k - 1)], np.uint32).reshape(-1, 3)
    out.setflags(write=False)
    return out


def _baseline_segment(baseline: npt.ArrayLike) -> np.ndarray:
    return frozen(np.array(baseline, np.float32)[None])


class WorldNodes:
    """The drawn pair's baseline, the selected point's epipolar plane and the sampled surfaces.

    Args:
        api: the client's scene.
    """

    def __init__(self, api: viser.SceneApi) -> None:
        self.baseline = api.add_line_segments(
            "/egt/baseline", EMPTY_SEG, hex_to_rgb(BASELINE_COLOUR), thickness=0.035, visible=False
        )
        self.epiplane = api.add_mesh_simple(
            "/egt/epiplane", np.zeros((3, 3), np.float32), np.array([[0, 1, 2]], np.uint32),
            color=(120, 120, 120), opacity=0.25, side="double", visible=False, cast_shadow=False, receive_shadow=False,
        )
        self.surfaces = api.add_point_cloud(
            "/egt/surfaces", EMPTY_PTS, (150, 150, 150), point_size=0.05, point_shape="circle", visible=False
        )
        #: The derived baseline and epipolar polygon last assigned (the same objects: nothing to send).
        self._baseline_src: np.ndarray | None = None
        self._epiplane_src: np.ndarray | None = None
        self._surf_key: object = None
        self._surf_pts = np.zeros((0, 3))

    def draw(self, scene: Scene, derived: Derived) -> None:
        """Bring the baseline, the epipolar plane and the surfaces up to date."""
        opts = scene.options
        sel = scene.selected_point
        baseline = derived.baseline
        if baseline is not None:
            if self._baseline_src is not baseline:
                _put_array(self.baseline, "points", SHARED.get("scene3d.baseline", (baseline,), None,
                                                               lambda: _baseline_segment(baseline)))
                self._baseline_src = baseline
            _put(self.baseline, "visible", True)
        else:
            _put(self.baseline, "visible", False)

        polygon = derived.epipolar_plane
        if polygon is not None and opts.show_planes:
            if self._epiplane_src is not polygon:
                V = SHARED.get("scene3d.epiplane", (polygon,), None,
                               lambda: frozen(np.asarray(polygon, np.float32)))
                _put_array(self.epiplane, "vertices", V)
                _put_array(self.epiplane, "faces", _fan(len(V)))
                self._epiplane_src = polygon
            _put(self.epiplane, "color", point_rgb(sel) if sel is not None else (120, 120, 120))
            _put(self.epiplane, "visible", True)
        else:
            _put(self.epiplane, "visible", False)

        if scene.surfaces and opts.show_surfaces:
            if self._surf_key is not scene.surfaces:
                self._surf_key, self._surf_pts = scene.surfaces, scene.surface_points()[0]
                _put_array(self.surfaces, "points", np.asarray(self._surf_pts, np.float32))
            _put(self.surfaces, "visible", len(self._surf_pts) > 0)
        else:
            _put(self.surfaces, "visible", False)
