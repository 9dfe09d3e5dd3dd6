"""The two visual-servoing demos without a page: each one's model, run parameters, simulation and frame geometry.

A demo (:class:`ServoDemoModel`) is what :class:`~egtviz.controllers.servo.ServoController` needs to know of it: its
name, its camera and scene (the image size, the world points, a mirror's rim), what its run fields accept
(:attr:`ServoDemoModel.RULES`, :attr:`ServoDemoModel.CHOICES`), its simulation (:mod:`egtviz.servo`) called with the
run values, the run's per-frame geometry (:mod:`egtviz.servo.frames`) and the image caption of a frame.
:data:`SERVO_MODELS` maps each demo's name to its model:

* ``"pinhole"``: :class:`PinholeServoModel`, a camera on a Puma 560 under Rives' hybrid task;
* ``"panoramic"``: :class:`PanoramicServoModel`, a catadioptric camera on a holonomic robot, bi-conics.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from functools import lru_cache
from typing import ClassVar

import numpy as np

from ..geometry.poses import Pose
from ..scene.limits import SERVO_DEMO_STEPS
from ..servo import ServoResult, simulate_panoramic, simulate_pinhole
from ..servo.cli import ESTIMATOR_CHOICES
from ..servo.frames import DHChain, ServoFrames, panoramic_frames, pinhole_frames
from ..servo.panoramic_robot import default_camera, mirror_pose
from ..servo.panoramic_robot import default_scene as panoramic_scene
from ..servo.pinhole_arm import TARGET_Q, camera_pose_from_q, default_intrinsics, puma
from ..servo.pinhole_arm import default_scene as pinhole_scene
from .workbench_fields import NumberRule

__all__ = ["PHASES", "RUN_RULES", "SERVO_MODELS", "SPEEDS", "Choice", "PanoramicServoModel",
           "PinholeServoModel", "Progress", "RunValue", "ServoDemoModel", "SimulationKwargs", "puma_chain"]

#: A choice field: its label in messages and its options.
Choice = tuple[str, tuple[str, ...]]
#: A run parameter's last valid value: a number (whole for an integer rule) or one of a choice's options.
RunValue = int | float | str
#: The keyword arguments of a demo's simulation (``seed``, ``noise_px``, ``steps`` and the demo's own).
SimulationKwargs = dict[str, int | float | None]
#: A simulation's ``progress(step, steps)``.
Progress = Callable[[int, int], None]

#: The playback speeds, simulated seconds per real second.
SPEEDS = ("0.25x", "0.5x", "1x", "2x", "4x")
#: What the run fields of every demo accept; a demo adds its own (``ServoDemoModel.RULES``).
RUN_RULES = {
    "seed": NumberRule("seed", "", 0, 2**32 - 1, integer=True),
    "noise_px": NumberRule("noise", "px", 0.0, 50.0),
    "steps": NumberRule("max steps", "", SERVO_DEMO_STEPS.low, SERVO_DEMO_STEPS.high, integer=True),
}
#: The phases of the panoramic control law (``result.extras["phase"]``) as the caption names them.
PHASES = {1: "step 1: rotation", 2: "step 2: translation"}


@lru_cache(maxsize=1)
def puma_chain() -> DHChain:
    """The Puma 560's Denavit-Hartenberg chain (forward kinematics of its link frames)."""
    return DHChain.of_robot(puma()[0])


class ServoDemoModel(ABC):
    """One demo's camera, scene and simulation: what its controller runs and its page draws.

    Attributes:
        width, height: the camera's image size, pixels.
        points: (N, 3) the world points.
        target_pose: the moving body's goal pose.
        rim: the mirror's rim in the image (``None``: no mirror).
    """

    kind: ClassVar[str]
    """The demo's name (``data-demo`` of its image, the thread names)."""
    DEFAULT_STEPS: ClassVar[int]
    RULES: ClassVar[dict[str, NumberRule]] = RUN_RULES
    """Every numeric run parameter and what its field accepts."""
    CHOICES: ClassVar[dict[str, Choice]] = {"speed": ("speed", SPEEDS)}
    """Every drop-down parameter: its label and options."""
    DEFAULTS: ClassVar[dict[str, RunValue]] = {}
    """The first values of the demo's own run parameters."""

    width: int
    height: int
    points: np.ndarray
    target_pose: Pose
    rim: np.ndarray | None = None

    def kwargs(self, values: Mapping[str, RunValue]) -> SimulationKwargs:
        """The simulation's keyword arguments from the run values."""
        return {"seed": int(values["seed"]), "noise_px": float(values["noise_px"]), "steps": int(values["steps"])}

    @abstractmethod
    def simulate(self, values: Mapping[str, RunValue], progress: Progress) -> ServoResult:
        """Run the simulation with the run values (the keyword arguments of :meth:`kwargs`)."""
        raise NotImplementedError

    @abstractmethod
    def derive(self, result: ServoResult, stop: Callable[[], bool]) -> ServoFrames | None:
        """The run's per-frame geometry (None if ``stop()`` became True)."""
        raise NotImplementedError

    def caption(self, result: ServoResult, k: int) -> str:
        """The image caption at frame ``k``."""
        return f"t = {result.time[k]:.2f} s"


