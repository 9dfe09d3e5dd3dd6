"""Surfaces sampled into points with normals (EGT's ``f_3Dsurface``); meshes come only from the assets folder."""

from __future__ import annotations

import io
import os
from functools import lru_cache
from pathlib import Path
from typing import cast

import numpy as np

from ..files import FileSafetyError, read_limited
from ..resources import shipped_folder
from .limits import MAX_MESH_FILE_BYTES
from ._values import SceneError
from .specs import SurfaceSpec

ASSETS = shipped_folder("assets")
"""The folder meshes are read from; nothing outside it is ever read for a surface."""
MESH_EXTENSIONS = (".obj", ".stl", ".ply", ".off")
MESH_EXTENT = 100.0
"""Largest |coordinate| of a mesh's vertices, before the surface's size scales it."""


def _asset_path(name: object) -> Path:
    """The file of the mesh asset ``name``: a plain file name, found in :data:`ASSETS`, not leaving it."""
    if (
        not isinstance(name, str)
        or not name
        or name in (".", "..")
        or os.path.basename(name) != name
        or any(c in name for c in "/\\\0")
        or not name.lower().endswith(MESH_EXTENSIONS)
    ):
        raise SceneError(f"surface path: expected the name of a mesh in the assets ({', '.join(mesh_names())}), "
                         f"got {name!r:.60}")
    root = os.path.realpath(ASSETS)
    real = os.path.realpath(ASSETS / name)
    if os.path.dirname(real) != root or not os.path.isfile(real):
        raise SceneError(f"surface path: no mesh named {name!r} in the assets (have {', '.join(mesh_names())})")
    return Path(real)


def mesh_names() -> tuple[str, ...]:
    """The meshes a surface can use: file names in the assets folder, sorted (the GUI's drop-down)."""
    try:
        entries = sorted(os.listdir(ASSETS))
    except OSError:
        return ()
    root = os.path.realpath(ASSETS)
    out = []
    for name in entries:
        if name.lower().endswith(MESH_EXTENSIONS):
            real = os.path.realpath(ASSETS / name)
            if os.path.dirname(real) == root and os.path.isfile(real):
                out.append(name)
    return tuple(out)


@lru_cache(maxsize=16)
def _load_mesh(name: str):
    """The checked mesh asset ``name`` (a trimesh), loaded once."""
    import trimesh

    path = _asset_path(name)
    try:
        data = read_limited(path, MAX_MESH_FILE_BYTES)
    except FileSafetyError as exc:
        raise SceneError(f"surface path: cannot read mesh {name!r}: {str(exc).split(': ', 1)[-1]}") from None
    try:
        # force="mesh": one Trimesh
        mesh = cast(trimesh.Trimesh, trimesh.load(io.BytesIO(data), file_type=path.suffix[1:].lower(), force="mesh"))
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        ok = len(mesh.faces) > 0 and np.isfinite(vertices).all() and float(mesh.area) > 0
    except Exception as exc:  # noqa: BLE001 - trimesh raises many kinds for unreadable files
        raise SceneError(f"surface path: cannot load mesh {name!r}: {type(exc).__name__}") from None
    if not ok:
        raise SceneError(f"surface path: mesh {name!r} has no faces with area or has non-finite vertices")
    if np.abs(vertices).max() > MESH_EXTENT:
        raise SceneError(f"surface path: mesh {name!r} reaches beyond {MESH_EXTENT:g} units")
    return mesh


@lru_cache(maxsize=32)
def mesh_samples(name: str, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """``(points, unit normals)`` sampled evenly on the mesh asset ``name`` (unscaled, read-only, deterministic).

    Raises:
        SceneError: ``name`` is not a mesh of the assets, or the mesh cannot be loaded.
    """
    import trimesh

    mesh = _load_mesh(name)
    pts, faces = trimesh.sample.sample_surface_even(mesh, samples, seed=0)
    normals = np.asarray(mesh.face_normals[faces], dtype=np.float64)
    pts = np.asarray(pts, dtype=np.float64)
    pts.setflags(write=False)
    normals.setflags(write=False)
    return pts, normals


def check_surface(spec: SurfaceSpec) -> SurfaceSpec:
    """``spec``, once its mesh (for a mesh surface) is found in the assets, loaded and checked (cached by name).

    Raises:
        SceneError: ``"surface path: ..."``: not the plain name of a mesh of the assets, or a mesh that cannot be
            loaded or is empty, degenerate or too large.
    """
    if not isinstance(spec, SurfaceSpec):
        raise SceneError(f"spec: expected a SurfaceSpec, got {type(spec).__name__}")
    if spec.kind == "mesh":
        mesh_samples(spec.path, spec.samples)
    return spec


def _plane_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def sample_surface(spec: SurfaceSpec) -> tuple[np.ndarray, np.ndarray]:
    """``(points (M, 3), unit normals (M, 3))`` of a surface, deterministic."""
    c = np.array(spec.center)
    if spec.kind == "plane":
        n = np.array(spec.normal) / np.linalg.norm(spec.normal)
        u, v = _plane_basis(n)
        k = max(1, int(round(np.sqrt(spec.samples))))
        s = (np.linspace(-0.5, 0.5, k) if k > 1 else np.zeros(1)) * spec.size
        su, sv = np.meshgrid(s, s)
        pts = c + su.reshape(-1, 1) * u + sv.reshape(-1, 1) * v
        return pts, np.tile(n, (len(pts), 1))
    if spec.kind == "sphere":
        # Fibonacci lattice: near-uniform, deterministic.
        i = np.arange(spec.samples) + 0.5
        z = 1.0 - 2.0 * i / spec.samples
        phi = np.pi * (1.0 + np.sqrt(5.0)) * i
        r = np.sqrt(1.0 - z * z)
        n = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
        return c + spec.size * n, n
    pts, normals = mesh_samples(spec.path, spec.samples)
    return c + spec.size * pts, normals.copy()
