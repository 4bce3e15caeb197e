"""ur10teach.viser_internals.shared_frames sends what viser's own producer sends, encoding a broadcast window once."""

from __future__ import annotations

import asyncio
import hashlib
import inspect
import threading

import numpy as np
import pytest
import zstandard
from viser import _messages
from viser.infra import _infra
from viser.infra._async_message_buffer import AsyncMessageBuffer

from ur10teach.viser_internals import shared_frames
from ur10teach.viser_internals.fast_updates import _UpdateMessage
from ur10dev.viser_client import decode_frame
from ur10dev.waiting import HANG_TIMEOUT, until, wait_for

#: viser 1.1.1's ``_message_producer``, which shared_frames.shared_message_producer copies.
VISER_PRODUCER_SHA256 = "8283328d06cfa014576888930c49a857a2d79892dc89f9694444895945018ea3"


class Recorder:
    """A websocket that keeps what is sent."""

    def __init__(self) -> None:
        self.sent: list[bytes] = []
        self.transport = self
        self.remote_address = ("127.0.0.2", 50000)
        self.aborted = False

    async def send(self, data: bytes) -> None:
        self.sent.append(data)

    def get_write_buffer_size(self) -> int:
        return 0

    def abort(self) -> None:
        self.aborted = True


class Link(Recorder):
    """A websocket over a link whose frame waits in the sender's buffer and leaves a little each time the sender
    looks (a crowded Wi-Fi: slow, but read), or never (``reads=False``: a laptop whose lid has closed)."""

    def __init__(self, reads: bool, looks: int = 0) -> None:
        super().__init__()
        self.reads, self.looks, self.left, self.step = reads, looks, 0, 0

    async def send(self, data: bytes) -> None:
        self.left, self.step = len(data), -(-len(data) // max(self.looks, 1))  # (it leaves in ``looks`` looks)
        await until(lambda: self.left == 0, what="the frame to leave")
        self.sent.append(data)

    def get_write_buffer_size(self) -> int:
        left = self.left
        if self.reads:
            self.left = max(0, self.left - self.step)
        return left


def a_window() -> list[_messages.Message]:
    return [
        _messages.SetOrientationMessage("/arm/link0/link1", (0.5, 0.5, 0.5, 0.5)),
        _messages.SetPositionMessage("/target", (0.1, -0.2, 0.3)),
        _UpdateMessage("/ghosts/link3", {
            "batched_wxyzs": np.arange(32, dtype=np.float32).reshape(8, 4),
            "batched_positions": np.linspace(0, 1, 24, dtype=np.float32).reshape(8, 3),
        }),
        _messages.GuiUpdateMessage("markdown-1", {"content": "**θ1** = 30.0°"}),
    ]


def produce(producer, window, persistent: bool = True, clients: int = 1) -> list[bytes]:
    """The first frame each of ``clients`` connections gets from ``producer`` for ``window``."""

    async def run() -> list[bytes]:
        buffer = AsyncMessageBuffer(asyncio.get_running_loop(), persistent_messages=persistent)
        for message in window:
            buffer.push(message)
        sockets = [Recorder() for _ in range(clients)]
        tasks = [asyncio.create_task(producer(socket, buffer, client_id)) for client_id, socket in enumerate(sockets)]
        await until(lambda: all(socket.sent for socket in sockets), what="a frame for every connection")
        buffer.set_done()
        await asyncio.wait_for(asyncio.gather(*tasks), HANG_TIMEOUT)
        return [socket.sent[0] for socket in sockets]

    return asyncio.run(run())


def decoded(frame: bytes):
    messages, buffers = decode_frame(frame, zstandard.ZstdDecompressor())
    return messages, [bytes(b) for b in buffers]


def test_frames_decode_to_what_viser_sends():
    window = a_window()
    ours = produce(shared_frames.shared_message_producer, window)[0]
    theirs = produce(shared_frames.VISER_PRODUCER, window)[0]
    assert decoded(ours) == decoded(theirs)
    # also for a browser's own queue, which is encoded per browser
    assert decoded(produce(shared_frames.shared_message_producer, window, persistent=False)[0]) == decoded(theirs)


def test_a_broadcast_window_is_encoded_once_for_every_browser():
    encoded, reused = shared_frames.KEPT.encoded, shared_frames.KEPT.reused
    frames = produce(shared_frames.shared_message_producer, a_window(), clients=5)
    assert all(frame is frames[0] for frame in frames)
    assert shared_frames.KEPT.encoded - encoded == 1
    assert shared_frames.KEPT.reused - reused == 4


def test_a_browsers_own_queue_is_not_kept():
    encoded = shared_frames.KEPT.encoded
    produce(shared_frames.shared_message_producer, a_window(), persistent=False)
    assert shared_frames.KEPT.encoded == encoded


def test_a_large_frame_is_not_kept():
    big = _messages.GuiUpdateMessage("markdown-2", {"content": np.random.default_rng(0).bytes(400_000).hex()})
    kept = shared_frames.KeptFrames()
    kept.frame([big])
    kept.frame([big])
    assert kept.encoded == 2 and kept.reused == 0


def test_only_recent_windows_are_kept():
    kept = shared_frames.KeptFrames()
    windows = [a_window() for _ in range(shared_frames.KEPT_WINDOWS + 1)]
    for window in windows:
        kept.frame(window)
    kept.frame(windows[-1])
    kept.frame(windows[0])  # pushed out by the newer ones
    assert kept.reused == 1 and kept.encoded == len(windows) + 1


def test_a_browser_that_reads_slowly_is_sent_its_frame_and_one_that_reads_nothing_is_dropped(monkeypatch):
    """A frame's whole sending was given 15 s: a student whose share of a crowded Wi-Fi was slow was dropped for asking
    for a workspace cloud (1.8 MB), and the page it came back to asked again. Now only a browser that has read nothing
    for that long is dropped. Here the slow link's frame takes four times that patience, and is sent; the laptop whose
    lid has closed (nothing read) is dropped, and its send ended."""
    monkeypatch.setattr(shared_frames, "SEND_TIMEOUT", 0.2)
    monkeypatch.setattr(shared_frames, "SEND_POLL", 0.02)

    async def run(socket: Link) -> bool:
        buffer = AsyncMessageBuffer(asyncio.get_running_loop(), persistent_messages=True)
        for message in a_window():
            buffer.push(message)
        producer = asyncio.create_task(shared_frames.shared_message_producer(socket, buffer, 0))
        await until(lambda: socket.sent or socket.aborted, what="the frame sent, or the browser dropped")
        buffer.set_done()
        await asyncio.wait_for(producer, HANG_TIMEOUT)
        return bool(socket.sent)

    slow = Link(reads=True, looks=round(4 * shared_frames.SEND_TIMEOUT / shared_frames.SEND_POLL))
    assert asyncio.run(run(slow)) and not slow.aborted
    frozen = Link(reads=False)
    assert not asyncio.run(run(frozen)) and frozen.aborted and frozen.left > 0


def test_viser_producer_is_the_one_copied():
    """Fails when a viser upgrade changes the producer that app/viser_internals/shared_frames.py replaces: compare them again."""
    source = inspect.getsource(shared_frames.VISER_PRODUCER)
    assert hashlib.sha256(source.encode()).hexdigest() == VISER_PRODUCER_SHA256


@pytest.mark.server
def test_the_app_sends_through_it(classroom):
    """Every connection of the running app, shared mode included, gets its frames from shared_frames."""
    assert _infra._message_producer is shared_frames.shared_message_producer


def test_a_thread_setting_a_queues_event_wakes_its_waiter_on_the_loop_alone():
    """A thread set viser's queue event while the loop added a waiter to it: "deque mutated during
    iteration", and the redraw that queued the message failed. Now the thread touches nothing of the
    event: the loop wakes the waiter."""
    loop = asyncio.new_event_loop()
    runner = threading.Thread(target=loop.run_forever, daemon=True)
    runner.start()
    try:
        event = shared_frames.WakeOnLoop(loop)
        waiting = asyncio.run_coroutine_threadsafe(event.wait(), loop)
        wait_for(lambda: len(event._waiters) == 1, what="the waiter")
        held, release = threading.Event(), threading.Event()
        loop.call_soon_threadsafe(lambda: (held.set(), release.wait(HANG_TIMEOUT)))  # the loop is busy
        held.wait(HANG_TIMEOUT)
        event.set()  # from this thread
        assert not event.is_set() and not waiting.done()  # left to the loop
        release.set()
        assert waiting.result(HANG_TIMEOUT) is True and event.is_set()
    finally:
        loop.call_soon_threadsafe(loop.stop)
        runner.join(HANG_TIMEOUT)
        loop.close()
    event.set()  # the loop has closed: nothing to wake, and no error


@pytest.mark.server
def test_the_app_makes_its_queues_events_safe(classroom):
    """The broadcast queue and each browser's own, from the first connection on."""
    from ur10dev.viser_client import ViserClient

    async def scenario():
        browser = await ViserClient(f"http://127.0.0.1:{classroom.port}").connect()
        websock = classroom.server._websock_server
        client_buffer = next(iter(websock._client_state_from_id.values())).message_buffer
        await until(lambda: all(isinstance(buffer.message_event, shared_frames.WakeOnLoop)
                                for buffer in (websock._broadcast_buffer, client_buffer)), what="both queues' events")
        await browser.close()

    asyncio.run(scenario())


@pytest.mark.server
def test_what_one_browser_is_sent_after_the_broadcast_arrives_after_it(classroom):
    """viser sends a browser the broadcast queue and its own on two tasks: ``after_broadcast`` holds
    one browser's message until the shared scene's, queued before it, have left. A shared node drawn
    anew and that browser's hidden node of the same name end hidden, every time (sent at once, the
    shared one arrived last now and then, and a classroom explorer saw the class's arm on theirs)."""
    from ur10teach.viser_internals import after_broadcast
    from ur10dev.viser_client import ViserClient

    server = classroom.server

    async def scenario():
        browser = await ViserClient(f"http://127.0.0.1:{classroom.port}").connect()
        client = next(iter(server.get_clients().values()))
        mine = str(client.client_id)
        names = [f"/probe/{k}" for k in range(40)]
        cloud = np.random.default_rng(0).uniform(-1, 1, (3000, 3)).astype(np.float32)  # a redrawn arm's size
        for name in names:
            server.scene.add_point_cloud(name, cloud, (200, 0, 0))
            after_broadcast(client, lambda name=name: client.scene.add_frame(name, show_axes=False, visible=False))

        def hidden() -> bool:
            return all(browser.received.node_owners.get(n) == mine and browser.received.visible.get(n) is False for n in names)

        await until(hidden, what="every probe hidden in the browser")
        server.scene.add_frame("/probe_end")  # the broadcast queue's order: once this is there, all before it is
        await until(lambda: "/probe_end" in browser.received.nodes, what="the shared marker")
        assert hidden(), [n for n in names if browser.received.node_owners.get(n) != mine]
        await browser.close()

    asyncio.run(scenario())
