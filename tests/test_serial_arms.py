"""The course's other arms (docs/kinematics.md §7): DH chains against roboticstoolbox-python,
and every analytic IK against FK on random and near-singular joints."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from ur10core import Arm
from ur10core.branches import INSIDE_OFFSET, ORIENTATION, OUT_OF_PLANE, TOO_CLOSE, TOO_FAR
from ur10core.dh import DHTable
from ur10core.orientation import rotation_from_zyx_euler
from ur10core.serial import PRESETS

import roboticstoolbox as rtb  # test-only reference: a missing test extra fails here, loudly
from spatialmath import SE3  # (comes with roboticstoolbox)

from .conftest import typed_copy

pytestmark = pytest.mark.core

ANALYTIC = tuple(PRESETS)
SPHERICAL_WRIST = ("kr210", "elbow", "stanford", "cylindrical_wrist")


def wrapped(difference: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    return np.where(revolute, (difference + np.pi) % (2 * np.pi) - np.pi, difference)


def random_joints(arm: Arm, n: int, seed: int) -> np.ndarray:
    low, high = arm.limits.T
    return np.random.default_rng(seed).uniform(low, high, (n, arm.n_joints))


def rtb_robot_from_table(table: DHTable, tool: np.ndarray | None = None):
    """roboticstoolbox's own DH robot for our rows: an FK and Jacobian written by someone else.

    Fixed rows are skipped: the caller passes what they add as ``tool``.
    """
    links = []
    for row in table.rows:
        if row.joint is None:
            continue
        kind = {("standard", "R"): rtb.RevoluteDH, ("standard", "P"): rtb.PrismaticDH,
                ("modified", "R"): rtb.RevoluteMDH, ("modified", "P"): rtb.PrismaticMDH}[(table.convention, row.joint)]
        if row.joint == "R":
            links.append(kind(a=row.a, alpha=row.alpha, d=row.d, offset=row.theta))
        else:
            links.append(kind(a=row.a, alpha=row.alpha, theta=row.theta, offset=row.d))
    robot = rtb.DHRobot(links)
    if tool is not None:
        robot.tool = SE3(tool, check=False)
    return robot


# ---------------------------------------------------------------------------- DH chains


@pytest.mark.parametrize("model", ["Puma560", "Stanford", "Cobra600", "Panda", "KR5", "IRB140"])
def test_dh_chain_matches_roboticstoolbox_models(model):
    """FK and the geometric Jacobian of our DHTable on roboticstoolbox's models (both conventions)."""
    robot = getattr(rtb.models.DH, model)()
    robot.tool = SE3()
    robot.base = SE3()
    rows = []
    for link in robot.links:
        if link.isprismatic:
            rows.append((link.a, link.alpha, link.offset, link.theta, "P"))
        else:
            rows.append((link.a, link.alpha, link.d, link.offset, "R"))
    table = DHTable(rows, "modified" if robot.mdh else "standard")
    q = np.random.default_rng(7).uniform(-2, 2, (50, robot.n))
    q[:, table.joint_types.find("P")] = np.abs(q[:, table.joint_types.find("P")]) if "P" in table.joint_types else 0
    ours = table.fk(q)
    theirs = np.array([robot.fkine(x).A for x in q])
    np.testing.assert_allclose(ours, theirs, atol=1e-12)
    np.testing.assert_allclose(table.jacobian(q), np.array([robot.jacob0(x) for x in q]), atol=1e-12)


@pytest.mark.parametrize("name", ANALYTIC)
def test_presets_fk_matches_roboticstoolbox_built_from_the_same_rows(name):
    arm = Arm.preset(name)
    tool_rows = [row for row in arm.dh.rows if row.joint is None]
    tool = None
    if tool_rows:  # the KR210's gripper row G: a translation along z6
        (row,) = tool_rows
        tool = np.eye(4)
        tool[2, 3] = row.d
    robot = rtb_robot_from_table(arm.dh, tool)
    q = random_joints(arm, 100, 1)
    np.testing.assert_allclose(arm.fk(q), np.array([robot.fkine(x).A for x in q]), atol=1e-12)
    np.testing.assert_allclose(arm.jacobian(q), np.array([robot.jacob0(x) for x in q]), atol=1e-12)


def test_the_stanford_reports_own_example_is_a_pose_of_the_arm():
    """The report's GUI starts from θ1 = θ2 = θ4 = θ5 = θ6 = 100°, d3 = 10 in. Until 2026-12-04 the assumed
    θ5 limit of ±90° refused it. Its T6 against roboticstoolbox built from the report's table as the
    course writes it (inches turned into metres here, not read from the preset)."""
    arm = Arm.preset("stanford")
    q = arm.specs.poses["report's example"]
    np.testing.assert_allclose(q, [*np.radians([100, 100]), 10 * 0.0254, *np.radians([100, 100, 100])])
    assert arm.within_limits(q)
    half = np.pi / 2
    report = rtb.DHRobot([rtb.RevoluteDH(alpha=-half), rtb.RevoluteDH(d=6.375 * 0.0254, alpha=half), rtb.PrismaticDH(),
                          rtb.RevoluteDH(alpha=-half), rtb.RevoluteDH(alpha=half), rtb.RevoluteDH()])
    np.testing.assert_allclose(arm.fk(q), report.fkine(q).A, atol=1e-12)


@pytest.mark.parametrize("name", ANALYTIC)
def test_jacobian_matches_finite_differences(name):
    arm = Arm.preset(name)
    q = random_joints(arm, 20, 2)
    h = 1e-6
    J = arm.jacobian(q)
    for k in range(arm.n_joints):
        step = np.zeros(arm.n_joints)
        step[k] = h
        plus, minus = arm.fk(q + step), arm.fk(q - step)
        v = (plus[:, :3, 3] - minus[:, :3, 3]) / (2 * h)
        dR = (plus[:, :3, :3] - minus[:, :3, :3]) / (2 * h) @ np.swapaxes(arm.fk(q)[:, :3, :3], -1, -2)
        w = np.stack([dR[:, 2, 1], dR[:, 0, 2], dR[:, 1, 0]], axis=-1)
        np.testing.assert_allclose(J[:, :3, k], v, atol=1e-8)
        np.testing.assert_allclose(J[:, 3:, k], w, atol=1e-8)


@pytest.mark.parametrize("name", ANALYTIC + ("rtb:Panda", "rtb:Puma560"))
def test_both_conventions_give_the_same_tool_pose(name):
    if name.startswith("rtb:"):
        robot = getattr(rtb.models.DH, name[4:])()
        rows = [(l.a, l.alpha, l.d, l.offset, "R") for l in robot.links]
        table = DHTable(rows, "modified" if robot.mdh else "standard")
    else:
        table = Arm.preset(name).dh
    other = table.converted("modified" if table.convention == "standard" else "standard")
    back = other.converted(table.convention)
    q = np.random.default_rng(3).uniform(-2, 2, (30, table.n_joints))
    np.testing.assert_allclose(other.fk(q), table.fk(q), atol=1e-12)
    np.testing.assert_allclose(back.fk(q), table.fk(q), atol=1e-12)
    np.testing.assert_allclose(other.jacobian(q), table.jacobian(q), atol=1e-12)
    assert other.joint_types == table.joint_types


@pytest.mark.parametrize("name", Arm.PRESETS)
def test_each_description_gives_its_lengths_in_millimetres_as_the_panel_does(name):
    """The panel shows an arm's description above its DH table, which is in mm: "links 0.5 m and 0.4 m" sat
    above a table of 500 and 400 (until 2026-12-06). Every length a description gives is the table's, in mm."""
    arm = Arm.preset(name)
    assert not re.search(r"\d\s*m\b", arm.description), arm.description
    given = {float(v) for v in re.findall(r"(\d+(?:\.\d+)?)\s*mm\b", arm.description)}
    if given:  # (the desktop arm's description gives none: it has no DH table)
        assert given <= {round(1000 * abs(v), 6) for row in arm.dh.rows for v in (row.a, row.d)}, arm.description


def test_course_numbers():
    """docs/kinematics.md §7.5: the KR210 at zero and the Stanford arm's default input."""
    kr210 = Arm.preset("kr210")
    # zero pose: the gripper straight out at x = a1 + d4 + dG, height d1 + a2 + a3 (a3 = −0.054), tool along x
    T = kr210.fk(np.zeros(6))
    np.testing.assert_allclose(T[:3, 3], [0.35 + 1.50 + 0.303, 0.0, 0.75 + 1.25 - 0.054], atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], [1.0, 0.0, 0.0], atol=1e-12)
    stanford = Arm.preset("stanford")
    q = np.radians([100, 100, 0, 100, 100, 100])
    q[2] = 10 * 0.0254
    p = stanford.fk(q)[:3, 3]
    t1, t2, d2, d3 = q[0], q[1], 0.161925, q[2]
    expected = [math.cos(t1) * math.sin(t2) * d3 - math.sin(t1) * d2,
                math.sin(t1) * math.sin(t2) * d3 + math.cos(t1) * d2, math.cos(t2) * d3]
    np.testing.assert_allclose(p, expected, atol=1e-12)


def test_the_cylindrical_arm_with_a_wrist_is_the_lecture_notes_t06():
    """The DH notes multiply T03 of the cylindrical arm by T36 of the spherical wrist and write out T06's
    twelve entries (Spong, Robot Modeling and Control, ch. 3): here, entry by entry, on 500 random joints."""
    arm = Arm.preset("cylindrical_wrist")
    d1, d6 = 0.3, 0.1
    for t1, d2, d3, t4, t5, t6 in random_joints(arm, 500, 31):
        c1, s1, c4, s4, c5, s5, c6, s6 = (f(t) for t in (t1, t4, t5, t6) for f in (math.cos, math.sin))
        notes = [[c1 * c4 * c5 * c6 - c1 * s4 * s6 + s1 * s5 * c6, -c1 * c4 * c5 * s6 - c1 * s4 * c6 - s1 * s5 * s6,
                  c1 * c4 * s5 - s1 * c5, c1 * c4 * s5 * d6 - s1 * c5 * d6 - s1 * d3],
                 [s1 * c4 * c5 * c6 - s1 * s4 * s6 - c1 * s5 * c6, -s1 * c4 * c5 * s6 - s1 * s4 * c6 + c1 * s5 * s6,
                  s1 * c4 * s5 + c1 * c5, s1 * c4 * s5 * d6 + c1 * c5 * d6 + c1 * d3],
                 [-s4 * c5 * c6 - c4 * s6, s4 * c5 * s6 - c4 * c6, -s4 * s5, -s4 * s5 * d6 + d1 + d2]]
        np.testing.assert_allclose(arm.fk([t1, d2, d3, t4, t5, t6])[:3], notes, atol=1e-12)


