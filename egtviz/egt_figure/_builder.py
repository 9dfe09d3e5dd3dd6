"""One EGT figure: what the drawing calls added to it, kept as the parts of a scene of the scene model.

Each drawing call is one transaction: it changes the figure, the figure is
rebuilt as a :class:`~egtviz.scene.Scene` and drawn once by the scene layer
(:func:`~egtviz.scene.compute_derived`); if that fails, the figure is put back
as it was and the reason becomes one of the figure's messages. A student's
script never fails because of a drawing.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import warnings
from collections import defaultdict
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from ..geometry.planar_mirror import split_virtual_pose
from ..scene import PanoramicSpec, PinholeSpec, Scene, SceneError, compute_derived
from ..scene.annotations import (
    Annotations,
    Frame,
    Mesh,
    PlanarMirror,
    Plot,
    PlotCircle,
    PointSet,
    Polyline,
)
from ..scene.examples import TUTORIAL_CCD
from ..scene.limits import (
    MAX_ANNOTATION_ITEMS,
    MAX_MESH_VERTICES,
    MAX_PLOT_ITEMS,
    MAX_POINTS,
    MAX_POLYLINE_VERTICES,
    MAX_TITLE_LENGTH,
    SURFACE_SIZE,
)
from ._style import parse_style

__all__ = ["Figure", "KINDS"]

#: Messages kept per figure (the newest).
MAX_MESSAGES = 20


def _columns(value: Any, rows: int, name: str) -> np.ndarray:
    """EGT columns ``(rows, N)`` (or a flat ``rows``-vector) as ``(N, rows)`` float rows."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and arr.shape[0] == rows:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != rows:
        raise ValueError(f"{name}: expected shape ({rows}, N), got {arr.shape}")
    return arr.T


def _finite_rows(P: np.ndarray) -> np.ndarray:
    return P[np.all(np.isfinite(P), axis=1)]


def _distinct_rows(*parts: np.ndarray) -> int:
    """How many different rows ``parts`` hold together (exact values; -0.0 is 0.0, as tuples compare)."""
    rows = [np.asarray(p, dtype=float) for p in parts if len(p)]
    if not rows:
        return 0
    A = np.ascontiguousarray(np.concatenate(rows) + 0.0)
    return len(np.unique(A.view(np.dtype((np.void, A.dtype.itemsize * A.shape[1]))).ravel()))


def _refuse_over(count: int, limit: int, name: str, phrase: str = "expected 0 to {limit} entries") -> None:
    """Refuse a drawing the scene would refuse for its size, before any work per item (a million points are
    refused at once). The message is the scene's own for that limit."""
    if count > limit:
        raise SceneError(f"{name}: {phrase.format(limit=limit)}, got {count}")


def _near(h: tuple[float, ...], p: tuple[float, ...]) -> bool:
    """``h`` and ``p`` are one pixel: every coordinate within ``1e-9 (1 + |p|)`` (a drawing's rounding)."""
    return all(abs(a - b) <= 1e-9 * (1.0 + abs(b)) for a, b in zip(h, p))


class _NearGrid:
    """Rows on a grid of cells at least twice the widest :func:`_near` tolerance, so a near row is in the same or
    a neighbouring cell: finding one costs a few lookups, not a pass over every row."""

    def __init__(self, rows: Iterable[tuple[float, ...]], extent: float) -> None:
        self.width = 2e-9 * (1.0 + extent)
        self.cells: defaultdict[tuple[int, ...], list[tuple[float, ...]]] = defaultdict(list)
        for r in rows:
            self.add(r)

    def _key(self, p: tuple[float, ...]) -> tuple[int, ...]:
        return tuple(math.floor(c / self.width) for c in p)

    def add(self, p: tuple[float, ...]) -> None:
        self.cells[self._key(p)].append(p)

    def holds(self, p: tuple[float, ...]) -> bool:
        key = self._key(p)
        for step in itertools.product((-1, 0, 1), repeat=len(key)):
            for h in self.cells.get(tuple(k + s for k, s in zip(key, step)), ()):
                if _near(h, p):
                    return True
        return False


