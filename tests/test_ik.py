"""Inverse kinematics: round trips, the fixed slots, singular and unreachable poses."""

import re

import numpy as np
import pytest

from ur10core import (
    ELBOW_TOO_CLOSE,
    ELBOW_TOO_FAR,
    REACHABLE,
    SLOT_LABELS,
    SLOTS,
    WRIST_INSIDE_CYLINDER,
    Arm,
)
from ur10core.ik import solve_reference

from .conftest import random_joints, wrapped_difference

pytestmark = pytest.mark.core

N_ROUND_TRIP = 5000


def _slot_from_signs(arm: Arm, q: np.ndarray) -> np.ndarray:
    """The slot that must hold q, from the sign rules: i by the shoulder factor A, j by θ5, l by θ3."""
    shoulder = arm.singularity_factors(q)[..., 0]
    i = (shoulder >= 0).astype(int)
    j = (q[..., 4] < 0).astype(int)
    l = (q[..., 2] < 0).astype(int)
    return 4 * i + 2 * j + l


def test_every_valid_slot_reproduces_the_pose(any_arm):
    q = random_joints(N_ROUND_TRIP, seed=10)
    T = any_arm.fk(q)
    sol = any_arm.ik(T)
    assert sol.q.shape == (N_ROUND_TRIP, 8, 6) and sol.valid.shape == (N_ROUND_TRIP, 8)
    assert sol.valid.sum() > 0.8 * 8 * N_ROUND_TRIP  # most random poses have all 8
    T_back = any_arm.fk(np.where(sol.valid[..., None], sol.q, 0.0))
    error = np.abs(T_back - T[:, None]).max(axis=(-2, -1))
    assert error[sol.valid].max() < 1e-9
    assert np.isnan(sol.q[~sol.valid]).all()
    assert (sol.q[sol.valid] > -np.pi).all() and (sol.q[sol.valid] <= np.pi).all()


def test_generating_joints_are_always_among_the_branches_in_their_slot(any_arm):
    q = random_joints(N_ROUND_TRIP, seed=11)
    sol = any_arm.ik(any_arm.fk(q))
    slot = _slot_from_signs(any_arm, q)
    in_slot = sol.q[np.arange(len(q)), slot]
    assert sol.valid[np.arange(len(q)), slot].all()
    assert wrapped_difference(in_slot, q).max() < 1e-6


def test_slot_sign_rules(course):
    sol = course.ik(course.fk(random_joints(2000, seed=12)))
    q, valid = sol.q, sol.valid
    shoulder = course.singularity_factors(np.where(valid[..., None], q, 0.0))[..., 0]
    for slot in SLOTS:
        k = slot.index
        v = valid[:, k]
        i, j, l = k // 4, (k // 2) % 2, k % 2
        assert ((shoulder[v, k] >= -1e-12) if i == 1 else (shoulder[v, k] <= 1e-12)).all()
        assert ((q[v, k, 4] >= 0) if j == 0 else (q[v, k, 4] <= 0) | (q[v, k, 4] == np.pi)).all()
        assert ((q[v, k, 2] >= 0) if l == 0 else (q[v, k, 2] <= 0) | (q[v, k, 2] == np.pi)).all()
        assert slot.theta5_sign == (1 if j == 0 else -1) and slot.theta3_sign == (1 if l == 0 else -1)


