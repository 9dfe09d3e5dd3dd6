"""A viser tab without a browser: viser's websocket protocol spoken directly (benchmarks, server tests).

Upstream (tab to server) every message is one msgpack map with a ``type``; downstream the server
batches messages into frames laid out as ``viser/infra/_infra.py`` writes them::

    [8 B little-endian size][8 B little-endian compressed size][zstd( msgpack({"messages": [...]}) )]

viser counts a connection as a tab after its first ``ViewerCameraMessage`` (:data:`CAMERA`), then
runs the app's connect callbacks, whose widgets and scene nodes arrive as messages.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import AsyncIterator, Iterable

import msgspec.msgpack
import viser
import websockets.asyncio.client
import zstandard
from websockets.typing import Origin, Subprotocol

__all__ = ["CAMERA", "RawClient", "decode_frame", "frame_payload"]

#: The first message of a tab: its 3D view's camera and canvas size.
CAMERA = {
    "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [0.0, -5.0, 2.0], "fov": 1.0,
    "near": 0.01, "far": 100.0, "image_height": 600, "image_width": 800, "look_at": [0.0, 0.0, 0.0],
    "up_direction": [0.0, 0.0, 1.0],
}

_HEADER = 16


def frame_payload(frame: bytes) -> bytes:
    """The decompressed msgpack of one server-to-client frame (cheap to search without decoding it).

    Raises:
        ValueError: ``frame`` is shorter than its 16-byte header or than the compressed size it declares.
    """
    if len(frame) < _HEADER:
        raise ValueError(f"frame: expected at least {_HEADER} bytes of header, got {len(frame)}")
    size = int.from_bytes(frame[:8], "little")
    compressed = int.from_bytes(frame[8:_HEADER], "little")
    if len(frame) < _HEADER + compressed:
        raise ValueError(f"frame: declares {compressed} compressed bytes, holds {len(frame) - _HEADER}")
    return zstandard.ZstdDecompressor().decompress(frame[_HEADER:_HEADER + compressed], max_output_size=size)


def decode_frame(frame: bytes) -> list[dict]:
    """The messages of one server-to-client frame, in order."""
    return msgspec.msgpack.decode(frame_payload(frame))["messages"]


class RawClient:
    """One tab: ``send`` msgpack messages, ``read_until_quiet`` to collect what the server sent.

    Attributes:
        ws: the open websocket connection.
        messages: every message received so far, decoded, in order.
    """

    def __init__(self, ws: websockets.asyncio.client.ClientConnection) -> None:
        self.ws = ws
        self.messages: list[dict] = []

    @classmethod
    @contextlib.asynccontextmanager
    async def connect(cls, port: int, *, origin: str | None = None) -> AsyncIterator[RawClient]:
        """Open a loopback connection to a viser server on ``port`` (``origin``: the Origin header, if any)."""
        async with websockets.asyncio.client.connect(
            f"ws://127.0.0.1:{port}", subprotocols=[Subprotocol(f"viser-v{viser.__version__}")],
            origin=None if origin is None else Origin(origin),
            max_size=None, open_timeout=60,
        ) as ws:
            yield cls(ws)

    async def send(self, message: dict) -> None:
        """Send one message as the browser would (no checks: a raw client may send anything)."""
        await self.ws.send(msgspec.msgpack.encode(message))

    async def read_until_quiet(self, quiet: float = 0.3, limit: float = 10.0) -> None:
        """Collect frames until none arrives for ``quiet`` seconds, at most ``limit`` seconds in all."""
        deadline = time.perf_counter() + limit
        while time.perf_counter() < deadline:
            try:
                frame = await asyncio.wait_for(self.ws.recv(decode=False), quiet)  # viser sends binary frames
            except TimeoutError:
                return
            self.messages.extend(decode_frame(frame))

    async def wait_for(self, kinds: Iterable[str], timeout: float = 10.0, *, camera: dict | None = None) -> None:
        """Send ``camera`` (default :data:`CAMERA`; viser then runs the connect callbacks) and read until a message
        of every kind came.

        Raises:
            AssertionError: ``timeout`` seconds passed first; the message names the kinds that did come.
        """
        kinds = tuple(kinds)
        await self.send(CAMERA if camera is None else camera)
        deadline = time.perf_counter() + timeout
        while time.perf_counter() < deadline:
            await self.read_until_quiet(0.2)
            if all(self.find(k) is not None for k in kinds):
                return
        raise AssertionError(f"the tab never got {kinds}: {sorted({m['type'] for m in self.messages})}")

    def find(self, kind: str) -> dict | None:
        """The first message of type ``kind`` received, or None."""
        return next((m for m in self.messages if m["type"] == kind), None)
