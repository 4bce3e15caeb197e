"""Hostile clients: what one browser (or a page a student opens) can no longer do to the class.

Each test here was a finding of the security review against the app before the gate
(``app/gate.py``) and fails without it. The clients are headless and speak viser's own
protocol (``ur10dev/viser_client.py``), so they can send what no browser would.
"""

from __future__ import annotations

import asyncio
import os
import socket
import subprocess
import time

import msgspec
import numpy as np
import pytest
import viser
import websockets
from viser import _messages as messages

from app import gate as gate_module
from app.gate import MAX_MESSAGE_BYTES, MESSAGE_BURST, Gate, TokenBucket, gated_serve, message_key
from app.server import TeachingServer

from .server_support import drag_a_little, session_of, until, url
from ur10dev.viser_client import ViserClient, encode
from ur10dev.waiting import HANG_TIMEOUT

pytestmark = pytest.mark.server


def resident_mib() -> float:
    with open(f"/proc/{os.getpid()}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS")


async def click_is_applied(client: ViserClient, session) -> None:
    """A student's slider change reaches their arm (how fast, beside an attack, is bench_hostile's)."""
    before = session.state.q[0]
    await client.set_gui("θ1 base", float(np.degrees(before)) + 1.0)
    await until(lambda: abs(session.state.q[0] - before) > 1e-6, what="the slider change")


# ---------------------------------------------------------------------------- messages, by kind


@pytest.mark.parametrize(
    "message, key",
    [
        (messages.GuiUpdateMessage("abc", {"value": 3.0}), ("GuiUpdateMessage", "abc")),
        (messages.GuiUpdateMessage("abc", {"value": [1.0, 2.0, 3.0]}), ("GuiUpdateMessage", "abc")),
        (messages.GuiUpdateMessage("abc", {"value": "30, 45"}), ("GuiUpdateMessage", "abc")),
        (messages.TransformControlsUpdateMessage("/ik_target", (1.0, 0, 0, 0), (0, 0, 0), "7"),
         ("TransformControlsUpdateMessage", "/ik_target")),
        (messages.ViewerCameraMessage((1.0, 0, 0, 0), (1, 1, 1), 1.0, 0.01, 100.0, 800, 600, (0, 0, 0), (0, 0, 1)),
         ("ViewerCameraMessage",)),
        # not the app's to take:
        (messages.ShareUrlRequest(), None),
        (messages.ShareUrlDisconnect(), None),
        (messages.GuiFormDirtyMessage("abc"), None),
        (messages.FileTransferStartUpload("abc", "t", "f.bin", "application/octet-stream", 1, 10), None),
        (messages.GuiUpdateMessage("abc", {"options": ("a", "b")}), None),  # a property a browser never sets
        (messages.GuiUpdateMessage("abc", {"value": 1.0, "disabled": False}), None),
        (messages.GuiUpdateMessage("abc", {"value": "x" * 5000}), None),
        (messages.GuiUpdateMessage("abc", {"value": [0.0] * 100}), None),
    ],
)
def test_only_the_messages_the_app_uses_pass(message, key):
    assert message_key(encode(message)) == key


