"""Class challenges' checks (ur10core.challenges): each kind's verdicts and mistake groups, against independent numbers."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re
import textwrap

import numpy as np
import pytest

from ur10core import Arm
from ur10core import challenges as C
from ur10core.dh import DHTable
from ur10core.three_dof import FOREARM, UPPER_ARM
from ur10core.workspace import branch_count_map

pytestmark = pytest.mark.core
COURSE = Arm.preset("course")


def arm_of(challenge: C.Challenge) -> Arm:
    return COURSE if challenge.arm == "ur10" else Arm.preset(challenge.arm)


def by_title(title: str) -> C.Challenge:
    return next(c for c in C.builtin() if c.title == title)


def right_answer(challenge: C.Challenge, arm: Arm) -> C.Answer:
    q, _ = C.solution(challenge, arm)
    home = arm.specs.home
    if challenge.kind == "velocity":
        return C.Answer(q=home, rates=arm.joint_rates(home, np.r_[challenge.velocity, 0, 0, 0]).qdot)
    return C.Answer(q=q, target=None if q is None else arm.fk(q), table=arm.dh,
                    numbers=C.expected_numbers(challenge, arm) if challenge.kind == "numbers" else None)


@pytest.mark.parametrize("challenge", C.builtin(), ids=lambda c: c.key)
def test_every_built_in_challenge_is_solved_by_its_own_solution(challenge):
    arm = arm_of(challenge)
    verdict = C.check(challenge, arm, right_answer(challenge, arm))
    assert verdict.solved and verdict.group == "" and verdict.message.startswith("Solved")


@pytest.mark.parametrize("challenge", C.builtin(), ids=lambda c: c.key)
def test_the_home_pose_and_empty_answers_are_not_solutions(challenge):
    """The arm as it starts solves nothing (a task a student need not touch would count nobody)."""
    arm = arm_of(challenge)
    home = arm.specs.home
    answer = C.Answer(q=home, target=arm.fk(home), table=Arm.preset("elbow").dh if arm.name != "elbow" else COURSE.dh,
                      numbers=np.zeros_like(C.expected_numbers(challenge, arm)) if challenge.kind == "numbers" else None,
                      rates=np.zeros(arm.n_joints))
    verdict = C.check(challenge, arm, answer)
    assert not verdict.solved and verdict.group and verdict.message


# ---------------------------------------------------------------------- reach


def test_reach_says_how_far_and_which_way():
    reach = by_title("Reach the target")
    goal = COURSE.fk(reach.joints)
    high = goal.copy()
    high[:3, 3] += (0.0, 0.0, 0.012)
    q = COURSE.ik(high).nearest(np.array(reach.joints)).q
    verdict = C.check(reach, COURSE, C.Answer(q=q))
    assert not verdict.solved and verdict.group == "tool too high"
    assert "12 mm from the target: 12 mm too high" in verdict.message
    aside = goal.copy()
    aside[:3, 3] += (-0.020, 0.0, 0.001)
    verdict = C.check(reach, COURSE, C.Answer(q=COURSE.ik(aside).nearest(np.array(reach.joints)).q))
    assert verdict.group == "tool too far towards −x" and "20 mm too far towards −x" in verdict.message
    # within the tolerance: 4 mm off is solved
    near = goal.copy()
    near[:3, 3] += (0.0, 0.004, 0.0)
    assert C.check(reach, COURSE, C.Answer(q=COURSE.ik(near).nearest(np.array(reach.joints)).q)).solved


def test_reach_notices_a_turned_tool():
    reach = by_title("Reach the target")
    turned = COURSE.fk(reach.joints) @ np.array([[math.cos(0.2), -math.sin(0.2), 0, 0], [math.sin(0.2), math.cos(0.2), 0, 0],
                                                 [0, 0, 1, 0], [0, 0, 0, 1]])
    verdict = C.check(reach, COURSE, C.Answer(q=COURSE.ik(turned).nearest(np.array(reach.joints)).q))
    assert verdict.group == "tool turned" and "turned 11°" in verdict.message


@pytest.mark.parametrize("slot", range(8))
def test_reach_elbow_down_names_the_branch_each_slot_is(slot):
    reach = by_title("Reach it elbow down")
    solution = COURSE.ik(COURSE.fk(reach.joints))
    label = solution.labels[slot]
    q = solution.q[slot] + np.where(np.arange(6) == 5, 2 * np.pi, 0.0)  # a whole turn of joint 6 is the same branch
    verdict = C.check(reach, COURSE, C.Answer(q=q))
    assert verdict.solved == ("elbow down" in label)
    if not verdict.solved:
        assert verdict.group == "elbow up instead of elbow down"
        assert f"branch {slot + 1}" in verdict.message


def test_reach_by_branch_number_and_on_other_arms():
    reach = C.Challenge("five", "reach", "kr210", "", joints=by_title("KR210: reach, wrist flipped").joints, branch=3)
    arm = Arm.preset("kr210")
    solution = arm.ik(arm.fk(reach.joints))
    valid = np.flatnonzero(solution.valid)
    assert 2 in valid
    other = int(next(k for k in valid if k != 2))
    assert C.check(reach, arm, C.Answer(q=solution.q[2])).solved
    assert C.check(reach, arm, C.Answer(q=solution.q[other])).group == f"branch {other + 1} instead of 3"
    # a position-only arm is not asked for an orientation
    planar = Arm.preset("planar_elbow")
    task = C.Challenge("p", "reach", "planar_elbow", "", joints=(0.4, 0.9), branch="elbow up")
    goal = planar.fk(task.joints)
    up = planar.ik(goal)
    slot = int(next(k for k, label in enumerate(up.labels) if "elbow up" in label))
    assert C.check(task, planar, C.Answer(q=up.q[slot])).solved
    assert C.check(task, planar, C.Answer(q=up.q[1 - slot])).group == "elbow down instead of elbow up"


# ---------------------------------------------------------------------- singularity


def test_singularity_checks_the_asked_factor_against_the_closed_form():
    wrist = by_title("Wrist singularity, tool up high")
    q = np.radians([30, 80, -40, 50, 0.0, 80])  # sin θ5 = 0: the course's wrist singularity, tool high
    assert COURSE.fk(q)[2, 3] > 0.5
    assert C.check(wrist, COURSE, C.Answer(q=q)).solved
    elbow_q = np.radians([30, 80, 0.0, 50, 60, 80])  # sin θ3 = 0: the elbow instead
    verdict = C.check(wrist, COURSE, C.Answer(q=elbow_q))
    assert verdict.group == "elbow instead of wrist" and "elbow singularity" in verdict.message
    low = np.radians([30, -30, 20, 50, 0.0, 80])  # the wrist, but the tool is low
    assert COURSE.fk(low)[2, 3] < 0.5
    assert C.check(wrist, COURSE, C.Answer(q=low)).group == "tool below 500 mm"
    # 1 % of the wrist factor's usual size (≈ 1) is about 0.6° of θ5 either side
    assert C.check(wrist, COURSE, C.Answer(q=q + np.radians([0, 0, 0, 0, 0.4, 0]))).solved
    verdict = C.check(wrist, COURSE, C.Answer(q=q + np.radians([0, 0, 0, 0, 5, 0])))
    assert verdict.group == "wrist factor not zero" and f"{math.sin(math.radians(5)):+.3g}" in verdict.message


def test_the_desktop_arms_tool_height_is_measured_up_its_y_from_its_floor():
    """The desktop arm's base frame has y up, on a pedestal 1.5 m high (``Arm.base_height``). Until 2026-12-03 a
    singularity challenge's tool height on it was its z, a horizontal: a fold with the tool 1.47 m above the floor
    was refused as "tool below 500 mm", and one with the tool under the floor could pass."""
    desk = Arm.preset("three_dof")
    task = C.Challenge("Fold, tool up", "singularity", "three_dof", "Fold it.", factor="fold", min_tool_height=0.5)
    folded = np.radians([-60.0, 30.0, 30.0])  # θ3 = θ2: the forearm back along the upper arm
    tool = desk.fk(folded)[:3, 3]
    assert tool[2] < 0 and 1.4 < tool[1] + 1.5
    assert C.check(task, desk, C.Answer(q=folded)).solved
    high = C.Challenge("Fold, tool high", "singularity", "three_dof", "Fold it.", factor="fold", min_tool_height=3.0)
    assert C.check(high, desk, C.Answer(q=folded)).group == "tool below 3000 mm"
    q = C.singular_pose(desk, "fold", 3.0)  # the answer: high enough up its own vertical
    assert desk.fk(q)[1, 3] + 1.5 >= 3.0 and C.check(high, desk, C.Answer(q=q)).solved


@pytest.mark.parametrize("name", Arm.PRESETS)
def test_a_singular_pose_exists_for_every_factor_of_every_arm(name):
    arm = Arm.preset(name)
    for k, factor in enumerate(arm.factor_names):
        if name.startswith("cylindrical") and factor == "reach":  # d3 = 0 is beyond the stroke (0.1 to 0.6 m): refused
            with pytest.raises(ValueError, match="within its limits"):
                C.singular_pose(arm, factor)
            continue
        q = C.singular_pose(arm, factor)
        assert arm.within_limits(q)
        assert abs(arm.singularity_factors(q)[k]) <= 1e-9 * C.factor_scales(arm)[k]
        assert arm.manipulability(q) <= 1e-6  # det J itself vanishes there: an independent view of the same claim


@pytest.mark.parametrize("name", [name for name in Arm.PRESETS if name != "cylindrical"])  # its only one: refused
def test_a_singularity_challenges_answer_moves_the_arm_from_home_as_little_as_a_button_does(name):
    """The answer shown at a singularity challenge's end, for every arm and factor, is where *Put the arm on
    the …* takes the arm from its home pose (one joint turned, or two where one cannot), not wherever a search
    of its own ended up."""
    arm = Arm.preset(name)
    for factor in arm.factor_names:
        if name.startswith("cylindrical") and factor == "reach":  # refused: d3 = 0 is beyond the stroke
            continue
        challenge = C.Challenge(f"{factor} singularity", "singularity", name, "Find one.", factor=factor)
        q, _ = C.solution(challenge, arm)
        np.testing.assert_allclose(q, arm.singular_configuration(factor, arm.specs.home), atol=1e-12)
        assert np.count_nonzero(np.abs(q - arm.specs.home) > 1e-12) <= 2


# ---------------------------------------------------------------------- branch count


def test_branch_count_agrees_with_the_reach_map():
    task = by_title("Four branches only")
    start = COURSE.fk(task.joints)
    grid = branch_count_map(COURSE, start, resolution=40)
    points, seen = grid.points(), set()
    for (i, j), count in np.ndenumerate(grid.counts):
        if count in seen:
            continue
        seen.add(int(count))
        T = start.copy()
        T[:3, 3] = points[i, j]
        verdict = C.check(task, COURSE, C.Answer(target=T))
        assert verdict.solved == (count == 4), (count, verdict)
        if count != 4:
            assert verdict.group == f"{count} branches instead of 4"
    assert {0, 4, 8} <= seen
    turned = start @ np.diag([1.0, -1.0, -1.0, 1.0])
    assert C.check(task, COURSE, C.Answer(target=turned)).group == "target turned"


def test_one_branch_is_one_branch_on_the_projector():
    """A SCARA target only one branch reaches, where the task asks for both ("1 branches instead of 2")."""
    scara = Arm.preset("scara")
    task = C.Challenge("both", "branch_count", "scara", "", count=2)
    targets = scara.fk(scara.sample_joints(500, seed=3))
    targets[:, :3, :3] = scara.fk(scara.specs.home)[:3, :3]  # the task's orientation: its arm's at home
    solutions = scara.ik(targets)
    one = targets[np.flatnonzero((solutions.valid & solutions.within_limits).sum(axis=-1) == 1)[0]]
    verdict = C.check(task, scara, C.Answer(target=one))
    assert (verdict.group, verdict.message) == ("1 branch instead of 2", "1 branch reaches your target; the task asks for 2.")


# ---------------------------------------------------------------------- DH table


@pytest.mark.parametrize("name", ["ur10", "kr210", "stanford", "elbow", "cylindrical_wrist"])
def test_a_dh_table_in_either_convention_is_right_and_a_flipped_alpha_is_named(name):
    arm = COURSE if name == "ur10" else Arm.preset(name)
    task = C.Challenge("dh", "dh_table", name, "")
    for convention in ("standard", "modified"):
        table = arm.dh.converted(convention)
        assert C.check(task, arm, C.Answer(table=table)).solved
        rows = list(table.rows)
        k = next(k for k, row in enumerate(rows) if abs(math.sin(row.alpha)) > 0.5)
        row = rows[k]
        rows[k] = (row.a, -row.alpha, row.d, row.theta, row.joint)
        verdict = C.check(task, arm, C.Answer(table=DHTable(rows, convention)))
        assert not verdict.solved and verdict.group == f"row {k + 1}: α has the wrong sign"
        assert f"Row {k + 1}'s α has the wrong sign" in verdict.message


def test_a_dh_table_with_lengths_in_metres_or_other_joints():
    arm = COURSE
    task = by_title("Type the UR10's DH table")
    rows = list(arm.dh.rows)
    k = next(k for k, row in enumerate(rows) if row.d)
    rows[k] = (rows[k].a, rows[k].alpha, rows[k].d / 1000, rows[k].theta, rows[k].joint)
    assert C.check(task, arm, C.Answer(table=DHTable(rows, arm.dh.convention))).group == f"row {k + 1}: d is in metres where mm are asked"
    assert C.check(task, arm, C.Answer(table=Arm.preset("stanford").dh)).group == "wrong joints"


# ---------------------------------------------------------------------- numbers


def test_numbers_against_independent_closed_forms():
    position, det_j, torque = (by_title(t) for t in ("Where is the flange?", "det J by hand", "Holding a weight"))
    # p of T06 from the DH table's own product of matrices (not the UR family's closed form)
    assert np.allclose(C.expected_numbers(position, COURSE), 1000 * COURSE.dh.fk(position.joints)[:3, 3])
    # det J = a2 a3 (a2 c2 + a3 c23 − d5 s234) s3 s5 (docs/kinematics.md §5), with the course's own signs
    q = np.array(det_j.joints)
    factors = COURSE.singularity_factors(q)
    det = float(np.linalg.det(COURSE.dh.jacobian(q)))
    assert math.isclose(C.expected_numbers(det_j, COURSE)[0], det, rel_tol=1e-9)
    assert math.isclose(abs(det), abs(COURSE.a2 * COURSE.a3 * np.prod(factors)), rel_tol=1e-9)
    # τ = Jᵀ F by virtual work: τ_i is the force times how fast the flange moves with joint i (finite differences)
    q = np.array(torque.joints)
    step = 1e-6
    rates = [(COURSE.fk(q + step * e)[:3, 3] - COURSE.fk(q - step * e)[:3, 3]) / (2 * step) for e in np.eye(6)]
    assert np.allclose(C.expected_numbers(torque, COURSE), [np.dot(torque.force, v) for v in rates], atol=1e-6)


def test_numbers_name_the_kind_of_mistake():
    position = by_title("Where is the flange?")
    p = C.expected_numbers(position, COURSE)
    cases = {
        "y has the wrong sign": p * [1, -1, 1],
        "x and y swapped": p[[1, 0, 2]],
        "x, y, z are in metres, not mm": p / 1000,
        "z is off": p + [0, 0, 50],
        "2 numbers off": p * [-1, 1, 1.5],
        # T05's origin, P5 = p − d6 z6 (docs §4.1): the product of the link transforms stopped one short
        "the last transform left out": 1000 * (COURSE.fk(position.joints)[:3, 3] - COURSE.d6 * COURSE.fk(position.joints)[:3, 2]),
    }
    for group, typed in cases.items():
        verdict = C.check(position, COURSE, C.Answer(numbers=typed))
        assert not verdict.solved and verdict.group == group, (group, verdict.group)
    # a name keeps its case where it starts the message: "X" and "Τ1" (a capital tau) named other quantities
    assert C.check(position, COURSE, C.Answer(numbers=p + 50)).message == "x is off; y is off; z is off (each within 1 %)."
    torque = by_title("Holding a weight")
    message = C.check(torque, COURSE, C.Answer(numbers=1000 * C.expected_numbers(torque, COURSE))).message
    assert message.startswith("τ2 is 1000 times too big; τ3 "), message  # (τ1 and τ6 hold next to nothing here)
    # J [F; M] typed for Jᵀ [F; M], J from the DH table's own product (not the UR family's closed form)
    slip = COURSE.dh.jacobian(np.array(torque.joints)) @ np.r_[torque.force, torque.moment]
    assert C.check(torque, COURSE, C.Answer(numbers=slip)).group == "J [F; M], not Jᵀ [F; M]"
    assert C.check(position, COURSE, C.Answer(numbers=p * 1.009)).solved  # within 1 %
    # a number rounded to fewer places than 1 % needs is named as such, not "off" as if the method were wrong:
    # τ4 = 11.57 N·m typed as 12, τ5 = −9.22 as −9 (until 2026-12-07 "τ4 is off; τ5 is off")
    tau = C.expected_numbers(torque, COURSE)
    rounded = [round(tau[0]), round(tau[1], 1), round(tau[2], 1), round(tau[3]), round(tau[4]), round(tau[5], 1)]
    verdict = C.check(torque, COURSE, C.Answer(numbers=rounded))
    assert verdict.group == "τ4, τ5 are rounded too far: give another digit", verdict.group
    assert C.check(torque, COURSE, C.Answer(numbers=[round(t, 1) for t in tau])).solved  # one place is enough here
    off = list(tau)
    off[3] = 12.5  # beyond half a unit of its last place: off, as before
    assert C.check(torque, COURSE, C.Answer(numbers=off)).group == "τ4 is off"
    off[3] = 0.0  # a zero is what the student means, not a rounding
    assert C.check(torque, COURSE, C.Answer(numbers=off)).group == "τ4 is off"
    with pytest.raises(ValueError, match="type 3 numbers"):
        C.check(position, COURSE, C.Answer(numbers=p[:2]))


def test_the_tool_velocity_on_the_courses_path_is_the_time_derivative_of_where_the_tool_is():
    """The course's velocity exercise as numbers (docs §8.6): v at t = 4 s against the central difference in t
    of the course's own position map along its path, p(θ(t)), written out in the test; rates in °/s read as
    rad/s are named; a sign flipped everywhere is not taken for a swap; the file keys go together."""
    challenge, arm = by_title("Desktop arm: tool velocity"), Arm.preset("three_dof")
    l5, l1, h = UPPER_ARM, FOREARM, 1e-6

    def course_position(t: float) -> np.ndarray:  # θ(t) as the course drives it, then p(θ) as the course writes it
        t1 = t2 = math.pi / 6 * math.sin(t)
        t3 = 3 * math.pi / 4 + math.pi / 8 * math.sin(t)
        reach = l1 * math.cos(t3) - l5 * math.cos(t2)
        return np.array([math.cos(t1) * reach, l1 * math.sin(t3) - l5 * math.sin(t2), -math.sin(t1) * reach])

    v = 1000 * (course_position(4.0 + h) - course_position(4.0 - h)) / (2 * h)
    np.testing.assert_allclose(C.expected_numbers(challenge, arm), v, atol=1e-4)
    assert C.number_names(challenge, arm) == ("vx", "vy", "vz") and C.check(challenge, arm, C.Answer(numbers=v)).solved
    degrees = 1000 * arm.tool_twist(np.array(challenge.joints), np.degrees(challenge.rates))[:3]
    for typed, group in ((degrees, "joint rates in °/s taken as rad/s"), (-v, "vx, vy, vz have the wrong sign"),
                         (v[[1, 0, 2]], "vx and vy swapped"), (v / 1000, "vx, vy, vz are 1000 times too small")):
        verdict = C.check(challenge, arm, C.Answer(numbers=typed))
        assert not verdict.solved and verdict.group == group, (group, verdict)
    head = '[[challenge]]\ntitle = "v"\nkind = "numbers"\narm = "three_dof"\njoints = [0, 0, 90]\n'
    assert C.parse(head + 'quantity = "tool_velocity"\nrates_deg_s = [10, 0, 0]\n')[0].rates == pytest.approx((math.radians(10), 0, 0))
    for tail, line in (('quantity = "tool_velocity"\n', 6), ('quantity = "position"\nrates_deg_s = [10, 0, 0]\n', 7)):
        with pytest.raises(ValueError, match=f"line {line}: tool_velocity needs the joint rates"):
            C.parse(head + tail)


def test_holding_itself_up_is_roboticstoolboxs_gravload_and_its_slips_are_named():
    """The joint torques that hold the UR10 against its weight and a payload (docs §8.5) against
    roboticstoolbox-python's gravload for its DH UR10 (UR's masses, the controller's angles); the sign
    flipped, the masses without g and the payload left out are named; the file's keys are checked."""
    import roboticstoolbox as rtb  # test-only reference

    from ur10core.controller import CONTROLLER_OFFSET

    challenge, arm = by_title("Holding itself up"), Arm.preset("ur10")
    robot = rtb.models.DH.UR10()
    q = np.array(challenge.joints) + CONTROLLER_OFFSET
    robot.payload(challenge.payload, [0.0, 0.0, 0.0])
    loaded = robot.gravload(q)
    robot.payload(0.0, [0.0, 0.0, 0.0])
    alone = robot.gravload(q)
    assert challenge.payload == 5.0 and loaded[1] > 150  # stretched out level: the shoulder holds the most
    np.testing.assert_allclose(C.expected_numbers(challenge, arm), loaded, atol=1e-9)
    assert C.check(challenge, arm, C.Answer(numbers=loaded)).solved
    for typed, group in ((-loaded, "gravity's torques, not the holding ones"), (loaded / 9.81, "masses, not weights"),
                         (alone, "the payload left out"), (loaded * [1, 1, 1.1, 1, 1, 1], "τ3 is off")):
        verdict = C.check(challenge, arm, C.Answer(numbers=typed))
        assert not verdict.solved and verdict.group == group, (group, verdict)
    # worked by hand from what the student reads on each preset (the readouts that gave it are off while it runs):
    # the terms' masses, centres of mass and axis points, the text's axis directions, the payload at the flange
    # (the arm's FK). Until 2026-12-04 the text gave the UR10's axes in numbers, and the terms its masses on any preset
    directions = {1: (0, 0, 1), 2: (0, -1, 0), 3: (0, -1, 0), 4: (0, -1, 0), 5: (1, 0, 0), 6: (0, -1, 0)}
    assert "Joint 1 turns about z; joints 2, 3 and 4 about −y; joint 5 about x; joint 6 about −y" in challenge.text
    for preset in ("ur10", "course", "ur10e"):
        arm = Arm.preset(preset)
        words = C.terms(challenge, arm)
        masses = [float(m) for m in re.search(r"links of \(([^)]*)\) kg", words).group(1).split(", ")]
        points = [np.array([float(v) for v in point.split(", ")]) / 1000
                  for point in re.findall(r"\((-?[\d.]+, -?[\d.]+, -?[\d.]+)\)", words.split("centres of mass at")[1])]
        where, through = points[:6] + [arm.fk(challenge.joints)[:3, 3]], points[6:]
        assert len(masses) == len(where) - 1 == len(through) == 6 and "g = 9.81 m/s²" in words
        weights = 9.81 * np.array([*masses, challenge.payload])
        by_hand = [sum(w * np.dot(directions[i], np.cross(p - through[i - 1], [0.0, 0.0, 1.0]))  # (gravity's opposite)
                       for w, p in zip(weights[i - 1:], where[i - 1:])) for i in directions]
        verdict = C.check(challenge, arm, C.Answer(numbers=by_hand))
        assert verdict.solved, (preset, by_hand, verdict)
        np.testing.assert_allclose(by_hand, C.expected_numbers(challenge, arm), rtol=2e-3, atol=0.05)
    head = '[[challenge]]\ntitle = "g"\nkind = "numbers"\njoints = [0, 0, 0, 0, 0, 0]\n'
    assert C.parse(head + 'quantity = "gravity_torque"\n')[0].payload == 0.0
    for tail, line, words in (('quantity = "gravity_torque"\npayload_kg = 11\n', 6, "payload_kg must be a number from 0 to 10"),
                              ('quantity = "position"\npayload_kg = 1\n', 6, "payload_kg is used by gravity_torque only"),
                              ('quantity = "gravity_torque"\narm = "kr210"\n', 5, "known for course, ur10, ur10e, not for 'kr210'"),
                              # not "payload_kg must be a number from 0 to 0": the arm has no masses to hold it with
                              ('quantity = "gravity_torque"\npayload_kg = 2\narm = "kr210"\n', 5, "known for course, ur10")):
        with pytest.raises(ValueError, match=f"line {line}: .*{words}"):
            C.parse(head + tail)


