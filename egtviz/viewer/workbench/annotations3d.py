"""The 3D part of a figure's annotations (:mod:`egtviz.scene.annotations`) as viser nodes.

Nothing is computed here beyond layout: frames become three segments with the
axis names at their tips, polylines segments, point sets point clouds (with
their numbers), meshes and plane mirrors translucent meshes (a mirror with its
outline). Lines are a few screen pixels thick whatever the scene's scale (EGT's
figures range from centimetre mirrors to 20 m scenes). A figure changes only
when a drawing call or a file changes it, so the nodes are rebuilt whenever the
annotations differ from the last ones drawn.

Scene tree::

    /egt/annot/frames, /egt/annot/frame_<i>_<x|y|z>     frames and their axis names
    /egt/annot/lines_<kind>                             polylines of one kind (line, ray, normal, outline)
    /egt/annot/labels_<i>                               texts
    /egt/annot/points_<i>, /egt/annot/points_<i>_<j>    point sets and their numbers
    /egt/annot/mesh_<i>                                 meshes
    /egt/annot/mirror_<i>, /egt/annot/mirror_<i>_edge   plane mirrors
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..render.palette import hex_to_rgb

if TYPE_CHECKING:
    import viser

    from ...scene.annotations import Annotations

__all__ = ["Annotations3D"]

#: Line thickness in screen pixels.
LINE_PX = 2.0
FRAME_PX = 3.0
MIRROR_RGB = (150, 190, 230)


def _segments(polyline_points: npt.ArrayLike) -> np.ndarray:
    P = np.asarray(polyline_points, np.float32)
    return np.stack([P[:-1], P[1:]], axis=1)


class Annotations3D:
    """Owns one client's annotation nodes; :meth:`draw` shows a scene's :class:`Annotations`."""

    def __init__(self, api: viser.SceneApi) -> None:
        self.api = api
        self._drawn: tuple[Annotations | None, bool] | None = None
        self._nodes: list[viser.SceneNodeHandle] = []
        #: Nodes drawn per kind (``frames``, ``frame_labels``, ``segments``, ``labels``, ``point_sets``, ``meshes``,
        #: ``mirrors``): what the tests count.
        self.counts: dict[str, int] = {}

    def clear(self) -> None:
        for node in self._nodes:
            node.remove()
        self._nodes = []
        self.counts = {}
        self._drawn = None

    def draw(self, annotations: Annotations | None, *, show_labels: bool = True) -> None:
        """Bring the nodes up to date with ``annotations`` (nothing happens if they did not change)."""
        key = (annotations, show_labels)
        if self._drawn is not None and (self._drawn[0] is annotations or self._drawn == key):
            return
        self.clear()
        self._drawn = key
        if annotations is None or annotations.empty:
            return
        api, add = self.api, self._nodes.append
        counts = {"frames": 0, "frame_labels": 0, "segments": 0, "labels": 0, "point_sets": 0, "meshes": 0,
                  "mirrors": 0}

        if annotations.frames:
            segs, cols = [], []
            for i, f in enumerate(annotations.frames):
                o = np.asarray(f.origin)
                rgb = hex_to_rgb(f.colour)
                for axis, name in zip(f.axes, "XYZ"):
                    tip = o + f.length * np.asarray(axis)
                    segs.append([o, tip])
                    cols.append([rgb, rgb])
                    if show_labels:
                        add(api.add_label(f"/egt/annot/frame_{i}_{name.lower()}", f"{name}{f.label}",
                                          position=tuple(tip), font_screen_scale=0.8))
                        counts["frame_labels"] += 1
            add(api.add_line_segments("/egt/annot/frames", np.asarray(segs, np.float32),
                                      np.asarray(cols, np.uint8), thickness=FRAME_PX, thickness_units="screen"))
            counts["frames"] = len(annotations.frames)

        by_kind: dict[str, tuple[list[np.ndarray], list[np.ndarray]]] = {}
        for pl in annotations.polylines:
            seg = _segments(pl.points)
            kind_segs, kind_cols = by_kind.setdefault(pl.kind, ([], []))
            kind_segs.append(seg)
            kind_cols.append(np.broadcast_to(np.array(hex_to_rgb(pl.colour), np.uint8), seg.shape).copy())
        for kind, (kind_segs, kind_cols) in by_kind.items():
            S = np.concatenate(kind_segs)
            add(api.add_line_segments(f"/egt/annot/lines_{kind}", S, np.concatenate(kind_cols), thickness=LINE_PX,
                                      thickness_units="screen"))
            counts["segments"] += len(S)

        for i, lab in enumerate(annotations.labels):
            add(api.add_label(f"/egt/annot/labels_{i}", lab.text, position=lab.position, font_screen_scale=0.9))
            counts["labels"] += 1

        for i, ps in enumerate(annotations.point_sets):
            P = np.asarray(ps.points, np.float32)
            span = float(np.ptp(P, axis=0).max()) if len(P) > 1 else 1.0
            add(api.add_point_cloud(f"/egt/annot/points_{i}", P, hex_to_rgb(ps.colour),
                                    point_size=max(0.01 * span, 1e-3), point_shape="diamond"))
            counts["point_sets"] += 1
            if ps.numbered and show_labels:
                for j, (p, text) in enumerate(zip(P, ps.labels)):
                    add(api.add_label(f"/egt/annot/points_{i}_{j}", text, position=tuple(p), font_screen_scale=0.8,
                                      anchor="bottom-left"))
                    counts["labels"] += 1

        for i, m in enumerate(annotations.meshes):
            add(api.add_mesh_simple(f"/egt/annot/mesh_{i}", np.asarray(m.vertices, np.float32),
                                    np.asarray(m.faces, np.uint32), color=hex_to_rgb(m.colour), opacity=m.opacity,
                                    side="double", cast_shadow=False, receive_shadow=False))
            counts["meshes"] += 1

        for i, mirror in enumerate(annotations.mirrors):
            C = mirror.corners.astype(np.float32)
            add(api.add_mesh_simple(f"/egt/annot/mirror_{i}", C, np.array([[0, 1, 2], [0, 2, 3]], np.uint32),
                                    color=MIRROR_RGB, opacity=0.35, side="double", cast_shadow=False,
                                    receive_shadow=False))
            edge = np.stack([C, np.roll(C, -1, axis=0)], axis=1)
            add(api.add_line_segments(f"/egt/annot/mirror_{i}_edge", edge, (70, 110, 160), thickness=LINE_PX,
                                      thickness_units="screen"))
            counts["mirrors"] += 1
        self.counts = counts
