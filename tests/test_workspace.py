"""The workspace cloud: positions by FK, manipulability = |det J|, reproducible."""

import numpy as np
import pytest

from ur10core import Arm, flange_to_controller
from ur10core.workspace import (MAP_PLANES, base_turn, branch_count_map, heights_above_floor, revolved_boundary, turnable_into,
                                vertical_section)

from .conftest import urs_own_solver

pytestmark = pytest.mark.core


def test_points_and_manipulability_come_from_fk_and_the_jacobian(course):
    points, manipulability, q = course.sample_workspace(20000, seed=3, return_joints=True)
    assert points.shape == (20000, 3) and manipulability.shape == (20000,) and q.shape == (20000, 6)
    np.testing.assert_allclose(points, course.fk(q)[:, :3, 3], atol=1e-14)
    np.testing.assert_allclose(manipulability, np.abs(np.linalg.det(course.jacobian(q))), atol=1e-14)
    assert (q[:, :5] > -np.pi).all() and (q[:, :5] <= np.pi).all() and (q[:, 5] == 0).all()


def test_reproducible_and_seeded(course):
    a, ma = course.sample_workspace(150_000, seed=7)  # more than one block: threaded
    b, mb = course.sample_workspace(150_000, seed=7)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(ma, mb)
    c, _ = course.sample_workspace(150_000, seed=8)
    assert not np.array_equal(a, c)
    # a prefix of a larger cloud is the smaller cloud: blocks are seeded by position
    d, _ = course.sample_workspace(70_000, seed=7)
    np.testing.assert_array_equal(d[:65536], a[:65536])


def test_inside_the_reach_sphere(course):
    points, _ = course.sample_workspace(100_000)
    shoulder = np.array([0, 0, course.d1])
    reach = np.sqrt((course.a2 + course.a3) ** 2 + course.d4**2) + course.d5 + course.d6
    assert np.linalg.norm(points - shoulder, axis=-1).max() <= reach
    # docs/kinematics.md §1: roughly a sphere of Ø2600 mm around the base
    assert np.linalg.norm(points - shoulder, axis=-1).max() == pytest.approx(1.3, abs=0.1)


def test_uniform_joint_angles(course):
    _, _, q = course.sample_workspace(200_000, seed=1, return_joints=True)
    counts, _ = np.histogram(q[:, 2], bins=10, range=(-np.pi, np.pi))
    assert counts.min() > 0.9 * 20_000 and counts.max() < 1.1 * 20_000


def test_lowest_points_is_the_lowest_of_every_body_point_moved_in_full(course):
    from ur10core.workspace import lowest_points

    rng = np.random.default_rng(3)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    frames = course.frames(q)  # (50, 7, 4, 4)
    points = rng.normal(scale=0.1, size=(7, 12, 3))
    lowest = lowest_points(frames, points)
    moved = np.einsum("nlij,lpj->nlpi", frames[..., :3, :3], points) + frames[:, :, None, :3, 3]
    flat = moved.reshape(50, -1, 3)
    expected = flat[np.arange(50), np.argmin(flat[..., 2], axis=1)]
    np.testing.assert_allclose(lowest, expected, atol=1e-12)
    np.testing.assert_allclose(lowest_points(frames[7], points), expected[7], atol=1e-12)  # one arm
    with pytest.raises(ValueError, match="body_points"):
        lowest_points(frames, points[:6])
    # along another vertical (the desktop arm's y up): the point least far along it
    up = np.array([0.6, 0.8, 0.0])
    expected = flat[np.arange(50), np.argmin(flat @ up, axis=1)]
    np.testing.assert_allclose(lowest_points(frames, points, up), expected, atol=1e-12)


SECTIONED = [name for name in Arm.PRESETS if name != "planar_elbow"]  # (its tool moves in one horizontal plane)


@pytest.mark.parametrize("name", SECTIONED)
def test_a_horizontal_section_is_sampled_in_its_plane_on_every_arm(name):
    """At five heights across what the tool reaches: each point is where FK puts the tool at its joints, within the
    limits, exactly at the height above the arm's floor (the desktop arm's along its y), with its manipulability."""
    arm = Arm.preset(name)
    up = np.asarray(arm.up)
    lowest, highest = arm.tool_heights
    for height in np.linspace(lowest, highest, 7)[1:-1]:
        points, manipulability, q = arm.sample_horizontal_section(height, 3000, seed=1, return_joints=True)
        assert len(points) == 3000, height
        np.testing.assert_allclose(arm.fk(q)[:, :3, 3], points, atol=1e-9)
        assert (points @ up + arm.base_height == height).all()
        assert arm.within_limits(q).all()
        np.testing.assert_allclose(manipulability, arm.manipulability(q), rtol=1e-12, atol=1e-15)
    again, _ = arm.sample_horizontal_section(height, 3000, seed=1)
    np.testing.assert_array_equal(points, again)


