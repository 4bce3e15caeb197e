"""Per-frame pose updates straight into viser's message queue: the drag path's hot spot.

Why it is built so: docs/architecture.md §6.
"""

from __future__ import annotations

import functools
import os
import typing

import numpy as np
import viser
from viser import _assignable_props_api, _messages


class _OrientationMessage(_messages.SetOrientationMessage):
    """A ``SetOrientationMessage`` whose ``wxyz`` is already a tuple of Python floats.

    (A leading underscore keeps it out of viser's message-type registry: on the wire it
    is, and says it is, a ``SetOrientationMessage``.)
    """

    def as_serializable_dict(self, binary_buffers: list | None = None) -> dict:
        return {"name": self.name, "wxyz": self.wxyz, "owner": self.owner, "type": "SetOrientationMessage"}

    def redundancy_key(self) -> str:
        return f"scene:{self.name}:update:SetOrientationMessage"  # supersedes viser's own, and vice versa


class _PositionMessage(_messages.SetPositionMessage):
    """A ``SetPositionMessage`` whose ``position`` is already a tuple of Python floats."""

    def as_serializable_dict(self, binary_buffers: list | None = None) -> dict:
        return {"name": self.name, "position": self.position, "owner": self.owner, "type": "SetPositionMessage"}

    def redundancy_key(self) -> str:
        return f"scene:{self.name}:update:SetPositionMessage"


class _UpdateMessage(_messages.SceneNodeUpdateMessage):
    """A ``SceneNodeUpdateMessage`` whose updates are C-contiguous float32 arrays or tuples of Python floats."""

    def as_serializable_dict(self, binary_buffers: list | None = None) -> dict:
        updates = {}
        for name, array in self.updates.items():
            if isinstance(array, tuple):
                updates[name] = array
            elif binary_buffers is None:
                updates[name] = array.data
            else:
                updates[name] = {"__binary_index": len(binary_buffers), "dtype": array.dtype.str}
                binary_buffers.append(array.data)
        return {"name": self.name, "updates": updates, "owner": self.owner, "type": "SceneNodeUpdateMessage"}


#: Draw through viser's public setters instead (for the benchmark that keeps this module honest).
PUBLIC_SETTERS = os.environ.get("UR10_TEACH_PUBLIC_SETTERS") == "1"

_HINTS_OF_CLASS: dict[type, dict[str, typing.Any]] = {}


def _prop_hints(handle) -> dict[str, typing.Any]:
    props_class = type(handle._impl.props)
    hints = _HINTS_OF_CLASS.get(props_class)
    if hints is None:
        hints = _HINTS_OF_CLASS[props_class] = typing.get_type_hints(props_class)
    return hints


def share_type_hints() -> None:
    """Every handle of one props class reads the same type hints, evaluated once (viser: once per handle).

    ``UR10_TEACH_PUBLIC_SETTERS=1`` leaves viser as it is (``benchmarks/bench_join_storm.py`` measures both).
    """
    if not PUBLIC_SETTERS:
        shared = functools.cached_property(_prop_hints)  # then read from the handle, as viser's own
        shared.__set_name__(_assignable_props_api.AssignablePropsBase, "_prop_hints")
        _assignable_props_api.AssignablePropsBase._prop_hints = shared


def _set_each(nodes: list[viser.SceneNodeHandle], values: np.ndarray, field: str, message: type) -> None:
    """``setattr(node, field, v)`` for each pair, one ``message`` each, without viser's per-call checks."""
    if PUBLIC_SETTERS:
        for node, value in zip(nodes, values):
            setattr(node, field, value)
        return
    for node, value in zip(nodes, values.tolist()):
        impl = node._impl
        getattr(impl, field)[:] = value  # the handle reads back what was sent
        impl.api._queue_scene_message(message(impl.name, tuple(value)))


def set_orientations(nodes: list[viser.SceneNodeHandle], wxyzs: np.ndarray) -> None:
    """``node.wxyz = w`` for each pair (see :func:`_set_each`)."""
    _set_each(nodes, wxyzs, "wxyz", _OrientationMessage)


def set_positions(nodes: list[viser.SceneNodeHandle], positions: np.ndarray) -> None:
    """``node.position = p`` for each pair (see :func:`_set_each`)."""
    _set_each(nodes, positions, "position", _PositionMessage)


def set_scales(nodes: list[viser.SceneNodeHandle], scales: np.ndarray) -> None:
    """``node.scale = (sx, sy, sz)`` for each pair (see :func:`_set_each`)."""
    if PUBLIC_SETTERS:
        for node, value in zip(nodes, scales):
            node.scale = tuple(value)
        return
    for node, value in zip(nodes, scales.tolist()):
        impl = node._impl
        impl.props.scale = tuple(value)  # the handle reads back what was sent
        impl.api._queue_scene_message(_UpdateMessage(impl.name, {"scale": tuple(value)}))


def set_instances(mesh: viser.BatchedMeshHandle, wxyzs: np.ndarray, positions: np.ndarray | None) -> None:
    """``mesh.batched_wxyzs = wxyzs`` and (unless None) ``mesh.batched_positions = positions`` in one message."""
    if PUBLIC_SETTERS:
        mesh.batched_wxyzs = wxyzs
        if positions is not None:
            mesh.batched_positions = positions
        return
    impl = mesh._impl
    # sent as they are when already C-contiguous float32 (the caller must not change them afterwards)
    updates = {"batched_wxyzs": np.ascontiguousarray(wxyzs, dtype=np.float32)}
    if positions is not None:
        updates["batched_positions"] = np.ascontiguousarray(positions, dtype=np.float32)
    for name, value in updates.items():
        np.copyto(getattr(impl.props, name), value)  # the handle reads back what was sent
    impl.api._queue_scene_message(_UpdateMessage(impl.name, updates))


def stop_echo(gizmo: viser.TransformControlsHandle) -> None:
    """A client-scoped gizmo has nobody to echo its drags to.

    For every drag event viser queues the gizmo's pose for "the other clients" of its
    scope and then drops it at send time, since a client scope has no others; that costs
    two queued messages and two wake-ups of the event loop per event.
    """
    gizmo._impl_aux.sync_cb = None