def test_slot_labels_describe_the_arm_geometrically(course):
    """Shoulder, elbow and wrist words checked on the frames each branch produces."""
    sol = course.ik(course.fk(random_joints(1000, seed=13)))
    q = sol.q[sol.valid]
    slots = np.nonzero(sol.valid)[1]
    F = course.frames(q)
    shoulder_point, elbow, p4, p5 = F[:, 2, :3, 3], F[:, 3, :3, 3], F[:, 4, :3, 3], F[:, 5, :3, 3]
    x1 = F[:, 1, :3, 0]
    reach = np.einsum("ni,ni->n", x1, p5)  # A: P5 along x1 (x1 is horizontal)
    # view the arm plane with the reach direction e to the right and z up
    e = np.sign(reach)[:, None] * x1
    to_p4 = np.stack([np.einsum("ni,ni->n", e, p4 - shoulder_point), (p4 - shoulder_point)[:, 2]], -1)
    to_elbow = np.stack([np.einsum("ni,ni->n", e, elbow - shoulder_point), (elbow - shoulder_point)[:, 2]], -1)
    elbow_left_of_line = to_p4[:, 0] * to_elbow[:, 1] - to_p4[:, 1] * to_elbow[:, 0]
    tilt = np.einsum("ni,ni->n", F[:, 6, :3, 2], F[:, 4, :3, 0])  # z6 · x4 = s5
    clear = (np.abs(reach) > 1e-6) & (np.abs(elbow_left_of_line) > 1e-9) & (np.abs(tilt) > 1e-9)
    for k, slot in enumerate(SLOTS):
        m = clear & (slots == k)
        assert m.sum() > 50
        assert (reach[m] > 0).all() if slot.shoulder == "right" else (reach[m] < 0).all()
        assert (elbow_left_of_line[m] > 0).all() if slot.elbow == "up" else (elbow_left_of_line[m] < 0).all()
        assert (tilt[m] > 0).all() if slot.wrist == "not flipped" else (tilt[m] < 0).all()
    assert len(set(SLOT_LABELS)) == 8
    assert SLOT_LABELS[4] == "shoulder right, elbow down, wrist not flipped"


def test_compiled_kernel_matches_readable_reference(any_arm):
    q = random_joints(1500, seed=14)
    T = any_arm.fk(q)
    sol = any_arm.ik(T)
    for k in range(len(q)):
        ref = solve_reference(any_arm, T[k])
        np.testing.assert_array_equal(ref.valid, sol.valid[k])
        np.testing.assert_array_equal(ref.failure, sol.failure[k])
        np.testing.assert_allclose(wrapped_difference(ref.q[ref.valid], sol.q[k][ref.valid]), 0, atol=1e-11)


def test_one_pose_path_equals_batch_path(course):
    q = random_joints(300, seed=15)
    T = course.fk(q)
    batch = course.ik(T, hint=q)
    for k in range(len(q)):
        one = course.ik(T[k], hint=q[k])
        # the numpy backend's one-pose path is plain Python: the last bit may differ
        np.testing.assert_allclose(one.q, batch.q[k], rtol=0, atol=1e-12)
        for name in ("valid", "wrist_singular", "elbow_singular", "shoulder_singular", "failure"):
            np.testing.assert_array_equal(getattr(one, name), getattr(batch, name)[k])


def test_batch_shapes_and_hint_broadcast(course):
    q = random_joints(6, seed=16).reshape(2, 3, 6)
    T = course.fk(q)
    sol = course.ik(T, hint=np.zeros(6))
    assert sol.q.shape == (2, 3, 8, 6) and sol.shoulder_singular.shape == (2, 3)
    assert sol.wrist2_radius.shape == (2, 3) and sol.elbow_distance.shape == (2, 3, 8)
    # one pose against many hints broadcasts the pose
    assert course.ik(T[0, 0], hint=q[0]).q.shape == (3, 8, 6)


def test_zero_pose_wrist_and_elbow_singular(course):
    q = np.zeros(6)
    sol = course.ik(course.fk(q), hint=q)
    k = 4  # shoulder right, θ5 >= 0, θ3 >= 0
    assert sol.valid[k] and sol.wrist_singular[k] and sol.elbow_singular[k]
    np.testing.assert_allclose(sol.q[k], q, atol=1e-7)
    np.testing.assert_allclose(sol.q[4], sol.q[5], atol=1e-7)  # elbow slots coincide
    np.testing.assert_allclose(sol.q[4], sol.q[6], atol=1e-7)  # wrist slots coincide
    assert not sol.shoulder_singular
    assert sol.unreachable_reason() == ""


