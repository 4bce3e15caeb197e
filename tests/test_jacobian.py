"""The Jacobian against finite differences of FK; det J against its three factors."""

import numpy as np
import pytest

from .conftest import random_joints

pytestmark = pytest.mark.core


def _finite_difference_jacobian(arm, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central differences: linear part dp/dq, angular part from (dR/dq) R^T = [w]x."""
    J = np.empty(q.shape[:-1] + (6, 6))
    R = arm.fk(q)[..., :3, :3]
    for i in range(6):
        step = np.zeros(6)
        step[i] = h
        plus, minus = arm.fk(q + step), arm.fk(q - step)
        J[..., :3, i] = (plus[..., :3, 3] - minus[..., :3, 3]) / (2 * h)
        W = (plus[..., :3, :3] - minus[..., :3, :3]) / (2 * h) @ np.swapaxes(R, -1, -2)
        J[..., 3:, i] = np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], axis=-1)
    return J


def test_jacobian_matches_finite_differences(any_arm):
    q = random_joints(1000, seed=20)
    np.testing.assert_allclose(any_arm.jacobian(q), _finite_difference_jacobian(any_arm, q), atol=1e-8)


def test_one_pose_jacobian(course):
    q = np.radians([30, 45, 26, 50, 60, 80])
    np.testing.assert_allclose(course.jacobian(q), _finite_difference_jacobian(course, q), atol=1e-8)


def test_det_equals_product_of_factors(any_arm):
    q = random_joints(5000, seed=21)
    det = np.linalg.det(any_arm.jacobian(q))
    np.testing.assert_allclose(any_arm.det_jacobian(q), det, rtol=1e-9, atol=1e-14)
    factors = any_arm.singularity_factors(q)
    np.testing.assert_allclose(any_arm.a2 * any_arm.a3 * factors.prod(axis=-1), det, rtol=1e-9, atol=1e-14)


def test_factors_vanish_at_the_course_singular_poses(course):
    zero = course.singularity_factors(np.zeros(6))
    assert zero[1] == 0 and zero[2] == 0 and zero[0] == pytest.approx(course.a2 + course.a3)
    stretched = course.singularity_factors(np.radians([45, 90, 0, -90, 0, 60]))
    np.testing.assert_allclose(stretched, 0, atol=1e-15)
    assert np.linalg.matrix_rank(course.jacobian(np.radians([45, 90, 0, -90, 0, 60])), tol=1e-9) < 6


def test_shoulder_factor_is_the_wrist2_reach_along_x1(course):
    # docs/kinematics.md §5: singular when P5 is at horizontal distance d4 from the base axis;
    # |P5_xy|² = A² + d4² with A the shoulder factor.
    q = random_joints(500, seed=22)
    g = course.singularity_geometry(q)
    A = course.singularity_factors(q)[:, 0]
    np.testing.assert_allclose(np.hypot(g.p5[:, 0], g.p5[:, 1]) ** 2, A**2 + course.d4**2, atol=1e-13)
    np.testing.assert_allclose(np.einsum("ni,ni->n", g.arm_forward, g.p5), A, atol=1e-14)


def test_singularity_geometry(course):
    q = random_joints(500, seed=23)
    g = course.singularity_geometry(q)
    F = course.frames(q)
    # wrist: axis 4 · axis 6 = c5, parallel exactly when s5 = 0
    np.testing.assert_allclose(np.einsum("ni,ni->n", g.axis4, g.axis6), np.cos(q[:, 4]), atol=1e-14)
    # elbow: the frame-4 origin's in-plane distance from the circle centre is the 2R reach
    r = np.linalg.norm(g.p4 - g.elbow_center, axis=-1)
    expected = np.sqrt(course.a2**2 + course.a3**2 + 2 * course.a2 * course.a3 * np.cos(q[:, 2]))
    np.testing.assert_allclose(r, expected, atol=1e-14)
    np.testing.assert_allclose(g.flange, F[:, 6, :3, 3])
    assert g.cylinder_radius == course.d4
    assert g.elbow_radii == pytest.approx((course.a2 + course.a3, abs(course.a2 - course.a3)))
    stretched = course.singularity_geometry(np.zeros(6))
    assert np.linalg.norm(stretched.p4 - stretched.elbow_center) == pytest.approx(course.a2 + course.a3)
    # p4 lies in the plane through elbow_center spanned by x1 and z
    normal = np.cross(g.arm_forward, [0, 0, 1])
    np.testing.assert_allclose(np.einsum("ni,ni->n", g.p4 - g.elbow_center, normal), 0, atol=1e-14)


def test_one_pose_factors_equal_batch_factors(course):
    q = random_joints(200, seed=24)
    batch = course.singularity_factors(q)
    for k in range(len(q)):
        np.testing.assert_allclose(course.singularity_factors(q[k]), batch[k], atol=1e-15)


def test_shoulder_singular_configuration_turns_only_theta4_when_it_can(course):
    """Upper arm and forearm pointing nearly up: |a2 c2 + a3 c23| ≤ d5, so θ4 alone reaches the singularity."""
    rng = np.random.default_rng(25)
    q = random_joints(300, seed=25)
    q[:, 1] = np.pi / 2 + rng.uniform(-0.05, 0.05, len(q))
    q[:, 2] = rng.uniform(-0.05, 0.05, len(q))
    assert (np.abs(course.a2 * np.cos(q[:, 1]) + course.a3 * np.cos(q[:, 1] + q[:, 2])) <= course.d5).all()
    moved = course.singular_configuration("shoulder", q)
    np.testing.assert_array_equal(np.delete(moved, 3, axis=-1), np.delete(q, 3, axis=-1))
    np.testing.assert_allclose(course.singularity_factors(moved)[:, 0], 0, atol=1e-14)
    # of the two θ234 with that sine, the one nearer the current θ234
    s234 = (course.a2 * np.cos(q[:, 1]) + course.a3 * np.cos(q[:, 1] + q[:, 2])) / course.d5
    current = q[:, 1:4].sum(-1)
    chosen = moved[:, 1:4].sum(-1)
    other = np.pi - chosen
    gap = lambda a, b: np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi)  # noqa: E731
    assert (gap(chosen, current) <= gap(other, current) + 1e-12).all()
    np.testing.assert_allclose(np.sin(chosen), s234, atol=1e-14)
    assert (np.abs(moved[:, 3]) <= 2 * np.pi).all()


def test_shoulder_singular_configuration_turns_theta2_when_it_must(course):
    q = np.radians([30, 45, 26, 50, 60, 80])  # |a2 c2 + a3 c23| = 0.62 m > d5
    moved = course.singular_configuration("shoulder", q)
    assert moved[1] != q[1]
    assert course.a2 * np.cos(moved[1]) + course.a3 * np.cos(moved[1] + moved[2]) == pytest.approx(0, abs=1e-14)
    assert np.sin(moved[1:4].sum()) == pytest.approx(0, abs=1e-14)
    np.testing.assert_array_equal(moved[[0, 2, 4, 5]], q[[0, 2, 4, 5]])
