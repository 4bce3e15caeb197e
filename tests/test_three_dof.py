"""The course's 3-DOF desktop arm (docs/kinematics.md §8.6): its equations, its J, and the course's exercises."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur10core import Arm
from ur10core.three_dof import FOREARM, UPPER_ARM, course_path, largest_torque

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
