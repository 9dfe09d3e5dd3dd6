"""What a figure holds beyond cameras and points: frames, 3D polylines, labels, point sets, meshes, planar
mirrors and 2D plots (frozen, serialisable, checked like the rest of a scene).

EGT drew these with ``plot3``/``text``/``surf`` into a MATLAB figure; here they
are part of the :class:`~egtviz.scene.Scene`, so a figure is saved, loaded and
drawn like any scene (3D: ``egtviz.viewer.workbench.annotations3d``; plots:
``egtviz.viewer.render.plot_svg``). Colours are ``"#rrggbb"``; coordinates are world
coordinates (metres) for 3D items and pixels for plots.

A :class:`PlanarMirror` may *reflect* a pin-hole camera of the scene: the
scene then keeps a second pin-hole camera, the mirror image of the first,
up to date whenever the first one moves (:func:`resolve_reflections`). A
reflected frame is left-handed, which a camera pose cannot be, so the scene
holds the *proper* virtual camera: the reflected frame with its x axis
reversed,

.. math:: R_p = (I - 2 n n^T) R\\, S, \\quad t_p = t - 2 (n \\cdot t - d) n, \\quad S = \\mathrm{diag}(-1, 1, 1).

Its pixels are the real camera's pixels of the reflected scene mirrored by
:math:`M = K S K^{-1}` (left and right swapped about the principal point), so
the F of the (real, proper virtual) pair is :math:`F = M^T [e]_\\times` with
:math:`e = K R^T n` the vanishing point of the mirror normal: the planar
mirror's skew-symmetric F up to that image flip.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from .limits import (
    COORDINATE,
    FRAME_AXIS_LENGTH,
    IMAGE_SIZE,
    MAX_ANNOTATION_ITEMS,
    MAX_MESH_VERTICES,
    MAX_NAME_LENGTH,
    MAX_PLOT_ITEMS,
    MAX_PLOTS,
    MAX_POLYLINE_VERTICES,
    MAX_TEXT_LENGTH,
    MESH_OPACITY,
    PLOT_COORDINATE,
    SURFACE_SIZE,
    Range,
)
from ._values import SceneError, as_pair, as_ranged, as_triple, has_control_characters, required_fields, short_text
from .cameras.pinhole import PinholeSpec

__all__ = [
    "ANNOTATION_KINDS",
    "Annotations",
    "Frame",
    "Label",
    "MAX_ANNOTATION_ITEMS",
    "MAX_MESH_VERTICES",
    "MAX_PLOTS",
    "MAX_PLOT_ITEMS",
    "MAX_POLYLINE_VERTICES",
    "MAX_TEXT_LENGTH",
    "Mesh",
    "POLYLINE_KINDS",
    "PlanarMirror",
    "Plot",
    "PlotCircle",
    "PointSet",
    "Polyline",
    "annotations_from_dict",
    "annotations_to_dict",
    "resolve_reflections",
    "virtual_camera_spec",
]

_COLOUR = re.compile(r"#[0-9a-fA-F]{6}")


def _colour(value: Any, name: str) -> str:
    if type(value) is not str or _COLOUR.fullmatch(value) is None:
        raise SceneError(f"{name}: expected a colour '#rrggbb', got {short_text(value)}")
    return value.lower()


def _text(value: Any, name: str, *, empty: bool = True) -> str:
    if type(value) is not str or len(value) > MAX_TEXT_LENGTH or has_control_characters(value) or (
        not empty and not value.strip()
    ):
        raise SceneError(f"{name}: expected text of at most {MAX_TEXT_LENGTH} characters without control "
                         f"characters, got {short_text(value)}")
    return value


def _tuple_of(value: Any, name: str, limit: int, minimum: int = 0) -> tuple:
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (tuple, list)):
        raise SceneError(f"{name}: expected a list, got {short_text(value)}")
    if not minimum <= len(value) <= limit:
        raise SceneError(f"{name}: expected {minimum} to {limit} entries, got {len(value)}")
    return tuple(value)


def _triples(value: Any, name: str, limit: int, minimum: int = 0,
             bound: Range = COORDINATE) -> tuple[tuple[float, float, float], ...]:
    return tuple(as_triple(p, f"{name}[{i}]", bound) for i, p in enumerate(_tuple_of(value, name, limit, minimum)))


def _pairs(value: Any, name: str, limit: int) -> tuple[tuple[float, float], ...]:
    return tuple(as_pair(p, f"{name}[{i}]", PLOT_COORDINATE) for i, p in enumerate(_tuple_of(value, name, limit)))


def _homogeneous(value: Any, name: str, limit: int) -> tuple[tuple[float, float, float], ...]:
    """3-vectors up to scale (lines, epipoles): finite, not all zero, any magnitude up to ``PLOT_COORDINATE``."""
    out = _triples(value, name, limit, bound=PLOT_COORDINATE)
    for i, v in enumerate(out):
        if not any(v):
            raise SceneError(f"{name}[{i}]: expected a non-zero homogeneous 3-vector, got {v}")
    return out


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class Frame:
    """A coordinate frame drawn as three axes (EGT's ``f_3Dframe``, ``f_3Dwf``); may be left-handed."""

    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axes: tuple[tuple[float, float, float], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    """The x, y and z axis directions in world coordinates (unit vectors, mutually orthogonal). A
    reflected camera's frame has determinant -1 (:attr:`mirrored`)."""
    length: float = 1.0
    """Drawn length of each axis (metres)."""
    colour: str = "#333333"
    label: str = ""
    """Subscript of the axis names: ``X<label>``, ``Y<label>``, ``Z<label>``."""

    def __post_init__(self) -> None:
        _set(self, "origin", as_triple(self.origin, "frame origin"))
        axes = _triples(self.axes, "frame axes", 3, 3, Range(-1.0 - 1e-9, 1.0 + 1e-9))
        A = np.array(axes)
        if np.abs(A @ A.T - np.eye(3)).max() > 1e-6:
            raise SceneError("frame axes: expected three orthonormal directions")
        _set(self, "axes", axes)
        _set(self, "length", as_ranged(self.length, FRAME_AXIS_LENGTH, "frame length"))
        _set(self, "colour", _colour(self.colour, "frame colour"))
        _set(self, "label", _text(self.label, "frame label"))

    @property
    def mirrored(self) -> bool:
        """The frame is left-handed (a reflection): ``det [x y z] < 0``."""
        return float(np.linalg.det(np.array(self.axes))) < 0.0


#: What a polyline shows (the viewer groups and colours by it; tests count by it).
POLYLINE_KINDS = ("line", "ray", "normal", "outline")


@dataclass(frozen=True)
class Polyline:
    """Connected 3D segments: a 3D line, projection rays, a normal, a drawn outline."""

    points: tuple[tuple[float, float, float], ...] = ()
    """Two or more vertices in world coordinates."""
    colour: str = "#333333"
    kind: str = "line"
    """One of :data:`POLYLINE_KINDS`."""

    def __post_init__(self) -> None:
        _set(self, "points", _triples(self.points, "polyline points", MAX_POLYLINE_VERTICES, 2))
        _set(self, "colour", _colour(self.colour, "polyline colour"))
        if self.kind not in POLYLINE_KINDS:
            raise SceneError(f"polyline kind: expected one of {list(POLYLINE_KINDS)}, got {short_text(self.kind)}")


@dataclass(frozen=True)
class Label:
    """A text in the 3D view (EGT's ``text``)."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    text: str = ""
    colour: str = "#333333"

    def __post_init__(self) -> None:
        _set(self, "position", as_triple(self.position, "label position"))
        _set(self, "text", _text(self.text, "label text", empty=False))
        _set(self, "colour", _colour(self.colour, "label colour"))


@dataclass(frozen=True)
class PointSet:
    """Coloured 3D points that are not scene points (mirror points, reflections, sphere points)."""

    points: tuple[tuple[float, float, float], ...] = ()
    colour: str = "#d62728"
    numbered: bool = False
    """Write each point's 1-based number next to it (EGT's ``f_3Dreflenum``)."""
    numbers: tuple[int, ...] = ()
    """The numbers to write (default ``1..N``)."""

    def __post_init__(self) -> None:
        _set(self, "points", _triples(self.points, "point set points", MAX_POLYLINE_VERTICES, 1))
        _set(self, "colour", _colour(self.colour, "point set colour"))
        if type(self.numbered) is not bool:
            raise SceneError(f"point set numbered: expected true or false, got {short_text(self.numbered)}")
        numbers = _tuple_of(self.numbers, "point set numbers", MAX_POLYLINE_VERTICES)
        if numbers and (len(numbers) != len(self.points) or not all(
            type(k) is int and 0 <= k < 10**9 for k in numbers
        )):
            raise SceneError(f"point set numbers: expected {len(self.points)} whole numbers 0..1e9, "
                             f"got {short_text(self.numbers)}")
        _set(self, "numbers", numbers)

    @property
    def labels(self) -> tuple[str, ...]:
        """The number written next to each point."""
        return tuple(str(k) for k in (self.numbers or range(1, len(self.points) + 1)))


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh (EGT's ``f_3Dsurface`` drawing, a panoramic mirror)."""

    vertices: tuple[tuple[float, float, float], ...] = ()
    faces: tuple[tuple[int, int, int], ...] = ()
    colour: str = "#9ab8d8"
    opacity: float = 0.5

    def __post_init__(self) -> None:
        _set(self, "vertices", _triples(self.vertices, "mesh vertices", MAX_MESH_VERTICES, 3))
        faces = _tuple_of(self.faces, "mesh faces", 2 * MAX_MESH_VERTICES, 1)
        n = len(self.vertices)
        checked = []
        for i, f in enumerate(faces):
            f = tuple(f) if isinstance(f, (list, tuple)) else f
            if type(f) is not tuple or len(f) != 3 or not all(type(k) is int and 0 <= k < n for k in f):
                raise SceneError(f"mesh faces[{i}]: expected three vertex indices below {n}, got {short_text(f)}")
            checked.append(f)
        _set(self, "faces", tuple(checked))
        _set(self, "colour", _colour(self.colour, "mesh colour"))
        _set(self, "opacity", as_ranged(self.opacity, MESH_OPACITY, "mesh opacity"))


@dataclass(frozen=True)
class PlanarMirror:
    r"""A plane mirror :math:`n \cdot X = d`, drawn as a square of side ``size`` about ``centre``.

    With ``reflects`` (a pin-hole camera's name) the scene keeps the camera
    ``virtual`` as that camera's proper virtual camera (module docstring).
    """

    normal: tuple[float, float, float] = (0.0, 1.0, 0.0)
    """Unit normal (any non-zero vector is normalised)."""
    distance: float = 0.0
    """Signed distance of the plane from the world origin along ``normal``."""
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Where the drawn square is centred (projected onto the plane)."""
    size: float = 2.0
    reflects: str = ""
    virtual: str = ""

    def __post_init__(self) -> None:
        n = np.array(as_triple(self.normal, "mirror normal"))
        norm = float(np.linalg.norm(n))
        if not norm > 1e-9:
            raise SceneError(f"mirror normal: expected a non-zero vector, got {short_text(self.normal)}")
        _set(self, "normal", tuple(float(v) for v in n / norm))
        _set(self, "distance", as_ranged(self.distance, COORDINATE, "mirror distance"))
        c = np.array(as_triple(self.centre, "mirror centre"))
        nn = np.array(self.normal)
        c = c - (c @ nn - self.distance) * nn
        _set(self, "centre", as_triple(tuple(float(v) for v in c), "mirror centre"))
        _set(self, "size", as_ranged(self.size, SURFACE_SIZE, "mirror size"))
        for key in ("reflects", "virtual"):
            value = getattr(self, key)
            if type(value) is not str or len(value) > MAX_NAME_LENGTH or has_control_characters(value):
                raise SceneError(f"mirror {key}: expected a camera name, got {short_text(value)}")
        if bool(self.reflects) != bool(self.virtual) or (self.reflects and self.reflects == self.virtual):
            raise SceneError("mirror reflects, virtual: expected both camera names (different) or neither, "
                             f"got {self.reflects!r} and {self.virtual!r}")

    @property
    def corners(self) -> np.ndarray:
        """(4, 3) corners of the drawn square (two in-plane axes of the normal)."""
        n = np.array(self.normal)
        a = np.cross(n, [0.0, 0.0, 1.0])
        if np.linalg.norm(a) < 1e-6:
            a = np.cross(n, [1.0, 0.0, 0.0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        h = self.size / 2.0
        c = np.array(self.centre)
        return np.array([c - h * a - h * b, c + h * a - h * b, c + h * a + h * b, c - h * a + h * b])


@dataclass(frozen=True)
class PlotCircle:
    """A circle in a plot (EGT's ``f_panparconic``), in pixels."""

    centre: tuple[float, float] = (0.0, 0.0)
    radius: float = 1.0
    colour: str = "#333333"

    def __post_init__(self) -> None:
        _set(self, "centre", as_pair(self.centre, "circle centre", PLOT_COORDINATE))
        _set(self, "radius", as_ranged(self.radius, Range(0.0, PLOT_COORDINATE.high, "px"), "circle radius"))
        _set(self, "colour", _colour(self.colour, "circle colour"))


@dataclass(frozen=True)
class Plot:
    """A 2D plot of an image plane (EGT's ``figure(n)`` with image points, epipolar lines, circles)."""

    number: int = 1
    """EGT's figure number; the panel is titled ``Figure <number>``."""
    points: tuple[tuple[float, float], ...] = ()
    """Pixels, numbered 1..N in the panel."""
    lines: tuple[tuple[float, float, float], ...] = ()
    """Lines ``(a, b, c)``, ``a u + b v + c = 0``."""
    line_points: tuple[tuple[float, float], ...] = ()
    """A pixel on each line (its point), one per line."""
    epipoles: tuple[tuple[float, float, float], ...] = ()
    """Homogeneous pixels (last coordinate 0: at infinity)."""
    circles: tuple[PlotCircle, ...] = ()
    image_size: tuple[int, int] | None = None
    """The image rectangle ``(width, height)`` when the camera's K defines one; None: none drawn."""

    def __post_init__(self) -> None:
        if type(self.number) is not int or not 1 <= self.number <= 10**6:
            raise SceneError(f"plot number: expected a whole number 1..1000000, got {short_text(self.number)}")
        _set(self, "points", _pairs(self.points, "plot points", MAX_PLOT_ITEMS))
        _set(self, "lines", _homogeneous(self.lines, "plot lines", MAX_PLOT_ITEMS))
        _set(self, "line_points", _pairs(self.line_points, "plot line_points", MAX_PLOT_ITEMS))
        if len(self.line_points) != len(self.lines):
            raise SceneError(
                f"plot line_points: expected one per line ({len(self.lines)}), got {len(self.line_points)}")
        for i, (line, p) in enumerate(zip(self.lines, self.line_points)):
            if math.hypot(line[0], line[1]) == 0.0:
                raise SceneError(f"plot lines[{i}]: the line at infinity (0, 0, c) cannot be drawn")
        _set(self, "epipoles", _homogeneous(self.epipoles, "plot epipoles", MAX_PLOT_ITEMS))
        circles = _tuple_of(self.circles, "plot circles", MAX_PLOT_ITEMS)
        for i, c in enumerate(circles):
            if type(c) is not PlotCircle:
                raise SceneError(f"plot circles[{i}]: expected a circle, got {short_text(c)}")
        _set(self, "circles", circles)
        if self.image_size is not None:
            size = _tuple_of(self.image_size, "plot image_size", 2, 2)
            _set(self, "image_size", tuple(int(as_ranged(v, IMAGE_SIZE, "plot image_size")) for v in size))

    @property
    def title(self) -> str:
        return f"Figure {self.number}"


#: The lists of an :class:`Annotations` and the type of their entries.
ANNOTATION_KINDS: dict[str, type] = {
    "frames": Frame,
    "polylines": Polyline,
    "labels": Label,
    "point_sets": PointSet,
    "meshes": Mesh,
    "mirrors": PlanarMirror,
    "plots": Plot,
}


@dataclass(frozen=True)
class Annotations:
    """Everything a figure draws besides the scene's cameras, points and surfaces."""

    frames: tuple[Frame, ...] = ()
    polylines: tuple[Polyline, ...] = ()
    labels: tuple[Label, ...] = ()
    point_sets: tuple[PointSet, ...] = ()
    meshes: tuple[Mesh, ...] = ()
    mirrors: tuple[PlanarMirror, ...] = ()
    plots: tuple[Plot, ...] = ()
    messages: tuple[str, ...] = ()
    """What the figure could not draw (shown by the viewer; a student's script never fails on a drawing)."""

    def __post_init__(self) -> None:
        for key, cls in ANNOTATION_KINDS.items():
            limit = MAX_PLOTS if key == "plots" else MAX_ANNOTATION_ITEMS
            items = _tuple_of(getattr(self, key), key, limit)
            for i, item in enumerate(items):
                if type(item) is not cls:
                    raise SceneError(f"{key}[{i}]: expected a {cls.__name__}, got {short_text(item)}")
            _set(self, key, items)
        numbers = [p.number for p in self.plots]
        if len(set(numbers)) != len(numbers):
            raise SceneError(f"plots: numbers must be unique, got {numbers}")
        total = sum(len(m.vertices) for m in self.meshes)
        if total > MAX_MESH_VERTICES:
            raise SceneError(f"meshes: at most {MAX_MESH_VERTICES} vertices in all, got {total}")
        messages = _tuple_of(self.messages, "messages", MAX_ANNOTATION_ITEMS)
        _set(self, "messages", tuple(_text(m, f"messages[{i}]") for i, m in enumerate(messages)))

    @property
    def empty(self) -> bool:
        return not any(getattr(self, f.name) for f in dataclasses.fields(self))


# -- reflected cameras -----------------------------------------------------------------------------------

_S = np.diag([-1.0, 1.0, 1.0])


def virtual_camera_spec(real: PinholeSpec, mirror: PlanarMirror, name: str) -> PinholeSpec:
    """The proper virtual camera of ``real`` in ``mirror`` (module docstring), named ``name``."""
    n = np.array(mirror.normal)
    pose = real.pose
    t = np.asarray(pose.t, float)
    position = t - 2.0 * (t @ n - mirror.distance) * n
    Rp = (np.eye(3) - 2.0 * np.outer(n, n)) @ np.asarray(pose.R, float) @ _S
    ypr = PinholeSpec.ypr_from_world_rotation(Rp)
    return real.with_fields(name=name, position=(float(position[0]), float(position[1]), float(position[2])),
                            ypr_deg=(float(ypr[0]), float(ypr[1]), float(ypr[2])))


def resolve_reflections(cameras: tuple, annotations: Annotations) -> tuple:
    """``cameras`` with every mirror's virtual camera (re)computed from the camera it reflects.

    The virtual camera replaces a camera of the same name (keeping its place) or is appended. A mirror
    whose ``reflects`` camera is not in the scene leaves its virtual camera as it is.

    Raises:
        SceneError: the reflected camera is not a pin-hole camera, or the virtual camera's position is
            out of range.
    """
    if not annotations.mirrors:
        return cameras
    out = list(cameras)
    for mirror in annotations.mirrors:
        if not mirror.reflects:
            continue
        real = next((c for c in out if c.name == mirror.reflects), None)
        if real is None:
            continue
        if real.kind != "pinhole":
            raise SceneError(f"mirror reflects: camera {mirror.reflects!r} is not a pin-hole camera")
        virtual = virtual_camera_spec(real, mirror, mirror.virtual)
        for i, c in enumerate(out):
            if c.name == mirror.virtual:
                if c != virtual:
                    out[i] = virtual
                break
        else:
            out.append(virtual)
    return tuple(out)


# -- file format ---------------------------------------------------------------------------------------


def _plain(value: Any) -> Any:
    """Tuples as lists, recursively (JSON)."""
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if dataclasses.is_dataclass(value):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    return value


def annotations_to_dict(annotations: Annotations) -> dict[str, Any]:
    """Plain JSON data: only the non-empty lists."""
    return {f.name: _plain(getattr(annotations, f.name)) for f in dataclasses.fields(annotations)
            if getattr(annotations, f.name)}


def _item(cls: type, entry: Any, where: str) -> Any:
    if not isinstance(entry, dict):
        raise SceneError(f"{where}: expected an object, got {short_text(entry)}")
    known = {f.name for f in dataclasses.fields(cls)}
    for key in entry:
        if key not in known:
            raise SceneError(f"{where}.{short_text(key)}: unknown field")
    for key in required_fields(cls):
        if key not in entry:
            raise SceneError(f"{where}: {key}: missing")
    fields = dict(entry)
    if cls is Plot and "circles" in fields:
        circles = _tuple_of(fields["circles"], f"{where}.circles", MAX_PLOT_ITEMS)
        fields["circles"] = tuple(_item(PlotCircle, c, f"{where}.circles[{i}]") for i, c in enumerate(circles))
    try:
        return cls(**fields)
    except SceneError as exc:
        raise SceneError(f"{where}: {exc}") from None


def annotations_from_dict(data: Any) -> Annotations:
    """:class:`Annotations` from JSON data, every entry checked.

    Raises:
        SceneError: ``"annotations.<list>[<i>]: <reason>"``.
    """
    if not isinstance(data, dict):
        raise SceneError(f"annotations: expected an object, got {short_text(data)}")
    fields: dict[str, Any] = {}
    for key, value in data.items():
        if key == "messages":
            fields[key] = _tuple_of(value, "annotations.messages", MAX_ANNOTATION_ITEMS)
            continue
        cls = ANNOTATION_KINDS.get(key)
        if cls is None:
            raise SceneError(f"annotations.{short_text(key)}: unknown entry (expected {sorted(ANNOTATION_KINDS)})")
        limit = MAX_PLOTS if key == "plots" else MAX_ANNOTATION_ITEMS
        items = _tuple_of(value, f"annotations.{key}", limit)
        fields[key] = tuple(_item(cls, e, f"annotations.{key}[{i}]") for i, e in enumerate(items))
    try:
        return Annotations(**fields)
    except SceneError as exc:
        raise SceneError(f"annotations: {exc}") from None
