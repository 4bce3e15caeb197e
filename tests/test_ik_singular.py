"""IK at and near the singularities: never call a reachable pose unreachable (docs/kinematics.md §4.3)."""

import math

import numpy as np
import pytest

from ur10core import ELBOW_TOO_FAR, Arm, from_controller
from ur10core.ik import solve_reference
from ur10core.tolerances import WRIST_TOLERANCE

from .conftest import random_joints, urs_own_solver, wrapped_difference

pytestmark = pytest.mark.core


def near_singular_joints(arm: Arm, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """n joint vectors near the singularities, and which: bit 1 elbow, 2 wrist, 4 shoulder.

    Every combination of the three appears. q3 and q5 lie 1e-12…1e-5 rad from 0 or ±π;
    the shoulder factor a2 c2 + a3 c23 − d5 s234 lies 1e-12…1e-6 m from 0 (θ4 chosen so;
    where θ2, θ3 leave no such θ4, θ2 is turned so that a2 c2 + a3 c23 = 0 first).
    """
    rng = np.random.default_rng(seed)
    q = -rng.uniform(-np.pi, np.pi, (n, 6))
    kind = np.arange(n) % 8

    def offset(count: int, low: float, high: float) -> np.ndarray:
        return rng.choice([-1.0, 1.0], count) * 10.0 ** rng.uniform(low, high, count)

    for bit, joint in ((1, 2), (2, 4)):
        near = kind & bit > 0
        q[near, joint] = rng.choice([0.0, np.pi, -np.pi], near.sum()) + offset(near.sum(), -12, -5)
    shoulder = np.flatnonzero(kind & 4)
    factor = offset(len(shoulder), -12, -6)
    t2, t3 = q[shoulder, 1], q[shoulder, 2]
    ratio = (arm.a2 * np.cos(t2) + arm.a3 * np.cos(t2 + t3) - factor) / arm.d5
    turn = np.abs(ratio) > 1
    t2 = np.where(turn, np.arctan2(arm.a2 + arm.a3 * np.cos(t3), arm.a3 * np.sin(t3)), t2)
    ratio = (arm.a2 * np.cos(t2) + arm.a3 * np.cos(t2 + t3) - factor) / arm.d5
    t234 = np.where(rng.random(len(shoulder)) < 0.5, np.arcsin(ratio), np.pi - np.arcsin(ratio))
    q[shoulder, 1], q[shoulder, 3] = t2, t234 - t2 - t3
    return q, kind


def test_the_generator_lands_near_each_singularity(course):
    q, kind = near_singular_joints(course, 800, seed=1)
    factors = np.abs(course.singularity_factors(q))
    for bit, column, bound in ((1, 1, 1e-5), (2, 2, 1e-5), (4, 0, 2e-6)):
        assert (factors[kind & bit > 0, column] < bound).all()
    assert (factors[kind == 0] > 1e-6).mean() > 0.99


@pytest.mark.parametrize("hint_kind", ["none", "generating", "random"])
def test_near_singular_poses_are_never_unreachable(any_arm, hint_kind):
    """The issue's property, on every combination of the three near-singularities.

    ``ik(fk(q))`` has a valid slot, every valid slot reproduces the pose to 1e-9, and with
    the generating joints as the hint they are among the branches.
    """
    q, kind = near_singular_joints(any_arm, 4000, seed=20)
    q = np.concatenate([q, random_joints(1000, seed=21)])
    T = any_arm.fk(q)
    hint = {"none": None, "generating": q, "random": random_joints(len(q), seed=22) * 2}[hint_kind]
    sol = any_arm.ik(T, hint=hint)
    assert sol.reachable.all(), f"unreachable: kinds {np.unique(kind[~sol.reachable[:len(kind)]])}"
    T_back = any_arm.fk(np.where(sol.valid[..., None], sol.q, 0.0))
    error = np.abs(T_back - T[:, None]).max(axis=(-2, -1))
    assert error[sol.valid].max() < 1e-9
    if hint_kind == "generating":
        distance = np.where(sol.valid, wrapped_difference(sol.q, q[:, None]).max(axis=-1), np.inf)
        assert distance.min(axis=-1).max() < 1e-6


def test_one_pose_path_agrees_near_singularities(course):
    q, _ = near_singular_joints(course, 400, seed=23)
    T = course.fk(q)
    for k in range(len(q)):
        for hint in (None, q[k]):
            one, ref = course.ik(T[k], hint=hint), solve_reference(course, T[k], hint=hint)
            assert one.valid.any() and ref.valid.any()
            np.testing.assert_array_equal(one.valid, ref.valid)
            np.testing.assert_array_equal(one.wrist_singular, ref.wrist_singular)


def _exactly_wrist_singular(arm: Arm, n: int, seed: int) -> np.ndarray:
    q = random_joints(n, seed=seed)
    q[:, 4] = np.random.default_rng(seed).choice([0.0, np.pi], n)
    return q


def _elbow_distance(arm: Arm, q: np.ndarray, theta6: np.ndarray, lift: float = 0.0) -> np.ndarray:
    """Shoulder to frame-4 origin for the wrist-singular joints ``q`` with θ6 turned to ``theta6``, worked out directly.

    With s5 = 0 the pose fixes θ234 + c5·θ6. Each θ6 thus gives θ234, and with it the
    frame-4 origin in the arm plane, (A + d5 s234, V − d5 c234) from the shoulder
    (docs/kinematics.md §3: A, V are the generating joints' reach and height of P5;
    ``lift`` raises the pose).
    """
    t2, t3, t4, t5, t6 = q[1:]
    A = arm.a2 * np.cos(t2) + arm.a3 * np.cos(t2 + t3) - arm.d5 * np.sin(t2 + t3 + t4)
    V = arm.a2 * np.sin(t2) + arm.a3 * np.sin(t2 + t3) + arm.d5 * np.cos(t2 + t3 + t4) + lift
    theta234 = t2 + t3 + t4 - np.cos(t5) * (theta6 - t6)
    return np.hypot(A + arm.d5 * np.sin(theta234), V - arm.d5 * np.cos(theta234))


def _feasible_theta6(arm: Arm, q: np.ndarray, theta6: np.ndarray) -> np.ndarray:
    r = _elbow_distance(arm, q, theta6)
    return (r <= arm.a2 + arm.a3) & (r >= abs(arm.a2 - arm.a3))


def test_wrist_singular_slot_is_empty_only_if_no_theta6_works(course):
    """Against a 0.05° sweep of θ6: valid exactly when some θ6 reaches, and then the θ6 nearest the hint."""
    q = _exactly_wrist_singular(course, 400, seed=30)
    grid = np.radians(np.arange(-180, 180, 0.05))
    step = np.radians(0.05)
    empty = 0
    for k in range(len(q)):
        hint = np.random.default_rng(k).uniform(-np.pi, np.pi)
        sol = course.ik(course.fk(q[k]), hint=[0, 0, 0, 0, 0, hint])
        pair = 4 * int(course.singularity_factors(q[k])[0] >= 0)  # the generating shoulder's slots
        assert sol.wrist_singular[pair : pair + 4].all()
        feasible = _feasible_theta6(course, q[k], grid)
        for j in (0, 2):
            if feasible.any():
                assert sol.valid[pair + j], (k, j)
                distance = wrapped_difference(grid[feasible], hint)
                chosen = wrapped_difference(sol.q[pair + j, 5], hint)
                assert chosen <= distance.min() + 1e-12  # nothing in the sweep is nearer the hint
                assert chosen >= distance.min() - step  # and it is as near as the sweep's step allows
                assert _feasible_theta6(course, q[k], np.array([sol.q[pair + j, 5]]) + 0.0)[0] or np.isclose(
                    course.fk(sol.q[pair + j]), course.fk(q[k]), atol=1e-9
                ).all()
            else:
                empty += 1
                assert not sol.valid[pair + j] or np.abs(course.fk(sol.q[pair + j]) - course.fk(q[k])).max() < 1e-9
    assert empty == 0  # generated poses always have a θ6 (their own)
    assert (np.abs(course.fk(np.where(sol.valid[..., None], sol.q, 0)) - course.fk(q[-1])).max(axis=(-2, -1))[sol.valid] < 1e-9).all()


def test_the_hints_theta6_is_kept_exactly_when_it_works(course):
    q = _exactly_wrist_singular(course, 500, seed=31)
    sol = course.ik(course.fk(q), hint=q)
    k = np.arange(len(q))
    slot = 4 * (course.singularity_factors(q)[:, 0] >= 0) + 2 * 0 + (q[:, 2] < 0)
    assert sol.valid[k, slot].all() and sol.wrist_singular[k, slot].all()
    # θ6 exactly the hint's (q6 is in (−π, π] already), not merely close
    np.testing.assert_array_equal(sol.q[k, slot, 5], q[:, 5])
    # and a hint a turn or a million turns away is the same angle, exactly
    far = q.copy()
    far[:, 5] += 2 * np.pi * np.random.default_rng(1).integers(-10**6, 10**6, len(q))
    np.testing.assert_allclose(course.ik(course.fk(q), hint=far).q[k, slot, 5], q[:, 5], rtol=0, atol=1e-9)


def test_course_stretched_pose_without_a_hint(course):
    """The issue's first example: the course's own stretched pose, no hint, used to give no solution."""
    q = np.radians([45, 90, 0, -90, 0, 60])
    T = course.fk(q)
    for solution in (course.ik(T), solve_reference(course, T)):
        assert solution.valid.all()
        np.testing.assert_allclose(np.degrees(solution.q[:, 5]), 60.0, atol=1e-4)  # the only θ6 that reaches
        assert np.abs(course.fk(solution.q) - T).max() < 1e-9


def test_wrist_singular_pose_whose_theta6_must_be_chosen(course):
    """The issue's second example: only θ6 in about [−180°, −138°] ∪ [160°, 175°] reaches."""
    q = np.radians([0, 0, 20, -90, 0, 180])
    T = course.fk(q)
    sol = course.ik(T)
    assert sol.valid.sum() == 4 and sol.wrist_singular[sol.valid].all()
    theta6 = np.degrees(sol.q[sol.valid, 5])
    assert np.allclose(theta6, theta6[0]) and -141 < theta6[0] < -137  # the arc's end nearest 0
    assert np.abs(course.fk(sol.q[sol.valid]) - T).max() < 1e-9
    # a hint inside the other arc stays there
    inside = course.ik(T, hint=[0, 0, 0, 0, 0, np.radians(170)])
    assert np.degrees(inside.q[inside.valid, 5]) == pytest.approx(170)


def test_near_singular_wrist_at_the_reach_limit(course):
    """The issue's example with |s5| = 2e-9: θ6 from numbers near 1e-9 used to push P4 out of reach."""
    q = np.radians([25, -35, 0, -109, 0, -148])
    q[4] = 2e-9
    for hint in (q, None, np.zeros(6)):
        sol = course.ik(course.fk(q), hint=hint)
        assert sol.valid.any()
        assert np.abs(course.fk(sol.q[sol.valid]) - course.fk(q)).max() < 1e-9
    sol = course.ik(course.fk(q), hint=q)
    assert (wrapped_difference(sol.q[sol.valid], q).max(axis=-1) < 1e-6).any()


@pytest.mark.parametrize("start_deg", [(0, 0, 0, 0, 0, 0), (45, 90, 0, -90, 0, 60)])
def test_twisting_the_target_about_the_tool_axis_turns_theta6(course, start_deg):
    """At the zero and stretched poses a 1° twist about z6 turns θ6 by 1°; no jump, no 'unreachable'."""
    q = np.radians(start_deg)
    twist = np.eye(4)
    twist[:2, :2] = [[math.cos(math.radians(1)), -math.sin(math.radians(1))], [math.sin(math.radians(1)), math.cos(math.radians(1))]]
    sol = course.ik(course.fk(q) @ twist, hint=q)
    branch = sol.nearest(q)
    assert int(branch.slot) >= 0
    change = np.degrees(branch.q - q)
    assert change[5] == pytest.approx(1.0, abs=1e-6)
    np.testing.assert_allclose(np.delete(change, 5), 0.0, atol=1e-4)  # the stretched elbow: θ3 to √rounding


def test_no_theta6_works_and_the_reason_says_so(course):
    """A wrist-singular pose pushed beyond every θ6's reach: empty slots, and a reason naming the wrist."""
    q = np.radians([45, 90, 0, -90, 0, 60])
    T = course.fk(q)
    T[2, 3] += 0.01  # 1 cm higher: the arm points straight up, so further out; θ1 (and s5 = 0) unchanged
    sol = course.ik(T)
    assert not sol.valid.any() and sol.wrist_singular.any()
    assert (sol.failure == ELBOW_TOO_FAR).all()
    reason = sol.unreachable_reason()
    assert "with the wrist singular (axes 4 and 6 parallel) no θ6 works" in reason
    # the distance reported is the nearest any θ6 comes (checked against a sweep): 10 mm too far
    nearest = _elbow_distance(course, q, np.radians(np.arange(-180, 180, 0.01)), lift=0.01).min()
    np.testing.assert_allclose(sol.elbow_distance, nearest, atol=1e-9)
    assert "10.0 mm beyond a2 + a3" in reason


def test_regular_wrist_beyond_reach_keeps_the_plain_reason(course):
    T = np.eye(4)
    T[:3, 3] = (2.5, 0.3, 0.4)
    sol = course.ik(T)
    assert not sol.wrist_singular.any()
    assert "would be" in sol.unreachable_reason() and "no θ6 works" not in sol.unreachable_reason()


@pytest.mark.parametrize("name", ["ur10", "ur10e"])
def test_ur_analytic_ik_finds_nothing_we_miss_on_wrist_singular_poses(name):
    """Where UR's own solver (ur-analytic-ik, test-only) finds a solution, so do we; and ours are exact."""
    ur_analytic_ik = urs_own_solver()
    arm = Arm.preset(name)
    solver = getattr(ur_analytic_ik, name)
    q = _exactly_wrist_singular(arm, 2000, seed=32)
    T = arm.fk(q)
    sol = arm.ik(T)
    assert sol.reachable.all()
    theirs_found = 0
    for k in range(len(q)):
        controller_pose = np.ascontiguousarray(T[k] @ np.diag([-1.0, -1.0, 1.0, 1.0]))
        theirs = np.array(solver.inverse_kinematics(controller_pose)).reshape(-1, 6)
        if len(theirs):
            theirs_found += 1
            assert sol.valid[k].any()
            # each of theirs reproduces the pose; its (shoulder, wrist) pair is one of ours
            course_q = from_controller(theirs)
            ok = np.abs(arm.fk(course_q) - T[k]).max(axis=(-2, -1)) < 1e-6
            for candidate in course_q[ok]:
                pair = 4 * int(arm.singularity_factors(candidate)[0] >= 0) + 2 * int(candidate[4] < -1e-9)
                assert sol.valid[k, pair] or sol.valid[k, pair ^ 2]  # at s5 = 0 the two wrist slots coincide
    assert theirs_found > 100
    assert np.abs(arm.fk(np.where(sol.valid[..., None], sol.q, 0.0)) - T[:, None]).max(axis=(-2, -1))[sol.valid].max() < 1e-9


@pytest.mark.parametrize("name", ["course", "ur10"])
def test_a_target_a_nanometre_beyond_the_stretched_elbow(name):
    """docs/kinematics.md §4.3: a wrist centre up to 1 nm beyond the elbow's reach is put on the
    boundary (the pose moves by at most that much); 5 nm beyond is out of reach, "too far"."""
    arm = Arm.preset(name)
    q = np.array([0.3, -0.7, 0.0, 0.4, 1.0, 0.2])  # θ3 = 0: stretched, slots 5 and 6
    frames = arm.frames(q)
    outward = frames[4, :3, 3] - frames[1, :3, 3]
    outward /= np.linalg.norm(outward)
    for beyond, reached in ((0.5e-9, True), (5e-9, False)):
        T = arm.fk(q)
        T[:3, 3] += beyond * outward
        sol = arm.ik(T, hint=q)
        assert sol.valid[4] == sol.valid[5] == reached, beyond
        if reached:
            assert np.abs(arm.fk(sol.q[4]) - T).max() <= 1e-9
        else:
            assert sol.failure[4] == sol.failure[5] == ELBOW_TOO_FAR


def test_wrist_tolerance_follows_from_the_turn_tolerance():
    """The singular-wrist threshold is not a free constant: every θ6 qualifies below it."""
    from ur10core.tolerances import WRIST_TURN_TOLERANCE

    assert WRIST_TOLERANCE * math.pi == pytest.approx(WRIST_TURN_TOLERANCE)


@pytest.mark.parametrize("theta3", [np.pi - 1e-9, -np.pi + 1e-11, 1e-10, -1e-12])
def test_the_hints_elbow_is_kept_at_the_fold_and_the_stretch(course, theta3):
    """θ3 = ±acos(c3) is fixed only to √rounding there (×14 into θ2 at the fold): the hint's stays."""
    q = np.array([0.4, -0.9, theta3, 0.7, 1.1, -0.6])
    sol = course.ik(course.fk(q), hint=q)
    k = int(np.argmin(np.where(sol.valid, wrapped_difference(sol.q, q).max(axis=-1), np.inf)))
    assert sol.elbow_singular[k]
    assert sol.q[k, 2] == q[2]  # exactly
    assert wrapped_difference(sol.q[k], q).max() < 1e-9


@pytest.mark.parametrize("name", ["ur10", "ur10e"])
def test_just_off_the_wrist_singularity_no_branch_is_lost(name):
    """|s5| of 3e-11…3e-10: the default θ6 (0) is close enough to the pose's own to be kept, but
    where it leaves the elbow out of reach the pose's own θ6 is taken (an issue's fuzz: 0.2 % of
    such poses lost even the branch they came from)."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(33)
    q = random_joints(5000, seed=33)
    q[:, 4] = rng.choice([-1.0, 1.0], len(q)) * 10.0 ** rng.uniform(np.log10(3e-11), np.log10(3e-10), len(q))
    sol = arm.ik(arm.fk(q))
    pair = 4 * (arm.singularity_factors(q)[:, 0] >= 0) + 2 * (q[:, 4] < 0)
    k = np.arange(len(q))
    generating = sol.valid[k, pair] & sol.valid[k, pair + 1]
    assert generating.all(), f"{(~generating).sum()} poses lost their own branch, e.g. q = {q[~generating][0].tolist()}"
    assert arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), arm.fk(q)[:, None])[sol.valid].max() < 1e-9


def test_ur_analytic_iks_answer_just_off_the_wrist_singularity():
    """The issue's example: slots 4 and 5 were empty ("too far"); UR's own solver finds the branch."""
    arm = Arm.preset("ur10")
    q = np.array([-0.8589528148585668, -0.6400991121907973, 1.1052184904077293, -1.1672787257323274, -1e-10,
                  2.2503913066405])
    sol = arm.ik(arm.fk(q))
    assert sol.valid.all()
    theirs = np.array([-0.8589528148585668, -0.16099699187938743, 0.45515332975386125, 2.1452767347794737, 1e-10,
                       -0.8912011135288425])
    np.testing.assert_allclose(arm.fk(theirs), arm.fk(q), atol=1e-15)
    assert wrapped_difference(sol.nearest(theirs).q, theirs).max() < 1e-6


def test_the_hint_survives_rounding_at_the_triple_singularity():
    """Elbow folded, wrist singular, wrist centre on the d4 cylinder: poses 2 ulp from the arm's own
    keep the arm's joints among the branches (the issue's fuzz: 400 of 2 000 lost them, the nearest
    slot π away; an arm resting there would jump). Both the kernel and the plain-Python reference."""
    arm = Arm.preset("ur10e")
    q = np.array([8.599515884126851e-15, 1.5707963267949816, 3.141592652913847, -1.5707963256097257,
                  9.20538493558695e-16, -1.5707963271770549])
    T = arm.fk(q)
    rng = np.random.default_rng(34)
    poses = np.repeat(T[None], 2000, axis=0)
    poses[:, :3] += rng.integers(-2, 3, (2000, 3, 4)) * np.spacing(T[:3])
    sol = arm.ik(poses, hint=q)
    moved = wrapped_difference(sol.nearest(q).q, q).max(axis=-1)
    assert moved.max() < 1e-6, f"{(moved >= 1e-6).sum()} of 2000 lost the hint, one by {moved.max():.3g} rad"
    assert arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), poses[:, None])[sol.valid].max() < 1e-9
    for pose in poses[:200]:
        assert wrapped_difference(solve_reference(arm, pose, hint=q).nearest(q).q, q).max() < 1e-6


@pytest.mark.parametrize("near", [False, True])
def test_the_separation_steps_end_at_the_arms_own_joints(any_arm, near):
    """docs §4.1 replayed on T06(q), one step at a time (the app's step-by-step readout): on 1,500 random and 1,500
    near-singular joint vectors each step's numbers are what the pose and the arm's joints say (P5 against frame 5's
    origin, ρ, A against the shoulder factor, c5 and c3 against the joints), the two θ1 are the IK's two shoulders, the
    steps end at q, and ``slot`` is the IK slot that holds q."""
    from ur10core.solvers.ur import separation_steps

    q = near_singular_joints(any_arm, 1500, seed=21)[0] if near else random_joints(1500, seed=20)
    frames = any_arm.frames(q)
    solution = any_arm.ik(frames[:, -1], hint=q)  # at a singularity q is one of many: the hint keeps it
    factors = any_arm.singularity_factors(q)
    d4 = any_arm.d4
    for k in range(len(q)):
        steps = separation_steps(any_arm, q[k], frames[k])
        np.testing.assert_allclose(steps.p5, frames[k, 5, :3, 3], atol=1e-12)
        # (√(ρ² − d4²) is ill-conditioned at ρ = d4: a rounding of ρ there makes a few nm of A)
        assert steps.rho >= d4 - 1e-12 and abs(steps.reach) == pytest.approx(math.sqrt(max(steps.rho**2 - d4**2, 0)), abs=2e-8)
        assert steps.reach == pytest.approx(factors[k, 0], abs=1e-12)  # A is det J's shoulder factor
        # the course's formulas are ill-conditioned near a singularity (none of it shows in a readout to 0.1°): θ1
        # comes from a square root that is 0 at the shoulder's; θ6 and θ234 divide by s5, and c3 takes θ234's error;
        # θ3 = ±acos(c3) turns by c3's error over |s3| (by its square root at s3 = 0), and θ2 by up to twenty times
        # that, through atan2(a3 s3, a2 + a3 c3) with a2 + a3 c3 ≈ 41 mm
        wrist = 0.0 if steps.wrist_singular else 1e-15 / abs(math.sin(q[k, 4]))
        c3_error = 3e-15 + wrist
        elbow = min(c3_error / max(abs(math.sin(q[k, 2])), 1e-300), math.sqrt(2 * c3_error))
        shoulder = min(1e-15 / max(abs(steps.reach), 1e-300), 1e-7)  # θ1 from A = ±√(ρ² − d4²), A ≈ 0
        tolerance = 1e-8 + wrist + 20 * elbow + shoulder
        assert steps.c5 == pytest.approx(math.cos(q[k, 4]), abs=1e-12)
        assert steps.c3 == pytest.approx(math.cos(q[k, 2]), abs=1e-9 + c3_error)
        for side in (0, 1):  # the IK's left and right shoulders (where A ≈ 0 the IK may move each slot's within its band)
            if solution.valid[k, 4 * side: 4 * side + 4].any() and abs(steps.reach) > 1e-4:
                theta1 = solution.q[k, 4 * side: 4 * side + 4, 0]
                assert wrapped_difference(steps.theta1[side], theta1[np.isfinite(theta1)]).max() < 1e-9
        replayed = [steps.theta1[steps.reach >= 0], steps.theta2, steps.theta3, steps.theta4, steps.theta5, steps.theta6]
        assert wrapped_difference(replayed, q[k]).max() < tolerance, (q[k], replayed)
        assert solution.valid[k, steps.slot]
        assert wrapped_difference(solution.q[k, steps.slot], q[k]).max() < 1e-6
    with pytest.raises(ValueError, match="the UR family's IK"):
        separation_steps(Arm.preset("kr210"), np.zeros(6))
    with pytest.raises(ValueError, match="one pose of 6 joints"):
        separation_steps(any_arm, np.zeros((2, 6)))
