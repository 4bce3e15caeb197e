"""The app's logic without a browser: ArmState and the text the panels show."""

import threading

import numpy as np
import pytest

from ur10teach.features.ik_target import branch_table, status_markdown
from ur10teach.features.joint_panel import joints_markdown
from ur10teach.features.readouts import orientation_markdown, pose_markdown
from ur10teach.features.singularity import alarm, factor_levels
from ur10teach.state import ArmState
from ur10teach.features.workspace import VIRIDIS, KeptClouds, colormap
from ur10core import Arm

from .conftest import typed_copy, wrapped_difference


@pytest.fixture
def state(course):
    return ArmState(course)


def test_starts_on_the_course_arbitrary_pose(state, course):
    snap = state.last
    np.testing.assert_allclose(np.degrees(snap.q), [30, 45, 26, 50, 60, 80])  # the course's arbitrary pose, docs §3
    np.testing.assert_allclose(snap.target, course.fk(snap.q))
    assert snap.reachable and snap.slot == 4 and snap.solution.valid.all()
    np.testing.assert_allclose(snap.flange, course.fk(snap.q), atol=1e-14)
    assert course.a2 * course.a3 * snap.factors.prod() == pytest.approx(np.linalg.det(course.jacobian(snap.q)), rel=1e-9)


def test_set_joints_moves_the_target_with_the_flange(state, course):
    q = np.radians([10, -80, 95, -30, 70, 200])
    snap = state.set_joints(q)
    np.testing.assert_allclose(snap.q, q)
    np.testing.assert_allclose(snap.target, course.fk(q))
    # the arm's own branch is found even with θ6 beyond 180°
    np.testing.assert_allclose(snap.solution.q[snap.slot], np.radians([10, -80, 95, -30, 70, -160]), atol=1e-9)
    assert snap.cause == "joints"
    assert state.set_joint(2, 0.5).q[2] == 0.5


@pytest.mark.parametrize(
    "q, message",
    [
        ([0, 0, np.nan, 0, 0, 0], "elbow: nan is not a number"),
        ([0, 0, 0, 0, np.radians(361), 0], r"wrist 2: from -360° to 360°, got 361.0°"),
        ([0, 0, 0, 0, 0], "6 joint values are needed, got 5"),
        ("abc", "joint values must be 6 numbers"),
    ],
)
def test_bad_joints_are_refused_and_nothing_changes(state, q, message):
    before = state.q
    with pytest.raises(ValueError, match=message):
        state.set_joints(q)
    np.testing.assert_array_equal(state.q, before)


def test_a_refusal_gives_a_joints_limits_as_its_slider_shows_them():
    """The SCARA's elbow turns ±157.5°: "from -158° to 158°, got 158.0°" read as within them."""
    scara = ArmState(Arm.preset("scara"))
    with pytest.raises(ValueError, match="^θ2: from -157.5° to 157.5°, got 158.0°$"):
        scara.set_joint(1, np.radians(158.0))
    with pytest.raises(ValueError, match="^d3: from 0 mm to 210 mm, got 210.5 mm$"):
        scara.set_joint(2, 0.2105)