@pytest.mark.parametrize("name", ["course", "ur10", "ur10e"])
def test_det_j_by_hand_names_the_constant_left_out_and_lengths_in_mm(name):
    """The course's det J = a2·a3·(a2 c2 + a3 c23 − d5 s234)·s3·s5 (docs §5), written out here: the three factors'
    product alone is "a2·a3 left out", and the same lengths in mm (det J in m³) "lengths in mm, not metres"."""
    challenge, arm = by_title("det J by hand"), Arm.preset(name)
    t1, t2, t3, t4, t5, t6 = challenge.joints
    factors = ((arm.a2 * math.cos(t2) + arm.a3 * math.cos(t2 + t3) - arm.d5 * math.sin(t2 + t3 + t4))
               * math.sin(t3) * math.sin(t5))
    det = C.expected_numbers(challenge, arm)[0]
    assert det == pytest.approx(arm.a2 * arm.a3 * factors, rel=1e-12)
    for typed, group in ((factors, "a2·a3 left out"), (1e9 * det, "lengths in mm, not metres"),
                         (-det, "det J has the wrong sign"), (1.5 * det, "det J is off")):
        verdict = C.check(challenge, arm, C.Answer(numbers=[typed]))
        assert not verdict.solved and verdict.group == group, (typed, verdict)