def test_stretched_pose_all_three_singular(course):
    q = np.radians([45, 90, 0, -90, 0, 60])
    T = course.fk(q)
    sol = course.ik(T, hint=q)
    assert sol.shoulder_singular and sol.valid.all()
    assert sol.wrist_singular.all() and sol.elbow_singular.all()
    np.testing.assert_allclose(sol.q[:4], sol.q[4:], atol=1e-6)  # shoulder slots coincide
    for k in range(8):
        np.testing.assert_allclose(wrapped_difference(sol.q[k], q), 0, atol=1e-6)
        np.testing.assert_allclose(course.fk(sol.q[k]), T, atol=1e-9)
    np.testing.assert_allclose(course.singularity_factors(q), 0, atol=1e-12)


def test_wrist_singular_takes_theta6_from_hint(course):
    q = np.array([0.4, -1.1, 1.3, 0.5, 0.0, 1.0])
    T = course.fk(q)
    for hint6 in (0.3, -2.0, 3.0):
        hint = np.array([0, 0, 0, 0, 0, hint6])
        sol = course.ik(T, hint=hint)
        # the singularity belongs to q's θ1 (shoulder right): the other θ1 turns axis 4 away
        assert sol.valid[4:].all() and sol.wrist_singular[4:].all()
        assert not sol.wrist_singular[:4].any()
        for k in range(4, 8):
            assert sol.q[k, 5] == pytest.approx(hint6)
            np.testing.assert_allclose(course.fk(sol.q[k]), T, atol=1e-9)  # θ2, θ3, θ4 compensate
    # with c5 = 1 the pose fixes only θ2 + θ3 + θ4 + θ6: the forearm moves with the choice of θ6
    sol = course.ik(T, hint=[0, 0, 0, 0, 0, 0.3])
    assert wrapped_difference(sol.q[4, 1:4].sum() + sol.q[4, 5], q[1:4].sum() + q[5]) < 1e-9
    # the default hint is θ6 = 0; the batch path agrees
    assert course.ik(T).q[4, 5] == 0.0
    assert course.ik(T[None]).q[0, 4, 5] == 0.0


def test_nearest_keeps_theta6_at_wrist_singularity(course):
    current = np.array([0.4, -1.1, 1.3, 0.5, 0.0, 5.5])  # θ6 beyond π: a second turn
    branch = course.ik(course.fk(current), hint=current).nearest(current)
    np.testing.assert_allclose(branch.q, current, atol=1e-9)


def _shoulder_singular_joints(arm: Arm, theta2: float, theta3: float, theta5: float) -> np.ndarray:
    # choose θ4 so that a2 c2 + a3 c23 − d5 s234 = 0 (docs/kinematics.md §5)
    s234 = (arm.a2 * np.cos(theta2) + arm.a3 * np.cos(theta2 + theta3)) / arm.d5
    assert abs(s234) <= 1
    return np.array([0.7, theta2, theta3, np.arcsin(s234) - theta2 - theta3, theta5, -0.4])


@pytest.mark.parametrize("theta2, theta3", [(np.radians(80), np.radians(20)), (np.radians(100), np.radians(-25))])
def test_shoulder_singular_slots_coincide(course, theta2, theta3):
    q = _shoulder_singular_joints(course, theta2, theta3, theta5=0.9)
    np.testing.assert_allclose(course.singularity_factors(q)[0], 0, atol=1e-15)
    T = course.fk(q)
    sol = course.ik(T)
    assert sol.shoulder_singular
    assert sol.wrist2_radius == pytest.approx(course.d4, abs=1e-12)
    valid = sol.valid[:4] & sol.valid[4:]
    assert valid.any()
    np.testing.assert_allclose(wrapped_difference(sol.q[:4][valid], sol.q[4:][valid]), 0, atol=1e-6)
    for k in np.nonzero(sol.valid)[0]:
        np.testing.assert_allclose(course.fk(sol.q[k]), T, atol=1e-9)
    assert (wrapped_difference(sol.q[sol.valid], q).max(axis=-1) < 1e-6).any()


