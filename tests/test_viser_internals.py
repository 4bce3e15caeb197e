"""Every viser internal the app relies on is still where and what it was (``ur10teach.viser_internals``).

viser is pinned exactly; these fail on an upgrade that moves or reshapes one of them, before
any classroom sees a wrong drawing or an unguarded socket. What each does with them is tested
beside it: tests/test_fast_updates.py, tests/test_shared_frames.py, tests/test_gate.py.
"""

from __future__ import annotations

import asyncio
import functools
import importlib.metadata
import inspect
import json
import pathlib
import re

import numpy as np
import pytest
import viser
from viser import _assignable_props_api
from viser.infra import _infra
from viser.infra._async_message_buffer import AsyncMessageBuffer

from ur10teach import viser_internals
from ur10teach.serving.gate import ALLOWED

ROOT = pathlib.Path(__file__).resolve().parent.parent


def test_viser_is_the_version_pinned():
    pinned = re.search(r'"viser==([0-9.]+)"', (ROOT / "pyproject.toml").read_text()).group(1)
    assert importlib.metadata.version("viser") == pinned


def test_nothing_else_in_the_app_reaches_into_viser():
    """Only ``app/viser_internals/`` imports viser's private modules, reads a handle's private parts or swaps the
    call that starts viser's websocket server."""
    private = re.compile(r"from viser(\.infra)? import _|viser\.infra\._|\._impl\b|\._impl_aux\b|\._viser_server\b|_queue_scene_message"
                         r"|server\.serve = ")
    offenders = [str(path.relative_to(ROOT)) for path in (ROOT / "app").rglob("*.py")
                 if "viser_internals" not in path.parts and private.search(path.read_text())]
    assert not offenders, offenders


def test_the_gates_message_classes_are_vipers():
    for kind, fields in ALLOWED.items():
        cls = getattr(viser_internals.messages, kind)
        assert set(fields) <= set(inspect.signature(cls).parameters), kind


def test_a_client_connection_is_found_where_it_was():
    server = viser.ViserServer(port=0, verbose=False)
    try:
        assert isinstance(server._websock_server._live_connections, dict)
    finally:
        server.stop()


def test_a_starting_server_makes_its_websocket_server_through_serving_through():
    """``serving_through``: viser starts its websocket server with one call of ``websockets.asyncio.server.serve``,
    handing it its handler, its HTTP request handler and its 50 MB limit, and reads each connection with ``recv``
    (what the gate's connection provides). Nothing started, it fails loudly: the gate would not apply."""
    handed = []

    def adapt(handler, process_request, keywords):
        handed.append((handler, process_request, dict(keywords)))
        return handler, process_request, keywords  # (what the gate puts in is tested in tests/test_gate.py)

    with viser_internals.serving_through(adapt):
        server = viser.ViserServer(port=0, verbose=False)
    try:
        [(handler, process_request, keywords)] = handed
        assert callable(handler) and callable(process_request) and keywords["max_size"] == 50 * 1024 * 1024
        assert "await websocket.recv()" in inspect.getsource(_infra)
    finally:
        server.stop()
    with pytest.raises(RuntimeError, match="the gate would not apply"):
        with viser_internals.serving_through(adapt):
            pass  # nothing started a server


def test_the_broadcast_queue_is_where_after_broadcast_reads_it():
    """Its count of queued messages and each connection's cursor in it (the message it has taken last)."""
    server = viser.ViserServer(port=0, verbose=False)
    try:
        buffer = server._websock_server._broadcast_buffer
        assert isinstance(buffer, AsyncMessageBuffer) and buffer.persistent_messages
        before = buffer.message_counter
        server.scene.add_frame("/probe")
        assert buffer.message_counter > before  # the count goes up with what the scene queues
        assert isinstance(buffer.generator_cursors, dict) and callable(buffer.flush)
        assert "self.generator_cursors[client_id] = last_sent_id" in inspect.getsource(AsyncMessageBuffer._window_loop)
    finally:
        server.stop()


def test_the_fast_updates_internals_are_there():
    server = viser.ViserServer(port=0, verbose=False)
    try:
        node = server.scene.add_frame("/probe")
        impl = node._impl
        assert callable(impl.api._queue_scene_message) and impl.name == "/probe"
        assert np.asarray(impl.wxyz).shape == (4,) and np.asarray(impl.position).shape == (3,)
        assert hasattr(impl.props, "scale")
        gizmo = server.scene.add_transform_controls("/probe_gizmo")
        assert hasattr(gizmo._impl_aux, "sync_cb")
        # share_type_hints puts its own cached property in the place of viser's
        assert isinstance(inspect.getattr_static(_assignable_props_api.AssignablePropsBase, "_prop_hints"), functools.cached_property)
    finally:
        server.stop()


def test_the_message_producer_is_what_shared_frames_replaces():
    parameters = list(inspect.signature(_infra._message_producer).parameters)
    assert parameters[:3] == ["websocket", "buffer", "client_id"]
    assert callable(_infra._append_aligned_buffers) and hasattr(AsyncMessageBuffer, "window_generator")


