"""The visual-servoing demos in the browser by name (EGT reference, section 7): one class per demo.

:data:`SERVO_DEMOS` maps each demo's name to its class, every one a
:class:`~egtviz.viewer.servo.servo_player.ServoPlayer` (the shared run fields, playback, panel and plots):

* ``"pinhole"``: :class:`~egtviz.viewer.servo.servo_pinhole_demo.PinholeServoDemo`, a camera on a Puma 560 under
  Rives' hybrid task;
* ``"panoramic"``: :class:`~egtviz.viewer.servo.servo_panoramic_demo.PanoramicServoDemo`, a catadioptric camera on a
  holonomic robot, bi-conics.

Lessons load a demo and drive it::

    demo = make_servo_demo(client, "pinhole", beta=0.0, autoplay=False)   # or PinholeServoDemo(client, ...)
    demo.on_result(lambda r: check(r))      # called after every finished run
    demo.set_params(beta=0.5); demo.run(wait=True); demo.seek_time(3.0); demo.play()
"""

from __future__ import annotations

from typing import Any, Literal

import viser

from .servo_panoramic_demo import PanoramicServoDemo
from .servo_pinhole_demo import PinholeServoDemo
from .servo_player import ServoPlayer

__all__ = ["SERVO_DEMOS", "DemoKind", "ServoDemo", "make_servo_demo"]

DemoKind = Literal["pinhole", "panoramic"]

#: Every demo's class by name.
SERVO_DEMOS: dict[str, type[ServoPlayer]] = {"pinhole": PinholeServoDemo, "panoramic": PanoramicServoDemo}

#: The type every demo is (``isinstance(demo, ServoDemo)``).
ServoDemo = ServoPlayer


def make_servo_demo(client: viser.ClientHandle, kind: str, **options: Any) -> ServoPlayer:
    """Open demo ``kind`` (a key of :data:`SERVO_DEMOS`) in ``client`` with the demo's keyword ``options``.

    Raises:
        ValueError: an unknown ``kind``, or an option the demo does not have or refuses.
    """
    cls = SERVO_DEMOS.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise ValueError(f"kind: expected one of {', '.join(map(repr, SERVO_DEMOS))}, got {kind!r}")
    return cls(client, **options)