def _extent(*parts: Any) -> float:
    """The largest absolute coordinate of ``parts`` (0 when empty)."""
    return max((float(np.max(np.abs(np.asarray(p, dtype=float)))) for p in parts if len(p)), default=0.0)


def _pose_matrix(H: Any, name: str = "H") -> np.ndarray:
    M = np.asarray(H, dtype=float)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise ValueError(f"{name}: expected a finite 4x4 pose, got shape {M.shape}")
    return M


def _float3(v: np.ndarray) -> tuple[float, float, float]:
    """The three entries of a 3-vector as plain floats."""
    return float(v[0]), float(v[1]), float(v[2])


def _homogeneous(v: Any) -> tuple[float, float, float]:
    """A homogeneous 3-vector scaled as ``docs/conventions.md`` says (last coordinate 1, or unit norm at infinity)."""
    e = np.asarray(v, dtype=float).reshape(3)
    norm = float(np.linalg.norm(e))
    if abs(e[2]) > 1e-12 * norm:
        e = e / e[2]
    elif norm > 0:
        e = e / norm
    return _float3(e)


def _tex_free(text: Any) -> str:
    """EGT's TeX labels (``'_{v_{1}^{[1]}}'``) as plain text (``'v_1^[1]'``)."""
    s = str(text).replace("{", "").replace("}", "")
    return s[1:] if s.startswith("_") else s


def intrinsics_from_K(K: Any) -> dict[str, Any]:
    """:class:`PinholeSpec` fields for a calibration ``K`` (focal length 1 m, so pixels per metre = K's focal
    lengths); the image is ``2 u0 x 2 v0`` pixels (2 x 2 for ``K = I``, as the tutorial's scenes)."""
    K = np.asarray(K, dtype=float)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)):
        raise ValueError(f"K: expected a finite 3x3 calibration, got shape {K.shape}")
    fx, skew, u0 = K[0]
    fy, v0 = K[1, 1], K[1, 2]
    size = [int(round(2 * c)) if c >= 1.0 else 2 for c in (u0, v0)]
    return dict(focal_length=1.0, pixels_per_metre=(float(fx), float(fy)), principal_point=(float(u0), float(v0)),
                skew=float(skew), width=size[0], height=size[1])


def image_size_from_K(K: Any) -> tuple[int, int] | None:
    """The image rectangle a K implies (``2 u0 x 2 v0``), or None when the principal point does not define one."""
    K = np.asarray(K, dtype=float)
    u0, v0 = K[0, 2], K[1, 2]
    if u0 >= 1.0 and v0 >= 1.0:
        return int(round(2 * u0)), int(round(2 * v0))
    return None


class _PlotState:
    """A plot being built: lists of rows, turned into a :class:`Plot` by :meth:`Figure.annotations`."""

    def __init__(self, number: int) -> None:
        self.number = number
        self.points: list[tuple[float, float]] = []
        self.lines: list[tuple[float, float, float]] = []
        self.line_points: list[tuple[float, float]] = []
        self.epipoles: list[tuple[float, float, float]] = []
        self.circles: list[PlotCircle] = []
        self.image_size: tuple[int, int] | None = None
        self.camera: np.ndarray | None = None
        """The pose of the camera whose image this is (None: not known)."""

    def copy(self) -> _PlotState:
        new = _PlotState(self.number)
        for key, value in self.__dict__.items():
            setattr(new, key, list(value) if isinstance(value, list) else value)
        return new

    def add_points(self, P: np.ndarray) -> None:
        """Append pixels not already there (drawing the same points twice draws them once).

        More different pixels than a plot holds are refused before any are compared one by one.
        """
        P = np.asarray(P, dtype=float).reshape(-1, 2)
        if len(self.points) + len(P) > MAX_PLOT_ITEMS:
            _refuse_over(_distinct_rows(np.array(self.points).reshape(-1, 2), P), MAX_PLOT_ITEMS, "plot points")
        grid = _NearGrid(self.points, _extent(self.points, P))
        for p in P:
            t = (float(p[0]), float(p[1]))
            if not grid.holds(t):
                self.points.append(t)
                grid.add(t)

    def holds(self, P: np.ndarray) -> bool:
        if not self.points or not len(P):
            return False
        grid = _NearGrid(self.points, _extent(self.points, P))
        return all(grid.holds((float(p[0]), float(p[1]))) for p in P)

    def plot(self) -> Plot:
        return Plot(number=self.number, points=tuple(self.points), lines=tuple(self.lines),
                    line_points=tuple(self.line_points), epipoles=tuple(self.epipoles), circles=tuple(self.circles),
                    image_size=self.image_size)


