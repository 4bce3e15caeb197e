"""The committed link meshes: reproducible from the script, and placed by the DH frames."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import trimesh

from ur10teach.meshes import MESH_DIR, REAL, _read, SCHEMATIC, body_points, load_links, load_models
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
    for preset in Arm.UR_PRESETS:
        written = builder.write(preset, tmp_path)
        assert len(written) == 14
        for path in written:
            committed = MESH_DIR / preset / path.name
            if committed.stat().st_size == 0 or path.stat().st_size == 0:
                assert committed.stat().st_size == path.stat().st_size == 0
                continue
            (fresh_vertices, fresh_faces), (old_vertices, old_faces) = (_read(p) for p in (path, committed))
            stale = f"{committed} is stale: run python scripts/build_meshes.py"
            np.testing.assert_array_equal(fresh_faces, old_faces, err_msg=stale)
            np.testing.assert_allclose(fresh_vertices, old_vertices, rtol=0, atol=1e-7, err_msg=stale)


def test_sharp_edges_are_split_and_smooth_sides_are_not():
    cylinder = trimesh.creation.cylinder(radius=0.1, height=0.2, sections=40)
    split = _build_meshes_module().split_sharp_edges(cylinder)
    # each rim vertex appears once on the side and once on its cap; the cap centres once
    assert len(split.vertices) == 2 * 2 * 40 + 2
    assert len(split.faces) == len(cylinder.faces)
    # no face changed shape, only which copy of a vertex it uses
    np.testing.assert_allclose(split.vertices[split.faces], cylinder.vertices[cylinder.faces])


@pytest.mark.parametrize("preset", Arm.UR_PRESETS)
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


# ---------------------------------------------------------------- UR's real UR10 meshes

def _convert_module():
    spec = importlib.util.spec_from_file_location("convert_ur_meshes", ROOT / "scripts" / "convert_ur_meshes.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_urdf_to_dh_mapping_is_the_controllers_convention():
    """Solved from UR's URDF numbers alone, the joint mapping is docs/kinematics.md §6's, found independently."""
    from ur10core.controller import CONTROLLER_OFFSET

    to_dh, signs, offsets = _convert_module().dh_from_urdf(Arm.preset("ur10"))
    np.testing.assert_array_equal(signs, np.ones(6))
    np.testing.assert_allclose(offsets, CONTROLLER_OFFSET)
    np.testing.assert_allclose(to_dh[:, 3], [[0, 0, 0, 1]] * 7, atol=1e-12)


def _seam(points: np.ndarray, origin: np.ndarray, axis: np.ndarray, side: int, reach: float,
          depth: float = 0.005, sectors: int = 24) -> tuple[float, float, float, int]:
    """Where a link's housing ends along ``axis`` (facing ``side``): (height, outline centre's distance
    from the axis, outline radius, sectors filled), from the outermost point in each of ``sectors``."""
    relative = points - origin
    height = relative @ axis
    radial = relative - np.outer(height, axis)
    near = np.linalg.norm(radial, axis=1) < reach
    end = (side * height[near]).max()
    ring = near & (side * height > end - depth)
    e1 = np.cross(axis, [1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.cross(axis, [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    xy = np.stack([radial[ring] @ e1, radial[ring] @ np.cross(axis, e1)], axis=1)
    sector = ((np.arctan2(xy[:, 1], xy[:, 0]) + np.pi) / (2 * np.pi) * sectors).astype(int) % sectors
    outline = np.array([xy[sector == s][np.argmax((xy[sector == s] ** 2).sum(1))] for s in np.unique(sector)])
    # the circle through the outline (least squares: |p|² = 2 c·p + k)
    (cx, cy, k), *_ = np.linalg.lstsq(np.c_[2 * outline, np.ones(len(outline))], (outline**2).sum(1), rcond=None)
    return side * end, float(np.hypot(cx, cy)), float(np.sqrt(k + cx * cx + cy * cy)), len(outline)


#: housing radii of the UR10's joints (Ø150, Ø117, Ø90 mm), plus a margin for the outline search
HOUSING_REACH = {1: 0.078, 2: 0.078, 3: 0.062, 4: 0.048, 5: 0.048, 6: 0.048}


@pytest.mark.parametrize("preset", ["ur10", "course"])
@pytest.mark.parametrize("joint", range(1, 7))
def test_real_links_meet_on_the_dh_joint_axes(preset, joint):
    """Each joint's housing, as both links' meshes draw it, is a circle about the DH axis z_j.

    Link j−1 ends where link j begins: same height along the axis, same radius, both
    centred on the axis. A mesh shifted 2–3 mm against its DH frame already fails one of them.
    """
    arm = Arm.preset(preset)
    links = load_models(preset).by_name[REAL]
    slack = 0.0 if preset == "ur10" else max(abs(x - y) for x, y in zip(arm.dh_lengths, Arm.preset("ur10").dh_lengths))
    before = arm.link_transforms(np.zeros(6))[joint - 1]  # frame {j} in frame {j−1}
    # points spread over the surfaces (by area), not the vertices: decimation leaves flat rims few of those
    meshes = [trimesh.sample.sample_surface(trimesh.Trimesh(*link.merged, process=False), 200_000, seed=joint)[0]
              for link in links[joint - 1:joint + 1]]
    placements = ((before[:3, 3], before[:3, 2]), (np.zeros(3), np.array([0.0, 0, 1])))
    # link j−1 ends and link j begins facing each other, which way round depends on the link
    arrangements = [[_seam(m, *where, side, HOUSING_REACH[joint]) for m, where, side in zip(meshes, placements, sides)]
                    for sides in ((1, -1), (-1, 1))]
    sides = max(arrangements, key=lambda seams: min(seam[3] for seam in seams))
    (end_a, off_a, radius_a, filled_a), (end_b, off_b, radius_b, filled_b) = sides
    assert min(filled_a, filled_b) >= 12, "a housing's outline should go at least half round the axis"
    assert off_a < 1.5e-3 + slack and off_b < 1.5e-3 + slack, f"outline centres {off_a * 1e3:.2f}, {off_b * 1e3:.2f} mm off axis {joint}"
    assert end_a == pytest.approx(end_b, abs=1e-3 + slack), "the two links should meet along the axis"
    assert radius_a == pytest.approx(radius_b, abs=1e-3)
    assert radius_a == pytest.approx(HOUSING_REACH[joint] - 0.003, abs=0.003)


def test_real_models_ship_beside_the_schematic_with_a_light_ghost():
    models = load_models("course")
    assert models.names == (REAL, SCHEMATIC)
    assert load_models("ur10e").names == (SCHEMATIC,)  # UR's UR10 meshes do not fit the e-series' lengths
    real = models.by_name[REAL]
    faces = sum(len(link.body_faces) + len(link.cap_faces) for link in real)
    ghost_faces = sum(len(link.ghost[1]) for link in real)
    assert 20_000 < faces < 80_000 and ghost_faces < faces / 2
    size = sum(p.stat().st_size for p in (MESH_DIR / "real" / "ur10").glob("*.glb"))
    assert size < 2 * 2**20  # light enough for thirty browsers on one classroom network
    assert (MESH_DIR / "real" / "ur10" / "LICENSE.md").read_text().count("BSD") >= 1
    # the floor check uses the arm that would collide: the real one
    assert models.outline.shape[0] == 7 and models.outline is body_points(real)
