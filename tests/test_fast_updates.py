"""ur10teach.viser_internals.fast_updates sends what viser's public setters send (it relies on viser internals)."""

from __future__ import annotations

import functools

import numpy as np
import pytest
import viser
from viser import _messages

from ur10teach.viser_internals.fast_updates import set_instances, set_orientations, set_positions, set_scales, stop_echo

pytestmark = pytest.mark.server


@pytest.fixture
def scene():
    server = viser.ViserServer(port=0, verbose=False)
    yield server.scene
    server.stop()


def record(scene, monkeypatch) -> list:
    sent = []
    original = type(scene)._queue_scene_message

    def spy(self, message):
        sent.append(message)
        original(self, message)

    monkeypatch.setattr(type(scene), "_queue_scene_message", spy)
    return sent


def test_orientations_match_the_public_setter(scene, monkeypatch):
    public = [scene.add_frame(f"/public/{i}") for i in range(3)]
    fast = [scene.add_frame(f"/fast/{i}") for i in range(3)]
    wxyz = np.array([[0.5, 0.5, 0.5, 0.5], [0.0, 1.0, 0.0, 0.0], [np.cos(0.2), 0.0, 0.0, np.sin(0.2)]])
    sent = record(scene, monkeypatch)
    for node, w in zip(public, wxyz):
        node.wxyz = w
    set_orientations(fast, wxyz)
    assert len(sent) == 6
    for a, b in zip(sent[:3], sent[3:]):
        assert type(a) is _messages.SetOrientationMessage and isinstance(b, _messages.SetOrientationMessage)
        assert a.name.replace("/public/", "") == b.name.replace("/fast/", "")
        np.testing.assert_allclose(a.wxyz, b.wxyz)
        assert a.owner == b.owner
    for p, f in zip(public, fast):
        np.testing.assert_allclose(p.wxyz, f.wxyz)


def test_positions_match_the_public_setter(scene, monkeypatch):
    public = [scene.add_label(f"/public/{i}", str(i)) for i in range(3)]
    fast = [scene.add_label(f"/fast/{i}", str(i)) for i in range(3)]
    positions = np.array([[0.1, 0.2, 0.3], [-1.0, 0.0, 2.5], [0.0, 0.0, 0.0]])
    sent = record(scene, monkeypatch)
    for node, p in zip(public, positions):
        node.position = p + 1.0  # differs from the initial value, so the setter sends
    set_positions(fast, positions + 1.0)
    assert len(sent) == 6
    for a, b in zip(sent[:3], sent[3:]):
        assert type(a) is _messages.SetPositionMessage and isinstance(b, _messages.SetPositionMessage)
        assert a.name.replace("/public/", "") == b.name.replace("/fast/", "")
        np.testing.assert_allclose(a.position, b.position)
        assert a.redundancy_key().replace("/public/", "") == b.redundancy_key().replace("/fast/", "")
        assert a.as_serializable_dict() | {"name": ""} == b.as_serializable_dict() | {"name": ""}
    for p, f in zip(public, fast):
        np.testing.assert_allclose(p.position, f.position)


def test_scales_match_the_public_setter(scene, monkeypatch):
    public = [scene.add_icosphere(f"/public/{i}", radius=1.0, color=(0, 0, 0)) for i in range(2)]
    fast = [scene.add_icosphere(f"/fast/{i}", radius=1.0, color=(0, 0, 0)) for i in range(2)]
    scales = np.array([[0.1, 0.2, 0.3], [1e-4, 2.0, 0.5]])
    sent = record(scene, monkeypatch)
    for node, s in zip(public, scales):
        node.scale = tuple(s)
    set_scales(fast, scales)
    assert len(sent) == 4
    for a, b in zip(sent[:2], sent[2:]):
        assert type(a) is _messages.SceneNodeUpdateMessage and isinstance(b, _messages.SceneNodeUpdateMessage)
        assert a.updates == b.updates and all(type(v) is float for v in b.updates["scale"])
        assert a.redundancy_key().replace("/public/", "") == b.redundancy_key().replace("/fast/", "")
        assert wire(a)[0] | {"name": ""} == wire(b)[0] | {"name": ""}  # the same on the wire, but for the name
    for p, f in zip(public, fast):
        assert p.scale == f.scale