#: The rows of J each arm's det J is over (docs §7.6), written out: all six for a wrist; v and ω_z for the SCARA;
#: v for the cylindrical arm; the plane's v_x, v_y for the planar elbow.
SQUARE_ROWS = {"kr210": [0, 1, 2, 3, 4, 5], "elbow": [0, 1, 2, 3, 4, 5], "stanford": [0, 1, 2, 3, 4, 5],
               "cylindrical_wrist": [0, 1, 2, 3, 4, 5], "scara": [0, 1, 2, 5], "cylindrical": [0, 1, 2],
               "planar_elbow": [0, 1]}


@pytest.mark.parametrize("name", [*SQUARE_ROWS, "three_dof"])
def test_det_j_as_numbers_on_every_arm_is_its_square_jacobians(name):
    """det J was asked of J's six rows whatever the arm: on a 2-, 3- or 4-joint arm the check raised numpy's
    "Last 2 dimensions of the array must be square". Against the DH table's own Jacobian over the rows
    written out above, and the desktop arm's against the course's det J_v (docs §8.6)."""
    arm = Arm.preset(name)
    q = arm.sample_joints(5, seed=4)[2]
    if name == "three_dof":
        _, t2, t3 = q
        det = -FOREARM * UPPER_ARM * (FOREARM * math.cos(t3) - UPPER_ARM * math.cos(t2)) * math.sin(t2 - t3)
    else:
        det = float(np.linalg.det(arm.dh.jacobian(q)[SQUARE_ROWS[name]]))
    challenge = C.Challenge("d", "numbers", name, "", joints=tuple(q.tolist()), quantity="det_j")
    assert C.expected_numbers(challenge, arm)[0] == pytest.approx(det, rel=1e-9) and abs(det) > 1e-6
    assert C.check(challenge, arm, C.Answer(numbers=[det])).solved
    assert C.check(challenge, arm, C.Answer(numbers=[-det])).group == "det J has the wrong sign"
    assert C.terms(challenge).startswith("Given: q = (") and C.solution(challenge, arm)[1].startswith("The answer: det J = ")