def test_the_desktop_arm_section_holds_its_closed_form_height():
    """docs/kinematics.md §8.6: the tool is l1 s3 − l5 s2 above the shoulder, which stands 1.5 m above the floor."""
    arm = Arm.preset("three_dof")
    _, _, q = arm.sample_horizontal_section(1.2, 2000, seed=3, return_joints=True)
    height = arm.forearm * np.sin(q[:, 2]) - arm.upper_arm * np.sin(q[:, 1]) + 1.5
    np.testing.assert_allclose(height, 1.2, atol=1e-12)


@pytest.mark.parametrize("name", SECTIONED)
def test_a_horizontal_section_covers_what_a_slab_of_the_cloud_covers(name):
    """Every point of a big cloud within a thin slab about the plane has a point of the section (the app's 40 000)
    near it, and the section holds far more points than the slab: sampled in the plane, it misses no part of it."""
    arm = Arm.preset(name)
    lowest, highest = arm.tool_heights
    height = lowest + 0.4 * (highest - lowest)
    cloud, _ = arm.sample_workspace(200_000, seed=2)
    standing = cloud @ arm.upright.T  # (z up: the desktop arm's y)
    slab = standing[np.abs(standing[:, 2] + arm.base_height - height) < 0.002 * arm.reach_bound]
    section, _ = arm.sample_horizontal_section(height, 40_000, seed=2)
    assert 20 < len(slab) < len(section)
    # the section's points in a grid of cells 1.5 % of the reach wide: a slab point's cell or one beside it holds one
    cell = 0.015 * arm.reach_bound
    filled = {tuple(c) for c in np.floor((section @ arm.upright.T)[:, :2] / cell).astype(int)}
    near = [any((i + di, j + dj) in filled for di in (-1, 0, 1) for dj in (-1, 0, 1))
            for i, j in np.floor(slab[:, :2] / cell).astype(int)]
    assert all(near), slab[~np.array(near)][:5]


def test_the_ur10s_section_is_a_ring_as_wide_as_the_slab():
    """The UR10's top view: the same ring of radii as the points of a big cloud within 5 mm of the plane, every
    radius in between filled."""
    course = Arm.preset("course")
    cloud, _ = course.sample_workspace(1_000_000, seed=2)
    slab = cloud[np.abs(cloud[:, 2] - 0.6) < 0.005]
    section, _ = course.sample_horizontal_section(0.6, 20000, seed=2)
    r_slab, r_section = np.hypot(*slab[:, :2].T), np.hypot(*section[:, :2].T)
    assert len(slab) < 5000 < len(section)
    assert abs(r_slab.min() - r_section.min()) < 0.03 and abs(r_slab.max() - r_section.max()) < 0.03
    bins = np.linspace(r_slab.min(), r_slab.max(), 30)
    slab_hist, _ = np.histogram(r_slab, bins)
    section_hist, _ = np.histogram(r_section, bins)
    assert (section_hist[slab_hist > 5] > 0).all()


@pytest.mark.parametrize("name", Arm.PRESETS)
def test_the_tool_heights_are_those_of_the_cloud(name):
    """The heights the tool reaches among 20 000 draws: within 2 % of its reach of a bigger cloud's extremes, and on
    the UR family within 1 % of its exact reach up and down, d1 ± (a2 + a3 + √(d5² + d6²)) (docs/kinematics.md §3:
    the upper arm and forearm vertical, d5 and d6 turned by θ4 to point up or down together); one height on the
    planar elbow."""
    arm = Arm.preset(name)
    lowest, highest = arm.tool_heights
    cloud, _ = arm.sample_workspace(200_000, seed=5)
    heights = cloud @ np.asarray(arm.up) + arm.base_height
    assert abs(lowest - heights.min()) < 0.02 * arm.reach_bound and abs(highest - heights.max()) < 0.02 * arm.reach_bound
    assert (highest - lowest < 1e-9) == (name == "planar_elbow")
    if name in Arm.UR_PRESETS:
        stretched = arm.a2 + arm.a3 + np.hypot(arm.d5, arm.d6)
        assert arm.d1 - stretched <= lowest < arm.d1 - stretched + 0.01 * stretched
        assert arm.d1 + stretched - 0.01 * stretched < highest <= arm.d1 + stretched
        # reached exactly there: θ2 = 90° (down: −90°), θ3 = 0, θ5 = 90°,
        # θ2 + θ3 + θ4 = atan2(d6, d5) (down: + 180°)
        for up, turn in ((1.0, 0.0), (-1.0, np.pi)):
            q = np.array([0.0, up * np.pi / 2, 0.0, np.arctan2(arm.d6, arm.d5) + turn - up * np.pi / 2, np.pi / 2, 0.0])
            assert arm.fk(q)[2, 3] == pytest.approx(arm.d1 + up * stretched, abs=1e-12)


