r"""The convention lens: the drawn pin-hole pair's epipolar geometry as the classic mistakes would compute it.

Headless: the viewer draws what :func:`lens_view` returns. With every toggle off the lens shows the true
geometry of ``docs/conventions.md``:

.. math:: R = R_2^T R_1, \quad t = R_2^T (t_1 - t_2), \quad E = [t]_\times R, \quad
          F = K_2^{-T} E K_1^{-1}, \quad m_2^T F m_1 = 0 .

Each toggle replaces one step by the mistake people make:

* ``opengl_axes``: the camera frames are read with OpenGL's axes (x right, **y up, z backwards**) where
  OpenCV's (y down, z forwards) are meant: :math:`R_i \to R_i D`, :math:`D = \mathrm{diag}(1, -1, -1)`,
  so :math:`E \to D E D`.
* ``r_tx``: :math:`E = R [t]_\times` instead of :math:`[t]_\times R`.
* ``k_transposed``: :math:`F = K_2^{-T} E K_1^{T}` instead of :math:`K_2^{-T} E K_1^{-1}`.
* ``f_transposed``: the panels use :math:`F^T` where :math:`F` is meant (lines :math:`F^T m_1` in image 2).
* ``wrong_singular_vector``: with :math:`F = U \Sigma V^T`, :math:`e_1` is taken from the last column of
  :math:`U` and :math:`e_2` from the last row of :math:`V^T` (they are the other way round:
  :math:`F e_1 = 0`, :math:`F^T e_2 = 0`). The lines are right; they no longer meet at the drawn epipole.

The live residuals :math:`m_2^T F m_1` (``F`` as shown, unit Frobenius norm) and the distances of each
point from its own epipolar line tell a working lens from a broken one.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ..geometry import GeometryError, PinholeCamera, normalize_homogeneous
from ..geometry.epipolar import relative_pose
from ..geometry.poses import skew
from .derived import Derived, compute_derived
from .scene import Scene
from .specs import SceneError

__all__ = ["LensToggles", "LensView", "lens_view"]

_D = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class LensToggles:
    """Which mistakes the lens applies (all False: the true geometry)."""

    f_transposed: bool = False
    """Use :math:`F^T` in place of :math:`F`."""
    wrong_singular_vector: bool = False
    """Take each epipole from the other singular vector of the SVD of ``F``."""
    r_tx: bool = False
    """:math:`E = R [t]_\\times` in place of :math:`[t]_\\times R`."""
    k_transposed: bool = False
    """:math:`K_2^{-T} E K_1^{T}` in place of :math:`K_2^{-T} E K_1^{-1}`."""
    opengl_axes: bool = False
    """Camera axes of the OpenGL convention (y up, z backwards) where OpenCV's are meant."""

    def __post_init__(self) -> None:
        for f in fields(self):
            if type(getattr(self, f.name)) is not bool:
                raise SceneError(f"{f.name}: expected true or false, got {getattr(self, f.name)!r:.40}")

    @property
    def any(self) -> bool:
        """At least one mistake is on."""
        return any(getattr(self, f.name) for f in fields(self))

    def switched(self, other: LensToggles) -> LensToggles:
        """The toggles that differ between ``self`` and ``other`` (on where one has the mistake and the other not).

        A lens that hides its settings shows ``start.switched(now)``: what the learner switched since the step
        set its hidden mistake, not which mistakes are on; and ``start.switched(shown)`` is the lens in effect.
        """
        return LensToggles(**{f.name: getattr(self, f.name) != getattr(other, f.name) for f in fields(self)})


@dataclass(frozen=True, eq=False)
class LensView:
    """What the panels draw through the lens, for the points of the drawn pin-hole pair."""

    names: tuple[str, str]
    """The drawn pair (image 1, image 2)."""
    F: np.ndarray
    """(3, 3) the fundamental matrix as shown (unit Frobenius norm)."""
    E: np.ndarray
    """(3, 3) the essential matrix it was built from (unit Frobenius norm)."""
    F_true: np.ndarray
    """(3, 3) the true ``F`` (unit Frobenius norm)."""
    e1: np.ndarray
    """(3,) the epipole drawn in image 1 (``normalize_homogeneous``: last coordinate 1, or 0 at infinity)."""
    e2: np.ndarray
    """(3,) the epipole drawn in image 2."""
    pixels1: np.ndarray
    """(N, 2) the points in image 1 (NaN without an image)."""
    pixels2: np.ndarray
    """(N, 2) the points in image 2."""
    lines1: np.ndarray
    """(N, 3) lines :math:`F^T m_2` in image 1, scaled to :math:`a^2 + b^2 = 1` (NaN rows without a point)."""
    lines2: np.ndarray
    """(N, 3) lines :math:`F m_1` in image 2, scaled likewise."""
    residuals: np.ndarray
    """(N,) :math:`m_2^T F m_1` with ``F`` as shown (NaN for a point missing from an image)."""
    distances1_px: np.ndarray
    """(N,) distance of each point of image 1 from its line in image 1, pixels."""
    distances2_px: np.ndarray
    """(N,) distance of each point of image 2 from its line in image 2, pixels."""


