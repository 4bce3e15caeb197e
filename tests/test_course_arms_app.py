"""The arm picker and the course's other arms in the app (server side, through viser's protocol)."""

from __future__ import annotations

import asyncio
import dataclasses
import math
import time
import weakref

import numpy as np
import pytest
import viser

from ur10teach.features import motion_lessons
from ur10teach.features.arm_picker import ARM_CHOICES, CUSTOM, UR10
from ur10teach.features.dh_table import dh_table_markdown
from ur10teach.features.ik_target import branches_markdown
from ur10teach.features.velocity import METRES_PER_SPEED
from ur10teach.session import ArmSession
from ur10core import Arm

from .server_support import a_ghost_to_take, become_presenter, get, screen_addresses, session_of, until, url
from ur10dev.viser_client import CAMERA, ViserClient, wxyz_of
from ur10dev.waiting import HANG_TIMEOUT

pytestmark = pytest.mark.server

KR210 = "KR210 (spherical wrist)"
TARGET = "/course_arm/ik_target"


def session_for(app, client_id: int):
    return app.sessions.get(client_id)


async def pick(app, client: ViserClient, label: str):
    """Choose ``label`` in the "Arm" dropdown, as a student does, once the current dropdown has arrived."""
    client_id = int(client.gizmo_owner)
    await until(lambda: "Which arm" in client.gui and client.gui["Which arm"]["uuid"] not in client.received.removed_gui,
                what="the arm picker")
    await until(lambda: app.can_switch(client_id), what="the arm to be ready for a change")  # one change per interval
    await client.set_gui("Which arm", label)
    await until(lambda: getattr(session_for(app, client_id), "choice", None) == label, what=f"the {label}")
    session = session_for(app, client_id)
    await arrived(client, session)
    return session


async def build_table(app, client: ViserClient, rows: str, joint_types: str, replacing) -> ArmSession:
    """Type ``rows`` into the DH editor and build them, as a student does, once the arm may change;
    returns the new arm's session (of ``joint_types``, in ``replacing``'s place) once its panel is in."""
    client_id = int(client.gizmo_owner)
    await until(lambda: "Rows" in client.gui, what="the editor")
    await client.set_gui("Rows", rows)
    await until(lambda: app.can_switch(client_id), what="the arm to be ready for a change")
    await client.set_gui("Build this arm", True)
    await until(lambda: session_for(app, client_id) is not replacing
                and getattr(session_for(app, client_id), "arm", None) is not None
                and session_for(app, client_id).arm.joint_types == joint_types, what="the typed arm")
    typed = session_for(app, client_id)
    await arrived(client, typed)
    return typed


async def arrived(client: ViserClient, session) -> None:
    """Wait until this browser holds ``session``'s own picker, the last widget a session builds.

    Messages arrive in order: by then the old arm's widgets are gone and the new ones are in,
    so a label (the UR10 and the other arms share some) names the new arm's widget.
    """
    await until(lambda: (client.gui.get("Which arm") or {}).get("uuid") == session.arm_picker.dropdown._impl.uuid,
                what="the new arm's panel")


def test_picking_the_kr210_builds_its_arm_and_drags_it(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        first = session_of(app, client)
        session = await pick(app, client, KR210)
        assert first.closed
        assert "/ik_target" in client.received.removed_nodes  # the UR10's gizmo went with its arm
        await until(lambda: "A1 (°)" in client.gui and "/course_arm/body" in client.received.nodes, what="the KR210")
        # drag the target to a pose of known joints: the arm takes the branch nearest where it was
        q = np.radians([25, 10, -20, 30, 45, 15])
        T = session.arm.fk(q)
        await client.drag_target(T[:3, 3], wxyz_of(T), "start", name=TARGET)
        await client.drag_target(T[:3, 3], wxyz_of(T), "end", name=TARGET)
        await until(lambda: np.allclose(session.state.last.q, q, atol=1e-9), what="the arm at the dragged pose")
        snapshot = session.state.last
        assert snapshot.reason == "" and snapshot.solution.valid[snapshot.slot]
        # out of reach: the arm stays, and the panel says why, with the numbers
        far = T.copy()
        far[:3, 3] = (5.0, 0.0, 1.0)
        await client.drag_target(far[:3, 3], wxyz_of(far), "update", name=TARGET)
        await until(lambda: session.state.last.reason != "", what="the reason")
        assert "reach at most" in session.state.last.reason
        np.testing.assert_allclose(session.state.last.q, q, atol=1e-9)
        assert "Target unreachable" in branches_markdown(session.state.last)
        # a slider moves one joint, in degrees
        await client.set_gui("A2 (°)", 30.0)
        await until(lambda: math.isclose(session.state.last.q[1], math.radians(30.0), abs_tol=1e-9), what="A2 = 30°")
        # and back to the UR10, with its whole panel
        back = await pick(app, client, UR10)
        assert session.closed and not back.closed
        await until(lambda: "Show workspace cloud" in client.gui, what="the UR10's panel")
        await client.close()

    asyncio.run(scenario())


def test_a_branch_the_target_does_not_have_is_refused_below_the_branch_buttons(app):
    """The KR210's first target has branches 1 to 4: pressing 6 is explained right below *Use branch* (it was a
    notice at the window's far corner), and the next branch taken clears it."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "KR210 (spherical wrist)")
        assert not session.state.last.solution.valid[5]
        line = session.ik_target.branch_refusal.line
        await client.set_gui("Use branch", "6")
        await until(lambda: line.visible and "Branch 6 (shoulder back, elbow up, wrist flipped) does not exist for this "
                    "target" in client.markdown[line._impl.uuid], what="the refusal below the buttons")
        assert not any(title == "Not accepted" for title, _ in client.received.notifications)
        await client.set_gui("Use branch", "2")
        await until(lambda: session.state.last.slot == 1 and not line.visible, what="branch 2, and the line gone")
        await client.close()

    asyncio.run(scenario())


def test_a_prismatic_joint_is_driven_in_millimetres(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Stanford arm (RRP + wrist)")
        await client.set_gui("d3 (mm)", 300.0)
        await until(lambda: math.isclose(session.state.last.q[2], 0.3, abs_tol=1e-9), what="d3 = 300 mm")
        await client.set_gui("d3 (mm)", 5000.0)  # beyond the stroke: refused below the sliders, with a message
        refusal = session.joints.slider_refusal.line
        await until(lambda: "from 0 mm to 762 mm, got 5000.0 mm" in client.markdown.get(refusal._impl.uuid, "") and refusal.visible,
                    what="the refusal, with the stroke")
        assert math.isclose(session.state.last.q[2], 0.3, abs_tol=1e-9)
        await until(lambda: client.gui["d3 (mm)"]["value"] == 300.0, what="the slider put back")
        await client.set_gui("Pose", "Random")  # the arm set another way: the refusal no longer stands below the sliders
        await until(lambda: not refusal.visible, what="the refusal gone with the pose")
        await client.close()

    asyncio.run(scenario())


def test_the_stanford_reports_example_is_one_click_and_its_t6_is_read_as_the_report_reads_it(app):
    """The *Report's example* pose (every angle 100°, d3 = 10 in) and the Tool pose folder's Z-Y-Z angles, both of
    the report's solutions, which its GUI reads from T6: against spatialmath's ``tr2eul`` of the arm's T06 (test-only)."""
    from spatialmath.base import tr2eul

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Stanford arm (RRP + wrist)")
        await client.set_gui("Pose", "Report's example")
        q = session.arm.specs.poses["report's example"]
        await until(lambda: np.allclose(session.state.last.q, q, atol=1e-12), what="the report's example")
        phi, theta, psi = np.degrees(tr2eul(session.arm.fk(q)[:3, :3]))
        other = np.degrees(tr2eul(session.arm.fk(q)[:3, :3], flip=True))  # the report's "or + 180°"
        line = (f"**Z-Y-Z Euler** (φ, θ, ψ) = ({phi:.2f}°, {theta:.2f}°, {psi:.2f}°) or "
                f"({other[0]:.2f}°, {other[1]:.2f}°, {other[2]:.2f}°)")
        await until(lambda: any(line in text for text in client.markdown.values()), what=line)
        await client.close()

    asyncio.run(scenario())


def test_the_stanford_arm_stands_on_a_pedestal_up_to_its_shoulder_and_its_floor_is_under_it(app):
    """The report's table starts at the shoulder (d1 = 0). Until 2026-12-04 the arm was drawn with its shoulder
    on the floor, and every branch of the report's own example read "⚠ floor". It stands on a pedestal from the
    floor to its base frame now; the floor check is against the drawing's own floor: the world's z of every
    point it draws, from its base frame's place as the browser was sent it."""
    from ur10core.orientation import from_frame

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Stanford arm (RRP + wrist)")
        arm, drawing = session.arm, session.drawing
        await until(lambda: drawing.root in client.received.positions, what="the arm's base frame placed")
        shoulder = np.array(client.received.positions[drawing.root])
        np.testing.assert_allclose(shoulder, (0.0, 0.0, arm.base_height))
        np.testing.assert_allclose(shoulder + drawing.pedestal.points[0], [(0.0, 0.0, 0.0), shoulder], atol=1e-6)
        down = np.array([0.3, math.radians(170.0), 0.7, 0.2, 0.5, 0.1])  # the boom hanging down: the wrist 0.69 m below
        for q, through in ((arm.specs.poses["report's example"], False), (down, True)):
            session.apply(lambda state: state.set_joints(q))
            snapshot = session.state.last
            drawn = np.concatenate([snapshot.frames[None], snapshot.ghost_frames])[..., :3, 3]
            lowest_z = np.array([(points + shoulder)[:, 2].min() for points in drawn])
            np.testing.assert_allclose(from_frame(drawing.world, drawn[0]), drawn[0] + shoulder)
            expected = np.concatenate([[True], snapshot.solution.valid]) & (lowest_z < -1e-3)
            np.testing.assert_array_equal(snapshot.through_floor, expected)
            assert expected[0] == through
        await client.close()

    asyncio.run(scenario())


def test_every_arm_can_be_picked_and_an_unknown_one_is_refused(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        for label, name in ARM_CHOICES.items():
            if name in (None, "custom", "three_dof"):  # the DH editor's arm and the desktop arm have their own tests
                continue
            session, last = await pick(app, client, label), name
            snapshot = session.state.last
            assert snapshot.slot >= 0 and snapshot.solution.valid.any()
            np.testing.assert_allclose(session.arm.fk(snapshot.q), snapshot.target, atol=1e-9)
        client_id = int(client.gizmo_owner)
        await client.set_gui("Which arm", "PUMA 560")
        await until(lambda: any("not one of the choices" in body for _, body in client.received.notifications),
                    what="the refusal")
        assert session_for(app, client_id).arm.name == last  # the last picked, kept
        await client.close()

    asyncio.run(scenario())


def test_dh_tables_show_both_conventions():
    kr210 = Arm.preset("kr210")
    modified = dh_table_markdown(kr210.dh)
    assert "α<sub>i−1</sub>" in modified and "q2 − 90°" in modified and "fixed" in modified and "303.0" in modified
    standard = dh_table_markdown(kr210.dh.converted("standard"))
    assert "θ<sub>i</sub> | d<sub>i</sub>" in standard
    stanford = dh_table_markdown(Arm.preset("stanford").dh)
    assert "q3" in stanford and "161.9" in stanford


def test_a_typed_dh_table_becomes_an_arm_with_numerical_ik(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, CUSTOM)
        assert session.state.numerical and session.arm.joint_types == "RRR"  # the starting table
        client_id = int(client.gizmo_owner)
        # a bad row is refused, naming the line
        await until(lambda: "Rows" in client.gui, what="the editor")
        await client.set_gui("Rows", "500 0 0 0 R\n400 0 0 R")
        await client.set_gui("Build this arm", True)  # one connection's messages are handled in order
        # explained beside the table it came from, not in a notice at the far edge (issue 30)
        await until(lambda: "line 2: a row is five entries" in session.editor.refusal.line.content.lower()
                    and session.editor.refusal.line.visible, what="the refusal beside the table")
        assert not any("five entries" in body.lower() for _, body in client.received.notifications)
        assert session_for(app, client_id) is session
        # a planar 2R arm ("Find every branch" was the last arm's too: its panel is waited for)
        typed = await build_table(app, client, "500 0 0 0 R\n400 0 0 0 R", "RR", session)
        assert typed.editor.rows.value.startswith("500 0 0 0 R")
        # dragging follows the target from the arm's joints
        goal = typed.arm.fk(np.radians([40.0, 50.0]))
        await client.drag_target(goal[:3, 3], wxyz_of(goal), "start", name=TARGET)
        await until(lambda: np.abs(typed.arm.fk(typed.state.last.q)[:3, 3] - goal[:3, 3]).max() < 1e-9,
                    what="the typed arm at the target")
        # and "Find every branch" finds both elbows
        await client.set_gui("Find every branch", True)
        await until(lambda: typed.state.last.solution is not None, what="the search")
        solution = typed.state.last.solution
        assert solution.method == "found numerically" and int(solution.valid.sum()) == 2
        shown = branches_markdown(typed.state.last)
        # a 2R arm has room for two solutions, not sixteen, and none is listed empty (issue 30, bug 3)
        assert len(solution.labels) == 2 and "found numerically 2" in shown
        assert "**2 solutions** found (this chain has at most 2)" in shown and "no solution" not in shown
        # a click on the other elbow's ball puts the arm on it
        other, balls = 1 - typed.state.last.slot, typed.drawing.ghost_joints
        drawn = lambda: balls.batched_scales.reshape(2, -1)[other]  # noqa: E731
        await until(lambda: drawn().any(), what="the other elbow's ghost")
        await client.click_node(balls.name, other * typed.drawing.joints_per_ghost + int(np.argmax(drawn())))
        await until(lambda: typed.state.last.slot == other, what="the arm on the other elbow")
        np.testing.assert_allclose(typed.arm.fk(typed.state.last.q)[:3, 3], goal[:3, 3], atol=1e-9)
        await client.close()

    asyncio.run(scenario())


def test_a_section_of_a_typed_arm_that_holds_no_point_is_refused_saying_so(app):
    """A table of zero lengths keeps its tool on the base axis: the cut-away holds nothing (numpy's "zero-size array
    to reduction operation maximum" reached the student)."""
    from ur10teach.features.workspace import SECTIONS

    async def scenario():
        client = await ViserClient(url(app)).connect()
        typed = await build_table(app, client, "0 0 0 0 R", "R", await pick(app, client, CUSTOM))
        await client.set_gui("Show workspace cloud", True)
        await until(lambda: typed.workspace._cloud is not None, what="the cloud, a dot on the base axis")
        await client.set_gui("Section", SECTIONS[3])
        line = typed.workspace.refusal.line  # in the folder (until 2026-12-05 a notice in the window's corner)
        await until(lambda: line.visible and f"the {SECTIONS[3]} holds no point of this arm's workspace" in line.content.lower(),
                    what="the refusal")
        assert not any(title == "Something went wrong" for title, _ in client.received.notifications)
        await client.close()

    asyncio.run(scenario())


def test_a_typed_tables_branches_are_numbered_where_they_part_once_searched(app):
    """A typed SCARA (RRP) has two elbows over one wrist: its numbers go by the elbows, chosen from the branches its
    search finds. (The SCARA preset's went by the wrist until 2026-12-03: one label, "arm: 1 · 2".)"""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, CUSTOM)
        typed = await build_table(app, client, "400 0 0 0 R\n300 0 0 0 R\n0 0 0 0 P", "RRP", session)
        goal = typed.arm.fk(np.array([0.5, 1.0, 0.1]))
        await client.drag_target(goal[:3, 3], wxyz_of(goal), "start", name=TARGET)
        await until(lambda: np.abs(typed.arm.fk(typed.state.last.q)[:3, 3] - goal[:3, 3]).max() < 1e-9,
                    what="the typed arm at the target")
        await client.set_gui("Find every branch", True)
        await until(lambda: typed.state.last.solution is not None and len(typed.drawing.numbers.placed) == 2,
                    what="both elbows numbered")
        assert [members for members, _, _ in typed.drawing.numbers.placed] == [(0,), (1,)]
        await client.close()

    asyncio.run(scenario())


def test_the_scaras_numbers_go_by_its_elbows_after_it_came_back_on_its_singularity(app):
    """Where the arm is first drawn on a singularity (its branches together), the frame its numbers go by is
    chosen once they are apart: a SCARA left stretched and picked again numbers its elbows once it bends."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        scara = await pick(app, client, "SCARA (RRP + roll)")
        await client.set_gui("θ2 (°)", 0.0)
        await until(lambda: scara.state.last.q[1] == 0.0, what="the SCARA stretched")
        await pick(app, client, "Planar elbow (2R)")
        scara = await pick(app, client, "SCARA (RRP + roll)")
        assert scara.state.last.q[1] == 0.0 and int(scara.state.last.solution.valid.sum()) == 2
        await client.set_gui("θ2 (°)", 60.0)
        await until(lambda: [members for members, _, _ in scara.drawing.numbers.placed] == [(0,), (1,)],
                    what="both elbows numbered")
        await client.close()

    asyncio.run(scenario())


def test_parse_table_refuses_what_is_not_a_table():
    from ur10teach.features.course_arms.editor import parse_table

    for text, words in (("", "empty"), ("1 2 3 4 X", "type must be"), ("a b c d R", "must be numbers"),
                        ("9000 0 0 0 R", "lengths up to"), ("1 0 0 0 F", "at least one joint"),
                        ("\n".join(["100 0 0 0 R"] * 11), "at most 10 rows"), ("nan 0 0 0 R", "finite"),
                        ("1 0 0 0 R 90 -90", "min < max"), ("1 0 0 0 R -400 0", "±360°"), ("1 0 0 0 P 0 9000", "±5000 mm"),
                        ("1 0 0 0 R 10", "five entries"), ("1 0 0 0 R\n1 0 0 0 F 0 1", "fixed row has no limits"),
                        ("1 0 0 0 R x 1", "must be numbers"), ("# " + "x" * 1000 + "\n1 0 0 0 R", "too long"),
                        ("1 0 0 0 R\n400 0 0,5 0 R", "line 2: is '0,5' one number or two")):
        with pytest.raises(ValueError, match=words):
            parse_table(text, "standard")
    arm = parse_table("# a comment\n0, 90, 400, 0, R  # base\n400 0 0 0 r\n0 0 100 0 P", "modified")
    assert arm.joint_types == "RRP" and arm.convention == "modified" and arm.task == "position"
    np.testing.assert_allclose(arm.limits, [[-math.pi, math.pi]] * 2 + [[0.0, 1.0]])  # none typed: the defaults
    limited = parse_table("0 90 400 0 R -170 170\n400 0 0 0 R, -45, 135\n0 0 100 0 P 50 300", "standard")
    assert parse_table("0 90 400 0 R \u2212170 170\n400 \u221290 0 0 R", "standard") == parse_table(
        "0 90 400 0 R -170 170\n400 -90 0 0 R", "standard")  # the minus the course writes, copied
    assert parse_table("0 90° 400 0° R -170° 170°\n400 0 0 0 R", "standard") == parse_table(
        "0 90 400 0 R -170 170\n400 0 0 0 R", "standard")  # degrees as the course writes them (refused until 2026-12-04)
    assert parse_table("０　９０　４００　０　Ｒ　－１７０　１７０　＃ｂａｓｅ\n４００，０，０，０，ｒ", "standard") == parse_table(
        "0 90 400 0 R -170 170\n400 0 0 0 R", "standard")  # a full-width input mode's (refused whole until 2026-12-07)
    np.testing.assert_allclose(limited.limits, [np.radians([-170, 170]), np.radians([-45, 135]), [0.05, 0.3]])


@pytest.mark.parametrize("name", ["scara", "kr210", "stanford"])
def test_the_skeleton_walks_each_row_along_d_then_a(name):
    """Every DH row is two straight moves between frame origins (standard: d along z_{i−1}, then a
    along x_i; modified: a along x_{i−1}, then d along z_i), so the drawing shows the table's numbers."""
    from ur10teach.features.course_arms.scene import skeleton

    arm = Arm.preset(name)
    q = np.random.default_rng(1).uniform(arm.limits[:, 0], arm.limits[:, 1])
    frames = arm.frames(q)
    segments = skeleton(arm.dh, frames)
    np.testing.assert_allclose(segments[1:, 0], segments[:-1, 1], atol=1e-12)  # one connected path
    np.testing.assert_allclose(segments[0, 0], frames[0, :3, 3], atol=1e-12)
    np.testing.assert_allclose(segments[-1, 1], frames[-1, :3, 3], atol=1e-12)
    _, d = arm.dh.row_parameters(q)
    lengths = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=-1)
    expected = [v for row, dv in zip(arm.dh.rows, d) for v in ((abs(dv), abs(row.a)) if arm.convention == "standard" else (abs(row.a), abs(dv)))]
    np.testing.assert_allclose(np.sort(lengths), np.sort([v for v in expected if v > 1e-9]), atol=1e-12)