@pytest.mark.parametrize("theta3", [0.0, np.pi])
def test_elbow_singular_slots_coincide(course, theta3):
    q = np.array([0.3, -0.7, theta3, 0.9, 1.2, -0.5])
    T = course.fk(q)
    sol = course.ik(T, hint=q)
    k = 4 * 1 + 2 * 0  # q's shoulder factor is positive (right), θ5 > 0
    assert course.singularity_factors(q)[0] > 0
    assert sol.elbow_singular[k] and sol.elbow_singular[k + 1]
    np.testing.assert_allclose(wrapped_difference(sol.q[k], sol.q[k + 1]), 0, atol=1e-6)
    assert wrapped_difference(sol.q[k], q).max() < 1e-6
    expected = course.a2 + course.a3 if theta3 == 0 else abs(course.a2 - course.a3)
    assert sol.elbow_distance[k] == pytest.approx(expected, abs=1e-9)


def test_unreachable_far_pose_says_elbow_reach_with_numbers(course):
    T = np.eye(4)
    T[:3, 3] = (2.5, 0.3, 0.4)
    sol = course.ik(T)
    assert not sol.valid.any() and not sol.reachable
    assert (sol.failure == ELBOW_TOO_FAR).all()
    assert np.isnan(sol.q).all()
    reason = sol.unreachable_reason()
    assert "elbow reach" in reason and "beyond a2 + a3 = 1184.5 mm" in reason
    # the number reported is the smallest excess over the branches
    excess_mm = 1e3 * (sol.elbow_distance.min() - (course.a2 + course.a3))
    assert f"{excess_mm:.1f} mm beyond" in reason


def test_a_pose_a_hair_beyond_the_reach_says_by_how_much(course):
    """The stretched pose typed back from its readout (rounded to 0.1 mm) lies micrometres beyond the reach: the
    reason read "the wrist-1 centre would be 1184.5 mm from the shoulder, 0.0 mm beyond a2 + a3 = 1184.5 mm"."""
    T = course.fk(np.radians([45, 90, 0, -90, 0, 60]))
    T[:3, 3] = np.round(T[:3, 3], 4)  # 181.090 mm → 181.1 mm: outwards
    sol = course.ik(T)
    assert not sol.valid.any()
    reason = sol.unreachable_reason()
    excess_mm = 1e3 * (np.nanmin(sol.elbow_distance) - (course.a2 + course.a3))
    assert 0 < excess_mm < 0.05
    match = re.search(r"would be (\d+\.\d+) mm from the shoulder, (\d+\.\d+) mm beyond a2 \+ a3 = (\d+\.\d+) mm", reason)
    at, off, bound = match.groups()
    assert at != bound and float(off) == pytest.approx(excess_mm, abs=0.6 * 10 ** -len(off.split(".")[1]))


@pytest.mark.parametrize("name", ["stanford", "cylindrical", "cylindrical_wrist", "scara", "kr210", "three_dof"])
def test_a_target_a_slide_reaches_1e300_m_out_has_a_nearest_branch(name):
    """A sliding joint reaches any distance: the Stanford arm's branches for a target 1e300 m out have d3 ≈ 1.4e303
    m. The nearest branch's distance, a float's ** 2, raised OverflowError ("(34, 'Numerical result out of range')",
    until 2026-12-05). Every distance is then inf: the first valid slot is as near as any, and none is within the
    limits."""
    arm = Arm.preset(name)
    for coordinate in (1e300, -1e300, 1e155):
        T = arm.fk(arm.limits.mean(axis=1))
        T[:2, 3] = coordinate
        solution = arm.ik(T)
        first = int(np.flatnonzero(solution.valid)[0]) if solution.valid.any() else -1
        assert int(solution.nearest(arm.limits.mean(axis=1)).slot) == first
        assert int(solution.nearest(arm.limits.mean(axis=1), within_limits=True).slot) == -1