def test_a_section_nobody_reaches_is_refused(course):
    with pytest.raises(ValueError, match="outside the workspace"):
        course.sample_horizontal_section(2.0, 10)
    with pytest.raises(ValueError, match="height must be one finite number"):
        course.sample_horizontal_section(float("nan"), 10)
    with pytest.raises(ValueError, match="positive integer"):
        course.sample_horizontal_section(0.5, 0)
    with pytest.raises(ValueError, match="height must be one finite number"):
        course.sample_horizontal_section([0.5, 0.6], 10)
    with pytest.raises(ValueError, match="no tool position found at that height"):  # on reach_bound, beyond its top
        course.sample_horizontal_section(1.6, 10)
    with pytest.raises(ValueError, match="a tool that does not move up and down"):
        Arm.preset("planar_elbow").sample_horizontal_section(0.0, 10)
    with pytest.raises(ValueError, match="no tool position found"):  # the SCARA's stroke ends 10 mm higher
        Arm.preset("scara").sample_horizontal_section(0.167, 10)


def test_a_typed_arm_has_a_horizontal_section_too():
    """A typed table's (numerical IK, no closed form of anything): its shoulder joint solved for the height."""
    typed = Arm.from_dh([(0.0, np.pi / 2, 0.3, 0), (0.4, 0, 0, 0), (0.3, 0, 0, 0)], joint_types="RRR")
    points, _, q = typed.sample_horizontal_section(0.5, 500, seed=0, return_joints=True)
    np.testing.assert_allclose(typed.fk(q)[:, :3, 3], points, atol=1e-12)
    assert (points[:, 2] == 0.5).all() and np.ptp(np.hypot(points[:, 0], points[:, 1])) > 0.2


# ---------------------------------------------------------------- the branch-count map

@pytest.mark.parametrize("plane", MAP_PLANES)
def test_branch_count_map_counts_what_urs_own_solver_finds(plane):
    """Every cell's count equals the number of solutions ur-analytic-ik (test-only, UR's numbers) returns.

    The map runs our IK on the ur10 preset; the reference is asked cell by cell, through
    the controller's convention (docs/kinematics.md §6), on a coarse grid.
    """
    ur_analytic_ik = urs_own_solver()
    arm = Arm.preset("ur10")
    rng = np.random.default_rng(7)
    for _ in range(3):
        target = arm.fk(rng.uniform(-np.pi, np.pi, 6))
        reach = branch_count_map(arm, target, plane, resolution=31)
        points = reach.points().reshape(-1, 3)
        for k, point in enumerate(points):
            pose = target.copy()
            pose[:3, 3] = point
            theirs = len(ur_analytic_ik.ur10.inverse_kinematics(np.ascontiguousarray(flange_to_controller(pose))))
            assert reach.counts.ravel()[k] == theirs, f"cell {k} at {point.round(3)}: ours {reach.counts.ravel()[k]}, theirs {theirs}"
        assert {0, 8} <= set(reach.counts.ravel().tolist()) <= {0, 2, 4, 6, 8}


