"""Faults and bad input: the server keeps serving everyone else and frees what the departed held.

Headless clients speak viser's own protocol (``ur10dev/viser_client.py``), so a test can
do what a browser never would: vanish mid-drag, stop reading, send garbage.
"""

from __future__ import annotations

import asyncio
import logging
import time
import traceback

import msgspec
import numpy as np
import pytest
import viser
from viser import _messages as messages

from ur10teach import feedback
from ur10teach.viser_internals import shared_frames
from ur10teach.features.arm_picker import ARM_CHOICES, UR10, ArmPicker
from ur10teach.features.workspace import SAMPLE_COUNTS
from ur10dev.app_process import running_app
from .server_support import drag_a_little, session_of, until, url, wait_for
from .test_course_arms_app import arrived, pick
from ur10dev.viser_client import BROWSER_SEND_INTERVAL, ViserClient, encode, wxyz_of
from ur10dev.waiting import HANG_TIMEOUT

pytestmark = pytest.mark.server


def test_clients_vanishing_mid_drag(app):
    async def scenario():
        clients = [await ViserClient(url(app)).connect() for _ in range(6)]
        sessions = [session_of(app, c) for c in clients]
        leaving, staying = clients[:3], clients[3:]
        T = sessions[0].state.last.flange.copy()
        for k in range(5):  # everyone is dragging...
            T[:3, 3] += (0.003, 0.0, 0.0)
            for c in clients:
                await c.drag_target(T[:3, 3], wxyz_of(T), "start" if k == 0 else "update")
            await asyncio.sleep(BROWSER_SEND_INTERVAL)
        for c in leaving:  # ...when three laptops drop off the network
            c.abort()
        targets = await asyncio.gather(*(drag_a_little(c, s) for c, s in zip(staying, sessions[3:])))
        for session, target in zip(sessions[3:], targets):
            await until(lambda s=session, t=target: np.allclose(s.state.last.target, t, atol=1e-9), what="the others' drags")
        await until(lambda: len(app.sessions) == 3, what="the departed sessions to be freed")
        assert all(s.closed for s in sessions[:3])
        for c in staying:
            await c.close()
        await until(lambda: len(app.sessions) == 0, what="everyone to be freed")

    asyncio.run(scenario())


def test_twenty_reconnect_at_once(app):
    async def scenario():
        clients = await asyncio.gather(*(ViserClient(url(app)).connect() for _ in range(20)))
        await until(lambda: len(app.sessions) == 20, what="twenty sessions")
        for c in clients:
            c.abort()
        await until(lambda: len(app.sessions) == 0, what="all twenty to be freed")
        clients = await asyncio.gather(*(ViserClient(url(app)).connect() for _ in range(20)))
        await until(lambda: len(app.sessions) == 20, what="twenty sessions again")
        # every one of them works
        targets = await asyncio.gather(*(drag_a_little(c, session_of(app, c), steps=3) for c in clients))
        for c, target in zip(clients, targets):
            await until(lambda s=session_of(app, c), t=target: np.allclose(s.state.last.target, t, atol=1e-9), what="drags")
        await asyncio.gather(*(c.close() for c in clients))
        await until(lambda: len(app.sessions) == 0, what="all twenty to be freed again")

    asyncio.run(scenario())


