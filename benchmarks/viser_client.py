"""A headless viser client: speaks viser's websocket protocol as the browser does, draws nothing.

Thirty real browsers do not fit on two cores of software WebGL; thirty of these do, and
the server cannot tell them from browsers: they announce a camera, receive and decode
every frame, and send the same messages a browser sends when a student drags the IK
target or moves a widget. Used by the drag benchmark, the classroom load test and the
fault tests.

Wire format (viser 1.1, ``viser/infra/_infra.py``): client → server frames are msgpack of
``Message.as_serializable_dict()``; server → client frames are
``[8 B inner length][8 B compressed length][zstd(msgpack)][padding][binary buffers]``.
"""

from __future__ import annotations

import asyncio
import dataclasses
import re
import time
from typing import Any

import msgspec
import numpy as np
import viser
import websockets
import zstandard
from viser import _messages as messages

FLANGE_MM = re.compile(r"\*\*([+-]?[0-9]+\.[0-9])\*\*")
#: What a browser reports for its camera; any plausible camera will do.
CAMERA = messages.ViewerCameraMessage(
    wxyz=(0.0, 0.0, 0.0, 1.0), position=(2.1, -1.9, 1.4), fov=0.87, near=0.01, far=100.0,
    image_height=800, image_width=1280, look_at=(0.2, 0.0, 0.5), up_direction=(0.0, 0.0, 1.0),
)


def encode(message: messages.Message) -> bytes:
    return msgspec.msgpack.encode(message.as_serializable_dict())


def decode_frame(raw: bytes, decompressor: zstandard.ZstdDecompressor) -> tuple[list[dict[str, Any]], list[memoryview]]:
    """Server frame → (its messages, the binary buffers their array placeholders index)."""
    inner_length = int.from_bytes(raw[0:8], "little")
    compressed_length = int.from_bytes(raw[8:16], "little")
    inner = decompressor.decompress(raw[16 : 16 + compressed_length], max_output_size=inner_length)
    decoded = msgspec.msgpack.decode(inner)
    buffers, offset, view = [], 16 + compressed_length, memoryview(raw)
    for length in decoded["binaryBufferLengths"]:
        offset += (8 - offset % 8) % 8
        buffers.append(view[offset : offset + length])
        offset += length
    return decoded["messages"], buffers


def array(placeholder: dict[str, Any], buffers: list[memoryview]) -> np.ndarray:
    """The numpy array a binary placeholder stands for (flat)."""
    return np.frombuffer(buffers[placeholder["__binary_index"]], dtype=np.dtype(placeholder["dtype"]))


@dataclasses.dataclass
class Received:
    """What this client has been sent, by the server's clock of arrival."""

    frames: int = 0
    bytes: int = 0
    byte_log: list[tuple[float, int]] = dataclasses.field(default_factory=list)
    #: (arrival time, flange position in m) each time the T06 readout changed
    flange_updates: list[tuple[float, tuple[float, float, float]]] = dataclasses.field(default_factory=list)
    #: (arrival time, (8, 3) flange positions of the ghost arms) each time the branches moved:
    #: every valid branch ends at the IK target, so this is the 3D view answering a drag
    ghost_flanges: list[tuple[float, np.ndarray]] = dataclasses.field(default_factory=list)
    notifications: list[tuple[str, str]] = dataclasses.field(default_factory=list)