def test_parse_typed_degrees():
    np.testing.assert_array_equal(ArmState.parse_numbers("30, 45, 26, 50, 60, 80", 6), [30, 45, 26, 50, 60, 80])
    np.testing.assert_array_equal(ArmState.parse_numbers("30 45;26,  50 60° 80", 6), [30, 45, 26, 50, 60, 80])
    # the minus the course's texts write (−, U+2212), as a student copies it, or an en dash
    np.testing.assert_array_equal(ArmState.parse_numbers("\u221230, 0, 0, \u201390, 5.1, -0.5", 6), [-30, 0, 0, -90, 5.1, -0.5])
    # a vector as the panel writes one, v = (+100, +0, +0) mm/s, or in a list's brackets: not "'(+100' is not a number"
    np.testing.assert_array_equal(ArmState.parse_numbers("(+100, −20, 0)", 3), [100, -20, 0])
    np.testing.assert_array_equal(ArmState.parse_numbers("[1.5, 2] (3)", 3), [1.5, 2, 3])
    with pytest.raises(ValueError, match="'abc' is not a number"):
        ArmState.parse_numbers("30, 45, abc, 50, 60, 80", 6)
    with pytest.raises(ValueError, match="expected 6 numbers, got 3"):
        ArmState.parse_numbers("1, 2, 3", 6)
    # a unit or a name typed with the numbers is named, not counted as more numbers ("expected 3 numbers, got 6")
    with pytest.raises(ValueError, match="^target: 'mm' is not a number; type the numbers alone$"):
        ArmState.parse_numbers("512 mm, -256 mm, 243 mm", 3, "target")
    with pytest.raises(ValueError, match="'x' is not a number"):
        ArmState.parse_numbers("x = 512, y = -256, z = 243", 3, "target")
    with pytest.raises(ValueError, match="^target: the box is empty; type 3 numbers in it$"):  # not "got 0 in ''"
        ArmState.parse_numbers("  ", 3, "target")
    with pytest.raises(ValueError, match="'inf' is not a finite number"):
        ArmState.parse_numbers("1 2 3 4 5 inf", 6)
    # a long word pasted in is quoted in part: the refusal is a line beside the box (it quoted all 900 characters)
    for pasted in ("x" * 900, "1e999" + "9" * 900):
        with pytest.raises(ValueError) as refusal:
            ArmState.parse_numbers(f"1 2 {pasted}", 3, "target")
        assert len(str(refusal.value)) < 120, str(refusal.value)[:200]


def test_numbers_typed_in_a_full_width_input_mode_are_read_as_typed_in_ascii():
    """A Chinese, Japanese or Korean keyboard's input mode types full-width forms: ``float`` read ３０ as 30, but
    "３０，４５，２６，５０，６０，８０" was refused whole as not a number, and the ideographic comma (、) too."""
    for typed in ("３０，４５，２６，５０，６０，８０", "３０、４５、２６、５０、６０、８０", "３０　４５；２６ ５０, ６０° ８０"):
        np.testing.assert_array_equal(ArmState.parse_numbers(typed, 6), [30, 45, 26, 50, 60, 80])
    np.testing.assert_array_equal(ArmState.parse_numbers("（＋１００，　－２０．５，　０）", 3), [100, -20.5, 0])
    # a decimal comma is asked about as in ASCII, in the ASCII a student can type back
    with pytest.raises(ValueError, match=r"^target: is '1,5' one number or two\? Write decimals with a point \(1\.5\)"):
        ArmState.parse_numbers("１，５　２，５　３，５", 3, "target")
    with pytest.raises(ValueError, match="^target: 1 number here\\? Write decimals with a point: 0.0123$"):
        ArmState.parse_numbers("０，０１２３", 1, "target")


@pytest.mark.parametrize("text, count, refusal", [
    # numbers with a decimal comma, parted by spaces or semicolons, were read as twice as many: three values
    # typed as 1,5 2,5 3,5 for six joints were taken as (1, 5, 2, 5, 3, 5)
    ("1,5 2,5 3,5", 6, "is '1,5' one number or two\\? Write decimals with a point \\(1.5\\)"),
    ("0,5; −1,25; 90", 3, "is '0,5' one number or two"),
    ("10 20,5 30", 3, "is '20,5' one number or two"),
    ("0,0123", 1, "1 number here\\? Write decimals with a point: 0.0123"),  # alone it may be a list: asked when a point fits
    ("1184,3,-163,9", 2, "2 numbers here\\? Write decimals with a point: 1184.3,-163.9"),
    ("1.184,3", 1, "expected 1 number, got 2 in '1.184,3'$"),  # a thousands point too: no "1.184.3" to suggest
])
def test_a_decimal_comma_is_refused_not_read_as_two_numbers(text, count, refusal):
    with pytest.raises(ValueError, match=f"your numbers: {refusal}"):
        ArmState.parse_numbers(text, count, "your numbers")
    for listed in ("1,5,2,5,3,5", "1, 5, 2, 5, 3, 5", "1,5, 2,5, 3,5"):  # a comma after each number: a list
        np.testing.assert_array_equal(ArmState.parse_numbers(listed, 6), [1, 5, 2, 5, 3, 5])