def test_a_browser_that_leaves_while_its_arm_is_being_built_is_freed(app):
    """viser runs connect and disconnect callbacks side by side on its thread pool."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        handle = app.server.get_clients()[int(client.gizmo_owner)]
        session = session_of(app, client)
        client.abort()
        await until(lambda: session.closed and not app.sessions, what="the departed session to be freed")
        # the connect callback of a browser that has already gone finishes only now
        await asyncio.to_thread(app._connected, handle)
        assert not app.sessions

    asyncio.run(scenario())


def test_a_client_that_stops_reading_is_dropped_and_holds_up_no_one(app, monkeypatch, caplog):
    """Review 2, finding 2: connections that asked for clouds and never read held 2.2 GB for as
    long as the server ran (the keepalive ping waited behind the blocked send)."""
    monkeypatch.setattr(shared_frames, "SEND_TIMEOUT", 2.0)  # the server's patience, shortened for the test

    def drawn(session, count: int) -> bool:
        cloud = session.workspace._cloud
        return cloud is not None and len(cloud.points) == count

    async def scenario():
        frozen = await ViserClient(url(app)).connect()
        frozen_session = session_of(app, frozen)
        cloud, samples = frozen.gui["Show workspace cloud"]["uuid"], frozen.gui["Samples"]["uuid"]
        frozen.freeze()  # stops reading its socket, even the server's pings
        # ...and asks for clouds: megabytes the server cannot hand over. The kernel's socket
        # buffers take a few (up to ~10 MB on loopback, a 1 M cloud is ~8 MB compressed), so it
        # asks for another once each is drawn, until the server gives up on it.
        await frozen.send(messages.GuiUpdateMessage(cloud, {"value": True}))
        for label in ("1 M", "500 k") * 6:  # 6 × 12 MB: far beyond any socket's buffers
            await frozen.send(messages.GuiUpdateMessage(samples, {"value": label}))
            await until(lambda n=SAMPLE_COUNTS[label]: frozen_session.closed or drawn(frozen_session, n),
                        what=f"the frozen client's {label} cloud to be drawn")
            if frozen_session.closed:
                break
        # a student next to it drags and is answered (how fast, beside a frozen client, is bench_hostile's)
        active = await ViserClient(url(app), local_address="127.0.0.2").connect()  # (from its own laptop: not the frozen one's return)
        session = session_of(app, active)
        target = await drag_a_little(active, session, steps=20)
        await until(lambda: any((np.abs(flanges - target[:3, 3]).max(axis=-1) < 1e-5).any()
                                for _, flanges in active.received.ghost_flanges[-3:]), what="the drag's last target on screen")
        # the server gives up on the frozen client once a frame has waited its patience, and frees it
        await until(lambda: frozen_session.closed, what="the frozen client to be dropped")
        assert any("has not read what was sent to it" in r.getMessage() for r in caplog.records)
        assert len(app.sessions) == 1
        await active.close()

    with caplog.at_level("WARNING", logger="ur10teach.viser_internals.shared_frames"):
        asyncio.run(scenario())


class NotifiedBrowser:
    """A stand-in for a viser client: the notifications it was shown, as (title, body), in ``shown``."""

    client_id = 7

    def __init__(self) -> None:
        self.shown: list[tuple[str, str]] = []

    def add_notification(self, title, body, **_):
        self.shown.append((title, body))


def test_refusals_are_shown_at_a_readable_pace(monkeypatch):
    """Review 2, finding 2: a paused browser sent bad values at 60/s and the server queued a
    notification for each (0.21 MiB/s, for as long as it lasted)."""
    now = [0.0]
    monkeypatch.setattr(feedback, "clock", lambda: now[0])
    browser = NotifiedBrowser()
    for _ in range(600):  # ten seconds of bad values at 60/s, all at one instant of the clock
        feedback.notify(browser, "Not accepted", "θ2: not a number")
    assert len(browser.shown) == feedback.NOTICE_BURST
    now[0] += 10.0
    feedback.notify(browser, "Not accepted", "θ2: not a number")
    assert browser.shown[-1][1] == f"θ2: not a number ({600 - feedback.NOTICE_BURST} more messages were not shown.)"


def test_a_refusal_reaches_the_student_when_the_widget_went_meanwhile():
    """A classroom monkey (2026-12-03): a presenter picked an arm just as another browser took the
    presenter's role over. The pick was refused ("only the presenter ...") and the picker, meanwhile
    removed with the presenter's controls, could not be put back: the student saw "Something went
    wrong" instead of why. The same holds for any widget a refused value is put back into."""
    browser = NotifiedBrowser()
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        def taken_over(label: str) -> None:  # the role went to someone else while this pick was on its way
            picker.folder.remove()
            raise ValueError("only the presenter chooses the class's arm")

        picker = ArmPicker(server.gui, UR10, taken_over, lambda handler: feedback.guard(browser, handler))
        picker.dropdown.value = "SCARA (RRP + roll)"
        assert browser.shown == [("Not accepted", "Only the presenter chooses the class's arm")]
        slider = server.gui.add_slider("Force at the tool (N)", min=0.0, max=400.0, step=5.0, initial_value=50.0)
        dropdown = server.gui.add_dropdown("Plane", ("vertical", "horizontal"))
        for widget in (slider, dropdown):
            widget._impl.value = "no such value"  # as viser stores what a browser sent, before the callback
            widget.remove()
        with pytest.raises(ValueError, match="force"):
            feedback.within(slider, "force")
        with pytest.raises(ValueError, match="plane"):
            feedback.chosen(dropdown, "plane")
    finally:
        server.stop()


