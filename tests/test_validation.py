"""Bad input: a ValueError that names what is wrong; the core keeps working afterwards."""

import warnings

import numpy as np
import pytest

from ur10core import Arm, from_controller, to_controller
from ur10core.paths import joint_interpolation

from .conftest import random_joints

pytestmark = pytest.mark.core


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
        ("zero", r"q must be real numbers, got text"),
        ([[0] * 6, [0, 0, 0, 0, 0, np.nan]], r"index \(1, 5\)"),
    ],
)
def test_bad_joint_vectors(course, method, q, message):
    with pytest.raises(ValueError, match=message):
        getattr(course, method)(q)


def test_a_one_joint_arm_asks_for_one_joint_value():
    arm = Arm.from_dh([(0.5, 0, 0, 0)], joint_types="R")
    with pytest.raises(ValueError, match=r"q must have shape \(\.\.\., 1\) \(1 joint value, R\), got shape \(2,\)"):
        arm.fk([0.0, 0.0])
    with pytest.raises(ValueError, match=r"q_start must be 1 joint value, got shape \(2,\)"):
        joint_interpolation(arm, [0.0, 0.0], [0.1])


def test_bad_pose_shape_and_values(course, pose):
    with pytest.raises(ValueError, match=r"T must have shape \(\.\.\., 4, 4\).*got shape \(3, 3\)"):
        course.ik(np.eye(3))
    with pytest.raises(ValueError, match=r"got shape \(4,\)"):
        course.ik(np.ones(4))
    bad = pose.copy()
    bad[1, 3] = np.nan
    with pytest.raises(ValueError, match=r"T contains a non-finite value \(nan at index \(1, 3\)\)"):
        course.ik(bad)
    with pytest.raises(ValueError, match="T must be real numbers"):
        course.ik([["a"] * 4] * 4)


def test_bottom_row(course, pose):
    bad = pose.copy()
    bad[3] = [0, 0, 1, 1]
    with pytest.raises(ValueError, match=r"bottom row \[0\.0, 0\.0, 1\.0, 1\.0\], expected \[0, 0, 0, 1\]"):
        course.ik(bad)


def test_the_bottom_row_is_held_to_a_nanometre_scale(course, pose):
    """Rounding (a product of transforms in floats) is accepted; anything a typing slip could make is refused."""
    for k in range(4):
        nearly, off = pose.copy(), pose.copy()
        nearly[3, k] += 5e-10
        off[3, k] += 5e-9
        assert course.ik(nearly).valid.any()
        with pytest.raises(ValueError, match="bottom row"):
            course.ik(off)


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
        Arm.ur_family(d1=0.1, a2=-0.6, a3=0.5, d4=0.1, d5=0.1, d6=0.1)
    with pytest.raises(ValueError, match="Arm.d4 must be a finite number of metres"):
        Arm.ur_family(d1=0.1, a2=0.6, a3=0.5, d4=float("nan"), d5=0.1, d6=0.1)


@pytest.mark.parametrize("n", [0, -5, 2.5, "100", True])
def test_bad_workspace_size(course, n):
    with pytest.raises(ValueError, match="n must be a positive integer"):
        course.sample_workspace(n)


@pytest.mark.parametrize("name", ["course", "scara"])
def test_a_sample_too_large_for_memory_is_refused_before_anything_is_allocated(name):
    arm = Arm.preset(name)
    for sample in (arm.sample_workspace, arm.sample_joints):
        with pytest.raises(ValueError, match="n must be at most 10,000,000 samples, got 1,000,000,000,000"):
            sample(10**12)


def test_bad_controller_input():
    with pytest.raises(ValueError, match=r"q_controller must have shape"):
        from_controller([1, 2, 3])
    with pytest.raises(ValueError, match="q contains a non-finite"):
        to_controller([0, 0, 0, 0, 0, np.nan])


