"""What the viewer draws, derived from a :class:`Scene` by the numeric core.

The viewer never computes geometry: it turns these arrays into viser nodes and
SVG. Everything here is recomputed from the immutable scene on each change;
pixel arrays are rows, NaN where nothing is drawn.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from ..geometry import GeometryError, PinholeCamera
from ..geometry.epipolar import epipolar_pair, epipolar_planes, epipole_of_centre, lines_of_planes
from ..geometry.homogeneous import clip_lines_to_rect
from .scene import Scene
from .specs import PanoramicSpec

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
    if e[2] == 0.0:
        d = e[:2] / max(np.linalg.norm(e[:2]), 1e-300)
        return Epipole(label, None, d, True, False)
    xy = e[:2] / e[2]
    inside = bool(0 <= xy[0] <= width and 0 <= xy[1] <= height)
    return Epipole(label, xy, None, False, inside)


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@lru_cache(maxsize=8)
def _points_array(points: tuple) -> np.ndarray:
    """The scene's points as a read-only (N, 3) array, built once per points tuple."""
    return _frozen(np.array(points, dtype=np.float64).reshape(-1, 3))


@lru_cache(maxsize=64)
def _camera_block(spec, points: tuple) -> dict:
    """Everything about one camera that depends only on its spec and the points (cached: a drag changes one
    camera, so the others' projections, rays, meshes and image content are reused). Arrays are read-only."""
    X = _points_array(points)
    cam = spec.camera()
    out: dict = {"cam": cam, "pose": (_frozen(np.array(cam.pose.quat_wxyz)), _frozen(cam.pose.t.copy()))}
    if isinstance(cam, PinholeCamera):
        proj = cam.project(X)
        visible = proj.in_front
        ray = np.stack([X, np.broadcast_to(cam.center, X.shape)], axis=1)
        out["frustum"] = {"fov": cam.intrinsics.fov_y, "aspect": cam.intrinsics.aspect}
        rim = None
        pts3 = np.full((len(X), 3), np.nan)
        if visible.any():
            pts3[visible] = cam.image_to_world(proj.pixels[visible], IMAGE_PLANE_DEPTH)
        out["pts3"] = _frozen(pts3)
    else:
        proj = cam.project(X)
        visible = proj.visible
        mirror_world = cam.pose.to_world(np.nan_to_num(proj.mirror_points)) if len(X) else np.zeros((0, 3))
        ray = np.stack([X, mirror_world, np.broadcast_to(cam.ccd_center_world, X.shape)], axis=1)
        v, f = _mirror_mesh_local(spec.mirror, float(spec.a), float(spec.b))
        out["mesh"] = (_frozen(cam.pose.to_world(v)), f)
        out["ccd"] = _frozen(np.array(cam.ccd_center_world))
        rim = _frozen(np.array(cam.rim_image(128)))
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
        n_hidden=int(len(visible) - np.count_nonzero(visible)),
        rim=rim,
    )
    return out