# ---------------------------------------------------------------------------- analytic IK


def near_singular_joints(arm: Arm, n: int, seed: int) -> np.ndarray:
    """Joints 1e-12 … 1e-5 from each singularity of the arm's family (random otherwise)."""
    rng = np.random.default_rng(seed)
    q = random_joints(arm, n, seed)
    tiny = 10.0 ** rng.uniform(-12, -5, n) * rng.choice([-1, 1], n)
    exact = rng.random(n) < 0.2
    tiny[exact] = 0.0
    kind = rng.integers(0, 3, n)
    if arm.name in SPHERICAL_WRIST:
        wrist = kind == 0  # θ5 at 0 or π: axes 4 and 6 aligned
        q[wrist, 4] = rng.choice([0.0, math.pi], wrist.sum()) + tiny[wrist]
        if arm.name == "stanford":
            stroke = kind == 1  # d3 at 0: the wrist centre on the shoulder
            q[stroke, 2] = np.abs(tiny[stroke])
            cylinder = kind == 2  # θ2 at 0 or π: the wrist centre on the d2 cylinder
            q[cylinder, 1] = rng.choice([0.0, math.pi], cylinder.sum()) + tiny[cylinder]
        elif arm.name == "cylindrical_wrist":
            column = kind > 0  # d3 at 0: the wrist centre on the column's axis (both, a third of the time)
            q[column, 2] = np.abs(tiny[column])
            q[kind == 2, 4] = tiny[kind == 2]
        else:
            plane = arm.solver.plane
            elbow = kind == 1  # stretched or folded: β = s3 θ3 + φ at 0 or π
            beta = rng.choice([0.0, math.pi], elbow.sum()) + tiny[elbow]
            q[elbow, 2] = (beta - plane["phi"]) * plane["s3"]
            both = kind == 2
            q[both, 4] = tiny[both]
            q[both, 2] = (np.abs(tiny[both]) - plane["phi"]) * plane["s3"]
    else:
        elbow = kind < 2
        if arm.name in ("planar_elbow", "scara"):
            q[elbow, 1] = rng.choice([0.0, math.pi], elbow.sum()) + tiny[elbow]
        if arm.name == "cylindrical":
            q[elbow, 2] = np.abs(tiny[elbow])
    return q


@pytest.mark.parametrize("name", ANALYTIC)
@pytest.mark.parametrize("kind", ["random", "near singular"])
def test_fk_of_ik_and_the_generating_joints(name, kind):
    """Every valid slot reproduces the pose to 1e-9; with the joints as hint they are among the branches;
    without a hint the pose is still reached."""
    arm = Arm.preset(name)
    q = random_joints(arm, 3000, 11) if kind == "random" else near_singular_joints(arm, 3000, 12)
    T = arm.fk(q)
    for hint in (q, None):
        sol = arm.ik(T, hint=hint)
        assert sol.valid.any(axis=-1).all(), sol.unreachable_reason((int(np.argmin(sol.valid.any(-1))),))
        error = arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), T[:, None])
        assert error[sol.valid].max() < 1e-9
        if hint is not None:
            distance = np.where(sol.valid, np.abs(wrapped(sol.q - q[:, None], arm.revolute)).max(axis=-1), np.inf)
            assert distance.min(axis=-1).max() < 1e-6
    assert len(sol.labels) == sol.q.shape[-2] == {"kr210": 8, "elbow": 8, "stanford": 8, "scara": 2,
                                                   "planar_elbow": 2, "cylindrical": 2, "cylindrical_wrist": 4}[name]


@pytest.mark.parametrize("name, kind", [  # the cylindrical arm's equations solve every point (d3 of either sign)
    (name, kind) for name in ("kr210", "elbow", "stanford", "cylindrical_wrist")
    for kind in ("random", "near singular", "out of reach") if (name, kind) != ("cylindrical_wrist", "out of reach")])
def test_one_pose_in_floats_decides_as_the_batch_does(name, kind):
    """The one-pose path (``_solve_one``, plain floats) against the batch path on the same poses and
    hints: the same slots valid, singular and failing, with the same numbers to rounding (one pose at
    a time is slow in a test: the thousands of poses are the batch tests' above)."""
    arm = Arm.preset(name)
    n = 1000 if kind == "near singular" else 300  # the rare decisions are near the singularities
    q = random_joints(arm, n, 21) if kind != "near singular" else near_singular_joints(arm, n, 22)
    T = arm.fk(q)
    if kind == "out of reach":
        T[:, :3, 3] *= np.random.default_rng(23).choice([0.05, 3.0], n)[:, None]
    hints = (None, q, random_joints(arm, n, 24))
    for hint in hints:
        batch = arm.solver.solve(T, hint)
        for k in range(n):
            one = arm.solver.solve(T[k:k + 1], None if hint is None else hint[k:k + 1])
            # near a singularity "singular" itself is decided on a value fixed only to √rounding
            for key in ("valid", "failure") if kind == "near singular" else ("valid", "singular", "failure"):
                np.testing.assert_array_equal(one[key][0], batch[key][k], err_msg=f"{key}, pose {k}")
            np.testing.assert_allclose(one["detail"][0], batch["detail"][k], rtol=1e-12, atol=1e-15)
            valid = batch["valid"][k]
            if kind != "near singular":
                np.testing.assert_allclose(wrapped(one["q"][0][valid] - batch["q"][k][valid], arm.revolute), 0.0, atol=1e-9)
            assert arm.pose_error(one["q"][0][valid], T[k]).max(initial=0.0) < 1e-9
    assert kind != "out of reach" or not arm.ik(T).valid.all()


@pytest.mark.parametrize("name", ["kr210", "elbow"])
def test_articulated_arms_have_eight_distinct_branches_inside_the_reach(name):
    arm = Arm.preset(name)
    q = random_joints(arm, 500, 4)
    sol = arm.ik(arm.fk(q))
    full = sol.valid.all(axis=-1)
    assert full.mean() > 0.5
    qs = sol.q[full]
    pairwise = np.abs(wrapped(qs[:, :, None] - qs[:, None], arm.revolute)).max(axis=-1)
    off_diagonal = pairwise[:, ~np.eye(8, dtype=bool)]
    assert (off_diagonal.min(axis=-1) > 1e-6).mean() > 0.99


@pytest.mark.parametrize("name", ["kr210", "elbow"])
def test_elbow_up_puts_the_elbow_above_the_shoulder_wrist_line(name):
    """The labels say what a student sees: "elbow up" has the elbow above the straight line from
    the shoulder joint to the wrist centre (checked where the arm reaches the way its shoulder faces)."""
    arm = Arm.preset(name)
    sol = arm.ik(arm.fk(random_joints(arm, 300, 5)))
    checked = 0
    for slot, label in enumerate(sol.labels):
        q = sol.q[:, slot][sol.valid[:, slot]]
        frames = arm.frames(q)
        _, points = arm.dh.joint_axes(frames)
        shoulder, elbow = points[:, 1], points[:, 2]
        centre = frames[:, arm.solver.wrist.first_row + 1, :3, 3]
        heading = np.stack([np.cos(q[:, 0]), np.sin(q[:, 0])], axis=-1)
        radial = lambda p: np.einsum("ni,ni->n", p[:, :2], heading)  # noqa: E731
        ahead = radial(centre) > radial(shoulder)
        as_labelled = ahead if "front" in label else ~ahead
        line = shoulder[:, 2] + (centre[:, 2] - shoulder[:, 2]) * (radial(elbow) - radial(shoulder)) / (radial(centre) - radial(shoulder))
        above = elbow[:, 2] > line
        assert (above[as_labelled] == ("up" in label)).mean() > 0.99, label
        checked += as_labelled.sum()
    assert checked > 1000


def test_wrist_singular_keeps_the_hints_theta4():
    arm = Arm.preset("kr210")
    q = np.radians([20, 10, -20, 35, 0, 50])
    sol = arm.ik(arm.fk(q), hint=q)
    slot = int(sol.nearest(q).slot)
    np.testing.assert_allclose(sol.q[slot], q, atol=1e-12)
    assert sol.singular[slot]
    other = arm.ik(arm.fk(q))  # no hint: θ4 = 0, θ6 takes the whole turn
    slot = int(other.nearest(q).slot)
    assert abs(other.q[slot, 3]) < 1e-12 and math.isclose(other.q[slot, 5], math.radians(85), abs_tol=1e-9)