def test_a_row_shown_on_the_arm_and_the_walkthrough(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Stanford arm (RRP + wrist)")
        scene = session.drawing
        await client.set_gui("Show a row on the arm", "row 3")  # the prismatic row: d3 is the joint
        await until(lambda: scene.dh_frames.highlight_row == 3 and scene.dh_frames.parameters["d"].visible, what="row 3 drawn")
        await until(lambda: getattr(scene.dh_frames.parameter_labels.get("d"), "text", "") == "d3 = 254.0 mm", what="d3's value")
        segment = scene.dh_frames.parameters["d"].points[0]
        assert np.linalg.norm(segment[1] - segment[0]) == pytest.approx(0.254, abs=1e-6)
        assert not scene.dh_frames.parameters["a"].visible  # a3 = 0: nothing to draw, and the panel lists it
        await until(lambda: "a<sub>3</sub> = 0.0 mm" in session.dh_table.row_values.content, what="row 3's values")
        await client.set_gui("Show a row on the arm", "row 99")  # not an option: refused
        await until(lambda: any("not one of the choices" in body for _, body in client.received.notifications),
                    what="the refusal")
        # the walkthrough: z axes alone, then x too, then each row
        await client.set_gui("Step", "Next ▶")
        # the step is counted before the scene is redrawn: wait for the drawing itself
        await until(lambda: session.walkthrough.step == 0 and not scene.dh_frames.x_axes.visible, what="step 1")
        assert scene.dh_frames.z_axes.visible and scene.dh_frames.highlight_row is None
        for expected in (1, 2):
            await client.set_gui("Step", "Next ▶")
            await until(lambda: session.walkthrough.step == expected, what=f"step {expected + 1}")
        await until(lambda: scene.dh_frames.x_axes.visible and scene.dh_frames.highlight_row == 1, what="row 1 drawn")
        await until(lambda: "Row 1" in session.walkthrough.text.content and "Step 3 of 8" in session.walkthrough.text.content,
                    what="row 1's text")
        await client.set_gui("Step", "Stop")
        await until(lambda: session.walkthrough.step == -1 and scene.dh_frames.highlight_row is None, what="the walkthrough stopped")
        await client.close()

    asyncio.run(scenario())


def test_a_course_arms_workspace_cloud(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "SCARA (RRP + roll)")
        await client.set_gui("Show workspace cloud", True)
        await until(lambda: session.workspace._cloud is not None, what="the cloud")
        points = session.workspace._cloud.points
        # a SCARA's tool stays in the annulus its links sweep and below its column
        radius = np.hypot(points[:, 0], points[:, 1])
        assert radius.max() <= 0.6 + 1e-4 and points[:, 2].max() <= 0.387 + 1e-3
        # the legend shows just after the cloud is drawn (a CI run read it in between, 2026-12-03)
        await until(lambda: session.workspace.legend.visible, what="the cloud's legend in the panel")
        await until(lambda: f"{session.drawing.root}/workspace" in client.received.nodes, what="the cloud under the arm's root")
        # the UR10's sections, where they apply: the cut-away keeps the half behind the arm's plane
        from ur10core.workspace import turnable_into
        from ur10teach.features.workspace import HULL, SECTIONS, coloured_cloud

        hint = session.workspace.section.hint
        assert session.workspace.sections_missing.visible and session.workspace.sections_missing.content == hint
        assert SECTIONS[2] in session.workspace.section.options and "horizontal" not in hint
        # θ1 turns ±105°: no hull, which would turn the outline a full turn; the side view keeps what θ1 turns into it
        assert HULL not in session.workspace.section.options and "θ1 turns from -105° to 105° only" in hint
        whole = np.asarray(points, dtype=float)
        turns = coloured_cloud(session.arm, len(whole))[3]
        await client.set_gui("Section", SECTIONS[1])
        q1 = float(session.state.last.q[0])
        kept = turnable_into(whole, q1, turns, (-np.radians(105), np.radians(105)))
        assert 0 < kept.sum() < len(whole)
        await until(lambda: len(session.workspace._cloud.points) == kept.sum(), what="the side view")
        await client.set_gui("Section", HULL)  # a browser never sends a choice it was not given: refused
        line = session.workspace.refusal.line
        await until(lambda: line.visible and "is not one of the choices" in line.content, what="the refusal")
        await client.set_gui("Show workspace cloud", False)
        await until(lambda: session.workspace._cloud is None, what="the cloud gone")
        await client.close()

    asyncio.run(scenario())


def test_the_kr210_gripper_pose_in_the_urdf_convention(app):
    async def scenario():
        from ur10teach.features.course_arms.gripper import GripperPose, parse_pose, pose_text

        from ur10core.serial import kr210_to_urdf

        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, KR210)
        gripper = next(lesson for lesson in session.lessons if isinstance(lesson, GripperPose))
        q = np.radians([20, 10, -15, 30, 40, 50])
        T = session.arm.fk(q)
        # typed in the simulation model's convention, the arm goes to the same gripper pose
        await client.set_gui("ROS/Gazebo gripper convention", True)
        # the box is rewritten in the new convention: a student types once it has been
        await until(lambda: gripper.typed.value == pose_text(kr210_to_urdf(session.state.last.target)),
                    what="the box in the URDF convention")
        await client.set_gui("x y z (mm) roll pitch yaw (°)", pose_text(kr210_to_urdf(T)))
        await client.set_gui("Go to this pose", True)
        await until(lambda: np.abs(session.arm.fk(session.state.last.q) - T).max() < 1e-3, what="the arm at the pose")
        await until(lambda: "URDF" in gripper.readout.content, what="the readout in the URDF convention")
        # a pose that is not six numbers is refused
        await client.set_gui("x y z (mm) roll pitch yaw (°)", "1 2 3")
        await client.set_gui("Go to this pose", True)
        await until(lambda: "six numbers" in gripper.refusal.line.content, what="the refusal beside the pose")
        np.testing.assert_allclose(parse_pose(pose_text(T)), T, atol=1e-3)
        # the minus the course writes, copied, is a minus here too (it was "must be numbers"); a decimal comma is asked about
        np.testing.assert_allclose(parse_pose(pose_text(T).replace("-", "\u2212")), T, atol=1e-3)
        with pytest.raises(ValueError, match="the pose: is '2,5' one number or two"):
            parse_pose("1000 2,5 1500 0 0 0")
        await client.close()

    asyncio.run(scenario())