def test_branch_count_map_lies_in_a_plane_through_the_target(course):
    target = course.fk(np.radians([30, 45, 26, 50, 60, 80]))
    for plane in MAP_PLANES:
        reach = branch_count_map(course, target, plane, resolution=20)
        np.testing.assert_allclose([reach.u @ reach.u, reach.v @ reach.v, reach.u @ reach.v], [1, 1, 0], atol=1e-12)
        normal = np.cross(reach.u, reach.v)
        points = reach.points()
        np.testing.assert_allclose((points - target[:3, 3]) @ normal, 0.0, atol=1e-12)  # the target's plane
        assert points.shape == (20, 20, 3) and reach.counts.shape == (20, 20)
        assert (points[0, 0] - points[-1, 0]) @ reach.v > 0 and (points[0, -1] - points[0, 0]) @ reach.u > 0  # image order
    vertical = branch_count_map(course, target, "vertical", resolution=20)
    assert abs(np.cross(vertical.u, vertical.v) @ [0, 0, 1]) < 1e-12  # holds the base axis
    np.testing.assert_allclose(vertical.centre, [0, 0, course.d1])
    horizontal = branch_count_map(course, target, "horizontal", resolution=20)
    np.testing.assert_allclose(horizontal.points()[..., 2], target[2, 3])


def test_branch_count_map_shows_the_hole_about_the_base_axis(course):
    """Where the wrist centre P5 would be closer than d4 to the base axis, no branch reaches (§4.2)."""
    target = np.eye(4)  # the tool pointing up: P5 sits right under the flange
    target[:3, 3] = (0.5, 0.0, 0.6)
    reach = branch_count_map(course, target, "horizontal", resolution=41)
    points = reach.points()
    near_axis = np.hypot(points[..., 0], points[..., 1]) < 0.9 * course.d4
    assert near_axis.any() and (reach.counts[near_axis] == 0).all()
    assert (reach.counts == 8).any()


@pytest.mark.parametrize("bad, message", [
    ({"plane": "diagonal"}, "plane"),
    ({"resolution": 1}, "resolution"),
    ({"resolution": 10_001}, "resolution"),
    ({"resolution": 20.0}, "resolution"),
    ({"target": np.eye(3)}, "target"),
    ({"target": np.tile(np.eye(4), (2, 1, 1))}, "target"),
])
def test_branch_count_map_refuses_bad_arguments(course, bad, message):
    arguments = {"target": np.eye(4), "plane": "vertical", "resolution": 10, **bad}
    with pytest.raises(ValueError, match=message):
        branch_count_map(course, **arguments)


# ---------------------------------------------------------------- the translucent hull

def test_revolved_boundary_finds_the_hole_of_radius_d4_minus_d6(course):
    """The flange is at least d4 − d6 from the base axis (P5 is at least d4 from it, and the flange d6 from P5)."""
    points, _ = course.sample_workspace(200_000, seed=0)
    heights, inner, outer = revolved_boundary(points, bins=24)
    assert len(heights) == 24 and heights[0] == points[:, 2].min() and heights[-1] == points[:, 2].max()
    np.testing.assert_allclose(inner, course.d4 - course.d6, atol=4e-3)
    assert (inner >= course.d4 - course.d6 - 1e-9).all()  # samples never beat the bound
    rho = np.hypot(points[:, 0], points[:, 1])
    assert outer.max() == rho.max() and outer.max() <= course.a2 + course.a3 + np.hypot(course.d5, course.d4) + 1e-9


@pytest.mark.parametrize("bad, message", [
    ({"points": np.zeros((0, 3))}, "empty"),
    ({"points": np.zeros((5, 2))}, "shape"),
    ({"points": [[0, 0, 1.0], [1, 0, 1.0]]}, "height"),
    ({"bins": 1}, "bins"),
    ({"points": [[0, 0, np.nan], [1, 0, 1.0]]}, "finite"),
])
def test_revolved_boundary_refuses_bad_arguments(bad, message):
    arguments = {"points": [[1.0, 0, 0], [0, 2.0, 1.0]], "bins": 4, **bad}
    with pytest.raises(ValueError, match=message):
        revolved_boundary(**arguments)


def test_the_hull_mesh_is_closed_and_turned_from_the_profile(course):
    import trimesh
    from ur10teach.features.workspace import revolved_mesh

    heights, inner, outer = revolved_boundary(course.sample_workspace(50_000, seed=1)[0], bins=30)
    vertices, faces = revolved_mesh(heights, inner, outer, segments=40)
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0  # closed, facing out
    # the volume between two surfaces of revolution, by the frustum rule slice by slice
    slices = np.diff(heights)
    shell = lambda r: np.pi / 3 * (slices * (r[:-1] ** 2 + r[:-1] * r[1:] + r[1:] ** 2)).sum()  # noqa: E731
    polygon = 40 / (2 * np.pi) * np.sin(2 * np.pi / 40)  # a 40-gon's area over its circle's
    assert mesh.volume == pytest.approx(polygon * (shell(outer) - shell(inner)), rel=1e-6)