@pytest.mark.parametrize(
    "q, message",
    [
        ([10**400] * 6, r"must be real numbers"),  # an int too large for a float: was OverflowError
        (np.array([10**400] * 6, dtype=object), r"must be real numbers"),
        (np.full(6, 1j), r"must be real numbers, got complex numbers"),  # was: imaginary part dropped
        ([0, 0, 0, 0, 0, 1 + 0j], r"got complex numbers"),
        (np.zeros(6, "datetime64[s]"), r"got dates"),  # was: read as numbers
        (np.zeros(6, "timedelta64[s]"), r"got time spans"),
        (np.ma.masked_array(np.zeros(6), mask=[0, 0, 1, 0, 0, 0]), r"not a masked array"),  # was: mask ignored
        (["0"] * 6, r"got text"),
        ([True] * 6, r"got true/false values"),
    ],
)
def test_values_that_are_not_plainly_real_numbers(course, pose, q, message):
    for call in (course.fk, course.jacobian, course.singularity_factors, lambda v: course.ik(pose, hint=v)):
        with pytest.raises(ValueError, match=message):
            call(q)


def test_poses_that_are_not_plainly_real_numbers(course, pose):
    for call in (course.ik, lambda T: course.pose_error(np.zeros(6), T)):  # pose_error: was TypeError
        with pytest.raises(ValueError, match=r"T must be real numbers, got complex numbers"):
            call(pose + 0j)
        with pytest.raises(ValueError, match=r"T must be real numbers"):
            call({"a": 1})
    with pytest.raises(ValueError, match=r"T must be a plain array of numbers, not a masked array"):
        course.ik(np.ma.masked_array(pose))
    with pytest.raises(ValueError, match=r"T must be real numbers"):
        course.ik(np.full((4, 4), 10**400, dtype=object))


@pytest.mark.parametrize("prefer", [3.7, True, 8, -2, "3", np.array([0.5, 1.0]), np.array([1, 9])])
def test_bad_preferred_slot(course, pose, prefer):
    """prefer=3.7 used to mean slot 3 on the one-pose path and an IndexError on the batch path."""
    one, batch = course.ik(pose), course.ik(np.stack([pose, pose]))
    with pytest.raises(ValueError, match=r"prefer must be a slot number 0\.\.7"):
        one.nearest(np.zeros(6), prefer=prefer)
    with pytest.raises(ValueError, match=r"prefer must be a slot number 0\.\.7"):
        batch.nearest(np.zeros((2, 6)), prefer=prefer)


def test_preferred_slot_must_broadcast(course, pose):
    batch = course.ik(np.stack([pose, pose]))
    with pytest.raises(ValueError, match=r"prefer of shape \(3,\) does not broadcast"):
        batch.nearest(np.zeros((2, 6)), prefer=np.array([1, 2, 3]))
    assert batch.nearest(np.zeros((2, 6)), prefer=-1).slot.shape == (2,)  # −1: no preference


@pytest.mark.parametrize("limit", [3.0, -1.0, -np.inf, np.nan, "2pi", True])
def test_bad_joint_limit(course, pose, limit):
    with pytest.raises(ValueError, match="joint_limit must be"):
        course.ik(pose).nearest(np.zeros(6), joint_limit=limit)


@pytest.mark.parametrize("batch", [False, True])
def test_nearest_stays_within_the_joint_limit_from_far_away(course, batch):
    """A current q1 of 20 rad used to give 15.62 rad, beyond ±360°."""
    q = np.array([0.5, -1.0, 1.2, 2.0, 0.8, -0.3])
    current = np.array([20.0, -1.0, 1.2, 2.0, 0.8, -55.0])
    solution = course.ik(course.fk(np.stack([q, q]) if batch else q))
    branch = solution.nearest(np.stack([current, current]) if batch else current)
    assert (np.abs(branch.q) <= 2 * np.pi).all()
    chosen = np.reshape(branch.q, (-1, 6))[0]
    slot = int(np.reshape(branch.slot, -1)[0])
    raw = np.reshape(solution.q, (-1, 8, 6))[0, slot]
    np.testing.assert_allclose(np.remainder(chosen - raw + np.pi, 2 * np.pi) - np.pi, 0, atol=1e-12)  # a whole turn
    assert chosen[0] + 2 * np.pi > 2 * np.pi  # q1 (current far above the range): its highest turn within it
    assert chosen[5] - 2 * np.pi < -2 * np.pi  # q6 (current far below): its lowest turn within it