class ViserClient:
    """One headless student. Use ``await client.connect()`` then the actions below."""

    def __init__(self, url: str, read: bool = True) -> None:
        self.url = url
        self.read = read  # False: a client that never reads its socket (a frozen laptop)
        self.received = Received()
        self.gui: dict[str, dict[str, Any]] = {}  # label -> {"uuid", "type", "value"}
        self.gizmo_owner: str | None = None
        self._pose_readout: str | None = None  # uuid of the T06 markdown
        self.ready = asyncio.Event()
        self._websocket: websockets.ClientConnection | None = None
        self._reader: asyncio.Task | None = None
        self._decompressor = zstandard.ZstdDecompressor()

    async def connect(self, timeout: float = 30.0) -> "ViserClient":
        self._websocket = await websockets.connect(
            self.url.replace("http://", "ws://"), subprotocols=[f"viser-v{viser.__version__}"],
            max_size=None, compression=None, open_timeout=timeout,
        )
        await self.send(CAMERA)  # the server counts a client as connected from its first camera
        if self.read:
            self._reader = asyncio.create_task(self._read())
            await asyncio.wait_for(self.ready.wait(), timeout)
        return self

    async def send(self, message: messages.Message) -> None:
        assert self._websocket is not None
        await self._websocket.send(encode(message))

    async def send_raw(self, payload: bytes) -> None:
        """Anything at all, for the fault tests."""
        assert self._websocket is not None
        await self._websocket.send(payload)

    async def close(self) -> None:
        if self._reader is not None:
            self._reader.cancel()
        if self._websocket is not None:
            await self._websocket.close()

    def abort(self) -> None:
        """Vanish without a goodbye, like a laptop lid closing: drop the TCP connection."""
        if self._reader is not None:
            self._reader.cancel()
        if self._websocket is not None:
            self._websocket.transport.abort()

    # ------------------------------------------------------------------ reading

    async def _read(self) -> None:
        assert self._websocket is not None
        async for raw in self._websocket:
            now = time.perf_counter()
            self.received.frames += 1
            self.received.bytes += len(raw)
            self.received.byte_log.append((now, len(raw)))
            decoded, buffers = decode_frame(raw, self._decompressor)
            for message in decoded:
                self._handle(now, message, buffers)

    def _handle(self, now: float, message: dict[str, Any], buffers: list[memoryview]) -> None:
        kind = message.get("type", "")
        if kind == "SceneNodeUpdateMessage" and message.get("name") == "/ghosts/link6":
            positions = message.get("updates", {}).get("batched_positions")
            if positions is not None:
                self.received.ghost_flanges.append((now, array(positions, buffers).reshape(-1, 3).copy()))
        if kind == "TransformControlsMessage" and message.get("name") == "/ik_target":
            self.gizmo_owner = message.get("owner", "")
        elif kind == "GuiMarkdownMessage" and "p (mm)" in message.get("props", {}).get("_markdown", ""):
            self._pose_readout = message["uuid"]
            self._read_flange(now, message["props"]["_markdown"])
        elif kind.startswith("Gui") and kind.endswith("Message") and "props" in message:
            label = message["props"].get("label")
            if label:
                self.gui[label] = {"uuid": message["uuid"], "type": kind, "value": message.get("value")}
        elif kind == "GuiUpdateMessage" and message.get("uuid") == self._pose_readout:
            if "_markdown" in message.get("updates", {}):
                self._read_flange(now, message["updates"]["_markdown"])
        elif kind == "NotificationShowMessage":
            props = message.get("props", {})
            self.received.notifications.append((props.get("title", ""), props.get("body", "")))
        # the session is built once its last widget exists and the arm has been drawn
        if self.gizmo_owner is not None and "Show workspace cloud" in self.gui and self.received.flange_updates:
            self.ready.set()

    def _read_flange(self, now: float, content: str) -> None:
        """The flange position a student reads in the T06 table (bold, mm)."""
        values = [float(v) for v in FLANGE_MM.findall(content)]
        if len(values) == 3:
            self.received.flange_updates.append((now, tuple(v / 1000.0 for v in values)))

    # ------------------------------------------------------------------ acting

    async def set_gui(self, label: str, value: Any) -> None:
        """What the browser sends when a student changes a widget (or clicks a button: value True)."""
        await self.send(messages.GuiUpdateMessage(self.gui[label]["uuid"], {"value": value}))

    async def drag_target(self, position, wxyz, phase: str = "update") -> float:
        """One gizmo event; returns the send time."""
        owner = self.gizmo_owner or ""
        if phase == "start":
            await self.send(messages.TransformControlsDragStartMessage(name="/ik_target", owner=owner))
        sent = time.perf_counter()
        await self.send(messages.TransformControlsUpdateMessage(
            name="/ik_target", wxyz=tuple(float(v) for v in wxyz), position=tuple(float(v) for v in position), owner=owner,
        ))
        if phase == "end":
            await self.send(messages.TransformControlsDragEndMessage(name="/ik_target", owner=owner))
        return sent

    def latencies(self, sends: list[tuple[float, Any]], tolerance: float = 1e-5, window: float = 2.0) -> list[float | None]:
        """For each ``(send time, target position)`` in time order: seconds until the first 3D
        update whose branches end at that position, or None (superseded by a newer event,
        unreachable, or not answered within ``window`` seconds)."""
        updates = self.received.ghost_flanges
        out: list[float | None] = []
        start = 0
        for sent, position in sends:
            target = np.asarray(position, dtype=np.float32)
            while start < len(updates) and updates[start][0] < sent:
                start += 1
            found = None
            for index in range(start, len(updates)):
                arrival, flanges = updates[index]
                if arrival - sent > window:
                    break
                if (np.abs(flanges - target).max(axis=-1) < tolerance).any():
                    found = arrival - sent
                    start = index
                    break
            out.append(found)
        return out


def wxyz_of(T: np.ndarray) -> np.ndarray:
    from ur10core.orientation import quaternion

    return quaternion(T[:3, :3])