@pytest.mark.parametrize("name, turn", [("ur10", None), ("kr210", None), ("planar_elbow", None), ("cylindrical", None),
                                        ("scara", (-105, 105)), ("stanford", (-170, 170)), ("elbow", (-170, 170)),
                                        ("three_dof", (-90, 90))])  # (about its vertical, its y)
def test_base_turn_is_the_first_joints_range_short_of_a_full_turn(name, turn):
    got = base_turn(Arm.preset(name))
    assert got == turn if turn is None else np.allclose(np.degrees(got), turn)


@pytest.mark.parametrize("rows, convention, types, why", [
    ([(0, 0, 0.3, 0), (0.4, 0, 0, 0)], "standard", "PR", "slides"),
    ([(0, np.pi / 2, 0.3, 0), (0.4, 0, 0, 0)], "modified", "RR", "not the base's z axis"),  # α0 tilts joint 1
    ([(0.2, 0, 0.3, 0), (0.4, 0, 0, 0)], "modified", "RR", "not the base's z axis"),  # a0 moves it off the origin
])
def test_base_turn_says_why_a_first_joint_does_not_turn_the_arm_about_z(rows, convention, types, why):
    with pytest.raises(ValueError, match=why):
        base_turn(Arm.from_dh(rows, convention, types))


@pytest.mark.parametrize("name", ["scara", "three_dof"])
def test_a_side_view_keeps_only_what_theta1_turns_into_its_plane(name):
    """The SCARA's θ1 turns ±105°: each point kept in its side view is the tool of the same joints with θ1 alone
    changed within its range (found by a search over θ1, not by the angle sum), and each point dropped is not.
    (The side view used every point, and showed a full ring behind the SCARA where it reaches nothing.) The desktop
    arm's θ1 turns ±90° about its y, its vertical: its points are cut in its upright frame (``Arm.upright``)."""
    arm = Arm.preset(name)
    low, high = base_turn(arm)
    points, _, q = arm.sample_workspace(3000, seed=2, return_joints=True)
    upright = arm.upright
    azimuth = 0.3
    section = vertical_section(points @ upright.T, azimuth) @ upright  # back in the arm's base frame
    kept = turnable_into(points @ upright.T, azimuth, q[:, 0], (low, high))
    assert 0.2 < kept.mean() < 0.95
    np.testing.assert_allclose(section @ arm.up, points @ arm.up)  # turned about the vertical: no point rises or falls
    grid = np.linspace(low, low + 2 * np.pi, 14401)  # a full turn, 0.025° apart: 1.2 mm at the desktop arm's 2.6 m reach
    for k in list(np.flatnonzero(kept)[:60]) + list(np.flatnonzero(~kept)[:60]):
        turned = np.tile(q[k], (len(grid), 1))
        turned[:, 0] = grid
        gaps = np.linalg.norm(arm.fk(turned)[:, :3, 3] - section[k], axis=1)
        needed = grid[gaps.argmin()]  # the θ1 that puts the tool there
        assert gaps.min() < 1e-3 * arm.reach_bound
        assert needed <= high + 1e-3 if kept[k] else needed > high - 1e-3, (k, np.degrees(needed))
    assert turnable_into(points @ upright.T, azimuth, q[:, 0], (-np.pi, np.pi)).all()  # a full turn keeps every point


@pytest.mark.parametrize("name, lacks", [
    ("ur10", set()), ("kr210", set()), ("cylindrical_wrist", set()),
    ("scara", {"translucent"}), ("stanford", {"translucent"}), ("elbow", {"translucent"}),
    ("planar_elbow", {"horizontal", "translucent"}), ("three_dof", {"translucent"}),
])
def test_each_arm_offers_the_sections_true_of_it_and_says_why_not_the_others(name, lacks):
    """A hull turns the outline a full turn about z: offered where θ1 turns a full turn and the workspace has height
    (the SCARA's turns ±105°, and its hull took in a ring behind it that it never reaches)."""
    from ur10teach.features.workspace import SECTIONS, sections_of

    offered, why = sections_of(Arm.preset(name))
    assert {s.split(" ")[0] for s in SECTIONS if s not in offered} == lacks
    assert bool(why) == bool(lacks)
    if "translucent" in lacks:
        assert ("no height to bound" if name == "planar_elbow" else "only, so it would take in places") in why
    if "horizontal" in lacks:  # (until 2026-12-07 every arm but the UR family's lacked it: it had the closed form)
        assert "No horizontal section: the tool stays 0 mm above the floor, so the whole cloud is already its top view" in why


