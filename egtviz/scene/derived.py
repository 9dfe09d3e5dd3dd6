"""What the viewer draws, derived from a :class:`Scene` by the numeric core.

The viewer never computes geometry: it turns these arrays into viser nodes and SVG. Everything here is
recomputed from the immutable scene on each change (a camera's own content is cached per camera spec, so a
drag recomputes only the moved camera and the pair); pixel arrays are rows, NaN where nothing is drawn.

Every camera is handled through the camera-model interface (``egtviz.geometry.camera_model``): projection,
light paths, the drawn region, and the epipolar curves of the drawn pair by one route for any two models
(``egtviz.geometry.epipolar_curves``). No camera kind is tested here.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field, fields, replace
from functools import lru_cache
from typing import NamedTuple, cast

import numpy as np

from ..geometry import GeometryError, Pose
from ..geometry._shared import inverse_calibration, matrix_rank3
from ..geometry.camera_model import (
    CAMERA_MODELS,
    CameraModel,
    rectangle_rim,
)
from ..geometry.epipolar import essential_from_poses, fundamental_from_essential
from ..geometry.epipolar_curves import EpipolarCurves, epipolar_curves
from ..geometry.homogeneous import clip_lines_to_rect
from .scene import Scene
from ._values import SceneError

COINCIDENT_MESSAGE = "no epipolar geometry: the centres coincide"
#: Samples on each epipolar curve (polylines): fewer per curve when there are many, so that a panel holds about
#: ``CONIC_VERTEX_BUDGET`` vertices.
CONIC_SAMPLES = (24, 96)
CONIC_VERTEX_BUDGET = 4800
#: Samples of a rim and of a horizon.
RIM_SAMPLES = 128
#: A matrix entry below this fraction of the matrix's norm is rounding (shown as 0).
ZERO_FRACTION = 1e-12


@dataclass(frozen=True, eq=False)
class Epipole:
    """An epipole as the viewer draws it."""

    label: str
    """``e1``, ``e1'``, ..."""
    xy: np.ndarray | None
    """(2,) pixel, or None when at infinity."""
    direction: np.ndarray | None
    """(2,) unit image direction when at infinity, else None."""
    at_infinity: bool
    inside: bool
    """Finite and inside the image rectangle."""


@dataclass(frozen=True, eq=False)
class ImagePlane:
    """The content of one camera's image-plane panel: what to draw, whatever the camera model."""

    camera: str
    width: int
    height: int
    points: np.ndarray
    """(N, 2) pixels; NaN where the point has no image."""
    visible: np.ndarray
    """(N,) the point has an image."""
    in_image: np.ndarray
    """(N,) visible and inside the image rectangle."""
    n_hidden: int
    """Points with no image."""
    no_image: str = "behind the camera"
    """Where the points without an image are, in a few words (the model's ``no_image``)."""
    epipoles: tuple[Epipole, ...] = ()
    lines: np.ndarray | None = None
    """(N, 2, 2) epipolar line segments clipped to the image, for a camera that images planes to lines inside the
    image rectangle (a pin-hole in the drawn pair); NaN rows where a line misses the image."""
    line_coefficients: np.ndarray | None = None
    """(N, 3) the same epipolar lines as ``(a, b, c)``, :math:`a u + b v + c = 0`, also those that miss the image
    (a panel zoomed out past the image draws them across its whole view); NaN rows where a point has none."""
    conics: tuple[tuple[np.ndarray, ...], ...] | None = None
    """Per point, the visible arcs (k, 2) of its epipolar curve, for any other camera in the drawn pair."""
    rim: np.ndarray | None = None
    """(k, 2) closed boundary of the region curves are drawn in, when it is not the image rectangle (the image of a
    mirror's rim)."""
    horizon: tuple[np.ndarray, ...] = ()
    """The visible arcs (k, 2) of the camera's horizon: the image of the plane through its centre perpendicular to
    its axis (none for a pin-hole: that plane images to the line at infinity)."""
    message: str | None = None
    in_pair: bool = False