def on_segments(points: np.ndarray, segments: np.ndarray) -> bool:
    """Every one of ``points`` (n, 3) lies on one of ``segments`` (m, 2, 3), to a micrometre."""
    start, along = segments[:, 0], segments[:, 1] - segments[:, 0]
    t = np.clip(np.einsum("nmk,mk->nm", points[:, None] - start[None], along) / np.einsum("mk,mk->m", along, along), 0, 1)
    gaps = np.linalg.norm(points[:, None] - (start[None] + t[..., None] * along[None]), axis=-1)
    return bool((gaps.min(axis=1) < 1e-6).all())


def test_the_kr210_reports_slip_is_drawn_where_its_formula_puts_the_arm(app):
    """The course's KR210 report writes the wrist centre's distance beyond the shoulder √(WC_x² + WC_y² − a1); ticked,
    the arm that formula gives is drawn dashed along its DH skeleton, to the gripper it reaches, with the gap to the
    target dashed and named, and the folder says by how much. Near axis 1 the report's square root fails: said, not
    drawn. Only the KR210 has the folder."""
    async def scenario():
        from ur10teach.features.course_arms.kr210_lessons import ReportSlipView
        from ur10teach.features.course_arms.scene import skeleton

        from ur10core.serial import report_slip

        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, KR210)
        view = next(lesson for lesson in session.lessons if isinstance(lesson, ReportSlipView))
        assert "The report's slip" in client.gui
        await client.set_gui("Show the report's arm", True)
        q = np.radians([20, 10, -30, 20, 40, 10])
        session.apply(lambda state: state.set_joints(q))
        slip = report_slip(session.arm, session.arm.fk(q), session.state.last.slot, q)
        await until(lambda: view.arm_lines.visible and client.received.visible.get(view.arm_lines.name), what="the dashed arm")
        dashes = np.asarray(view.arm_lines.points, float).reshape(-1, 3)
        assert on_segments(dashes, skeleton(session.arm.dh, session.arm.frames(slip.q)))
        assert not on_segments(dashes, skeleton(session.arm.dh, session.arm.frames(q)))  # not the arm's own
        gap = np.asarray(view.miss.points, float).reshape(-1, 3)
        np.testing.assert_allclose(gap[[0, -1]], [slip.reached[:3, 3], session.arm.fk(q)[:3, 3]], atol=1e-6)
        assert 0.2 < np.linalg.norm(gap[0] - gap[-1]) < 0.3
        (point, text, _), = view.names()
        np.testing.assert_allclose(point, slip.reached[:3, 3])
        assert text == f"the report's gripper, {1000 * abs(slip.slipped - slip.distance):.0f} mm off"
        await until(lambda: f"**{1000 * abs(slip.slipped - slip.distance):.0f} mm** farther out" in view.readout.content,
                    what="the gap in the folder")
        np.testing.assert_allclose(slip.right, q, atol=1e-9)  # the arm is on a front branch: its own joints are right
        for name, mine, right in zip(session.arm.joint_names, slip.q, q):  # side by side, for a student's own code
            assert f"| {name} | {np.degrees(mine):.1f}° | {np.degrees(right):.1f}° |" in view.readout.content
        # the wrist centre near axis 1: WC_x² + WC_y² < a1, and the report's code stops (a pose within the joint
        # limits: the one this test had, (300, 200, 697) mm pointing down, is reached only with A3 at 118°)
        near = session.arm.fk(np.radians([-106, -11, -66, 115, -96, 168]))
        wrist_centre = session.arm.wrist_centre(np.radians([-106, -11, -66, 115, -96, 168]))
        assert wrist_centre[0] ** 2 + wrist_centre[1] ** 2 < session.arm.dh.rows[1].a
        session.apply(lambda state: state.move_target(near, cause="typed"))
        await until(lambda: "square root of" in view.readout.content and not client.received.visible.get(view.arm_lines.name),
                    what="the report's error, nothing drawn")
        assert session.state.last.reachable
        assert view.names()[0][0] is None
        elbow = await pick(app, client, "Elbow arm + spherical wrist")
        assert "The report's slip" not in client.gui and not any(isinstance(v, ReportSlipView) for v in elbow.panel_views)
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", [KR210, "Stanford arm (RRP + wrist)", "Elbow arm + spherical wrist",
                                   "Cylindrical arm + wrist"])
def test_every_arm_with_a_spherical_wrist_splits_its_pose_at_the_wrist_centre(app, label):
    """Kinematic decoupling, the course's IK method for these arms: ticked, WC is named in 3D where the last three axes
    meet; the folder gives WC, the joints that place it, R3_6 and its Z-Y-Z Euler angles, the arm's wrist joints,
    with the other solution the other wrist. The UR10 and the SCARA have no spherical wrist: their folder says so."""
    async def scenario():
        from ur10core.solvers.spherical_wrist import wrist_split

        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        arm, view = session.arm, session.decoupling
        assert "Wrist centre (decoupling)" in client.gui and "Name WC on the arm" in client.gui
        (point, text, _), = view.names()
        assert point is None and text == "WC"  # not named until asked
        await client.set_gui("Name WC on the arm", True)
        q = arm.specs.home.copy()
        q[4] = -q[4]  # the wrist flipped
        session.apply(lambda state: state.set_joints(q))
        await until(lambda: view.names()[0][0] is not None and np.allclose(view.names()[0][0], arm.wrist_centre(q)),
                    what="WC named where the wrist's axes meet")
        split = wrist_split(arm, q)
        own = split.euler if np.abs(split.wrist[0] - q[3:]).max() < 1e-9 else split.euler_flipped
        words = f"(φ, θ, ψ) = **({', '.join(f'{np.degrees(a):.1f}°' for a in own)})**"
        await until(lambda: words in view.readout.content, what="the arm's wrist as Z-Y-Z Euler angles")
        content = view.readout.content
        assert "is the wrist not flipped" in content and "Joints 1–3 place WC" in content
        assert f"{split.centre[2] * 1000:.0f}) mm" in content
        for other, why in ((UR10, "the last three axes do not meet in one point"),
                           ("SCARA (RRP + roll)", "this arm has 4 joints")):
            session = await pick(app, client, other)
            assert "Wrist centre (decoupling)" in client.gui and "Name WC on the arm" not in client.gui
            assert session.decoupling.readout.content.startswith(f"No spherical wrist: {why}")
            assert all(text != "WC" for _, text, _ in session.decoupling.names())
        assert session.decoupling.names() == [] and not session.decoupling.steps.visible  # the SCARA: nothing to name
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("wrist", [60.0, 0.0, -60.0])
def test_the_ur10s_folder_shows_the_course_ik_step_by_step_from_p5(app, wrist):
    """Its last three axes do not meet, so the pose does not split at a wrist centre: the folder says so and replays
    the course's separation of variables (docs §4.1) on the pose with its numbers, from P5, which it names in 3D
    when asked, to the arm's own joints and branch, the IK target's number for it. On θ5 = 0 it says that R fixes
    only θ234 ± θ6 and keeps the arm's θ6."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client)
        arm, view = session.arm, session.decoupling
        assert "Name P5 on the arm" in client.gui and "Name WC on the arm" not in client.gui
        assert view.readout.content.startswith("No spherical wrist: the last three axes do not meet in one point")
        (point, text, _), = view.names()
        assert point is None and text == "P5"
        await client.set_gui("Name P5 on the arm", True)
        q = np.radians([30, 45, 26, 50, wrist, 80])
        session.apply(lambda state: state.set_joints(q))
        T = arm.fk(q)
        p5 = T[:3, 3] - arm.d6 * T[:3, 2]  # P5 = p − d6 z6, from the pose
        await until(lambda: view.names()[0][0] is not None and np.allclose(view.names()[0][0], p5, atol=1e-12),
                    what="P5 named where axes 5 and 6 meet")
        own = [f"**θ{k} = {value:.1f}°**" for k, value in ((1, 30), (6, 80), (3, 26))] + ["= **45.0°**", "= **50.0°**",
                                                                                       f"**θ5 = {wrist:.1f}°**"]
        await until(lambda: all(words in view.steps.content for words in own), what="the steps ending at the arm's joints")
        solution = arm.ik(T, hint=q)
        slot = next(k for k in range(8) if solution.valid[k] and np.abs(solution.q[k] - q).max() < 1e-9)
        content = view.steps.content
        assert f"branch {slot + 1} ({arm.slot_labels[slot]})" in content
        assert f"ρ = {1000 * np.hypot(*p5[:2]):.1f} mm" in content and f"d4 = {1000 * arm.d4:.1f} mm" in content
        assert ("R fixes only θ234 ± θ6" in content) == (wrist == 0.0)
        assert ("wrist flipped" in content) == (wrist < 0)
        await client.close()

    asyncio.run(scenario())


def test_changing_arms_too_fast_is_refused_and_the_picker_shows_the_arm_still_driven(app, monkeypatch):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, KR210)
        monkeypatch.setattr("ur10teach.serving.server.SWITCH_INTERVAL", 30.0)  # however slow this machine, the next change is too soon
        client_id = int(client.gizmo_owner)
        await until(lambda: "Which arm" in client.gui, what="the new picker")
        await client.set_gui("Which arm", "SCARA (RRP + roll)")  # at once: too soon
        await until(lambda: any("one change of arm every" in body.lower() for _, body in client.received.notifications),
                    what="the refusal")
        assert session_for(app, client_id) is session and not session.closed
        await until(lambda: session.arm_picker.dropdown.value == KR210, what="the picker put back")
        await client.close()

    asyncio.run(scenario())


def test_singularity_gauges_empty_and_turn_red_at_each_factors_singularity():
    from ur10teach.features.singularity import factors_html

    kr210 = Arm.preset("kr210")
    regular = factors_html(kr210, np.radians([0, 15, -30, 20, 40, 10]))
    assert "width:0.0%" not in regular and "zero when the wrist centre is on axis 1" in regular
    aligned = factors_html(kr210, np.radians([0, 15, -30, 20, 0, 10]))  # θ5 = 0
    wrist = aligned[aligned.index("gauge-wrist"):]
    assert wrist.split("width:")[1].startswith("0.0%") and "#dc2626" in wrist[:200]
    typed = Arm.from_dh([(0.5, 0, 0, 0), (0.4, 0, 0, 0)], joint_types="RR")
    assert "smallest singular value" in factors_html(typed, np.array([0.2, 0.4]))


@pytest.mark.parametrize("name", Arm.PRESETS)
def test_on_each_singularity_button_the_panel_reads_manipulability_and_sigma_min_zero(name):
    """As the factor's gauge reads +0.0000 and the ellipsoids' axis 0: "manipulability 3.197e-18, smallest singular
    value 7.048e-18" (rounding) was what the UR10's shoulder button showed until 2026-12-06. Off it, they read as
    before, to four digits."""
    from ur10teach.features.singularity import factors_html

    arm = Arm.preset(name)
    for factor in arm.factor_names:
        try:
            q = arm.singular_configuration(factor, arm.specs.home)
        except ValueError:  # the cylindrical arms' reach: no such pose within the limits
            continue
        assert "manipulability 0, smallest singular value 0<" in factors_html(arm, q), factor
    away = factors_html(arm, arm.specs.home)
    assert f"smallest singular value {float(arm.smallest_singular_value(arm.specs.home)):.4g}<" in away


def test_any_table_a_student_types_can_be_built_driven_and_searched():
    """Random tables (1–10 rows, R/P/F, odd twists, zero lengths, both conventions): every view's
    text builds, a small drag follows, and every branch the search reports reaches the target."""
    from ur10teach.features.course_arms.editor import parse_table
    from ur10teach.features.course_arms.scene import skeleton
    from ur10teach.features.dh_table import walkthrough_steps
    from ur10teach.features.singularity import factors_html
    from ur10teach.state import ArmState

    rng = np.random.default_rng(0)
    built = 0
    for _ in range(40):
        rows = [f"{rng.choice([0, rng.uniform(-800, 800)]):.1f} {rng.choice([0, 90, -90, 180, rng.uniform(-180, 180)]):.1f} "
                f"{rng.choice([0, rng.uniform(-800, 800)]):.1f} {rng.choice([0, 90, rng.uniform(-180, 180)]):.1f} "
                f"{rng.choice(['R', 'P', 'F'], p=[0.6, 0.3, 0.1])}" for _ in range(rng.integers(1, 11))]
        try:
            arm = parse_table("\n".join(rows), str(rng.choice(["standard", "modified"])))
        except ValueError:
            continue  # every row fixed
        built += 1
        state = ArmState(arm)
        snapshot = state.last
        assert branches_markdown(snapshot) and factors_html(arm, snapshot.q) and walkthrough_steps(arm)
        assert dh_table_markdown(arm.dh) and len(skeleton(arm.dh, snapshot.frames))
        target = snapshot.frames[-1].copy()
        target[:3, 3] += 0.02
        moved = state.move_target(target)
        assert moved.reason or arm.pose_error(moved.q, moved.target) <= 1e-9
        solution = arm.ik(moved.target, hint=moved.q)
        if solution.valid.any():
            assert arm.pose_error(solution.q[solution.valid], moved.target).max() <= 1e-9
    assert built >= 30



def test_singularities_shown_on_the_arm_turn_red_at_the_singularity(app):
    async def scenario():
        from ur10teach.features.singularity import FACTOR_COLORS
        from ur10teach.style import DANGER_RED

        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, KR210)
        overlay = session.drawing.overlay
        assert not overlay.lines["wrist"].visible  # off until asked for
        await client.set_gui("Show singularity overlay", True)
        await until(lambda: overlay.enabled and overlay.lines["wrist"].visible and getattr(overlay.labels.get("elbow"), "visible", False),
                    what="the factors drawn")
        assert tuple(overlay.lines["wrist"].colors) == FACTOR_COLORS["wrist"]  # far from s5 = 0 at home
        # A5 to 0: axes 4 and 6 in line, drawn parallel and red
        await client.set_gui("A5 (°)", 0.0)
        await until(lambda: session.state.last.q[4] == 0.0, what="A5 = 0")
        await until(lambda: tuple(overlay.lines["wrist"].colors) == DANGER_RED, what="the wrist axes red")
        axes = overlay.lines["wrist"].points
        directions = [(b - a) / np.linalg.norm(b - a) for a, b in axes]
        assert np.linalg.norm(np.cross(*directions)) < 1e-6
        await client.set_gui("Show singularity overlay", False)
        await until(lambda: not overlay.lines["wrist"].visible, what="the factors hidden")
        await client.close()

    asyncio.run(scenario())


def test_every_line_is_drawn_in_one_colour_a_browser_can_read(app):
    """viser's browser reads per-vertex uint8 line colours as 0…1 floats: every colour above 1 shows
    white. So each line-segments node of the UR10 and of a course arm, overlays on, has one (3,) colour."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        ur10 = session_of(app, client)
        await client.set_gui("Show singularity overlay", True)
        await until(lambda: ur10.drawing.overlay.enabled, what="the UR10 overlay")
        kr210 = await pick(app, client, KR210)
        await client.set_gui("Show singularity overlay", True)
        await until(lambda: kr210.drawing.overlay.enabled, what="the KR210 overlay")
        for session in (ur10, kr210):
            lines = [h for h in session.client.scene._handle_from_node_name.values() if isinstance(h, viser.LineSegmentsHandle)]
            if session is ur10:  # its scene was reset when the KR210 came: check the handles it kept
                lines = list(session.drawing.overlay.lines.values())
            assert lines and all(np.asarray(h.colors).shape == (3,) for h in lines), [h.name for h in lines]
        await client.close()

    asyncio.run(scenario())