class PinholeServoModel(ServoDemoModel):
    """The pin-hole demo: a camera on a Puma 560 under Rives' hybrid task; run fields beta and the F estimator."""

    kind: ClassVar[str] = "pinhole"
    DEFAULT_STEPS: ClassVar[int] = 1000
    RULES: ClassVar[dict[str, NumberRule]] = {**RUN_RULES, "beta": NumberRule("beta", "", 0.0, 100.0)}
    CHOICES: ClassVar[dict[str, Choice]] = {**ServoDemoModel.CHOICES,
                                            "estimator": ("F estimator", tuple(ESTIMATOR_CHOICES))}
    """Beside the shared ones: the F estimator (``egtviz servo``'s ``--estimator`` options)."""
    DEFAULTS: ClassVar[dict[str, RunValue]] = {"beta": 1.0, "estimator": "true"}

    def __init__(self) -> None:
        self.intrinsics = default_intrinsics()
        self.target_pose = camera_pose_from_q(TARGET_Q)
        self.points = pinhole_scene(self.target_pose)
        self.width, self.height = self.intrinsics.width, self.intrinsics.height

    def kwargs(self, values: Mapping[str, RunValue]) -> SimulationKwargs:
        return {**super().kwargs(values), "beta": float(values["beta"]),
                "f_algorithm": ESTIMATOR_CHOICES[str(values["estimator"])]}

    def simulate(self, values: Mapping[str, RunValue], progress: Progress) -> ServoResult:
        return simulate_pinhole(seed=int(values["seed"]), noise_px=float(values["noise_px"]),
                                steps=int(values["steps"]), beta=float(values["beta"]),
                                f_algorithm=ESTIMATOR_CHOICES[str(values["estimator"])], progress=progress)

    def derive(self, result: ServoResult, stop: Callable[[], bool]) -> ServoFrames | None:
        target = result.extras.get("target_pose")
        target_pose = self.target_pose if target is None else Pose.from_matrix(target)
        return pinhole_frames(result, self.intrinsics, target_pose, chain=puma_chain(), stop=stop)


class PanoramicServoModel(ServoDemoModel):
    """The panoramic demo: a catadioptric camera on a holonomic robot; only the shared run fields."""

    kind: ClassVar[str] = "panoramic"
    DEFAULT_STEPS: ClassVar[int] = 1500

    def __init__(self) -> None:
        self.camera = default_camera()
        self.target_pose = mirror_pose(np.zeros(3))
        self.points = panoramic_scene()
        self.width, self.height = self.camera.width, self.camera.height
        self.rim = self.camera.rim_image()

    def simulate(self, values: Mapping[str, RunValue], progress: Progress) -> ServoResult:
        return simulate_panoramic(seed=int(values["seed"]), noise_px=float(values["noise_px"]),
                                  steps=int(values["steps"]), camera=self.camera, progress=progress)

    def derive(self, result: ServoResult, stop: Callable[[], bool]) -> ServoFrames | None:
        return panoramic_frames(result, self.camera, self.target_pose, stop=stop)

    def caption(self, result: ServoResult, k: int) -> str:
        phases = result.extras.get("phase")
        caption = super().caption(result, k)
        if phases is not None and k < len(phases) and np.isfinite(phases[k]):
            caption += "  " + PHASES.get(int(phases[k]), PHASES[2])
        return caption


#: Every demo's model by name.
SERVO_MODELS: dict[str, type[ServoDemoModel]] = {"pinhole": PinholeServoModel, "panoramic": PanoramicServoModel}
