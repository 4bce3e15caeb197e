"""What the server tests share: where a server is, waiting for it, and finding a client's session."""

from __future__ import annotations

import asyncio
import time

import numpy as np

from app.server import TeachingServer

from .viser_client import ViserClient, wxyz_of


def url(server: TeachingServer) -> str:
    return f"http://127.0.0.1:{server.port}"


async def until(condition, timeout: float = 15.0, what: str = "condition"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        await asyncio.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def member_of(server: TeachingServer, index: int):
    """The ``index``-th browser of a shared-mode server's classroom, in order of arrival."""
    return list(server.classroom.members.values())[index]


def session_of(server: TeachingServer, client: ViserClient):
    """The server's session for ``client`` (registered a moment after the page is drawn)."""
    client_id = int(client.gizmo_owner)  # a client-scoped node's owner is its client id
    deadline = time.monotonic() + 15.0
    while client_id not in server.sessions and time.monotonic() < deadline:
        time.sleep(0.01)
    return server.sessions[client_id]


async def drag_a_little(client: ViserClient, session, steps: int = 10, offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    T = session.state.last.flange.copy()
    for k in range(steps):
        T[:3, 3] += np.array([0.004, -0.003, 0.002]) + offset
        await client.drag_target(T[:3, 3], wxyz_of(T), "start" if k == 0 else "update")
        await asyncio.sleep(0.05)
    return T


async def become_presenter(client: ViserClient, server: TeachingServer) -> None:
    """Enter the join code and press "Become presenter", as the teacher does; returns once it has the gizmo."""
    await client.set_gui("Join code", server.classroom.code)
    await asyncio.sleep(0.1)
    await client.set_gui("Become presenter", True)
    await until(lambda: client.gizmo_owner is not None and server.classroom.presenter is not None,
                what="the presenter's gizmo")