class Figure:
    """One EGT figure (``figure(n)``): cameras, points and annotations, as a :class:`Scene` on demand."""

    def __init__(self, number: int) -> None:
        self.number = number
        self.revision = 0
        """Counts the changes (each drawing call, ``clf``)."""
        self.displayed = False
        """Shown inline in a notebook already."""
        self.clear()

    # -- state ----------------------------------------------------------------------

    def clear(self) -> None:
        """Empty the figure (EGT's ``clf``)."""
        self.cameras: list[Any] = []
        self._camera_poses: list[np.ndarray] = []
        self._calibrations: list[tuple[np.ndarray, np.ndarray]] = []
        self.points: list[tuple[float, float, float]] = []
        self.items: dict[str, list[Any]] = {k: [] for k in ("frames", "polylines", "labels", "point_sets", "meshes",
                                                            "mirrors")}
        self.plots: dict[int, _PlotState] = {}
        self.messages: list[str] = []
        self._last_plot: int | None = None
        self.revision += 1

    def _snapshot(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        for key, value in state.items():
            if isinstance(value, list):
                state[key] = list(value)
        state["items"] = {k: list(v) for k, v in self.items.items()}
        state["plots"] = {k: p.copy() for k, p in self.plots.items()}
        return state

    def annotations(self) -> Annotations:
        return Annotations(
            **{k: tuple(v) for k, v in self.items.items()},
            plots=tuple(self.plots[k].plot() for k in sorted(self.plots)),
            messages=tuple(self.messages[-MAX_MESSAGES:]),
        )

    def scene(self) -> Scene:
        """The figure as a scene (checked)."""
        return Scene(cameras=tuple(self.cameras), points=tuple(self.points), annotations=self.annotations(),
                     title=f"Figure {self.number}"[:MAX_TITLE_LENGTH])

    # -- one drawing call -------------------------------------------------------------

    def draw(self, kind: str, data: dict[str, Any]) -> bool:
        """Apply one drawing; True if it was drawn. Never raises: what fails becomes a message."""
        handler: Callable[..., None] | None = getattr(self, f"_draw_{kind}", None) if isinstance(kind, str) else None
        if handler is None:
            known = ", ".join(sorted(k[len("_draw_"):] for k in dir(self) if k.startswith("_draw_")))
            self._message(f"unknown drawing {kind!r}: nothing drawn (this figure draws: {known})")
            return False
        before = self._snapshot()
        try:
            handler(**data)
            compute_derived(self.scene())  # drawable, or nothing changes
        except Exception as exc:  # noqa: BLE001 - a drawing never stops the student's script; the reason is shown
            self.__dict__.update(before)
            self._message(f"{kind}: not drawn ({exc})")
            return False
        self.revision += 1
        return True

    def _refuse_items(self, key: str, count: int) -> None:
        """Refuse ``count`` new items of kind ``key`` (``"polylines"``, ...) over the scene's limit, before any
        is made."""
        _refuse_over(len(self.items[key]) + count, MAX_ANNOTATION_ITEMS, key)

    def _message(self, text: str) -> None:
        # stacklevel: the student's line (an EGT function -> _draw -> egt_figure.draw -> Figure.draw -> here).
        warnings.warn(f"egtviz figure {self.number}: {text}", RuntimeWarning, stacklevel=6)
        self.messages.append(text[:200])
        self.revision += 1

    # -- cameras ------------------------------------------------------------------------

    def _known_camera(self, H: np.ndarray) -> int | None:
        for i, M in enumerate(self._camera_poses):
            if np.allclose(M, H, atol=1e-9):
                return i
        return None

    def _name(self, title: Any, prefix: str) -> str:
        names = {c.name for c in self.cameras}
        base = _tex_free(title).strip()[:30] if isinstance(title, str) and _tex_free(title).strip() else ""
        if base and base not in names and not base.startswith("point:"):
            return base
        k = len(self.cameras) + 1
        while f"{prefix}{k}" in names:
            k += 1
        return f"{prefix}{k}"

    def _calibration(self, H: np.ndarray) -> np.ndarray | None:
        for M, K in self._calibrations:
            if np.allclose(M, H, atol=1e-9):
                return K
        return None

    def add_pinhole(self, H: Any, title: Any = None, colour: str = "#333333") -> str:
        """A scene camera for the pose ``H`` (once per pose); a reflected ``H`` adds its mirrored frame."""
        M = _pose_matrix(H)
        known = self._known_camera(M)
        if known is not None:
            return self.cameras[known].name
        pose, flipped = split_virtual_pose(M, "H")
        name = self._name(title, "cam")
        K = self._calibration(M)
        spec = PinholeSpec(name, _float3(pose.t), PinholeSpec.ypr_from_world_rotation(pose.R))
        if K is not None:
            spec = self._with_K(spec, K)
        self.cameras.append(spec)
        self._camera_poses.append(M)
        if flipped:
            # The frustum is symmetric in x, so the proper camera's frustum is the reflected camera's; the
            # reflected (left-handed) axes are drawn as a frame of their own.
            self._draw_frame(M, colour, 0.5, f"_{{{name}}}")
        return name

    def _with_K(self, spec: PinholeSpec, K: np.ndarray) -> PinholeSpec:
        try:
            return dataclasses.replace(spec, **intrinsics_from_K(K))
        except (SceneError, ValueError) as exc:
            self._message(f"camera {spec.name}: K not used ({exc}); default intrinsics drawn")
            return spec

    def _remember_K(self, H: np.ndarray, K: np.ndarray) -> None:
        if self._calibration(H) is None:
            self._calibrations.append((H, K))
        i = self._known_camera(H)
        if i is not None and self.cameras[i].kind == "pinhole":
            self.cameras[i] = self._with_K(self.cameras[i], K)

    # -- the facade's kinds -------------------------------------------------------------

    def _draw_camera(self, H: Any, style: Any = None, scale: Any = None, frame_length: Any = None,
                     title: Any = None) -> None:
        colour = parse_style(style, "#d00000").colour
        name = self.add_pinhole(H, title, colour)
        if frame_length:
            self._draw_frame(H, style, frame_length, f"_{name}")

    def _draw_image_points(self, pixels: Any, H: Any, K: Any, figure: Any = None, style: Any = None) -> None:
        M, Kc = _pose_matrix(H), np.asarray(K, dtype=float)
        self._remember_K(M, Kc)
        plot = self._plot(figure, camera=M)
        if plot.image_size is None:
            plot.image_size = image_size_from_K(Kc)
        P = _columns(pixels, 2, "pixels")
        seen = _finite_rows(P)
        if len(seen) < len(P):
            self._message(f"Figure {plot.number}: {len(P) - len(seen)} of {len(P)} points have no image "
                          "(behind the camera); not drawn")
        plot.add_points(seen)

    def _draw_projection_rays(self, points: Any, centre: Any) -> None:
        C = np.asarray(centre, dtype=float).reshape(3)
        P = _finite_rows(_columns(points, 3, "points"))
        self._refuse_items("polylines", len(P))
        for X in P:
            self.items["polylines"].append(Polyline(points=(tuple(C), tuple(X)), colour="#777777", kind="ray"))

    def _draw_epipolar_lines(self, lines: Any, points: Any, epipole: Any, figure: Any = None,
                             style: Any = None) -> None:
        L = _columns(lines, 3, "lines")
        P = _columns(points, 2, "points")
        if len(L) != len(P):
            raise ValueError(f"lines, points: expected as many lines as points, got {len(L)} and {len(P)}")
        seen = _finite_rows(P)
        if len(seen) > MAX_PLOT_ITEMS:
            _refuse_over(_distinct_rows(seen), MAX_PLOT_ITEMS, "plot points")
        drawn = np.all(np.isfinite(L), axis=1) & np.all(np.isfinite(P), axis=1) & np.any(L[:, :2] != 0, axis=1)
        _refuse_over(int(drawn.sum()), MAX_PLOT_ITEMS, "plot lines")
        plot = self._plot(figure, points=seen)
        plot.add_points(seen)
        _refuse_over(len(plot.lines) + int(drawn.sum()), MAX_PLOT_ITEMS, "plot lines")
        for line, p in zip(L[drawn], P[drawn]):
            plot.lines.append(_float3(line / math.hypot(line[0], line[1])))
            plot.line_points.append((float(p[0]), float(p[1])))
        e = np.asarray(epipole, dtype=float).reshape(3)
        if np.all(np.isfinite(e)) and np.any(e):
            e_h = _homogeneous(e)
            if not any(np.allclose(e_h, f, atol=1e-9) for f in plot.epipoles):
                plot.epipoles.append(e_h)

    def _draw_circle(self, centre: Any, radius: Any, figure: Any = None, style: Any = None) -> None:
        plot = self._plot(figure)
        c = np.asarray(centre, dtype=float).reshape(2)
        plot.circles.append(PlotCircle(centre=(float(c[0]), float(c[1])), radius=float(radius),
                                       colour=parse_style(style).colour))

    def _draw_panoramic_points(self, points: Any, mirror_points: Any, focus: Any, style: Any = None) -> None:
        colour = parse_style(style, "#d00000").colour
        X = _columns(points, 3, "points")
        Xh = _columns(mirror_points, 3, "mirror_points")
        seen = np.all(np.isfinite(Xh), axis=1) & np.all(np.isfinite(X), axis=1)
        _refuse_over(int(seen.sum()), MAX_POLYLINE_VERTICES, "point set points", "expected 1 to {limit} entries")
        self._refuse_items("polylines", int(seen.sum()))
        self.add_points(X)
        if seen.any():
            self.items["point_sets"].append(PointSet(points=tuple(map(tuple, Xh[seen])), colour=colour))
        for a, b in zip(X[seen], Xh[seen]):
            self.items["polylines"].append(Polyline(points=(tuple(a), tuple(b)), colour=colour, kind="ray"))

    def _draw_sphere_model(self, H: Any, ell: Any, m: Any, points: Any, sphere_points: Any, style: Any = None,
                           rays: Any = False) -> None:
        colour = parse_style(style, "#0000e0").colour
        M = _pose_matrix(H)
        S = _finite_rows(_columns(sphere_points, 3, "sphere_points"))
        _refuse_over(len(S), MAX_POLYLINE_VERTICES, "point set points", "expected 1 to {limit} entries")
        if rays:
            self._refuse_items("polylines", len(S))
        self.add_points(_columns(points, 3, "points"))
        if len(S):
            self.items["point_sets"].append(PointSet(points=tuple(map(tuple, S)), colour=colour))
        if rays:
            for X in S:
                self.items["polylines"].append(Polyline(points=(tuple(M[:3, 3]), tuple(X)), colour=colour, kind="ray"))

    def _draw_normal(self, origin: Any, direction: Any, style: Any = None) -> None:
        o = np.asarray(origin, dtype=float).reshape(3)
        d = np.asarray(direction, dtype=float).reshape(3)
        self.items["polylines"].append(Polyline(points=(tuple(o), tuple(o + d)), colour=parse_style(style).colour,
                                                kind="normal"))

    def _draw_line3d(self, points: Any, style: Any = None) -> None:
        P = _columns(points, 3, "points")
        _refuse_over(len(P), MAX_POLYLINE_VERTICES, "polyline points", "expected 2 to {limit} entries")
        self.items["polylines"].append(Polyline(points=tuple(map(tuple, P)), colour=parse_style(style).colour,
                                                kind="line"))

    def _draw_scene_points(self, points: Any, style: Any = None) -> None:
        P = _finite_rows(_columns(points, 3, "points"))
        _refuse_over(len(P), MAX_POLYLINE_VERTICES, "point set points", "expected 1 to {limit} entries")
        if len(P):
            self.items["point_sets"].append(PointSet(points=tuple(map(tuple, P)),
                                                     colour=parse_style(style, "#d00000").colour))

    def _draw_surface(self, x: Any, y: Any, z: Any, nx: Any = None, ny: Any = None, nz: Any = None) -> None:
        X, Y, Z = (np.asarray(a, dtype=float) for a in (x, y, z))
        if X.ndim != 2 or X.shape != Y.shape or X.shape != Z.shape or min(X.shape) < 2:
            raise ValueError(
                f"x, y, z: expected three (n, m) grids with n, m >= 2, got {X.shape}, {Y.shape}, {Z.shape}")
        n, m = X.shape
        have = sum(len(mesh.vertices) for mesh in self.items["meshes"])
        _refuse_over(have + n * m, MAX_MESH_VERTICES, "meshes", "at most {limit} vertices in all")
        V = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
        idx = np.arange(n * m).reshape(n, m)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
        faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        self.items["meshes"].append(Mesh(vertices=tuple(map(tuple, V)), faces=tuple(map(tuple, faces.tolist())),
                                         colour="#9ab8d8", opacity=0.6))

    # -- the front-end's own kinds (EGT's drawing functions) ---------------------------------------

    def _draw_frame(self, H: Any, style: Any = None, length: Any = 1.0, label: Any = "") -> None:
        """A frame; a left-handed one (a reflected camera's) is labelled ``mirrored``. A frame drawn again at the
        same pose replaces the earlier one."""
        M = _pose_matrix(H)
        text = str(label or "").replace("{", "").replace("}", "")
        frame = Frame(origin=tuple(M[:3, 3]), axes=tuple(map(tuple, M[:3, :3].T)), length=float(length or 1.0),
                      colour=parse_style(style).colour, label=text)
        if frame.mirrored:
            frame = dataclasses.replace(frame, label=f"{text} (mirrored)")
        frames = self.items["frames"]
        same = [i for i, f in enumerate(frames) if np.allclose(f.origin, frame.origin, atol=1e-9)
                and np.allclose(f.axes, frame.axes, atol=1e-9)]
        if same:
            frames[same[0]] = frame
        else:
            frames.append(frame)

    def _draw_panoramic_camera(self, H: Any, style: Any = None, quadric: Any = 1, a: Any = 3.0, b: Any = 1.0,
                               title: Any = None) -> None:
        M = _pose_matrix(H)
        if self._known_camera(M) is not None:
            return
        if int(quadric) not in (1, 2):
            raise ValueError(f"quadric: expected 1 (hyperbolic) or 2 (parabolic), got {quadric!r}")
        name = self._name(title, "pano")
        ypr = PanoramicSpec.ypr_from_world_rotation(M[:3, :3])
        spec = PanoramicSpec(name, _float3(M[:3, 3]), ypr,
                             mirror="hyperbolic" if int(quadric) == 1 else "parabolic", a=float(a), b=float(b),
                             **TUTORIAL_CCD)
        self.cameras.append(spec)
        self._camera_poses.append(M)

    def add_points(self, P: np.ndarray) -> None:
        """Scene points (rows), skipping non-finite ones and points the figure already has.

        More different points than a scene holds are refused before any are added one by one.
        """
        P = _finite_rows(np.asarray(P, dtype=float).reshape(-1, 3))
        if len(self.points) + len(P) > MAX_POINTS:
            _refuse_over(_distinct_rows(np.array(self.points).reshape(-1, 3), P), MAX_POINTS, "points",
                         "at most {limit}")
        have = set(self.points)
        for p in P:
            t = (float(p[0]), float(p[1]), float(p[2]))
            if t not in have:
                self.points.append(t)
                have.add(t)

    def _draw_world_points(self, points: Any, style: Any = None) -> None:
        self.add_points(_columns(points, 3, "points"))

    def _draw_numbered_points(self, points: Any, numbers: Any = None, style: Any = None, offset: Any = 0.0) -> None:
        P = _columns(points, 3, "points")
        keep = np.all(np.isfinite(P), axis=1)
        _refuse_over(int(keep.sum()), MAX_POLYLINE_VERTICES, "point set points", "expected 1 to {limit} entries")
        nums = list(range(1, len(P) + 1)) if numbers is None else [int(k) for k in np.asarray(numbers).reshape(-1)]
        if len(nums) != len(P):
            raise ValueError(f"numbers: expected one per point ({len(P)}), got {len(nums)}")
        if keep.any():
            self.items["point_sets"].append(PointSet(
                points=tuple(map(tuple, P[keep])), colour=parse_style(style, "#d00000").colour, numbered=True,
                numbers=tuple(k for k, ok in zip(nums, keep) if ok)))

    def _draw_plane(self, normal: Any, distance: Any, xlimit: Any = (-10, 10), ylimit: Any = (-10, 10),
                    zlimit: Any = (-10, 10), reflects: Any = "", virtual: Any = "") -> None:
        box = np.array([np.asarray(lim, dtype=float).reshape(2) for lim in (xlimit, ylimit, zlimit)])
        centre = box.mean(axis=1)
        size = float(np.clip(np.ptp(box, axis=1).max(), SURFACE_SIZE.low, SURFACE_SIZE.high))
        self.items["mirrors"].append(PlanarMirror(normal=tuple(np.asarray(normal, float).reshape(3)),
                                                  distance=float(distance), centre=tuple(centre), size=size,
                                                  reflects=str(reflects), virtual=str(virtual)))

    # -- plots -----------------------------------------------------------------------------------

    def _plot(self, figure: Any = None, *, camera: np.ndarray | None = None,
              points: np.ndarray | None = None) -> _PlotState:
        """The plot a 2D drawing goes to: figure ``n`` if given, else the plot of the same camera (or holding the
        same points), else a new one with the next free number."""
        number = None
        if isinstance(figure, (int, np.integer)) and not isinstance(figure, bool) and figure >= 1:
            number = int(figure)
        elif camera is not None:
            number = next((n for n, p in self.plots.items() if p.camera is not None
                           and np.allclose(p.camera, camera, atol=1e-9)), None)
        elif points is not None:
            number = next((n for n, p in self.plots.items() if p.holds(points)), None)
        elif self._last_plot is not None:
            number = self._last_plot
        if number is None:
            number = max(self.plots, default=0) + 1
        plot = self.plots.get(number)
        if plot is None:
            plot = self.plots[number] = _PlotState(number)
        if camera is not None and plot.camera is None:
            plot.camera = camera
        self._last_plot = number
        return plot


#: Every kind :meth:`Figure.draw` handles.
KINDS = tuple(sorted(k[len("_draw_"):] for k in dir(Figure) if k.startswith("_draw_")))