def test_equal_upper_arm_and_forearm_are_refused():
    with pytest.raises(ValueError, match="Arm.a2 and Arm.a3 must differ"):
        Arm.ur_family(d1=0.1, a2=0.5, a3=0.5, d4=0.1, d5=0.1, d6=0.1)
    Arm.ur_family(d1=0.1, a2=0.5, a3=0.5 + 1e-12, d4=0.1, d5=0.1, d6=0.1)


@pytest.mark.parametrize("seed", [-1, 2.5, "7", True, None])
def test_bad_workspace_seed(course, seed):
    with pytest.raises(ValueError, match="seed must be a non-negative integer"):
        course.sample_workspace(10, seed=seed)


# --------------------------------------------------------------------------- an issue's fuzz: the last edge cases


@pytest.mark.parametrize("name", ["course", "kr210", "scara"])
def test_a_current_joint_value_beyond_reason_is_refused_not_answered_with_nan(name):
    arm = Arm.preset(name)
    q = np.zeros(arm.n_joints)
    sol = arm.ik(arm.fk(q))
    with pytest.raises(ValueError, match="q_current has .* joint values beyond"):
        sol.nearest(np.full(arm.n_joints, 1e300))  # one pose
    with pytest.raises(ValueError, match="q_current has .* joint values beyond"):
        arm.ik(arm.fk(np.zeros((2, arm.n_joints)))).nearest(np.full((2, arm.n_joints), -1e12))  # a batch
    assert np.isfinite(sol.nearest(np.full(arm.n_joints, 1e6)).q).all()  # a million radians is still an answer


@pytest.mark.parametrize("kind, joint", [("elbow", 2), ("wrist", 4)])
@pytest.mark.parametrize("start", [6.2, -6.2, 0.3])
def test_a_singular_configuration_turns_the_joint_to_the_nearest_whole_turn(kind, joint, start):
    arm = Arm.preset("ur10")
    q = np.array([0.1, -1.0, 0.5, -0.4, 0.7, 0.2])
    q[joint] = start
    moved = arm.singular_configuration(kind, q)
    assert moved[joint] == pytest.approx(2 * np.pi * round(start / (2 * np.pi)), abs=1e-15)


@pytest.mark.parametrize("name", ["scara", "planar_elbow", "three_dof", "cylindrical", "stanford", "kr210"])
def test_a_target_at_1e300_is_too_far_without_an_overflow_warning(name):
    arm = Arm.preset(name)
    T = np.eye(4)
    T[:3, 3] = 1e300
    if name == "scara":  # its tool points straight down
        T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sol = arm.ik(T)
    assert not sol.within_limits.any()  # the prismatic arms solve it, with a stroke of 1e300 m: far beyond their range


def test_a_typed_table_refuses_absurd_lengths_and_answers_far_targets_at_once():
    with pytest.raises(ValueError, match=r"DH row 2: d must be a length within ±1e\+06 m"):
        Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 1e300, 0)])
    arm = Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR")
    T = np.tile(np.eye(4), (2, 1, 1))
    T[0, :3, 3], T[1, :3, 3] = 1e300, (0.6, 0.2, 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sol = arm.ik(T)
    assert not sol.valid[0].any() and sol.valid[1].any()
    assert "reaches 900.0 mm at most" in sol.unreachable_reason((0,))
