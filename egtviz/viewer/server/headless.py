"""A minimal websocket stand-in for a browser tab (headless tests, the benchmark).

viser counts a client as connected after its first ``ViewerCameraMessage``;
this client sends one, then drains the server's messages in a thread.
"""

from __future__ import annotations

import threading

import msgspec
import viser
from websockets.sync.client import connect
from websockets.typing import Subprotocol


#: Seconds a fake tab waits for its connection and :func:`start_headless` for each tab's view: minutes, since a
#: test on a busy machine is slow but must not fail for it (a broken server still fails, after this bound).
CONNECT_TIMEOUT = 300.0


class FakeTab:
    def __init__(self, port: int) -> None:
        self.ws = connect(
            f"ws://127.0.0.1:{port}", subprotocols=[Subprotocol(f"viser-v{viser.__version__}")], max_size=None,
            open_timeout=CONNECT_TIMEOUT,
        )
        self.received = 0
        self.ws.send(
            msgspec.msgpack.encode(
                {
                    "type": "ViewerCameraMessage",
                    "wxyz": [1.0, 0.0, 0.0, 0.0],
                    "position": [0.0, -10.0, 3.0],
                    "fov": 1.0,
                    "near": 0.01,
                    "far": 1000.0,
                    "image_height": 720,
                    "image_width": 1280,
                    "look_at": [0.0, 0.0, 0.0],
                    "up_direction": [0.0, 0.0, 1.0],
                }
            )
        )
        self._thread = threading.Thread(target=self._drain, daemon=True)
        self._thread.start()

    def _drain(self) -> None:
        try:
            while True:
                self.ws.recv()
                self.received += 1
        except Exception:  # noqa: BLE001 - closed
            pass

    def send(self, message_type: str, **fields: object) -> None:
        """Send one viser message as a raw client may (no checks: tests forge values with it)."""
        self.ws.send(msgspec.msgpack.encode({"type": message_type, **fields}))

    def close(self) -> None:
        self.ws.close()


def start_headless(scene=None, *, tabs: int = 1, field_delay: float = 0.0):
    """A server on a free local port with the app and ``tabs`` connected fake tabs.

    ``field_delay`` is the app's text-field delay; 0 (the default here) judges a
    field's text inside the assignment to ``handle.value``, so a test can read the result at once.
    Returns ``(server, app, fake_tabs, views)``; call ``server.stop()`` when done.
    """
    from ..tabs import EgtvizApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = EgtvizApp(server, scene, field_delay=field_delay)
    fakes = []
    views = []
    for k in range(tabs):
        fakes.append(FakeTab(server.get_port()))
        app.wait_for_view(count=k + 1, timeout=CONNECT_TIMEOUT)
        views = sorted(app.views.items())
    return server, app, fakes, [v for _, v in views]