@pytest.mark.parametrize("name", C.PRESETS)
def test_det_j_on_a_singularity_is_answered_by_zero(name):
    """A teacher puts the class's arm on a singularity with its button and asks *Pose shown: det J*. There det J is
    zero to rounding (1e-20 to 1e-15 m³), and the right answer, 0, was "det J is off" on 17 of the 23 (until
    2026-12-06): a number was judged within 1 % of itself. A number near zero is judged against its usual size.
    Worked from the joints as written (two decimals), the answer is right too; the home pose's det J is not. The
    class is shown 0 at the end, not the rounding (5.49852e-18)."""
    arm = Arm.preset(name)
    home = arm.det_jacobian(arm.specs.home)
    for factor in arm.factor_names:
        try:
            challenge = C.about_the_pose("Pose shown: det J", arm, arm.singular_configuration(factor, arm.specs.home))
        except ValueError:  # the cylindrical arms' reach: no such pose within the limits
            continue
        assert abs(C.expected_numbers(challenge, arm)[0]) < 1e-14
        written = np.where(arm.revolute, np.radians(np.round(np.degrees(challenge.joints), 2)),
                           np.round(1000 * np.array(challenge.joints), 2) / 1000)
        for typed in (0.0, arm.det_jacobian(written)):
            assert C.check(challenge, arm, C.Answer(numbers=[typed])).solved, (factor, typed)
        assert C.solution(challenge, arm)[1] == "The answer: det J = 0"  # the class is shown 0, not 5.49852e-18
        assert not C.check(challenge, arm, C.Answer(numbers=[home])).solved and abs(home) > 0.01


def test_numbers_that_are_zero_to_rounding_are_answered_by_zeros():
    """The same for the other quantities: wrist 3 alone moves the tool at 0 mm/s, and a force straight down on the
    UR10 held straight up passes through every joint's axis (τ = 0 to rounding, 6e-15 N·m); 0.1 N·m is still off."""
    still = C.Challenge("v", "numbers", "ur10", "", joints=tuple(np.radians([30, 45, 26, 50, 60, 80])),
                        quantity="tool_velocity", rates=(0.0, 0.0, 0.0, 0.0, 0.0, 0.5))
    assert np.abs(C.expected_numbers(still, COURSE)).max() < 1e-12
    assert C.check(still, COURSE, C.Answer(numbers=[0.0, 0.0, 0.0])).solved
    upright = C.Challenge("t", "numbers", "ur10", "", joints=tuple(np.radians([0, 90, 0, 90, 0, 0])), quantity="torque",
                          force=(0.0, 0.0, -100.0))
    assert 0 < np.abs(C.expected_numbers(upright, COURSE)).max() < 1e-12
    assert C.check(upright, COURSE, C.Answer(numbers=np.zeros(6))).solved
    assert C.solution(upright, COURSE)[1] == "The answer: " + ", ".join(f"τ{k} = 0" for k in range(1, 7))
    for k in range(6):
        assert not C.check(upright, COURSE, C.Answer(numbers=0.1 * (np.arange(6) == k))).solved


def test_both_shoulders_theta1_are_the_iks_and_their_mistakes_are_named():
    """IK step 1 as numbers (docs §4.1): both θ1 against the IK's own slots (left: 1–4, right: 5–8) on the UR family;
    angles equal a turn apart; the shoulders swapped, a sign and radians are named; another arm is refused in a file."""
    challenge = by_title("IK step 1: both shoulders")
    for arm in (COURSE, Arm.preset("ur10"), Arm.preset("ur10e")):
        solution = arm.ik(arm.fk(challenge.joints))
        expected = C.expected_numbers(challenge, arm)
        for side in (0, 1):
            shoulder = solution.q[4 * side: 4 * side + 4, 0][solution.valid[4 * side: 4 * side + 4]]
            assert len(shoulder) and np.allclose(np.radians(expected[side]), shoulder, atol=1e-9)
    left, right = C.expected_numbers(challenge, COURSE)
    assert right == pytest.approx(30.0) and C.number_names(challenge, COURSE) == ("θ1 left", "θ1 right")
    assert C.check(challenge, COURSE, C.Answer(numbers=[left + 360.0 + 1.0, right - 360.0])).solved  # within 1.8°
    cases = {
        "θ1 left and θ1 right swapped": [right, left],
        "θ1 left has the wrong sign": [-left, right],
        "θ1 right is in radians, not degrees": [left, math.radians(right)],
        "θ1 left is off": [left + 5.0, right],
    }
    for group, typed in cases.items():
        verdict = C.check(challenge, COURSE, C.Answer(numbers=typed))
        assert not verdict.solved and verdict.group == group, (group, verdict.group)
    assert verdict.message == "θ1 left is off (each within 1.8°)."
    # step 1 done on the flange's p instead of P5: the roots of p_y c1 − p_x s1 = −d4, ρ sin(φ − θ1) = −d4
    p, d4 = COURSE.fk(challenge.joints)[:3, 3], COURSE.solver.dh_lengths[3]
    phi, off = math.atan2(p[1], p[0]), math.asin(d4 / math.hypot(p[0], p[1]))
    roots = np.degrees([phi + off, phi + math.pi - off])
    groups = {C.check(challenge, COURSE, C.Answer(numbers=typed)).group for typed in (roots, roots[::-1])}
    apart = np.abs((roots[:, None] - [left, right] + 180.0) % 360.0 - 180.0)
    assert "θ1 from p, not from P5" in groups and apart.min() > 2.0  # a slip a student can make: not the answer itself
    text = GOOD.replace('kind = "reach"', 'kind = "numbers"\nquantity = "theta1"').replace('branch = "wrist flipped"\n', "")
    text = text.replace("position_tolerance_mm = 3", "relative_tolerance = 0.01")
    with pytest.raises(ValueError, match="line 5: theta1 is a step of the UR family's IK"):
        C.parse(text, source="class.toml")
    numbers, _ = C.parse(text.replace('arm = "kr210"', 'arm = "ur10"'))
    assert numbers.quantity == "theta1"


def meeting_point(z: np.ndarray, o: np.ndarray) -> np.ndarray:
    """The point nearest every line through o_k along z_k (k rows), by least squares: Σ (I − z zᵀ)(x − o) = 0."""
    projections = np.eye(3) - z[:, :, None] * z[:, None, :]
    return np.linalg.solve(projections.sum(axis=0), np.einsum("kij,kj->i", projections, o))


@pytest.mark.parametrize("name", ["kr210", "elbow", "stanford", "cylindrical_wrist"])
def test_the_wrist_centre_is_where_the_wrist_axes_meet_and_its_slips_are_named(name):
    """Decoupling's step 1 as numbers (docs §7.3): WC against the point where the last three joint axes meet, found
    from the DH frames alone; the tool's p and the offset taken the wrong way are named; an arm without a
    spherical wrist is refused in a file, with why."""
    arm = Arm.preset(name)
    for q in arm.sample_joints(20, seed=8):
        text = ", ".join(f"{v:.9f}" for v in np.where(arm.revolute, np.degrees(q), 1000 * q))
        challenge = C.parse(f'[[challenge]]\ntitle = "t"\nkind = "numbers"\narm = "{name}"\njoints = [{text}]\n'
                            'quantity = "wrist_centre"\n')[0]
        z, o = arm.dh.joint_axes(arm.dh.frames(challenge.joints))
        centre = meeting_point(z[-3:], o[-3:])
        assert np.linalg.norm(np.cross(centre - o[-3:], z[-3:]), axis=-1).max() < 1e-9  # on all three axes
        np.testing.assert_allclose(C.expected_numbers(challenge, arm), 1000 * centre, atol=1e-6)
    assert C.number_names(challenge, arm) == ("x", "y", "z")
    T, wc = arm.fk(challenge.joints), C.expected_numbers(challenge, arm)
    if np.linalg.norm(1000 * T[:3, 3] - wc) > 50:  # a tool beyond the wrist centre
        slips = {"p of the tool, not WC": 1000 * T[:3, 3], "the tool's offset taken the wrong way": 2000 * T[:3, 3] - wc}
        for group, typed in slips.items():
            verdict = C.check(challenge, arm, C.Answer(numbers=typed))
            assert not verdict.solved and verdict.group == group, (group, verdict)