def test_dragging_the_target_never_jumps(state, course):
    """A smooth target path gives a smooth joint path: the nearest branch every step."""
    q0 = state.q
    start = course.fk(q0)
    previous = q0
    for t in np.linspace(0, 1, 200):
        T = start.copy()
        T[:3, 3] += t * np.array([-0.25, 0.3, -0.2])
        snap = state.move_target(T)
        assert snap.reachable
        assert np.abs(snap.q - previous).max() < np.radians(5)
        np.testing.assert_allclose(course.fk(snap.q), T, atol=1e-9)
        previous = snap.q
    assert snap.slot == 4  # stayed on its branch


def test_unreachable_target_keeps_the_last_reachable_pose(state, course):
    q_before = state.q
    T = course.fk(q_before)
    T[:3, 3] = (2.0, 0.5, 0.5)
    snap = state.move_target(T)
    assert not snap.reachable and snap.slot == -1
    np.testing.assert_array_equal(snap.q, q_before)
    np.testing.assert_array_equal(snap.target, T)
    assert "elbow reach" in snap.reason and "beyond a2 + a3" in snap.reason
    assert not snap.solution.valid.any()
    # back within reach, the arm follows again
    snap = state.move_target(course.fk(q_before))
    assert snap.reachable and snap.reason == ""
    np.testing.assert_allclose(snap.q, q_before, atol=1e-9)


def test_malformed_target_is_refused(state):
    before = state.last
    with pytest.raises(ValueError, match="not orthonormal"):
        state.move_target(np.diag([2.0, 2.0, 2.0, 1.0]))
    assert state.last is before


def test_wrist_singularity_keeps_theta6(state, course):
    q = np.radians([20, -60, 70, -40, 30, 123])
    state.set_joints(q)
    for theta5 in np.radians([20, 10, 5, 1, 0.0]):  # drag towards the singularity
        target = q.copy()
        target[4] = theta5
        snap = state.move_target(course.fk(target))
    assert snap.solution.wrist_singular[snap.slot]
    assert snap.q[5] == pytest.approx(np.radians(123), abs=np.radians(1))


def test_select_every_branch(state, course):
    T = state.last.target
    for k in range(8):
        snap = state.select_branch(k)
        assert snap.slot == k and snap.cause == "branch"
        np.testing.assert_allclose(course.fk(snap.q), T, atol=1e-9)
        assert wrapped_difference(snap.q, snap.solution.q[k]).max() < 1e-12


def test_select_branch_keeps_the_joint_turns(state, course):
    q = np.radians([350, -60, 70, -40, 30, 10])  # base one turn round
    state.set_joints(q)
    snap = state.select_branch(state.last.slot ^ 1)  # the other elbow
    assert snap.q[0] == pytest.approx(q[0])


def test_select_missing_or_bad_branch(state, course):
    q = np.array([0.2, 0.1, 0.05, -0.3, 1.0, 0.4])  # near the reach: some branches missing
    state.set_joints(q)
    missing = int(np.flatnonzero(~state.last.solution.valid)[0])
    with pytest.raises(ValueError, match=f"branch {missing + 1} .* does not exist for this target"):
        state.select_branch(missing)
    for bad in (8, -1, 2.5, True):
        with pytest.raises(ValueError, match="branch must be 1..8"):
            state.select_branch(bad)


def test_a_branch_beyond_a_joint_limit_is_refused_and_says_which():
    """A widget monkey (2026-12-03): the elbow arm could be put on a branch beyond its θ2 limit, after which
    every slider, the typed joints and "Put target back on the tool" were refused ("θ2: from -90° to 150°")."""
    state = ArmState(Arm.preset("elbow"))
    solution, before = state.last.solution, state.last
    beyond = int(np.flatnonzero(solution.valid & ~solution.within_limits)[0])
    with pytest.raises(ValueError, match=rf"branch {beyond + 1} \(.*\) is beyond a joint limit \(θ2: from -90° to 150°, got"):
        state.select_branch(beyond)
    assert state.last is before
    within = int(np.flatnonzero(solution.valid & solution.within_limits & (np.arange(len(solution.valid)) != before.slot))[0])
    state.select_branch(within)
    state.set_joints(state.q)  # and from there the arm moves on


