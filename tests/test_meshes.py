"""The committed link meshes: reproducible from the script, and placed by the DH frames."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import trimesh

from app.meshes import MESH_DIR, load_links
from ur10core import Arm

ROOT = Path(__file__).resolve().parent.parent


def _build_meshes_module():
    spec = importlib.util.spec_from_file_location("build_meshes", ROOT / "scripts" / "build_meshes.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_script_reproduces_the_committed_files(tmp_path):
    """The same geometry (not the same bytes: a PLY header may change with trimesh's version)."""
    builder = _build_meshes_module()
    for preset in Arm.PRESETS:
        written = builder.write(preset, tmp_path)
        assert len(written) == 14
        for path in written:
            committed = MESH_DIR / preset / path.name
            if committed.stat().st_size == 0 or path.stat().st_size == 0:
                assert committed.stat().st_size == path.stat().st_size == 0
                continue
            fresh, old = (trimesh.load(p, process=False, force="mesh") for p in (path, committed))
            stale = f"{committed} is stale: run python scripts/build_meshes.py"
            np.testing.assert_array_equal(fresh.faces, old.faces, err_msg=stale)
            np.testing.assert_allclose(fresh.vertices, old.vertices, rtol=0, atol=1e-7, err_msg=stale)


def test_sharp_edges_are_split_and_smooth_sides_are_not():
    cylinder = trimesh.creation.cylinder(radius=0.1, height=0.2, sections=40)
    split = _build_meshes_module().split_sharp_edges(cylinder)
    # each rim vertex appears once on the side and once on its cap; the cap centres once
    assert len(split.vertices) == 2 * 2 * 40 + 2
    assert len(split.faces) == len(cylinder.faces)
    # no face changed shape, only which copy of a vertex it uses
    np.testing.assert_allclose(split.vertices[split.faces], cylinder.vertices[cylinder.faces])


@pytest.mark.parametrize("preset", Arm.PRESETS)
def test_meshes_sit_in_their_dh_frames(preset):
    arm = Arm.preset(preset)
    links = load_links(preset)
    base = links[0].body_vertices
    assert np.hypot(base[:, 0], base[:, 1]).max() == pytest.approx(0.095, abs=1e-6)  # Ø190 mm footprint
    assert base[:, 2].min() == pytest.approx(0.0, abs=1e-6)  # standing on the floor
    flange = links[6].body_vertices
    assert flange[:, 2].max() == pytest.approx(0.0, abs=1e-6)  # the tool face is the flange frame
    assert np.hypot(flange[:, 0], flange[:, 1]).max() == pytest.approx(0.0315, abs=1e-6)
    # the wrist-1 housing of link 4 is centred on axis 4 (the z axis of frame {4})
    wrist = links[4].body_vertices
    ring = np.abs(wrist[:, 1]) < 0.02
    assert np.abs(wrist[ring, 0].mean()) < 1e-3
    # the upper arm reaches from the shoulder to the elbow along x2
    upper = links[2].body_vertices
    assert upper[:, 0].min() == pytest.approx(0.0, abs=1e-6)
    assert upper[:, 0].max() == pytest.approx(arm.a2 + 0.060, abs=1e-3)  # the elbow housing, Ø120 mm


def test_assembled_arm_touches_every_joint(course):
    """Placed with frames(q), consecutive links meet: each joint origin is inside a mesh's bounds."""
    links = load_links("course")
    q = np.radians([30, 45, 26, 50, 60, 80])
    frames = course.frames(q)
    for i in range(1, 7):
        origin = frames[i, :3, 3]
        placed = [(frames[j, :3, :3] @ links[j].body_vertices.T).T + frames[j, :3, 3] for j in (i - 1, i)]
        for vertices in placed:
            assert np.linalg.norm(vertices - origin, axis=1).min() < 0.13, f"joint {i} is not covered by link meshes"