def test_the_kr210s_wrist_centre_is_303_mm_back_along_the_gripper():
    challenge = by_title("KR210: its wrist centre")
    arm = Arm.preset("kr210")
    T = arm.fk(challenge.joints)
    wc = C.expected_numbers(challenge, arm)
    np.testing.assert_allclose(wc, 1000 * (T[:3, 3] - 0.303 * T[:3, 2]), atol=1e-9)  # the course's WC = p − 0.303 z
    verdict = C.check(challenge, arm, C.Answer(numbers=1000 * T[:3, 3]))
    assert verdict.message == "That is p, where the tool is: WC is 303 mm back along the tool's z."
    assert C.check(challenge, arm, C.Answer(numbers=wc / 1000)).group == "x, y, z are in metres, not mm"
    for other in ("ur10", "scara"):
        text = f'[[challenge]]\ntitle = "t"\nkind = "numbers"\narm = "{other}"\njoints = [0, 0, 0, 0]\nquantity = "wrist_centre"\n'
        if other == "ur10":
            text = text.replace("[0, 0, 0, 0]", "[0, 0, 0, 0, 0, 0]")
        with pytest.raises(ValueError, match="line 6: wrist_centre is a step of decoupling, and the .* arm has no spherical wrist"):
            C.parse(text)


# ---------------------------------------------------------------------- velocity


@pytest.mark.parametrize("name", C.PRESETS)
def test_a_velocity_task_is_one_the_sliders_can_do_and_the_answer_shown_does_it(name):
    """The answer shown at the end was the least-squares rates of (v, 0): on the desktop arm and the planar elbow,
    which cannot hold ω at 0, it moved the tool 16 and 77 mm/s off the asked v. It is now solved from J_v where
    the tool may turn. A velocity no pose gives with the sliders' rates is refused at start: along the planar
    elbow's axis, or 20 m/s."""
    arm = Arm.preset(name)
    asked = [100, 0, 0] if name == "planar_elbow" else [0, 0, 100]
    head = f'[[challenge]]\ntitle = "v"\nkind = "velocity"\narm = "{name}"\n'
    challenge, = C.parse(head + f"velocity_mm_s = {asked}\n")
    # at a singularity (each factor's, and the arm's zero pose) no rates at the student's pose give the velocity: the
    # answer shown was damped least squares there, which missed it by up to 100 mm/s; the arm now goes where some do
    singular = []
    for factor in arm.factor_names:
        with contextlib.suppress(ValueError):  # (the cylindrical arms' stroke never reaches 0 within its limits)
            singular.append(C.singular_pose(arm, factor))
    for q in (arm.specs.home, *arm.sample_joints(3, seed=5), *singular, np.clip(np.zeros(arm.n_joints), *arm.limits.T)):
        moved, words = C.solution(challenge, arm, q)
        at = q if moved is None else moved
        assert (moved is None) == words.startswith("At your pose, one answer"), words
        shown = np.array([float(v) for v in re.search(r"q̇ = \(([^)]*)\)", words).group(1).split()])
        rates = np.where(arm.revolute, np.radians(shown), shown / 1000)  # as typed into the sliders, to 0.1
        assert C.check(challenge, arm, C.Answer(q=at, rates=rates)).solved, (np.degrees(q), words)
    impossible = [0, 0, 100] if name == "planar_elbow" else [20_000, 0, 0]
    with pytest.raises(ValueError, match="line 5: no pose of the .* arm within its limits moves the tool so with joint rates"):
        C.parse(head + f"velocity_mm_s = {impossible}\n")


def test_velocity_groups():
    task = by_title("Straight up")
    q = COURSE.specs.home
    right = COURSE.joint_rates(q, [0, 0, 0.1, 0, 0, 0]).qdot
    assert C.check(task, COURSE, C.Answer(q=q, rates=right)).solved
    assert C.check(task, COURSE, C.Answer(q=q, rates=-right)).group == "wrong sign"
    assert C.check(task, COURSE, C.Answer(q=q, rates=0 * right)).group == "not moving"
    assert C.check(task, COURSE, C.Answer(q=q, rates=2 * right)).group == "too fast"
    sideways = COURSE.joint_rates(q, [0.1, 0, 0, 0, 0, 0]).qdot
    assert C.check(task, COURSE, C.Answer(q=q, rates=sideways)).group == "wrong direction"
    turning = COURSE.joint_rates(q, [0, 0, 0.1, 0, 0, 0.1]).qdot
    verdict = C.check(task, COURSE, C.Answer(q=q, rates=turning))
    assert verdict.group == "tool turns" and "5.7 °/s" in verdict.message


# ---------------------------------------------------------------------- largest torque


@pytest.mark.parametrize("name, force, largest", [
    # the desktop arm (y up): pushed sideways, the base holds it all, both links stretched across the force
    ("three_dof", (20.0, 0.0, 0.0), 20.0 * (UPPER_ARM + FOREARM)),
    ("three_dof", (0.0, 0.0, -7.0), 7.0 * (UPPER_ARM + FOREARM)),
    # pushed down, the parallelogram decouples the links: F l5 cos θ2 and F l1 cos θ3, each largest level
    ("three_dof", (0.0, -10.0, 0.0), 10.0 * math.hypot(UPPER_ARM, FOREARM)),
    # the planar elbow, in its plane: τ1 = F (a1 s1 + a2 s12) and τ2 = F a2 s12, both largest across the force
    ("planar_elbow", (3.0, -4.0, 0.0), None),
])
def test_the_largest_torque_is_the_closed_forms_and_no_sampled_pose_beats_it(name, force, largest):
    arm = Arm.preset(name)
    if largest is None:
        a1, a2 = (row.a for row in arm.dh.rows)
        largest = np.linalg.norm(force) * math.hypot(a1 + a2, a2)
    text = " ".join(f"{v:g}" for v in force)
    task = C.parse(f'[[challenge]]\ntitle = "t"\nkind = "largest_torque"\narm = "{name}"\nforce_n = [{text.replace(" ", ", ")}]\n')[0]
    worst = C.worst_pose(task, arm)
    assert worst.norm == pytest.approx(largest, rel=1e-9) and arm.within_limits(worst.q)
    np.testing.assert_allclose(worst.torques, arm.static_torques(worst.q, force), atol=1e-12)
    low, high = arm.limits.T
    sampled = np.linalg.norm(arm.static_torques(np.random.default_rng(4).uniform(low, high, (50_000, arm.n_joints)), force), axis=-1)
    assert sampled.max() <= worst.norm * (1 + 1e-12)
    q, words = C.solution(task, arm)
    assert np.array_equal(q, worst.q) and f"{largest:.2f} N·m" in words
    assert C.check(task, arm, C.Answer(q=worst.q)).solved


def test_the_heaviest_pose_groups_say_how_close():
    task = by_title("Desktop arm: heaviest pose")
    arm = Arm.preset("three_dof")
    assert task.is_pose and "20 N along +x" in task.text
    verdicts = {q: C.check(task, arm, C.Answer(q=np.radians(q))) for q in
                ((0, 0, 90), (30, 0, 120), (80, 0, 170), (-89, 2, 178), (95, 0, 0))}
    assert verdicts[(0, 0, 90)].group == "under half the largest"  # only the upper arm is across it: 1.35 / 2.63
    assert "49 % of the most" in verdicts[(0, 0, 90)].message
    assert verdicts[(30, 0, 120)].group == "half to 90 % of the largest"
    assert verdicts[(80, 0, 170)].group == "over 90 % of the largest"
    assert verdicts[(-89, 2, 178)].solved  # within 1 %
    assert verdicts[(95, 0, 0)].group == "beyond the joint ranges"
    assert "‖τ‖ 52.56 N·m" in verdicts[(-89, 2, 178)].answer


