"""What the viewer draws, derived from a :class:`Scene` by the numeric core.

The viewer never computes geometry: it turns these arrays into viser nodes and
SVG. Everything here is recomputed from the immutable scene on each change;
pixel arrays are rows, NaN where nothing is drawn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..geometry import GeometryError, PinholeCamera
from ..geometry.epipolar import _epipolar_normals, _epipole_of_centre, _matrix_rank3, epipolar_pair
from ..geometry.homogeneous import _clip_lines
from ..geometry.panoramic_epipolar import _circle_arcs
from .scene import Scene
from .specs import PanoramicSpec, SceneError

COINCIDENT_MESSAGE = "no epipolar geometry: the centres coincide"
#: Samples on each epipolar great circle (conic polylines): fewer per conic when there are many,
#: so that a panel holds about ``CONIC_VERTEX_BUDGET`` vertices.
CONIC_SAMPLES = (24, 96)
CONIC_VERTEX_BUDGET = 4800


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
    """The content of one camera's image-plane panel."""

    camera: str
    kind: str
    width: int
    height: int
    points: np.ndarray
    """(N, 2) pixels; NaN where the point has no image."""
    visible: np.ndarray
    """(N,) the point has an image (in front / seen by the mirror)."""
    in_image: np.ndarray
    """(N,) visible and inside the image rectangle."""
    n_hidden: int
    """Points with no image (behind the camera, in the blind cone)."""
    epipoles: tuple[Epipole, ...] = ()
    lines: np.ndarray | None = None
    """(N, 2, 2) epipolar line segments clipped to the image (pin-hole in the drawn pair)."""
    conics: tuple[tuple[np.ndarray, ...], ...] | None = None
    """Per point, the visible arcs (k, 2) of its epipolar conic (panoramic in the drawn pair)."""
    rim: np.ndarray | None = None
    """(k, 2) image of the mirror rim (panoramic)."""
    message: str | None = None
    in_pair: bool = False


@dataclass(frozen=True, eq=False)
class PairReadout:
    """F, E and epipoles of the drawn pair (pin-hole pair), or a message."""

    names: tuple[str, str] | None
    F: np.ndarray | None = None
    E: np.ndarray | None = None
    rank: int | None = None
    e1: np.ndarray | None = None
    e2: np.ndarray | None = None
    message: str | None = None


@dataclass(frozen=True, eq=False)
class Derived:
    """Everything drawn for one scene snapshot."""

    image_planes: dict[str, ImagePlane]
    pair: PairReadout
    poses: dict[str, tuple[np.ndarray, np.ndarray]]
    """Camera (mirror) frame per name: ``(wxyz, position)``."""
    rays: dict[str, np.ndarray]
    """(N, k, 3) polylines point -> (mirror point ->) centre or CCD; NaN rows where not visible."""
    frustums: dict[str, dict[str, float]] = field(default_factory=dict)
    """Pin-hole frustum shape: ``fov`` (vertical, radians), ``aspect``."""
    image_in_3d: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)
    """Pin-hole image content on the frustum's image plane: ``points`` (N, 3), ``lines`` (N, 2, 3)."""
    mirror_meshes: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    """Mirror surface per panoramic camera: ``(vertices (V, 3) in the world, faces (F, 3))``."""
    ccd_centres: dict[str, np.ndarray] = field(default_factory=dict)
    epipolar_plane: np.ndarray | None = None
    """(3, 3) triangle (centre 1, centre 2, selected point) grown by ``PLANE_MARGIN``, or None."""
    baseline: np.ndarray | None = None
    """(2, 3) the drawn pair's centres, or None."""


#: Depth of the drawn image plane in front of a pin-hole centre, scene units.
IMAGE_PLANE_DEPTH = 0.6
PLANE_MARGIN = 1.25


