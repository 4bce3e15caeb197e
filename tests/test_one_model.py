"""One model of a serial arm: every preset and a typed table are one class, with one IK result type."""

from __future__ import annotations

import itertools
import pickle

import numpy as np
import pytest

from ur10core import Arm, IKSolution
from ur10core.branches import INSIDE_OFFSET, NOT_FOUND, ORIENTATION, OUT_OF_PLANE, REACHED, TOO_CLOSE, TOO_FAR, Branch

pytestmark = pytest.mark.core

TYPED = ("typed RR", lambda: Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR", name="typed"))
EVERY_ARM = [(name, lambda name=name: Arm.preset(name)) for name in Arm.PRESETS] + [TYPED]
CODES = {REACHED, INSIDE_OFFSET, TOO_FAR, TOO_CLOSE, ORIENTATION, OUT_OF_PLANE, NOT_FOUND}


def test_every_preset_is_named():
    assert Arm.PRESETS == ("course", "ur10", "ur10e", "kr210", "stanford", "elbow", "scara", "planar_elbow",
                           "cylindrical", "cylindrical_wrist", "three_dof")


@pytest.mark.parametrize("name, make", EVERY_ARM, ids=[name for name, _ in EVERY_ARM])
def test_every_arm_is_one_class_and_its_ik_one_result_type(name, make):
    arm = make()
    assert type(arm) is Arm
    rng = np.random.default_rng(7)
    low, high = arm.limits[:, 0], arm.limits[:, 1]
    q = rng.uniform(np.maximum(low, -3.0), np.minimum(high, 3.0), (25, arm.n_joints))
    T = arm.fk(q)
    batch = arm.ik(T, hint=q)
    assert type(batch) is IKSolution
    k = len(batch.labels)
    assert batch.q.shape == (25, k, arm.n_joints) and batch.valid.shape == batch.within_limits.shape == (25, k)
    assert batch.singular.shape == batch.failure.shape == batch.detail.shape == (25, k)
    assert set(np.unique(batch.failure)) <= CODES
    assert not (batch.within_limits & ~batch.valid).any()
    assert batch.reachable.all()  # a reachable pose is never reported unreachable
    branch = batch.nearest(q)
    assert type(branch) is Branch and branch.q.shape == (25, arm.n_joints) and (branch.slot >= 0).all()
    assert arm.pose_error(branch.q, T).max() < 1e-9
    # the branch the arm is on comes back, turned next to its joints (numerical search: the one it found)
    if not arm.numerical:
        np.testing.assert_allclose(branch.q, q, atol=1e-7)
    # one pose: the same answer as the batch's
    one = arm.ik(T[3], hint=q[3])
    assert type(one) is IKSolution and int(one.nearest(q[3]).slot) == int(branch.slot[3])


@pytest.mark.parametrize("name, make", EVERY_ARM, ids=[name for name, _ in EVERY_ARM])
def test_a_pose_with_a_joint_on_its_limit_is_reached_within_the_limits(name, make):
    """The desktop arm with its forearm level (θ3 = 0, its lower limit) was reached "only beyond a limit": IK gave
    θ3 = −0.0 or −1e-16, a rounding below it. So did θ3 = 180° and the cylindrical arm's d2 = 0."""
    arm = make()
    poses = arm.sample_joints(6, seed=3)
    for pose, joint, end in itertools.product(poses, range(arm.n_joints), (0, 1)):
        q = pose.copy()
        q[joint] = arm.limits[joint, end]
        for hint in (None, q):
            solution = arm.ik(arm.fk(q), hint=hint)
            assert solution.within_limits.any(), (joint, end, hint)
            branch = solution.nearest(q, within_limits=True)
            assert int(branch.slot) >= 0 and arm.pose_error(branch.q, arm.fk(q)) < 1e-9
            inside = (arm.limits[:, 0] <= branch.q) & (branch.q <= arm.limits[:, 1])
            assert inside.all(), (joint, end, branch.q)  # a slider takes it: on the limit, not a rounding beyond


@pytest.mark.parametrize("name, make", EVERY_ARM, ids=[name for name, _ in EVERY_ARM])
def test_every_arm_says_why_a_pose_out_of_reach_is_out_of_reach(name, make):
    arm = make()
    T = arm.fk(arm.specs.home)
    T[:3, 3] *= 20.0  # far beyond any of these arms
    solution = arm.ik(T)
    assert not solution.within_limits.any()
    if "P" in arm.joint_types:  # a slide without an end reaches it: only the stroke's limit says no
        return
    assert not solution.reachable and int(solution.nearest(arm.specs.home).slot) == -1
    assert np.isnan(solution.nearest(arm.specs.home).q).all()
    assert solution.unreachable_reason()  # words, with the numbers
    assert set(np.unique(solution.failure)) <= CODES - {REACHED}


@pytest.mark.parametrize("name, make", EVERY_ARM, ids=[name for name, _ in EVERY_ARM])
def test_arms_compare_by_what_they_are_and_travel_to_a_worker_process(name, make):
    arm, again = make(), make()
    assert arm == again and hash(arm) == hash(again)
    copy = pickle.loads(pickle.dumps(arm))
    assert copy == arm
    np.testing.assert_array_equal(copy.fk(arm.specs.home), arm.fk(arm.specs.home))
    assert Arm.preset("course") != Arm.preset("ur10")


#: Two 5 m slides up one axis and a 1 m link: its tool gets 10.05 m from the base, beyond a preset's 10 m room.
LONG_TYPED = ("typed with long slides", lambda: Arm.from_dh(
    [(0.0, 0.0, 0.0, 0.0, "P"), (0.0, 0.0, 0.0, 0.0, "P"), (1.0, 0.0, 0.0, 0.0, "R")],
    limits=[(0.0, 5.0), (0.0, 5.0), (-np.pi, np.pi)], name="long"))


@pytest.mark.parametrize("name, make", [*EVERY_ARM, LONG_TYPED], ids=[name for name, _ in [*EVERY_ARM, LONG_TYPED]])
def test_the_reach_bound_is_never_passed_and_is_reached_where_the_links_line_up(name, make):
    """``reach_bound`` against the tool's distance over 100,000 random joints and every corner of the joint limits:
    never beyond it; and close to it where the chain can line its links up (the planar elbow stretched)."""
    arm = make()
    q = np.concatenate([arm.sample_joints(100_000, seed=4), np.array(list(itertools.product(*arm.limits)))])
    farthest = np.linalg.norm(arm.fk(q)[:, :3, 3], axis=-1).max()
    assert farthest <= arm.reach_bound + 1e-12
    if name in ("planar_elbow", "three_dof", "typed RR"):
        assert farthest > arm.reach_bound - 1e-3
    assert arm.reach_bound < 4.3 if name != "typed with long slides" else farthest > 10.0


def test_nearest_turns_a_joint_next_to_the_current_one_within_the_limits():
    """KR210's A4 turns ±350°: at 300° the arm stays at 300°, not at the wrapped −60°."""
    kr210 = Arm.preset("kr210")
    q = np.radians([10, 20, -30, 300, 50, 60])
    branch = kr210.ik(kr210.fk(q), hint=q).nearest(q)
    np.testing.assert_allclose(branch.q, q, atol=1e-9)
    # A1 turns ±185°: from −179°, 170° is nearest as −190°, beyond the limit; the arm turns the long way
    q = np.radians([170, 20, -30, 40, 50, 60])
    near = kr210.ik(kr210.fk(q), hint=q).nearest(np.radians([-179, 20, -30, 40, 50, 60]))
    assert np.degrees(near.q[0]) == pytest.approx(170.0) and kr210.within_limits(near.q)
    # and from −178°, 181° is −179°, within it
    q = np.radians([181, 20, -30, 40, 50, 60])
    near = kr210.ik(kr210.fk(q), hint=q).nearest(np.radians([-178, 20, -30, 40, 50, 60]))
    assert np.degrees(near.q[0]) == pytest.approx(-179.0)


def test_family_data_is_the_solvers_and_reached_through_the_arm():
    course = Arm.preset("course")
    assert course.d4 == course.solver.d4 == 0.1639
    with pytest.raises(AttributeError, match="no 'd4'"):
        Arm.preset("kr210").d4
    assert Arm.preset("three_dof").up == (0.0, 1.0, 0.0) and course.up == (0.0, 0.0, 1.0)


def test_a_ur_arm_from_its_lengths_refuses_bad_ones():
    with pytest.raises(ValueError, match="a2 must be positive"):
        Arm.ur_family(d1=0.1, a2=-0.6, a3=0.5, d4=0.1, d5=0.1, d6=0.1)
    with pytest.raises(ValueError, match="unknown preset"):
        Arm.preset("ur5")


@pytest.mark.parametrize("name", ["kr210", "stanford", "scara", "three_dof"])
def test_one_pose_nearest_is_the_batchs(name):
    """The drag path's plain-Python pick agrees with the vectorised one, preferred slot and turns included."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(11)
    low, high = arm.limits[:, 0], arm.limits[:, 1]
    q = rng.uniform(np.maximum(low, -3.0), np.minimum(high, 3.0), (40, arm.n_joints))
    current = q + rng.normal(0.0, 0.3, q.shape) + np.where(arm.revolute, rng.choice([-2, 0, 2], q.shape) * np.pi, 0.0)
    solution = arm.ik(arm.fk(q), hint=q)
    prefer = rng.integers(-1, len(solution.labels), 40)
    batch = solution.nearest(current, prefer=prefer)
    for k in range(40):
        one = arm.ik(arm.fk(q[k]), hint=q[k]).nearest(current[k], prefer=int(prefer[k]))
        assert int(one.slot) == int(batch.slot[k])
        np.testing.assert_allclose(one.q, batch.q[k], atol=1e-12)


def test_joint_limit_is_the_ur_familys_alone():
    kr210 = Arm.preset("kr210")
    q = kr210.specs.home
    with pytest.raises(ValueError, match="joint_limit is the UR family's"):
        kr210.ik(kr210.fk(q)).nearest(q, joint_limit=7.0)
    course = Arm.preset("course")
    q = course.specs.home
    assert int(course.ik(course.fk(q)).nearest(q, joint_limit=4.0).slot) == 4


def test_the_readmes_tour_of_the_core_runs():
    """The README's code block, with the arrays it names given values, runs as written."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    tour = readme.split("## The kinematics core", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    q = np.radians([10, -60, 80, -30, 70, 20])
    names = {"np": np, "q": q, "q6": np.radians([10, 20, -30, 40, 50, 60]), "qdot": np.full(6, 0.1),
             "twist": np.array([0.1, 0, 0, 0, 0, 0]), "force": np.array([0, 0, -10.0]), "moment": np.zeros(3),
             "q0": q, "q1": q + 0.3, "T_goal": Arm.preset("course").fk(q + 0.3)}
    exec(compile(tour, "README.md", "exec"), names)
    assert names["reach"].counts.shape == (200, 200)
    assert np.allclose(names["branch"].q, q) and names["points"].shape == (200_000, 3)