def wrist_centre_behind_the_shoulder() -> tuple:
    """The Stanford arm, its typed copy (with its limits), joints with d3 = 2 mm, and the same joints with d3 = -50 mm:
    the wrist centre behind the shoulder, a pose only a reversed stroke or θ2 turned over reaches."""
    stanford = Arm.preset("stanford")
    q = np.array([0.3, 0.8, 0.002, 0.2, 0.5, 0.1])
    behind = q.copy()
    behind[2] = -0.05
    return stanford, typed_copy(stanford, with_limits=True), q, behind


def test_a_drag_never_puts_the_arm_beyond_a_joint_limit():
    """A drag took the branch nearest the arm's joints, beyond a limit or not: the Stanford arm's wrist centre
    dragged 50 mm behind its shoulder put d3 at -50 mm, and from there every slider and "Put target back on the
    tool" were refused ("d3: from 0 mm to 762 mm", until 2026-12-04). The arm takes the nearest branch a real arm
    can take; a typed table, which follows one branch, stays where it is and says which joint would leave its range."""
    stanford, typed, q, behind = wrist_centre_behind_the_shoulder()
    for arm in (stanford, typed):
        state = ArmState(arm, q)
        snap = state.move_target(arm.fk(behind))
        assert arm.within_limits(snap.q), np.round(snap.q, 3)
        if arm is stanford:  # the branch with the stroke forward, θ2 turned over: the same pose
            assert snap.reachable and snap.q[2] == pytest.approx(0.05)
            np.testing.assert_allclose(arm.fk(snap.q), arm.fk(behind), atol=1e-9)
        else:
            assert not snap.reachable and np.array_equal(snap.q, q)
            assert "beyond a joint limit (joint 3: from 0 mm to 762 mm, got -50.0 mm)" in snap.reason
            assert "Find every branch" in snap.reason
        state.set_joint(0, 0.31)  # and the sliders move it on
        state.set_joints(state.q)  # and "Put target back on the tool"


def test_find_every_branch_puts_a_typed_arm_that_stopped_short_on_the_nearest_branch_within_its_limits():
    """After a typed arm's drag stopped short ("another branch may reach it within them (Find every branch)"), the
    search's branches were listed with "← arm" on one beyond d3's limit, the arm not at the target at all, and the
    reason kept saying the target was unreachable (until 2026-12-04). The arm now takes the nearest branch found
    within its limits, as a preset's arm takes its nearest on a drag."""
    stanford, typed, q, behind = wrist_centre_behind_the_shoulder()
    state = ArmState(typed, q)
    stopped = state.move_target(typed.fk(behind))
    assert not stopped.reachable
    found = state.with_branches(stopped, typed.ik(stopped.target, hint=stopped.q))
    assert found.reachable and found.solution.within_limits[found.slot]
    assert typed.within_limits(found.q) and found.q[2] == pytest.approx(0.05)
    np.testing.assert_allclose(typed.fk(found.q), typed.fk(behind), atol=1e-9)
    state.set_joint(0, found.q[0] + 0.01)  # and the sliders move it on


def test_a_typed_arm_never_calls_a_target_it_did_not_search_enough_unreachable():
    """A typed Stanford arm told "Target unreachable." of a pose typed from its own joints (114 of 200 such poses)
    when its search from the arm's joints stopped short, or took a branch beyond a limit, while its reason said
    another branch "may reach it" (until 2026-12-05). Its headline says not reached; Find every branch reaches it."""
    stanford, typed, q, _ = wrist_centre_behind_the_shoulder()
    state = ArmState(typed, q)
    goal = typed.sample_joints(200, seed=3)[0]  # within the limits: reachable by construction
    stopped = state.move_target(typed.fk(goal), cause="typed")
    assert not stopped.reachable and "Find every branch" in stopped.reason
    assert "**Target not reached.**" in status_markdown(stopped) and "unreachable" not in status_markdown(stopped).lower()
    found = state.with_branches(stopped, typed.ik(stopped.target, hint=stopped.q))
    assert found.reachable
    np.testing.assert_allclose(typed.fk(found.q), typed.fk(goal), atol=1e-9)
    far = np.eye(4)
    far[:3, 3] = (5.0, 0.0, 0.0)
    beyond = state.move_target(far, cause="typed")
    searched = state.with_branches(beyond, typed.ik(beyond.target, hint=beyond.q))  # and its search says why
    assert "every length and stroke laid end to end, reaches" in status_markdown(searched)
    assert "**Target not reached.**" in status_markdown(searched)


