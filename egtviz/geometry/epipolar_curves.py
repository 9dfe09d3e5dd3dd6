r"""Epipolar curves of any two central camera models, by one route.

The epipolar plane of a scene point :math:`X` contains both centres :math:`c_1, c_2` and :math:`X`; its
world normal is

.. math:: n = (c_2 - c_1) \times (X - c_1).

Each camera images that plane through its own centre with
:meth:`~egtviz.geometry.camera_model.CameraModel.plane_image_conics` (a double line for the pin-hole, a conic
for the sphere models), ``plane_image_lines`` (the pin-hole's line :math:`l`, equal to :math:`F m_1` up to scale)
and ``plane_image_arcs`` (the sampled, really visible arcs). The epipoles are the images of the baseline:
in image 1 of the direction :math:`c_2 - c_1`, in image 2 of :math:`c_1 - c_2`
(``baseline_images``: one for a pin-hole, two, :math:`\pm`, for a sphere model). Every epipolar curve of an
image passes through that image's epipoles and through the image of its point (H&Z 9.1; Geyer &
Daniilidis; ``docs/conventions.md``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_points
from .camera_model import CameraModel, check_sample_count
from ._shared import epipolar_normals_columns
from .epipolar import epipolar_planes

__all__ = ["EpipolarCurvePair", "EpipolarCurves", "epipolar_curves", "epipolar_plane_normals"]


@dataclass(frozen=True, eq=False)
class EpipolarCurves:
    """The epipolar curves of N scene points in one camera of a pair, and that image's epipoles."""

    conics: np.ndarray | None
    """(N, 3, 3) exact conics :math:`m^T C m = 0`, unit Frobenius norm (a double line :math:`l l^T` for a pin-hole);
    NaN rows for points on the baseline; None if not asked for or the model has none (its plane images are sampled
    arcs)."""
    lines: np.ndarray | None
    """(N, 3) exact lines :math:`l \\cdot m = 0` where the model images planes to lines (pin-hole), else None."""
    arcs: Sequence[Sequence[np.ndarray]]
    """Per point, the visible arcs (k, 2) of its curve inside the camera's drawn region (empty: none); an empty
    list when not asked for."""
    epipoles: np.ndarray
    """(k, 3) homogeneous epipoles (``baseline_images`` of the direction to the other centre; row 0 towards it)."""
    epipoles_visible: np.ndarray
    """(k,) bool: the camera really shows that epipole."""


@dataclass(frozen=True, eq=False)
class EpipolarCurvePair:
    """The epipolar curves of N scene points in both cameras of a pair."""

    normals: np.ndarray
    """(N, 3) unit world normals of the epipolar planes; NaN rows for points on the baseline."""
    first: EpipolarCurves
    """In camera 1."""
    second: EpipolarCurves
    """In camera 2."""


_MODEL_TYPES: set[type] = set()
"""Classes whose instances passed the (structural, slow) ``isinstance(camera, CameraModel)`` check."""


def _check_model(camera: object, name: str) -> CameraModel:
    if type(camera) in _MODEL_TYPES:  # every instance of a model class has the interface's members
        return camera  # type: ignore[return-value]
    if not isinstance(camera, CameraModel):
        raise GeometryError(f"{name}: expected a camera model (CameraModel), got {type(camera).__name__}")
    _MODEL_TYPES.add(type(camera))
    return camera


def epipolar_plane_normals(cam1: CameraModel, cam2: CameraModel, X_world: npt.ArrayLike) -> np.ndarray:
    r"""Unit world normals (N, 3) :math:`n \propto (c_2 - c_1) \times (X - c_1)` of the epipolar planes of ``X_world``.

    Raises:
        DegenerateConfigurationError: if the two centres coincide.
    """
    cam1 = _check_model(cam1, "cam1")
    cam2 = _check_model(cam2, "cam2")
    X = as_points(X_world, "X_world", 3)
    return epipolar_planes(cam1.centre, cam2.centre, X)[:, :3]


def epipolar_curves(
    cam1: CameraModel, cam2: CameraModel, X_world: npt.ArrayLike, *, n_samples: int = 96, conics: bool = True,
    arcs: bool = True, check: bool = True,
) -> EpipolarCurvePair:
    """Epipolar curves of scene points in both cameras, and the epipoles, for any two camera models.

    Args:
        cam1: first camera (any :class:`~egtviz.geometry.camera_model.CameraModel`).
        cam2: second camera.
        X_world: (N, 3) scene points.
        n_samples: samples per curve for the arcs (>= 3).
        conics: compute the exact conics (False: ``conics`` is None; a viewer that draws the arcs needs none).
        arcs: sample the arcs (False: ``arcs`` is empty; a viewer that draws a pin-hole's lines clips them itself).
        check: check the arguments (default). ``check=False`` is the per-drag fast path: the caller promises two
            camera models, ``X_world`` a float64 (N, 3) array of finite values within ``MAX_MAGNITUDE`` and
            ``n_samples`` a whole number in ``3..MAX_SAMPLES``; nothing is converted or checked, and anything else
            gives an undefined result. Coincident centres still raise.

    Returns:
        An :class:`EpipolarCurvePair`. A point on the baseline (the centres included) has no unique epipolar
        plane: NaN normal, NaN conic and line rows, no arcs.

    Raises:
        DegenerateConfigurationError: if the two centres coincide.
        GeometryError: on a camera that is not a camera model, or bad points.
    """
    if check:
        n_samples = check_sample_count(n_samples, "n_samples", 3)
        normals = epipolar_plane_normals(cam1, cam2, X_world)
    else:
        # Coordinate-major normals of the checked points (one product for all of them), back to rows.
        normals = epipolar_normals_columns(cam1.centre, cam2.centre, cast(np.ndarray, X_world).T).T
    baseline = cam2.centre - cam1.centre
    return EpipolarCurvePair(
        normals, _curves(cam1, normals, baseline, n_samples, conics, arcs, check),
        _curves(cam2, normals, -baseline, n_samples, conics, arcs, check),
    )


def _curves(camera: CameraModel, normals: np.ndarray, towards_other: np.ndarray, n_samples: int,
            conics: bool, arcs: bool, check: bool) -> EpipolarCurves:
    epipoles = camera.baseline_images(towards_other, check=check)
    return EpipolarCurves(
        conics=camera.plane_image_conics(normals, check=check) if conics else None,
        lines=camera.plane_image_lines(normals, check=check),
        arcs=camera.plane_image_arcs(normals, n_samples, check=check) if arcs else [],
        epipoles=epipoles.points,
        epipoles_visible=epipoles.visible,
    )
