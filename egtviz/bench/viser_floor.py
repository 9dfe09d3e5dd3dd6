"""The floor under the server CPU per drag update: a bare viser server whose gizmo callback does nothing.

Method: a :class:`viser.ViserServer` on a free loopback port with one transform control and a callback that only
counts; one raw websocket tab (:mod:`egtviz.bench.ws_client`) in a separate process sends the gizmo's pose
``rate`` times a second for ``seconds``, as a browser does during a drag. The figure is the server process's CPU
time (``time.process_time``: all its threads) from the first send until the tab has sent its last and drained what
came back, divided by the callbacks run. No egtviz code runs in the server: this is what receiving one pose costs
before the app does anything, so no app can spend less per update at that rate on the same machine.
"""

from __future__ import annotations

import asyncio
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["FLOOR_RATES_HZ", "FloorRun", "format_floor", "viser_floor"]

#: Update rates of ``egtviz bench classroom``'s floor rows: one dragging tab, five, and a busy classroom.
FLOOR_RATES_HZ = (20.0, 100.0, 500.0)
_GIZMO = "/floor_gizmo"


@dataclass(frozen=True)
class FloorRun:
    """One floor measurement."""

    rate_hz: float
    sent: int
    callbacks: int
    cpu_s: float

    @property
    def cpu_ms_per_update(self) -> float:
        """Server CPU per callback run, in ms (NaN when none ran)."""
        return 1e3 * self.cpu_s / self.callbacks if self.callbacks else float("nan")


async def _tab(port: int, rate: float, seconds: float) -> None:
    from .ws_client import RawClient

    async with RawClient.connect(port) as client:
        await client.wait_for(("TransformControlsMessage",))
        owner = next(m for m in client.messages if m["type"] == "TransformControlsMessage")["owner"]
        print("ready", flush=True)
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)
        n = round(rate * seconds)
        t0 = time.time()
        for k in range(n):
            await asyncio.sleep(max(0.0, t0 + k / rate - time.time()))
            await client.send({"type": "TransformControlsUpdateMessage", "name": _GIZMO, "owner": owner,
                               "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [1e-3 * (k + 1), 0.0, 0.0]})
        await client.read_until_quiet(0.3, limit=5.0)
        print(f"sent {n}", flush=True)
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.read)


def viser_floor(rate: float = 20.0, seconds: float = 5.0) -> FloorRun:
    """Server CPU per received gizmo update of a bare viser server with a no-op callback (see the module's method).

    Raises:
        ValueError: ``rate`` or ``seconds`` is not a positive number.
        RuntimeError: the tab's process ended early (the server is stopped all the same).
    """
    if not (rate > 0 and seconds > 0):
        raise ValueError(f"rate, seconds: expected positive numbers, got {rate!r}, {seconds!r}")
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    callbacks = 0

    def counted(_event: object) -> None:
        nonlocal callbacks
        callbacks += 1

    def connected(client: viser.ClientHandle) -> None:
        client.scene.add_transform_controls(_GIZMO).on_update(counted)

    server.on_client_connect(connected)
    proc = subprocess.Popen(
        [sys.executable, "-m", "egtviz.bench.viser_floor", "--tab-of", str(server.get_port()), str(rate),
         str(seconds)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )
    try:
        assert proc.stdin is not None and proc.stdout is not None
        if proc.stdout.readline().strip() != "ready":
            raise RuntimeError(f"the tab's process ended (status {proc.wait(30)}) before joining")
        time.sleep(0.5)  # let the join's messages go before the clock starts
        cpu0 = time.process_time()
        proc.stdin.write("go\n")
        proc.stdin.flush()
        done = proc.stdout.readline().split()
        cpu_s = time.process_time() - cpu0
        if len(done) != 2 or done[0] != "sent":
            raise RuntimeError(f"the tab's process ended (status {proc.wait(30)}) before its last update")
        proc.stdin.close()
        proc.wait(30)
        return FloorRun(float(rate), int(done[1]), callbacks, cpu_s)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
        server.stop()


def format_floor(runs: Sequence[FloorRun]) -> str:
    """The floor rows as text."""
    lines = ["Floor: a bare viser server, one gizmo, a callback that does nothing (no egtviz code):"]
    for r in runs:
        lines.append(f"  {r.rate_hz:>5g} updates/s: {r.callbacks} of {r.sent} received, "
                     f"server CPU {r.cpu_ms_per_update:.3f} ms per update")
    return "\n".join(lines)


def _tab_main(argv: Sequence[str]) -> int:
    port, rate, seconds = argv
    asyncio.run(asyncio.wait_for(_tab(int(port), float(rate), float(seconds)), 60.0 + 2.0 * float(seconds)))
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--tab-of"]:
        raise SystemExit(_tab_main(sys.argv[2:]))
    print(format_floor([viser_floor(r) for r in FLOOR_RATES_HZ]))