def test_a_target_reachable_only_beyond_a_limit_is_unreachable_with_its_branches_listed():
    """The cylindrical arm's tool below its base needs d2 < 0: its two branches reach it, beyond d2's range."""
    from ur10teach.features.ik_target import branches_markdown

    arm = Arm.preset("cylindrical")
    state = ArmState(arm)
    before = state.q
    T = state.last.target.copy()
    T[2, 3] = -0.2
    snap = state.move_target(T)
    assert not snap.reachable and np.array_equal(snap.q, before)
    assert snap.reason == "reachable only beyond a joint limit (d2: from 0 mm to 700 mm, got -500.0 mm)"
    assert snap.solution.valid.all() and not snap.solution.within_limits.any()
    assert branches_markdown(snap).count("beyond a joint limit") == 3  # the reason, and each branch's flag


@pytest.mark.parametrize("name", ["elbow", "kr210", "scara", "stanford", "cylindrical_wrist", "three_dof"])
def test_a_random_drag_keeps_every_arm_within_its_limits(name):
    """A random walk of the target (2 cm steps), back to the arm where it is refused. Until 2026-12-04 it put the
    elbow arm, the KR210, the SCARA, the Stanford arm and the cylindrical arm with a wrist beyond a limit."""
    arm = Arm.preset(name)
    state = ArmState(arm)
    rng = np.random.default_rng(0)
    for _ in range(1500):
        T = state.last.target.copy()
        T[:3, 3] += rng.normal(0.0, 0.02, 3)
        snap = state.move_target(T)
        assert arm.within_limits(snap.q), (np.round(snap.q, 3), snap.slot)
        if not snap.reachable:  # back to where the arm is, as a student would drag back
            state.set_joints(state.q)


@pytest.mark.parametrize("kind, factor", [("shoulder", 0), ("elbow", 1), ("wrist", 2)])
def test_place_in_singularity(state, kind, factor):
    snap = state.place_in_singularity(kind)
    assert abs(snap.factors[factor]) < 1e-12
    assert snap.factors.prod() == pytest.approx(0, abs=1e-12)
    with pytest.raises(ValueError, match="kind must be 'shoulder', 'elbow' or 'wrist', got 'knee'"):
        state.place_in_singularity("knee")


def test_each_singularity_button_starts_from_a_clean_pose(state):
    """Pressing "wrist" after "elbow" used to leave the arm on both."""
    start = state.q
    assert (np.abs(state.last.factors) > 0.1).all()
    for kind, factor in (("elbow", 1), ("wrist", 2), ("shoulder", 0), ("wrist", 2)):
        snap = state.place_in_singularity(kind)
        assert abs(snap.factors[factor]) < 1e-12
        others = [k for k in range(3) if k != factor]
        assert (np.abs(snap.factors[others]) > 0.05).all(), f"{kind} left the arm on another singularity"
    # any other change starts a new row from where the arm then is
    moved = state.set_joint(0, 1.0)
    snap = state.place_in_singularity("elbow")
    assert snap.q[0] == pytest.approx(1.0) and snap.q[2] == 0.0
    assert not np.allclose(start, moved.q)


def test_ghost_frames(state, course):
    q = np.array([0.2, 0.1, 0.05, -0.3, 1.0, 0.4])
    snap = state.set_joints(q)
    valid = snap.solution.valid
    assert not valid.all()
    np.testing.assert_array_equal(snap.ghost_frames[~valid], np.broadcast_to(np.eye(4), (int((~valid).sum()), 7, 4, 4)))
    np.testing.assert_allclose(snap.ghost_frames[valid], course.frames(snap.solution.q[valid]), atol=1e-14)