@pytest.mark.parametrize("coordinate", [1e150, 1e300, -1e308])
def test_absurdly_far_finite_pose_is_unreachable_not_nan(course, coordinate):
    """Finite but huge coordinates overflow the reach to inf or NaN: every slot must still say "too far"."""
    T = np.eye(4)
    T[:3, 3] = coordinate
    for solution in (course.ik(T), solve_reference(course, T), course.ik(np.stack([T, T]))):
        assert not solution.valid.any()
        assert (solution.failure == ELBOW_TOO_FAR).all()
    assert course.ik(T).unreachable_reason().startswith("unreachable: elbow reach")
    branch = course.ik(T).nearest(np.zeros(6))
    assert int(branch.slot) == -1 and np.isnan(branch.q).all()


def test_unreachable_inside_cylinder_says_so_with_numbers(course):
    T = np.eye(4)
    T[:3, 3] = (0.05, 0.02, 0.6)  # z6 = z: P5 is 53.9 mm from the base axis
    sol = course.ik(T)
    assert not sol.valid.any()
    assert (sol.failure == WRIST_INSIDE_CYLINDER).all()
    rho = np.hypot(0.05, 0.02)
    assert sol.wrist2_radius == pytest.approx(rho)
    reason = sol.unreachable_reason()
    assert f"{1e3 * (course.d4 - rho):.1f} mm inside" in reason
    assert "d4 = 163.9 mm" in reason
    # batch path reports the same per pose
    batch = course.ik(np.stack([T, course.fk(np.zeros(6))]))
    assert batch.unreachable_reason((0,)) == reason
    assert batch.unreachable_reason((1,)) == ""


def test_folded_elbow_pulled_closer_fails_as_too_close(course):
    # fold the elbow (θ3 = π, frame-4 origin |a2 − a3| = 41.3 mm from the shoulder in the arm
    # plane), then pull the whole pose towards the shoulder by half of that
    q = np.array([0.0, 0.3, np.pi, 0.0, np.pi / 2, 0.0])
    F = course.frames(q)
    in_plane = F[4, :3, 3] - F[2, :3, 3] - course.d4 * F[2, :3, 2]
    assert np.linalg.norm(in_plane) == pytest.approx(abs(course.a2 - course.a3))
    T = course.fk(q)
    T[:3, 3] -= 0.5 * in_plane
    sol = course.ik(T)
    k = _slot_from_signs(course, q) & ~1  # q's (i, j) pair
    assert (sol.failure[k : k + 2] == ELBOW_TOO_CLOSE).all() and not sol.valid[k : k + 2].any()
    assert sol.elbow_distance[k] == pytest.approx(0.5 * abs(course.a2 - course.a3), abs=1e-9)


def test_too_close_reason_wording(course):
    from ur10core.ik import IKSolution

    sol = IKSolution(
        np.full((8, 6), np.nan), np.zeros(8, bool), np.full(8, ELBOW_TOO_CLOSE, np.int8), course,
        extra=(np.zeros(8, bool), np.zeros(8, bool), np.bool_(False), np.float64(0.3), np.array([0.03, 0.03, 0.02, 0.02] * 2)),
    )
    assert sol.unreachable_reason() == (
        "unreachable: elbow reach — the wrist-1 centre would be 30.0 mm from the shoulder, "
        "11.3 mm closer than |a2 − a3| = 41.3 mm"
    )


def test_some_branches_missing_never_shift_others(course):
    # near the far edge of the workspace the shoulder-left branches vanish first
    q = np.array([0.2, 0.1, 0.05, -0.3, 1.0, 0.4])
    sol = course.ik(course.fk(q))
    assert sol.valid.any() and not sol.valid.all()
    assert (sol.failure[sol.valid] == REACHABLE).all()
    assert (sol.failure[~sol.valid] != REACHABLE).all()
    assert sol.valid[_slot_from_signs(course, q)]


