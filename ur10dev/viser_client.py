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
import collections
import dataclasses
import html
import re
import time
from typing import Any, NamedTuple

import msgspec
import numpy as np
import viser
import websockets
import zstandard
from viser import _messages as messages
from websockets.asyncio.client import ClientConnection
from websockets.asyncio.client import connect as websocket_connect
from websockets.frames import DATA_OPCODES, Frame

from .waiting import HANG_TIMEOUT, until

FLANGE_MM = re.compile(r"\*\*([+-]?[0-9]+\.[0-9])\*\*")
GHOST_FLANGE = re.compile(r"/ghosts/\w+/link6")
TAB_TITLE = re.compile(r"<title>(.*)</title>")
#: How a readout a class challenge holds back begins (``ur10teach.view.HELD_BACK``): the tool pose's, while p is asked.
HELD_BACK_START = "Off while the class challenge"
#: A browser sends a gizmo's or a panel's updates at most this often (viser throttles them to 50 ms):
#: a client that stands in for a student paces its drags so.
BROWSER_SEND_INTERVAL = 0.05
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
    decode_frame.last_sent = decoded.get("timestampSec")
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
    """What this client has been sent, by the clock of its arrival (:class:`StampedConnection`)."""

    frames: int = 0
    bytes: int = 0
    byte_log: list[tuple[float, int]] = dataclasses.field(default_factory=list)
    #: (arrival time, flange position in m) each time the T06 readout changed
    flange_updates: list[tuple[float, tuple[float, float, float]]] = dataclasses.field(default_factory=list)
    #: (arrival time, (8, 3) flange positions of the ghost arms) each time the branches moved:
    #: every valid branch ends at the IK target, so this is the 3D view answering a drag
    ghost_flanges: list[tuple[float, np.ndarray]] = dataclasses.field(default_factory=list)
    #: when this client's reader got to each of ``ghost_flanges``: its arrival plus the wait
    #: behind the other clients of this process decoding theirs (a load generator's own delay)
    ghost_flanges_read: list[float] = dataclasses.field(default_factory=list)
    notifications: list[tuple[str, str]] = dataclasses.field(default_factory=list)
    #: files the server sent to download: transfer id -> (file name, its bytes so far)
    downloads: dict[str, tuple[str, bytearray]] = dataclasses.field(default_factory=dict)
    held_back: bool = False  #: a readout was held back by a class challenge (the tool pose's, say: no flange updates then)
    #: scene nodes added (name -> the message's type), removed, and each node's last position
    nodes: dict[str, str] = dataclasses.field(default_factory=dict)
    removed_nodes: list[str] = dataclasses.field(default_factory=list)
    node_owners: dict[str, str] = dataclasses.field(default_factory=dict)  #: "" for the shared scene, else a client id
    positions: dict[str, tuple[float, float, float]] = dataclasses.field(default_factory=dict)
    visible: dict[str, bool] = dataclasses.field(default_factory=dict)
    removed_gui: set[str] = dataclasses.field(default_factory=set)
    modals: dict[str, str] = dataclasses.field(default_factory=dict)  #: the windows open over the page: uuid -> title
    modals_opened: int = 0
    #: the panel's images: uuid -> (the uuid of what holds it, a folder or a window; its encoded bytes)
    images: dict[str, tuple[str, bytes]] = dataclasses.field(default_factory=dict)
    panel_label: str | None = None  #: the panel's title, once the server has set it for this browser
    #: the 3D view's lighting as last set for this browser: shadows cast, an environment map's image sent
    shadows: bool | None = None
    environment_image: bool | None = None
    #: seconds from the server sending a frame (its perf_counter, the same clock) to its arrival here
    delivery_lag: list[float] = dataclasses.field(default_factory=list)