def test_a_course_arms_velocities_ellipsoids_and_forces(app):
    """The Stanford arm (a sliding joint): joint rates to v and ω at its tool, a typed twist to joint rates
    (mm/s for d3, no speed limits), the ellipsoids' lengths, and τ = Jᵀ F for a force at the tool."""
    async def scenario():
        from ur10teach.features.statics import bars_html
        from ur10teach.features.velocity import (
            METRES_PER_SPEED,
            parse_twist,
            rates_markdown,
        )

        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Stanford arm (RRP + wrist)")
        arm, root = session.arm, session.drawing.root
        await client.set_gui("ḋ3 (mm/s)", 100.0)  # the boom slides out at 0.1 m/s
        await until(lambda: session.velocity.linear.visible, what="the velocity arrow")
        snapshot = session.state.last
        tip = snapshot.frames[-1, :3, 3]
        expected = tip + METRES_PER_SPEED * arm.tool_twist(snapshot.q, [0, 0, 0.1, 0, 0, 0])[:3]
        np.testing.assert_allclose(session.velocity.linear.points[0], [tip, expected], atol=1e-6)
        assert f"{root}/velocity/linear" in client.received.nodes
        # a typed tool velocity: the rates it needs, d3's in mm/s, with no limits to flag
        await client.set_gui("Find the joint rates", True)
        asked = parse_twist("100 0 0 0 0 0")
        rates = arm.joint_rates(snapshot.q, asked)
        text = rates_markdown(rates.qdot, float(rates.damping), asked, rates.achieved, arm.joint_names, "RRPRRR", None)
        await until(lambda: session.velocity.rates.content == text, what="the joint rates")
        assert " mm/s |" in text and "limit" not in text
        # the ellipsoids' lengths, with the tool's orientation held
        await client.set_gui("Show at the tool", True)
        await until(lambda: session.ellipsoids.velocity.visible and "orientation held" in session.ellipsoids.lengths.content,
                    what="the ellipsoids")
        # a force at the tool: the joints' torques, d3's as a force along its axis; no masses, no ratings
        await client.set_gui("Show the torques", True)
        await client.set_gui("Force direction", "+x")
        torques = arm.static_torques(snapshot.q, [50.0, 0, 0])
        expected = bars_html(torques, np.zeros(6), None, arm.joint_names, "RRPRRR")
        await until(lambda: session.statics.bars.content == expected, what="the torques")
        assert session.statics.arrow.visible and f"{torques[2]:+.1f} N " in expected and "No published ratings" in expected
        assert not session.statics.payload.visible  # no link masses: no gravity, no payload
        await client.close()

    asyncio.run(scenario())


def test_the_tabs_of_one_address_change_arms_no_more_often_than_one_tab():
    """Review 2, finding 5: eight tabs of one address flicking the picker at 4/s took 59 % of the server."""
    from ur10teach.serving.gate import Gate
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(port=0, gate=Gate(trust_loopback=False))  # loopback addresses stand in for laptops
    app.clock = lambda: 1000.0  # time stands still: what the address has in hand is all it gets

    async def scenario():
        tabs = [await ViserClient(url(app), local_address="127.0.0.2").connect() for _ in range(3)]
        for tab in tabs:
            await tab.set_gui("Which arm", KR210)
        await until(lambda: sum(getattr(session_for(app, int(tab.gizmo_owner)), "choice", None) == KR210 for tab in tabs) == 2
                    and any("one change of arm every" in body.lower() for tab in tabs for _, body in tab.received.notifications),
                    what="two tabs on the KR210 and the third refused")
        other = await ViserClient(url(app), local_address="127.0.0.3").connect()  # another laptop: its own allowance
        await pick(app, other, KR210)
        for client in (*tabs, other):
            await client.close()

    try:
        asyncio.run(scenario())
    finally:
        app.stop()


