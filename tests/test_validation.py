"""Bad input: a ValueError that names what is wrong; the core keeps working afterwards."""

import numpy as np
import pytest

from ur10core import Arm, from_controller, to_controller

from .conftest import random_joints


@pytest.fixture
def pose(course):
    return course.fk(np.radians([30, 45, 26, 50, 60, 80]))


@pytest.mark.parametrize("method", ["fk", "frames", "jacobian", "singularity_factors", "det_jacobian", "singularity_geometry"])
@pytest.mark.parametrize(
    "q, message",
    [
        ([0, 0, 0, np.nan, 0, 0], r"q contains a non-finite value \(nan at index \(3,\)\)"),
        ([0, 0, 0, 0, np.inf, 0], r"non-finite value \(inf at index \(4,\)\)"),
        ([0, 0, 0, 0, 0], r"q must have shape \(\.\.\., 6\) \(six joint angles\), got shape \(5,\)"),
        (np.zeros((3, 7)), r"got shape \(3, 7\)"),
        (0.0, r"got shape \(\)"),
        ("zero", r"q must be numeric"),
        ([[0] * 6, [0, 0, 0, 0, 0, np.nan]], r"index \(1, 5\)"),
    ],
)
def test_bad_joint_vectors(course, method, q, message):
    with pytest.raises(ValueError, match=message):
        getattr(course, method)(q)


def test_bad_pose_shape_and_values(course, pose):
    with pytest.raises(ValueError, match=r"T must have shape \(\.\.\., 4, 4\).*got shape \(3, 3\)"):
        course.ik(np.eye(3))
    with pytest.raises(ValueError, match=r"got shape \(4,\)"):
        course.ik(np.ones(4))
    bad = pose.copy()
    bad[1, 3] = np.nan
    with pytest.raises(ValueError, match=r"T contains a non-finite value \(nan at index \(1, 3\)\)"):
        course.ik(bad)
    with pytest.raises(ValueError, match="T must be numeric"):
        course.ik([["a"] * 4] * 4)


def test_bottom_row(course, pose):
    bad = pose.copy()
    bad[3] = [0, 0, 1, 1]
    with pytest.raises(ValueError, match=r"bottom row \[0\.0, 0\.0, 1\.0, 1\.0\], expected \[0, 0, 0, 1\]"):
        course.ik(bad)


def test_not_orthonormal(course, pose):
    bad = pose.copy()
    bad[:3, :3] *= 1.01
    with pytest.raises(ValueError, match=r"rotation part is not orthonormal \(max \|R\^T R - I\| = 0\.0201 > 1e-06\)"):
        course.ik(bad)
    sheared = pose.copy()
    sheared[0, 1] += 1e-5
    with pytest.raises(ValueError, match="not orthonormal"):
        course.ik(sheared)
    # within the tolerance is accepted
    nearly = pose.copy()
    nearly[0, 1] += 1e-8
    assert course.ik(nearly).valid.any()


def test_reflection(course, pose):
    bad = pose.copy()
    bad[:3, 2] *= -1
    with pytest.raises(ValueError, match=r"determinant -1; a proper rotation has \+1 \(this one is a reflection\)"):
        course.ik(bad)


def test_batch_names_the_offending_pose(course):
    T = course.fk(random_joints(6, seed=50)).reshape(2, 3, 4, 4)
    T[1, 2, :3, :3] *= 2
    with pytest.raises(ValueError, match=r"T\[1, 2\]: rotation part is not orthonormal"):
        course.ik(T)
    T = course.fk(random_joints(40000, seed=50))  # the threaded path
    T[33333, 3, 0] = 0.5
    with pytest.raises(ValueError, match=r"T\[33333\] has bottom row"):
        course.ik(T)


def test_bad_hint(course, pose):
    with pytest.raises(ValueError, match=r"hint must have shape \(\.\.\., 6\)"):
        course.ik(pose, hint=[0, 0])
    with pytest.raises(ValueError, match="hint contains a non-finite value"):
        course.ik(pose, hint=[0, 0, 0, 0, 0, np.nan])
    with pytest.raises(ValueError, match=r"hint of shape \(3, 6\) does not broadcast against poses of shape \(2, 4, 4\)"):
        course.ik(np.stack([pose, pose]), hint=np.zeros((3, 6)))


def test_unreachable_is_not_an_error(course):
    T = np.eye(4)
    T[:3, 3] = (10, 10, 10)
    assert not course.ik(T).valid.any()


def test_core_keeps_working_after_errors(course, pose):
    for bad in (np.full((4, 4), np.nan), np.eye(3), np.diag([1.0, 1.0, -1.0, 1.0])):
        with pytest.raises(ValueError):
            course.ik(bad)
    assert course.ik(pose).valid.all()


def test_bad_arm_and_preset():
    with pytest.raises(ValueError, match="unknown preset 'ur5'; choose one of course, ur10, ur10e"):
        Arm.preset("ur5")
    with pytest.raises(ValueError, match="Arm.a2 must be positive"):
        Arm(d1=0.1, a2=-0.6, a3=0.5, d4=0.1, d5=0.1, d6=0.1)
    with pytest.raises(ValueError, match="Arm.d4 must be a finite number of metres"):
        Arm(d1=0.1, a2=0.6, a3=0.5, d4=float("nan"), d5=0.1, d6=0.1)


@pytest.mark.parametrize("n", [0, -5, 2.5, "100", True])
def test_bad_workspace_size(course, n):
    with pytest.raises(ValueError, match="n must be a positive integer"):
        course.sample_workspace(n)


def test_bad_controller_input():
    with pytest.raises(ValueError, match=r"q_controller must have shape"):
        from_controller([1, 2, 3])
    with pytest.raises(ValueError, match="q contains a non-finite"):
        to_controller([0, 0, 0, 0, 0, np.nan])