class StampedConnection(ClientConnection):
    """A websocket connection that notes when each message has arrived in full.

    A hundred clients in one process read their messages one after another, each decoding
    its own, so the last one reads a frame long after it arrived. Stamped as the socket's
    bytes complete a message, a client's times no longer include the others' decoding:
    in a classroom each browser decodes on its own machine.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.arrivals: collections.deque[float] = collections.deque()

    def process_event(self, event: Any) -> None:
        if isinstance(event, Frame) and event.opcode in DATA_OPCODES and event.fin:
            self.arrivals.append(time.perf_counter())
        super().process_event(event)


class DragStep(NamedTuple):
    """One gizmo event as encoded frames: ``before`` and ``after`` hold a drag's start and end messages."""

    before: tuple[bytes, ...]
    update: bytes
    after: tuple[bytes, ...]


class ViserClient:
    """One headless student. Use ``await client.connect()`` then the actions below."""

    def __init__(self, url: str, read: bool = True, local_address: str | None = None, user_agent: str | None = None,
                 cookie: str | None = None) -> None:
        self.url = url
        self.cookie = cookie  #: the Cookie header its websocket sends (None: none, as a browser that blocks cookies)
        self.read = read  # False: a client that never reads its socket (a frozen laptop)
        #: where it connects from: another loopback address (127.0.0.2, ...) stands in for another laptop
        self.local_address = local_address
        self.user_agent = user_agent  #: the browser it says it is (None: the websockets library's own name)
        self.received = Received()
        self.gui: dict[str, dict[str, Any]] = {}  # label -> {"uuid", "type", "value"}
        self.markdown: dict[str, str] = {}  # uuid -> the content of each markdown widget shown
        self.html: dict[str, str] = {}  # uuid -> the content of each HTML element shown
        self.gizmo_owner: str | None = None
        self.owners_seen: set[str] = set()  # scene scopes this client was sent messages for
        self.ready = asyncio.Event()
        self._websocket: StampedConnection | None = None
        self._reader: asyncio.Task | None = None
        self._decompressor = zstandard.ZstdDecompressor()
        self._read_at = 0.0  # when the frame being handled was read (after its arrival)

    async def connect(self, timeout: float = HANG_TIMEOUT) -> "ViserClient":
        self._websocket = await websocket_connect(
            self.url.replace("http://", "ws://"), subprotocols=[f"viser-v{viser.__version__}"],
            max_size=None, compression=None, open_timeout=timeout, create_connection=StampedConnection,
            **({"local_addr": (self.local_address, 0)} if self.local_address else {}),
            **({"user_agent_header": self.user_agent} if self.user_agent else {}),
            **({"additional_headers": {"Cookie": self.cookie}} if self.cookie else {}),
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

    @property
    def closed_by_server(self) -> bool:
        """The server closed this connection (before :meth:`close`)."""
        return self._websocket is not None and self._websocket.close_code is not None

    def freeze(self) -> None:
        """Stop reading the socket altogether (a frozen laptop): not even pings are answered."""
        if self._reader is not None:
            self._reader.cancel()
        if self._websocket is not None:
            self._websocket.transport.pause_reading()

    def abort(self) -> None:
        """Vanish without a goodbye, like a laptop lid closing: drop the TCP connection."""
        if self._reader is not None:
            self._reader.cancel()
        if self._websocket is not None:
            self._websocket.transport.abort()

    # ------------------------------------------------------------------ reading

    async def _read(self) -> None:
        assert self._websocket is not None
        try:
            await self._read_frames()
        except websockets.ConnectionClosed:
            pass  # the server hung up (as it should on garbage): nothing more to read

    async def _read_frames(self) -> None:
        assert self._websocket is not None
        arrivals = self._websocket.arrivals
        async for raw in self._websocket:
            self._read_at = time.perf_counter()
            now = arrivals.popleft()
            self.received.frames += 1
            self.received.bytes += len(raw)
            self.received.byte_log.append((now, len(raw)))
            decoded, buffers = decode_frame(raw, self._decompressor)
            if decode_frame.last_sent is not None:  # the server stamps frames with its monotonic clock
                self.received.delivery_lag.append(now - decode_frame.last_sent)
            for message in decoded:
                self._handle(now, message, buffers)

    def _handle(self, now: float, message: dict[str, Any], buffers: list[memoryview]) -> None:
        kind = message.get("type", "")
        if "owner" in message:
            self.owners_seen.add(message["owner"])
        name = message.get("name")
        if kind == "RemoveSceneNodeMessage":
            self.received.removed_nodes.append(name)
            self.received.nodes.pop(name, None)
        elif kind == "SetPositionMessage":
            self.received.positions[name] = tuple(message["position"])
        elif kind == "SetSceneNodeVisibilityMessage":
            self.received.visible[name] = message["visible"]
        elif kind == "GuiRemoveMessage":
            self.received.removed_gui.add(message["uuid"])
            self.received.images.pop(message["uuid"], None)
            self.markdown.pop(message["uuid"], None)
            self.html.pop(message["uuid"], None)
            # a label now means the widget that replaced it (a rebuilt panel), not the removed one
            for label in [label for label, entry in self.gui.items() if entry["uuid"] == message["uuid"]]:
                del self.gui[label]
        elif kind.endswith("Message") and isinstance(name, str) and name.startswith("/") and "props" in message:
            self.received.nodes[name] = kind
            self.received.node_owners[name] = message.get("owner", "")
            if "position" in message.get("props", {}):
                self.received.positions[name] = tuple(message["props"]["position"])
        if kind == "GuiModalMessage":
            self.received.modals[message["uuid"]] = message["title"]
            self.received.modals_opened += 1
        elif kind == "GuiCloseModalMessage":
            self.received.modals.pop(message["uuid"], None)
        elif kind == "GuiImageMessage" or (kind == "GuiUpdateMessage" and message["uuid"] in self.received.images
                                           and "_data" in message.get("updates", {})):
            # (viser sends an image's bytes in an update after making it empty)
            data = (message.get("props") or message["updates"]).get("_data")
            holder = message.get("container_uuid") or self.received.images[message["uuid"]][0]
            self.received.images[message["uuid"]] = (holder, b"" if data is None else bytes(
                buffers[data["__binary_index"]] if isinstance(data, dict) else data))
        if kind == "FileTransferStartDownload":
            self.received.downloads[message["transfer_uuid"]] = (message["filename"], bytearray())
        elif kind == "FileTransferPart" and message["transfer_uuid"] in self.received.downloads:
            self.received.downloads[message["transfer_uuid"]][1].extend(message["content"])
        if kind == "SceneNodeUpdateMessage" and GHOST_FLANGE.fullmatch(str(name)):  # the shown model's
            positions = message.get("updates", {}).get("batched_positions")
            if positions is not None:
                self.received.ghost_flanges.append((now, array(positions, buffers).reshape(-1, 3).copy()))
                self.received.ghost_flanges_read.append(self._read_at)
        if kind == "TransformControlsMessage" and message.get("owner"):  # a gizmo of this browser's own
            self.gizmo_owner = message["owner"]
        if kind == "GuiHtmlMessage":
            self.html[message["uuid"]] = message.get("props", {}).get("content", "")
        if kind == "GuiMarkdownMessage":
            self.markdown[message["uuid"]] = message.get("props", {}).get("_markdown", "")
        elif kind == "GuiUpdateMessage" and "_markdown" in message.get("updates", {}) and message["uuid"] in self.markdown:
            self.markdown[message["uuid"]] = message["updates"]["_markdown"]
            self.received.held_back |= message["updates"]["_markdown"].startswith(HELD_BACK_START)
        if kind == "GuiUpdateMessage" and "visible" in message.get("updates", {}):
            for entry in self.gui.values():
                if entry["uuid"] == message["uuid"]:
                    entry["visible"] = message["updates"]["visible"]
        if kind == "GuiMarkdownMessage" and "p (mm)" in message.get("props", {}).get("_markdown", ""):
            self._read_flange(now, message["props"]["_markdown"])
        elif kind.startswith("Gui") and kind.endswith("Message") and "props" in message:
            label = message["props"].get("label")
            if label:
                self.gui[label] = {"uuid": message["uuid"], "type": kind, "value": message.get("value"),
                                   "visible": message["props"].get("visible", True)}
        elif kind == "GuiUpdateMessage" and "value" in message.get("updates", {}):
            for entry in self.gui.values():
                if entry["uuid"] == message["uuid"]:
                    entry["value"] = message["updates"]["value"]
        elif kind == "GuiUpdateMessage" and "p (mm)" in message.get("updates", {}).get("_markdown", ""):
            # viser may send a markdown's content as a separate update after creating it empty
            self._read_flange(now, message["updates"]["_markdown"])
        elif kind == "SetGuiPanelLabelMessage":
            self.received.panel_label = message.get("label")
        elif kind == "EnableLightsMessage":
            self.received.shadows = bool(message["enabled"] and message["cast_shadow"])
        elif kind == "EnvironmentMapMessage":
            self.received.environment_image = message.get("hdri_data") is not None
        elif kind == "NotificationShowMessage":
            props = message.get("props", {})
            self.received.notifications.append((props.get("title", ""), props.get("body", "")))
        # ready once the arm is drawn (its tool pose read, or held back by a class challenge) and either a whole
        # session (own gizmo and panel) is built or, in the classroom's shared mode, the watcher's controls are there
        if (self.received.flange_updates or self.received.held_back) and (
            (self.gizmo_owner is not None and "Show workspace cloud" in self.gui) or "Explore on my own" in self.gui
        ):
            self.ready.set()

    def _read_flange(self, now: float, content: str) -> None:
        """The flange position a student reads in the T06 table (bold, mm)."""
        values = [float(v) for v in FLANGE_MM.findall(content)]
        if len(values) == 3:
            self.received.flange_updates.append((now, tuple(v / 1000.0 for v in values)))

    # ------------------------------------------------------------------ acting

    def shown(self, words: str) -> list[str]:
        """The markdown widgets of the panel that contain ``words``."""
        return [text for text in list(self.markdown.values()) if words in text]

    @property
    def tab_title(self) -> str | None:
        """The browser tab's title the panel sets (``ur10teach.viser_internals.name_tab``), or None while it sets none."""
        titles = [TAB_TITLE.fullmatch(text) for text in list(self.markdown.values())]
        return next((html.unescape(found[1]) for found in titles if found), None)

    def showing(self, label: str) -> bool:
        """Whether the panel shows a widget labelled ``label`` now (not one since removed)."""
        entry = self.gui.get(label)
        return entry is not None and entry["uuid"] not in self.received.removed_gui

    async def present(self, code: str) -> None:
        """Take the classroom's presenter role as the teacher does: enter the join code and press "Become presenter",
        unless this page presents already (one on the server's own computer that found nobody presenting)."""
        await until(lambda: self.showing("Stop presenting") or self.showing("Become presenter"), what="the page's role")
        if not self.showing("Stop presenting"):
            await self.set_gui("Join code", code)
            await self.set_gui("Become presenter", True)  # one connection's messages are handled in order

    async def set_gui(self, label: str, value: Any, timeout: float = HANG_TIMEOUT) -> None:
        """What the browser sends when a student changes a widget (or clicks a button: value True).

        The panel arrives a moment after the page: a widget not seen yet is waited for.
        """
        await until(lambda: label in self.gui, timeout, what=f"the widget {label!r}")
        await self.send(messages.GuiUpdateMessage(self.gui[label]["uuid"], {"value": value}))

    async def click_node(self, name: str, instance: int | None = None) -> None:
        """Click scene node ``name`` (instance ``instance`` of a batched one), as a browser reports a click on it."""
        await self.send(messages.SceneNodeClickMessage(
            name=name, instance_index=instance, ray_origin=(0.0, 0.0, 0.0), ray_direction=(1.0, 0.0, 0.0),
            screen_pos=(0.5, 0.5), modifier=None, owner=self.received.node_owners.get(name, "")))

    def drag_step(self, position, wxyz, phase: str = "update", name: str = "/ik_target") -> DragStep:
        """The frames a browser sends for one gizmo event, encoded now so that sending costs little.

        ``phase`` "start" and "end" add the drag's start and end messages around the update;
        ``name`` is the gizmo's (a course arm's is ``/course_arm/ik_target``).
        """
        owner = self.gizmo_owner or ""
        update = encode(messages.TransformControlsUpdateMessage(
            name=name, wxyz=tuple(float(v) for v in wxyz), position=tuple(float(v) for v in position), owner=owner,
        ))
        before = (encode(messages.TransformControlsDragStartMessage(name=name, owner=owner)),) if phase == "start" else ()
        after = (encode(messages.TransformControlsDragEndMessage(name=name, owner=owner)),) if phase == "end" else ()
        return DragStep(before, update, after)

    async def send_drag(self, step: DragStep) -> float:
        """Send one prepared gizmo event; returns the time its update was sent."""
        assert self._websocket is not None
        for frame in step.before:
            await self._websocket.send(frame)
        sent = time.perf_counter()
        await self._websocket.send(step.update)
        for frame in step.after:
            await self._websocket.send(frame)
        return sent

    async def drag_target(self, position, wxyz, phase: str = "update", name: str = "/ik_target") -> float:
        """One gizmo event; returns the send time."""
        return await self.send_drag(self.drag_step(position, wxyz, phase, name))

    def latencies(self, sends: list[tuple[float, Any]], tolerance: float = 1e-5) -> list[float | None]:
        """End-to-end latency of each ``(send time, target position)`` (in sending order).

        The latency of event k is the time until the screen first shows a target at least
        as new as k: the first 3D update answering event k *or a later one* (a busy server
        folds queued events into the newest). None for events after the last answer
        (or when nothing was answered).
        """
        return staleness(sends, self.received.ghost_flanges, tolerance)


def staleness(sends, updates, tolerance: float = 1e-5) -> list[float | None]:
    """See :meth:`ViserClient.latencies`; ``updates`` are (arrival, (8, 3) ghost flanges)."""
    targets = np.array([np.asarray(p, dtype=np.float32) for _, p in sends]) if sends else np.zeros((0, 3))
    sent_at = np.array([t for t, _ in sends])
    # events sorted by x, so each update looks only at the few within tolerance of its x
    # (a 10-minute soak has 12 000 events and as many updates per student)
    by_x = np.argsort(targets[:, 0], kind="stable")
    xs = targets[by_x, 0]
    answered = []  # (arrival, index of the event it answers)
    for arrival, flanges in updates:
        valid = np.abs(flanges).sum(axis=-1) > 0  # invalid branches sit at the origin
        if not valid.any():
            continue
        position = flanges[valid][0]
        # a window twice the tolerance, so float32 rounding at its edges cannot leave a match out
        near = by_x[np.searchsorted(xs, position[0] - 2 * tolerance):np.searchsorted(xs, position[0] + 2 * tolerance, "right")]
        matches = np.sort(near[np.abs(targets[near] - position).max(axis=-1) < tolerance])
        earlier = matches[sent_at[matches] <= arrival]
        if len(earlier):
            answered.append((arrival, int(earlier[-1])))
    first_answer = np.full(len(sends), np.inf)  # earliest arrival answering each event
    for arrival, index in answered:
        first_answer[index] = min(first_answer[index], arrival)
    shown = np.minimum.accumulate(first_answer[::-1])[::-1]  # first answer to this event or a later one
    out: list[float | None] = []
    for (sent, _), arrival in zip(sends, shown):
        out.append(float(arrival - sent) if np.isfinite(arrival) and arrival >= sent else None)
    return out


def wxyz_of(T: np.ndarray) -> np.ndarray:
    from ur10core.orientation import quaternion

    return quaternion(T[:3, :3])
