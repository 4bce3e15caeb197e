"""The course's 3-DOF desktop arm in the app (docs/kinematics.md §8.6): picked, driven, played, searched."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from ur10core.orientation import from_frame
from ur10teach.features.arm_picker import DESKTOP, UR10
from ur10teach.features.course_arms.desktop_lessons import PATH_VIEW, SEARCH_VIEW
from ur10teach.features.course_arms.scene import world_placement
from ur10teach.features.readouts import pose_markdown
from ur10teach.features.ik_target import lead, same_pose_groups
from ur10teach.features.singularity import factors_html
from ur10teach.state import ArmState
from ur10core import Arm
from ur10core.three_dof import FOREARM, UPPER_ARM

from .server_support import scene_pose, until, url
from .test_course_arms_app import pick
from ur10dev.viser_client import ViserClient, wxyz_of


def test_the_readout_names_each_factor_and_flags_the_one_near_zero():
    arm = Arm.preset("three_dof")
    state = ArmState(arm)
    level = state.set_joints(np.radians([0.0, -90.0, 0.0]))
    pose = pose_markdown(level.flange)
    assert "**+1280.0**" in pose and "**+1350.0**" in pose  # l1 out, l5 up (the course's frame, y up)
    assert "zero when the upper arm and the forearm are in one line" in factors_html(arm, level.q)
    folded = factors_html(arm, state.set_joints(np.radians([0.0, 30.0, 30.0])).q)  # the forearm back along the upper arm
    assert "class='gauge-fold' style='height:8px;width:0.0%" in folded
    with pytest.raises(ValueError, match="θ3 forearm: from 0° to 180°, got 200.0°"):  # every arm's state words it so
        state.set_joints(np.radians([0.0, 0.0, 200.0]))


UPRIGHT = Arm.preset("three_dof").upright  # the desktop arm's base frame, y up, turned into the world's (z up)


def test_the_world_stands_the_courses_y_up():
    np.testing.assert_allclose(UPRIGHT @ (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    assert np.linalg.det(UPRIGHT) == pytest.approx(1.0)
    # the lowest the tool gets in the joint ranges stays above the floor
    arm = Arm.preset("three_dof")
    grid = np.stack(np.meshgrid(*(np.linspace(lo, hi, 19) for lo, hi in arm.limits), indexing="ij"), -1).reshape(-1, 3)
    assert arm.base_height + arm.fk(grid)[:, 1, 3].min() > 0.1


@pytest.mark.server
def test_the_desktop_arm_is_picked_driven_played_and_searched(app):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, DESKTOP)
        frame = session.drawing.root
        await until(lambda: f"{frame}/links" in client.received.nodes and "θ2 upper arm (°)" in client.gui,
                    what="the desktop arm")
        # sliders: upper arm straight up, forearm level → the tool is l1 out and l5 up (the course's frame)
        await client.set_gui("θ2 upper arm (°)", -90.0)
        await client.set_gui("θ3 forearm (°)", 0.0)
        await until(lambda: np.allclose(session.state.last.q, np.radians([0.0, -90.0, 0.0])), what="the sliders")
        np.testing.assert_allclose(session.state.last.flange[:3, 3], (FOREARM, UPPER_ARM, 0.0), atol=1e-12)
        np.testing.assert_allclose(from_frame(world_placement(session.arm), session.state.last.flange[:3, 3]),
                                   (FOREARM, 0.0, session.arm.base_height + UPPER_ARM), atol=1e-12)
        # its base frame stands in the world y up, and the IK target hangs in it (a position-only gizmo)
        np.testing.assert_allclose(world_placement(session.arm)[:3, :3] @ (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
        await until(lambda: f"{frame}/ik_target" in client.received.nodes, what="the IK target in the course's frame")
        await client.set_gui("θ3 forearm (°)", 200.0)  # beyond its range: refused below the sliders, with the range
        await until(lambda: "from 0° to 180°" in session.joints.slider_refusal.line.content, what="the refusal")
        assert session.state.last.q[2] == 0.0

        # the course's path: while it plays the arm is on it (θ1 = θ2, θ3 = 3π/4 + ¾ θ1) and the arrows show
        await client.set_gui("Play the course's path", True)
        await until(lambda: session.state.last.rates is not None and abs(session.state.last.q[0]) > 0.05, what="the path playing")
        q = session.state.last.q
        assert q[0] == pytest.approx(q[1]) and q[2] == pytest.approx(3 * math.pi / 4 + 0.75 * q[0])
        await until(lambda: client.received.visible.get(f"{frame}/velocity/linear") is True, what="the velocity arrow")
        # the camera frames the arm, not its reach: the path is kept in view while it plays, and no longer after
        assert PATH_VIEW in session.camera.extra
        await client.set_gui("Stop", True)
        await until(lambda: session.state.last.rates is None and PATH_VIEW not in session.camera.extra, what="the path stopped")
        # stopped by a slider instead (it stops whatever plays): no longer kept in view either (until 2026-12-05 a
        # path stopped so stayed in every framing after, the Motion folder's too)
        await client.set_gui("Play the course's path", True)
        await until(lambda: PATH_VIEW in session.camera.extra and session.state.last.rates is not None, what="playing again")
        await client.set_gui("θ1 base (°)", 10.0)
        await until(lambda: PATH_VIEW not in session.camera.extra and session.state.last.q[0] == pytest.approx(math.radians(10.0)),
                    what="the path stopped by the slider")
        await until(lambda: client.received.visible.get(f"{frame}/velocity/linear") is False, what="the arrow hidden")

        # the statics exercise: with no force, no pose needs any torque, said below the button
        refusal = session.lessons[2].refusal.line
        await client.set_gui("Force at the tool (N)", 0.0)
        await client.set_gui("Find the pose that needs the largest ‖τ‖", True)
        await until(lambda: refusal.visible and "set a force first" in refusal.content.lower(), what="the refusal")
        # 10 N down (its y), the worst pose has both links level, and the map is drawn
        await client.set_gui("Force at the tool (N)", 10.0)
        assert session.statics.direction.value == "down (−y)"
        await client.set_gui("Find the pose that needs the largest ‖τ‖", True)
        await until(lambda: f"{frame}/torque_map" in client.received.nodes, what="the torque map")
        # both links level (the path above may have left θ2 at 0 already: θ3 too is waited for)
        await until(lambda: min(abs(math.cos(session.state.last.q[1])), abs(math.cos(session.state.last.q[2]))) > 0.999,
                    what="the arm at the worst pose")
        assert len(session.camera.extra[SEARCH_VIEW]) > 1000  # the map in view with the arm
        worst = session.state.last.q
        assert abs(math.cos(worst[2])) == pytest.approx(1.0)
        torques = session.arm.static_torques(worst, (0.0, -10.0, 0.0))
        assert np.linalg.norm(torques) == pytest.approx(10.0 * math.hypot(UPPER_ARM, FOREARM), rel=1e-9)
        await until(lambda: "F √(l5² + l1²) = 18.60 N·m" in session.lessons[2].result.content, what="the course's closed form")
        assert not refusal.visible
        # the captions and numbers keep clear of its "largest ‖τ‖" (until 2026-12-03 it sat on "y₀ (up)")
        from ur10teach.features.branch_labels import boxes, overlapping
        from ur10teach.features.course_arms.desktop_lessons import WORST_LABEL_RISE
        from ur10teach.viser_internals import labels_of
        world = session.drawing.world
        worst = next(label for label in labels_of(session.client.scene) if label.text.startswith("largest"))
        label = {"text": worst.text, "font_screen_scale": worst.font_screen_scale, "anchor": worst.anchor}
        # on its stalk over the red ball, which is at the tool: the arm is put in the worst pose
        worst_at = (session.state.last.flange[:3, 3] + (0.0, WORST_LABEL_RISE, 0.0)) @ world[:3, :3].T + world[:3, 3]
        await until(lambda: session.drawing.captions.placed, what="the captions placed")
        over = []
        for pool in session.drawing.label_sets:
            pool.place()
            view = pool.view()
            worst_box = boxes(view.to_screen(worst_at[None])[0], [label["text"]], label["font_screen_scale"], label["anchor"])[0]
            over += [text for _, text, position in pool.placed
                     if overlapping(boxes(view.to_screen((position @ world[:3, :3].T + world[:3, 3])[None])[0], [text],
                                          pool.labels[0].font_screen_scale, "bottom-center")[0], worst_box, gap=0.0)]
        assert not over, f"over the largest ‖τ‖: {over}"
        # sideways the closed form does not hold, and the result does not claim it
        await client.set_gui("Force direction", "+x")
        await client.set_gui("Find the pose that needs the largest ‖τ‖", True)
        await until(lambda: "Largest ‖τ‖" in session.lessons[2].result.content and "√" not in session.lessons[2].result.content,
                    what="the sideways search")
        # the base holds it all, stretched across the force (docs §8.6): the refined search's pose, not a grid point near it
        await until(lambda: np.linalg.norm(session.arm.static_torques(session.state.last.q, (10.0, 0.0, 0.0)))
                    == pytest.approx(10.0 * (UPPER_ARM + FOREARM), rel=1e-9), what="the arm at the sideways worst pose")

        back = await pick(app, client, UR10)
        assert session.closed and not back.closed
        assert f"{frame}/links" not in client.received.nodes
        await client.close()

    asyncio.run(scenario())


def test_the_desktop_arms_camera_frames_the_arm_as_large_as_another_arms():
    """Its camera framed its reach on every side of the shoulder: the arm filled a third of the canvas (134 × 224 px
    at home on 1280 × 720, until 2026-12-05; a KR210 301 × 284). It frames the arm, its ghosts and target as every
    arm's does; a path played or a torque map is kept in view beside it (the test above)."""
    import viser

    from ur10teach.features.camera import arm_points, framed_view
    from ur10teach.features.drawings import arm_drawing

    server = viser.ViserServer(port=0, verbose=False)
    try:
        arm = Arm.preset("three_dof")
        snapshot = ArmState(arm).last
        drawing = arm_drawing(server.scene, arm, snapshot)
        view = framed_view(arm_points(drawing.framed(snapshot), drawing.body_radius))
        shown = from_frame(drawing.world, drawing._points(snapshot.frames))  # foot, shoulder, elbow, tool
        width, height = np.ptp(view.to_screen(shown)[0], axis=0)
        assert height > 0.45 * view.height and width > 0.15 * view.width, (width, height)
    finally:
        server.stop()