@lru_cache(maxsize=32)
def _mirror_mesh_local(mirror_kind: str, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    spec = PanoramicSpec("m", mirror=mirror_kind, a=a, b=b)  # type: ignore[arg-type]
    return spec.mirror_model().surface(16, 48)


def _epipole(label: str, e: np.ndarray, width: int, height: int) -> Epipole:
    """A homogeneous epipole ``e`` (3,) (``normalize_homogeneous``: last coordinate 1, or 0 at infinity)."""
    x, y, z = e.tolist()
    if z == 0.0:
        n = max(math.sqrt(x * x + y * y), 1e-300)
        return Epipole(label, None, np.array([x / n, y / n]), True, False)
    return _finite_epipole(label, x / z, y / z, width, height)


def _finite_epipole(label: str, u: float, v: float, width: int, height: int) -> Epipole:
    return Epipole(label, np.array([u, v]), None, False, bool(0 <= u <= width and 0 <= v <= height))


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


class _PointArrays:
    """The scene's points, read-only, in both layouts: ``X`` (N, 3) and ``XT`` (3, N) contiguous (the
    coordinate-major layout of the pair computations). Hashed by identity (a cheap cache key)."""

    __slots__ = ("X", "XT")

    def __init__(self, X: np.ndarray) -> None:
        self.X = X
        self.XT = _frozen(np.ascontiguousarray(X.T))


@lru_cache(maxsize=8)
def _points(points: tuple) -> _PointArrays:
    """The :class:`_PointArrays` of a scene's points (``Scene.points``: it carries its checked read-only array,
    remembers its hash and stays the same object across camera drags, so the lookup is cheap)."""
    return _PointArrays(points.array)  # type: ignore[attr-defined]


@lru_cache(maxsize=64)
def _camera_block(spec, pts: _PointArrays) -> dict:
    """Everything about one camera that depends only on its spec and the points (cached: a drag changes one
    camera, so the others' projections, rays, meshes and image content are reused). Arrays are read-only.

    Built on every drag of this camera: the points and the camera come checked from the core, so its
    internal (unchecked) projections are used."""
    X = pts.X
    n = len(X)
    cam = spec.camera()
    pose = cam.pose
    out: dict = {"cam": cam, "pose": (_frozen(np.array(pose.quat_wxyz)), _frozen(pose.t.copy()))}
    if isinstance(cam, PinholeCamera):
        proj = cam._project(X)
        visible = proj.in_front
        ray = np.empty((n, 2, 3))
        ray[:, 1] = pose.t
        out["frustum"] = {"fov": cam.intrinsics.fov_y, "aspect": cam.intrinsics.aspect}
        rim = None
        # Pixel (u, v) on the drawn image plane, image_to_world(., IMAGE_PLANE_DEPTH):
        # IMAGE_PLANE_DEPTH R K^-1 (u, v, 1) + t = (u, v) @ A + b.
        G = IMAGE_PLANE_DEPTH * cam._R_K_inv
        to_plane = (_frozen(G[:, :2].T.copy()), _frozen(G[:, 2] + pose.t))
        out["to_plane"] = to_plane
        pts3 = proj.pixels @ to_plane[0]
        pts3 += to_plane[1]
        pts3[~visible] = np.nan
        out["pts3"] = _frozen(pts3)
    else:
        proj = cam._project_world(X)
        visible = proj.visible
        ray = np.empty((n, 3, 3))
        ccd = _frozen(pose.to_world([0.0, 0.0, -cam.mirror.ccd_offset])[0])  # cam.ccd_center_world
        np.matmul(proj.mirror_points, pose.R.T, out=ray[:, 1])  # mirror points in the world (NaN rows: invisible)
        ray[:, 1] += pose.t
        ray[:, 2] = ccd
        v, f = _mirror_mesh_local(spec.mirror, float(spec.a), float(spec.b))
        mesh = v @ pose.R.T
        mesh += pose.t
        out["mesh"] = (_frozen(mesh), f)
        out["ccd"] = ccd
        rim = _rim_image(cam.mirror, cam.K.tobytes())  # independent of the pose
    ray[:, 0] = X
    ray[~visible] = np.nan
    out["ray"] = _frozen(ray)
    out["plane"] = ImagePlane(
        camera=spec.name,
        kind=spec.kind,
        width=spec.width,
        height=spec.height,
        points=_frozen(proj.pixels),
        visible=_frozen(visible),
        in_image=_frozen(proj.in_image),
        n_hidden=int(n - np.count_nonzero(visible)),
        rim=rim,
    )
    return out


@lru_cache(maxsize=16)
def _rim_image(mirror, K_bytes: bytes) -> np.ndarray:
    """``rim_image(128)`` of a camera with this mirror and calibration: the rim's pixels do not depend on the pose."""
    from ..geometry.catadioptric import CatadioptricCamera

    return _frozen(np.array(CatadioptricCamera(mirror=mirror, K=np.frombuffer(K_bytes).reshape(3, 3)).rim_image(128)))


def compute_derived(scene: Scene) -> Derived:
    """Project, and compute the epipolar entities of the drawn pair, for every camera of ``scene``.

    On a drag only the pair-dependent part is new work (the per-camera blocks are cached); it calls the
    geometry core's unchecked internal functions, since every array here was built and checked by the core.

    Raises:
        SceneError: the scene cannot be drawn (the core refused it, or a drawn value is infinite). A scene
            whose ``compute_derived`` succeeds is one the viewer can draw.
    """
    try:
        derived = _compute_derived(scene)
    except (GeometryError, ArithmeticError, ValueError) as exc:
        raise SceneError(f"cannot be drawn: {exc}") from exc
    for name, plane in derived.image_planes.items():
        if np.isinf(plane.points).any() or (plane.lines is not None and np.isinf(plane.lines).any()):
            raise SceneError(f"cannot be drawn: camera {name!r}: image coordinates overflow")
    for name, ray in derived.rays.items():
        if np.isinf(ray).any():
            raise SceneError(f"cannot be drawn: camera {name!r}: rays overflow")
    return derived


def _compute_derived(scene: Scene) -> Derived:
    pts = _points(scene.points)
    X = pts.X
    n_points = len(X)
    blocks = {spec.name: _camera_block(spec, pts) for spec in scene.cameras}
    cams = {name: b["cam"] for name, b in blocks.items()}
    planes: dict[str, ImagePlane] = {name: b["plane"] for name, b in blocks.items()}
    rays: dict[str, np.ndarray] = {name: b["ray"] for name, b in blocks.items()}
    poses = {name: b["pose"] for name, b in blocks.items()}
    frustums: dict[str, dict[str, float]] = {name: dict(b["frustum"]) for name, b in blocks.items() if "frustum" in b}
    meshes: dict[str, tuple[np.ndarray, np.ndarray]] = {name: b["mesh"] for name, b in blocks.items() if "mesh" in b}
    ccd: dict[str, np.ndarray] = {name: b["ccd"] for name, b in blocks.items() if "ccd" in b}
    # Pin-hole cameras of the drawn pair: clipped epipolar segments and which rows hit the image.
    segments: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    pair_names = scene.drawn_pair
    readout = PairReadout(pair_names)
    epi_plane = baseline = None
    if pair_names is not None:
        n1, n2 = pair_names
        c1, c2 = cams[n1], cams[n2]
        o1, o2 = c1.pose.t, c2.pose.t
        try:
            # (3, N) unit world normals of the epipolar planes, NaN columns for points on the baseline.
            normals_T = _epipolar_normals(o1, o2, pts.XT)
        except GeometryError:
            for n in pair_names:
                planes[n] = _with(planes[n], message=COINCIDENT_MESSAGE, in_pair=True)
            readout = PairReadout(pair_names, message=COINCIDENT_MESSAGE)
        else:
            baseline = np.array([o1, o2])
            content = {n1: {}, n2: {}}
            pinholes = [(n, c) for n, c in ((n1, c1), (n2, c2)) if isinstance(c, PinholeCamera)]
            if len(pinholes) == 2:
                ep = epipolar_pair(c1, c2)
                rank = _matrix_rank3(ep.F, 1e-9)
                readout = PairReadout(pair_names, ep.F, ep.E, rank, ep.e1, ep.e2)
                # The pair's epipoles are the images of the other centre (epipole_of_centre): reuse them.
                epipoles = {n1: ep.e1, n2: ep.e2}
            else:
                epipoles = {n: _epipole_of_centre(c, o2 if n == n1 else o1)[0] for n, c in pinholes}
            segments = _pinhole_segments(pinholes, normals_T, planes)
            for name, seg_hit in segments.items():
                idx = "1" if name == n1 else "2"
                ip = planes[name]
                content[name] = {"epipoles": (_epipole(f"e{idx}", epipoles[name], ip.width, ip.height),),
                                 "lines": seg_hit[0]}
            for name, cam, other in ((n1, c1, o2), (n2, c2, o1)):
                if not isinstance(cam, PinholeCamera):
                    content[name] = _panoramic_content(cam, other, normals_T, planes[name], name == n1)
            for name in (n1, n2):
                planes[name] = _with(planes[name], in_pair=True, **content[name])
            sel = scene.selected_point
            if sel is not None and not math.isnan(normals_T[0, sel]):  # a normal is all NaN or all finite
                tri = np.array([o1, o2, X[sel]])
                centroid = (tri[0] + tri[1] + tri[2]) / 3.0  # tri.mean(axis=0)
                epi_plane = centroid + PLANE_MARGIN * (tri - centroid)

    image_in_3d: dict[str, dict[str, np.ndarray]] = {}
    for name, b in blocks.items():
        if "pts3" in b:
            if name in segments:
                seg, hit = segments[name]
                A, t = b["to_plane"]
                lines3 = seg.reshape(-1, 2) @ A
                lines3 += t
                lines3 = lines3.reshape(n_points, 2, 3)
                lines3[~hit] = np.nan  # (seg is NaN there; set anyway rather than rely on BLAS propagating NaN)
            else:
                lines3 = np.full((n_points, 2, 3), np.nan)
            image_in_3d[name] = {"points": b["pts3"], "lines": lines3}

    return Derived(
        image_planes=planes,
        pair=readout,
        poses=poses,
        rays=rays,
        frustums=frustums,
        image_in_3d=image_in_3d,
        mirror_meshes=meshes,
        ccd_centres=ccd,
        epipolar_plane=epi_plane,
        baseline=baseline,
    )


def _with(plane: ImagePlane, **changes) -> ImagePlane:
    """``dataclasses.replace`` for these plain frozen records (no ``__post_init__``), without its overhead."""
    new = object.__new__(ImagePlane)
    new.__dict__.update(plane.__dict__)
    new.__dict__.update(changes)
    return new


def _pinhole_segments(pinholes: list, normals_T: np.ndarray, planes: dict[str, ImagePlane]
                      ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    r"""Epipolar lines :math:`l = K^{-T} R^T n` of the planes with world normals ``normals_T`` (3, N) in each
    pin-hole camera of the pair, clipped to its image: ``{name: (segments (N, 2, 2), hit (N,))}``.

    Images of the same size are clipped in one call (the lines are independent).
    """
    n = normals_T.shape[1]
    sizes = {(planes[name].width, planes[name].height) for name, _ in pinholes}
    if len(pinholes) == 2 and len(sizes) == 1:
        (w, h), = sizes
        (na, ca), (nb, cb) = pinholes
        lines_T = np.empty((3, 2 * n))
        np.matmul(ca._plane_to_line, normals_T, out=lines_T[:, :n])
        np.matmul(cb._plane_to_line, normals_T, out=lines_T[:, n:])
        seg, hit = _clip_lines(lines_T, float(w), float(h))
        return {na: (seg[:n], hit[:n]), nb: (seg[n:], hit[n:])}
    return {name: _clip_lines(cam._plane_to_line @ normals_T, float(planes[name].width), float(planes[name].height))
            for name, cam in pinholes}


def _panoramic_content(cam, other_centre: np.ndarray, normals_T: np.ndarray, plane: ImagePlane, first: bool) -> dict:
    """Epipoles and epipolar conics of a panoramic member of the drawn pair.

    The baseline meets the mirror twice: ``e`` is the image of the direction :math:`d = R^T (o' - o)` towards
    the other centre, ``e'`` of :math:`-d`; each is drawn when the mirror shows it. The conics are the visible
    arcs of the epipolar planes' great circles (normals :math:`R^T n` in the mirror frame).
    """
    idx = "1" if first else "2"
    R = cam.pose.R
    dx, dy, dz = (R.T @ (other_centre - cam.pose.t)).tolist()
    epis = []
    for label, sign in ((f"e{idx}", 1.0), (f"e{idx}'", -1.0)):
        px = cam._direction_pixel(sign * dx, sign * dy, sign * dz)
        if px is not None:
            epis.append(_finite_epipole(label, *px, plane.width, plane.height))
    n_normals = normals_T.shape[1]
    lo, hi = CONIC_SAMPLES
    n_samples = min(max(CONIC_VERTEX_BUDGET // max(n_normals, 1), lo), hi)
    arcs = _circle_arcs(cam, R.T @ normals_T, n_samples) if n_normals else ()
    return {"epipoles": tuple(epis), "conics": tuple(arcs)}