@pytest.mark.parametrize("table, words", [
    ('arm = "ur10"\nforce_n = [0, 0, -10]', "at most 3 joints, all revolute (planar_elbow, three_dof), got 'ur10'"),
    ('arm = "cylindrical"\nforce_n = [0, 0, -10]', "all revolute"),  # ‖τ‖ would add N·m to N
    ('arm = "three_dof"\nforce_n = [0, 0, 0]', "must not be zero"),
    ('arm = "planar_elbow"\nforce_n = [0, 0, 5]', "needs no torque in any pose"),  # along its joints' axes
    ('arm = "three_dof"', "needs 'force_n'"),
    ('arm = "three_dof"\nforce_n = [1, 0, 0]\njoints = [0, 0, 90]', "'joints' is not used by a largest_torque"),
])
def test_a_largest_torque_challenge_must_be_searchable_and_need_torque(table, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        C.parse(f'[[challenge]]\ntitle = "t"\nkind = "largest_torque"\n{table}\n')


# ---------------------------------------------------------------------- files


GOOD = textwrap.dedent("""\
    # a teacher's file
    [[challenge]]
    title = "Reach it"
    kind = "reach"
    arm = "kr210"
    joints = [10, 20, -30, 40, 50, 60]
    branch = "wrist flipped"
    position_tolerance_mm = 3

    [[challenge]]
    title = "Stroke"
    kind = "singularity"
    arm = "stanford"
    factor = "wrist"
    time_limit_s = 120
    """)


TERSE = textwrap.dedent("""\
    [[challenge]]
    title = "a"
    kind = "reach"
    arm = "kr210"
    joints = [10, 20, -30, 40, 50, 60]
    branch = 2
    position_tolerance_mm = 12
    orientation_tolerance_deg = 7
    [[challenge]]
    title = "b"
    kind = "singularity"
    factor = "wrist"
    factor_tolerance = 0.02
    min_tool_height_mm = 300
    [[challenge]]
    title = "c"
    kind = "velocity"
    velocity_mm_s = [10, 0, -2.5]
    velocity_tolerance_mm_s = 2
    still = true
    [[challenge]]
    title = "d"
    kind = "numbers"
    joints = [0, 0, 0, 90, 0, 0]
    quantity = "torque"
    force_n = [0, 0, -100]
    moment_nm = [1, 0, 0]
    relative_tolerance = 0.05
    [[challenge]]
    title = "e"
    kind = "numbers"
    arm = "stanford"
    joints = [10, 20, 250, 30, 40, 50]
    quantity = "position"
    [[challenge]]
    title = "f"
    kind = "largest_torque"
    arm = "planar_elbow"
    force_n = [0, -30, 0]
    relative_tolerance = 0.02
    [[challenge]]
    title = "g"
    kind = "dh_table"
    arm = "scara"
    position_tolerance_mm = 20
    [[challenge]]
    title = "h"
    kind = "branch_count"
    arm = "scara"
    count = 2
    joints = [30, 60, 100, 20]
    orientation_tolerance_deg = 4
    """)


def test_the_terms_give_what_the_check_takes_whatever_the_task_says():
    """A teacher's text may be a title alone: the words under it still give the joints, the force, the branch
    and each tolerance, as the file sets them."""
    terms = [C.terms(c) for c in C.parse(TERSE)]
    assert terms[0] == ("Checked: your tool on the target, on branch 2 (shoulder front, elbow up, wrist flipped), "
                        "within 12 mm and 7°.")
    assert terms[1] == ("Checked: the wrist factor of det J zero, within 2 % of its usual size, with the tool at least "
                        "300 mm above the floor.")
    assert terms[2] == ("Checked: your joint rates, at your pose, move the tool at v = (10, 0, -2.5) mm/s, in the base "
                        "frame, within 2 mm/s, without turning (under 1 °/s).")
    assert terms[3] == ("Given: q = (0°, 0°, 0°, 90°, 0°, 0°); F = (0, 0, -100) N and M = (1, 0, 0) N·m at the tool, in "
                        f"the base frame. Asked: {C.QUANTITIES['torque']}, each within 5 %.")
    assert terms[4].startswith("Given: q = (10°, 20°, 250 mm, 30°, 40°, 50°). Asked: p of the tool frame")
    assert terms[5] == ("Given: F = (0, -30, 0) N at the tool, in the base frame. Checked: your joints, within their "
                        "ranges, need ‖τ‖ = ‖J_vᵀ F‖ within 2 % of the largest any pose needs.")
    assert terms[6].endswith("the tool frame within 2 mm.")  # the table's tool within a tenth of the tolerance
    assert terms[7] == ("Checked: your IK target where exactly 2 branches reach within the joint limits, with the tool's "
                        "orientation at q = (30°, 60°, 100 mm, 20°), within 4° of its yaw.")
    # the planar elbow controls no orientation: none is written
    planar = TERSE.replace('arm = "kr210"\njoints = [10, 20, -30, 40, 50, 60]\nbranch = 2', 'arm = "planar_elbow"\njoints = [10, 20]')
    assert C.terms(C.parse(planar)[0]) == "Checked: your tool on the target, within 12 mm."


@pytest.mark.parametrize("challenge", [c for c in C.builtin() if c.kind == "numbers"], ids=lambda c: c.key)
def test_a_numbers_tasks_givens_as_written_are_enough_to_solve_it(challenge):
    """Joints and rates are written to two decimals: worked from them, the answer is still within the tolerance."""
    arm = arm_of(challenge)

    def given(symbol: str) -> tuple[float, ...] | None:
        found = re.search(rf"{symbol} = \(([^)]*)\)", C.terms(challenge))
        if found is None:
            return None
        shown = [float(re.sub(r"[^0-9.\-]", "", v)) for v in found.group(1).split(",")]
        return tuple(np.where(arm.revolute, np.radians(shown), np.array(shown) / 1000).tolist())

    worked = C.Challenge(**{**challenge.__dict__, "joints": given("q"), "rates": given("q̇")})
    assert worked.joints is not None and (challenge.rates is None) == (worked.rates is None)
    assert C.check(challenge, arm, C.Answer(numbers=C.expected_numbers(worked, arm))).solved


def _file_joints(arm: Arm, q: np.ndarray) -> list[float]:
    return [round(v, 6) for v in np.where(arm.revolute, np.degrees(q), 1000 * q).tolist()]


@pytest.mark.parametrize("name", C.PRESETS)
def test_every_kind_and_quantity_on_every_arm_is_refused_by_line_or_checks(name):
    """A teacher may write any kind and quantity for any arm. Each is either refused when the server starts,
    naming its line, or its terms, its solution and the check of any answer work (a numbers task's det J on a
    3-joint arm raised numpy's error at every check; a DH table task on the desktop arm, an AttributeError)."""
    arm = Arm.preset(name)
    q = arm.sample_joints(3, seed=1)[1]
    extras = {"torque": "force_n = [1, 2, 3]\n", "gravity_torque": "payload_kg = 2\n",
              "tool_velocity": f"rates_deg_s = {[10.0] * arm.n_joints}\n"}
    tables = [f'kind = "numbers"\njoints = {_file_joints(arm, q)}\nquantity = "{quantity}"\n{extras.get(quantity, "")}'
              for quantity in C.QUANTITIES]
    tables += ['kind = "largest_torque"\nforce_n = [0, 0, -10]\n', 'kind = "velocity"\nvelocity_mm_s = [10, 0, 0]\nstill = true\n',
               'kind = "dh_table"\n', 'kind = "branch_count"\ncount = 2\n', f'kind = "reach"\njoints = {_file_joints(arm, q)}\nbranch = 1\n',
               *(f'kind = "singularity"\nfactor = "{factor}"\n' for factor in arm.factor_names)]
    answers = [C.Answer(q=p, target=arm.fk(p), table=arm.dh, rates=np.ones(arm.n_joints)) for p in arm.sample_joints(3, seed=2)]
    checked = 0
    for table in tables:
        try:
            challenge, = C.parse(f'[[challenge]]\ntitle = "t"\narm = "{name}"\n{table}')
        except ValueError as refusal:
            assert re.match(r"challenges, line \d+: ", str(refusal)), str(refusal)
            continue
        assert C.terms(challenge)
        C.solution(challenge, arm)
        for answer in answers:
            if challenge.kind == "numbers":
                expected = C.expected_numbers(challenge, arm)
                for typed in (expected, np.zeros_like(expected), 2 * expected, expected[::-1]):
                    assert isinstance(C.check(challenge, arm, dataclasses.replace(answer, numbers=typed)), C.Verdict)
            else:
                assert isinstance(C.check(challenge, arm, answer), C.Verdict)
        checked += 1
    assert checked >= 6  # position, det J, torque, tool velocity, velocity, reach: every arm has them


@pytest.mark.parametrize("name", C.PRESETS)
def test_every_question_about_the_pose_shown_is_asked_at_its_joints_or_refused_saying_why(name):
    """What the presenter asks of the arm the class sees: the task is at the joints shown (the arm there, on its
    branch, solves a reach; the numbers are those of its own pose), and a question the arm cannot be asked is
    refused, saying why in the teacher's words (a file's field names, like wrist_centre, mean nothing on the desk)."""
    arm = Arm.preset(name)
    q = arm.sample_joints(5, seed=6)[3]
    slot = int(arm.ik(arm.fk(q), hint=q).nearest(q).slot)
    asked = 0
    for question in C.POSE_QUESTIONS:
        try:
            challenge = C.about_the_pose(question, arm, q)
        except ValueError as why:
            assert re.search(r"three axes meet, and this arm has none|need the arm's link masses", str(why)), (question, str(why))
            assert not re.search(r"wrist_centre|gravity_torque|decoupling", str(why)), (question, str(why))
            continue
        asked += 1
        assert challenge.title == question and np.allclose(challenge.joints, q) and C.terms(challenge)
        on_the_pose = C.Answer(q=q, numbers=C.expected_numbers(challenge, arm) if challenge.kind == "numbers" else None)
        assert C.check(challenge, arm, on_the_pose).solved
        if challenge.quantity == "position":
            np.testing.assert_allclose(C.expected_numbers(challenge, arm), 1000 * arm.fk(q)[:3, 3])
        if challenge.branch is not None:
            others = [k for k in range(len(arm.slot_labels)) if k != slot]
            other = next((k for k in others if arm.ik(arm.fk(q)).within_limits[k]), None)
            if other is not None:  # the same tool pose on another branch is not it
                assert not C.check(challenge, arm, C.Answer(q=arm.ik(arm.fk(q)).q[other])).solved
    assert asked >= 4  # reach, its branch, where the tool is, det J
    with pytest.raises(ValueError, match="question must be one of"):
        C.about_the_pose("Pose shown: dance", arm, q)


def test_a_teachers_file_is_read_in_its_units():
    reach, singular = C.parse(GOOD)
    assert reach.arm == "kr210" and np.allclose(np.degrees(reach.joints), [10, 20, -30, 40, 50, 60])
    assert reach.position_tolerance == pytest.approx(0.003) and reach.branch == "wrist flipped"
    assert singular.time_limit == 120 and singular.factor == "wrist" and singular.text == "Stroke"


def test_titles_in_any_script_are_told_apart_and_name_their_results_files():
    # every title with no letter a-z or digit had the same key, "": a second challenge in Chinese was refused as
    # "two challenges titled" the same, and Greek or Russian titles all named their results file "challenge--<date>"
    titles = ("到达目标", "奇异位形", "Ταχύτητα", "Скорость", "Übung 2: Reichweite")
    text = "".join(f'[[challenge]]\ntitle = "{t}"\nkind = "velocity"\nvelocity_mm_s = [0, 0, 100]\n' for t in titles)
    assert [c.key for c in C.parse(text)] == ["到达目标", "奇异位形", "ταχύτητα", "скорость", "übung-2-reichweite"]
    with pytest.raises(ValueError, match="line 6: two challenges titled 'Reach: it' and 'Reach it!', the same but for"):
        C.parse(text.replace(titles[0], "Reach: it").replace(titles[1], "Reach it!"))


@pytest.mark.parametrize("turn", [0, 50, 90, 120, -150])
def test_a_branch_at_a_singular_target_is_told_by_the_branch_not_by_how_the_free_joints_are_split(turn):
    """The teacher's target has θ5 = 0, where only θ4 + θ6 is fixed. A student on the asked branch with θ4 turned by
    90° and θ6 back by as much (the same pose) was told "That is the shoulder front, elbow down, wrist flipped branch":
    the check compared their joints with slots that split θ4 + θ6 as the IK chose without a hint."""
    challenge = C.parse('[[challenge]]\ntitle = "KR210 wrist"\nkind = "reach"\narm = "kr210"\n'
                        'joints = [10, 0, -30, 40, 0, 60]\nbranch = "elbow up, wrist not flipped"\n')[0]
    arm = Arm.preset("kr210")
    q = np.radians([10, 0, -30, 40 + turn, 0, 60 - turn])
    assert arm.within_limits(q) and np.allclose(arm.fk(q), arm.fk(np.array(challenge.joints)))
    verdict = C.check(challenge, arm, C.Answer(q=q, target=arm.fk(q)))
    assert verdict.solved, verdict.message
    elbow_down = arm.ik(arm.fk(np.array(challenge.joints))).q[2]  # on the target too, but not on the asked branch
    verdict = C.check(challenge, arm, C.Answer(q=elbow_down, target=arm.fk(elbow_down)))
    assert not verdict.solved and "shoulder front, elbow down, wrist not flipped branch" in verdict.message, verdict.message


@pytest.mark.parametrize("branch", ['"elbow up, wrist not flipped"', '"elbow up, wrist flipped"', "1", "2"])
def test_at_a_singular_target_the_two_branches_that_are_one_pose_are_each_the_asked_one(branch):
    """At θ5 = 0 the wrist flipped and not flipped are one pose. A challenge asking for "wrist flipped" there judged
    the teacher's own joints, its solution, "the wrist not flipped branch (branch 1)": nobody could solve it."""
    challenge = C.parse('[[challenge]]\ntitle = "KR210 wrist"\nkind = "reach"\narm = "kr210"\n'
                        f'joints = [10, 0, -30, 40, 0, 60]\nbranch = {branch}\n')[0]
    arm = Arm.preset("kr210")
    q = np.array(challenge.joints)
    verdict = C.check(challenge, arm, C.Answer(q=q, target=arm.fk(q)))
    assert verdict.solved, verdict.message
    solution, _ = C.solution(challenge, arm)
    assert C.check(challenge, arm, C.Answer(q=solution, target=arm.fk(solution))).solved


@pytest.mark.parametrize("branch", ["1", "2", "3", "4", '"behind, elbow above"', '"behind, elbow below"'])
def test_on_the_base_axis_a_branch_behind_is_the_one_in_front_turned_half_a_turn(branch):
    """The desktop arm stretched straight up: θ1 is free, and the branches behind the base are those in front with θ1
    half a turn on. A challenge on branch 3 there, which the file check allowed, judged its own solution (θ1 = 90°)
    "branch 1 (in front, elbow above)": nobody could solve it. Stretched, the elbow is both above and below, with θ2
    on its limit (−90°): the IK gives θ2 to √rounding either side of it, and the file check said "branch 4 does not
    reach this target within the joint limits; branches 2, 3 do" (until 2026-12-06). Every branch reaches it."""
    challenge = C.parse('[[challenge]]\ntitle = "Up"\nkind = "reach"\narm = "three_dof"\n'
                        f'joints = [30, -90, 90]\nbranch = {branch}\n')[0]
    arm = Arm.preset("three_dof")
    solution, _ = C.solution(challenge, arm)
    for q in (solution, np.array(challenge.joints), np.radians([-60, -90, 90])):
        assert C.check(challenge, arm, C.Answer(q=q, target=arm.fk(q))).solved, np.degrees(q)


def test_a_tool_that_must_not_turn_is_held_to_what_the_arm_controls_of_its_turn():
    """``still = true`` was checked on an arm that controls its tool's whole orientation only: a SCARA's tool could
    spin about its axis (the one turn it controls) and be told "Solved", and the terms did not say it must not
    turn; on an arm that places its tool's position only, it was taken and ignored. That one is refused now."""
    text = '[[challenge]]\ntitle = "t"\nkind = "velocity"\narm = "{}"\nvelocity_mm_s = [100, 0, 0]\nstill = true\n'
    arm = Arm.preset("scara")
    challenge, = C.parse(text.format("scara"))
    assert C.terms(challenge, arm).endswith("without turning about its axis (under 1 °/s).")
    q = np.array(arm.specs.home)
    rates = C._velocity_rates(challenge, arm, q)
    assert C.check(challenge, arm, C.Answer(q=q, rates=rates)).solved
    np.testing.assert_allclose(arm.tool_twist(q, rates)[5], 0.0, atol=1e-9)
    spinning = rates + np.radians([0, 0, 0, 10])  # its tool's own joint: v is the same, the yaw is not
    verdict = C.check(challenge, arm, C.Answer(q=q, rates=spinning))
    assert not verdict.solved and verdict.group == "tool turns" and "10.0 °/s" in verdict.message
    solution, words = C.solution(challenge, arm)
    assert solution is None and "one answer" in words
    for name in ("three_dof", "cylindrical"):
        with pytest.raises(ValueError, match=f"line 6: the {name} arm places its tool's position only"):
            C.parse(text.format(name))


@pytest.mark.parametrize("arm_name", ["course", "three_dof"])
def test_a_tool_off_the_target_is_too_high_along_the_arms_own_vertical(arm_name):
    """The desktop arm stands with its y axis up: a student 50 mm above its target was told "too far towards +y", and
    one 50 mm beside it, along z, "50 mm too high"."""
    arm = Arm.preset(arm_name)
    joints = "[10, -30, 60]" if arm_name == "three_dof" else "[10, -60, 80, -30, 60, 20]"
    challenge = C.parse(f'[[challenge]]\ntitle = "t"\nkind = "reach"\narm = "{arm_name}"\njoints = {joints}\n')[0]
    q = np.array(challenge.joints)
    up = int(np.argmax(np.abs(arm.up)))
    for axis in range(3):
        shift = np.zeros(3)
        shift[axis] = 0.05 * (1 if axis == up else -1)
        moved = q + np.linalg.lstsq(arm.jacobian(q)[:3, :], shift, rcond=None)[0]
        verdict = C.check(challenge, arm, C.Answer(q=moved))
        words = "too high" if axis == up else f"too far towards −{'xyz'[axis]}"
        assert verdict.group == f"tool {words}" and re.search(rf"\b(49|50|51) mm {words}\.", verdict.message), verdict.message


@pytest.mark.parametrize("arm_name, joints", [("scara", "[-100, 136, 9, 6]"), ("planar_elbow", "[-120, 28]")])
def test_a_branch_named_by_its_whole_label_is_that_branch(arm_name, joints):
    """The SCARA's and the planar elbow's labels say which sign of θ2 each elbow is: "elbow right (θ2 ≥ 0)". A file
    that named a branch so, as the panel shows it, was refused as not "words of a branch's name ('elbow right (θ2 ≥
    0)', ...)", its own words; its check told a student on that branch that the task asked for it."""
    arm = Arm.preset(arm_name)
    q = np.array(C.parse(f'[[challenge]]\ntitle = "t"\nkind = "reach"\narm = "{arm_name}"\njoints = {joints}\n')[0].joints)
    solution = arm.ik(arm.fk(q), hint=q)
    slots = np.flatnonzero(solution.valid & arm.within_limits(solution.q))
    assert slots.tolist() == [0, 1]
    for slot in slots:
        label = arm.slot_labels[slot]
        challenge = C.parse(f'[[challenge]]\ntitle = "t"\nkind = "reach"\narm = "{arm_name}"\njoints = {joints}\n'
                            f'branch = "{label}"\n')[0]
        assert C.check(challenge, arm, C.Answer(q=solution.q[slot])).solved, label
        other = solution.q[1 - slot]
        verdict = C.check(challenge, arm, C.Answer(q=other))
        assert not verdict.solved and verdict.group == f"{arm.slot_labels[1 - slot].split(' (')[0]} instead of {label}"


def test_long_titles_that_differ_only_at_their_end_are_two_challenges_and_each_names_a_file(tmp_path):
    # the key was cut to 60 characters: "... from the pose given: part A" and "... part B" were refused as "the same but
    # for case, signs and spaces"; and 60 letters of four bytes each made a file's name of 272 bytes, which most
    # systems refuse, so the results were not saved
    stem = "Find the wrist singularity of the UR10 arm from the pose given: part"
    text = "".join(f'[[challenge]]\ntitle = "{t}"\nkind = "velocity"\nvelocity_mm_s = [0, 0, 100]\n'
                   for t in (f"{stem} A", f"{stem} B", "𝐀" * 80, "到" * 80))
    challenges = C.parse(text)
    assert len(challenges) == 4 and challenges[0].key != challenges[1].key
    for challenge in challenges:
        longest = f"challenge-{challenge.key}-2026-12-06-113500-99.part"  # serving/challenge_run.py's, renumbered
        assert len(longest.encode()) <= 255
        (tmp_path / longest).write_bytes(b"")


@pytest.mark.parametrize("change, line, words", [
    (("arm = \"kr210\"", "arm = \"kr2100\""), 5, "arm must be one of"),
    (("joints = [10, 20, -30, 40, 50, 60]", "joints = [10, 20, -30, 40, 50]"), 6, "list of 6 numbers"),
    # a long list's message is cut short: it says how many values came (it showed six of seven)
    (("joints = [10, 20, -30, 40, 50, 60]", "joints = [10.1234567, 20.1234567, -30.1234567, 40.1234567, 50.1234567, 60.1234567, 7]"),
     6, "list of 6 numbers, got 7 values"),
    (("joints = [10, 20, -30, 40, 50, 60]", "joints = [10, nan, -30, 40, 50, 60]"), 6,
     "value 2 of joints is nan: each must be a number from -100000 to 100000"),
    (("kind = \"singularity\"\n", ""), 10, "a challenge needs a kind: one of reach, singularity"),  # (it said "got None")
    (("joints = [10, 20, -30, 40, 50, 60]", "joints = [10, 100, -30, 40, 50, 60]"), 6,
     "A2 is 100°, outside the kr210 arm's limits for it: -45° to 85°"),
    (("arm = \"kr210\"", "arm = \"stanford\""), 6, "d3 is -30 mm, outside the stanford arm's limits for it: 0 mm to 762 mm"),
    (("branch = \"wrist flipped\"", "branch = \"wrist upside down\""), 7, "words of a branch's name"),
    # elbow down needs θ2 = 88° there, past the KR210's 85°: nobody could do it (the README's example asked it)
    (("branch = \"wrist flipped\"", "branch = \"elbow down\""), 7, "'elbow down' does not reach this target within the joint limits; branches 1, 2 do"),
    (("position_tolerance_mm = 3", "position_tolerance_mm = -3"), 8, "position_tolerance_mm must be a number"),
    (("factor = \"wrist\"", "factor = \"elbow\""), 14, "factors are stroke, shoulder, wrist"),
    (("time_limit_s = 120", "time_limt_s = 120"), 15, "unknown key 'time_limt_s'"),
    (("factor = \"wrist\"", "count = 3"), 12, "needs 'factor'"),
    (("kind = \"singularity\"", "kind = \"singularity\"\nvelocity_mm_s = [0, 0, 1]"), 13, "not used by a singularity"),
    (("title = \"Stroke\"", "title = \"Reach it\""), 11, "two challenges titled"),
    # the desk offers it as its own question, asked at the joints shown: the file's took its place in the list
    (("title = \"Stroke\"", "title = \"Pose shown: det J\""), 11, "is the desk's own question about the pose shown"),
    (("title = \"Stroke\"", "title = \"Stroke"), 11, "Illegal character"),
    (("factor = \"wrist\"", "factor = \"stroke\"\nmin_tool_height_mm = 5000"), 14, "5000 mm above the floor"),  # TOML's own syntax error names its line
    # a table or a list where a name goes (for quantity it raised TypeError, "unhashable type")
    (("arm = \"kr210\"", "arm = {name = \"kr210\"}"), 5, "arm must be one of"),
    (("kind = \"singularity\"", "kind = [\"singularity\"]"), 12, "kind must be one of"),
    (("factor = \"wrist\"", "factor = [\"wrist\"]"), 14, "factors are stroke, shoulder, wrist"),
    # a key written twice on the file's last line: TOML's "(at end of document)" is that line
    (("time_limit_s = 120\n", "time_limit_s = 120\ntime_limit_s = 60"), 16, "overwrite a value"),  # the parser's words: tomli 2.0 writes "Can not"
])
def test_a_bad_file_is_refused_naming_the_line(change, line, words):
    text = GOOD.replace(*change)
    with pytest.raises(ValueError) as error:
        C.parse(text, source="class.toml")
    assert f"line {line}" in str(error.value) and words in str(error.value), str(error.value)


def test_a_numbers_quantity_that_is_not_a_name_is_refused_naming_its_line():
    for value in ("[\"position\"]", "{ p = 1 }"):  # raised TypeError ("unhashable type")
        with pytest.raises(ValueError, match="line 5: quantity must be one of"):
            C.parse(f'[[challenge]]\ntitle = "t"\nkind = "numbers"\njoints = [0, 0, 0, 0, 0, 0]\nquantity = {value}\n')


def test_files_are_bounded_and_branch_counts_must_exist(tmp_path):
    with pytest.raises(ValueError, match="no \\[\\[challenge\\]\\]"):
        C.parse("")
    many = "".join(f'[[challenge]]\ntitle = "t{k}"\nkind = "velocity"\nvelocity_mm_s = [1, 0, 0]\n' for k in range(101))
    with pytest.raises(ValueError, match="at most 100"):
        C.parse(many)
    with pytest.raises(ValueError, match="line 4: no target .* is one where exactly 3 branches reach"):
        C.parse('[[challenge]]\ntitle = "x"\nkind = "branch_count"\ncount = 3\n')
    with pytest.raises(ValueError, match="line 4: no target .* is one where exactly 1 branch reaches"):  # ("1 branches")
        C.parse('[[challenge]]\ntitle = "x"\nkind = "branch_count"\ncount = 1\n')
    with pytest.raises(ValueError, match="line 4: the three_dof arm has no DH table to type"):  # its check raised AttributeError
        C.parse('[[challenge]]\ntitle = "x"\nkind = "dh_table"\narm = "three_dof"\n')
    big = tmp_path / "big.toml"
    big.write_text("#" * 200_000)
    with pytest.raises(ValueError, match="at most 100 kB"):
        C.load(big)
    good = tmp_path / "good.toml"
    good.write_text(GOOD)
    assert len(C.load(good)) == 2


def test_a_file_saved_on_windows_is_read(tmp_path):
    """Older Notepads and PowerShell 5's "utf8" start a file with a byte-order mark, which TOML does not allow: the
    whole file was refused with "Invalid statement (at line 1, column 1)". A file saved as ANSI (Windows-1252) is
    named by its line."""
    windows = tmp_path / "notepad.toml"
    windows.write_bytes(b"\xef\xbb\xbf" + GOOD.replace("\n", "\r\n").encode())
    assert [c.title for c in C.load(windows)] == [c.title for c in C.parse(GOOD)]
    ansi = tmp_path / "ansi.toml"
    ansi.write_bytes(GOOD.replace('title = "Stroke"', 'title = "Stroke at 45\xb0"').encode("cp1252"))
    with pytest.raises(ValueError, match="line 11: not UTF-8 text .*save the file as UTF-8"):
        C.load(ansi)


def test_the_readmes_example_file_is_a_valid_challenge_file():
    from pathlib import Path

    readme = (Path(__file__).resolve().parent.parent / "README.md").read_text()
    example = readme.split("```toml\n", 1)[1].split("```", 1)[0]
    reach, numbers = C.parse(example)
    assert reach.branch == "elbow down" and reach.time_limit == 300 and numbers.relative_tolerance == 0.005