def test_the_desktop_arm_has_its_branch_count_map_standing_the_right_way_up(app):
    """Issue 29: the desktop arm's map, in its own frame (y up) and drawn in the scene's (z up)."""
    from ur10core.workspace import branch_count_map
    from ur10teach.features.reach_map import COURSE_RESOLUTION, map_image

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, DESKTOP)
        view = session.reach_map
        assert view.slots == 4
        await client.set_gui("Show branch-count map", True)
        await until(lambda: view.image is not None and view.shown_key is not None, what="the map")
        expected = branch_count_map(session.arm, session.state.last.target, "vertical", COURSE_RESOLUTION)
        np.testing.assert_array_equal(view.image.image, map_image(expected.counts, 4))
        # the vertical map stands upright in the scene, through the node that stands the arm on its pedestal: its
        # image's y axis (v, the arm's y) is the world's z. Until 2026-12-04 it was placed in the world twice, on its
        # back 1.5 m too high, out of sight (this test read the image's own pose, in its parent's frame)
        drawn = scene_pose(session.client.scene, view.image)
        np.testing.assert_allclose(drawn[:3, 1], [0.0, 0.0, 1.0], atol=1e-9)
        np.testing.assert_allclose(drawn[:3, 3], UPRIGHT @ expected.centre + (0.0, 0.0, session.arm.base_height),
                                   atol=1e-6)
        np.testing.assert_allclose(UPRIGHT @ expected.v, [0.0, 0.0, 1.0], atol=1e-12)
        await client.close()

    asyncio.run(scenario())


