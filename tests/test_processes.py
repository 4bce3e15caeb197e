"""Several processes on one port (``--processes``): balanced, isolated, and never left behind."""

from __future__ import annotations

import asyncio
import os
import signal
import socket
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from app.__main__ import parse_args
from app.processes import BalancedListener, Helpers, LoadBoard, bind_listener, default_process_count, serve_balanced
from app.server import TeachingServer
from app.workers import DUTY
from benchmarks.bench_drag import HOME_ROTATION
from benchmarks.server_process import running_app
from benchmarks.viser_client import ViserClient, wxyz_of

from .browser_support import wait_for
from .test_classroom import until


def children_of(pid: int) -> set[int]:
    """The running child processes of ``pid`` (its helpers)."""
    found = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            found.update(int(c) for c in (task / "children").read_text().split())
        except FileNotFoundError:  # a thread that has just ended
            pass
    return {c for c in found if alive(c)}


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(") ", 1)[1][0] != "Z"
    except FileNotFoundError:
        return False


# ---------------------------------------------------------------------- the command line


def test_one_process_unless_serving_a_class_in_independent_mode(monkeypatch):
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    assert default_process_count("127.0.0.1", shared=False) == 1  # a student alone
    assert default_process_count("localhost", shared=False) == 1
    assert default_process_count("0.0.0.0", shared=False) == 2  # a class: one per core
    assert default_process_count("0.0.0.0", shared=True) == 1  # one arm for everyone
    monkeypatch.setattr(os, "cpu_count", lambda: 16)
    assert default_process_count("192.168.1.20", shared=False) == 4  # capped
    assert parse_args(["--host", "0.0.0.0", "--processes", "3"]).processes == 3
    assert parse_args(["--host", "0.0.0.0", "--shared"]).processes == 1


@pytest.mark.parametrize("argv", [["--processes", "0"], ["--shared", "--processes", "2"]])
def test_impossible_process_counts_are_refused(argv, capsys):
    with pytest.raises(SystemExit):
        parse_args(argv)
    assert "--processes" in capsys.readouterr().err


# ---------------------------------------------------------------------- the pieces


def test_a_busy_port_moves_on_and_is_never_shared():
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        busy = other.getsockname()[1]
        with bind_listener("127.0.0.1", busy) as ours:
            port = ours.getsockname()[1]
            assert port > busy
            with pytest.raises(OSError):  # not even a second copy of the app gets in (no SO_REUSEPORT)
                socket.create_server(("127.0.0.1", port), reuse_port=True)


def test_the_board_is_shared_and_absent_helpers_are_never_least_loaded():
    board = LoadBoard(3)
    seen = LoadBoard.attach(os.dup(board.fd))  # as a helper inherits it
    assert list(seen.counts) == [0, LoadBoard.ABSENT, LoadBoard.ABSENT]
    assert board.least_loaded(0)
    seen.counts[1] = 0  # helper 1 is serving now
    assert board.least_loaded(0) and board.least_loaded(1)
    board.counts[0] = 2
    assert not seen.least_loaded(0) and seen.least_loaded(1)
    assert not board.least_loaded(2)  # still starting


def test_only_the_least_loaded_process_accepts():
    board = LoadBoard(2)
    plain = bind_listener("127.0.0.1", 0)
    port = plain.getsockname()[1]
    first = BalancedListener.wrap(os.dup(plain.fileno()), board, 0)
    second = BalancedListener.wrap(plain.detach(), board, 1)
    first.publish(), second.publish()
    first.setblocking(False), second.setblocking(False)
    students = [socket.create_connection(("127.0.0.1", port)) for _ in range(3)]
    try:
        a, _ = first.accept()  # a tie: either may take it
        assert list(board.counts) == [1, 0]
        with pytest.raises(BlockingIOError):  # the first now leaves the next one to the second...
            first.accept()
        b, _ = second.accept()  # ...which takes it
        assert list(board.counts) == [1, 1]
        a.close()
        assert list(board.counts) == [0, 1]  # a closed connection no longer counts
        a.close()  # closing twice counts once
        assert list(board.counts) == [0, 1]
        c, _ = first.accept()
        b.close(), c.close()
        assert list(board.counts) == [0, 0]
    finally:
        for s in students:
            s.close()
        first.close(), second.close()