@pytest.mark.parametrize("raw", [b"", b"\xc1", msgspec.msgpack.encode([[]] * 1000), msgspec.msgpack.encode({"type": 5}),
                                 msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": {"a": 1}, "updates": {"value": 1}})])
def test_garbage_is_dropped(raw):
    assert message_key(raw) is None


def test_token_bucket():
    now = [100.0]
    bucket = TokenBucket(rate=10.0, burst=3, clock=lambda: now[0])
    assert [bucket.take() for _ in range(4)] == [True, True, True, False]
    assert bucket.wait_time() == pytest.approx(0.1)
    now[0] += 0.06
    assert not bucket.take() and bucket.wait_time() == pytest.approx(0.04)
    now[0] += 0.05
    assert bucket.take() and not bucket.take()
    now[0] += 3600
    assert [bucket.take() for _ in range(4)] == [True, True, True, False]  # never more than the burst


# ---------------------------------------------------------------------------- against a server


def test_a_huge_message_closes_its_connection_before_it_is_decoded(app):
    """10 MB of empty msgpack arrays took the server from 140 to ~850 MiB and froze everyone for 3.7 s."""

    async def scenario():
        student = await ViserClient(url(app)).connect()
        session = session_of(app, student)
        attacker = await ViserClient(url(app)).connect()
        session_of(app, attacker)  # its arm is built: what follows is the bomb alone
        bomb = b"\xdd" + (10_000_000).to_bytes(4, "big") + b"\x90" * 10_000_000  # array32 of 10 M empty arrays
        before = resident_mib()  # the bomb's own 10 MB in this process (the test's) counted already
        await attacker.send_raw(bomb)
        await until(lambda: attacker._websocket.close_code is not None, what="the attacker's connection to close")
        assert attacker._websocket.close_code == 1009  # message too big
        assert resident_mib() - before < 30  # the frame is refused as it arrives, never decoded
        await click_is_applied(student, session)  # everyone else carries on
        await student.close()

    asyncio.run(scenario())


def test_the_limit_is_what_the_app_needs(app):
    """A message just under the limit passes the socket (and is then judged by kind); one over it does not."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        await client.send_raw(msgspec.msgpack.encode({"type": "Nothing", "pad": "x" * (MAX_MESSAGE_BYTES - 100)}))
        await until(lambda: app.gate.dropped["Nothing"] == 1, what="the message to be read, and dropped by kind")
        assert client._websocket.close_code is None
        await client.send_raw(msgspec.msgpack.encode({"type": "Nothing", "pad": "x" * MAX_MESSAGE_BYTES}))
        await until(lambda: client._websocket.close_code == 1009, what="the connection to close")

    asyncio.run(scenario())


def test_no_client_can_open_a_public_tunnel(app, monkeypatch):
    """Any client, a view-only one included, could make the server look up share.viser.studio and start two processes."""
    asked = []
    monkeypatch.setattr(viser.ViserServer, "request_share_url", lambda self, *a, **k: asked.append(a))
    started = []
    real_popen = subprocess.Popen.__init__

    def popen(self, *args, **kwargs):
        started.append(args)
        real_popen(self, *args, **kwargs)

    monkeypatch.setattr(subprocess.Popen, "__init__", popen)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        for _ in range(3):
            await client.send(messages.ShareUrlRequest())
            await client.send(messages.ShareUrlDisconnect())
        await until(lambda: app.gate.dropped["ShareUrlRequest"] == app.gate.dropped["ShareUrlDisconnect"] == 3,
                    what="the requests to be dropped")
        assert client._websocket.close_code is None  # dropped quietly: the rest of the page still works
        await client.close()

    asyncio.run(scenario())
    assert not asked and not started
    assert app.gate.dropped["ShareUrlRequest"] == 3


def test_form_broadcasts_are_not_replayed_to_the_class(app):
    """600 × 1 MiB GuiFormDirtyMessages from one viewer added 1.35 GB to the server and to every newcomer."""

    async def scenario():
        sender = await ViserClient(url(app)).connect()
        watcher = await ViserClient(url(app)).connect()
        persistent = len(app.server._websock_server._broadcast_buffer.message_from_id)
        uuid = next(iter(sender.gui.values()))["uuid"]
        for _ in range(50):
            await sender.send(messages.GuiFormDirtyMessage(uuid))
        await until(lambda: app.gate.dropped["GuiFormDirtyMessage"] == 50, what="the broadcasts to be dropped")
        assert len(app.server._websock_server._broadcast_buffer.message_from_id) == persistent
        assert app.gate.dropped["GuiFormDirtyMessage"] == 50
        await sender.close()
        await watcher.close()

    asyncio.run(scenario())


def test_uploads_are_refused(app):
    """20 × 49 MB "uploads" parked +1 GB until the client left."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        uuid = next(iter(client.gui.values()))["uuid"]
        for k in range(5):
            await client.send(messages.FileTransferStartUpload(uuid, f"t{k}", "f.bin", "x", 1000, 49_000_000))
            await client.send(messages.FileTransferPart(uuid, f"t{k}", 0, b"x" * 1000))
        await until(lambda: app.gate.dropped["FileTransferPart"] == 5, what="the uploads to be dropped")
        assert app.gate.dropped["FileTransferStartUpload"] == 5 and app.gate.dropped["FileTransferPart"] == 5
        assert not getattr(app.server.gui, "_current_file_upload_states", {})
        await client.close()

    asyncio.run(scenario())


async def _handshake(port: int, headers: dict[str, str], host: str = "127.0.0.1") -> int | None:
    """The HTTP status that refused the websocket, or None if it opened.

    The connection always goes to 127.0.0.1; ``host`` is the name the request asks for
    (as a browser would after a DNS rebinding: an attacker's name, resolving here).
    """
    sock = socket.create_connection(("127.0.0.1", port))
    try:
        async with websockets.connect(f"ws://{host}:{port}", sock=sock, subprotocols=[f"viser-v{viser.__version__}"],
                                      additional_headers=headers, open_timeout=HANG_TIMEOUT):
            return None
    except websockets.InvalidStatus as refusal:
        return refusal.response.status_code


def test_pages_from_elsewhere_cannot_connect():
    """Any page a student or the teacher opened could reach 127.0.0.1:8080 or the teacher's LAN address."""
    app = TeachingServer(port=0, allowed_origins=["http://course-site.example:8000"])
    try:
        port = app.port

        async def scenario():
            own = f"http://127.0.0.1:{port}"
            assert await _handshake(port, {"Origin": own}) is None  # the app's own page
            assert await _handshake(port, {}) is None  # no Origin: not a browser page (tests, tools)
            assert await _handshake(port, {"Origin": "http://course-site.example:8000"}) is None  # allowed by the teacher
            assert await _handshake(port, {"Origin": "http://evil.example"}) == 403
            assert await _handshake(port, {"Origin": f"http://localhost:{port}"}) == 403  # another origin, same machine
            assert await _handshake(port, {"Origin": "null"}) == 403  # a sandboxed iframe or a file:// page
            # DNS rebinding: evil.example resolves to 127.0.0.1, so Host and Origin agree
            assert await _handshake(port, {"Origin": f"http://evil.example:{port}"}, host="evil.example") == 403
            assert await _handshake(port, {}, host="evil.example") == 403
            assert await _handshake(port, {"Origin": own}, host="localhost") == 403  # a page of 127.0.0.1 talking to localhost
            assert await _handshake(port, {}, host="localhost") is None

        asyncio.run(scenario())
        assert app.gate.refused["origin"] == 4 and app.gate.refused["host"] == 2
    finally:
        app.stop()


def test_one_address_cannot_open_sessions_without_end():
    """146 connections/s that each built a full session pushed others' drag p95 to 968 ms."""
    app = TeachingServer(port=0, gate=Gate(trust_loopback=False))  # loopback stands in for a laptop on the LAN
    try:
        async def scenario():
            statuses = await asyncio.gather(*(_handshake(app.port, {}) for _ in range(30)))
            opened = [s for s in statuses if s is None]
            assert len(opened) <= gate_module.CONNECTIONS_PER_ADDRESS
            assert statuses.count(429) >= 30 - gate_module.CONNECTIONS_PER_ADDRESS
            await until(lambda: len(app.sessions) == 0, what="the short-lived sessions to be freed")

        asyncio.run(scenario())
    finally:
        app.stop()


def test_a_slider_flood_costs_one_update_per_tick(app):
    """20 000 slider updates in 0.16 s made other students' clicks take 8.5 s."""

    async def scenario():
        flooder = await ViserClient(url(app)).connect()
        flooded = session_of(app, flooder)
        student = await ViserClient(url(app)).connect()
        session = session_of(app, student)
        uuid = flooder.gui["θ2 shoulder"]["uuid"]
        applied = []
        flooded.observers.append(lambda snapshot: applied.append(snapshot.q[1]))
        frames = [encode(messages.GuiUpdateMessage(uuid, {"value": float(k % 90)})) for k in range(20_000)]
        started = time.monotonic()
        for frame in frames:
            await flooder.send_raw(frame)
        await click_is_applied(student, session)  # the student next to the flood is served
        await until(lambda: abs(np.degrees(flooded.state.q[1]) - (19_999 % 90)) < 1e-6, what="the newest value")
        lasted = time.monotonic() - started
        # The gate passed at most its burst plus its rate for as long as the flood was being
        # handled: 20 000 would have been applied without it. (A slow machine only makes
        # the bound looser, never the test fail: this is a count, not a timing.)
        assert len(applied) <= MESSAGE_BURST + gate_module.MESSAGES_PER_SECOND * lasted + 1, (len(applied), lasted)
        await flooder.close()
        await student.close()

    asyncio.run(scenario())


def test_a_drag_flood_does_not_slow_the_others(app):
    async def scenario():
        flooder = await ViserClient(url(app)).connect()
        flooded = session_of(app, flooder)
        student = await ViserClient(url(app)).connect()
        session = session_of(app, student)
        T = flooded.state.last.flange.copy()
        steps = [flooder.drag_step(T[:3, 3] + (0.0001 * k, 0, 0), (1.0, 0, 0, 0)) for k in range(5000)]
        await asyncio.gather(*(flooder.send_drag(step) for step in steps[:1]))
        for step in steps[1:]:
            await flooder._websocket.send(step.update)
        target = await drag_a_little(student, session, steps=5)
        # served beside the flood (how fast is bench_hostile's flood row)
        await until(lambda: np.allclose(session.state.last.target, target, atol=1e-9), what="the student's drag")
        await flooder.close()
        await student.close()

    asyncio.run(scenario())


def test_the_gate_fails_loudly_if_viser_stops_starting_its_server_through_websockets():
    """The gate rides on viser calling websockets.asyncio.server.serve: if a viser upgrade changes that, startup fails."""
    with pytest.raises(RuntimeError, match="the gate would not apply"):
        with gated_serve(Gate()):
            pass  # nothing started a server