def test_a_free_wrist_joint_turns_from_the_hints_value_where_that_would_leave_the_branch_beyond_a_limit():
    """The Stanford arm's wrist turns ±170°. At θ5 = 0 only θ4 + θ6 is fixed (here −165°): the hint's θ4 of 20° would
    leave θ6 at 175° (−185°), beyond its limit, though θ4 and θ6 near 102.5° and 92.5° reach the pose within the
    limits."""
    arm = Arm.preset("stanford")
    home = arm.specs.home  # θ4 = 20°, θ6 = 10°
    q = home.copy()
    q[3:] = np.radians([-120.0, 0.0, -45.0])
    T = arm.fk(q)
    one, batch = arm.ik(T, hint=home), arm.ik(np.stack([T, np.eye(4)]), hint=home)
    for q_slots, within in ((one.q, one.within_limits), (batch.q[0], batch.within_limits[0])):
        assert within[:4].all() and not within[4:].any()  # d3 < 0 beyond either way
        assert arm.pose_error(q_slots[:4], T).max() < 1e-9
        # the nearest: θ4 and θ6 each turned 82.5° from the hint's 20° and 10°, to within half of the 4.7° tried apart
        np.testing.assert_allclose(np.degrees(q_slots[0, 3:]), [102.5, 0.0, 92.5], atol=2.4)
    assert one.nearest(home, within_limits=True).slot in (0, 1)  # the arm keeps its shoulder
    raw = arm._branches(T, home)  # what the closed form alone gives: the hint's θ4
    np.testing.assert_allclose(np.degrees(raw.q[0, 3:]), [20.0, 0.0, 175.0], atol=1e-9)


def test_a_pose_whose_strokes_are_beyond_their_range_is_not_probed_for_a_free_joint():
    """A free joint turns the arm; it never changes a stroke. The cylindrical arm's reach map at a θ5 = 0 orientation
    is wrist-singular in every cell, and the cells beyond its strokes' reach had each joint's hint value moved in turn
    (six more solves each) to find a free joint that could not help: the 100 × 100 map took 0.55 s, against 0.12 s
    now (medians of seven, one process)."""
    from ur10core.branches import keep_free_values_within_limits

    arm = Arm.preset("cylindrical_wrist")
    q = np.array([0.0, 0.35, 0.35, 0.0, 0.0, 0.0])  # θ5 = 0: only θ4 + θ6 is fixed
    T = np.stack([arm.fk(q)] * 3)
    T[:, :3, 3] *= [[1.0, 1.0, 3.0], [2.5, 2.5, 1.0], [1.0, 1.0, -1.0]]  # above, beyond and below the strokes
    solution = arm._branches(T, None)
    assert (solution.valid & solution.singular & ~solution.within_limits).all(axis=-1).all()
    solved = []
    keep_free_values_within_limits(solution, lambda *pose_and_hint: solved.append(1) or arm._branches(*pose_and_hint),
                                   T, None)
    assert not solved
    within = arm.ik(arm.fk(q), hint=q)  # and a pose within them is solved as before
    assert within.within_limits.any() and arm.pose_error(within.q[within.valid], arm.fk(q)).max() < 1e-9


def test_a_typed_tables_search_pins_a_free_joint_where_every_joint_stays_within_its_limits():
    """The numerical search, too, moves each solution on a curve of them to where its last free joint has the hint's
    value: a typed Stanford arm's θ6 at 10° put θ4 at −175° on the shoulder the arm was on (until 2026-12-05)."""
    arm = Arm.preset("stanford")
    typed = typed_copy(arm, with_limits=True)
    home = arm.specs.home
    q = home.copy()
    q[3:] = np.radians([-120.0, 0.0, -45.0])
    T = arm.fk(q)
    sol = typed.ik(T, hint=home)
    on_its_shoulder = sol.valid & (np.abs(sol.q[..., :3] - home[:3]).max(axis=-1) < 1e-6)
    assert on_its_shoulder.sum() == 1 and sol.within_limits[on_its_shoulder].all()
    assert typed.pose_error(sol.q[on_its_shoulder], T).max() < 1e-9


@pytest.mark.parametrize("name", ["stanford", "kr210", "elbow", "cylindrical_wrist"])
def test_a_wrist_singular_pose_within_the_limits_always_has_a_branch_within_them(name):
    arm = Arm.preset(name)
    q = arm.sample_joints(4000, seed=4)
    q[:, 4] = 0.0
    T = arm.fk(q)
    sol = arm.ik(T, hint=arm.sample_joints(4000, seed=9))
    assert (sol.valid & sol.within_limits).any(axis=-1).all()
    error = arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), T[:, None])
    assert error[sol.valid].max() < 1e-9


def assert_a_branch_within_the_limits_reaches_each(arm, T: np.ndarray, hint_seed: int, one_pose_hints=None) -> None:
    """Every pose of ``T`` (N, 4, 4) has a branch within the joint limits, and every slot reaches its pose to 1e-9: in
    one batch with no hint and with random hints, and one pose at a time (a drag's path; ``one_pose_hints`` (N, n))."""
    for hint in (None, arm.sample_joints(len(T), seed=hint_seed)):
        sol = arm.ik(T, hint=hint)
        assert (sol.valid & sol.within_limits).any(axis=-1).all()
        assert arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), T[:, None])[sol.valid].max() <= 1e-9
    for k in range(0, len(T), 20):
        sol = arm.ik(T[k], hint=None if one_pose_hints is None else one_pose_hints[k])
        assert (sol.valid & sol.within_limits).any()


@pytest.mark.parametrize("stroke", [0.0, 1e-10, 5e-10, 3e-8, 1e-7, 1e-6, 1e-5])
def test_a_stanford_pose_with_its_stroke_at_the_stop_and_theta2_on_a_limit_has_a_branch_within_them(stroke):
    """With the stroke d3 a few µm from its stop, the wrist centre lies a few µm from the shoulder, and the pose fixes
    θ2 only to its rounding over the stroke (2e-5 rad at 1 µm); at d3 ≤ 1e-9 m θ2 is free. θ2 on its 170° limit
    (its slider at an end) came out beyond it in every slot, or θ2 was taken from the rounding and the wrist turned
    past its limits, though the arm reaches the pose within them (until 2026-12-07: 29 of 3,000 poses with joints
    at their ends, in a probe; here 2 to 159 of the 400 at each stroke but 0)."""
    arm = Arm.preset("stanford")
    rng = np.random.default_rng(11)
    q = arm.sample_joints(400, seed=12)
    q[:, 2] = stroke
    q[:, 1] = rng.choice(arm.limits[1], len(q))
    q[:, 4] = rng.choice([-1.0, 1.0], len(q)) * rng.uniform(0.1, arm.limits[4, 1], len(q))  # the wrist not singular too
    for joint in (0, 3, 5):  # and now and then another joint on a limit
        ends = rng.random(len(q)) < 0.3
        q[ends, joint] = rng.choice(arm.limits[joint], ends.sum())
    assert_a_branch_within_the_limits_reaches_each(arm, arm.fk(q), hint_seed=13, one_pose_hints=q + 1e-3)


@pytest.mark.parametrize("theta5", [5e-11, 1e-10, 3e-10, 1e-9, 3e-9, 1e-8])
def test_a_stanford_pose_with_theta5_near_0_and_wrist_joints_on_their_limits_has_a_branch_within_them(theta5):
    """Just off the wrist singularity θ4 = atan2(W23, W13) carries W's rounding over sin θ5 (1e-7 rad at θ5 = 9e-9),
    and a hint's θ4 is kept wherever turning to it moves the pose by less than the tolerance (any θ4 at θ5 = 1e-10).
    With θ4 or θ6 on its 170° limit, a slot then read θ4 at 170.0002°, or θ6 at 174° from the hint's θ4, while the
    arm reaches the pose within its limits (until 2026-12-08: here 2 to 7 of the 2,000 at each θ5, with or without a
    hint). A short stroke carries θ2's rounding into W too (at 0.8 mm, θ4 off by 4e-5 rad at θ5 = 1e-8)."""
    arm = Arm.preset("stanford")
    rng = np.random.default_rng(21)
    q = arm.sample_joints(2000, seed=22)
    q[:, 4] = theta5 * rng.choice([-1.0, 1.0], len(q))
    for joint, share in ((3, 0.6), (5, 0.6), (1, 0.5)):  # θ4, θ6 and θ2 at an end, now and then together
        ends = rng.random(len(q)) < share
        q[ends, joint] = rng.choice(arm.limits[joint], ends.sum())
    assert_a_branch_within_the_limits_reaches_each(arm, arm.fk(q), hint_seed=23)