def test_a_connection_the_others_leave_waiting_is_taken_after_a_while():
    board = LoadBoard(2)
    plain = bind_listener("127.0.0.1", 0)
    listener = BalancedListener.wrap(plain.detach(), board, 0)
    listener.setblocking(False)
    listener.publish(+5)  # we look busier than process 1, which is stuck and never accepts
    board.counts[1] = 0
    student = socket.create_connection(listener.getsockname())
    started = time.monotonic()
    try:
        while True:  # as asyncio does: the socket stays readable, so accept is tried again and again
            try:
                connection, _ = listener.accept()
                break
            except BlockingIOError:
                time.sleep(0.01)
        waited = time.monotonic() - started
        assert BalancedListener.PATIENCE <= waited < BalancedListener.PATIENCE + 0.5
        connection.close()
    finally:
        student.close()
        listener.close()


def test_a_helper_that_cannot_start_stops_the_app_with_a_clear_error(monkeypatch):
    monkeypatch.setattr(sys, "executable", "/bin/false")  # a helper that exits at once
    listener = serve_balanced("127.0.0.1", 0, 2)
    try:
        with pytest.raises(RuntimeError, match="helper process 1 could not start"):
            Helpers(listener, preset="course", host="127.0.0.1")
        assert listener.board.counts[1] == LoadBoard.ABSENT  # never chosen for a connection
    finally:
        listener.close()


# ---------------------------------------------------------------------- the app


def test_the_processes_split_the_machines_panel_budget():
    listener = serve_balanced("127.0.0.1", 0, 2)
    app = TeachingServer(port=0, listener=listener)
    alone = TeachingServer(port=0)
    try:
        assert app.refresher.duty == pytest.approx(DUTY / 2)
        assert alone.refresher.duty == pytest.approx(DUTY)
    finally:
        app.stop()
        alone.stop()
        listener.close()


async def drag_and_see(client: ViserClient, offset: float) -> np.ndarray:
    """Drag this student's target to a place of their own (``offset`` m along x); wait for their ghosts to get there."""
    start = np.array(client.received.flange_updates[-1][1])
    T = np.eye(4)
    T[:3, :3] = HOME_ROTATION
    for k in range(5):
        T[:3, 3] = start + (offset, 0.01 * (k + 1), -0.05)
        await client.drag_target(T[:3, 3], wxyz_of(T), "start" if k == 0 else "update")
        await asyncio.sleep(0.05)

    def shows_target() -> bool:
        if not client.received.ghost_flanges:
            return False
        flanges = client.received.ghost_flanges[-1][1]
        valid = np.abs(flanges).sum(axis=-1) > 0
        return bool(valid.any()) and np.allclose(flanges[valid], T[:3, 3], atol=1e-4)

    await until(shows_target, what="the student's own ghosts at their target")
    return T[:3, 3]