def test_going_back_to_an_arm_finds_its_pose_target_typed_table_and_display_as_left(app):
    """Issue 29: switching to another arm and back lost the UR10's pose and target, a typed table
    went back to the starting one, and what the student had switched on was off again (and, until
    2026-12-03, the joint rates and the force the student had set; until 2026-12-05, a velocity asked and the
    texts typed)."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        ur10 = session_of(app, client)
        ur10.apply(lambda state: state.set_joints(np.radians([10.0, -70.0, 80.0, -20.0, 50.0, 30.0])))
        ur10_left = ur10.state.last
        stanford = await pick(app, client, "Stanford arm (RRP + wrist)")
        goal = stanford.state.last.frames[-1].copy()
        goal[:3, 3] += (0.05, -0.03, 0.02)
        await client.drag_target(goal[:3, 3], wxyz_of(goal), "start", name=f"{stanford.drawing.root}/ik_target")  # under its pedestal's top
        await until(lambda: np.allclose(stanford.state.last.target[:3, 3], goal[:3, 3], atol=1e-6), what="the Stanford arm moved")
        stanford_left = stanford.state.last
        await client.set_gui("Show ghost arms", False)  # and what it shows
        await client.set_gui("Show singularity overlay", True)
        rate = stanford.velocity.sliders[2].label  # and what its lessons were set to: the stroke's rate, the force
        await client.set_gui(rate, 120.0)
        await client.set_gui("Force at the tool (N)", 200.0)
        await client.set_gui("vx vy vz (mm/s) ωx ωy ωz (°/s)", "0 0 50 0 0 0")  # a tool velocity asked
        await client.set_gui("Find the joint rates", True)
        await client.set_gui("vx vy vz (mm/s) ωx ωy ωz (°/s)", "0 0 80")  # and one typed, not yet asked
        await client.set_gui(stanford.ik_target.typed_pose.label, "100 200 300")  # a target typed, not yet moved to
        await until(lambda: not stanford.drawing.show_ghosts and stanford.drawing.overlay.enabled
                    and stanford.velocity.sliders[2].value == 120.0 and stanford.statics.newtons.value == 200.0
                    and "| joint | rate |" in stanford.velocity.rates.content and stanford.ik_target.typed_pose.value == "100 200 300"
                    and stanford.velocity.typed.value == "0 0 80", what="the choices applied")
        rates_left = stanford.velocity.rates.content
        typed = await pick(app, client, CUSTOM)
        await build_table(app, client, "500 0 0 0 R\n400 0 0 0 R", "RR", typed)

        # the panel's title and the tab's name the arm (until 2026-12-07 every tab was named "Viser")
        await until(lambda: client.received.panel_label == CUSTOM and client.tab_title == CUSTOM, what="the titles naming the arm")
        back = await pick(app, client, UR10)
        assert back.state.last is ur10_left  # the pose, target and branches as left
        await until(lambda: client.received.panel_label == client.tab_title == "UR10 kinematics (course)", what="the UR10's titles")
        await until(lambda: abs(back.joints.sliders[1].value + 70.0) < 1e-6, what="the shoulder slider at −70°")
        back = await pick(app, client, "Stanford arm (RRP + wrist)")
        assert back.state.last is stanford_left
        assert not back.ik_target.show_ghosts.value and not back.drawing.show_ghosts  # shown as chosen, in the panel and 3D
        assert back.singularities.enabled.value and back.drawing.overlay.enabled and back.drawing.overlay.lines["wrist"].visible
        assert back.velocity.sliders[2].value == 120.0 and back.statics.newtons.value == 200.0
        assert back.velocity.typed.value == "0 0 80" and back.ik_target.typed_pose.value == "100 200 300"  # as typed
        await until(lambda: back.velocity.rates.content == rates_left, what="the joint rates of the velocity asked")
        assert [slider.value for slider in back.joints.sliders] == pytest.approx(  # the pose is the state's, not a kept setting
            np.degrees(stanford_left.q) * np.where(np.array(list(back.arm.joint_types)) == "R", 1.0, 0.0)
            + 1000 * stanford_left.q * (np.array(list(back.arm.joint_types)) == "P"), abs=0.06)
        back = await pick(app, client, CUSTOM)
        assert back.arm.joint_types == "RR" and back.editor.rows.value.startswith("500 0 0 0 R\n400")
        await client.close()

    asyncio.run(scenario())


def test_a_browser_back_from_its_computer_finds_its_arms_as_it_left_them(app):
    """viser makes a browser that reconnects (a reload, a laptop woken, the Wi-Fi back) a new client: it started again
    on the UR10 at home, its typed table and what it showed gone (until 2026-12-05). Another computer starts afresh,
    and so does this one once it has been away longer than ``RETURN_WINDOW``."""
    from ur10teach.serving.gate import RETURN_WINDOW

    async def connect(address: str) -> tuple[ViserClient, ArmSession]:
        client = await ViserClient(url(app), local_address=address).connect()
        session = session_of(app, client)
        await arrived(client, session)
        return client, session

    async def scenario():
        laptop, ur10 = await connect("127.0.0.2")
        ur10.apply(lambda state: state.set_joints(np.radians([10.0, -70.0, 80.0, -20.0, 50.0, 30.0])))
        ur10_left = ur10.state.last
        typed = await build_table(app, laptop, "500 0 0 0 R\n400 0 0 0 R", "RR", await pick(app, laptop, CUSTOM))
        await laptop.set_gui("Show ghost arms", False)
        await until(lambda: not typed.drawing.show_ghosts, what="the ghosts off")
        typed_left = typed.state.last
        await laptop.close()
        await until(lambda: not app.sessions, what="the laptop gone")

        neighbour, fresh = await connect("127.0.0.3")  # another computer: nothing of the laptop's
        assert fresh.choice == UR10 and fresh.state.last is not ur10_left and not neighbour.received.notifications
        again, back = await connect("127.0.0.2")
        assert back.choice == CUSTOM and back.state.last is typed_left and not back.drawing.show_ghosts
        assert back.editor.rows.value.startswith("500 0 0 0 R\n400")
        await until(lambda: again.received.panel_label == CUSTOM, what="the title naming the typed arm")
        await until(lambda: ("Welcome back", "Your arms are as this browser left them.") in again.received.notifications,
                    what="the welcome back")
        assert (await pick(app, again, UR10)).state.last is ur10_left
        await again.close()
        await until(lambda: len(app.sessions) == 1, what="the laptop gone again")

        app.clock = lambda: time.monotonic() + RETURN_WINDOW + 1.0  # away longer than the window: afresh
        late, afresh = await connect("127.0.0.2")
        assert afresh.choice == UR10 and afresh.state.last is not ur10_left
        for client in (neighbour, late):
            await client.close()

    asyncio.run(scenario())


def test_browsers_on_one_computer_or_behind_one_address_each_find_their_own_arms(app):
    """A page's browser gets a cookie, which its websocket sends back: a browser back finds its own arms, not those of
    another browser that left from the same address (students behind a router's NAT, two accounts on one computer),
    which it was given (until 2026-12-06)."""
    import urllib.request

    from ur10teach.serving.gate import BROWSER_COOKIE, CONNECTIONS_PER_ADDRESS, address_in

    with urllib.request.urlopen(url(app), timeout=HANG_TIMEOUT) as page:
        given = page.headers["Set-Cookie"]
    name, token = given.split(";")[0].split("=")
    assert name == BROWSER_COOKIE and len(token) == 22
    assert {"Path=/", "SameSite=Lax", "HttpOnly"} <= {part.strip() for part in given.split(";")}
    asked = urllib.request.Request(url(app), headers={"Cookie": f"theme=dark; {BROWSER_COOKIE}={token}"})
    with urllib.request.urlopen(asked, timeout=HANG_TIMEOUT) as page:
        assert page.headers["Set-Cookie"] is None  # a browser keeps the one it has
    ada, bo = (f"{BROWSER_COOKIE}={name * 22}" for name in "ab")

    async def connect(cookie: str | None) -> tuple[ViserClient, ArmSession]:
        client = await ViserClient(url(app), local_address="127.0.0.2", cookie=cookie).connect()
        session = session_of(app, client)
        await arrived(client, session)
        return client, session

    async def scenario():
        laptop, _ = await connect(ada)
        await pick(app, laptop, CUSTOM)
        await laptop.close()
        await until(lambda: not app.sessions, what="Ada's browser gone")
        other, fresh = await connect(bo)  # behind the same address: nothing of Ada's
        assert fresh.choice == UR10 and not other.received.notifications
        again, back = await connect(ada)
        assert back.choice == CUSTOM
        await until(lambda: ("Welcome back", "Your arms are as this browser left them.") in again.received.notifications,
                    what="the welcome back")
        await other.close()
        await until(lambda: len(app.sessions) == 1, what="Bo's browser gone")
        # one that sends none is known by its address alone (the test above): none of the arms Bo's browser left
        no_cookie, first = await connect(None)
        assert first.choice == UR10 and not no_cookie.received.notifications
        for client in (again, no_cookie):
            await client.close()
        # a page that sends a new cookie each time keeps no more arms than its address may have browsers open
        for k in range(CONNECTIONS_PER_ADDRESS + 2):
            client, _ = await connect(f"{BROWSER_COOKIE}={k:022d}")
            await client.close()
            await until(lambda: not app.sessions, what="the page gone")
        kept = [browser for browser in app._departed if address_in(browser) == "127.0.0.2"]
        assert len(kept) == CONNECTIONS_PER_ADDRESS and f"127.0.0.2 {CONNECTIONS_PER_ADDRESS + 1:022d}" in kept

    asyncio.run(scenario())


def test_the_light_view_is_one_browsers_and_goes_with_it(app):
    """A laptop without a graphics driver draws the real UR10 at about 4 frames a second, and only a server started
    with ``--light`` helped it (until 2026-12-06): a class started without it had nothing for the few such laptops.
    *Light view* in a browser's View folder turns off that browser's shadows and environment lighting, lights it
    evenly instead (a fill light in its own scene) and draws its arm as the schematic, toon-shaded (13 frames a
    second then, BENCHMARKS.md). It stays on across a change of arm and a return from the same computer; a
    neighbour's view is untouched, and turning it off brings viser's lighting back."""
    from ur10teach.features.light_view import FILL_NAME
    from ur10teach.meshes import REAL, SCHEMATIC

    async def connect(address: str) -> tuple[ViserClient, ArmSession]:
        client = await ViserClient(url(app), local_address=address).connect()
        session = session_of(app, client)
        await arrived(client, session)
        return client, session

    def lighting(client: ViserClient) -> tuple:  # shadows, the environment map's image, the fill light
        return client.received.shadows, client.received.environment_image, FILL_NAME in client.received.nodes

    def shading(session: ArmSession) -> set[str]:  # of the arm and its ghosts, every model sent
        drawing = session.drawing
        return {mesh.material for meshes in (*drawing.robot.meshes.values(), *drawing.branches.models.values())
                for mesh in meshes}

    async def scenario():
        laptop, ur10 = await connect("127.0.0.2")
        neighbour, theirs = await connect("127.0.0.3")
        assert lighting(laptop) == (None, None, False) and ur10.drawing.robot.model == REAL  # viser's own, UR's meshes
        assert shading(ur10) == {"standard"}
        await laptop.set_gui("Light view", True)
        await until(lambda: lighting(laptop) == (False, False, True), what="no shadows or environment map; a fill light")
        await until(lambda: ur10.drawing.robot.model == SCHEMATIC and laptop.gui["Arm drawn as"]["value"] == SCHEMATIC,
                    what="the schematic arm, named in its dropdown")
        assert shading(ur10) == {"toon3"}
        assert lighting(neighbour) == (None, None, False) and theirs.drawing.robot.model == REAL
        assert shading(theirs) == {"standard"}
        assert (await pick(app, laptop, "Stanford arm (RRP + wrist)")).camera.light.on
        back_on_ur10 = await pick(app, laptop, UR10)
        assert back_on_ur10.camera.light.on and back_on_ur10.drawing.robot.model == SCHEMATIC
        assert back_on_ur10.camera.light.fill is not None and lighting(laptop)[2]  # again in the scene the new arm emptied
        assert shading(back_on_ur10) == {"toon3"}
        await laptop.close()
        await until(lambda: len(app.sessions) == 1, what="the laptop gone")
        again, session = await connect("127.0.0.2")
        assert again.gui["Light view"]["value"] is True
        await until(lambda: lighting(again) == (False, False, True), what="the light view back with the computer")
        assert session.drawing.robot.model == SCHEMATIC
        await again.set_gui("Light view", False)
        await until(lambda: lighting(again) == (True, True, False), what="shadows and viser's environment map back")
        await until(lambda: session.drawing.robot.model == REAL, what="UR's meshes back")
        assert shading(session) == {"standard"}
        for client in (again, neighbour):
            await client.close()

    asyncio.run(scenario())


def test_the_light_view_shades_an_arm_drawn_one_way_only():
    """The UR10e has its schematic arm alone (no "Arm drawn as"): the light view left its ghosts in the standard
    material, which without the environment map's light greys them. They are toon-shaded as the UR10's are."""
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(port=0, preset="ur10e")

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client)
        drawing = session.drawing
        assert session.arm_model is None and len(drawing.names) == 1

        def shading() -> set[str]:
            return {mesh.material for meshes in (*drawing.robot.meshes.values(), *drawing.branches.models.values())
                    for mesh in meshes}

        await client.set_gui("Light view", True)
        await until(lambda: shading() == {"toon3"}, what="the UR10e's arm and ghosts toon-shaded")
        await client.set_gui("Light view", False)
        await until(lambda: shading() == {"standard"}, what="their own shading back")
        await client.close()

    try:
        asyncio.run(scenario())
    finally:
        app.stop()


@pytest.mark.parametrize("shared", [False, True])
def test_the_light_flag_starts_every_browser_in_the_light_view(shared):
    """``--light`` ticks *Light view* in every browser, a classroom's viewers' too: each can untick its own."""
    from ur10teach.serving.server import TeachingServer

    app = TeachingServer(port=0, light=True, shared=shared)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        await until(lambda: "Light view" in client.gui, what="the View folder")
        assert client.gui["Light view"]["value"] is True
        await until(lambda: (client.received.shadows, client.received.environment_image) == (False, False),
                    what="the light view's lighting")
        await client.set_gui("Light view", False)
        await until(lambda: client.received.shadows, what="shadows in this browser again")
        await client.close()

    try:
        asyncio.run(scenario())
    finally:
        app.stop()


def test_a_browser_back_before_the_server_noticed_it_had_gone_finds_its_arms(monkeypatch):
    """A page whose websocket dropped retries every second, and is often back before the server notices its old
    connection has died (viser's websockets ping every 20 s and wait 20 s more): it started afresh, and its arms
    were kept for a later return. A live tab of the same computer is left alone."""
    from ur10teach.serving import gate
    from ur10teach.serving.gate import BROWSER_COOKIE, Gate
    from ur10teach.serving.server import TeachingServer

    monkeypatch.setattr(gate, "NEW_CONNECTION_BURST", 10)  # (the pace of one address's arrivals is not tested here)
    app = TeachingServer(port=0, gate=Gate(trust_loopback=False))  # loopback addresses stand for laptops

    async def scenario():
        laptop = await ViserClient(url(app), local_address="127.0.0.2").connect()
        stanford = await pick(app, laptop, "Stanford arm (RRP + wrist)")
        left = stanford.state.last
        laptop.freeze()  # off the network: its old connection answers nothing, and nothing has told the server
        again = await ViserClient(url(app), local_address="127.0.0.2").connect()
        back = session_of(app, again)
        assert back.choice == "Stanford arm (RRP + wrist)" and back.state.last is left
        assert len(app.sessions) == 1
        await until(lambda: int(laptop.gizmo_owner) not in app.server.get_clients(), what="the old connection hung up")
        tab = await ViserClient(url(app), local_address="127.0.0.2").connect()  # a second tab there: its own arm
        assert session_of(app, tab).choice == UR10 and len(app.sessions) == 2 and not again.closed_by_server
        for client in (again, tab):
            await client.close()
        laptop.abort()
        # behind one address, only the arriving browser's own pages are pinged: another student's, busy reading its
        # scene over a slow Wi-Fi (here: not reading at all), is not hung up as a classmate joins (until 2026-12-06)
        busy = await ViserClient(url(app), local_address="127.0.0.2", cookie=f"{BROWSER_COOKIE}={'b' * 22}").connect()
        busy_session = session_of(app, busy)
        busy.freeze()
        classmate = await ViserClient(url(app), local_address="127.0.0.2", cookie=f"{BROWSER_COOKIE}={'c' * 22}").connect()
        session_of(app, classmate)
        assert not busy_session.closed and int(busy.gizmo_owner) in app.server.get_clients()
        back = await ViserClient(url(app), local_address="127.0.0.2", cookie=f"{BROWSER_COOKIE}={'b' * 22}").connect()
        assert session_of(app, back).state.last is busy_session.state.last  # its own page back: the silent one has left
        assert int(busy.gizmo_owner) not in app.server.get_clients()
        for client in (classmate, back):
            await client.close()
        busy.abort()

    asyncio.run(scenario())
    app.stop()


@pytest.mark.parametrize("shared", [False, True])
def test_a_browser_back_before_its_old_one_has_finished_leaving_finds_what_it_left(monkeypatch, shared):
    """viser lists a client gone, then runs the server's disconnect callback on its thread pool, where a class's
    arrivals may hold it up. A page reloaded meanwhile came back before its old connection had left: a student's
    laptop started afresh (its arms were kept for a later return), a projector came back as a viewer."""
    import threading

    from ur10teach.serving.gate import Gate
    from ur10teach.serving.server import TeachingServer

    leaving, held = TeachingServer._disconnected, threading.Event()
    seen: set[int] = set()

    def held_up(self, client):  # the first call for each client (viser's) waits until the test lets it go
        if client.client_id not in seen:
            seen.add(client.client_id)
            held.wait(HANG_TIMEOUT)
        leaving(self, client)

    monkeypatch.setattr(TeachingServer, "_disconnected", held_up)
    app = TeachingServer(port=0, shared=shared, gate=Gate(trust_loopback=False))  # loopback addresses stand for laptops

    async def scenario():
        laptop = await ViserClient(url(app), local_address="127.0.0.2").connect()
        if shared:
            await become_presenter(laptop, app)
        else:
            await pick(app, laptop, "Stanford arm (RRP + wrist)")
        await laptop.close()  # a reload: the old page closes its connection, the new one opens another
        await until(lambda: not app.server.get_clients(), what="viser to let the old page go")
        again = await ViserClient(url(app), local_address="127.0.0.2").connect()
        if not shared:
            assert session_of(app, again).choice == "Stanford arm (RRP + wrist)"
        await until(lambda: any(title == "Welcome back" for title, _ in again.received.notifications),
                    what="the page welcomed back")
        assert not shared or app.classroom.presenter is not None and app.classroom.presenter.client.client_id in \
            app.server.get_clients()
        held.set()
        await again.close()

    try:
        asyncio.run(scenario())
    finally:
        held.set()
        app.stop()


def test_the_arms_kept_for_returns_are_bounded_the_oldest_forgotten_first(app, monkeypatch):
    """A server running for days, or addresses made up on the class network, must not grow it without end."""
    from ur10teach.serving import server as serving

    monkeypatch.setattr(serving, "MAX_RETURNING", 1)

    async def visit(address: str, label: str | None = None) -> str:
        client = await ViserClient(url(app), local_address=address).connect()
        session = session_of(app, client)
        await arrived(client, session)
        if label is not None:
            session = await pick(app, client, label)
        await client.close()
        await until(lambda: not app.sessions, what=f"{address} gone")
        return session.choice

    async def scenario():
        await visit("127.0.0.2", "Stanford arm (RRP + wrist)")
        await visit("127.0.0.3", "SCARA (RRP + roll)")  # one more than the bound: the first is forgotten
        assert await visit("127.0.0.3") == "SCARA (RRP + roll)"
        assert await visit("127.0.0.2") == UR10

    asyncio.run(scenario())


def test_this_machines_own_tabs_are_not_pinged_as_another_opens(app):
    """A tab on the machine the server runs on does not drop off the network; a load test's hundred clients from
    there, each busy reading, are not hung up for answering slowly."""
    async def scenario():
        busy = await ViserClient(url(app)).connect()
        session = session_of(app, busy)
        busy.freeze()  # would not answer a ping
        other = await ViserClient(url(app)).connect()
        session_of(app, other)
        assert not session.closed and len(app.sessions) == 2
        await other.close()
        busy.abort()

    asyncio.run(scenario())


def test_a_return_whose_kept_arm_cannot_be_built_starts_afresh(app, monkeypatch, caplog):
    """What a computer left must not stop its every return: an arm that failed to build would be kept again as that
    browser left, and fail again at the next return, for the whole window."""
    from ur10teach.serving import server as serving

    built = serving.ArmSession

    def failing(client, arm, *args, state=None, **kwargs):
        if state is not None:
            raise RuntimeError("a bug in building a kept arm")
        return built(client, arm, *args, state=state, **kwargs)

    async def scenario():
        laptop = await ViserClient(url(app), local_address="127.0.0.2").connect()
        await pick(app, laptop, "Stanford arm (RRP + wrist)")
        await laptop.close()
        await until(lambda: not app.sessions, what="the laptop gone")
        monkeypatch.setattr(serving, "ArmSession", failing)
        again = await ViserClient(url(app), local_address="127.0.0.2").connect()
        fresh = session_of(app, again)
        await arrived(again, fresh)
        assert fresh.choice == UR10 and "could not bring back the arms" in caplog.text
        assert not any(title == "Welcome back" for title, _ in again.received.notifications)
        await again.close()

    asyncio.run(scenario())


def test_an_arm_the_browser_has_left_is_freed_and_its_camera_moves_reach_the_arm_shown(app):
    """viser keeps a camera callback for the browser's whole visit. Each arm a browser changed to registered its own,
    so every arm it had left stayed in memory with its drawing and views (sixty changes of arm: sixty arms), and each
    ran on every message of its camera (until 2026-12-05)."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        left = [weakref.ref(session_of(app, client)),
                weakref.ref(await pick(app, client, "Stanford arm (RRP + wrist)")),
                weakref.ref(await pick(app, client, KR210))]
        shown = await pick(app, client, UR10)
        await asyncio.to_thread(app.janitor.sweep)  # what the server does a few seconds after a change of arm
        assert [ref() for ref in left] == [None, None, None]
        # the browser's camera still reaches the arm it shows: a new canvas size frames it again
        await client.send(dataclasses.replace(CAMERA, image_width=1000, image_height=700))
        await until(lambda: shown.camera._framed_size == (1000, 700), what="the arm framed for the new canvas size")
        await client.close()

    asyncio.run(scenario())


def camera_of(app, client: ViserClient):
    """The camera controls of ``client``'s browser: its classroom member's (the only one), or its session's."""
    return next(iter(app.classroom.members.values())).camera if app.classroom is not None else session_of(app, client).camera


async def first_framed(app, client: ViserClient):
    """:func:`camera_of` ``client``, once the server has framed the arm in it."""
    controls = camera_of(app, client)
    await until(lambda: controls._framed_at is not None and controls._where_framed(), what="the first framing")
    return controls


async def orbit_heard(controls, reports: list, heard: int, orbit) -> None:
    """Until ``controls`` has had the camera report ``orbit`` (a view the student turned to, at its canvas size) and
    told ``on_moved`` (which appends to ``reports``) of it. A count of ``on_moved`` alone was not enough: a framing
    tells it after its lock, so the first framing's own call could come after :func:`first_framed` returned, and be
    taken for the report's (a CI run, 2026-12-08)."""
    camera = controls._client.camera
    await until(lambda: len(reports) > heard and np.allclose(camera.position, orbit.position)
                and np.allclose(camera.look_at, orbit.look_at)
                and (camera.image_width, camera.image_height) == (orbit.image_width, orbit.image_height),
                what="the camera's report handled")


@pytest.mark.parametrize("server", ["app", "classroom"])
@pytest.mark.parametrize("phone", [True, False])
def test_on_a_phone_held_upright_the_arm_is_framed_above_the_panel(request, server, phone):
    """In a window narrower than 576 px viser shows the panel as a sheet over the lower 60 % of the canvas. On a
    phone held upright, the arm was framed in the whole canvas, its lower half under the sliders that move it. A
    phone's browser (its User-Agent says so) now frames it in the band above; held sideways the panel docks beside
    the canvas, and the arm fills it. A laptop's canvas taller than wide keeps it whole (its panel docks), unless its
    page says its window is narrow, where viser lays the sheet over it too. viser's ``minimize`` does not fold the
    sheet: "Hide the panel" did nothing on an upright phone."""
    from ur10dev.browser import PHONE
    from ur10teach.features.camera import SHEET_UNCOVERED, arm_points
    from ur10teach.features.branch_labels import ScreenView

    app = request.getfixturevalue(server)

    async def scenario():
        client = await ViserClient(url(app), user_agent=PHONE["user_agent"] if phone else None).connect()
        controls = camera_of(app, client)

        def rows(size):
            """(highest, lowest) of the arm's points, as shares of the canvas's height from its top, once framed
            for ``size``."""
            # (the size is noted as its report arrives, before its framing has moved the camera)
            if controls._framed_size != size or not controls._where_framed():
                return None
            view = ScreenView.of(controls._client.camera)
            pixels, depth = view.to_screen(arm_points(controls._snapshot(), controls.body_radius))
            assert (depth > 0).all() and (np.abs(pixels[:, 0]) <= view.width / 2).all()
            from_top = (view.height / 2 - pixels[:, 1]) / view.height
            return from_top.min(), from_top.max()

        for size in [(390, 664), (664, 390)]:
            await client.send(dataclasses.replace(CAMERA, image_width=size[0], image_height=size[1]))
            highest, lowest = await until(lambda: rows(size), what=f"the arm framed for a {size} canvas")
            assert highest >= 0
            upright_phone = phone and size[0] < size[1]
            assert lowest <= SHEET_UNCOVERED if upright_phone else lowest > 0.8, lowest
            if upright_phone:  # "Hide the panel" cannot fold viser's sheet: the student is told what does
                await client.set_gui("Hide the panel", True)
                await until(lambda: any("Tap or click the panel's title" in body for _, body in client.received.notifications),
                            what="what folds the panel on a phone")
        if not phone:
            # a laptop's window beside another, 540 px wide: narrower than viser's 36 em, and its panel a sheet too,
            # whatever the User-Agent. Its page says so (serving.screens), and the arm is framed above the sheet; a
            # window widened again gets the whole canvas back
            size = (540, 760)
            await client.send(dataclasses.replace(CAMERA, image_width=size[0], image_height=size[1]))
            assert (await until(lambda: rows(size), what="the arm framed for the narrow window"))[1] > 0.8
            for said, framed in (("narrow", lambda lowest: lowest <= SHEET_UNCOVERED), ("wide", lambda lowest: lowest > 0.8)):
                addresses = await until(lambda: screen_addresses(client), what="the page's element")
                assert await asyncio.to_thread(get, app, addresses[said]) == 204
                await until(lambda: (found := rows(size)) is not None and framed(found[1]), what=f"the arm framed in a {said} window")
        await client.close()

    asyncio.run(scenario())


def test_a_framing_for_a_canvas_the_browser_has_since_resized_is_not_shown(app, monkeypatch):
    """A framing takes a moment, and the browser may report a new canvas meanwhile (a phone turned). Once framings
    noted the size they were for, the one for the old canvas, shown last, was noted as being for the new: its report
    then looked like the student's own move, and the arm stayed framed for the old canvas (a CI run, 2026-12-06)."""
    from ur10teach.features import camera as camera_module
    from ur10teach.features.branch_labels import ScreenView
    from ur10teach.features.camera import arm_points
    from ur10dev.waiting import wait_for

    framing = camera_module.framing
    turned = dataclasses.replace(CAMERA, image_width=390, image_height=664)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        controls = await first_framed(app, client)
        loop = asyncio.get_running_loop()
        first = []

        def slow(*args, **kwargs):  # the first framing meets the turn, and finishes after the new canvas's framing
            result = framing(*args, **kwargs)
            if not first:
                first.append(1)
                asyncio.run_coroutine_threadsafe(client.send(turned), loop).result()
                wait_for(lambda: controls._framed_size == (390, 664) and controls._where_framed(),
                         what="the new canvas framed")
            return result

        monkeypatch.setattr(camera_module, "framing", slow)
        await asyncio.to_thread(controls.frame)
        view = ScreenView.of(controls._client.camera)
        pixels, _ = view.to_screen(arm_points(controls._snapshot(), controls.body_radius))
        assert (np.abs(pixels) <= (view.width / 2, view.height / 2)).all(), "framed for the old canvas"
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("server", ["app", "classroom"])
def test_a_page_that_puts_its_camera_back_at_the_start_is_framed_again(request, server):
    """viser's page puts its camera back at the initial one as its 3D view mounts, and a phone's page mounts it
    late: at times after the server's first framing had arrived, which it undid (the arm stood under a phone's
    panel). A camera reported there, at the server's initial camera or at viser's own, is framed again; one the
    student moved elsewhere is left where it is. A classroom's browser is framed as it joins (its page may send no
    other camera until the student moves it)."""
    from ur10teach.features.camera import RESET_POSES

    app = request.getfixturevalue(server)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        controls = await first_framed(app, client)
        framed = controls._framed_at[0].copy()
        reports = []
        controls.on_moved.append(lambda: reports.append(1))
        orbit = ((2.5, -0.4, 1.7), (0.1, 0.2, 0.3))  # a view the student turned to
        for position, look_at in [*RESET_POSES, orbit]:
            heard = len(reports)
            message = dataclasses.replace(CAMERA, position=position, look_at=look_at)
            await client.send(message)
            if (position, look_at) == orbit:
                await orbit_heard(controls, reports, heard, message)
                assert not controls._where_framed() and np.allclose(controls._client.camera.position, position)
            else:
                await until(lambda: len(reports) > heard, what="the camera's report handled")
                await until(lambda: controls._where_framed(), what="the camera framed again")
                np.testing.assert_allclose(controls._framed_at[0], framed, atol=1e-9)
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("server", ["app", "classroom"])
def test_a_students_orbit_stays_when_viser_draws_fewer_pixels_and_a_new_shape_of_canvas_is_framed(request, server):
    """viser draws the canvas at 0.875 and then 0.75 of the screen's pixel ratio while its frame rate is low, and
    reports the camera with that canvas's pixels. On a laptop without a graphics driver this comes mid-orbit (at
    3.8 s and 12.4 s of a 15 s orbit in headless Chromium: 946 × 800, 827 × 700, then 709 × 600), and each new size
    was framed again: the view the student was turning to jumped back to the course's (until 2026-12-06)."""
    app = request.getfixturevalue(server)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        controls = await first_framed(app, client)
        reports = []
        controls.on_moved.append(lambda: reports.append(1))
        orbit = dataclasses.replace(CAMERA, position=(2.5, -0.4, 1.7), look_at=(0.1, 0.2, 0.3))
        for width, height in [(1280, 800), (1120, 700), (961, 601), (1280, 800)]:
            heard = len(reports)
            message = dataclasses.replace(orbit, image_width=width, image_height=height)
            await client.send(message)
            await orbit_heard(controls, reports, heard, message)
            assert not controls._where_framed() and np.allclose(controls._client.camera.position, orbit.position)
        await client.send(dataclasses.replace(orbit, image_width=1000, image_height=800))  # a window of a new shape
        await until(lambda: controls._framed_size == (1000, 800) and controls._where_framed(),
                    what="the arm framed for the new shape")
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("first_arm, shared", [("scara", False), ("three_dof", False), ("kr210", True), ("three_dof", True)])
def test_a_teacher_can_open_every_browser_on_another_arm(first_arm, shared):
    """``--arm``: a lecture on the SCARA opens every browser on it (in shared mode, the class sees it first and a
    student explores it), where each student had to find it in the picker; the UR10 stays a pick away."""
    from ur10teach.serving.gate import Gate
    from ur10teach.serving.server import TeachingServer

    label = next(choice for choice, name in ARM_CHOICES.items() if name == first_arm)
    app = TeachingServer(port=0, shared=shared, first_arm=first_arm, gate=Gate(trust_loopback=False))  # a student's laptop

    async def scenario():
        client = await ViserClient(url(app)).connect()
        await until(lambda: client.received.panel_label == label, what="the title naming the arm")
        if shared:
            assert app.classroom.choice == label and app.classroom.state.arm.name == first_arm
            await client.set_gui("Explore on my own", True)
            member = next(iter(app.classroom.members.values()))
            await until(lambda: member.session is not None and member.session.built, what="the student's own arm")
            assert member.session.arm.name == first_arm
        else:
            session = session_of(app, client)
            assert session.choice == label and session.arm.name == first_arm
            assert session.arm_picker.dropdown.value == label
            await pick(app, client, UR10)
            await until(lambda: client.received.panel_label == "UR10 kinematics (course)", what="the UR10's title")
        await client.close()

    try:
        asyncio.run(scenario())
    finally:
        app.stop()


def test_an_arm_to_open_on_must_be_in_the_picker():
    from ur10teach.serving.server import TeachingServer

    for name in ("ur10e", "custom", "puma"):  # the UR10's numbers are --preset's; a typed table is each student's own
        with pytest.raises(ValueError, match=f"first_arm: '{name}' is not an arm of the picker"):
            TeachingServer(port=0, first_arm=name)


@pytest.mark.parametrize("label", [label for label in ARM_CHOICES if label not in (UR10, CUSTOM)])
def test_a_course_arm_moves_from_a_remembered_pose_along_both_paths(app, label, monkeypatch):
    """Issue 29: the Motion folder was the UR10's alone. On the course's arms and its desktop arm: a
    straight tool line, the rates of a sliding joint in mm/s, no speed limits an arm does not have,
    and no gravity drop without link masses."""
    monkeypatch.setattr(motion_lessons, "PATH_SECONDS", 1.0)  # played in real time: 4 s an arm is waiting, not testing
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        motion = session.motion
        assert motion.release.disabled and "no link masses" in motion.gravity_text.content.lower()
        start = session.state.last.q.copy()
        # a path asked for first is explained below its buttons (it was a notice at the window's far corner)
        await client.set_gui("Go from the start to here along", "joints interpolated")
        await until(lambda: motion.refusal.line.visible and "Remember a start pose first" in motion.refusal.line.content,
                    what="the refusal below the paths")
        await client.set_gui("Remember this pose as the start", True)
        await until(lambda: motion.start is not None and not motion.refusal.line.visible, what="the start remembered")
        goal_q = start.copy()
        goal_q[0] += np.radians(20.0)
        session.apply(lambda state: state.set_joints(goal_q))
        goal = session.arm.fk(goal_q)
        await client.set_gui("Go from the start to here along", "straight tool line")
        await until(lambda: motion.player.playing, what="the path to start")
        # while it plays, the tool's v is the path's own: J q̇ at the pose shown (the arrow, from its rates)
        await until(lambda: session.state.last.rates is not None and session.velocity.linear.visible, what="v while it plays")
        with session.state.lock:  # a frame is drawn under the lock: the arrow and the pose it was drawn for, together
            shown = session.state.last
            tip, end = session.velocity.linear.points[0]
        np.testing.assert_allclose(end - tip, METRES_PER_SPEED * session.arm.tool_twist(shown.q, shown.rates)[:3], atol=1e-5)
        await until(lambda: not motion.player.playing, what="the path to end")
        await until(lambda: session.state.last.rates is None and not session.velocity.linear.visible, what="the arrows gone")
        np.testing.assert_allclose(session.arm.fk(session.state.last.q)[:3, 3], goal[:3, 3], atol=1e-4)
        data = motion.path_charts["straight tool line"].data
        n = session.arm.n_joints
        assert len(data) == 1 + n + 2  # time, each joint, the two marks: no limit lines for an arm without limits
        assert ("mm/s" in motion.summary.content) == ("P" in session.arm.joint_types)
        assert "publishes no speed limits" in motion.summary.content
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", ["KR210 (spherical wrist)", "SCARA (RRP + roll)"])
def test_a_course_arm_has_its_branch_count_map_and_a_typed_table_says_why_not(app, label):
    """Issue 29: the branch-count map was the UR10's alone."""
    from ur10teach.features.reach_map import COURSE_RESOLUTION, legend_text, map_image

    from ur10core.workspace import branch_count_map

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        view = session.reach_map
        slots = len(session.state.last.solution.labels)
        assert view.slots == slots
        await client.set_gui("Plane", "horizontal, at the target's height")
        await client.set_gui("Show branch-count map", True)
        await until(lambda: view.image is not None and view.shown_key is not None, what="the map")
        target = session.state.last.target
        expected = branch_count_map(session.arm, target, "horizontal", COURSE_RESOLUTION)
        assert expected.counts.max() > 0  # the arm reaches part of its plane
        np.testing.assert_array_equal(view.image.image, map_image(expected.counts, slots))
        assert str(slots) in legend_text(slots)
        typed = await pick(app, client, CUSTOM)
        assert typed.reach_map.slots == 0 and typed.reach_map.enabled.disabled
        # a made-up "on" for the disabled checkbox (a browser cannot send it) is refused once and put back:
        # until 2026-12-03 it stayed on, and every redraw of the panel refused it again
        await client.set_gui("Show branch-count map", True)
        await until(lambda: any("no branch-count map" in body for _, body in client.received.notifications), what="the refusal")
        assert not typed.reach_map.enabled.value
        redrawn = typed.reach_map.computed, len(client.received.notifications)
        for _ in range(3):
            typed.apply(lambda state: state.set_joints(state.q + 0.01))
            await asyncio.to_thread(typed.render_panel)
        assert (typed.reach_map.computed, len(client.received.notifications)) == redrawn
        await client.close()

    asyncio.run(scenario())


#: Each teaching feature (issue 29) and the folder it has in an arm's panel.
FEATURE_FOLDERS = {
    "joints": ("Joints",), "IK target and its branches": ("IK target", *(f"IK target: all {k} branches" for k in (1, 2, 4, 8))),
    "singularities": ("Singularities",), "workspace": ("Workspace",), "reach map": ("Reachable with this orientation", "Reachable points"),
    "velocities": ("Velocities",), "ellipsoids": ("Manipulability ellipsoids",), "forces and gravity": ("Forces and gravity",),
    "motion": ("Motion",), "DH table": ("DH table",), "DH walkthrough": ("DH walkthrough",),
}


def test_every_arm_in_the_picker_offers_every_feature(app):
    """Issue 29: 65 of 81 arm × feature cells were there. Each arm's panel has a folder for each feature
    (saying why, where its maths does not apply)."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        for label, name in ARM_CHOICES.items():
            session = await pick(app, client, label)
            folders = {k for k, v in client.gui.items() if v["type"] == "GuiFolderMessage"}
            missing = [feature for feature, titles in FEATURE_FOLDERS.items() if not folders & set(titles)]
            assert not missing, (label, missing)
            assert session.built
        await client.close()

    asyncio.run(scenario())


def test_the_ur10_walks_through_its_dh_frames(app):
    """Issue 29: the DH walkthrough was the other arms' alone. On the UR10 its frames, hidden until then,
    are built step by step from the course's (modified) table, and go again when it stops."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, UR10)
        frames = session.drawing.dh_frames
        assert not frames.x_axes.visible and not frames.z_axes.visible
        await client.set_gui("Step", "Next ▶")
        await until(lambda: session.walkthrough.step == 0 and frames.z_axes.visible and not frames.x_axes.visible,
                    what="step 1: the z axes")
        np.testing.assert_allclose(frames.z_axes.points[:, 0], session.state.last.frames[:, :3, 3], atol=1e-6)
        for step in (1, 2):
            await client.set_gui("Step", "Next ▶")
            await until(lambda s=step: session.walkthrough.step == s, what=f"step {step + 1}")
        # (the text is written after the row is chosen: waited for too, as a redraw by another thread may come between)
        await until(lambda: frames.highlight_row == 1 and getattr(frames.parameter_labels.get("d"), "text", "") == "d1 = 128.0 mm"
                    and "*Step 3 of" in session.walkthrough.text.content, what="row 1: d1 drawn with its value")
        assert "a<sub>0</sub>" in session.walkthrough.text.content  # modified DH: row 1 holds a0, α0
        await client.set_gui("Step", "Stop")
        await until(lambda: session.walkthrough.step == -1 and not frames.z_axes.visible and not frames.parameters["d"].visible,
                    what="the frames hidden again")
        await client.close()

    asyncio.run(scenario())


def test_a_target_only_branches_beyond_a_limit_reach_keeps_the_arm_and_draws_them(app):
    """Dragged below the cylindrical arm's base, the target needs d2 < 0: the arm stays, the panel names d2, the two
    branches that reach it are drawn as ghosts beside the arm, and the sliders still move it (until 2026-12-04 the
    arm went there, d2 at -500 mm, and every slider was refused)."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Cylindrical arm (RPP)")
        before = session.state.q
        below = session.state.last.target.copy()
        below[2, 3] = -0.2
        await client.drag_target(below[:3, 3], wxyz_of(below), "start", name=TARGET)
        await client.drag_target(below[:3, 3], wxyz_of(below), "end", name=TARGET)
        await until(lambda: "beyond a joint limit (d2:" in session.state.last.reason, what="the reason")
        np.testing.assert_allclose(session.state.q, before)
        await until(lambda: "beyond a joint limit (d2:" in session.ik_target.branches.content, what="the panel")
        # the two lie on each other (θ1 half a turn on, d3 < 0): one ghost, marked as one the arm cannot take
        assert [ghost.visible for ghost in session.drawing.ghosts[:2]].count(True) == 1
        await until(lambda: [text[:13] for _, text, _ in session.drawing.numbers.placed] == ["1 = 2 ⚠ limit"],
                    what=f"its number, not {[text for _, text, _ in session.drawing.numbers.placed]}")
        await client.set_gui("θ1 (°)", 40.0)
        await until(lambda: math.isclose(session.state.q[0], math.radians(40.0), abs_tol=1e-9), what="θ1 = 40°")
        assert not client.received.notifications, client.received.notifications
        await client.close()

    asyncio.run(scenario())


def test_a_course_arms_ghosts_leave_out_what_lies_on_the_solid_arm_and_number_every_branch(app):
    """Issue 30: ghosts and the solid arm flickered where they overlap (the same segment drawn twice). A
    ghost's skeleton leaves out every segment the solid arm draws; every shown branch is numbered."""
    from ur10teach.features.course_arms.scene import skeleton
    from ur10teach.features.ik_target import same_pose_groups

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "KR210 (spherical wrist)")
        drawing, snapshot = session.drawing, session.state.last
        solid = skeleton(session.arm.dh, snapshot.frames)
        shown = [k for k, ghost in enumerate(drawing.ghosts) if ghost.visible]
        assert shown, "no ghost drawn at the home pose"
        for k in shown:
            for segment in drawing.ghosts[k].points:
                assert not np.isclose(segment, solid, atol=1e-6).all(axis=(1, 2)).any(), f"ghost {k + 1} repeats the arm"
            # and what it leaves out is exactly what it shares with the arm
            full = skeleton(session.arm.dh, snapshot.ghost_frames[k])
            kept = [s for s in full if not np.isclose(s, solid, atol=1e-6).all(axis=(1, 2)).any()]
            np.testing.assert_allclose(drawing.ghosts[k].points, np.array(kept), atol=1e-6)
        await until(lambda: drawing.numbers.placed, what="the numbers")
        numbered = {k for members, _, _ in drawing.numbers.placed for k in members}
        groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)  # "3 = 4" is one number
        assert all(numbered & set(group) for group in groups if set(group) & {*shown, snapshot.slot})
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", [label for label, name in ARM_CHOICES.items() if name not in (None, "custom")])
def test_no_ghosts_disc_sits_on_a_joint_of_the_solid_arm(app, label):
    """A ghost's joints are discs in its colour; where one fell on a joint of the solid arm, the arm's joint took
    that colour (until 2026-12-03 the SCARA's other elbow put orange discs on the arm's base and wrist, every
    course arm's ghosts on its base, the desktop arm's on its tool)."""
    from ur10teach.features.ik_target import same_pose_groups

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        drawing = session.drawing
        tool = getattr(drawing, "tool", None)  # the desktop arm's tool frame; a DH skeleton's tool is its last joint's
        solid = [joint.position for joint in drawing.joints] + ([tool.position] if tool is not None else [])
        balls = drawing.ghost_joints
        drawn = balls.batched_scales > 0
        poses = same_pose_groups(session.state.last.ghost_frames, session.state.last.solution.valid)
        assert drawn.any() or len(poses) == 1, "no ghost drawn with its joints"  # the cylindrical arm's two are one
        for k in np.flatnonzero(drawn) // drawing.joints_per_ghost:
            assert drawing.ghosts[k].visible, f"ghost {k + 1}'s joints drawn without it"
        nearest = np.linalg.norm(balls.batched_positions[drawn][:, None] - np.array(solid)[None], axis=-1).min(axis=1)
        assert (nearest > 1e-4).all(), "a ghost has a ball on a joint of the solid arm"
        await client.close()

    asyncio.run(scenario())


