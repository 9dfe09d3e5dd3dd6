"""The pin-hole camera in 3D: its frustum, and its image (points and epipolar lines) on the frustum's image plane."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ...server.viser_adapter import assign, assign_array
from . import CameraDrawing, DrawContext
from .common import EMPTY_PTS, EMPTY_SEG, colours, pair_colours, segments
from .shared import SHARED, frozen

if TYPE_CHECKING:
    import viser

    from ....geometry.pinhole import PinholeCamera
    from ....scene.derived import ImagePlane

#: Depth of the drawn image plane in front of the centre, scene units.
IMAGE_PLANE_DEPTH = 0.6


class PinholeDrawing(CameraDrawing["PinholeCamera"]):
    """A frustum whose image plane lies ``IMAGE_PLANE_DEPTH`` in front of the centre, with the image drawn on it."""

    def __init__(self, api: viser.SceneApi, root: str, k: int, colour: tuple[int, int, int]) -> None:
        super().__init__(api, root, k, colour)
        self.frustum = api.add_camera_frustum(f"{root}/frustum", fov=0.6, aspect=4 / 3, scale=0.3, color=colour,
                                              thickness=0.012)
        self.img_pts = api.add_point_cloud(f"/egt/img3d_{k}_pts", EMPTY_PTS, (0, 0, 0), point_size=0.03,
                                           point_shape="circle", visible=False)
        self.img_lines = api.add_line_segments(f"/egt/img3d_{k}_lines", EMPTY_SEG, (0, 0, 0), thickness=0.006,
                                               visible=False)
        self._shape: tuple[float, float, float] | None = None
        # The prepared arrays last assigned, compared by identity (None: nothing to draw; False: none yet).
        self._pts_src: object = False
        self._lines_key: object = False

    def named_nodes(self) -> dict[str, viser.SceneNodeHandle]:
        return {"frustum": self.frustum, "img_pts": self.img_pts, "img_lines": self.img_lines}

    @property
    def body(self) -> viser.CameraFrustumHandle:
        return self.frustum

    def update(self, camera: PinholeCamera, plane: ImagePlane, ctx: DrawContext) -> None:
        # Each array is prepared once per derived camera and plane (SHARED: a classroom's followers draw the
        # instructor's), and assigned only when this drawing holds another one.
        shape = SHARED.get("pinhole.shape", (camera,), None, lambda: _frustum_shape(camera))
        if shape != self._shape:
            fov, aspect, scale = shape
            assign(self.frustum, "fov", fov)
            assign(self.frustum, "aspect", aspect)
            assign(self.frustum, "scale", scale)
            self._shape = shape
        pts = SHARED.get("pinhole.points", (camera, plane.points, plane.visible), None,
                         lambda: _image_points(camera, plane))
        if pts is not self._pts_src:
            if pts is not None:
                assign_array(self.img_pts, "points", pts[0])
                assign_array(self.img_pts, "colors", pts[1])
            assign(self.img_pts, "visible", pts is not None)
            self._pts_src = pts
        lines = SHARED.get("pinhole.lines", (camera, plane.lines, plane.points), ctx.line_rows,
                           lambda: _image_lines(camera, plane, ctx.line_rows))
        if lines is not self._lines_key:
            if lines is not None:
                assign_array(self.img_lines, "points", lines[0])
                assign_array(self.img_lines, "colors", lines[1])
            assign(self.img_lines, "visible", lines is not None)
            self._lines_key = lines

    def remove(self) -> None:
        self.img_pts.remove()
        self.img_lines.remove()


def _frustum_shape(camera: PinholeCamera) -> tuple[float, float, float]:
    """``(fov, aspect, scale)`` of the frustum node that puts the image plane at ``IMAGE_PLANE_DEPTH``."""
    K = camera.projective_calibration
    fov, aspect = 2.0 * math.atan2(camera.height / 2.0, float(K[1, 1])), camera.width / camera.height
    y = math.tan(fov / 2.0)
    # viser normalises the frustum to unit volume; undo that so the image plane sits at IMAGE_PLANE_DEPTH.
    return fov, aspect, IMAGE_PLANE_DEPTH * float(np.cbrt(y * aspect * y / 3.0))


def _image_points(camera: PinholeCamera, plane: ImagePlane) -> tuple[np.ndarray, np.ndarray] | None:
    """float32 (M, 3) points and (M, 3) colours of the imaged points on the image plane in 3D; None: none."""
    ok = np.flatnonzero(plane.visible)
    if not len(ok):
        return None
    P = camera.image_to_world(plane.points[ok], IMAGE_PLANE_DEPTH, check=False)  # derived pixels
    return frozen(P.astype(np.float32)), frozen(np.ascontiguousarray(colours(len(plane.points))[ok]))


def _image_lines(camera: PinholeCamera, plane: ImagePlane,
                 line_rows: tuple[int, ...] | None) -> tuple[np.ndarray, np.ndarray] | None:
    """float32 (S, 2, 3) segments and (S, 2, 3) colours of the drawn epipolar lines on the image plane in 3D
    (above MAX_RAY_POINTS points, the selected point's only: ``line_rows``); None: none."""
    L = plane.lines
    if L is None or not len(L):
        return None
    rows = np.arange(len(L)) if line_rows is None else np.asarray(line_rows, np.intp)
    hit = rows[np.isfinite(L[rows]).all(axis=(1, 2))]
    lines3 = np.full((len(L), 2, 3), np.nan)
    if len(hit):
        lines3[hit] = camera.image_to_world(L[hit].reshape(-1, 2), IMAGE_PLANE_DEPTH, check=False).reshape(-1, 2, 3)
    seg, point = segments(lines3, line_rows)
    if not len(seg):
        return None
    return frozen(seg), frozen(np.ascontiguousarray(pair_colours(len(plane.points))[point]))
