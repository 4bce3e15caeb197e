"""The course's convention against UR's own (docs/kinematics.md §6) via the ur-analytic-ik package."""

import numpy as np
import pytest

from ur10core import FLANGE_TURN, Arm, flange_from_controller, flange_to_controller, from_controller, to_controller

from .conftest import random_joints, urs_own_solver, wrapped_difference

pytestmark = pytest.mark.core
ur_analytic_ik = urs_own_solver()

REFERENCES = {"ur10": ur_analytic_ik.ur10, "ur10e": ur_analytic_ik.ur10e}


@pytest.mark.parametrize("preset", REFERENCES)
def test_fk_matches_official_numbers_through_to_controller(preset):
    arm, reference = Arm.preset(preset), REFERENCES[preset]
    q = random_joints(1000, seed=30)
    ours = arm.fk(q) @ FLANGE_TURN
    for k, q_controller in enumerate(to_controller(q)):
        np.testing.assert_allclose(reference.forward_kinematics(*q_controller), ours[k], atol=1e-12)


@pytest.mark.parametrize("preset", REFERENCES)
def test_ik_branches_match_official_solver(preset):
    arm, reference = Arm.preset(preset), REFERENCES[preset]
    q = random_joints(1000, seed=31)
    T = arm.fk(q)
    ours = arm.ik(T)
    for k in range(len(q)):
        theirs = reference.inverse_kinematics(np.ascontiguousarray(flange_to_controller(T[k])))
        theirs = from_controller(np.array(theirs).reshape(-1, 6))
        valid = ours.q[k][ours.valid[k]]
        assert len(theirs) == len(valid)
        for solution in theirs:  # each of theirs is one of ours
            assert wrapped_difference(valid, solution).max(axis=-1).min() < 1e-8


def test_zero_pose_maps_to_the_pendant_angles():
    np.testing.assert_allclose(np.degrees(to_controller(np.zeros(6))), [0, 180, 0, 0, 0, 0])
    np.testing.assert_allclose(from_controller(to_controller(np.radians([10, -20, 30, 40, 50, 60]))), np.radians([10, -20, 30, 40, 50, 60]))


def test_shoulder_stays_within_the_joint_range():
    q = np.radians([0, 300, 0, 0, 0, 0])
    assert np.degrees(to_controller(q))[1] == pytest.approx(120)  # 480° is 120° one turn back
    assert np.degrees(from_controller(np.radians([0, -300, 0, 0, 0, 0])))[1] == pytest.approx(-120)
    q = random_joints(200, seed=32) * 2  # within ±2π
    assert (np.abs(to_controller(q)) <= 2 * np.pi).all()
    np.testing.assert_allclose(wrapped_difference(from_controller(to_controller(q)), q), 0, atol=1e-12)


def test_flange_turn_is_its_own_inverse(course):
    T = course.fk(random_joints(10, seed=33))
    np.testing.assert_allclose(flange_from_controller(flange_to_controller(T)), T)
