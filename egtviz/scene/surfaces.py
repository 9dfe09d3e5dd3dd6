"""Surfaces sampled into points with normals (EGT's ``f_3Dsurface``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .specs import SceneError, SurfaceSpec

ASSETS = Path(__file__).resolve().parents[2] / "assets"


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
    import trimesh

    path = Path(spec.path)
    if not path.is_absolute():
        path = ASSETS / path
    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise SceneError(f"surface path: cannot load mesh {path}: {exc}") from exc
    pts, faces = trimesh.sample.sample_surface_even(mesh, spec.samples, seed=0)
    return c + spec.size * pts, mesh.face_normals[faces]
