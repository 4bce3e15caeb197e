"""The only code that touches viser's internals (viser is pinned exactly in pyproject.toml).

* :mod:`.fast_updates` — pose updates queued straight as viser's own messages, type hints
  evaluated once per props class, a client gizmo's echo switched off;
* :mod:`.shared_frames` — viser's per-connection message producer, replaced by one that
  encodes a broadcast window once for every browser and drops a browser that stops reading;
* :func:`connection_of` — the websocket connection behind a client (the gate's, with its address);
* :data:`messages` — viser's message classes, which the gate validates every incoming message against.

``tests/test_viser_internals.py`` checks that each of these is still where and what it was:
a viser upgrade that moves one fails there, not in a classroom.
"""

from __future__ import annotations

from viser import _messages as messages

__all__ = ["connection_of", "messages"]


def connection_of(client):  # noqa: ANN001, ANN201
    """The connection viser keeps for ``client`` (a ``viser.ClientHandle``), or None once it has gone."""
    return client._viser_server._websock_server._live_connections.get(client.client_id)