def test_a_typed_pose_on_the_stanford_arms_wrist_singularity_keeps_its_shoulder_and_its_wrist_within_limits(app):
    """At θ5 = 0 only θ4 + θ6 is fixed (here −165°), and the arm's own θ4 (20°) would have put θ6 at 175°, beyond
    the wrist's ±170°: the status counted 2 branches within the limits, not 4, and the arm swung its shoulder
    around for a pose its wrist reaches with a turn (until 2026-12-05)."""
    from ur10core.orientation import zyx_euler

    async def scenario():
        client = await ViserClient(url(app)).connect()
        stanford = await pick(app, client, "Stanford arm (RRP + wrist)")
        home = stanford.arm.specs.home
        np.testing.assert_allclose(stanford.state.last.q, home)
        q = home.copy()
        q[3:] = np.radians([-120.0, 0.0, -45.0])
        T = stanford.arm.fk(q)
        typed = [*(1000 * T[:3, 3]), *np.degrees(zyx_euler(T[:3, :3]))]
        at_home = stanford.ik_target.branches.content
        await client.set_gui("Target x y z (mm), α β γ (°)", ", ".join(repr(float(v)) for v in typed))
        await client.set_gui("Move target here", True)
        await until(lambda: stanford.state.last.cause == "typed", what="the typed target")
        last = stanford.state.last
        await until(lambda: stanford.ik_target.branches.content != at_home, what="the typed target's branches")
        assert "**4 of 8 branches** reach this target within the joint limits" in stanford.ik_target.branches.content
        assert last.slot in (0, 1) and stanford.arm.within_limits(last.q)  # the shoulder it had, the wrist turned
        np.testing.assert_allclose(last.q[:3], home[:3], atol=1e-9)
        assert stanford.arm.pose_error(last.q, T) < 1e-9
        await client.close()

    asyncio.run(scenario())