@dataclass(frozen=True, eq=False)
class PairReadout:
    """The epipolar relation of the drawn pair, or a message.

    ``E`` relates the viewing rays of any two central cameras, :math:`d_2^T E d_1 = 0` (each ray in its camera's
    model frame). ``F`` relates pixels, :math:`m_2^T F m_1 = 0`, and exists only when both cameras image linearly
    (``projective_calibration``: two pin-hole cameras); otherwise it is None.
    """

    names: tuple[str, str] | None
    F: np.ndarray | None = None
    E: np.ndarray | None = None
    rank: int | None = None
    """Rank of F (2 for a valid pair), or None without F."""
    e1: np.ndarray | None = None
    """Homogeneous epipole of image 1 (the image of the other centre; normalised, last coordinate 1 or 0)."""
    e2: np.ndarray | None = None
    message: str | None = None


@dataclass(frozen=True, eq=False)
class Derived:
    """Everything drawn for one scene snapshot."""

    image_planes: dict[str, ImagePlane]
    pair: PairReadout
    poses: dict[str, tuple[np.ndarray, np.ndarray]]
    """Model frame per camera name: ``(wxyz, position)``."""
    rays: dict[str, np.ndarray]
    """(N, k, 3) light paths point -> ... -> sensor (``light_paths``); NaN rows where not visible."""
    cameras: dict[str, CameraModel] = field(default_factory=dict)
    """The camera model of each camera (the same object while its spec is unchanged): the viewer's drawing
    modules ask it for the body they draw (frustum, mirror, sphere)."""
    epipolar_plane: np.ndarray | None = None
    """(3, 3) triangle (centre 1, centre 2, selected point) grown by ``PLANE_MARGIN``, or None."""
    selected_normal: np.ndarray | None = None
    """(3,) unit world normal of the selected point's epipolar plane in the drawn pair, or None."""
    baseline: np.ndarray | None = None
    """(2, 3) the drawn pair's centres, or None."""


PLANE_MARGIN = 1.25


def _epipole(label: str, e: np.ndarray, width: int, height: int) -> Epipole:
    """A homogeneous epipole ``e`` (3,) (``normalize_homogeneous``: last coordinate 1, or 0 at infinity)."""
    x, y, z = e.tolist()
    if z == 0.0:
        n = max(math.sqrt(x * x + y * y), 1e-300)
        return Epipole(label, None, np.array([x / n, y / n]), True, False)
    u, v = x / z, y / z
    return Epipole(label, np.array([u, v]), None, False, bool(0 <= u <= width and 0 <= v <= height))


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


_PLANE_FIELDS = frozenset(f.name for f in fields(ImagePlane))


def _replaced(plane: ImagePlane, **changes) -> ImagePlane:
    """``dataclasses.replace(plane, **changes)`` without its per-call introspection and keyword call (twice per
    drag): ImagePlane has no ``__post_init__`` and no slots, so a copy of its ``__dict__`` is the same object."""
    if not _PLANE_FIELDS.issuperset(changes):
        raise TypeError(f"ImagePlane has no field {sorted(set(changes) - _PLANE_FIELDS)[0]!r}")
    new = object.__new__(ImagePlane)
    values = new.__dict__
    values.update(plane.__dict__)
    values.update(changes)
    return new


class _CameraBlock(NamedTuple):
    cam: CameraModel
    pose: tuple[np.ndarray, np.ndarray]
    ray: np.ndarray
    plane: ImagePlane
    overflow: str | None
    """Why the camera cannot be drawn (its pixels or rays overflow), or None; ``compute_derived`` raises it."""


class _BlockCache:
    """:func:`_new_camera_block` remembered for the last ``size`` (spec, points) pairs, found by identity: a drag
    makes a new spec for the moved camera only, so the other cameras' blocks are found again without hashing
    or comparing a spec's fields (and whatever a spec's hash covers). Least recently used first out."""

    def __init__(self, size: int) -> None:
        self._size = size
        self._entries: dict[tuple[int, int, bool], tuple[object, object, _CameraBlock]] = {}
        self._lock = threading.Lock()

    def __call__(self, spec, points, check: bool) -> _CameraBlock:
        key = (id(spec), id(points), check)
        with self._lock:
            hit = self._entries.pop(key, None)
            # An entry holds its spec and points, so their ids are not reused while it lives.
            if hit is not None and hit[0] is spec and hit[1] is points:
                self._entries[key] = hit
                return hit[2]
        block = _new_camera_block(spec, points, check)
        with self._lock:
            if len(self._entries) >= self._size:
                del self._entries[next(iter(self._entries))]
            self._entries[key] = (spec, points, block)
        return block

    def cache_clear(self) -> None:
        with self._lock:
            self._entries.clear()


