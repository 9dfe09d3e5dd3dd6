"""Visual-servoing simulations of the EGT tutorial (reference section 7), headless.

- :func:`simulate_pinhole`: pin-hole camera on a Puma 560, Rives' hybrid task function.
- :func:`simulate_panoramic`: panoramic camera on a holonomic robot, bi-conics then translation.

Both return a :class:`ServoResult` (time series + summary, ``to_json_dict()``);
:mod:`egtviz.servo.frames` derives what a viewer draws at every frame of it (epipolar lines, bi-conics,
epipoles, the arm's forward kinematics, paths and trails). Each
demo keeps its pure control-law functions, its state-update step and its
``simulate_*`` loop apart, so a viewer can replay or step them. No viewer imports here.
"""

from .panoramic_robot import simulate_panoramic as simulate_panoramic
from .pinhole_arm import simulate_pinhole as simulate_pinhole
from .result import ServoResult as ServoResult

__all__ = ["ServoResult", "simulate_panoramic", "simulate_pinhole"]