def test_a_refusal_said_by_the_run_an_input_started_stays_below_it():
    """A choice whose work runs on a thread of its own (a cloud, a singularity search) is refused by that run; the
    input's callback returning cleared the line the run had just filled, when the run was the quicker
    (2026-12-05: a horizontal section at 999 M samples, its refusal shown for an instant). A refusal said before
    the input came stays until an input is accepted."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        beside = feedback.Beside(server.gui)
        event = type("Event", (), {"client": object()})()

        def run_that_refuses_first(_) -> None:  # the thread's refusal came before the callback returned
            beside.say("height 1.600 m is outside the workspace")

        feedback.guard(None, run_that_refuses_first, beside=beside)(event)
        assert beside.line.visible and "1.600 m" in beside.line.content
        feedback.guard(None, lambda _: None, beside=beside)(event)  # the next input accepted
        assert not beside.line.visible
    finally:
        server.stop()


def test_a_refusal_shows_what_was_typed_as_text():
    """viser's markdown renders raw HTML: a student's "<b>" (or "<p/style=position:fixed;inset:0>"), quoted in the
    refusal below the box, was taken as a tag (until 2026-12-06). It is shown as typed."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        beside = feedback.Beside(server.gui)
        beside.say("target: '<b>' is not a number; type the numbers alone")
        assert "&lt;b&gt;" in beside.line.content and "<b>" not in beside.line.content
    finally:
        server.stop()


def test_a_refusal_line_gone_with_its_panel_meanwhile_is_no_error(caplog):
    """A classroom monkey (2026-12-05): a presenter's input with a refusal shown below it was accepted while another
    browser's action rebuilt that panel. Clearing the line, removed with it, raised: "Something went wrong" in the
    browser and an error logged. A refusal whose line has gone is told in a notice instead."""
    browser = NotifiedBrowser()
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        event = type("Event", (), {"client": object()})()
        beside = feedback.Beside(server.gui)

        def refused(_) -> None:
            raise ValueError("no challenge chosen")

        feedback.guard(browser, refused, beside=beside)(event)
        assert beside.line.visible and browser.shown == []

        def accepted_as_the_panel_goes(_) -> None:  # another browser's action, meanwhile
            beside.line.remove()

        feedback.guard(browser, accepted_as_the_panel_goes, beside=beside)(event)
        beside = feedback.Beside(server.gui)

        def refused_as_the_panel_goes(_) -> None:
            beside.line.remove()
            raise ValueError("a challenge is running: end it first")

        feedback.guard(browser, refused_as_the_panel_goes, beside=beside)(event)
        assert browser.shown == [("Not accepted", "A challenge is running: end it first")]
        assert not [record for record in caplog.records if record.levelno >= logging.ERROR]
    finally:
        server.stop()