def test_the_planar_elbows_typed_target_is_a_point_of_its_plane(app):
    """The planar elbow moves in its plane z = 0, but its typed target asked for x y z and dropped the z
    it was given without a word (until 2026-12-03): it asks for x and y."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        planar = await pick(app, client, "Planar elbow (2R)")
        assert "Target x y (mm)" in client.gui and "Target x y z (mm)" not in client.gui
        await client.set_gui("Target x y (mm)", "600, 200, 100")  # a height it cannot reach: refused, with why
        await client.set_gui("Move target here", True)
        await until(lambda: planar.ik_target.refusal.line.visible, what="the refusal")
        assert "expected 2 numbers, got 3" in planar.ik_target.refusal.line.content
        await client.set_gui("Target x y (mm)", "600, 200")
        await client.set_gui("Move target here", True)
        await until(lambda: planar.state.last.cause == "typed", what="the typed target")
        np.testing.assert_allclose(planar.state.last.target[:3, 3], (0.6, 0.2, 0.0), atol=1e-12)
        np.testing.assert_allclose(planar.state.last.flange[:3, 3], (0.6, 0.2, 0.0), atol=1e-9)  # and the arm is there
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", ["Cylindrical arm (RPP)", "Stanford arm (RRP + wrist)"])
def test_a_target_typed_far_beyond_the_room_is_refused_dragged_there_stops_and_one_within_10_m_is_framed(app, label):
    """A target typed 1e300 m out was taken: a sliding joint's branches reach it, so ghosts were drawn there and
    the camera framing them became NaN (until 2026-12-05). A typed position is within 10 m of the base, as the
    KR210's gripper pose is; 8 m out is taken and framed. A target dragged farther stops 10 m out, without a notice."""
    from ur10teach.features.camera import arm_points, framing

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        field = next(name for name in client.gui if name.startswith("Target x y z"))
        rest = " 0" * (len(field.split(",")) > 1 and 3)  # the angles, where it asks for them
        before = session.state.last.target
        await client.set_gui(field, "1e300 0 0" + rest)
        await client.set_gui("Move target here", True)
        line = session.ik_target.refusal.line
        await until(lambda: line.visible and "within 10 m of the base" in line.content and "1e+300 mm" in line.content,
                    what="the refusal below the box")
        np.testing.assert_array_equal(session.state.last.target, before)
        await client.set_gui(field, "8000 0 0" + rest)
        await client.set_gui("Move target here", True)
        await until(lambda: session.state.last.cause == "typed" and not line.visible, what="8 m taken")
        assert not session.state.last.reachable and "beyond a joint limit" in session.state.last.reason
        position, look_at = framing(arm_points(session.drawing.framed(session.state.last), session.drawing.body_radius),
                                    (1.0, -1.0, 0.6), 1.0, 16 / 9)
        assert np.isfinite(position).all() and 3.5 < np.abs(look_at).max() < 20.0  # midway to the target 8 m out
        # a dragged target stops 10 m out, as a typed one does: a forged drag 1e300 m out had its ghosts drawn there
        gizmo = session.ik_target.gizmo.name
        for position in ((12.0, 0.3, 0.5), (1e300, 0.0, -1e300)):
            await client.drag_target(position, (1.0, 0.0, 0.0, 0.0), "update", name=gizmo)
        await until(lambda: np.array_equal(session.state.last.target[:3, 3], (10.0, 0.0, -10.0)), what="the drag's stop")
        assert "beyond a joint limit" in session.state.last.reason
        assert np.abs(session.state.last.ghost_frames).max() < 100.0
        assert not any(title == "Not accepted" for title, _ in client.received.notifications)  # a drag is no refusal
        # the 3D labels keep clear of the gizmo where a target can be: not 1e300 m out, where placing them overflowed
        np.testing.assert_array_equal(session.ik_target.obstacles()[0][0], (10.0, 0.0, -10.0))
        await client.drag_target((0.4, 0.1, 0.5), (1.0, 0.0, 0.0, 0.0), "end", name=gizmo)
        await until(lambda: np.allclose(session.state.last.target[:3, 3], (0.4, 0.1, 0.5)), what="a drag within reach")
        await client.close()

    asyncio.run(scenario())


