"""The only code that touches viser's internals (viser is pinned exactly in pyproject.toml).

* :mod:`.fast_updates` — pose updates queued straight as viser's own messages, type hints
  evaluated once per props class, a client gizmo's echo switched off;
* :mod:`.shared_frames` — viser's per-connection message producer, replaced by one that
  encodes a broadcast window once for every browser, drops a browser that stops reading, and makes
  each queue's event safe to set from a callback's thread;
* :func:`connection_of` — the websocket connection behind a client (the gate's, with its address);
* :func:`after_broadcast` — an action for one browser held until the shared scene's queued messages
  have left for it (viser sends the two queues on two tasks, in no set order);
* :data:`messages` — viser's message classes, which the gate validates every incoming message against;
* :func:`labels_of` — every 3D label of a scene (lecture mode sizes them all);
* :func:`value_fits` — whether a browser's value converts to its widget's type as viser converts it
  (the gate drops one that would raise inside viser's handler);
* :func:`send_again` — a widget's value or a node's pose sent to its browser again, though viser holds it unchanged;
* :func:`name_tab` — the browser tab's title, which viser's page fixes as "Viser";
* :func:`page_titled` — viser's page with a tab title of the app's own, for while the panel's is not shown;
* :func:`serving_through` — the websocket server viser starts, made with the gate's handler, request check
  and limits (the gate's connection stands in for websockets' own: viser reads it with ``recv``).

``tests/test_viser_internals.py`` checks that each of these is still where and what it was:
a viser upgrade that moves one fails there, not in a classroom.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import gzip
import html
import logging
import threading
from typing import Any, Callable, Iterator

import websockets.asyncio.server

from viser import _messages as messages

from .shared_frames import SEND_TIMEOUT

__all__ = ["after_broadcast", "connection_of", "labels_of", "messages", "name_tab", "page_titled", "send_again",
           "serving_through", "value_fits"]

log = logging.getLogger(__name__)

#: How often :func:`after_broadcast` looks whether the broadcast queue has reached a browser (s).
BROADCAST_POLL = 0.005
#: A broadcast window is written on its producer's next step after it leaves the queue: this much
#: later, what the browser's own queue sends (itself a window of 1/60 s later) follows it.
WINDOW_WRITTEN = 0.02
#: The tab title in viser's page (``client/build/index.html``), whichever panel title is shown or not.
VISER_TAB_TITLE = b"<title>Viser</title>"
#: The tab title's place in a panel: last, where the few pixels viser gives any element show nothing.
TAB_TITLE_ORDER = 1e12


def connection_of(client):  # noqa: ANN001, ANN201
    """The connection viser keeps for ``client`` (a ``viser.ClientHandle``), or None once it has gone."""
    return client._viser_server._websock_server._live_connections.get(client.client_id)


def labels_of(scene):  # noqa: ANN001, ANN201
    """Every label node of ``scene`` (a ``viser.SceneApi``): viser keeps its handles by node name."""
    import viser

    return [handle for handle in list(scene._handle_from_node_name.values()) if isinstance(handle, viser.LabelHandle)]


def value_fits(server, uuid: str, value) -> bool:  # noqa: ANN001
    """Whether ``value`` converts to the type of the value of widget ``uuid`` of ``server`` (a ``viser.ViserServer``:
    its own widgets and every browser's), as viser converts it before anything checks it: ``float("x")`` for a
    slider would raise inside viser's handler. True for a widget it does not have (viser ignores those)."""
    for gui in (server.gui, *(client.gui for client in server.get_clients().values())):
        handle = gui._gui_input_handle_from_uuid.get(uuid)
        if handle is None:
            continue
        current = handle._impl.value
        try:
            if isinstance(current, tuple):
                tuple(type(current[0])(v) for v in value) if current else tuple(value)
            else:
                type(current)(value)
        except (TypeError, ValueError, OverflowError):
            return False
        return True
    return True


def send_again(handle) -> None:  # noqa: ANN001
    """Send what viser holds of ``handle`` to its browser again: a GUI input's value, or a scene node's pose.

    viser sends only what changes. A browser whose own change (a slider moved, the gizmo dropped) crossed
    the server's on the way shows the server's, while viser holds the browser's as unchanged.
    """
    import viser

    impl = handle._impl
    if isinstance(handle, viser.SceneNodeHandle):
        impl.api._queue_scene_message(messages.SetOrientationMessage(impl.name, tuple(map(float, impl.wxyz))))
        impl.api._queue_scene_message(messages.SetPositionMessage(impl.name, tuple(map(float, impl.position))))
    else:
        impl.gui_api._websock_interface.queue_message(messages.GuiUpdateMessage(impl.uuid, {"value": impl.value}))


def after_broadcast(client, action: Callable[[], None]) -> None:  # noqa: ANN001
    """Run ``action()`` on viser's event loop once the broadcast messages queued so far have left for
    ``client`` (a ``viser.ClientHandle``); at once if it has gone, at the latest after :data:`SEND_TIMEOUT`.

    viser sends each browser the broadcast queue and the browser's own queue on two tasks, in no
    set order: a node the shared scene has just drawn anew could otherwise reach the browser after
    what ``action`` queues for that one browser under the same name, and replace it.
    """
    server = client._viser_server
    websock = server._websock_server
    buffer = websock._broadcast_buffer
    last = buffer.message_counter - 1
    buffer.flush()
    loop = server.get_event_loop()

    async def when_sent() -> None:
        deadline = loop.time() + SEND_TIMEOUT
        while (buffer.generator_cursors.get(client.client_id, last) < last and client.client_id in websock._live_connections
               and loop.time() < deadline):
            await asyncio.sleep(BROADCAST_POLL)
        await asyncio.sleep(WINDOW_WRITTEN)
        try:
            action()
        except Exception:  # one browser's trouble (it left meanwhile, say) is logged, not raised into the loop
            log.exception("an action after the broadcast for browser %s failed", client.client_id)

    asyncio.run_coroutine_threadsafe(when_sent(), loop)


def name_tab(gui, title: str, element=None):  # noqa: ANN001, ANN201
    """Name the browser's tab ``title``, from ``gui``'s panel (a ``viser.GuiApi``); viser's page names it "Viser".

    viser renders a markdown's HTML with React 19, which puts a ``<title>`` into the page's head ahead of
    viser's own while the panel shows it (folded away to its strip, the tab reads :func:`page_titled`'s).
    ``tests/test_browser_lecture_hall.py`` reads the tab's title. Returns the element that holds it: pass it
    back as ``element`` to rename the tab.
    """
    text = f"<title>{html.escape(title)}</title>"
    if element is None:
        return gui.add_markdown(text, order=TAB_TITLE_ORDER)
    element.content = text
    return element


def page_titled(response, title: str):  # noqa: ANN001, ANN201
    """``response`` (viser's answer to an HTTP request, a ``websockets.http11.Response`` or None) with its page's
    tab titled ``title`` in place of "Viser"; any other answer as it is.

    The panel's title names the tab (:func:`name_tab`) only while the panel shows it: a student who folds the
    panel away, or whose page is still loading, sees this one.
    """
    if (response is None or response.status_code != 200
            or not response.headers.get("Content-Type", "").startswith("text/html")):
        return response
    gzipped = response.headers.get("Content-Encoding") == "gzip"
    body = gzip.decompress(response.body) if gzipped else response.body
    if VISER_TAB_TITLE not in body:
        return response
    body = body.replace(VISER_TAB_TITLE, f"<title>{html.escape(title)}</title>".encode())
    body = gzip.compress(body) if gzipped else body
    headers = response.headers.copy()
    del headers["Content-Length"]
    headers["Content-Length"] = str(len(body))
    return dataclasses.replace(response, headers=headers, body=body)


#: One viser server starting at a time: :func:`serving_through` swaps a name of the whole process's.
_STARTING = threading.Lock()

#: What :func:`serving_through` is handed: viser's handler, its HTTP request handler and the other keywords it
#: passes ``websockets.asyncio.server.serve``, to return as they are to be passed.
Adapt = Callable[[Callable, Any, dict], tuple[Callable, Any, dict]]


@contextlib.contextmanager
def serving_through(adapt: Adapt) -> Iterator[None]:
    """While active, a viser server that starts makes its websocket server with what ``adapt(handler,
    process_request, keywords)`` returns in place of its own handler, HTTP request handler and keywords.

    viser calls ``websockets.asyncio.server.serve`` once, as it starts (``viser.ViserServer()`` returns once
    it is listening), and reads each connection its handler is given with ``recv``. Raises RuntimeError as it
    ends if no server called it: what ``adapt`` puts in would not apply (has viser changed?).
    """
    with _STARTING:
        original = websockets.asyncio.server.serve
        used = False

        class adapted_serve(original):  # type: ignore[misc, valid-type]
            def __init__(self, handler, *args, process_request=None, **kwargs) -> None:  # noqa: ANN001
                nonlocal used
                used = True
                handler, process_request, kwargs = adapt(handler, process_request, kwargs)
                super().__init__(handler, *args, process_request=process_request, **kwargs)

        websockets.asyncio.server.serve = adapted_serve
        try:
            yield
        finally:
            websockets.asyncio.server.serve = original
    if not used:
        raise RuntimeError("viser did not start its websocket server through websockets.asyncio.server.serve: "
                           "the gate would not apply (has viser changed?)")
