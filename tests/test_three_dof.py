"""The course's 3-DOF desktop arm (docs/kinematics.md §8.6): its equations, its J, and the course's exercises."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur10core import Arm
from ur10core.specs import largest_torque
from ur10core.three_dof import FOREARM, UPPER_ARM, course_path

pytestmark = pytest.mark.core


def course_position(q: np.ndarray) -> np.ndarray:
    """The course's map, written out as it gives it: p = (c1(l1c3 − l5c2), l1s3 − l5s2, −s1(l1c3 − l5c2))."""
    t1, t2, t3 = q
    return np.array([math.cos(t1) * (FOREARM * math.cos(t3) - UPPER_ARM * math.cos(t2)),
                     FOREARM * math.sin(t3) - UPPER_ARM * math.sin(t2),
                     -math.sin(t1) * (FOREARM * math.cos(t3) - UPPER_ARM * math.cos(t2))])


def test_the_position_map_and_j_omega_are_the_courses():
    arm = Arm.preset("three_dof")
    for q in np.random.default_rng(1).uniform(-math.pi, math.pi, (200, 3)):
        np.testing.assert_allclose(arm.fk(q)[:3, 3], course_position(q), atol=1e-12)
        s1, c1 = math.sin(q[0]), math.cos(q[0])
        np.testing.assert_allclose(arm.jacobian(q)[3:], [[0, s1, 0], [1, 0, 0], [0, c1, 0]], atol=1e-15)


def test_j_is_the_derivative_of_the_pose():
    """J_v by central differences of the course's p; J_ω from Ṙ Rᵀ of the orientation fk reports."""
    arm = Arm.preset("three_dof")
    h = 1e-6
    for q in np.random.default_rng(2).uniform(-math.pi, math.pi, (100, 3)):
        J = arm.jacobian(q)
        for i, e in enumerate(np.eye(3)):
            np.testing.assert_allclose(J[:3, i], (course_position(q + h * e) - course_position(q - h * e)) / (2 * h), atol=1e-8)
            dR = (arm.fk(q + h * e)[:3, :3] - arm.fk(q - h * e)[:3, :3]) / (2 * h)
            S = dR @ arm.fk(q)[:3, :3].T
            np.testing.assert_allclose(J[3:, i], [S[2, 1], S[0, 2], S[1, 0]], atol=1e-8)


def test_det_jv_is_the_product_of_its_two_factors():
    """det J_v from numpy against −l1 l5 · reach · sin(θ2 − θ3), and each factor at a pose the course names."""
    arm = Arm.preset("three_dof")
    q = np.random.default_rng(4).uniform(-math.pi, math.pi, (500, 3))
    reach, fold = np.moveaxis(arm.singularity_factors(q), -1, 0)
    np.testing.assert_allclose(np.linalg.det(arm.jacobian(q)[:, :3]), -FOREARM * UPPER_ARM * reach * fold, atol=1e-12)
    np.testing.assert_allclose(reach, np.hypot(arm.fk(q)[:, 0, 3], arm.fk(q)[:, 2, 3]) * np.sign(reach), atol=1e-12)
    stretched = np.radians([10.0, 200.0, 20.0])  # the upper arm points along the forearm: one straight line
    assert arm.singularity_factors(stretched)[1] == pytest.approx(0.0, abs=1e-12)
    assert np.linalg.matrix_rank(arm.jacobian(stretched)[:3], tol=1e-9) == 2


def test_tool_velocities_along_the_courses_path():
    """The course plots J q̇ along its path and checks it against a simulation: here against the time
    derivative of the tool's position and orientation along the same path."""
    arm = Arm.preset("three_dof")
    t = np.linspace(0.0, 2 * math.pi, 241)
    q, qdot = course_path(t)
    np.testing.assert_allclose(q[0], [0, 0, 3 * math.pi / 4])
    np.testing.assert_allclose(q[:, 2], 3 * math.pi / 4 + math.pi / 8 * np.sin(t))
    twist = arm.tool_twist(q, qdot)
    h = 1e-6
    ahead, behind = arm.fk(course_path(t + h)[0]), arm.fk(course_path(t - h)[0])
    np.testing.assert_allclose(twist[:, :3], (ahead[:, :3, 3] - behind[:, :3, 3]) / (2 * h), atol=1e-7)
    S = (ahead[:, :3, :3] - behind[:, :3, :3]) / (2 * h) @ np.swapaxes(arm.fk(q)[:, :3, :3], -1, -2)
    np.testing.assert_allclose(twist[:, 3:], np.stack([S[:, 2, 1], S[:, 0, 2], S[:, 1, 0]], -1), atol=1e-7)
    # the angular velocity is the course's ω = (s1 θ̇2, θ̇1, c1 θ̇2)
    np.testing.assert_allclose(twist[:, 4], qdot[:, 0])


