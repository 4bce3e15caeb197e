"""The only code that touches viser's internals (viser is pinned exactly in pyproject.toml).

* :mod:`.fast_updates` — pose updates queued straight as viser's own messages, type hints
  evaluated once per props class, a client gizmo's echo switched off;
* :mod:`.shared_frames` — viser's per-connection message producer, replaced by one that
  encodes a broadcast window once for every browser and drops a browser that stops reading;
* :func:`connection_of` — the websocket connection behind a client (the gate's, with its address);
* :data:`messages` — viser's message classes, which the gate validates every incoming message against;
* :func:`labels_of` — every 3D label of a scene (lecture mode sizes them all).

``tests/test_viser_internals.py`` checks that each of these is still where and what it was:
a viser upgrade that moves one fails there, not in a classroom.
"""

from __future__ import annotations

from viser import _messages as messages

__all__ = ["connection_of", "labels_of", "messages"]


def connection_of(client):  # noqa: ANN001, ANN201
    """The connection viser keeps for ``client`` (a ``viser.ClientHandle``), or None once it has gone."""
    return client._viser_server._websock_server._live_connections.get(client.client_id)


def labels_of(scene):  # noqa: ANN001, ANN201
    """Every label node of ``scene`` (a ``viser.SceneApi``): viser keeps its handles by node name."""
    import viser

    return [handle for handle in list(scene._handle_from_node_name.values()) if isinstance(handle, viser.LabelHandle)]
