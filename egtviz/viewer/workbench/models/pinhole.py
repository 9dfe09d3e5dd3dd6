"""The pin-hole camera in 3D: its frustum, and its image (points and epipolar lines) on the frustum's image plane."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ...server.viser_adapter import assign, assign_array
from . import CameraDrawing, DrawContext
from .common import EMPTY_PTS, EMPTY_SEG, colours, pair_colours, segments

if TYPE_CHECKING:
    from ....geometry.pinhole import PinholeCamera
    from ....scene.derived import ImagePlane

#: Depth of the drawn image plane in front of the centre, scene units.
IMAGE_PLANE_DEPTH = 0.6


class PinholeDrawing(CameraDrawing["PinholeCamera"]):
    """A frustum whose image plane lies ``IMAGE_PLANE_DEPTH`` in front of the centre, with the image drawn on it."""

    def __init__(self, api: Any, root: str, k: int, colour: tuple[int, int, int]) -> None:
        super().__init__(api, root, k, colour)
        self.frustum = api.add_camera_frustum(f"{root}/frustum", fov=0.6, aspect=4 / 3, scale=0.3, color=colour,
                                              thickness=0.012)
        self.img_pts = api.add_point_cloud(f"/egt/img3d_{k}_pts", EMPTY_PTS, (0, 0, 0), point_size=0.03,
                                           point_shape="circle", visible=False)
        self.img_lines = api.add_line_segments(f"/egt/img3d_{k}_lines", EMPTY_SEG, (0, 0, 0), thickness=0.006,
                                               visible=False)
        self._shape: tuple[float, float] | None = None
        self._pts_src: Any = None
        self._lines_key: Any = None

    def named_nodes(self) -> dict[str, Any]:
        return {"frustum": self.frustum, "img_pts": self.img_pts, "img_lines": self.img_lines}

    @property
    def body(self) -> Any:
        return self.frustum

    def update(self, camera: PinholeCamera, plane: ImagePlane, ctx: DrawContext) -> None:
        K = camera.projective_calibration
        shape = (2.0 * math.atan2(camera.height / 2.0, float(K[1, 1])), camera.width / camera.height)
        if shape != self._shape:
            fov, aspect = shape
            y = math.tan(fov / 2.0)
            # viser normalises the frustum to unit volume; undo that so the image plane sits at IMAGE_PLANE_DEPTH.
            scale = IMAGE_PLANE_DEPTH * float(np.cbrt(y * aspect * y / 3.0))
            assign(self.frustum, "fov", fov)
            assign(self.frustum, "aspect", aspect)
            assign(self.frustum, "scale", scale)
            self._shape = shape
        n = len(plane.points)
        if self._pts_src is not plane.points:  # an unchanged camera brings the same array
            ok = np.flatnonzero(plane.visible)
            if len(ok):
                P = camera.image_to_world(plane.points[ok], IMAGE_PLANE_DEPTH, check=False)  # derived pixels
                assign_array(self.img_pts, "points", P.astype(np.float32))
                assign_array(self.img_pts, "colors", np.ascontiguousarray(colours(n)[ok]))
            assign(self.img_pts, "visible", len(ok) > 0)
            self._pts_src = plane.points
        old = self._lines_key
        if old is None or old[0] is not plane.lines or old[1] is not camera or old[2] != ctx.line_rows:
            L = plane.lines
            seg: np.ndarray | tuple[()] = ()
            point: np.ndarray | tuple[()] = ()
            if L is not None and len(L):
                # Only the drawn rows (above MAX_RAY_POINTS points, the selected point's) go to the image plane in 3D.
                rows = np.arange(len(L)) if ctx.line_rows is None else np.asarray(ctx.line_rows, np.intp)
                hit = rows[np.isfinite(L[rows]).all(axis=(1, 2))]
                lines3 = np.full((len(L), 2, 3), np.nan)
                if len(hit):
                    lines3[hit] = camera.image_to_world(L[hit].reshape(-1, 2), IMAGE_PLANE_DEPTH,
                                                        check=False).reshape(-1, 2, 3)
                seg, point = segments(lines3, ctx.line_rows)
                if len(seg):
                    assign_array(self.img_lines, "points", seg)
                    assign_array(self.img_lines, "colors", np.ascontiguousarray(pair_colours(n)[point]))
            assign(self.img_lines, "visible", len(seg) > 0)
            self._lines_key = (plane.lines, camera, ctx.line_rows)

    def remove(self) -> None:
        self.img_pts.remove()
        self.img_lines.remove()