@pytest.mark.parametrize("name, kind", [("kr210", "elbow"), ("elbow", "elbow"), ("three_dof", "fold"), ("course", "elbow")])
def test_a_pose_on_a_stretched_or_folded_elbow_with_joints_on_their_limits_has_a_branch_within_them(name, kind):
    """On a stretched or folded elbow the IK gives the elbow's angle, and the joints that follow from it, to
    √rounding only (up to 3e-8 rad measured): a joint on its limit came out beyond it by more than the 1e-9 the
    limits allowed, and a pose the arm reaches within its limits (a slider at its end, the elbow stretched) had no
    branch within them (until 2026-12-06: 73 of 300 such KR210 poses, in a probe)."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(5)
    poses = []
    for start in arm.sample_joints(200, seed=6):
        try:
            q = arm.singular_configuration(kind, start)
        except ValueError:  # no such pose near this one within the limits
            continue
        for joint in rng.choice(arm.n_joints, size=2, replace=False):
            q[joint] = arm.limits[joint, rng.integers(2)]
        if arm.within_limits(q):
            poses.append(q)
    q = np.array(poses)
    assert len(q) > 50
    T = arm.fk(q)
    sol = arm.ik(T)
    assert (sol.valid & sol.within_limits).any(axis=-1).all()
    assert arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), T[:, None])[sol.valid].max() < 1e-9


def test_a_pose_with_the_wrist_centre_on_axis_one_and_two_wrist_joints_on_their_limits_has_a_branch_within_them():
    """The elbow arm with WC on axis 1 leaves θ1 free. As θ1 turns, |θ5| turns back where θ4 is 0° or 180°; where it
    is least there (104 of these 300 poses) and on its limit, any other θ1 takes θ5 beyond it. That one θ1 lies
    between two of the free joint's 73 values: without a hint, 101 of the 300 had no branch within the limits
    (until 2026-12-07)."""
    arm = Arm.preset("elbow")
    rng = np.random.default_rng(3)
    q = np.repeat([arm.singular_configuration("shoulder", start) for start in arm.sample_joints(20, seed=8)], 15, axis=0)
    q[:, [0, 5]] = arm.sample_joints(len(q), seed=9)[:, [0, 5]]  # θ1 turns WC about axis 1, where it stays
    q[:, 3:5] = arm.limits[[3, 4], rng.integers(2, size=(len(q), 2))]
    assert arm.within_limits(q).all()
    T = arm.fk(q)
    sol = arm.ik(T)
    assert (sol.valid & sol.within_limits).any(axis=-1).all()
    assert arm.pose_error(np.where(sol.valid[..., None], sol.q, 0.0), T[:, None])[sol.valid].max() < 1e-9


def test_wrist_centre_on_axis_one_keeps_the_hints_theta1():
    arm = Arm.preset("kr210")
    T = np.eye(4)
    T[:3, 3] = (0.0, 0.0, 2.6)  # the wrist centre straight above the base, 0.303 below the tool
    T[:3, 3] += (0, 0, 0.303)
    hint = np.radians([37, 0, 0, 0, 0, 0])
    sol = arm.ik(T, hint=hint)
    assert sol.valid.any()
    np.testing.assert_allclose(sol.q[sol.valid][:, 0] % math.pi, math.radians(37), atol=1e-12)
    assert sol.singular[sol.valid].all()
    assert arm.pose_error(sol.q[sol.valid], T).max() < 1e-9


@pytest.mark.parametrize("name, position, failure, words", [
    ("kr210", (4.0, 0.0, 1.0), TOO_FAR, "reach at most"),
    ("elbow", (0.0, 0.0, 0.72), TOO_CLOSE, "cannot come closer"),  # WC 20 mm above the shoulder, folded 50 mm
    ("stanford", (0.05, 0.05, 0.3), INSIDE_OFFSET, "inside the shoulder offset"),
    ("planar_elbow", (0.5, 0.2, 0.1), OUT_OF_PLANE, "off the plane"),
    ("scara", (2.0, 0.0, 0.2), TOO_FAR, "reach at most"),
])
def test_unreachable_poses_are_explained_with_numbers(name, position, failure, words):
    arm = Arm.preset(name)
    T = np.eye(4)
    if name == "scara":
        T[:3, :3] = np.diag([1.0, -1.0, -1.0])
    T[:3, 3] = position
    sol = arm.ik(T)
    assert not sol.valid.any()
    assert (sol.failure == failure).any()
    reason = sol.unreachable_reason()
    assert words in reason and "mm" in reason


def test_a_target_a_hair_beyond_the_planar_elbows_reach_says_by_how_much():
    """11 µm beyond a1 + a2 = 900 mm read "900.0 mm from …; the two links reach at most 900.0 mm"."""
    arm = Arm.preset("planar_elbow")
    T = np.eye(4)
    T[0, 3] = 0.9 + 11e-6
    reason = arm.ik(T).unreachable_reason()
    assert "900.011 mm from the first joint's axis; the two links reach at most 900.000 mm (0.011 mm short)" in reason


def test_scara_refuses_a_tilted_tool_and_says_by_how_much():
    arm = Arm.preset("scara")
    T = arm.fk(np.array([0.3, 0.5, 0.1, 0.2]))
    tilt = np.array([[1, 0, 0], [0, math.cos(0.01), -math.sin(0.01)], [0, math.sin(0.01), math.cos(0.01)]])
    T[:3, :3] = tilt @ T[:3, :3]
    sol = arm.ik(T)
    assert not sol.valid.any() and (sol.failure == ORIENTATION).all()
    assert "0.57°" in sol.unreachable_reason()


def test_a_slot_beyond_a_joint_limit_stays_valid_and_is_flagged():
    arm = Arm.preset("kr210")
    q = random_joints(arm, 200, 6)
    sol = arm.ik(arm.fk(q))
    assert (sol.within_limits == sol.valid & arm.within_limits(np.where(sol.valid[..., None], sol.q, 0.0))).all()
    beyond = sol.valid & ~sol.within_limits
    assert beyond.any(axis=-1).mean() > 0.5  # KR210's q2 (−45…85°) and q3 (−210…65°) rule out many branches
    assert sol.within_limits.any(axis=-1).all()  # the generating joints are inside


def test_batches_and_hints_broadcast():
    arm = Arm.preset("stanford")
    q = random_joints(arm, 12, 8).reshape(3, 4, 6)
    sol = arm.ik(arm.fk(q), hint=q[0])
    assert sol.q.shape == (3, 4, 8, 6) and sol.valid.shape == (3, 4, 8)
    one = arm.ik(arm.fk(q[1, 2]), hint=q[0, 2])
    np.testing.assert_allclose(one.q, sol.q[1, 2], atol=1e-15)


# ---------------------------------------------------------------------------- numerical IK


def test_numerical_ik_finds_the_kr210s_branches():
    """The damped-least-squares search against the closed form: every branch it reports is
    real, and on most poses it finds all eight (the rate is printed in BENCHMARKS.md)."""
    arm = Arm.preset("kr210")
    numerical = Arm(arm.dh, arm.limits, None, "kr210 (numerical)")
    q = random_joints(arm, 30, 9)
    T = arm.fk(q)
    analytic, found = arm.ik(T), numerical.ik(T)
    assert found.method == "found numerically" and found.labels[0] == "found numerically 1"
    assert numerical.pose_error(np.where(found.valid[..., None], found.q, 0), T[:, None])[found.valid].max() < 1e-9
    complete = 0
    for k in range(len(T)):
        ours = found.q[k][found.valid[k]]
        branches = analytic.q[k][analytic.valid[k]]
        hits = [np.abs(wrapped(ours - b, arm.revolute)).max(axis=-1).min() < 1e-6 for b in branches]
        assert len(ours) == sum(hits)  # nothing it reports is outside the closed form's list
        complete += all(hits)
    assert complete / len(T) >= 0.7


def test_a_typed_table_finds_poses_near_a_singularity():
    """Found by a fuzz of typed copies of the presets: the Stanford arm with its stroke d3 a few mm
    long (the wrist centre close to the shoulder's axis, where J is singular) had no start within
    1e-10 after the usual steps, so a pose 0.1 µm away was reported as not found. Its closed form
    is the independent check: every one of these poses has eight branches."""
    stanford = Arm.preset("stanford")
    typed = typed_copy(stanford)
    q = np.array([[0.319, 2.528, 0.002, -2.004, 1.307, -0.626],
                  [1.164, -1.230, 0.001, 2.810, -1.196, -1.104],
                  [-2.188, -0.115, 0.003, 1.717, -2.521, -2.732]])
    T = typed.fk(q)
    assert stanford.ik(T).valid.sum(axis=-1).tolist() == [8, 8, 8]
    sol = typed.ik(T)
    assert sol.valid.any(axis=-1).all(), sol.detail[:, 0]  # how near the nearest start came
    assert typed.pose_error(np.where(sol.valid[..., None], sol.q, 0), T[:, None])[sol.valid].max() < 1e-9


@pytest.mark.parametrize("name, joint, within", [("stanford", 2, 1e-3), ("ur10", 4, 1e-3)])
def test_a_typed_table_finds_every_branch_next_to_a_singularity(name, joint, within):
    """Within 1 mm or 1 mrad of a singularity (the Stanford arm's stroke d3 near 0, the UR10's wrist θ5 near 0)
    damped least squares stalls a hair from each solution: J's smallest singular value is below the least
    damping. Until 2026-12-04 half of such Stanford poses were reported as not found, and a fifth of the
    branches of such UR10 poses were missing; undamped Gauss–Newton steps from the starts that came near now
    finish them. The preset's closed form is the independent check: each branch it gives is found."""
    arm = Arm.preset(name)
    typed = typed_copy(arm, with_limits=True)
    rng = np.random.default_rng(12)
    q = rng.uniform(np.maximum(arm.limits[:, 0], -np.pi), np.minimum(arm.limits[:, 1], np.pi), (40, 6))
    q[:, joint] = rng.uniform(0.0 if name == "stanford" else -within, within, 40)
    T = arm.fk(q)
    closed, found = arm.ik(T), typed.ik(T)
    assert found.valid.any(axis=-1).all(), f"{(~found.valid.any(axis=-1)).sum()} of 40 reachable poses not found"
    assert typed.pose_error(np.where(found.valid[..., None], found.q, 0), T[:, None])[found.valid].max() < 1e-9
    revolute = np.array([kind == "R" for kind in arm.joint_types])
    apart = closed.q[:, :, None] - found.q[:, None]  # (pose, closed-form branch, numerical solution, joint)
    apart = np.abs(np.where(revolute, np.angle(np.exp(1j * apart)), apart)).max(axis=-1)
    matched = (np.where(found.valid[:, None], apart, np.inf).min(axis=-1) < 1e-2) & closed.valid
    assert matched.sum() >= 0.95 * closed.valid.sum(), f"{matched.sum()} of {closed.valid.sum()} branches found"


def test_a_typed_ur10s_search_finds_every_branch_its_closed_form_has_within_the_limits():
    """At 48 starts, a typed UR10 missed one of these poses' eight branches (each within its ±360° limits): 6 of
    2,162 over 300 random poses (until 2026-12-05). Its search starts from more joint vectors now."""
    ur10 = Arm.preset("ur10")
    typed = typed_copy(ur10, with_limits=True)
    q = ur10.sample_joints(300, seed=11)[[31, 40, 57, 58, 233, 275]]
    T = ur10.fk(q)
    closed = ur10.ik(T, hint=q)
    for k in range(len(q)):
        found = typed.ik(T[k], hint=q[k])
        ours = found.q[found.valid & found.within_limits]
        for branch in closed.q[k][closed.valid[k] & closed.within_limits[k]]:
            apart = np.abs(wrapped(ours - branch, ur10.revolute)).max(axis=-1)
            assert apart.min() < 1e-6, f"pose {k}: the branch {np.degrees(branch).round(1)} was not found"


@pytest.mark.parametrize("name, joint", [("elbow", 4), ("kr210", 4), ("stanford", 4), ("cylindrical_wrist", 4),
                                         ("ur10", 4), ("ur10", 2), ("elbow", 2)])
def test_a_typed_table_on_a_singularity_lists_each_branch_once(name, joint):
    """On a singularity (θ5 = 0: axes 4 and 6 in line, only θ4 + θ6 fixed; θ3 = 0: the elbow stretched) the pose
    leaves the joints free along a curve, or fixes them only to √rounding. Each of the search's starts stopped at
    another point of one branch, and a typed arm with its wrist straight listed 16 solutions where its closed form
    has six (until 2026-12-04). A solution is now moved along such a curve to the hint's value of its last joint,
    as the closed forms keep the hint's, and two whose midpoint is as close to the pose are one. The preset's
    closed form is the reference: as many distinct branches (2 % more at most, 5 % fewer at most: a start now and
    then misses a branch's basin), the arm's own joints among them."""
    arm = Arm.preset(name)
    typed = typed_copy(arm, with_limits=True)
    q = arm.sample_joints(40, seed=8)
    q[:, joint] = 0.0
    T = arm.fk(q)
    closed, found = arm.ik(T, hint=q), typed.ik(T, hint=q)
    assert typed.pose_error(np.where(found.valid[..., None], found.q, 0), T[:, None])[found.valid].max() < 1e-9
    distinct = 0
    for k in range(len(q)):
        kept = []
        for branch in closed.q[k][closed.valid[k]]:
            if all(np.abs(wrapped(branch - other, arm.revolute)).max() > 1e-3 for other in kept):
                kept.append(branch)
        distinct += len(kept)
    listed = int(found.valid.sum())
    assert 0.95 * distinct <= listed <= 1.02 * distinct, (listed, distinct)
    np.testing.assert_allclose(found.nearest(q).q, q, atol=1e-6)


def test_a_typed_scara_places_its_position_and_yaw_as_the_preset_does():
    """A typed SCARA was a position-only chain: its roll θ4 turned about the tool point, every θ4 reached, and its
    16 slots were 16 rolls of one elbow (until 2026-12-04); a drag's yaw did nothing. Its axes all stay parallel
    to z0, with three revolute joints and a slide: it now places its position and yaw, as the preset's closed form
    does, with the same two branches."""
    scara = Arm.preset("scara")
    typed = typed_copy(scara, with_limits=True)
    assert typed.task == scara.task == "position and yaw" and len(typed.slot_labels) == 2
    q = scara.sample_joints(30, seed=4)
    T = typed.fk(q)
    closed, found = scara.ik(T), typed.ik(T)
    assert (found.valid.sum(axis=-1) == closed.valid.sum(axis=-1)).all()
    for k in range(len(q)):
        ours, branches = found.q[k][found.valid[k]], closed.q[k][closed.valid[k]]
        apart = np.abs(wrapped(ours[:, None] - branches[None], scara.revolute)).max(axis=-1)
        assert (apart.min(axis=0) < 1e-6).all()
    # a yaw asked of it turns its roll, as the preset's
    from ur10teach.state import ArmState

    followed = []
    for arm in (scara, typed):
        state = ArmState(arm, scara.specs.home)
        goal = state.last.target.copy()
        goal[:3, :3] = rotation_from_zyx_euler(np.array([0.5, 0.0, 0.0])) @ goal[:3, :3]
        snapshot = state.move_target(goal)
        assert snapshot.reachable and arm.pose_error(snapshot.q, goal) < 1e-9
        followed.append(snapshot.q)
    np.testing.assert_allclose(followed[1], followed[0], atol=1e-7)
    assert abs(followed[1][3] - scara.specs.home[3]) == pytest.approx(0.5)  # (its tool points down: θ4 turns back)


def test_a_typed_tables_joint_that_does_not_move_the_tool_point_does_not_fill_its_slots():
    """The cylindrical arm with a roll at its tool point (RPPR) places a position: the roll turns about the tool
    point, every value of it reaches, and each of the search's starts brought back another, filling the 16 slots
    with one branch. The roll is now kept at the arm's, and the search lists the closed form's branches of the
    other three joints."""
    cylindrical = Arm.preset("cylindrical")
    rows = [(r.a, r.alpha, r.d, r.theta, r.joint) for r in cylindrical.dh.rows] + [(0.0, 0.0, 0.0, 0.0, "R")]
    typed = Arm.from_dh(rows, "standard", limits=[*cylindrical.limits, (-np.pi, np.pi)])
    assert typed.task == "position"
    q = np.column_stack([cylindrical.sample_joints(30, seed=4), np.linspace(-3, 3, 30)])
    T = typed.fk(q)
    closed, found = cylindrical.ik(T, hint=q[:, :3]), typed.ik(T, hint=q)
    for k in range(len(q)):
        branches = closed.q[k][closed.valid[k]]
        ours = found.q[k][found.valid[k]]
        apart = np.abs(wrapped(ours[:, None, :3] - branches[None], cylindrical.revolute)).max(axis=-1)
        assert len(ours) == len(branches) and (apart.min(axis=0) < 1e-6).all()
        np.testing.assert_allclose(ours[:, 3], q[k, 3])  # the roll the arm has, on each branch
    np.testing.assert_allclose(found.nearest(q).q, q, atol=1e-7)  # the arm's own joints among them


def test_a_typed_tables_drag_follows_the_target_next_to_a_singularity():
    """The drag's one search, from the arm's own joints, stalled the same way a hair from the target: a typed
    Stanford arm dragged with its stroke d3 under 3 mm was told "the search came within 1.06e-06 mm of it: it
    may be out of reach" on 27 of these 400 steps (until 2026-12-04). Each one is reachable by construction."""
    stanford = Arm.preset("stanford")
    typed = typed_copy(stanford)
    rng = np.random.default_rng(5)
    errors = []
    for _ in range(40):
        q = rng.uniform(-2, 2, 6)
        q[2] = rng.uniform(3e-4, 3e-3)
        arm_q = q.copy()
        for _ in range(10):  # the target slides a fraction of a millimetre at a time, d3 staying positive
            step = q.copy()
            step[:2] += rng.uniform(-2e-3, 2e-3, 2)
            step[2] = max(q[2] + rng.uniform(-2e-4, 2e-4), 1e-5)
            T = typed.fk(step)
            followed, _ = typed.solver.follow(T, arm_q)  # from the arm's joints, as the app's drag does
            errors.append(float(typed.pose_error(followed, T)))
            q, arm_q = step, followed if errors[-1] <= 1e-9 else arm_q
    assert max(errors) <= 1e-9, f"{sum(e > 1e-9 for e in errors)} of {len(errors)} steps stalled, up to {max(errors):.2g}"


#: Poses a typed table reaches within its limits, which its search found only beyond them or not at all until
#: 2026-12-06 (a fuzz of random typed tables, with the editor's limits or narrower ones): (convention, joint types,
#: DH rows, limits or None for the editor's, joints within the limits that reach the pose).
FOUND_ONLY_BEYOND_THE_LIMITS = [
    ('standard', 'RRR',
     [(0.0, 0.0, 0.0, 0.0), (0.418673, 1.570796, 0.0, 0.0), (0.0, -1.570796, 0.375992, 0.0)],
     [(-2.527297, 2.527297), (-1.574865, 1.574865), (-2.445075, 2.445075)],
     [-2.287752, 0.057395, -0.61196]),
    ('modified', 'RPRPR',
     [(0.0, 3.139254, 0.38304, 0.0), (0.0, 0.0, 0.0, 0.0), (0.0, 1.570796, 0.421705, 0.0),
      (0.0, 1.570796, 0.0, 0.0), (0.271854, 1.570796, 0.0, 0.0)],
     None,
     [-0.975141, 0.281725, -0.269716, 0.907009, -2.563121]),
    ('modified', 'PRRPP',
     [(0.0, -1.570796, 0.136874, 0.0), (0.469403, -1.570796, 0.0, 0.0), (0.0, -3.053215, 0.0, 0.0),
      (0.0, -1.570796, 0.142454, 0.0), (0.427943, -1.321212, 0.0, 0.0)],
     None,
     [0.876735, 1.463097, 0.735081, 0.931448, 0.019037]),
    ('standard', 'RRRRR',
     [(0.279566, 0.0, 0.0, 0.0), (0.56359, 1.570796, 0.107022, 0.0), (0.344966, 0.0, 0.0, 0.0),
      (0.0, 0.0, 0.0, 0.0), (0.111993, 1.570796, 0.0, 0.0)],
     [(-2.871013, 2.871013), (-2.877066, 2.877066), (-1.503984, 1.503984), (-1.620666, 1.620666),
      (-2.50498, 2.50498)],
     [-0.413434, -1.945178, 1.335701, 0.459459, 2.047213]),
    ('standard', 'RRRPP',
     [(0.0, 0.626499, 0.0, 0.0), (0.56013, 2.972857, 0.0, 0.0), (0.0, -0.942615, 0.199385, 0.0),
      (0.0, 2.136725, 0.0, 0.0), (0.398048, 1.290696, 0.0, 0.0)],
     [(-1.744882, 1.744882), (-2.161775, 2.161775), (-2.745275, 2.745275), (0.0, 0.875086),
      (0.0, 0.649165)],
     [1.736642, 1.533944, -1.550057, 0.857712, 0.265242]),
    ('modified', 'PRRRP',
     [(0.183361, 0.627999, 0.0, 0.0), (0.0, -1.570796, 0.384842, 0.0), (0.0, -1.570796, 0.0, 0.0),
      (0.36573, -1.570796, 0.221652, 0.0), (0.0, 1.570796, 0.0, 0.0)],
     [(0.0, 0.807919), (-1.048822, 1.048822), (-2.330107, 2.330107), (-3.103638, 3.103638),
      (0.0, 0.420965)],
     [0.59972, -0.980516, -1.136805, -2.361333, 0.301575]),
    ('standard', 'RPPRPR',
     [(0.0, 1.570796, 0.111591, 0.0), (0.0, 0.437629, 0.185952, 0.0), (0.563972, 0.0, 0.0, 0.0),
      (0.274728, 1.570796, 0.0, 0.0), (0.0, -1.570796, 0.0, 0.0), (0.0, 1.570796, 0.0, 0.0)],
     [(-1.69808, 1.69808), (0.0, 0.861655), (0.0, 0.468033), (-1.546245, 1.546245),
      (0.0, 0.824439), (-1.94627, 1.94627)],
     [-0.80152, 0.141047, 0.272086, -0.126519, 0.597571, 0.9502]),
    ('modified', 'RRPPR',
     [(0.0, -1.570796, 0.0, 0.0), (0.0, -1.570796, 0.0, 0.0), (0.502089, 2.845638, 0.0, 0.0),
      (0.0, 1.570796, 0.202564, 0.0), (0.0, -0.654962, 0.420626, 0.0)],
     [(-1.9477, 1.9477), (-1.232497, 1.232497), (0.0, 0.740556), (0.0, 0.490953),
      (-1.285344, 1.285344)],
     [-1.438078, -0.370229, 0.21552, 0.039641, -0.865616]),
]


@pytest.mark.parametrize("convention, types, rows, limits, q", FOUND_ONLY_BEYOND_THE_LIMITS,
                         ids=[case[1] for case in FOUND_ONLY_BEYOND_THE_LIMITS])
def test_a_pose_a_typed_table_reaches_within_its_limits_is_found_within_them(convention, types, rows, limits, q):
    """The search's steps ignored the limits: a stroke went below 0 and a redundant chain drifted past a stop, a
    solution within the limits was then moved along its curve of solutions to one beyond them, or the solutions
    beyond them filled the slots first. The joints that made the pose are the independent check: it is reached
    within the limits, so a solution within them must be listed."""
    arm = Arm.from_dh(rows, convention, types, limits)
    assert arm.within_limits(np.array(q))
    T = arm.fk(q)
    sol = arm.ik(T)
    inside = sol.valid & sol.within_limits
    assert inside.any(), f"{sol.valid.sum()} solutions listed, none within the limits"
    assert arm.pose_error(sol.q[inside], T).max() < 1e-9


def test_random_typed_tables_with_stops_find_every_pose_they_reach_within_their_limits():
    """Random chains of two to six joints, a sliding joint's stroke 0.2 m to 1 m, a turning joint's limits ±60° to
    ±180°: every pose made by joints within the limits is found within them (until 2026-12-06 about 1 % were
    not). Where no start ends within the limits, the search starts again with each step kept within them."""
    rng = np.random.default_rng(21)
    missed = []
    for table in range(30):
        n = int(rng.integers(2, 7))
        types = "".join(rng.choice(list("RRRRP"), n))
        rows = [(float(rng.choice([0.0, rng.uniform(0.05, 0.6)])), float(rng.choice([0.0, np.pi / 2, -np.pi / 2,
                 rng.uniform(-np.pi, np.pi)])), float(rng.choice([0.0, rng.uniform(0.05, 0.5)])), 0.0) for _ in range(n)]
        limits = [(-h, h) if kind == "R" else (0.0, float(rng.uniform(0.2, 1.0)))
                  for kind, h in zip(types, np.radians(rng.uniform(60, 180, n)))]
        arm = Arm.from_dh(rows, str(rng.choice(["standard", "modified"])), types, limits)
        q = arm.sample_joints(10, seed=table)
        sol = arm.ik(arm.fk(q))
        missed += [(types, k) for k in np.flatnonzero(~(sol.valid & sol.within_limits).any(axis=-1))]
    assert not missed, f"{len(missed)} of 300 poses not found within the limits: {missed[:5]}"


def dragged_along(arm: Arm, start: np.ndarray, goal: np.ndarray, steps: int = 40) -> list[tuple]:
    """An arm at ``start`` whose target is dragged to ``goal``'s tool along the tool's path between the two joint
    vectors, as the app takes a drag (``ArmState.move_target``): (share of the way, target, snapshot) at each step."""
    from ur10teach.state import ArmState

    state, steps_taken = ArmState(arm, start), []
    for share in np.linspace(0.0, 1.0, steps + 1)[1:]:
        T = arm.fk((1 - share) * start + share * goal)
        steps_taken.append((share, T, state.move_target(T)))
    return steps_taken


def test_a_typed_redundant_chains_drag_keeps_clear_of_a_stop_it_can_keep_clear_of():
    """A chain with more joints than its task needs (five for a position) can reach the target many ways. The
    drag's search from the arm's joints took the shortest step, which here takes the slide d3 past its end: the drag
    was refused as "reachable only beyond a joint limit" (until 2026-12-06), though the joints the target was made
    from reach it within the limits. A step that would take a joint past its stop is now found without that joint."""
    rows = [(0.0, 1.571, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), (0.0, 1.571, 0.351, 0.0), (0.0, 1.571, 0.0, 0.0),
            (0.163, 1.571, 0.0, 0.0)]
    arm = Arm.from_dh(rows, joint_types="RRPRR",
                      limits=[(-2.419, 2.419), (-2.786, 2.786), (0.0, 0.431), (-2.531, 2.531), (-1.624, 1.624)])
    start, goal = np.array([1.1877, 1.604, 0.4056, -0.7233, 0.0111]), np.array([1.0676, 0.3018, 0.3417, -0.2777, -0.4395])
    for share, T, snapshot in dragged_along(arm, start, goal):
        assert snapshot.reachable, f"at {share:.3f} of the way: {snapshot.reason}"
        assert arm.within_limits(snapshot.q) and arm.pose_error(snapshot.q, T) < 1e-9


def test_a_typed_redundant_chain_stalled_at_a_stop_moves_its_joints_off_their_stops_and_follows_on():
    """A drag follows the target by the shortest step: this chain, with two joints to spare for a position, drifted
    until its last slide met its stop at 0, and from there 30 of the 40 steps of the drag were refused (until
    2026-12-06), though the joints the targets were made from reach each within the limits. Stalled so, it now tries
    once more from its joints moved along J's null space towards the middle of their travel."""
    rows = [(0.0, 0.0, 0.344, 0.0), (0.487, -1.571, 0.0, 0.0), (0.178, 0.0, 0.307, 0.0), (0.0, 1.571, 0.0, 0.0),
            (0.0, 0.0, 0.0, 0.0)]
    arm = Arm.from_dh(rows, joint_types="RRPRP",
                      limits=[(-2.628, 2.628), (-2.6, 2.6), (0.0, 0.831), (-2.374, 2.374), (0.0, 0.794)])
    start, goal = np.array([1.8492, 2.0014, 0.6363, -2.2211, 0.0399]), np.array([-0.8966, 1.9552, 0.7902, 0.1548, 0.6234])
    refused = []
    for share, T, snapshot in dragged_along(arm, start, goal):
        if not snapshot.reachable:
            refused.append(f"{share:.3f}: {snapshot.reason}")
        else:
            assert arm.within_limits(snapshot.q) and arm.pose_error(snapshot.q, T) < 1e-9
    assert not refused, f"{len(refused)} of 40 steps refused, the first at {refused[0]}"
    assert arm.solver.redundant
    # where it stalled: the centring leaves the tool where it is (here exactly: θ4 turns it about its own axis) and
    # brings the joints nearer the middle of their travel
    q = np.array([1.5878, 1.7396, 0.5665, -2.2401, 0.0])
    centred, middle = arm.solver._centred(q), arm.limits.mean(axis=1)
    assert arm.within_limits(centred) and np.linalg.norm(arm.fk(centred)[:3, 3] - arm.fk(q)[:3, 3]) < 1e-9
    assert np.abs(centred - middle).sum() < np.abs(q - middle).sum() - 2.0


def test_a_custom_arm_typed_by_a_student():
    arm = Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0), (0, 0, 0, 0)], convention="standard", joint_types="RRP")
    assert arm.joint_types == "RRP" and arm.task == "position"
    q = np.array([0.4, 0.9, 0.3])
    sol = arm.ik(arm.fk(q), hint=q)
    assert sol.method == "found numerically"
    assert arm.pose_error(sol.q[sol.valid], arm.fk(q)).max() < 1e-9
    far = np.eye(4)
    far[:3, 3] = (1.5, 0.0, 0.0)
    assert "numerical search found no joints" in arm.ik(far).unreachable_reason()
    far[:3, 3] = (3.0, 0.0, 0.0)  # beyond every length and stroke laid end to end: not searched
    assert "reaches 1900.0 mm at most" in arm.ik(far).unreachable_reason()


