"""Forward kinematics against the course's worked examples and an independent construction."""

import numpy as np
import pytest

from ur10core import Arm

from .conftest import random_joints

pytestmark = pytest.mark.core


def test_zero_state_matches_course_example(course):
    # docs/kinematics.md §3: all joints 0°.
    T = course.fk(np.zeros(6))
    np.testing.assert_allclose(T[:3, :3], [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-15)
    np.testing.assert_allclose(T[:3, 3] * 1000, [1184.5, -256.1, 243.7], atol=1e-9)
    np.testing.assert_array_equal(T[3], [0, 0, 0, 1])


def test_stretched_pose_matches_course_example(course):
    T = course.fk(np.radians([45, 90, 0, -90, 0, 60]))
    np.testing.assert_allclose(T[:3, 3] * 1000, [181.090, -181.090, 1428.2], atol=5e-4)
    np.testing.assert_allclose(T[:3, 0], [0.35355, 0.35355, 0.86603], atol=5e-6)


def test_arbitrary_pose_matches_course_example(course):
    T = course.fk(np.radians([30, 45, 26, 50, 60, 80]))
    expected_R = [
        [-0.84497, 0.51716, -0.13628],
        [-0.31420, -0.68623, -0.65603],
        [-0.43279, -0.51151, 0.74233],
    ]
    np.testing.assert_allclose(T[:3, :3], expected_R, atol=5e-6)
    np.testing.assert_allclose(T[:3, 3] * 1000, [519.984, 57.726, 1110.697], atol=5e-4)


def test_closed_form_equals_product_of_dh_link_transforms(any_arm):
    # frames() multiplies the six Craig link transforms; fk() is the §3 closed form.
    q = random_joints(2000, seed=1)
    np.testing.assert_allclose(any_arm.fk(q), any_arm.frames(q)[:, 6], atol=1e-14)


def test_one_pose_fast_path_equals_batch_path(any_arm):
    q = random_joints(500, seed=2)
    batch = any_arm.fk(q)
    for k in range(len(q)):
        np.testing.assert_allclose(any_arm.fk(q[k]), batch[k], atol=1e-15)
        np.testing.assert_allclose(any_arm.fk(q[k].tolist()), batch[k], atol=1e-15)


@pytest.mark.parametrize("shape", [(), (3,), (2, 4), (2, 1, 3)])
def test_any_leading_batch_shape(course, shape):
    q = random_joints(int(np.prod(shape, dtype=int)), seed=3).reshape(shape + (6,))
    assert course.fk(q).shape == shape + (4, 4)
    assert course.frames(q).shape == shape + (7, 4, 4)
    assert course.jacobian(q).shape == shape + (6, 6)
    assert course.singularity_factors(q).shape == shape + (3,)


def test_frames_are_proper_transforms_with_base_at_identity(course):
    F = course.frames(random_joints(200, seed=4))
    np.testing.assert_array_equal(F[:, 0], np.broadcast_to(np.eye(4), (200, 4, 4)))
    R = F[..., :3, :3]
    np.testing.assert_allclose(np.swapaxes(R, -1, -2) @ R, np.broadcast_to(np.eye(3), R.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)


def test_dh_table_link_lengths(course):
    # the frame origins realise the DH lengths: |o3 - o2| = a2, and so on
    F = course.frames(random_joints(50, seed=5))
    o = F[..., :3, 3]
    np.testing.assert_allclose(o[:, 1], [[0, 0, course.d1]] * 50, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(o[:, 3] - o[:, 2], axis=-1), course.a2, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(o[:, 6] - o[:, 5], axis=-1), course.d6, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(o[:, 5] - o[:, 4], axis=-1), course.d5, atol=1e-14)


def test_presets_hold_the_published_numbers():
    ur10 = Arm.preset("ur10")
    assert (ur10.d1, ur10.a2, ur10.a3, ur10.d4, ur10.d5, ur10.d6) == (0.1273, 0.612, 0.5723, 0.163941, 0.1157, 0.0922)
    ur10e = Arm.preset("ur10e")
    assert (ur10e.d1, ur10e.a2, ur10e.a3, ur10e.d4, ur10e.d5, ur10e.d6) == (0.1807, 0.6127, 0.57155, 0.17415, 0.11985, 0.11655)
    course = Arm.preset("course")
    assert course.dh_lengths == (0.128, 0.6129, 0.5716, 0.1639, 0.1157, 0.0922)


def test_compiled_frames_equal_the_product_of_link_transforms(any_arm):
    q = random_joints(300, seed=6)
    links = any_arm.link_transforms(q)
    product = np.broadcast_to(np.eye(4), (300, 4, 4)).copy()
    expected = [product.copy()]
    for i in range(6):
        product = product @ links[:, i]
        expected.append(product.copy())
    np.testing.assert_allclose(any_arm.frames(q), np.stack(expected, axis=1), atol=1e-14)