def test_concurrent_changes_stay_consistent(state, course):
    """Callbacks of one browser overlap on viser's thread pool; the state must not tear."""
    rng = np.random.default_rng(5)
    targets = course.fk(rng.uniform(-1, 1, (200, 6)))
    errors = []

    def drag():
        for T in targets:
            try:
                state.move_target(T)
            except Exception as error:  # pragma: no cover - reported below
                errors.append(error)

    def slide():
        for q in rng.uniform(-1, 1, (200, 6)):
            state.set_joints(q)

    threads = [threading.Thread(target=drag), threading.Thread(target=slide)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    snap = state.last
    np.testing.assert_allclose(snap.frames, course.frames(snap.q), atol=1e-14)


def test_panel_texts(course):
    state = ArmState(course)
    snap = state.last
    table = branch_table(snap)
    assert table.count("\n") == 9 and "**← arm**" in table and "shoulder right, elbow down, wrist not flipped" in table
    assert "8 of 8 branches" in status_markdown(snap) and "5: shoulder right, elbow down" in status_markdown(snap)
    T = snap.target.copy()
    T[:3, 3] = (0.05, 0.02, 0.6)
    T[:3, :3] = np.eye(3)
    unreachable = state.move_target(T)
    assert "Target unreachable" in status_markdown(unreachable) and "inside the shoulder cylinder" in status_markdown(unreachable)
    assert "no solution" in branch_table(unreachable)
    pose = pose_markdown(course.fk(np.zeros(6)))
    assert "**+1184.5**" in pose and "**-256.1**" in pose and "**+243.7**" in pose
    assert pose.startswith("| n | o | a | p (mm) |")  # the columns named as the course's reports name them
    # R = Rx(90°), a = (0, −1, 0): φ = atan2(−1, 0), θ = atan2(1, 0), ψ = atan2(1, 0) by the report's formulas, or
    # with φ + 180° ("or + 180°", the report says) θ = atan2(−1, 0) and ψ = atan2(−1, 0)
    assert ("**Z-Y-Z Euler** (φ, θ, ψ) = (-90.00°, 90.00°, 90.00°) or (90.00°, -90.00°, -90.00°)"
            in orientation_markdown(course.fk(np.zeros(6))[:3, :3]))
    assert "**Z-Y-Z Euler** (φ, θ, ψ) = (0.00°, 0.00°, 0.00°), as" in orientation_markdown(np.eye(3))  # only φ + ψ: one
    assert "Z-Y-X Euler" in orientation_markdown(np.eye(3)) and "(+1.0000, +0.0000, +0.0000, +0.0000)" in orientation_markdown(np.eye(3))
    controller = joints_markdown(course, np.zeros(6), with_controller=True)
    assert "| shoulder | 0.00° | 180.00° |" in controller


def test_singular_poses_show_in_the_status(course):
    state = ArmState(course, q=np.radians([45, 90, 0, -90, 0, 60]))
    text = status_markdown(state.last)
    assert "Shoulder singular" in text and "Elbow singular" in text and "Wrist singular" in text


def test_overlay_levels_and_alarm(course):
    state = ArmState(course, q=np.radians([45, 90, 0, -90, 0, 60]))
    np.testing.assert_allclose(factor_levels(course, state.last.factors), 0, atol=1e-12)
    assert alarm(0.0) == 1.0 and alarm(1.0) == 0.0 and 0 < alarm(0.2) < 1


def test_colormap_ends():
    colors = colormap(np.array([0.0, 1.0, 2.0]), top=1.0)
    np.testing.assert_array_equal(colors[0], VIRIDIS[0])
    np.testing.assert_array_equal(colors[1], VIRIDIS[-1])
    np.testing.assert_array_equal(colors[2], VIRIDIS[-1])


def test_presets_load_their_meshes():
    from ur10teach.meshes import load_links

    for preset in Arm.UR_PRESETS:
        links = load_links(preset)
        assert len(links) == 7 and all(len(link.body_faces) for link in links)


def test_the_kept_clouds_stay_within_their_memory_budget():
    """Review 2, finding 5: the cache kept four clouds whatever their size (six sizes cycled: a 1.46 GB peak)."""
    kept = KeptClouds(budget=10 * 2**20)
    made = []

    def cloud(n: int):
        made.append(n)
        return np.zeros((n, 3), np.float32), np.zeros((n, 3), np.uint8), 1.0  # 15 bytes a point

    for n in (100_000, 200_000, 500_000, 100_000, 200_000, 500_000):
        kept.get(("cloud", n), lambda n=n: cloud(n))
        assert kept.nbytes <= 10 * 2**20
    assert made == [100_000, 200_000, 500_000, 100_000, 200_000, 500_000]  # 7.5 MB leaves room for no other
    kept.get(("cloud", 500_000), lambda: cloud(1))
    assert made[-1] == 500_000  # the newest is kept
    huge = kept.get(("cloud", 1_000_000), lambda: cloud(1_000_000))  # over the budget alone: kept, the others go
    assert len(huge[0]) == 1_000_000 and kept.nbytes == 15_000_000


def test_the_clouds_nobody_shows_are_forgotten_once_browsers_leave():
    """Review 2, finding 2: memory went back to its baseline only once no cloud outlived the browsers showing it."""
    kept = KeptClouds()
    shown, left = object(), object()

    def cloud(n: int):
        return np.zeros((n, 3), np.float32), np.zeros((n, 3), np.uint8), 1.0

    kept.get(("cloud", 10), lambda: cloud(10), shown)
    kept.get(("cloud", 20), lambda: cloud(20), left)
    kept.get(("cloud", 30), lambda: cloud(30))  # asked for, shown by no one
    kept.release(left)
    kept.forget_unheld()
    assert kept.nbytes == 10 * 15  # only what a browser still shows
    kept.release(shown)
    kept.forget_unheld()
    assert kept.nbytes == 0


@pytest.mark.parametrize("name", ["stanford", "cylindrical", "scara", "kr210", "three_dof", "ur10"])
def test_a_target_typed_1e300_m_out_is_refused_in_a_reason_of_a_few_words(name):
    """Until 2026-12-05 the Stanford arm's raised OverflowError (the nearest branch's distance), and the lengths of a
    reason read as 300 digits: "got 14142135623730952903445465077352849385153726695921116…  mm"."""
    from ur10core import Arm

    state = ArmState(Arm.preset(name))
    for coordinate in (1e300, -1e300, 1e30):
        T = state.last.target.copy()
        T[:2, 3] = coordinate
        snapshot = state.move_target(T, cause="typed")
        assert not snapshot.reachable and len(snapshot.reason) < 200, snapshot.reason
        assert "e+" in snapshot.reason or "too far away to measure" in snapshot.reason, snapshot.reason


@pytest.mark.parametrize("name", ["course", "kr210", "stanford", "elbow", "scara", "cylindrical", "cylindrical_wrist",
                                  "planar_elbow"])
def test_each_walkthrough_row_names_the_value_its_joint_moves(name):
    """The walkthrough's rows read alike for every joint; each now says which value varies ("θ2 = q2 − 90°", "d3 =
    q3"). Checked against the row's geometry: move only that joint and see which of θ, d, a, α changes, and by how much."""
    import math
    import re

    from ur10core import Arm
    from ur10teach.features.dh_table import walkthrough_steps

    arm = Arm.preset(name)
    q = arm.limits.mean(axis=1)
    for text, _, row in walkthrough_steps(arm)[2:]:
        before = arm.dh.row_geometry(q, row).values
        match = re.search(r"\*Joint (\d+) (turns|slides): (θ|d)<sub>(\d+)</sub> = q(\d+)(?: ([+−]) ([\d.]+)°?)? varies", text)
        if arm.dh.rows[row - 1].joint is None:
            assert "A fixed row" in text and match is None
            continue
        joint = int(match.group(1)) - 1
        moved = q.copy()
        moved[joint] += 0.01
        after = arm.dh.row_geometry(moved, row).values
        changed = [key for key in ("theta", "d", "a", "alpha") if not math.isclose(before[key], after[key], abs_tol=1e-12)]
        assert changed == ["theta" if match.group(3) == "θ" else "d"], (text, changed)
        assert int(match.group(4)) == row and match.group(5) == match.group(1)
        assert (match.group(2) == "turns") == (match.group(3) == "θ") == (arm.joint_types[joint] == "R")
        offset = 0.0 if match.group(6) is None else float(match.group(7)) * (1 if match.group(6) == "+" else -1)
        value = math.degrees(before["theta"]) - math.degrees(q[joint]) if match.group(3) == "θ" else 1000 * (before["d"] - q[joint])
        assert math.isclose(value, offset, abs_tol=0.51), (text, value)