def compute_derived(scene: Scene) -> Derived:
    """Project, and compute the epipolar entities of the drawn pair, for every camera of ``scene``."""
    X = _points_array(scene.points)
    blocks = {spec.name: _camera_block(spec, scene.points) for spec in scene.cameras}
    cams = {name: b["cam"] for name, b in blocks.items()}
    planes: dict[str, ImagePlane] = {name: b["plane"] for name, b in blocks.items()}
    rays: dict[str, np.ndarray] = {name: b["ray"] for name, b in blocks.items()}
    poses = {name: b["pose"] for name, b in blocks.items()}
    frustums: dict[str, dict[str, float]] = {name: dict(b["frustum"]) for name, b in blocks.items() if "frustum" in b}
    image_in_3d: dict[str, dict[str, np.ndarray]] = {}
    meshes: dict[str, tuple[np.ndarray, np.ndarray]] = {name: b["mesh"] for name, b in blocks.items() if "mesh" in b}
    ccd: dict[str, np.ndarray] = {name: b["ccd"] for name, b in blocks.items() if "ccd" in b}

    pair_names = scene.drawn_pair
    readout = PairReadout(pair_names)
    epi_plane = baseline = None
    if pair_names is not None:
        n1, n2 = pair_names
        c1, c2 = cams[n1], cams[n2]
        o1, o2 = c1.pose.t, c2.pose.t
        try:
            plane_eqs = epipolar_planes(o1, o2, X) if len(X) else np.zeros((0, 4))
        except GeometryError:
            for n in pair_names:
                planes[n] = _with(planes[n], message=COINCIDENT_MESSAGE, in_pair=True)
            readout = PairReadout(pair_names, message=COINCIDENT_MESSAGE)
        else:
            normals = plane_eqs[:, :3]
            baseline = np.stack([o1, o2])
            ep = None
            if isinstance(c1, PinholeCamera) and isinstance(c2, PinholeCamera):
                ep = epipolar_pair(c1, c2)
                readout = PairReadout(pair_names, ep.F, ep.E, int(np.linalg.matrix_rank(ep.F, tol=1e-9)), ep.e1, ep.e2)
            for name, cam, other in ((n1, c1, o2), (n2, c2, o1)):
                # The pair's epipoles are the images of the other centre (epipole_of_centre): reuse them.
                e = None if ep is None else (ep.e1 if name == n1 else ep.e2)
                planes[name] = _with(planes[name], in_pair=True,
                                     **_pair_content(cam, other, normals, planes[name], name == n1, e))
            sel = scene.selected_point
            if sel is not None and np.all(np.isfinite(normals[sel])):
                tri = np.stack([o1, o2, X[sel]])
                centroid = tri.mean(axis=0)
                epi_plane = centroid + PLANE_MARGIN * (tri - centroid)

    for name, cam in cams.items():
        if isinstance(cam, PinholeCamera):
            ip = planes[name]
            lines3 = np.full((len(X), 2, 3), np.nan)
            if ip.lines is not None and len(X):
                good = np.isfinite(ip.lines.reshape(len(X), -1)).all(axis=1)
                if good.any():
                    lines3[good] = cam.image_to_world(ip.lines[good].reshape(-1, 2), IMAGE_PLANE_DEPTH).reshape(-1, 2, 3)
            image_in_3d[name] = {"points": blocks[name]["pts3"], "lines": lines3}

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


def _pair_content(cam, other_centre: np.ndarray, normals: np.ndarray, plane: ImagePlane, first: bool,
                  epipole: np.ndarray | None = None) -> dict:
    """Epipoles and epipolar curves of one member of the drawn pair (``epipole``: already known, pin-hole)."""
    idx = "1" if first else "2"
    if isinstance(cam, PinholeCamera):
        e = epipole if epipole is not None else epipole_of_centre(cam, other_centre)[0]
        lines = lines_of_planes(cam, normals) if len(normals) else np.zeros((0, 3))
        segs, _ = clip_lines_to_rect(lines, plane.width, plane.height) if len(lines) else (np.zeros((0, 2, 2)), None)
        return {"epipoles": (_epipole(f"e{idx}", e, plane.width, plane.height),), "lines": segs}
    from ..geometry.panoramic_epipolar import sample_plane_conics

    d = cam.pose.R.T @ (other_centre - cam.pose.t)
    proj = cam.project_directions(np.stack([d, -d]))
    epis = []
    for label, px, vis in zip((f"e{idx}", f"e{idx}'"), proj.pixels, proj.visible):
        if vis:
            epis.append(_epipole(label, np.append(px, 1.0), plane.width, plane.height))
    n_mirror = normals @ cam.pose.R
    lo, hi = CONIC_SAMPLES
    n_samples = int(np.clip(CONIC_VERTEX_BUDGET // max(len(normals), 1), lo, hi))
    arcs = sample_plane_conics(cam, n_mirror, n_samples) if len(normals) else []
    return {"epipoles": tuple(epis), "conics": tuple(tuple(a) for a in arcs)}