def test_garbage_and_out_of_range_input_is_refused(app):
    async def scenario():
        bad = await ViserClient(url(app)).connect()
        good = await ViserClient(url(app)).connect()
        bad_session, good_session = session_of(app, bad), session_of(app, good)
        before = bad_session.state.q
        slider = bad.gui["θ1 base (°)"]["uuid"]

        async def one_by_one(kind: str, frame: bytes) -> None:
            """Send, and wait until the gate has handed it on: it would fold back-to-back values for one widget into the last."""
            passed = app.gate.passed[kind]
            await bad.send_raw(frame)
            await until(lambda: app.gate.passed[kind] > passed, what=f"the gate to pass a {kind}")

        for value in (float("nan"), float("inf"), 1e9, -725.0):
            await one_by_one("GuiUpdateMessage", encode(messages.GuiUpdateMessage(slider, {"value": value})))
        await bad.send(messages.GuiUpdateMessage(slider, {"value": "forty"}))  # viser cannot even cast it
        await bad.send(messages.GuiUpdateMessage(bad.gui["Use branch"]["uuid"], {"value": "99"}))
        await bad.send(messages.GuiUpdateMessage(bad.gui["All 6 (°)"]["uuid"], {"value": "1, 2, x, 4, 5, 6"}))
        await bad.set_gui("Set these values", True)
        for position, wxyz in (
            ((np.nan, 0.0, 0.5), (1.0, 0.0, 0.0, 0.0)),
            ((0.5, 0.0, 0.5), (0.0, 0.0, 0.0, 0.0)),
            ((1e300, 1e300, 1e300), (1.0, 0.0, 0.0, 0.0)),
            ((0.5, 0.2, 0.5), (np.inf, 0.0, 0.0, 0.0)),
        ):
            await one_by_one("TransformControlsUpdateMessage", bad.drag_step(position, wxyz).update)
        # nothing of it reached the arm, and the student was told: the slider's values beside the sliders
        await until(lambda: [title for title, _ in bad.received.notifications].count("Not accepted") >= 3,
                    what="the refusals")
        refusal = bad_session.joints.slider_refusal.line
        await until(lambda: refusal.visible and "Base: from -360° to 360°, got -725.0°" in bad.markdown[refusal._impl.uuid],
                    what="the slider's refusal beside it")
        np.testing.assert_array_equal(bad_session.state.q, before)
        assert np.isfinite(bad_session.state.last.target).all()
        titles = [title for title, _ in bad.received.notifications]
        assert not any(title == "Something went wrong" for title in titles)
        # the slider was put back on the arm's angle, on the server and in the student's browser
        await until(lambda: bad_session.joints.sliders[0].value == 30.0, what="the slider to be restored")
        await until(lambda: bad.gui["θ1 base (°)"]["value"] == 30.0, what="the browser's slider to be restored")
        # both students carry on
        await bad.set_gui("θ2 shoulder (°)", 50.0)
        await until(lambda: abs(np.degrees(bad_session.state.q[1]) - 50.0) < 1e-9, what="a good value after the bad ones")
        await until(lambda: not refusal.visible, what="the refusal gone with the next value accepted")
        target = await drag_a_little(good, good_session, steps=5)
        await until(lambda: np.allclose(good_session.state.last.target, target, atol=1e-9), what="the other student")
        # bytes that are not even a message are dropped at the gate (app/serving/gate.py), before viser sees them
        await bad.send_raw(b"\x00\x01garbage")
        await bad.send_raw(msgspec.msgpack.encode({"type": "NoSuchMessage"}))
        await until(lambda: app.gate.dropped["undecodable message"] == 1 and app.gate.dropped["NoSuchMessage"] == 1,
                    what="the garbage to be dropped")
        await bad.set_gui("θ2 shoulder (°)", 51.0)  # the connection still works
        await until(lambda: abs(np.degrees(bad_session.state.q[1]) - 51.0) < 1e-9, what="a good value after the garbage")
        target = await drag_a_little(good, good_session, steps=3)
        await until(lambda: np.allclose(good_session.state.last.target, target, atol=1e-9), what="the other student, still")
        await asyncio.gather(bad.close(), good.close())  # (left open, the server's stop waited 6 s for its close)

    asyncio.run(scenario())


def test_a_refused_rate_force_or_payload_is_put_back_and_the_arm_goes_on(app, caplog):
    """A NaN or out-of-range value left in a velocity or force slider was refused again by every
    redraw that read it: the panel stopped ("panel redraw failed") and each drag was refused,
    until the student moved that slider back. The slider is now put back at once, to the value it showed (a section
    height refused before any other went to 0 mm, not to the 600 mm it started at)."""
    rate = "θ̇1 base (°/s)"

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client)
        await client.set_gui("Show the torques", True)
        await until(lambda: session.statics.bars.visible, what="the torque bars")
        still = session.velocity.readout.content
        await client.set_gui(rate, 10.0)
        await until(lambda: session.velocity.readout.content != still, what="the tool's velocity for 10 °/s")
        low, high, first_height = session.workspace.height.min, session.workspace.height.max, session.workspace.height.value
        bad = (("Force at the tool (N)", float("nan")), (rate, float("nan")), ("θ̇2 shoulder (°/s)", 1e6),
               ("Payload (kg)", -1.0), ("Section height (mm)", 99999.0))
        for (label, value), (line, words) in zip(bad, (
                (session.statics.refusal.line, "Force (N): from 0 to"), (session.velocity.rates_refusal.line, f"{rate}: from -180 to 180"),
                (session.velocity.rates_refusal.line, "θ̇2 shoulder (°/s): from -180 to 180, got 1000000"),
                (session.statics.refusal.line, "Payload (kg): from 0 to"),
                (session.workspace.refusal.line, f"Section height (mm): from {low:g} to {high:g}, got 99999"))):
            await client.set_gui(label, value)  # refused beside its slider (its folder's line)
            await until(lambda: line.visible and words in line.content, what=f"{label}'s refusal")
        handles = (session.statics.newtons, *session.velocity.sliders[:2], session.statics.payload, session.workspace.height)
        await until(lambda: [handle.value for handle in handles] == [50.0, 10.0, 0.0, 0.0, first_height], what="the last values accepted")
        await goes_on(client, session)
        await client.close()

    without_failures(scenario, caplog)