@pytest.mark.server
def test_the_desktop_arms_side_view_and_cut_away_are_cut_about_its_vertical(app):
    """Its folder offered the whole cloud only, "the sections are cut about a vertical base axis z, and this arm's
    vertical is its y axis": they are cut about its y now. The side view lies in the vertical plane the arm moves in,
    seen square-on (each point at its own height: tests/test_workspace.py); the cut-away keeps the half behind that
    plane, seen from the open side."""
    from ur10teach.features.workspace import SECTIONS

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, DESKTOP)
        view, up = session.workspace, np.asarray(session.arm.up)
        assert SECTIONS[1] in view.section.options and SECTIONS[3] in view.section.options
        await client.set_gui("θ1 base (°)", 30.0)
        await until(lambda: abs(session.state.last.q[0] - math.radians(30.0)) < 1e-9, what="θ1 at 30°")
        await client.set_gui("Show workspace cloud", True)
        await until(lambda: view._cloud is not None, what="the cloud")
        whole = np.asarray(view._cloud.points, dtype=float)
        # the plane the arm moves in, turned by θ1 about y: the tool is at (c1·r, h, −s1·r) (docs §8.6), so it reaches
        # along (c1, 0, −s1) for r > 0; "behind" it is against up × that, as on the UR10 (z × (c1, s1, 0))
        normal = np.cross(up, [math.cos(math.radians(30.0)), 0.0, -math.sin(math.radians(30.0))])

        async def section(name: str) -> tuple[np.ndarray, np.ndarray]:  # its points, and where the camera looks from
            before = view._cloud
            await client.set_gui("Section", name)
            # the run done: the camera turns after the cloud is drawn (a CI run read it in between, 2026-12-07)
            await until(lambda: view._cloud is not before and view._cloud is not None and not view._clouds.busy, what=name)
            position, look_at = session.camera._framed_at
            return np.asarray(view._cloud.points, dtype=float), (position - look_at) / np.linalg.norm(position - look_at)

        side, looking = await section(SECTIONS[1])  # (viser sends a cloud's points as float16: 2 mm steps at 2 m)
        assert 0 < len(side) < len(whole) and np.abs(side @ normal).max() < 5e-3
        assert np.ptp(side @ up) > 0.9 * np.ptp(whole @ up)  # turned about its vertical, not flattened onto the floor
        world = session.drawing.world[:3, :3]
        assert abs(looking @ (world @ normal)) > 0.99  # square-on
        cut, looking = await section(SECTIONS[3])
        beside = whole @ normal
        assert (beside < -5e-3).sum() <= len(cut) <= (beside < 5e-3).sum()  # (those within a float16 step either way)
        assert (cut @ normal < 5e-3).all() and looking @ (world @ normal) > 0.99
        await client.close()

    asyncio.run(scenario())