def _new_camera_block(spec, points, check: bool) -> _CameraBlock:
    """Everything about one camera that depends only on its spec and the points (cached by :data:`_camera_block`:
    a drag changes one camera, so the others' projections, light paths and image content are reused). Arrays are
    read-only.

    The points were checked when the scene took them (``Scene.points_array``): the core is called with
    ``check=False`` unless ``check`` asks for its checked calls (the reference the tests compare with)."""
    X = points.array  # type: ignore[attr-defined]
    cam = spec.camera()
    pose = cam.pose
    proj = cam.project(X, check=check)
    visible = proj.visible
    rim, horizon = _rim_and_horizon(spec.model_kind, spec.model_key)
    plane = ImagePlane(
        camera=spec.name,
        width=cam.width,
        height=cam.height,
        points=_frozen(proj.pixels),
        visible=_frozen(visible),
        in_image=_frozen(proj.in_image),
        n_hidden=int(len(X) - np.count_nonzero(visible)),
        no_image=cam.no_image,
        rim=rim,
        horizon=horizon,
    )
    ray = _frozen(cam.light_paths(X, check=check))
    overflow = None
    # logical_or.reduce: ndarray.any's Python wrapper costs more than the test on a few points (every drag).
    if np.logical_or.reduce(np.isinf(plane.points), axis=None):
        overflow = f"camera {spec.name!r}: image coordinates overflow"
    elif np.logical_or.reduce(np.isinf(ray), axis=None):
        overflow = f"camera {spec.name!r}: rays overflow"
    return _CameraBlock(cam, (_frozen(np.array(pose.quat_wxyz)), pose.t), ray, plane, overflow)


_camera_block = _BlockCache(64)


@lru_cache(maxsize=64)
def _rim_and_horizon(kind: str, values: tuple[tuple[str, float], ...]) -> tuple[np.ndarray | None, tuple]:
    """A camera's drawn-region boundary (None: the image rectangle, which the panel's frame draws) and its horizon's
    arcs. Neither depends on the pose (the horizon is the image of the plane through the centre perpendicular to the
    camera's axis, fixed in the camera's frame), so they are computed once per set of parameters, at the origin."""
    cam = CAMERA_MODELS[kind].build(Pose(), **dict(values))
    rim = cam.rim(RIM_SAMPLES)
    horizon = tuple(_frozen(a) for a in cam.plane_image_arcs([0.0, 0.0, 1.0], RIM_SAMPLES)[0])
    if rim.shape == (5, 2) and np.array_equal(rim, rectangle_rim(cam.width, cam.height)):
        return None, horizon
    return _frozen(rim), horizon


def compute_derived(scene: Scene, *, check: bool = False) -> Derived:
    """Project, and compute the epipolar entities of the drawn pair, for every camera of ``scene``.

    The scene was checked when it was made (its points, its specs, so its cameras), so the core is called on
    its fast path (``check=False``, ``docs/conventions.md``). ``check=True`` calls the core's checked functions
    instead: the same results (the tests compare the two), slower.

    Raises:
        SceneError: the scene cannot be drawn (the core refused it, or a drawn value is infinite). A scene
            whose ``compute_derived`` succeeds is one the viewer can draw.
    """
    try:
        return _compute_derived(scene, check=True) if check else _compute_derived(scene)
    except (GeometryError, ArithmeticError, ValueError) as exc:
        raise SceneError(f"cannot be drawn: {exc}") from exc


