"""What the server tests share: where a server is, waiting for it, and finding a client's session."""

from __future__ import annotations

import asyncio
import re
import urllib.error
import urllib.request

import numpy as np

from ur10teach.serving.server import TeachingServer
from ur10dev.viser_client import BROWSER_SEND_INTERVAL, ViserClient, wxyz_of
from ur10dev.waiting import HANG_TIMEOUT, until, wait_for

__all__ = ["a_ghost_to_take", "become_presenter", "drag_a_little", "get", "member_of", "screen_addresses", "scene_pose",
           "session_of", "until", "url", "wait_for"]


def a_ghost_to_take(arm, seed: int = 2) -> tuple[np.ndarray, int]:
    """(joints, slot): a pose of ``arm`` where a ghost is drawn (one apart from the arm, the one standing for its
    pose) whose branch is within the joint limits, and that ghost's slot."""
    from ur10teach.features.ik_target import lead, same_pose_groups
    from ur10teach.state import ArmState

    for q in arm.sample_joints(50, seed=seed):
        last = ArmState(arm, q).last
        within = last.solution.within_limits
        slots = [lead(g, within) for g in same_pose_groups(last.ghost_frames, last.solution.valid) if last.slot not in g]
        if any(within[k] for k in slots):
            return q, next(k for k in slots if within[k])
    raise AssertionError(f"no pose of the {arm.name} arm with a ghost it can take")


def url(server: TeachingServer) -> str:
    return f"http://127.0.0.1:{server.port}"


def get(server: TeachingServer, path: str) -> int:
    """The HTTP status ``server`` answers a plain request for ``path`` with (as a page's picture is asked for)."""
    try:
        with urllib.request.urlopen(url(server) + path, timeout=HANG_TIMEOUT) as answer:
            return answer.status
    except urllib.error.HTTPError as refusal:  # viser's own answer to an address it has no file at
        return refusal.code


def screen_addresses(client: ViserClient) -> dict[str, str]:
    """What a page may say of its screen (a pixel ratio, "narrow", "wide") -> the address the page's element asks for
    to say it (``serving.screens``), once it has one element (none while one replaces another)."""
    probes = [content for content in client.html.values() if "url(dppx/" in content]
    found = re.findall(r"url\((dppx/[\w-]+/(\d\.\d\d|narrow|wide))\)", probes[0]) if len(probes) == 1 else []
    return {said: "/" + path for path, said in found}  # (relative to the page's address, the root here)


def scene_pose(scene, handle) -> np.ndarray:
    """(4, 4) where a scene node is in the world: its own pose through every node above it, as the browser
    composes them (a node's pose is in its parent's frame)."""
    from ur10core.orientation import transform_from_quaternion

    nodes, parts = scene._handle_from_node_name, handle.name.split("/")
    pose = transform_from_quaternion(np.asarray(handle.wxyz, dtype=float), np.asarray(handle.position, dtype=float))
    for name in ("/".join(parts[:k]) for k in range(len(parts) - 1, 1, -1)):
        if name in nodes:
            parent = nodes[name]
            pose = transform_from_quaternion(np.asarray(parent.wxyz, dtype=float), np.asarray(parent.position, dtype=float)) @ pose
    return pose


def member_of(server: TeachingServer, index: int):
    """The ``index``-th browser of a shared-mode server's classroom, in order of arrival."""
    return list(server.classroom.members.values())[index]


def session_of(server: TeachingServer, client: ViserClient):
    """The server's session for ``client``, once built (registered a moment after the page is drawn)."""
    client_id = int(client.gizmo_owner)  # a client-scoped node's owner is its client id

    def built():
        session = server.sessions.get(client_id)
        return session if session is not None and session.built else None

    return wait_for(built, what=f"client {client_id}'s session")


async def drag_a_little(client: ViserClient, session, steps: int = 10, offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Drag ``session``'s target in ``steps`` small moves at a browser's pace; returns the last target.

    Nothing here waits for the server: a test waits for the target it returns.
    """
    T = session.state.last.flange.copy()
    for k in range(steps):
        T[:3, 3] += np.array([0.004, -0.003, 0.002]) + offset
        await client.drag_target(T[:3, 3], wxyz_of(T), "start" if k == 0 else "update", name=session.ik_target.gizmo.name)
        await asyncio.sleep(BROWSER_SEND_INTERVAL)
    return T


async def become_presenter(client: ViserClient, server: TeachingServer) -> None:
    """Enter the join code and press "Become presenter", as the teacher does (a page on the teacher's own computer that
    found nobody presenting presents already); returns once it has the gizmo."""
    await client.present(server.classroom.code)
    await until(lambda: client.gizmo_owner is not None and server.classroom.presenter is not None
                and server.classroom.presenter.session is not None and server.classroom.presenter.session.built,
                what="the presenter's gizmo and panel")
