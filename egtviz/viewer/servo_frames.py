"""Per-frame drawing data of a recorded servo run (pure; no viser).

A :class:`~egtviz.servo.ServoResult` records poses and features; the image
panels also need, at every frame, the epipolar lines (pin-hole) or the
bi-conics (panoramic). This module derives them by calling
:mod:`egtviz.geometry` only:

* pin-hole: :func:`~egtviz.geometry.epipolar.epipolar_pair` of the current and
  target cameras, then the lines ``l1 = F^T m*`` of the desired features in the
  current image (:func:`~egtviz.geometry.epipolar.epipolar_lines_in_first`),
  clipped to the image (:func:`~egtviz.geometry.epipolar.clipped_epipolar_lines`).
  Every current feature lies on its line once the rotation is compensated.
* panoramic: the bi-conic of each feature pair is the image of the plane through
  the focus spanned by the current and desired rays
  (:meth:`~egtviz.geometry.catadioptric.CatadioptricCamera.back_project`, the
  plane normal ``d x d*`` as in :func:`~egtviz.geometry.panoramic_epipolar.biconic`),
  sampled into polylines with
  :func:`~egtviz.geometry.panoramic_epipolar.sample_biconics`; the true
  epipoles of the current image come from
  :func:`~egtviz.geometry.panoramic_epipolar.panoramic_epipoles`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from egtviz.geometry.catadioptric import CatadioptricCamera
from egtviz.geometry.epipolar import clipped_epipolar_lines, epipolar_lines_in_first, epipolar_pair
from egtviz.geometry.panoramic_epipolar import panoramic_epipoles, sample_biconics
from egtviz.geometry.pinhole import Intrinsics, PinholeCamera
from egtviz.geometry.poses import Pose

__all__ = ["FrameGeometry", "ServoFrames"]

#: Samples per great circle for the bi-conics (each panel draws N of them per frame).
CONIC_SAMPLES = 96


@dataclass(frozen=True)
class FrameGeometry:
    """What the image panel draws at one frame, besides the features and trails."""

    lines: np.ndarray | None = None
    """(N, 2, 2) clipped epipolar-line segments in the current image (pin-hole); NaN rows miss the image."""
    conics: list[list[np.ndarray]] = field(default_factory=list)
    """Per feature, the (k, 2) polylines of its bi-conic (panoramic)."""
    epipoles: list[tuple[str, np.ndarray]] = field(default_factory=list)
    """``(label, (2,) pixel)`` of the epipoles in the current image."""
    message: str = ""
    """Why something is not drawn (e.g. the centres coincide at the goal)."""


class ServoFrames:
    """Lazily derived, cached :class:`FrameGeometry` for every frame of a run.

    Args:
        result: the recorded run.
        pinhole_intrinsics: the pin-hole camera's intrinsics (pin-hole demo).
        camera: the catadioptric camera model, pose ignored (panoramic demo).
        target_pose: the target camera / mirror pose in the world.
    """

    def __init__(
        self,
        result,
        *,
        target_pose: Pose,
        pinhole_intrinsics: Intrinsics | None = None,
        camera: CatadioptricCamera | None = None,
    ) -> None:
        self.result = result
        self.kind = result.demo
        self.target_pose = target_pose
        self.intrinsics = pinhole_intrinsics
        self.camera = camera.moved(Pose()) if camera is not None else None
        if self.kind == "pinhole":
            assert pinhole_intrinsics is not None
            self.width, self.height = pinhole_intrinsics.width, pinhole_intrinsics.height
        else:
            assert camera is not None
            self.width, self.height = camera.width, camera.height
        self._cache: dict[int, FrameGeometry] = {}
        self.rim = self.camera.rim_image() if self.camera is not None else None

    def __len__(self) -> int:
        return self.result.n_samples

    def precompute(self, stop=None) -> None:
        """Derive every frame now (call from a background thread); ``stop()`` True aborts."""
        for k in range(len(self)):
            if stop is not None and stop():
                return
            self.at(k)

    def at(self, k: int) -> FrameGeometry:
        k = int(np.clip(k, 0, len(self) - 1))
        g = self._cache.get(k)
        if g is None:
            g = self._pinhole(k) if self.kind == "pinhole" else self._panoramic(k)
            self._cache[k] = g
        return g

    # -- derivations (egtviz.geometry only) -------------------------------------------

    def _pinhole(self, k: int) -> FrameGeometry:
        r = self.result
        current = PinholeCamera(Pose.from_matrix(r.camera_poses[k]), self.intrinsics)
        target = PinholeCamera(self.target_pose, self.intrinsics)
        try:
            pair = epipolar_pair(current, target)
        except Exception:  # noqa: BLE001 - the centres coincide (goal reached): no epipolar geometry
            return FrameGeometry(message="at the goal: no epipolar geometry (the centres coincide)")
        lines = epipolar_lines_in_first(pair.F, r.desired_features)
        segs, hit = clipped_epipolar_lines(lines, self.width, self.height)
        segs = np.where(np.asarray(hit)[:, None, None], segs, np.nan)
        eps = []
        if not pair.e1_at_infinity:
            eps.append(("e", pair.e1[:2] / pair.e1[2]))
        return FrameGeometry(lines=segs, epipoles=eps)

    def _panoramic(self, k: int) -> FrameGeometry:
        r = self.result
        cam = self.camera
        d = cam.back_project(r.features[k])
        d_star = cam.back_project(r.desired_features)
        ok = np.all(np.isfinite(d), axis=1) & np.all(np.isfinite(d_star), axis=1)  # features the mirror shows
        conics: list[list[np.ndarray]] = [[] for _ in range(len(d))]
        if ok.any():
            arcs = sample_biconics(cam, d[ok], d_star[ok], n=CONIC_SAMPLES)
            for i, a in zip(np.flatnonzero(ok), arcs):
                conics[int(i)] = a
        eps: list[tuple[str, np.ndarray]] = []
        message = ""
        try:
            pe = panoramic_epipoles(cam.moved(Pose.from_matrix(r.camera_poses[k])), cam.moved(self.target_pose))
            for label, e, vis in (("e", pe.e1, pe.e1_visible), ("e'", pe.e1p, pe.e1p_visible)):
                e = np.asarray(e, float)
                if vis and np.all(np.isfinite(e)) and abs(e[2]) > 1e-12:
                    eps.append((label, e[:2] / e[2]))
        except Exception:  # noqa: BLE001 - the foci coincide (goal reached)
            message = "at the goal: no epipoles (the foci coincide)"
        return FrameGeometry(conics=conics, epipoles=eps, message=message)
