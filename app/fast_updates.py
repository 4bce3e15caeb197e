"""Per-frame pose updates straight into viser's message queue: the drag path's hot spot.

viser's public setters (``node.wxyz = …``, ``mesh.batched_positions = …``) cast the
value, compare it with the previous one and queue one message per property: about
60 µs each on the classroom machine. A drag event turns six link nodes and moves six
ghost links; with thirty students dragging, those setters were most of the server's
time. These helpers queue viser's own messages directly — one per node, both instance
arrays of a batched mesh in one message — and keep each handle's stored value in step,
so reading a handle afterwards still tells the truth.

They rely on viser 1.1 internals (``SceneApi._queue_scene_message``, the handles'
``_impl``); ``tests/test_fast_updates.py`` holds what they send to what the public
setters send, so a viser upgrade that changes those internals fails the tests instead
of drawing wrong.
"""

from __future__ import annotations

import numpy as np
import viser
from viser import _messages


def set_orientations(nodes: list[viser.SceneNodeHandle], wxyzs: np.ndarray) -> None:
    """``node.wxyz = w`` for each pair, one message each, without viser's per-call checks."""
    for node, wxyz in zip(nodes, wxyzs.tolist()):
        impl = node._impl
        impl.wxyz[:] = wxyz
        impl.api._queue_scene_message(_messages.SetOrientationMessage(impl.name, tuple(wxyz)))


def set_instances(mesh: viser.BatchedMeshHandle, wxyzs: np.ndarray, positions: np.ndarray | None) -> None:
    """``mesh.batched_wxyzs = wxyzs`` and (unless None) ``mesh.batched_positions = positions`` in one message."""
    impl = mesh._impl
    updates = {"batched_wxyzs": np.array(wxyzs, dtype=np.float32)}
    if positions is not None:
        updates["batched_positions"] = np.array(positions, dtype=np.float32)
    for name, value in updates.items():
        np.copyto(getattr(impl.props, name), value)  # the handle reads back what was sent
    impl.api._queue_scene_message(_messages.SceneNodeUpdateMessage(impl.name, updates))


def stop_echo(gizmo: viser.TransformControlsHandle) -> None:
    """A client-scoped gizmo has nobody to echo its drags to.

    For every drag event viser queues the gizmo's pose for "the other clients" of its
    scope and then drops it at send time, since a client scope has no others; that costs
    two queued messages and two wake-ups of the event loop per event.
    """
    gizmo._impl_aux.sync_cb = None
