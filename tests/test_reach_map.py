"""The branch-count map in the app: drawn for the gizmo's orientation, following it, off the drag path."""

from __future__ import annotations

import asyncio
import threading

import numpy as np
import pytest

from ur10teach.features import reach_map
from ur10teach.features.reach_map import PLANES, map_image
from ur10teach.style import REACH_COLORS
from ur10core.orientation import rotation_from_zyx_euler
from ur10core.workspace import branch_count_map

from .server_support import session_of, until, url
from ur10dev.viser_client import BROWSER_SEND_INTERVAL, ViserClient, wxyz_of
from ur10dev.waiting import HANG_TIMEOUT

pytestmark = pytest.mark.server


def test_map_image_colours_each_count():
    counts = np.array([[0, 2, 4], [6, 8, 7]], np.int8)
    image = map_image(counts)
    assert image.shape == (2, 3, 4) and image.dtype == np.uint8
    expected = [REACH_COLORS[i] for i in (0, 1, 2, 3, 4, 4)]  # an odd count (a coincidence) as the next even
    for pixel, (rgb, alpha) in zip(image.reshape(-1, 4), expected):
        assert tuple(pixel) == (*rgb, alpha)


def test_the_map_follows_the_gizmos_orientation_at_the_panels_pace(app, monkeypatch):
    """While a map is being computed, the drags that come meanwhile fold into one more map, of the newest pose.

    The first map of the drag is held until every drag event has been applied to the arm,
    however slow the machine: the 30 events then owe at most one more map.
    """
    computing = []  # which thread computed each map
    real_map = reach_map.branch_count_map
    holding, release = threading.Event(), threading.Event()

    def spied(*args, **kwargs):
        computing.append(threading.current_thread().name)
        if holding.is_set():
            release.wait(HANG_TIMEOUT)
        return real_map(*args, **kwargs)

    monkeypatch.setattr(reach_map, "branch_count_map", spied)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client)
        view = session.reach_map
        await client.set_gui("Show branch-count map", True)
        await until(lambda: view.image is not None, what="the map")
        expected = branch_count_map(session.arm, session.state.last.target, "vertical", reach_map.RESOLUTION)
        np.testing.assert_array_equal(view.image.image, map_image(expected.counts))
        # turn the tool about its own z axis in 30 small steps, as a student drags the gizmo's ring
        start = session.state.last.target
        before = view.computed
        holding.set()
        for step in range(1, 31):
            pose = start.copy()
            pose[:3, :3] = start[:3, :3] @ rotation_from_zyx_euler([np.radians(3 * step), 0.0, 0.0])
            await client.drag_target(pose[:3, 3], wxyz_of(pose))
            await asyncio.sleep(BROWSER_SEND_INTERVAL)
        await until(lambda: np.allclose(session.state.last.target[:3, :3], pose[:3, :3], atol=1e-9), what="the drag")
        holding.clear()
        release.set()
        final = session.state.last.target
        await until(lambda: view.shown_key is not None and view.shown_key[0] == final.tobytes(), what="the map of the final pose")
        expected = branch_count_map(session.arm, final, "vertical", reach_map.RESOLUTION)
        np.testing.assert_array_equal(view.image.image, map_image(expected.counts))
        # folded: the held map and one more for the 30 drag events, and none on the drag queue's thread
        assert 1 <= view.computed - before <= 2
        assert all(name.startswith("background") for name in computing)  # the pool's, not the drag queue's
        # another plane; a value not among the options is refused
        await client.set_gui("Plane", tuple(PLANES)[1])
        await until(lambda: view.shown_key[1] == "horizontal", what="the horizontal map")
        np.testing.assert_allclose(view.image.position, [0, 0, final[2, 3]], atol=1e-6)
        refusals = len(client.received.notifications)
        await client.set_gui("Plane", "diagonal")
        await until(lambda: len(client.received.notifications) > refusals, what="the refusal")
        # put back to the plane the map is drawn in, which stays
        await until(lambda: view.plane.value == tuple(PLANES)[1], what="the value put back")
        assert view.shown_key[1] == "horizontal"
        await client.set_gui("Show branch-count map", False)
        await until(lambda: view.image is None, what="the map gone")
        await client.close()

    asyncio.run(scenario())