def test_the_largest_torque_for_a_tool_force():
    """The grid's worst pose: its torques are J_vᵀF there, no random pose in the ranges needs more,
    and for a downward force it has both links level. The parallelogram decouples them: joint 2
    holds F·l5·cos θ2 and joint 3 F·l1·cos θ3, each largest with its own link level."""
    arm = Arm.preset("three_dof")
    force = np.array([0.0, -10.0, 0.0])  # 10 N down (y is up)
    worst = largest_torque(arm, force)
    np.testing.assert_allclose(worst.torques, arm.static_torques(worst.q, force), atol=1e-12)
    low, high = arm.limits.T
    sampled = np.linalg.norm(arm.static_torques(np.random.default_rng(3).uniform(low, high, (20000, 3)), force), axis=-1)
    assert sampled.max() <= worst.norm + 1e-9
    assert worst.torques[0] == pytest.approx(0.0, abs=1e-9)  # the base's axis is vertical
    assert worst.norm == pytest.approx(10.0 * math.hypot(UPPER_ARM, FOREARM), rel=1e-12)
    assert math.cos(worst.q[1]) == pytest.approx(1.0) and abs(math.cos(worst.q[2])) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="force must be three numbers"):
        largest_torque(arm, [1.0, 2.0])


def _elbow_above(arm, q) -> np.ndarray:
    """Independently of ik: is the elbow above the straight line from the shoulder to the tool?

    In the arm's vertical plane, with s the horizontal distance toward the tool and h the height,
    the side of the line (t_s, t_h) the elbow (e_s, e_h) is on is the sign of t_s e_h − t_h e_s.
    """
    frames = arm.frames(q)
    elbow, tool = frames[..., 1, :3, 3], frames[..., 2, :3, 3]
    toward = tool[..., [0, 2]] / np.linalg.norm(tool[..., [0, 2]], axis=-1, keepdims=True)
    tool_s, elbow_s = np.linalg.norm(tool[..., [0, 2]], axis=-1), np.einsum("...i,...i->...", elbow[..., [0, 2]], toward)
    return tool_s * elbow[..., 1] - tool[..., 1] * elbow_s > 0


def test_ik_finds_every_generating_pose_in_its_labelled_slot():
    """FK∘IK on 5 000 random joint vectors: the generating one is found, in the slot its geometry names
    (the tool in front or behind, the elbow above or below), and every valid slot reaches the position."""
    arm = Arm.preset("three_dof")
    rng = np.random.default_rng(7)
    q = rng.uniform(-np.pi, np.pi, (5000, 3))
    T = arm.fk(q)
    sol = arm.ik(T)
    assert sol.q.shape == (5000, 4, 3) and sol.valid.all()
    reached = arm.fk(np.where(sol.valid[..., None], sol.q, 0.0))[..., :3, 3]
    assert np.abs(reached - T[:, None, :3, 3]).max() < 1e-9
    planar = arm.forearm * np.cos(q[:, 2]) - arm.upper_arm * np.cos(q[:, 1])
    slot = 2 * (planar > 0) + (~_elbow_above(arm, q))
    found = sol.q[np.arange(5000), slot]
    difference = np.abs(np.angle(np.exp(1j * (found - q))))
    assert difference.max() < 1e-7, np.argmax(difference.max(axis=1))
    inside = ((q >= arm.limits[:, 0]) & (q <= arm.limits[:, 1])).all(axis=1)
    assert sol.within_limits[np.arange(5000), slot][inside].all()


def test_ik_near_its_singularities_and_out_of_reach():
    arm = Arm.preset("three_dof")
    # links in one line, stretched (θ3 = θ2 + π) and folded (θ3 = θ2): the boundary of the workspace
    for q in (np.radians([10.0, -40.0, 140.0]), np.radians([10.0, -40.0, -40.0])):
        for nudge in (0.0, 1e-9, -1e-9):
            target = arm.fk(q + [0.0, 0.0, nudge])
            sol = arm.ik(target)
            assert sol.valid.any(), "a reachable position was called unreachable"
            assert np.abs(arm.fk(sol.q[sol.valid])[:, :3, 3] - target[:3, 3]).max() < 1e-6
    # the tool on the vertical axis: θ1 is free, the hint's is kept, and the slots say singular
    q = np.array([0.3, -np.pi / 2, np.arccos(0.0)])  # reach l1 c3 − l5 c2 = 0
    sol = arm.ik(arm.fk(q), hint=q)
    assert sol.valid.any() and sol.singular[sol.valid].all()
    assert np.isclose(sol.q[sol.valid][0, 0] % np.pi, 0.3 % np.pi)
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.5, 0.0)
    sol = arm.ik(far)
    assert not sol.valid.any() and "reach at most 2630.0 mm" in sol.unreachable_reason()
    near = np.eye(4)
    near[:3, 3] = (0.0, 0.05, 0.0)
    assert "no closer than 70.0 mm" in arm.ik(near).unreachable_reason()
    with pytest.raises(ValueError):
        arm.ik(np.eye(3))