def test_a_redraw_that_refuses_is_logged_with_its_traceback(app, caplog):
    """A view's redraw that raises ``ValueError`` is shown as "Not accepted" (a value a browser set that it will
    not draw) and the other views are drawn. numpy's shape errors are ValueErrors too: the console now keeps the
    traceback, where such a bug was seen only as a notice in one browser."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client)

        def broken(snapshot):
            np.ones(3) + np.ones(4)  # a bug of the type a refusal has

        session.velocity.render_panel = broken
        before = session.readouts.pose.content
        with caplog.at_level("INFO", logger="ur10teach.session"):
            await drag_a_little(client, session, steps=3)
            await until(lambda: session.readouts.pose.content != before, what="the other views drawn all the same")
            await until(lambda: any("could not be broadcast" in body for _, body in client.received.notifications),
                        what="the notice")
        record = next(r for r in caplog.records if r.name == "ur10teach.session" and "a redraw refused" in r.getMessage())
        assert record.exc_info is not None and "broken" in "".join(traceback.format_exception(*record.exc_info))
        await client.close()

    asyncio.run(scenario())


async def goes_on(client: ViserClient, session) -> None:
    """After refusals: nothing failed, a drag is taken and the panel follows it."""
    before, panel = session.state.last.target, session.readouts.pose.content
    await drag_a_little(client, session, steps=3)  # (a planar arm's target is kept in its plane)
    await until(lambda: not np.allclose(session.state.last.target, before), what="a drag after the refusals")
    await until(lambda: session.readouts.pose.content != panel, what="the panel to follow the drag")
    assert not any(title == "Something went wrong" for title, _ in client.received.notifications)


def without_failures(scenario, caplog) -> None:
    """Run ``scenario``; the app must log no failure meanwhile."""
    with caplog.at_level("ERROR"):
        asyncio.run(scenario())
    assert not [r.getMessage() for r in caplog.records if r.name.startswith("ur10teach")]


def bad_value(kind: str):
    """A value a widget of this kind must refuse: what a browser never sends, or (a text) what no parser takes.
    None: anything viser takes for a button or a checkbox is one of its values."""
    if kind in ("GuiSliderMessage", "GuiNumberMessage"):
        return float("nan")
    if kind in ("GuiDropdownMessage", "GuiButtonGroupMessage"):
        return "no such choice"
    if kind == "GuiTextMessage":
        return "1, x, nan"
    return None


def input_handles(session) -> dict:
    """The session's widgets by uuid, as its views hold them (a list of sliders included)."""
    found = {}
    for view in (*session.panel_views, session.arm_picker):
        for held in vars(view).values():
            for handle in held if isinstance(held, (list, tuple)) else (held,):
                if isinstance(handle, (viser.GuiInputHandle, viser.GuiButtonGroupHandle)):
                    found[handle._impl.uuid] = handle
    return found


def holds_one_of_its_values(handle) -> bool:
    """A slider within its range, a dropdown on one of its options (a text may hold anything)."""
    if isinstance(handle, (viser.GuiSliderHandle, viser.GuiNumberHandle)):
        return (handle.min is None or handle.min <= handle.value) and (handle.max is None or handle.value <= handle.max)
    return not isinstance(handle, viser.GuiDropdownHandle) or handle.value in handle.options


