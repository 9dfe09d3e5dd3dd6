"""One process, one instructor's drags shown to M headless followers: the sender's cost per follower.

``python -m egtviz.bench.classroom_followers [--followers M] [--steps K]``. Method (also in
``docs/benchmarks.md``): a viser server on a free loopback port, M raw websocket tabs (``FakeTab``), a
:class:`~egtviz.viewer.classroom.follow_view.FollowView` on each; every 50 ms (20 Hz) camera 1 of the default scene
moves and one frame of it is shown to every follower in turn, as the room's sender thread does. Reported: the
wall time to show one frame to all followers (p50, p99) and the sender thread's CPU time per follower (median).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence

import numpy as np

__all__ = ["run_followers_local"]

#: Steps left out of the figures (the first frames also build nodes).
WARM_UP = 2


def run_followers_local(followers: int = 100, steps: int = 100, rate: float = 20.0) -> dict[str, float]:
    """``{"p50_ms", "p99_ms", "cpu_us_per_follower", "failed"}`` of ``steps`` drags shown to ``followers`` tabs."""
    import viser

    from ..scene import SceneModel, default_scene
    from ..viewer.classroom.follow_view import FollowView, RoomFrame
    from ..viewer.server.headless import FakeTab

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tabs = [FakeTab(server.get_port()) for _ in range(followers)]
    try:
        deadline = time.monotonic() + 60
        while len(server.get_clients()) < followers and time.monotonic() < deadline:
            time.sleep(0.05)
        model = SceneModel(default_scene())
        name = model.scene.cameras[0].name
        p0 = np.asarray(model.scene.camera(name).position, float)
        views = [FollowView(c, RoomFrame(1, 1, model.scene, model.derived, (), "", False))
                 for c in server.get_clients().values()]
        time.sleep(2.0)  # the first frames reach the tabs
        wall, cpu, failed = [], [], 0
        tick = time.perf_counter()
        for i in range(steps):
            model.update_camera(name, position=tuple(p0 + (0.01 * (i + 1), 0.005 * i, 0.0)))
            frame = RoomFrame(i + 2, i + 2, model.scene, model.derived, (), "", False)
            time.sleep(max(0.0, 1.0 / rate - (time.perf_counter() - tick)))
            tick = time.perf_counter()
            c0 = time.thread_time()
            for view in views:
                try:
                    view.show(frame)
                except RuntimeError:  # viser's message event, set from this thread, raced its event loop
                    failed += 1
            wall.append(time.perf_counter() - tick)
            cpu.append(time.thread_time() - c0)
        w = np.array(wall[WARM_UP:]) * 1e3
        return {"p50_ms": float(np.percentile(w, 50)), "p99_ms": float(np.percentile(w, 99)),
                "cpu_us_per_follower": float(np.median(cpu[WARM_UP:])) * 1e6 / max(len(views), 1),
                "failed": float(failed)}
    finally:
        for tab in tabs:
            tab.close()
        server.stop()


def main(argv: Sequence[str] | None = None) -> int:
    import os

    p = argparse.ArgumentParser(prog="python -m egtviz.bench.classroom_followers")
    p.add_argument("--followers", type=int, default=100)
    p.add_argument("--steps", type=int, default=100)
    args = p.parse_args(argv)
    r = run_followers_local(args.followers, args.steps)
    print(f"{args.followers} followers, {args.steps} drags at 20 Hz (load average {os.getloadavg()[0]:.1f}): "
          f"one frame to all followers p50 {r['p50_ms']:.1f} ms, p99 {r['p99_ms']:.1f} ms; sender CPU per follower "
          f"{r['cpu_us_per_follower']:.0f} us; failed shows {r['failed']:.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