def _compute_derived(scene: Scene, check: bool = False) -> Derived:
    X = scene.points_array()
    points = scene.points
    blocks = {spec.name: _camera_block(spec, points, check) for spec in scene.cameras}
    for b in blocks.values():
        if b.overflow is not None:
            raise SceneError(b.overflow)
    cams = {name: b.cam for name, b in blocks.items()}
    planes: dict[str, ImagePlane] = {name: b.plane for name, b in blocks.items()}

    pair_names = scene.drawn_pair
    readout = PairReadout(pair_names)
    epi_plane = baseline = selected_normal = None
    if pair_names is not None:
        n1, n2 = pair_names
        c1, c2 = cams[n1], cams[n2]
        lo, hi = CONIC_SAMPLES
        n_samples = min(max(CONIC_VERTEX_BUDGET // max(len(X), 1), lo), hi)
        try:
            curves = epipolar_curves(c1, c2, X, n_samples=n_samples, conics=False, arcs=False, check=check)
        except GeometryError:  # DegenerateConfigurationError: the centres coincide
            for n in pair_names:
                planes[n] = replace(planes[n], message=COINCIDENT_MESSAGE, in_pair=True)
            readout = PairReadout(pair_names, message=COINCIDENT_MESSAGE)
        else:
            baseline = np.array([c1.centre.tolist(), c2.centre.tolist()])
            sides = ((n1, "1", c1, curves.first), (n2, "2", c2, curves.second))
            segments = _clipped_lines([(side, planes[name]) for name, _, _, side in sides])
            for (name, idx, cam, side), seg in zip(sides, segments, strict=True):
                planes[name] = _replaced(planes[name], in_pair=True,
                                       **_pair_content(cam, side, seg, curves.normals, n_samples, idx, planes[name],
                                                       check))
            readout = _readout(pair_names, c1, c2, curves.first, curves.second, check)
            sel = scene.selected_point
            if sel is not None and not math.isnan(curves.normals[sel, 0]):  # a normal is all NaN or all finite
                epi_plane = _grown_triangle(c1.centre, c2.centre, X[sel])
                selected_normal = _frozen(curves.normals[sel].copy())

    return Derived(
        image_planes=planes,
        pair=readout,
        poses={name: b.pose for name, b in blocks.items()},
        rays={name: b.ray for name, b in blocks.items()},
        cameras=cams,
        epipolar_plane=epi_plane,
        selected_normal=selected_normal,
        baseline=baseline,
    )


def _grown_triangle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(3, 3) the triangle ``(a, b, c)`` grown about its centroid by ``PLANE_MARGIN``: the numpy formula
    ``centroid + PLANE_MARGIN * (tri - centroid)`` on plain floats (every drag; the same operations in the same
    order, so the same values)."""
    rows = (a.tolist(), b.tolist(), c.tolist())
    centroid = [(x + y + z) / 3.0 for x, y, z in zip(*rows, strict=True)]
    return np.array([[m + PLANE_MARGIN * (v - m) for v, m in zip(row, centroid, strict=True)] for row in rows])


def _clipped_lines(sides: list[tuple[EpipolarCurves, ImagePlane]]) -> list[np.ndarray | None]:
    """Per camera of the pair, its epipolar lines clipped to its image, (N, 2, 2) with NaN rows where a line misses
    it, or None for a camera that does not draw lines (no exact lines, or a drawn region other than the image
    rectangle). Images of one size are clipped in one call (the lines are independent). The clip clamps the
    segments into the image: they are finite or NaN, never infinite (nothing for ``compute_derived`` to refuse)."""
    drawn = [k for k, (curves, plane) in enumerate(sides) if curves.lines is not None and plane.rim is None]
    out: list[np.ndarray | None] = [None] * len(sides)
    groups: dict[tuple[int, int], list[int]] = {}
    for k in drawn:
        groups.setdefault((sides[k][1].width, sides[k][1].height), []).append(k)
    for (w, h), members in groups.items():
        # Every member has lines (``drawn``).
        parts = [cast(np.ndarray, sides[k][0].lines) for k in members]
        lines = np.concatenate(parts) if len(parts) > 1 else parts[0]
        # The core computed these lines from validated cameras: its unchecked path, which also gives NaN rows for
        # a point with no line (NaN or zero), as for a line that misses the image.
        seg = clip_lines_to_rect(lines, w, h, check=False)[0]
        n = len(seg) // len(members)
        for j, k in enumerate(members):
            out[k] = _frozen(seg[j * n:(j + 1) * n])
    return out


def _pair_content(cam: CameraModel, curves: EpipolarCurves, lines: np.ndarray | None, normals: np.ndarray,
                  n_samples: int, idx: str, plane: ImagePlane, check: bool) -> dict:
    """Epipoles and epipolar curves of one camera of the drawn pair, as its panel draws them.

    A model with one image of the baseline (a pin-hole: both directions image to one point, where every epipolar
    line meets) always shows it; a sphere model's two images (towards the other centre, ``e``, and away, ``e'``)
    are drawn where the camera really sees them. A camera that draws lines gets them clipped to its image
    (``lines``, from :func:`_clipped_lines`); every other camera the arcs it really shows (``conics``,
    ``plane_image_arcs``).
    """
    labels = (f"e{idx}", f"e{idx}'")
    single = len(curves.epipoles) == 1
    epipoles = tuple(
        _epipole(labels[k], e, plane.width, plane.height)
        for k, (e, seen) in enumerate(zip(curves.epipoles, curves.epipoles_visible.tolist(), strict=True))
        if seen or single
    )
    if lines is not None:
        # The core's fresh array of this update (the clipped segments were made from a copy): frozen, not copied.
        return {"epipoles": epipoles, "lines": lines, "line_coefficients": _frozen(cast(np.ndarray, curves.lines))}
    arcs = cam.plane_image_arcs(normals, n_samples, check=check)
    # tuple() of a tuple is that tuple: the models' tuples are kept, any other sequence becomes one.
    return {"epipoles": epipoles, "conics": tuple(map(tuple, arcs))}


def _readout(names: tuple[str, str], c1: CameraModel, c2: CameraModel, first: EpipolarCurves,
             second: EpipolarCurves, check: bool) -> PairReadout:
    r"""E between the rays of any pair, :math:`d_2^T E d_1 = 0`; F between pixels when both cameras image
    linearly, :math:`F = K_2^{-T} E K_1^{-1}`; the epipoles towards the other centre."""
    K1, K2 = c1.projective_calibration, c2.projective_calibration
    F = rank = None
    if not check:
        # The same formulas in plain floats (every drag): numpy's per-call cost dominates on 3x3 arrays.
        E, F = _essential_and_fundamental(c1.pose, c2.pose, K1, K2)
        if F is not None:
            # The SVD's rank, decided from F's invariants when they are conclusive (every drag of a pin-hole pair);
            # the tolerance from np.linalg.norm(F)'s own arithmetic, sqrt(x . x), without its wrapper.
            x = F.ravel()
            rank = matrix_rank3(F, 1e-9 * math.sqrt(x.dot(x)))
        return PairReadout(names, F, E, rank, first.epipoles[0], second.epipoles[0])
    E = essential_from_poses(c1.pose, c2.pose, check=check)
    if K1 is not None and K2 is not None:
        F = fundamental_from_essential(E, K1, K2, check=check)
        rank = int(np.linalg.matrix_rank(F, tol=1e-9 * float(np.linalg.norm(F))))
    return PairReadout(names, F, E, rank, first.epipoles[0], second.epipoles[0])


def _essential_and_fundamental(pose1: Pose, pose2: Pose, K1: np.ndarray | None,
                                K2: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    r"""``(E, F)`` of ``essential_from_poses`` and ``fundamental_from_essential`` (``F`` None when either
    calibration is None), unchecked; ``F`` in plain floats: the same formula on nine numbers without numpy's
    per-call cost on 3x3 arrays (every drag of a pair), equal to the numpy call up to rounding (1e-16 relative).

    The caller promises two :class:`Pose` objects and float64 calibration matrices (checked when the cameras were
    made).

    Raises:
        DegenerateConfigurationError: the two centres coincide.
    """
    # E by the core's numpy function: its sign (the largest entry made positive) is decided on exactly the checked
    # path's values, which matters when entries tie in magnitude (two cameras with one rotation: E = [t]x).
    E_array = essential_from_poses(pose1, pose2, check=False)
    if K1 is None or K2 is None:
        return E_array, None
    E = E_array.ravel().tolist()
    top = max(map(abs, E))
    ea, eb, ec, ed, ee, ef, eg, eh, ei = (v / top for v in E)
    (A0, A1, A2), (A3, A4, A5), (A6, A7, A8) = inverse_calibration(K2, "K2").tolist()
    (B0, B1, B2), (B3, B4, B5), (B6, B7, B8) = inverse_calibration(K1, "K1").tolist()
    # F = K2^-T E K1^-1 (A = K2^-1, B = K1^-1): first M = A^T E, then M B.
    m = (A0 * ea + A3 * ed + A6 * eg, A0 * eb + A3 * ee + A6 * eh, A0 * ec + A3 * ef + A6 * ei,
         A1 * ea + A4 * ed + A7 * eg, A1 * eb + A4 * ee + A7 * eh, A1 * ec + A4 * ef + A7 * ei,
         A2 * ea + A5 * ed + A8 * eg, A2 * eb + A5 * ee + A8 * eh, A2 * ec + A5 * ef + A8 * ei)
    F: list[float] = []
    for r in (0, 3, 6):
        u, v, w = m[r], m[r + 1], m[r + 2]
        F += (u * B0 + v * B3 + w * B6, u * B1 + v * B4 + w * B7, u * B2 + v * B5 + w * B8)
    top = max(map(abs, F))
    F = [v / top for v in F]
    n = math.sqrt(math.fsum([v * v for v in F]))
    return E_array, np.array([v / n for v in F]).reshape(3, 3)


def shown_value(value: float, matrix_norm: float) -> float:
    """``value``, or 0.0 when its magnitude is below ``ZERO_FRACTION`` of the matrix's norm (rounding, shown as 0)."""
    return 0.0 if abs(value) < ZERO_FRACTION * matrix_norm else value


def with_pair_lines(derived: Derived, names: tuple[str, str], *, lines1: np.ndarray, lines2: np.ndarray,
                    e1: np.ndarray, e2: np.ndarray, points: tuple[np.ndarray, np.ndarray] | None = None,
                    no_image: str = "") -> Derived:
    """``derived`` with the drawn pair's panels showing other epipolar lines and epipoles (and pixels): what a
    lesson's estimation lab or convention lens draws instead of the true geometry.

    Args:
        derived: the model's derived quantities.
        names: the drawn pair (image 1, image 2).
        lines1, lines2: (N, 3) lines in image 1 and image 2, one per point (NaN rows: none drawn).
        e1, e2: homogeneous epipoles of image 1 and image 2 (last coordinate 1, or 0 at infinity).
        points: (N, 2) pixels to draw instead of the true images (NaN: not drawn), for image 1 and image 2.
        no_image: why a point of ``points`` is not drawn, in a few words (the panels' status line).
    """
    planes = dict(derived.image_planes)
    for name, lines, e, label, k in ((names[0], lines1, e1, "e1", 0), (names[1], lines2, e2, "e2", 1)):
        plane = planes[name]
        extra: dict = {}
        if points is not None:
            px = np.asarray(points[k], float)
            seen = np.isfinite(px).all(axis=1)
            inside = seen & (px[:, 0] >= 0) & (px[:, 0] <= plane.width) & (px[:, 1] >= 0) & (px[:, 1] <= plane.height)
            extra = {"points": px, "visible": seen, "in_image": inside, "n_hidden": int((~seen).sum()),
                     "no_image": no_image or plane.no_image}
        lines = np.asarray(lines, float)
        planes[name] = replace(plane, lines=_segments_in_image(lines, plane.width, plane.height),
                               line_coefficients=lines, epipoles=(_epipole(label, np.asarray(e, float), plane.width,
                                                                           plane.height),),
                               conics=None, **extra)
    return replace(derived, image_planes=planes)


def _segments_in_image(lines: np.ndarray, width: float, height: float) -> np.ndarray:
    """(N, 2, 2) lines clipped to the image for drawing; NaN rows for missing lines (NaN, or the line at infinity)
    and for lines that miss it."""
    if not len(lines):
        return np.full((0, 2, 2), np.nan)
    return clip_lines_to_rect(lines, width, height, check=False)[0]