def test_the_desktop_arm_follows_its_ik_target_with_its_other_branches_as_ghosts(app):
    """Issue 29: the desktop arm had sliders only. Its position IK (four branches) now drives it from a
    gizmo in the course's frame, the arm on the nearest branch, the others drawn as numbered ghosts."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, DESKTOP)
        arm, frame = session.arm, session.drawing.root
        goal_q = np.radians([15.0, -20.0, 70.0])
        goal = arm.fk(goal_q)
        await client.drag_target(goal[:3, 3], wxyz_of(goal), "start", name=f"{frame}/ik_target")
        await client.drag_target(goal[:3, 3], wxyz_of(goal), "end", name=f"{frame}/ik_target")
        await until(lambda: np.allclose(session.state.last.flange[:3, 3], goal[:3, 3], atol=1e-9), what="the arm at the target")
        snapshot = session.state.last
        assert snapshot.solution.valid.sum() >= 2 and snapshot.slot >= 0
        # a branch drawn exactly where the arm is (θ1 turned half a turn, the links mirrored) is the arm's:
        # drawn once, not a ghost on top of it that would flicker through it (issue 30)
        same = np.abs(snapshot.ghost_frames[:, :, :3, 3] - snapshot.frames[None, :, :3, 3]).max(axis=(1, 2)) < 1e-6
        groups = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
        others = [lead(g, snapshot.solution.within_limits) for g in groups if not same[list(g)].any()]  # one per pose
        assert others and same.sum() >= 1
        await until(lambda: all(client.received.visible.get(f"{frame}/ghosts/slot{k + 1}") is True for k in others)
                    and not any(client.received.visible.get(f"{frame}/ghosts/slot{k + 1}") for k in np.flatnonzero(same)),
                    what="the other branches as ghosts")
        # the arm's number with the branch it coincides with: "arm: 2 = 4"
        await until(lambda: any(text.startswith("arm: ") and " = " in text for _, text, _ in session.drawing.numbers.placed),
                    what="the arm's number with its twin's")
        # out of reach: the arm stays, and says why in the branch table
        far = goal.copy()
        far[:3, 3] = (4.0, 0.0, 0.0)
        await client.drag_target(far[:3, 3], wxyz_of(far), "end", name=f"{frame}/ik_target")
        await until(lambda: "Target unreachable" in session.ik_target.branches.content, what="the reason")
        np.testing.assert_allclose(session.state.last.flange[:3, 3], goal[:3, 3], atol=1e-9)
        await client.close()

    asyncio.run(scenario())


@pytest.mark.server
def test_the_desktop_arms_floor_is_under_its_pedestal_not_the_plane_z_0(app):
    """The desktop arm's base frame has y up and stands on a pedestal; until 2026-12-03 the floor check took
    its z = 0 (a vertical plane through the shoulder) for the floor, and flagged "⚠ floor" on branches on the
    far side of it, high in the air. Each branch is checked against the drawing's own floor here: the world's
    z of every point it draws, from the drawing's placement in the world."""
    from ur10teach.features.ik_target import branch_labels, same_pose_groups

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, DESKTOP)
        arm, frame = session.arm, session.drawing.root
        for where in (arm.fk(np.radians([25.0, -35.0, 60.0]))[:3, 3], (1.0, -1.6, 0.0)):  # z < 0 up high; under the floor
            goal = arm.fk(np.zeros(3))
            goal[:3, 3] = where
            await client.drag_target(goal[:3, 3], wxyz_of(goal), "end", name=f"{frame}/ik_target")
            await until(lambda: np.allclose(session.state.last.target[:3, 3], where), what="the target moved")
            snapshot = session.state.last
            assert snapshot.solution.valid.any()
            drawn = np.concatenate([snapshot.frames[None], snapshot.ghost_frames])[..., :3, 3]  # shoulder, elbow, tool
            lowest_z = np.array([from_frame(session.drawing.world, points)[:, 2].min() for points in drawn])
            expected = np.concatenate([[True], snapshot.solution.valid]) & (lowest_z < -1e-3)
            np.testing.assert_array_equal(snapshot.through_floor, expected)
            assert expected[1:].any() == (where[1] < -arm.base_height)
            flagged = [k for k, text in enumerate(branch_labels(snapshot, same_pose_groups(snapshot.ghost_frames,
                                                                                           snapshot.solution.valid)))
                       if "floor" in text]
            assert bool(flagged) == bool(expected[1:].any()), flagged
        await client.close()

    asyncio.run(scenario())