class TestNearestBranch:
    def test_returns_current_joints_with_their_turns(self, course):
        q = np.array([0.5, -1.0, 1.2, 2.0, 0.8, -0.3])
        current = q + 2 * np.pi * np.array([-1, 0, -1, 0, 0, 1])  # same pose, other turns, within ±360°
        branch = course.ik(course.fk(q)).nearest(current)
        np.testing.assert_allclose(branch.q, current, atol=1e-9)
        assert int(branch.slot) == _slot_from_signs(course, q)

    def test_picks_the_branch_closest_to_a_perturbed_current(self, course):
        rng = np.random.default_rng(17)
        q = random_joints(300, seed=17)
        sol = course.ik(course.fk(q))
        current = q + rng.normal(scale=0.01, size=q.shape)
        branch = sol.nearest(current)
        # never farther than the branch that generated the pose; that one nearly always
        chosen = np.linalg.norm(branch.q - current, axis=-1)
        generating = np.linalg.norm(wrapped_difference(q, current), axis=-1)
        assert (chosen <= generating + 1e-9).all()
        assert (wrapped_difference(branch.q, q).max(axis=-1) < 1e-6).mean() > 0.97
        assert (np.abs(branch.q - current) <= np.pi + 1e-12).all()

    @pytest.mark.parametrize(
        "current_deg, value_deg, expected_deg",
        [(350, -10, 350), (-350, 170, -190), (359, 179.9, 179.9), (-359, -179.9, -179.9), (10, 10, 10)],
    )
    def test_stays_within_plus_minus_360(self, course, current_deg, value_deg, expected_deg):
        from ur10core import nearest_branch
        from ur10core.ik import IKSolution

        q = np.zeros((8, 6))
        q[:, 0] = np.radians(value_deg)
        valid = np.zeros(8, bool)
        valid[3] = True
        sol = IKSolution(q, valid, np.zeros(8, np.int8), course)
        branch = nearest_branch(sol, np.radians([current_deg, 0, 0, 0, 0, 0]))
        assert np.degrees(branch.q[0]) == pytest.approx(expected_deg)
        assert int(branch.slot) == 3

    def test_no_valid_branch(self, course):
        T = np.eye(4)
        T[:3, 3] = (3, 0, 0)
        branch = course.ik(T).nearest(np.zeros(6))
        assert int(branch.slot) == -1 and np.isnan(branch.q).all()

    def test_batched(self, course):
        q = random_joints(40, seed=18).reshape(4, 10, 6)
        branch = course.ik(course.fk(q)).nearest(q)
        assert branch.q.shape == (4, 10, 6) and branch.slot.shape == (4, 10)
        np.testing.assert_allclose(branch.q, q, atol=1e-6)


def test_nearest_prefers_the_current_slot_on_a_tie(course):
    q = np.radians([45, 90, 0, -90, 0, 60])  # stretched: all eight slots coincide
    sol = course.ik(course.fk(q), hint=q)
    for k in range(8):
        assert int(sol.nearest(q, prefer=k).slot) == k
    generic = course.ik(course.fk(np.radians([30, 45, 26, 50, 60, 80])))
    assert int(generic.nearest(np.radians([30, 45, 26, 50, 60, 80]), prefer=0).slot) == 4  # no tie: nearest wins
    batch = course.ik(course.fk(np.stack([q, q])), hint=q)
    np.testing.assert_array_equal(batch.nearest(np.stack([q, q]), prefer=np.array([3, 6])).slot, [3, 6])


def test_nearest_one_pose_path_equals_batch_path(course):
    rng = np.random.default_rng(19)
    q = random_joints(400, seed=19)
    sol = course.ik(course.fk(q))
    current = q + rng.normal(scale=0.3, size=q.shape) + 2 * np.pi * rng.integers(-1, 2, size=q.shape)
    current = np.clip(current, -2 * np.pi, 2 * np.pi)
    prefer = rng.integers(0, 8, size=len(q))
    batch = sol.nearest(current, prefer=prefer)
    for k in range(len(q)):
        one = course.ik(course.fk(q[k])).nearest(current[k], prefer=int(prefer[k]))
        assert int(one.slot) == int(batch.slot[k])
        np.testing.assert_allclose(one.q, batch.q[k], atol=1e-12)