def test_instances_match_the_public_setters(scene, monkeypatch):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2]], np.uint32)
    kwargs = dict(batched_wxyzs=np.tile([1.0, 0, 0, 0], (8, 1)), batched_positions=np.zeros((8, 3)), lod="off")
    public = scene.add_batched_meshes_simple("/public", vertices, faces, **kwargs)
    fast = scene.add_batched_meshes_simple("/fast", vertices, faces, **kwargs)
    rng = np.random.default_rng(0)
    wxyzs, positions = rng.normal(size=(8, 4)), rng.normal(size=(8, 3))
    wxyzs /= np.linalg.norm(wxyzs, axis=1, keepdims=True)
    sent = record(scene, monkeypatch)
    public.batched_wxyzs = wxyzs
    public.batched_positions = positions
    set_instances(fast, wxyzs, positions)
    assert all(isinstance(m, _messages.SceneNodeUpdateMessage) for m in sent) and len(sent) == 3
    merged = {**sent[0].updates, **sent[1].updates}
    assert merged.keys() == sent[2].updates.keys()
    for key in merged:
        np.testing.assert_array_equal(merged[key], sent[2].updates[key])
        assert merged[key].dtype == sent[2].updates[key].dtype
    np.testing.assert_array_equal(public.batched_wxyzs, fast.batched_wxyzs)
    np.testing.assert_array_equal(public.batched_positions, fast.batched_positions)
    set_instances(fast, wxyzs[::-1], None)  # orientations only
    assert list(sent[-1].updates) == ["batched_wxyzs"]
    np.testing.assert_array_equal(fast.batched_positions, public.batched_positions)


def wire(message) -> tuple[dict, list[bytes]]:
    buffers: list = []
    encoded = message.as_serializable_dict(buffers)
    return encoded, [bytes(b) for b in buffers]


def plain(message):
    """The same message as viser's own class, which viser encodes by walking its type hints."""
    viser_class = next(c for c in type(message).__mro__ if c.__module__ == _messages.__name__)
    copy = viser_class(**{f: getattr(message, f) for f in ("name", "wxyz", "updates") if hasattr(message, f)})
    copy.owner = message.owner
    return copy


def test_fast_wire_encoding_is_vipers_own(scene, monkeypatch):
    frame = scene.add_frame("/frame")
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    mesh = scene.add_batched_meshes_simple(
        "/mesh", vertices, np.array([[0, 1, 2]], np.uint32),
        batched_wxyzs=np.tile([1.0, 0, 0, 0], (8, 1)), batched_positions=np.zeros((8, 3)), lod="off",
    )
    sphere = scene.add_icosphere("/sphere", radius=1.0, color=(0, 0, 0))
    sent = record(scene, monkeypatch)
    set_orientations([frame], np.array([[np.cos(0.3), 0.0, np.sin(0.3), 0.0]]))
    rng = np.random.default_rng(1)
    set_instances(mesh, rng.normal(size=(8, 4)), rng.normal(size=(8, 3)))
    set_instances(mesh, rng.normal(size=(8, 4)), None)
    set_scales([sphere], np.array([[0.5, 0.25, 2.0]]))
    assert len(sent) == 4
    for message in sent:
        assert type(plain(message)) is not type(message)  # the fast path is really being compared
        assert wire(message) == wire(plain(message))
        assert message.as_serializable_dict().keys() == plain(message).as_serializable_dict().keys()
        assert message.redundancy_key() == plain(message).redundancy_key()  # culled like viser's own
        message.owner = "someone"  # stamped late: the encoder reads it when it runs
        assert wire(message) == wire(plain(message))


def test_stop_echo(scene):
    gizmo = scene.add_transform_controls("/gizmo")
    assert callable(gizmo._impl_aux.sync_cb)  # viser still echoes by default...
    stop_echo(gizmo)
    assert gizmo._impl_aux.sync_cb is None  # ...and this is how it is switched off


def test_shared_type_hints_are_viser_s_own_and_handles_behave_the_same(scene, monkeypatch):
    """``share_type_hints`` replaces viser's per-handle hints with one evaluation per class: the hints
    must be the ones viser would evaluate, and a handle must cast and refuse values as before."""
    import typing

    from viser import _assignable_props_api

    from ur10teach.viser_internals import fast_updates

    # what it replaces (a viser upgrade that renames it fails here)
    assert isinstance(vars(_assignable_props_api.AssignablePropsBase).get("_prop_hints"), (property, functools.cached_property))
    monkeypatch.setattr(_assignable_props_api.AssignablePropsBase, "_prop_hints",
                        _assignable_props_api.AssignablePropsBase._prop_hints)  # put back after the test
    fast_updates.share_type_hints()
    first, second = scene.add_icosphere("/a", radius=0.1), scene.add_icosphere("/b", radius=0.2)
    assert first._prop_hints is second._prop_hints  # evaluated once for the class
    assert first._prop_hints == typing.get_type_hints(type(first._impl.props))
    first.color = (10, 20, 30)
    first.position = [1, 2, 3]  # a list: cast to the declared array type, as viser does
    assert tuple(first.color) == (10, 20, 30) and first.position.dtype == np.float64
    first.remove()
    with pytest.raises(RuntimeError, match="removed"):
        first.color = (1, 2, 3)