@pytest.mark.parametrize("label", list(ARM_CHOICES))
def test_every_widget_of_every_arm_refuses_what_a_browser_never_sends(app, label, caplog):
    """A NaN in a slider, or a choice not among a dropdown's options, is refused and the widget put
    back, in every arm's panel: nothing fails, and the arm still drags. (A velocity slider left
    at NaN stopped the panel and refused every drag.)"""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client) if label == UR10 else await pick(app, client, label)
        await arrived(client, session)  # the whole panel
        handles = input_handles(session)
        sent = {entry["uuid"]: bad_value(entry["type"]) for entry in client.gui.values() if bad_value(entry["type"]) is not None}
        assert set(sent) <= set(handles), [name for name, entry in client.gui.items() if entry["uuid"] not in handles]
        for uuid, value in sent.items():
            await client.send(messages.GuiUpdateMessage(uuid, {"value": value}))
        await until(lambda: all(holds_one_of_its_values(handles[uuid]) for uuid in sent), what="every widget put back")
        await until(lambda: "Not accepted" in {title for title, _ in client.received.notifications}, what="the refusals")
        await goes_on(client, session)
        await client.close()

    without_failures(scenario, caplog)


def test_students_never_see_each_others_arms(app):
    async def scenario():
        alice = await ViserClient(url(app)).connect()
        bob = await ViserClient(url(app)).connect()
        bob_owner = bob.gizmo_owner
        alice_target = await drag_a_little(alice, session_of(app, alice), steps=8, offset=(0.01, 0.0, 0.0))
        await until(lambda: np.allclose(session_of(app, alice).state.last.target, alice_target, atol=1e-9), what="alice")
        # alice's screen has her last drag: a leak to bob would have been sent with it
        await until(lambda: any((np.abs(flanges - alice_target[:3, 3]).max(axis=-1) < 1e-5).any()
                                for _, flanges in alice.received.ghost_flanges[-3:]), what="alice's screen")
        # every scene message bob received is his own or the shared, unchanging scene
        assert bob.owners_seen <= {bob_owner, ""}
        for _, flanges in bob.received.ghost_flanges:
            assert not (np.abs(flanges - alice_target[:3, 3]).max(axis=-1) < 1e-4).any()
        np.testing.assert_allclose(np.degrees(session_of(app, bob).state.q), [30, 45, 26, 50, 60, 80])
        await alice.close()
        await bob.close()

    asyncio.run(scenario())


@pytest.mark.slow
def test_memory_returns_to_baseline_after_a_class_leaves():
    """Thirty students come, drag, and go, three times: the server's memory stays flat."""

    async def one_class(app) -> None:
        try:
            clients = await asyncio.gather(*(ViserClient(app.url).connect() for _ in range(30)))
        except TimeoutError:  # seen once under a CI run's load: what was the server doing?
            raise AssertionError("a student was not served; the app's last output:\n"
                                 + "".join(app.output[-40:])) from None
        T0 = np.eye(4)
        for k in range(8):  # what a student holds is their session; more drags only add time
            for i, c in enumerate(clients):
                T0[:3, :3] = np.eye(3)
                T = T0.copy()
                T[:3, 3] = (0.6 + 0.01 * k, 0.1 + 0.005 * i, 0.6)
                await c.drag_target(T[:3, 3], wxyz_of(T), "update")
            await asyncio.sleep(BROWSER_SEND_INTERVAL)
        await asyncio.gather(*(c.close() for c in clients))

    def swept_after(app, sweeps: int) -> dict:
        """The server's first report showing nobody left and a sweep of the janitor after ``sweeps``:
        the memory of those who left has been handed back (reading before that raced it, and the
        figure swung by tens of MiB)."""
        return wait_for(lambda: (lambda r: r if r["clients"] == 0 and r["sessions"] == 0 and r["janitor_sweeps"] > sweeps
                                 else None)(app.metrics(time.time(), timeout=HANG_TIMEOUT)), what="the janitor's sweep after everyone left")

    with running_app() as app:
        async def run():
            warm = await ViserClient(app.url).connect()  # first client: caches, imports, the lot
            await warm.close()
            baseline = await asyncio.to_thread(swept_after, app, 0)
            rss = []
            for _ in range(3):
                before = (await asyncio.to_thread(app.metrics, time.time(), HANG_TIMEOUT))["janitor_sweeps"]
                await one_class(app)
                report = await asyncio.to_thread(swept_after, app, before)
                rss.append(report["rss_bytes"])
            return baseline["rss_bytes"], rss

        baseline, rss = asyncio.run(run())
    growth = [(r - baseline) / 2**20 for r in rss]
    # the first class may leave allocator slack behind; later ones must not add to it
    assert growth[-1] - growth[0] < 8, f"memory grew by {growth} MiB over three classes"
    assert growth[0] < 40, f"memory after the first class: +{growth[0]:.1f} MiB"