def test_arm_preset_serves_every_arm():
    assert isinstance(Arm.preset("kr210"), Arm)
    assert Arm.preset("course").__class__ is Arm
    for name in ANALYTIC:
        arm = Arm.preset(name)
        assert arm.dh.n_joints == arm.n_joints == len(arm.joint_names) == len(arm.limits)
        points, manipulability = arm.sample_workspace(2000, seed=1)
        assert points.shape == (2000, 3) and (manipulability >= 0).all()
        q = arm.sample_workspace(2000, seed=1, return_joints=True)[2]
        np.testing.assert_allclose(points, arm.fk(q)[:, :3, 3])
        np.testing.assert_array_equal(arm.sample_joints(2000, seed=1), q)
        assert arm.within_limits(q).all() and not np.array_equal(arm.sample_joints(2000, seed=2), q)
        for bad in ({"n": 0}, {"n": 2.5}, {"n": 10, "seed": -1}):
            with pytest.raises(ValueError, match="must be a"):
                arm.sample_joints(**bad)


def test_manipulability_vanishes_at_the_singularities():
    kr210 = Arm.preset("kr210")
    assert kr210.manipulability(np.radians([10, 20, -30, 40, 0, 60])) < 1e-12
    q = np.radians([10, 20, -30, 40, 50, 60])
    np.testing.assert_allclose(kr210.manipulability(q), abs(np.linalg.det(kr210.jacobian(q))), rtol=1e-12)
    stanford = Arm.preset("stanford")
    assert stanford.manipulability(np.array([0.3, 0.4, 0.0, 0.2, 0.5, 0.1])) < 1e-12
    # fewer joints than rows: √det(Jᵀ J), built here from J, away from a singularity; on one, as small as σ_min
    # (the root of a rounding-level det was 5e-9 on the stretched planar elbow until 2026-12-05)
    planar = Arm.preset("planar_elbow")
    q = np.array([[0.3, 0.8], [-1.0, 2.5]])
    J = planar.jacobian(q)[..., :3, :]
    np.testing.assert_allclose(planar.manipulability(q), np.sqrt(np.linalg.det(np.swapaxes(J, -1, -2) @ J)), rtol=1e-12)
    for start in (q[0], q[1], planar.specs.home):
        stretched = planar.singular_configuration("elbow", start)
        assert planar.manipulability(stretched) < 1e-15 and planar.smallest_singular_value(stretched) == 0.0
    # more joints than rows (a typed 7R table): √det(J Jᵀ)
    seven = Arm.from_dh([(0, np.pi / 2, 0.3, 0, "R"), (0.4, 0, 0, 0, "R"), (0.3, 0, 0, 0, "R"), (0, np.pi / 2, 0, 0, "R"),
                         (0, -np.pi / 2, 0.2, 0, "R"), (0, np.pi / 2, 0.1, 0, "R"), (0, 0, 0.1, 0, "R")], "standard")
    q = seven.sample_joints(20)
    J = seven.jacobian(q)
    np.testing.assert_allclose(seven.manipulability(q), np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2))), rtol=1e-9)