def test_a_class_is_spread_evenly_and_every_student_keeps_their_own_arm():
    with running_app("--processes", "2") as app:
        assert app.processes == 2

        async def scenario():
            arriving = [await ViserClient(app.url).connect(timeout=60) for _ in range(6)]  # one after another
            together = await asyncio.gather(*(ViserClient(app.url).connect(timeout=60) for _ in range(10)))
            clients = [*arriving, *together]
            report = await asyncio.to_thread(app.metrics, time.time() + 0.2)
            split = [r["clients"] for r in report["processes"]]
            assert sum(split) == 16 and max(split) - min(split) <= 2, split
            # students on either process drag their own targets, each to a different place
            targets = await asyncio.gather(*(drag_and_see(c, 0.003 * k) for k, c in enumerate(clients)))
            for k, c in enumerate(clients):  # nobody's 3D view ever showed another student's target
                assert c.owners_seen <= {c.gizmo_owner, ""}
                others = np.delete(np.array(targets), k, axis=0)
                for _, flanges in c.received.ghost_flanges:
                    assert not (np.abs(flanges[:, None] - others[None]).max(axis=-1) < 1e-4).any()
            for c in clients:
                await c.close()
            report = await asyncio.to_thread(app.metrics, time.time() + 1.5)
            assert [r["clients"] for r in report["processes"]] == [0, 0]

        asyncio.run(scenario())


def test_a_helper_that_dies_is_replaced_and_its_students_reconnect():
    with running_app("--processes", "2") as app:
        (helper,) = children_of(app.process.pid)
        killed = []

        async def scenario():
            clients = [await ViserClient(app.url).connect(timeout=60) for _ in range(4)]
            os.kill(helper, signal.SIGKILL)  # a helper crashes mid-lesson
            killed.append(time.time())
            await until(lambda: sum(c._websocket.state.name == "CLOSED" for c in clients) == 2,
                        what="the crashed helper's two students to be cut off")
            # they reload at once and are served (by the first process: the helper is gone)
            rejoined = [await ViserClient(app.url).connect(timeout=30) for _ in range(2)]
            await asyncio.gather(*(drag_and_see(c, 0.02) for c in rejoined))
            for c in clients + rejoined:
                await c.close()

        asyncio.run(scenario())
        wait_for(lambda: len(children_of(app.process.pid) - {helper}) == 1, what="a new helper")
        wait_for(lambda: any("restarting it" in line for line in app.output), what="the warning")

        async def after():  # once serving, the new helper takes its share again
            await asyncio.to_thread(app.metrics, killed[0] + 1.0, 120)
            clients = [await ViserClient(app.url).connect(timeout=60) for _ in range(4)]
            report = await asyncio.to_thread(app.metrics, time.time() + 0.2)
            assert [r["clients"] for r in report["processes"]] == [2, 2]
            for c in clients:
                await c.close()

        asyncio.run(after())


@pytest.mark.parametrize("how", ["stopped", "killed"])
def test_helpers_never_outlive_the_app(how):
    with running_app("--processes", "3") as app:
        helpers = children_of(app.process.pid)
        assert len(helpers) == 2 and all(alive(pid) for pid in helpers)
        if how == "killed":  # even without a chance to stop them, they notice and leave
            app.process.kill()
            app.process.wait()
    wait_for(lambda: not any(alive(pid) for pid in helpers), timeout=30, what="the helpers to exit")


@pytest.mark.browser
def test_real_browsers_load_the_page_from_several_processes():
    """Two Chromium tabs: each page's requests may be answered by either process; both get a whole app."""
    from playwright.sync_api import sync_playwright

    from .browser_support import CONNECTED, SMALL_VIEWPORT, launch

    with running_app("--processes", "2") as app, sync_playwright() as playwright:
        own = app.url.removeprefix("http://")
        browser = launch(playwright)
        requests: list[str] = []
        pages = []
        for _ in range(2):
            page = browser.new_page(viewport=SMALL_VIEWPORT)
            page.on("request", lambda request: requests.append(request.url))
            page.goto(app.url)
            page.wait_for_selector(CONNECTED, timeout=60_000)
            wait_for(lambda: page.get_by_text("shoulder right, elbow down, wrist not flipped").count() > 0,
                            timeout=60, what="the panel")
            pages.append(page)
        report = app.metrics(time.time() + 0.2)
        assert [r["clients"] for r in report["processes"]] == [1, 1]  # one tab in each process
        browser.close()
    assert requests and all(url.split("/")[2] == own for url in requests if url.startswith("http"))