def test_a_typed_arm_reaching_beyond_10_m_takes_a_target_it_reaches_there(app):
    """The 10 m room of a typed or dragged target is the room of an arm that reaches less far: a typed table of three
    5 m slides reaches 15 m up, and a target 12 m up is taken, typed or dragged, never refused."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, CUSTOM)
        typed = await build_table(app, client, "0 0 0 0 P 0 5000\n" * 3 + "1000 0 0 0 R", "PPPR", session)
        assert typed.arm.reach_bound == 16.0
        field = next(name for name in client.gui if name.startswith("Target x y z"))
        await client.set_gui(field, "1000 0 12000")
        await client.set_gui("Move target here", True)
        await until(lambda: typed.state.last.cause == "typed", what="the typed target")
        assert not typed.ik_target.refusal.line.visible
        await until(lambda: np.allclose(typed.state.last.flange[:3, 3], (1.0, 0.0, 12.0), atol=1e-6), what="the arm there")
        await client.drag_target((0.0, 1.0, 12.5), (1.0, 0.0, 0.0, 0.0), "end", name=TARGET)
        await until(lambda: np.allclose(typed.state.last.flange[:3, 3], (0.0, 1.0, 12.5), atol=1e-6), what="dragged there")
        await client.close()

    asyncio.run(scenario())


def test_a_target_typed_or_dropped_that_the_arms_own_search_does_not_reach_is_searched_for_at_once(app):
    """A typed 2R arm at (34°, 92°), given the point (685, -515) mm that (-21°, -36°) reaches, stayed where it was: its
    search from its own joints came within 609 mm, and it waited for Find every branch (until 2026-12-05). A target
    typed, or dragged there and let go of, is searched for as that button would: the arm goes there."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, CUSTOM)
        typed = await build_table(app, client, "500 0 0 0 R\n400 0 0 0 R", "RR", session)
        await client.set_gui("All 2 (°)", "34, 92")
        await client.set_gui("Set these values", True)
        await until(lambda: np.allclose(np.degrees(typed.state.last.q), (34.0, 92.0)), what="the arm at (34°, 92°)")
        await client.set_gui("Target x y (mm)", "685, -515")
        await client.set_gui("Move target here", True)
        await until(lambda: typed.state.last.solution is not None, what="the search")
        last = typed.state.last
        assert last.reachable and last.solution.method == "found numerically"
        np.testing.assert_allclose(last.flange[:2, 3], (0.685, -0.515), atol=1e-9)
        # the same point, the target dragged there in one move and let go of: searched for too. (Typed as other text
        # than "34, 92", which the box showed before the search moved the arm: a redraw of the box still to come would
        # take that for its own text, and write the arm's new joints over it before the click.)
        await client.set_gui("All 2 (°)", "34.0, 92.0")
        await client.set_gui("Set these values", True)
        await until(lambda: typed.state.last.cause == "joints" and np.allclose(np.degrees(typed.state.last.q), (34.0, 92.0)),
                    what="the arm back at (34°, 92°)")
        await client.drag_target((0.685, -0.515, 0.0), (1.0, 0.0, 0.0, 0.0), "end", name=TARGET)
        await until(lambda: typed.state.last.cause == "branch", what="the search after the drop")
        assert typed.state.last.reachable
        np.testing.assert_allclose(typed.state.last.flange[:2, 3], (0.685, -0.515), atol=1e-9)
        await client.close()

    asyncio.run(scenario())


def test_lecture_mode_sizes_the_axes_of_every_chart_on_every_arm(app):
    """uPlot draws a chart's tick numbers and axis names on its canvas in px, out of reach of the page's type:
    in lecture mode they stayed at 12 px. They are 20 px on every chart of the arm shown, on a panel built in
    lecture mode too, and back at uPlot's own size when it is switched off."""
    from ur10teach.features.arm_picker import DESKTOP
    from ur10teach.features.lecture import LECTURE_AXIS, LECTURE_AXIS_SIZE

    def lecture_sized(session, on: bool) -> bool:
        charts = [chart for view in session.panel_views for chart in view.charts]
        assert len(charts) >= 4  # the factors' history and Motion's three, and the desktop arm's two more
        return all(all((axis.get("font") == LECTURE_AXIS["font"] and axis.get("size") == size) == on and axis.get("label")
                       for axis, size in zip(chart.axes, LECTURE_AXIS_SIZE, strict=True))
                   and (chart.padding is not None) == on for chart in charts)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = session_of(app, client)
        assert lecture_sized(session, False)
        await client.set_gui("Lecture mode", True)
        await until(lambda: lecture_sized(session, True), what="the UR10's charts at lecture size")
        desktop = await pick(app, client, DESKTOP)
        assert len(desktop.lessons) and lecture_sized(desktop, True)  # built in lecture mode: sized as it is built
        await client.set_gui("Lecture mode", False)
        await until(lambda: lecture_sized(desktop, False), what="the desktop arm's charts at their own size")
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", [label for label, name in ARM_CHOICES.items()
                                   if name not in (None, "custom", "cylindrical", "cylindrical_wrist")])  # (their 2 are 1)
def test_a_click_on_a_line_drawn_ghosts_joint_puts_the_arm_on_its_branch(app, label):
    """The IK folder says "click a ghost … to put the arm on it", but only the UR family's mesh ghosts could be
    clicked: viser reports no click on a line, and the other arms' ghosts are lines (until 2026-12-05). The
    balls at their joints are one clickable mesh, slot by slot."""
    arm = Arm.preset(ARM_CHOICES[label])
    q, slot = a_ghost_to_take(arm)

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        drawing = session.drawing
        assert "click a ball at a ghost's joint" in client.shown("Drag the gizmo")[0]
        session.apply(lambda state: state.set_joints(q, cause="typed"))
        drawn = lambda: drawing.ghost_joints.batched_scales.reshape(-1, drawing.joints_per_ghost).any(axis=1)  # noqa: E731
        await until(lambda: np.allclose(session.state.q, q) and drawn()[slot] and drawing.ghosts[slot].visible,
                    what=f"ghost {slot + 1} drawn with its joints")
        ball = slot * drawing.joints_per_ghost + int(np.argmax(drawing.ghost_joints.batched_scales.reshape(-1, drawing.joints_per_ghost)[slot]))
        await client.click_node(drawing.ghost_joints.name, ball)
        await until(lambda: session.state.last.slot == slot, what=f"the arm on branch {slot + 1}")
        np.testing.assert_allclose(session.state.last.flange[:3, 3], arm.fk(q)[:3, 3], atol=1e-9)  # the same target
        await client.close()

    asyncio.run(scenario())


def test_a_ghost_clicked_where_branches_coincide_takes_the_one_within_the_limits(app):
    """A Stanford arm's wrist flip moves no joint: branches 1 and 5, say, are one ghost. Where 1 needs d3 < 0 and
    5 does not, the ghost drawn must be 5's, or a click on it is refused as beyond a limit: the ghost drawn and
    clicked for such a group is the first of it within the limits."""
    from ur10teach.features.ik_target import same_pose_groups
    from ur10teach.state import ArmState

    arm = Arm.preset("stanford")
    for q in arm.sample_joints(400, seed=3):
        last = ArmState(arm, q).last
        within = last.solution.within_limits
        group = next((g for g in same_pose_groups(last.ghost_frames, last.solution.valid)
                      if not within[g[0]] and within[list(g)].any() and last.slot not in g), None)
        if group is not None:
            break
    lead = next(k for k in group if within[k])

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, "Stanford arm (RRP + wrist)")
        drawing, per_ghost = session.drawing, session.drawing.joints_per_ghost
        session.apply(lambda state: state.set_joints(q, cause="typed"))
        drawn = lambda: drawing.ghost_joints.batched_scales.reshape(-1, per_ghost).any(axis=1)  # noqa: E731
        await until(lambda: np.allclose(session.state.last.q, q) and drawn()[lead] and drawn()[list(group)].sum() == 1,
                    what=f"one ghost for branches {group}: {lead + 1}'s")
        ball = lead * per_ghost + int(np.argmax(drawing.ghost_joints.batched_scales[lead * per_ghost:(lead + 1) * per_ghost]))
        await client.click_node(drawing.ghost_joints.name, ball)
        await until(lambda: session.state.last.slot == lead, what=f"the arm on branch {lead + 1}")
        assert not any(title == "Not accepted" for title, _ in client.received.notifications)
        await client.close()

    asyncio.run(scenario())