def test_a_queues_event_is_what_shared_frames_makes_safe():
    """viser sets a queue's ``message_event`` in ``push``, from whichever thread queues, and its window
    loop waits on it: shared_frames swaps in a :class:`~ur10teach.viser_internals.shared_frames.WakeOnLoop`."""
    loop = asyncio.new_event_loop()
    try:
        buffer = AsyncMessageBuffer(loop, persistent_messages=False)
        assert type(buffer.message_event) is asyncio.Event and buffer.event_loop is loop
    finally:
        loop.close()
    assert "self.message_event.set()" in inspect.getsource(AsyncMessageBuffer.push)
    assert "await self.message_event.wait()" in inspect.getsource(AsyncMessageBuffer._window_loop)


def test_a_value_fits_its_widget_as_viser_converts_it():
    """``value_fits`` makes the conversion viser's GUI handler makes before anything checks a value."""
    from viser import _gui_api

    assert "type(handle_state.value)(prop_value)" in inspect.getsource(_gui_api.GuiApi._handle_gui_updates)
    server = viser.ViserServer(port=0, verbose=False)
    try:
        slider = server.gui.add_slider("s", min=0.0, max=1.0, step=0.1, initial_value=0.5)
        text = server.gui.add_text("t", "a")
        vector = server.gui.add_vector3("v", (0.0, 0.0, 0.0))
        fits = functools.partial(viser_internals.value_fits, server)
        assert fits(slider._impl.uuid, 1) and fits(slider._impl.uuid, "0.3") and not fits(slider._impl.uuid, "x")
        assert not fits(slider._impl.uuid, [1.0])
        assert fits(text._impl.uuid, "x") and fits(vector._impl.uuid, [1, 2, 3]) and not fits(vector._impl.uuid, ["a", 1, 2])
        assert fits("no such widget", "x")  # viser ignores it
    finally:
        server.stop()


def test_a_value_or_a_pose_is_sent_again_the_way_viser_sends_a_changed_one():
    """``send_again`` queues the messages viser's own setters queue, where they queue them."""
    from viser import _gui_handles, _scene_handles

    assert "GuiUpdateMessage(self._impl.uuid, {\"value\": value})" in inspect.getsource(_gui_handles._GuiInputHandle)
    assert "self._impl.gui_api._websock_interface.queue_message(" in inspect.getsource(_gui_handles._GuiInputHandle)
    node_source = inspect.getsource(_scene_handles.SceneNodeHandle)
    for message in ("SetOrientationMessage", "SetPositionMessage"):
        assert f"_messages.{message}(self._impl.name, v)" in node_source
    assert "self._impl.api._queue_scene_message" in node_source
    server = viser.ViserServer(port=0, verbose=False)
    try:
        slider = server.gui.add_slider("s", min=0.0, max=1.0, step=0.1, initial_value=0.5)
        gizmo = server.scene.add_transform_controls("/gizmo", wxyz=(0.0, 1.0, 0.0, 0.0), position=(1.0, 2.0, 3.0))
        sent = []
        slider._impl.gui_api._websock_interface.queue_message = sent.append
        gizmo._impl.api._queue_scene_message = sent.append
        viser_internals.send_again(slider)
        viser_internals.send_again(gizmo)
        messages = viser_internals.messages
        assert [(type(m), m.uuid, m.updates) for m in sent[:1]] == [(messages.GuiUpdateMessage, slider._impl.uuid, {"value": 0.5})]
        assert [(type(m), m.name) for m in sent[1:]] == [(messages.SetOrientationMessage, "/gizmo"),
                                                          (messages.SetPositionMessage, "/gizmo")]
        assert sent[1].wxyz == (0.0, 1.0, 0.0, 0.0) and sent[2].position == (1.0, 2.0, 3.0)
    finally:
        server.stop()


def test_a_markdowns_title_reaches_the_tab_as_name_tab_relies_on():
    """``name_tab``: viser's page renders a markdown's HTML as React elements, and React 19 lifts a ``<title>``
    among them into the page's head (the lecture hall's browser test reads the tab's title)."""
    client = pathlib.Path(viser.__file__).parent / "client"
    assert json.loads((client / "package.json").read_text())["dependencies"]["react"].startswith("^19")
    assert "rehypePlugins = [rehypeRawDom," in (client / "src" / "Markdown.tsx").read_text()
    assert viser_internals.VISER_TAB_TITLE.decode() in (client / "index.html").read_text()  # what page_titled replaces


@pytest.mark.server
@pytest.mark.parametrize("encoding", ["gzip", "identity"])
def test_the_page_names_its_tab_for_the_app_not_viser(app, encoding):
    """``page_titled``: viser's page titles the tab "Viser", which a student saw whenever the panel (and with it the
    arm's title, ``name_tab``) was folded away, among their other tabs (until 2026-12-07). Its page, as a browser
    asks for it compressed or not, is titled for the app, and its length is the new page's."""
    import gzip
    import urllib.request

    from ur10teach.features.arm_picker import PAGE_TITLE

    from ur10dev.waiting import HANG_TIMEOUT

    from .server_support import url

    asked = urllib.request.Request(url(app), headers={"Accept-Encoding": encoding})
    with urllib.request.urlopen(asked, timeout=HANG_TIMEOUT) as page:
        body = page.read()
        assert int(page.headers["Content-Length"]) == len(body)
        assert page.headers["Content-Encoding"] == encoding
    text = (gzip.decompress(body) if encoding == "gzip" else body).decode()
    assert re.findall("<title>(.*?)</title>", text) == [PAGE_TITLE] and "<script" in text