@pytest.mark.parametrize("rows, words", [
    ([(0.5, 0, 0, 0, "X")], "joint must be 'R'"),
    ([(0.5, 0, float("nan"), 0, "R")], "d must be a finite number"),
    ([(0.5, 0, 0)], "must be (a, alpha, d, theta, joint)"),
    ([], "at least one row"),
    ([(0.5, 0, 0, 0, None)], "at least one joint"),
])
def test_bad_tables_are_refused_with_the_reason(rows, words):
    with pytest.raises(ValueError, match=None) as error:
        DHTable(rows, "standard")
    assert words in str(error.value)


def test_bad_values_are_refused():
    arm = Arm.preset("scara")
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 4\)"):
        arm.fk(np.zeros(6))
    with pytest.raises(ValueError, match="complex"):
        arm.fk(np.zeros(4, complex))
    with pytest.raises(ValueError, match="hint"):
        arm.ik(arm.fk(np.zeros(4)), hint=np.zeros(3))
    with pytest.raises(ValueError, match="orthonormal"):
        arm.ik(np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(ValueError, match="joint_types"):
        Arm.from_dh([(0.5, 0, 0, 0)], joint_types="RX")
    with pytest.raises(ValueError, match="unknown preset"):
        Arm.preset("kr2100")
    with pytest.raises(ValueError, match="convention"):
        DHTable([(0.5, 0, 0, 0, "R")], "craig")


@pytest.mark.parametrize("name", ["course", "ur10", "ur10e"])
def test_the_ur_family_is_the_same_chain_as_its_dh_table(name):
    """The UR closed forms are the fast path of the general chain built from their own table."""
    arm = Arm.preset(name)
    q = np.random.default_rng(4).uniform(-np.pi, np.pi, (200, 6))
    table = arm.dh
    assert table.convention == "modified" and table.joint_types == arm.joint_types == "RRRRRR"
    np.testing.assert_allclose(table.fk(q), arm.fk(q), atol=1e-12)
    np.testing.assert_allclose(table.frames(q)[:, :7], arm.frames(q), atol=1e-12)
    np.testing.assert_allclose(table.jacobian(q), arm.jacobian(q), atol=1e-12)
    assert arm.limits.shape == (6, 2)


def test_singular_flags_only_where_the_pose_leaves_a_value_free():
    kr210 = Arm.preset("kr210")
    q = np.radians([0, 15, -30, 20, 40, 10])  # the app's home: no singularity, and θ1 = 0 equals the hint's
    sol = kr210.ik(kr210.fk(q), hint=q)
    assert sol.valid.any() and not sol.singular.any()
    aligned = np.radians([0, 15, -30, 20, 0, 10])
    wrist = kr210.ik(kr210.fk(aligned), hint=aligned)
    # the branch with these joints has θ5 = 0; the elbow-down branches turn their wrists otherwise
    assert wrist.singular[int(wrist.nearest(aligned).slot)]
    assert not wrist.singular[np.abs(np.sin(wrist.q[:, 4])) > 1e-6].any()
    cylindrical = Arm.preset("cylindrical")
    assert not cylindrical.ik(cylindrical.fk([0.0, 0.3, 0.3]), hint=[0.0, 0.3, 0.3]).singular.any()
    assert cylindrical.ik(cylindrical.fk([0.5, 0.3, 0.0]), hint=[0.5, 0.3, 0.0]).singular.all()
    with_wrist = Arm.preset("cylindrical_wrist")
    for q, singular in (([0.5, 0.3, 0.3, 0.2, 0.4, 0.1], [False] * 4), ([0.5, 0.3, 0.0, 0.2, 0.4, 0.1], [True] * 4),
                        ([0.5, 0.3, 0.3, 0.2, 0.0, 0.1], [True] * 4)):  # on the column's axis; axes 4 and 6 in line
        assert with_wrist.ik(with_wrist.fk(q), hint=q).singular.tolist() == singular


@pytest.mark.parametrize("name", ["kr210", "stanford", "scara", "elbow"])
def test_row_geometry_puts_each_parameter_where_it_acts(name):
    """Turning a turn's start by its angle about its axis lands on the next axis, and the two
    segments have the row's lengths and lead from one frame origin to the next."""
    arm = Arm.preset(name)
    q = random_joints(arm, 1, 3)[0]
    frames = arm.frames(q)
    for row in range(1, len(arm.dh.rows) + 1):
        g = arm.dh.row_geometry(q, row)
        first, second = (g.d, g.a) if arm.convention == "standard" else (g.a, g.d)
        np.testing.assert_allclose(first[0], frames[row - 1, :3, 3], atol=1e-12)
        np.testing.assert_allclose(second[1], frames[row, :3, 3], atol=1e-12)
        np.testing.assert_allclose(first[1], second[0], atol=1e-12)
        assert np.linalg.norm(g.d[1] - g.d[0]) == pytest.approx(abs(g.values["d"]), abs=1e-12)
        assert np.linalg.norm(g.a[1] - g.a[0]) == pytest.approx(abs(g.values["a"]), abs=1e-12)
        theta_end = frames[row, :3, 0]
        alpha_end = frames[row, :3, 2]
        for turn, end in ((g.theta, theta_end), (g.alpha, alpha_end)):
            arc = turn.points(1.0, 3)
            np.testing.assert_allclose(arc[-1] - turn.centre, end, atol=1e-12)


def test_the_kr210_urdf_gripper_convention():
    """R_DH = R_URDF · Rz(π) · Ry(−π/2) (docs/kinematics.md §7.5), built here from the two rotations."""
    from ur10core.serial import KR210_URDF_TURN, kr210_from_urdf, kr210_to_urdf

    rz = np.diag([-1.0, -1.0, 1.0])
    c, s = math.cos(-math.pi / 2), math.sin(-math.pi / 2)
    ry = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    np.testing.assert_allclose(KR210_URDF_TURN, rz @ ry, atol=1e-15)
    arm = Arm.preset("kr210")
    T = arm.fk(random_joints(arm, 20, 2))
    urdf = kr210_to_urdf(T)
    np.testing.assert_allclose(urdf[:, :3, 0], T[:, :3, 2], atol=1e-15)  # the URDF's x is the approach z_G
    np.testing.assert_allclose(urdf[:, :3, 3], T[:, :3, 3])
    np.testing.assert_allclose(kr210_from_urdf(urdf), T, atol=1e-15)


def kr210_report_ik(T: np.ndarray, slip: bool) -> np.ndarray:
    """The KR210 report's IK written out step by step (the course's pick-and-place report, docs/kinematics.md
    §7.3): the triangle shoulder, elbow, wrist centre by the law of cosines, then R3_6 = R0_3ᵀ R0_G read off.
    ``slip``: its planar distance √(WC_x² + WC_y² − a1) in place of √(WC_x² + WC_y²) − a1."""
    centre = T[:3, 3] - 0.303 * T[:3, 2]
    theta1 = math.atan2(centre[1], centre[0])
    u = math.sqrt(centre[0] ** 2 + centre[1] ** 2 - 0.35) if slip else math.hypot(centre[0], centre[1]) - 0.35
    w = centre[2] - 0.75
    side_a, side_b, side_c = math.hypot(1.5, 0.054), math.hypot(u, w), 1.25
    angle_a = math.acos((side_b ** 2 + side_c ** 2 - side_a ** 2) / (2 * side_b * side_c))
    angle_b = math.acos((side_a ** 2 + side_c ** 2 - side_b ** 2) / (2 * side_a * side_c))
    theta2 = math.pi / 2 - angle_a - math.atan2(w, u)
    theta3 = math.pi / 2 - (angle_b + math.atan2(0.054, 1.5))
    first = SE3.Rz(theta1) * SE3.Rx(-math.pi / 2) * SE3.Rz(theta2 - math.pi / 2) * SE3.Rz(theta3)  # R0_3, by hand
    r = first.R.T @ T[:3, :3]  # R3_6 (G turns no further than frame 6)
    theta4 = math.atan2(r[2, 2], -r[0, 2])
    theta5 = math.atan2(math.hypot(r[0, 2], r[2, 2]), r[1, 2])
    theta6 = math.atan2(-r[1, 1], r[1, 0])
    return np.array([theta1, theta2, theta3, theta4, theta5, theta6])


def test_the_kr210_reports_slip_puts_the_gripper_where_its_own_steps_do():
    """The report's steps, written out in the test, with its slip: the arm they give reaches :func:`report_slip`'s
    pose, on its shoulder-front, elbow-up branch; without the slip they reach the target itself. And where
    WC_x² + WC_y² < a1 the report's square root has no value; for an arm with no shoulder offset, no slip."""
    from ur10core.serial import report_slip

    arm = Arm.preset("kr210")
    rng = np.random.default_rng(31)
    q = random_joints(arm, 400, 30)
    q[:, 0] = rng.uniform(-1.5, 1.5, len(q))  # the wrist centre in front of the shoulder: the report's θ1
    checked = 0
    for T, joints in zip(arm.fk(q), q):
        solution = arm.ik(T, hint=joints)
        if not solution.valid[:4].any():
            continue
        np.testing.assert_allclose(arm.fk(kr210_report_ik(T, slip=False)), T, atol=1e-9)
        slot = int(np.flatnonzero(solution.valid[:4])[0])
        slip = report_slip(arm, T, slot, joints)
        centre = T[:3, 3] - 0.303 * T[:3, 2]
        rho = math.hypot(centre[0], centre[1])
        assert math.isclose(slip.distance, rho - 0.35) and math.isclose(slip.radicand, rho * rho - 0.35)
        np.testing.assert_allclose(arm.fk(slip.right), T, atol=1e-9)  # the same branch, right
        np.testing.assert_allclose(slip.right, solution.take(slot, joints))
        if rho * rho < 0.35:  # the report's square root has no value
            assert math.isnan(slip.slipped) and slip.reached is None and slip.q is None
            continue
        assert math.isclose(slip.slipped, math.sqrt(rho * rho - 0.35))
        if slip.q is None:  # moved out of reach
            assert not arm.ik(slip.reached).valid[slot]
            continue
        checked += 1
        np.testing.assert_allclose(arm.fk(slip.q), slip.reached, atol=1e-9)
        report = kr210_report_ik(T, slip=True)
        np.testing.assert_allclose(arm.fk(report), slip.reached, atol=1e-9)
        assert math.isclose(np.linalg.norm(slip.reached[:3, 3] - T[:3, 3]), abs(slip.slipped + 0.35 - rho), abs_tol=1e-12)
        np.testing.assert_allclose(slip.reached[:3, :3], T[:3, :3])
        # the report's arm is the shoulder-front, elbow-up branch its wrist formula picks (θ5 ≥ 0)
        ours = [report_slip(arm, T, up, report).q for up in (0, 1)]
        assert any(mine is not None and np.abs(wrapped(mine - report, True)).max() < 1e-9 for mine in ours)
    assert checked > 200
    near = np.eye(4)
    near[:3, :3] = np.diag([1.0, -1.0, -1.0])  # gripper down: the wrist centre 0.303 m above it
    near[:3, 3] = (0.3, 0.2, 1.0 - 0.303)  # and 0.36 m from axis 1: WC_x² + WC_y² = 0.13 < 0.35
    stuck = report_slip(arm, near, 0, np.zeros(6))
    assert math.isnan(stuck.slipped) and stuck.reached is None and stuck.q is None
    with pytest.raises(ValueError, match="no shoulder offset"):
        report_slip(Arm.preset("elbow"), arm.fk(np.zeros(6)), 0, np.zeros(6))
    with pytest.raises(ValueError, match="slot must be 0..7"):
        report_slip(arm, T, 8, joints)


@pytest.mark.parametrize("name", ["kr210", "elbow", "stanford", "cylindrical_wrist"])
def test_the_wrist_centre_is_on_the_last_three_axes_and_behind_the_tool(name):
    """Every spherical wrist's centre lies on its last three joint axes, also at s5 = 0 (axes 4 and 6
    in line), and sits back from the tool along its z axis by the table's last d (KR210: d_G = 303 mm)."""
    arm = Arm.preset(name)
    rng = np.random.default_rng(3)
    q = rng.uniform(arm.limits[:, 0], arm.limits[:, 1], (2000, 6))
    q[::4, 4] = 0.0  # wrist singular
    centre = arm.wrist_centre(q)
    z, o = arm.dh.joint_axes(arm.frames(q))
    for k in (3, 4, 5):
        assert np.linalg.norm(np.cross(centre - o[:, k], z[:, k]), axis=-1).max() < 1e-12
    T = arm.fk(q)
    behind = {"kr210": 0.303, "elbow": 0.1, "stanford": 0.0, "cylindrical_wrist": 0.1}[name]
    np.testing.assert_allclose(centre, T[:, :3, 3] - behind * T[:, :3, 2], atol=1e-12)
    assert arm.wrist_centre(q[0]).shape == (3,)
    with pytest.raises(ValueError, match="no wrist"):
        Arm.preset("scara").wrist_centre(np.zeros(4))


@pytest.mark.core
@pytest.mark.parametrize("rows, slots", [(1, 1), (2, 2), (3, 4), (4, 16), (6, 16)])
def test_a_typed_tables_slots_fit_its_chain(rows, slots):
    """Issue 30, bug 3: a typed 2-link arm had sixteen slots, fourteen always empty."""
    arm = Arm.from_dh([(0.3, 0.5, 0.1, 0.0)] * rows)
    assert len(arm.ik(arm.fk(np.full(rows, 0.3))).labels) == len(arm.slot_labels) == slots


@pytest.mark.parametrize("name", ["stanford", "cylindrical", "cylindrical_wrist"])
def test_the_reversed_stroke_is_a_branch_flagged_beyond_the_range(name):
    """(s2, c2) d3 = (u, z) also holds with θ2 + π and −d3 (the cylindrical arm: θ1 + π): the
    numerical solver finds those joints too, so the closed form keeps them, valid, exact, and
    flagged as beyond the prismatic joint's range (an issue's fuzz: 4 slots where it found 8)."""
    arm = Arm.preset(name)
    q = random_joints(arm, 40, 12)
    T = arm.fk(q)
    sol = arm.ik(T)
    half = sol.q.shape[-2] // 2
    assert sol.valid.all() and "stroke reversed" in sol.labels[half]
    assert arm.pose_error(sol.q, T[:, None]).max() < 1e-9
    stroke = arm.dh.joint_types.rindex("P")
    assert (sol.q[:, half:, stroke] < 0).all() and (sol.q[:, :half, stroke] > 0).all()
    assert not sol.within_limits[:, half:].any() and sol.within_limits[:, :half].any(axis=-1).all()
    np.testing.assert_allclose(sol.nearest(q).q, q, atol=1e-9)  # the arm's own branch stays the one chosen
    if arm.n_joints == 6:  # every branch the numerical search finds is one of ours, reversed ones included
        numerical = Arm(arm.dh, arm.limits, None, f"{name} (numerical)")
        found = numerical.ik(T[:10])
        reversed_found = 0
        for k in range(10):
            ours = sol.q[k]
            for theirs in found.q[k][found.valid[k]]:
                match = np.abs(wrapped(ours - theirs, arm.revolute)).max(axis=-1) < 1e-6
                assert match.any()
                reversed_found += bool(match[half:].any())
        assert reversed_found > 0


@pytest.mark.parametrize("name", ["kr210", "stanford", "elbow", "cylindrical_wrist"])
def test_the_wrist_split_reads_the_wrist_joints_as_zyz_euler_angles(name):
    """Kinematic decoupling (docs/kinematics.md §7.3): WC is where the last three axes meet (``Arm.wrist_centre``'s
    least squares); R3_6's Z-Y-Z Euler angles, by spatialmath's ``tr2eul`` (test-only), are the arm's wrist joints,
    and the other solution (``flip=True``) is the wrist of the IK's other branch for the same target."""
    from spatialmath.base import tr2eul

    from ur10core.solvers.spherical_wrist import wrist_split

    arm = Arm.preset(name)
    for q in random_joints(arm, 200, 41):
        split = wrist_split(arm, q)
        np.testing.assert_allclose(split.centre, arm.wrist_centre(q), atol=1e-12)
        frames = arm.frames(q)
        np.testing.assert_allclose(split.R0_3 @ split.R3_6, frames[-1, :3, :3], atol=1e-12)
        c, s = math.cos(split.twist), math.sin(split.twist)
        W = np.array([[1, 0, 0], [0, c, s], [0, -s, c]]) @ split.R3_6  # Rx(−twist) R3_6
        s5, s6 = split.signs
        for flip, euler in ((False, split.euler), (True, split.euler_flipped)):
            np.testing.assert_allclose(wrapped(euler - tr2eul(W, flip=flip), np.ones(3, bool)), 0.0, atol=1e-9)
        readings = np.array([[e[0], s5 * e[1], s6 * e[2]] for e in (split.euler, split.euler_flipped)])
        np.testing.assert_allclose(wrapped(readings - split.wrist, np.ones(3, bool)), 0.0, atol=1e-9)
        own = np.abs(wrapped(split.wrist - q[3:], np.ones(3, bool))).max(axis=-1)
        assert own.min() < 1e-9
        sol = arm.ik(arm.fk(q), hint=q)
        slot = int(sol.nearest(q).slot)
        other = sol.q[slot ^ 1]  # the same arm slot, the other wrist
        np.testing.assert_allclose(wrapped(other[3:] - split.wrist[int(np.argmax(own))], np.ones(3, bool)), 0.0, atol=1e-9)
    typed = typed_copy(arm)  # numerical IK, the same wrist
    q = arm.specs.home
    np.testing.assert_allclose(wrist_split(typed, q).R3_6, wrist_split(arm, q).R3_6, atol=1e-15)
    for other_arm, why in (("ur10", r"the last three axes do not meet in one point \(at the zero pose, axes 4 and 6 pass "
                                    r"116 mm apart\)"), ("scara", "this arm has 4 joints"),
                           ("three_dof", "this arm has 3 joints")):
        with pytest.raises(ValueError, match=f"no spherical wrist: {why}"):
            wrist_split(Arm.preset(other_arm), Arm.preset(other_arm).specs.home)
