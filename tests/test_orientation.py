"""The five orientation readouts against independent constructions."""

import numpy as np
import pytest

from ur10core.orientation import (
    angle_axis,
    from_frame,
    in_frame,
    quaternion,
    rotation_from_angle_axis,
    rotation_from_quaternion,
    rotation_from_xyz_fixed,
    rotation_from_zyx_euler,
    rotation_from_zyz_euler,
    xyz_fixed,
    zyx_euler,
    zyz_euler,
)

pytestmark = pytest.mark.core


def _rx(a):
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def _ry(a):
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def _rz(a):
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


@pytest.fixture
def angles():
    rng = np.random.default_rng(40)
    a = rng.uniform(-np.pi, np.pi, (500, 3))
    a[:, 1] /= 2  # β in (−π/2, π/2)
    return a


def test_zyx_euler_round_trip_and_construction(angles):
    R = rotation_from_zyx_euler(angles)
    for k in range(20):
        alpha, beta, gamma = angles[k]
        np.testing.assert_allclose(R[k], _rz(alpha) @ _ry(beta) @ _rx(gamma), atol=1e-15)
    np.testing.assert_allclose(zyx_euler(R), angles, atol=1e-12)


def test_xyz_fixed_equals_zyx_euler_reversed(angles):
    # rotate about fixed X, then fixed Y, then fixed Z (Craig 2.71)
    R = rotation_from_xyz_fixed(angles[:, ::-1])
    np.testing.assert_allclose(R, rotation_from_zyx_euler(angles), atol=1e-15)
    np.testing.assert_allclose(xyz_fixed(R), angles[:, ::-1], atol=1e-12)


def test_gimbal_lock():
    for beta in (np.pi / 2, -np.pi / 2):
        R = rotation_from_zyx_euler([0.4, beta, 0.9])
        alpha, b, gamma = zyx_euler(R)
        assert alpha == 0 and b == pytest.approx(beta)
        np.testing.assert_allclose(rotation_from_zyx_euler([alpha, b, gamma]), R, atol=1e-12)


def test_zyz_euler_round_trip_construction_and_spatialmath(angles):
    """Z-Y-Z Euler angles, as the Stanford report reads T6: against the product written out by hand and
    spatialmath's ``tr2eul`` (roboticstoolbox's, test-only), θ in (0, π)."""
    from spatialmath.base import tr2eul

    zyz = angles.copy()
    zyz[:, 1] = np.abs(zyz[:, 1]) * 2  # θ in (0, π)
    by_hand = np.array([_rz(phi) @ _ry(theta) @ _rz(psi) for phi, theta, psi in zyz])
    np.testing.assert_allclose(rotation_from_zyz_euler(zyz), by_hand, atol=1e-14)
    np.testing.assert_allclose(zyz_euler(by_hand), zyz, atol=1e-9)
    np.testing.assert_allclose(zyz_euler(by_hand), [tr2eul(R) for R in by_hand], atol=1e-9)
    # the report's own formulas, read off n, o, a
    n, o, a = by_hand[:, :, 0], by_hand[:, :, 1], by_hand[:, :, 2]
    phi = np.arctan2(a[:, 1], a[:, 0])
    c, s = np.cos(phi), np.sin(phi)
    np.testing.assert_allclose(zyz_euler(by_hand)[:, 2], np.arctan2(-s * n[:, 0] + c * n[:, 1], -s * o[:, 0] + c * o[:, 1]))
    # and the report's other solution, φ + 180°: the same rotation, as tr2eul's flip reads it
    flipped = zyz_euler(by_hand, flip=True)
    np.testing.assert_allclose(flipped, [tr2eul(R, flip=True) for R in by_hand], atol=1e-9)
    np.testing.assert_allclose(rotation_from_zyz_euler(flipped), by_hand, atol=1e-12)
    np.testing.assert_allclose(flipped[:, 1], -zyz[:, 1], atol=1e-9)


@pytest.mark.parametrize("theta", [0.0, np.pi])
def test_zyz_euler_with_the_approach_along_z_keeps_phi_zero(theta):
    R = rotation_from_zyz_euler([0.4, theta, 0.9])
    phi, t, psi = zyz_euler(R)
    assert phi == 0 and t == pytest.approx(theta)
    np.testing.assert_array_equal(zyz_euler(R, flip=True), (phi, t, psi))
    np.testing.assert_allclose(rotation_from_zyz_euler([phi, t, psi]), R, atol=1e-12)


def test_quaternion(angles):
    R = rotation_from_zyx_euler(angles)
    q = quaternion(R)
    assert (q[:, 0] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1, atol=1e-15)
    np.testing.assert_allclose(rotation_from_quaternion(q), R, atol=1e-14)
    # independent: the half-angle form of a rotation about z
    np.testing.assert_allclose(quaternion(_rz(0.6)), [np.cos(0.3), 0, 0, np.sin(0.3)], atol=1e-15)


def test_angle_axis(angles):
    R = rotation_from_zyx_euler(angles)
    theta, axis = angle_axis(R)
    assert ((theta >= 0) & (theta <= np.pi)).all()
    np.testing.assert_allclose(rotation_from_angle_axis(theta, axis), R, atol=1e-14)
    # Craig: cos θ = (trace − 1)/2
    np.testing.assert_allclose(np.cos(theta), (np.trace(R, axis1=-2, axis2=-1) - 1) / 2, atol=1e-14)


@pytest.mark.parametrize("theta", [0.0, 1e-9, np.pi - 1e-9, np.pi])
def test_angle_axis_edges(theta):
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    R = rotation_from_angle_axis(theta, axis)
    got_theta, got_axis = angle_axis(R)
    assert got_theta == pytest.approx(theta, abs=1e-8)
    np.testing.assert_allclose(rotation_from_angle_axis(got_theta, got_axis), R, atol=1e-12)
    if theta == 0:
        np.testing.assert_array_equal(got_axis, [0, 0, 1])


def test_course_arbitrary_pose_readouts(course):
    R = course.fk(np.radians([30, 45, 26, 50, 60, 80]))[:3, :3]
    alpha, beta, gamma = zyx_euler(R)
    np.testing.assert_allclose(_rz(alpha) @ _ry(beta) @ _rx(gamma), R, atol=1e-14)
    w, x, y, z = quaternion(R)
    # Craig (2.91): ε4 = ½ sqrt(1 + r11 + r22 + r33)
    assert w == pytest.approx(0.5 * np.sqrt(1 + np.trace(R)))


def test_refuses_non_rotations():
    with pytest.raises(ValueError, match="not orthonormal"):
        zyx_euler(np.eye(3) * 1.1)
    with pytest.raises(ValueError, match="reflection"):
        quaternion(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3, 3\)"):
        angle_axis(np.eye(4))


def test_points_from_a_frame_are_its_homogeneous_transform_and_in_frame_undoes_it():
    rng = np.random.default_rng(3)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = _rz(0.7) @ _ry(-1.1) @ _rx(2.3), (0.4, -0.2, 1.5)
    points = rng.normal(size=(5, 2, 3))  # segments, as the app draws them
    homogeneous = np.concatenate([points, np.ones((5, 2, 1))], axis=-1) @ T.T
    np.testing.assert_allclose(from_frame(T, points), homogeneous[..., :3], atol=1e-15)
    np.testing.assert_allclose(in_frame(T, from_frame(T, points)), points, atol=1e-14)
    with pytest.raises(ValueError, match="points"):
        from_frame(T, [1.0, 2.0])
