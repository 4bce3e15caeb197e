"""Straight tool lines by resolved rates, and joint interpolation (docs/kinematics.md §8.7)."""

from __future__ import annotations

import numpy as np
import pytest

from ur10core import Arm, paths
from ur10core.paths import joint_interpolation, straight_line

pytestmark = pytest.mark.core


def distance_from_line(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    direction = (end - start) / np.linalg.norm(end - start)
    offset = points - start
    return np.linalg.norm(offset - np.outer(offset @ direction, direction), axis=-1)


@pytest.mark.parametrize("name, q_start, q_goal", [
    ("course", [10, -60, 80, -110, 60, 20], [60, -40, 50, -100, 80, -30]),
    ("kr210", [0, 15, -30, 20, 40, 10], [40, 30, -10, -20, 60, 40]),
    ("three_dof", [0, -60, 30], [40, -20, 80]),
    ("scara", [20, 60, 0, 10], [-30, 90, 0, 60]),
])
def test_the_tool_follows_the_straight_line_and_arrives(name, q_start, q_goal):
    arm = Arm.preset(name)
    q_start, q_goal = np.radians(q_start), np.radians(q_goal)
    if name == "scara":
        q_start[2], q_goal[2] = 0.1, 0.2  # the prismatic joint, in metres
    goal = arm.fk(q_goal)
    path = straight_line(arm, q_start, goal, duration=4.0, steps=400)
    start = arm.fk(q_start)[:3, 3]
    np.testing.assert_allclose(path.tool[-1], goal[:3, 3], atol=1e-6)
    if getattr(arm, "task", "pose") != "position":  # and turned as the goal is (a SCARA: its yaw)
        np.testing.assert_allclose(arm.fk(path.q[-1])[:3, :3], goal[:3, :3], atol=1e-6)
    assert distance_from_line(path.tool, start, goal[:3, 3]).max() < 5e-4
    # along the line as the cubic time scaling says: s(t) = 3τ² − 2τ³ of the way at time t
    tau = path.t / path.t[-1]
    progress = (path.tool - start) @ (goal[:3, 3] - start) / np.sum((goal[:3, 3] - start) ** 2)
    np.testing.assert_allclose(progress, 3 * tau**2 - 2 * tau**3, atol=2e-3)
    assert np.abs(path.qdot[-1]).max() < 1e-3 and path.damping.max() == 0.0


def test_joint_interpolation_moves_the_joints_evenly_and_the_tool_on_a_curve():
    arm = Arm.preset("course")
    q_start, q_goal = np.radians([10, -60, 80, -110, 60, 20]), np.radians([60, -40, 50, -100, 80, -30])
    joints = joint_interpolation(arm, q_start, q_goal, duration=4.0, steps=201)
    np.testing.assert_allclose(joints.q[[0, -1]], [q_start, q_goal], atol=1e-15)
    np.testing.assert_allclose(joints.tool, arm.fk(joints.q)[:, :3, 3])
    # q̇ is the derivative of q: central differences
    np.testing.assert_allclose(joints.qdot[1:-1], (joints.q[2:] - joints.q[:-2]) / (2 * (joints.t[1] - joints.t[0])), atol=1e-4)
    line = straight_line(arm, q_start, arm.fk(q_goal), duration=4.0, steps=201)
    ends = arm.fk(q_start)[:3, 3], arm.fk(q_goal)[:3, 3]
    assert distance_from_line(joints.tool, *ends).max() > 0.05 > 100 * distance_from_line(line.tool, *ends).max()


def test_a_line_through_the_wrist_singularity_needs_fast_joints_and_is_damped():
    """From q5 = +20° to −20° the tool's line crosses s5 = 0: the wrist joints would need unbounded
    rates; the damping bounds them (still above the UR10's 180°/s), and says where it acted."""
    arm = Arm.preset("course")
    q_start, q_goal = np.radians([10, -60, 80, -110, 20, 20]), np.radians([10, -60, 80, -110, -20, 20])
    path = straight_line(arm, q_start, arm.fk(q_goal), duration=4.0, steps=400)
    damped = path.damping > 0
    assert damped.any() and not damped[0] and not damped[-1]
    assert np.abs(np.sin(path.q[damped, 4])).max() < 0.05  # only near s5 = 0
    assert np.abs(path.qdot).max() > np.pi  # faster than the wrist's limit
    np.testing.assert_allclose(path.tool[-1], arm.fk(q_goal)[:3, 3], atol=1e-3)


def test_bad_paths_are_refused():
    arm = Arm.preset("course")
    for call, words in ((lambda: straight_line(arm, np.zeros(5), np.eye(4)), "q_start must be 6"),
                        (lambda: straight_line(arm, np.zeros(6), np.eye(3)), "T_goal must be a 4 × 4"),
                        (lambda: joint_interpolation(arm, np.zeros(6), np.zeros(6), duration=-1.0), "duration"),
                        (lambda: joint_interpolation(arm, np.zeros(6), np.zeros(6), steps=1), "steps"),
                        (lambda: joint_interpolation(arm, np.zeros(6), [np.inf] * 6), "q_goal contains a non-finite")):
        with pytest.raises(ValueError, match=words):
            call()


@pytest.mark.core
def test_the_issues_straight_line_is_measured_and_its_unreachable_stretch_named():
    """Issue 30, bug 1: from (−30, 60, 60, 30, 60, 0)° to (30, 45, 26, 50, 60, 80)° the line passes inside
    the shoulder cylinder. The path leaves it by hundreds of millimetres; that is measured, and said."""
    arm = Arm.preset("course")
    start, goal = np.radians([-30, 60, 60, 30, 60, 0]), np.radians([30, 45, 26, 50, 60, 80])
    path = paths.straight_line(arm, start, arm.fk(goal), 4.0, 240)
    # the deviation measured independently: each tool point's distance from the nearest of 2001 points along the
    # segment between the endpoints (not the line through them: with numpy 2.5 the path, chaotic through the
    # cylinder, overshoots the goal along the line and comes back, and the projection on the line fell short)
    p0, p1 = arm.fk(start)[:3, 3], arm.fk(goal)[:3, 3]
    along_segment = p0 + np.linspace(0.0, 1.0, 2001)[:, None] * (p1 - p0)
    nearest = np.linalg.norm(path.tool[:, None, :] - along_segment[None], axis=2).min(axis=1)
    assert paths.line_deviation(path) == pytest.approx(nearest.max(), abs=1e-6)
    assert paths.line_deviation(path) > 0.1
    first, last, why = paths.line_out_of_reach(arm, start, arm.fk(goal))
    assert 0 < first < last < 1 and "shoulder cylinder" in why
    poses = paths.line_poses(arm.fk(start), arm.fk(goal), np.array([first, (first + last) / 2, last]))
    assert not arm.ik(poses).valid.any(axis=1).any()  # each named sample is indeed out of reach
    # a reachable line keeps to it, and says nothing is out of reach
    near = start + np.radians([10, 0, 0, 0, 0, 0])
    assert paths.line_out_of_reach(arm, start, arm.fk(near)) is None
    assert paths.line_deviation(paths.straight_line(arm, start, arm.fk(near))) < 1e-4


@pytest.mark.core
def test_a_path_beyond_a_joints_range_is_named_with_the_joint_and_the_time():
    arm = Arm.preset("scara")
    low, high = arm.limits[1]
    path = paths.joint_interpolation(arm, np.zeros(4), np.zeros(4))
    assert paths.out_of_range(arm, path) == ""
    beyond = paths.Path(path.t, np.where(path.t[:, None] > 2.0, [0.0, high + 0.1, 0.0, 0.0], 0.0),
                        path.qdot, path.tool, path.damping)
    message = paths.out_of_range(arm, beyond)
    assert message.startswith(f"{arm.joint_names[1]} would go beyond its limit of {np.degrees(high):.1f}° at "
                              f"{path.t[path.t > 2.0][0]:.2f} s, up to {np.degrees(high + 0.1):.1f}°")
    # only just beyond: not "up to 157.5°" beside a limit of 157.5°
    barely = paths.Path(path.t, np.tile([0.0, high + 1e-4, 0.0, 0.0], (len(path.t), 1)), path.qdot, path.tool, path.damping)
    assert "by less than 0.1°" in paths.out_of_range(arm, barely)
    low_d3 = arm.limits[2, 0]
    under = paths.Path(path.t, np.where(path.t[:, None] > 1.0, [0.0, 0.0, low_d3 - 0.0123, 0.0], [0.0, 0.0, low_d3, 0.0]),
                       path.qdot, path.tool, path.damping)
    assert f"beyond its limit of {1000 * low_d3:.0f} mm" in paths.out_of_range(arm, under)
    assert f"up to {1000 * (low_d3 - 0.0123):.0f} mm" in paths.out_of_range(arm, under)