def _unit(M: np.ndarray) -> np.ndarray:
    return M / np.linalg.norm(M)


def _lines(F_rows: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """Lines ``F_rows @ (u, v, 1)`` per pixel row, scaled to ``a^2 + b^2 = 1``; NaN rows where the pixel is NaN."""
    h = np.column_stack([pixels, np.ones(len(pixels))])
    lines = h @ F_rows.T
    with np.errstate(invalid="ignore", divide="ignore"):
        return lines / np.hypot(lines[:, 0], lines[:, 1])[:, None]


def lens_view(scene: Scene, toggles: LensToggles = LensToggles(), derived: Derived | None = None) -> LensView:
    r"""The drawn pair's ``F``, epipoles, epipolar lines and residuals through the lens ``toggles``.

    Args:
        scene: a scene whose drawn pair (:attr:`Scene.drawn_pair`) is two pin-hole cameras.
        toggles: the mistakes to apply (module docstring).
        derived: ``compute_derived(scene)`` if already at hand (the points' pixels are read from it).

    Raises:
        SceneError: no drawn pair, a panoramic camera in it, or coincident centres.
    """
    if not isinstance(toggles, LensToggles):
        raise SceneError(f"toggles: expected LensToggles, got {type(toggles).__name__}")
    names = scene.drawn_pair
    if names is None:
        raise SceneError("the convention lens needs two cameras")
    c1, c2 = (scene.camera(n).camera() for n in names)
    if not (isinstance(c1, PinholeCamera) and isinstance(c2, PinholeCamera)):
        raise SceneError(f"the convention lens needs a pin-hole pair, got {names[0]!r} and {names[1]!r}")
    derived = compute_derived(scene) if derived is None else derived
    if derived.pair.F is None:
        raise SceneError(f"the convention lens: {derived.pair.message}")
    R, t = relative_pose(c1.pose, c2.pose)
    if toggles.opengl_axes:
        R, t = _D @ R @ _D, _D @ t
    E = R @ skew(t) if toggles.r_tx else skew(t) @ R
    K1, K2 = c1.K, c2.K
    K1_part = K1.T if toggles.k_transposed else np.linalg.inv(K1)
    F = np.linalg.inv(K2).T @ E @ K1_part
    if toggles.f_transposed:
        F = F.T
    F = _unit(F)
    try:
        U, _, Vt = np.linalg.svd(F)
        right, left = normalize_homogeneous(Vt[2]), normalize_homogeneous(U[:, 2])
    except GeometryError as exc:  # pragma: no cover - an SVD null vector is never zero
        raise SceneError(f"the convention lens: {exc}") from exc
    e1, e2 = (left, right) if toggles.wrong_singular_vector else (right, left)
    p1 = derived.image_planes[names[0]].points
    p2 = derived.image_planes[names[1]].points
    lines2 = _lines(F, p1)  # F m1
    lines1 = _lines(F.T, p2)  # F^T m2
    h1 = np.column_stack([p1, np.ones(len(p1))])
    h2 = np.column_stack([p2, np.ones(len(p2))])
    residuals = np.einsum("ni,ij,nj->n", h2, F, h1)
    d2 = np.abs(np.einsum("ni,ni->n", lines2, h2))
    d1 = np.abs(np.einsum("ni,ni->n", lines1, h1))
    return LensView(
        names=names, F=F, E=_unit(E), F_true=_unit(np.asarray(derived.pair.F)), e1=e1, e2=e2,
        pixels1=p1, pixels2=p2, lines1=lines1, lines2=lines2, residuals=residuals,
        distances1_px=d1, distances2_px=d2,
    )