@pytest.mark.parametrize("convention, rows, types, limits", [
    # (a mm, α°, d mm, θ°) and the limits typed (° or mm; None for the default), as a student's editor takes them
    ("standard", [(500, 90, 100, 90), (-300, 180, 0, 90), (0, 45, -300, 0), (0, -90, -300, 0), (500, 45, 0, -90),
                  (500, 0, 100, 0)], "RRPRRR", [None, None, (100, 110), (-180, 320), None, None]),
    ("modified", [(1000, 180, 500, -90), (500, 0, 0, 0), (0, 90, 1000, 30), (-300, 0, 1000, 30), (500, 45, 0, 30)],
     "RRRRP", [None, (-90, -80), None, None, None]),
])
def test_a_typed_arm_has_a_section_at_either_end_of_its_heights(convention, rows, types, limits):
    """Within 10 mm of the lowest and highest of ``tool_heights`` (the slider's ends), a typed arm's section was refused
    as "no tool position found" (a fuzz of typed tables found 7 in 600, 2026-12-07): of 256 trial draws none reached
    so near the top, and the joint then chosen to move the tool onto the plane was θ1, which turns about the
    vertical and never moves the height. The trial now grows until some draws reach the plane."""
    kinds = {"R": np.radians, "P": lambda v: np.asarray(v) / 1000.0}
    limits = [None if typed is None else kinds[kind](typed) for typed, kind in zip(limits, types)]
    defaults = Arm.from_dh([(0, 0, 0, 0)] * len(types), joint_types=types).limits
    arm = Arm.from_dh([(a / 1000, np.radians(alpha), d / 1000, np.radians(theta)) for a, alpha, d, theta in rows],
                      convention, types, limits=[d if t is None else t for t, d in zip(limits, defaults)])
    low, high = arm.tool_heights
    for seed in (3, 5, 7, 8):  # (seeds on which the old trial failed, of the first ten)
        for height in (low + 0.005, high - 0.005):
            points, _, q = arm.sample_horizontal_section(height, 2000, seed=seed, return_joints=True)
            np.testing.assert_allclose(arm.fk(q)[:, :3, 3], points, atol=1e-9)
            np.testing.assert_allclose(heights_above_floor(arm, points), height, atol=1e-12)


def test_a_typed_arm_whose_first_joint_slides_has_no_side_view_nor_hull_and_is_told_why():
    from ur10teach.features.workspace import SECTIONS, sections_of

    offered, why = sections_of(Arm.from_dh([(0, 0, 0.3, 0), (0.4, 0, 0, 0)], "standard", "PR"))
    assert offered == (SECTIONS[0], SECTIONS[2], SECTIONS[3])  # (its sliding joint moves the tool up and down)
    assert "No side view and no hull: they turn the cloud about the base axis by θ1, and its first joint slides" in why


def test_joints_are_sampled_over_each_joints_whole_range():
    """The KR210's A3 turns from -210° to 65°: its cloud (and every search drawing joints) lost the poses beyond
    -180°, where the range was cut to one turn; a typed joint limited to 250°..340° could not be sampled at all."""
    kr210 = Arm.preset("kr210")
    a3 = np.degrees(kr210.sample_joints(20_000, seed=1)[:, 2])
    assert a3.min() >= -210 and a3.max() <= 65 and a3.min() < -209 and a3.max() > 64
    assert (a3 < -180).mean() == pytest.approx(30 / 275, abs=0.01)  # uniform over the whole range
    typed = Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR", limits=np.radians([[250, 340], [-90, 90]]))
    q = np.degrees(typed.sample_joints(2000, seed=1)[:, 0])
    assert q.min() >= 250 and q.max() <= 340 and np.ptp(q) > 85
    assert typed.sample_workspace(200)[0].shape == (200, 3)
    whole_turns = np.degrees(Arm.preset("ur10").sample_joints(2000, seed=1))  # ±360°: one turn, every pose once
    assert whole_turns.min() >= -180 and whole_turns.max() <= 180 and np.ptp(whole_turns, axis=0).min() > 350
    lopsided = Arm.from_dh([(0.5, 0, 0, 0)], joint_types="R", limits=np.radians([[0, 400]]))  # a turn, within its limits
    q = np.degrees(lopsided.sample_joints(2000, seed=1)[:, 0])
    assert q.min() >= 0 and q.max() <= 360 and np.ptp(q) > 350
