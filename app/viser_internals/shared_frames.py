"""Encode a broadcast window once, for every browser that receives it: the lecture hall's hot spot.

Why it is built so: docs/architecture.md §7.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import math
import os
import threading
import time
from typing import Sequence

import msgspec
import zstandard
from viser.infra import _infra
from viser.infra._async_message_buffer import AsyncMessageBuffer
from viser.infra._messages import Message

log = logging.getLogger(__name__)

#: Seconds a browser may read nothing of a frame sent to it before it is dropped (a laptop whose lid has closed).
#: A browser that reads, however slowly, is not: a frame's whole time was limited once, and a student on a
#: crowded Wi-Fi was dropped for asking for a workspace cloud (1.8 MB).
SEND_TIMEOUT = 15.0
#: How often (s) a frame that has not left yet is looked at again.
SEND_POLL = 1.0
#: Frames larger than this (a newcomer's backlog, a point cloud) are encoded per browser, not kept.
MAX_KEPT_BYTES = 256 * 1024
#: Recent windows kept: a hundred viewers drain the same redraw within a few windows of each other.
KEPT_WINDOWS = 16

VISER_PRODUCER = _infra._message_producer
ENCODE_PER_CLIENT = os.environ.get("UR10_TEACH_ENCODE_PER_CLIENT") == "1"


def encode(window: Sequence[Message], zstd: zstandard.ZstdCompressor) -> bytes:
    """One websocket frame for ``window``, in viser's wire format (as its ``_message_producer``)."""
    binary_buffers: list[memoryview] = []
    serialized = tuple(message.as_serializable_dict(binary_buffers) for message in window)
    inner = msgspec.msgpack.encode({
        "messages": serialized,
        "timestampSec": time.perf_counter(),
        "binaryBufferLengths": tuple(b.nbytes for b in binary_buffers),
    })
    compressed = zstd.compress(inner)
    parts: list[bytes | memoryview] = [len(inner).to_bytes(8, "little"), len(compressed).to_bytes(8, "little"), compressed]
    _infra._append_aligned_buffers(parts, binary_buffers, 16 + len(compressed))
    return b"".join(parts)


class KeptFrames:
    """The frames of the last :data:`KEPT_WINDOWS` windows, by the identity of their messages.

    An entry holds its window's messages, so no other message can take their ids while
    it is kept. Every server in the process shares it (tests run several, on their own
    threads), hence the lock.
    """

    def __init__(self) -> None:
        self._frames: collections.OrderedDict[tuple[int, ...], tuple[Sequence[Message], bytes]] = collections.OrderedDict()
        self._lock = threading.Lock()
        self._zstd = zstandard.ZstdCompressor(level=1)
        self.encoded = self.reused = 0

    def frame(self, window: Sequence[Message]) -> bytes:
        key = tuple(map(id, window))
        with self._lock:
            kept = self._frames.get(key)
            if kept is not None:
                self._frames.move_to_end(key)
                self.reused += 1
                return kept[1]
            frame = encode(window, self._zstd)
            self.encoded += 1
            if len(frame) <= MAX_KEPT_BYTES:
                self._frames[key] = (window, frame)
                if len(self._frames) > KEPT_WINDOWS:
                    self._frames.popitem(last=False)
            return frame


KEPT = KeptFrames()


class WakeOnLoop(asyncio.Event):
    """An ``asyncio.Event`` that a thread may set: its waiters are woken on the event loop alone.

    viser's queue sets its event from whichever thread queued a message. ``asyncio.Event`` is not
    thread-safe: a thread setting it while the loop added a waiter raised "deque mutated during
    iteration" in the thread, and the redraw that queued the message failed halfway (once in about
    3,500 random classroom actions).
    """

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__()
        self._owner = loop
        self._waking = False  # a wake-up is on its way to the loop: a redraw's many messages need one

    def set(self) -> None:
        try:
            on_loop = asyncio.get_running_loop() is self._owner
        except RuntimeError:
            on_loop = False
        if on_loop:
            super().set()
        elif not self._waking:
            self._waking = True
            with contextlib.suppress(RuntimeError):  # the loop has closed: no one waits any more
                self._owner.call_soon_threadsafe(self._wake)

    def _wake(self) -> None:
        self._waking = False
        super().set()


async def send_while_read(websocket, frame: bytes) -> bool:  # noqa: ANN001
    """Send ``frame`` on ``websocket``; False (the send given up) once the browser has read nothing of what waits
    for it, in this process's buffer, for :data:`SEND_TIMEOUT`."""
    sending = asyncio.ensure_future(websocket.send(frame))
    loop, transport = asyncio.get_running_loop(), websocket.transport
    waiting, since = math.inf, loop.time()  # (what waits is known once the send has written its frame)
    try:
        while not (await asyncio.wait({sending}, timeout=SEND_POLL))[0]:
            left = transport.get_write_buffer_size()
            if left < waiting:
                waiting, since = left, loop.time()
            elif loop.time() - since >= SEND_TIMEOUT:
                return False
    finally:  # (given up, or this producer cancelled as its browser leaves)
        sending.cancel()
    sending.result()  # (a connection closed meanwhile raises, as the send alone did)
    return True


async def shared_message_producer(websocket, buffer: AsyncMessageBuffer, client_id: int,
                                  backlog_done_message: Message | None = None) -> None:
    """viser's ``_message_producer``, with the broadcast queue's frames encoded once for everyone,
    a browser that has read nothing for :data:`SEND_TIMEOUT` dropped, and the queue's
    event made safe to set from a callback's thread (:class:`WakeOnLoop`)."""
    if not isinstance(buffer.message_event, WakeOnLoop):  # before anyone waits on it (the broadcast queue's: once)
        buffer.message_event = WakeOnLoop(buffer.event_loop)
    window_generator = buffer.window_generator(client_id, backlog_done_message=backlog_done_message)
    zstd = zstandard.ZstdCompressor(level=1)
    shared = buffer.persistent_messages and not ENCODE_PER_CLIENT  # each browser's own queue is not kept
    try:
        while not buffer.done:
            try:
                window = await window_generator.__anext__()
            except StopAsyncIteration:
                break
            if not await send_while_read(websocket, KEPT.frame(window) if shared else encode(window, zstd)):
                remote = websocket.remote_address
                log.warning("dropped browser %s at %s: it has not read what was sent to it for %.0f s",
                            client_id, remote[0] if remote else "?", SEND_TIMEOUT)
                websocket.transport.abort()  # its receive side then ends, and viser tears the client down
                break
    finally:
        await window_generator.aclose()  # as viser's: run the generator's cleanup now, not at a later collection


def install() -> None:
    """Use :func:`shared_message_producer` for every connection from now on."""
    _infra._message_producer = shared_message_producer
