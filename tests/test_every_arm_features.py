"""Every arm in the picker, through viser's protocol: each shared feature computes the right thing for that arm.

The references are independent of the Jacobian the features use: central differences of
the arm's forward kinematics give the tool's velocity for a joint rate and, by the
principle of virtual work, the joint torques τ = J_vᵀ F for a force at the tool.
"""

from __future__ import annotations

import asyncio
import math
import time

import numpy as np
import pytest

from ur10core.orientation import from_frame
from ur10teach.features.arm_picker import ARM_CHOICES
from ur10teach.features.ik_target import GIZMO_SHARE, HALO_SHARE
from ur10teach.features.joint_panel import rate_label
from ur10teach.features.statics import bars_html
from ur10teach.features.velocity import METRES_PER_SPEED, METRES_PER_TURN_RATE, parse_twist
from ur10teach.features.workspace import FROM_ABOVE, POINT_SIZE, SECTIONS, section_heights
from ur10teach.style import UR10_SIZE

from .server_support import scene_pose, until, url
from .test_course_arms_app import pick
from ur10dev.viser_client import ViserClient
from ur10dev.waiting import HANG_TIMEOUT

pytestmark = pytest.mark.server

EVERY_ARM = [label for label, name in ARM_CHOICES.items() if name != "custom"]  # the typed table: its own tests
STEP = 1e-6


def position_rate(arm, q: np.ndarray, joint: int) -> np.ndarray:
    """(3,) ∂p/∂q_joint of the tool's position, by central differences of FK."""
    dq = np.zeros_like(q)
    dq[joint] = STEP
    return (arm.fk(q + dq)[:3, 3] - arm.fk(q - dq)[:3, 3]) / (2 * STEP)


@pytest.mark.parametrize("label", EVERY_ARM)
def test_velocity_and_forces_on_every_arm_match_finite_differences(app, label):
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        arm, snapshot = session.arm, session.state.last
        q, tool = snapshot.q, snapshot.flange[:3, 3]
        assert client.shown("mm drawn per rad/s (57.3°/s)"), "the turning rate's scale, in the sliders' °/s too"
        # a base rate of 10°/s: the arrow is the tool's velocity
        await client.set_gui(rate_label(arm, 0), 10.0)
        expected = tool + METRES_PER_SPEED * math.radians(10.0) * position_rate(arm, q, 0)
        await until(lambda: session.velocity.linear.visible
                    and np.allclose(session.velocity.linear.points[0], [tool, expected], atol=1e-5), what="the velocity arrow")
        # the base turning at 10°/s turns the tool at 10°/s, drawn as long for the arm's reach as on the UR10 (0.15 m
        # per rad/s there): the KR210's was 8 cm long at 30°/s beside its 3.9 m
        turning = np.linalg.norm(np.diff(session.velocity.angular.points[0], axis=0))
        assert turning / session.drawing.size == pytest.approx(METRES_PER_TURN_RATE * math.radians(10.0) / UR10_SIZE, rel=1e-5)
        # as thick for the arm's size as the force's arrow is: a UR10's 8 mm shaft was a hair beside a 3.9 m KR210
        for arrow in (session.velocity.linear, session.velocity.angular):
            assert arrow.shaft_radius / arrow.head_radius == pytest.approx(0.4)
            assert arrow.shaft_radius / session.statics.arrow.shaft_radius == pytest.approx(0.5)
        # and the target's "unreachable" halo grows with its gizmo (on a 3.9 m KR210 it was a dot in the gizmo)
        assert session.ik_target.unreachable.radius / session.ik_target.gizmo.scale == pytest.approx(HALO_SHARE / GIZMO_SHARE)
        # that velocity typed alone (so ω is asked to be zero): the rates for what the arm controls give it back
        v = 1000 * math.radians(10.0) * position_rate(arm, q, 0)
        typed = " ".join(f"{c:.6f}" for c in v)
        await client.set_gui("vx vy vz (mm/s) ωx ωy ωz (°/s)", typed)
        await client.set_gui("Find the joint rates", True)
        await until(lambda: "| joint | rate |" in session.velocity.rates.content, what="the joint rates")
        rates = arm.joint_rates(q, parse_twist(typed))
        np.testing.assert_allclose(sum(rates.qdot[i] * position_rate(arm, q, i) for i in range(arm.n_joints)), v / 1000, atol=1e-6)
        assert ("This arm controls its tool's position" in session.velocity.rates.content) == (arm.task != "pose")
        # J⁻¹ only where it exists: the planar elbow's J over the position it controls is 3 × 2 (said J⁻¹ until 2026-12-05)
        formula = "q̇ = J⁺ v" if arm.name == "planar_elbow" else "q̇ = J⁻¹ v"
        assert any(formula in text for text in client.markdown.values()), formula
        # 50 N along +x at the tool: each joint holds ∂p/∂q_i · F (virtual work)
        await client.set_gui("Show the torques", True)
        await client.set_gui("Force direction", "+x")
        await until(lambda: session.statics.direction.value == "+x" and session.statics.enabled.value, what="the force set")
        force = np.array([50.0, 0.0, 0.0])
        reference = np.array([position_rate(arm, q, i) @ force for i in range(arm.n_joints)])
        _, torques, gravity = session.statics.loads(session.state.last)
        np.testing.assert_allclose(torques, reference, atol=1e-6)
        html = bars_html(torques, gravity, arm.specs.torque_ratings, arm.joint_names, arm.joint_types)
        await until(lambda: session.statics.bars.content == html, what="the torque bars")
        assert f"‖Jᵀ F‖ = {np.linalg.norm(reference):.2f} N·m" in html  # the statics exercise's measure, beside the bars
        # the arrow's head clears the IK target's gizmo, drawn over everything at the same tool: at the first 50 N its
        # whole arrow lay inside the gizmo on every arm, "F = 50 N" named at a tip no student saw (until 2026-12-07)
        arrow = session.statics.arrow
        await until(lambda: arrow.visible and np.allclose(np.diff(arrow.points[0], axis=0)[0, 1:], 0.0), what="the arrow")
        length = np.linalg.norm(np.diff(arrow.points[0], axis=0))
        assert client.shown(f"{length / 5 * 1000:.0f} mm drawn per 10 N"), "the arrow's scale, as the velocity's is said"
        shaft = length - arrow.head_length
        assert shaft > 1.1 * session.ik_target.gizmo.scale, (shaft, session.ik_target.gizmo.scale)
        await client.close()

    asyncio.run(scenario())


def jacobian_by_differences(arm, q: np.ndarray) -> np.ndarray:
    """(6, n) the tool's v and ω per unit joint rate, by central differences of FK (ω from dR Rᵀ)."""
    R = arm.fk(q)[:3, :3]
    columns = []
    for joint in range(arm.n_joints):
        dq = np.zeros_like(q)
        dq[joint] = STEP
        ahead, behind = arm.fk(q + dq), arm.fk(q - dq)
        spin = (ahead[:3, :3] - behind[:3, :3]) / (2 * STEP) @ R.T
        columns.append(np.concatenate([(ahead[:3, 3] - behind[:3, 3]) / (2 * STEP), [spin[2, 1], spin[0, 2], spin[1, 0]]]))
    return np.array(columns).T


#: The force ellipsoid's longest semi-axis at an arm's home pose, at least, as a share of the arm's reach.
FORCE_SHARE = 0.08


@pytest.mark.parametrize("label", EVERY_ARM)
def test_the_ellipsoids_and_the_gauges_of_every_arm_are_its_own(app, label):
    """The velocity ellipsoid drawn at the tool has the semi-axes of J_v on the joint rates that keep what the
    arm controls of its orientation still (from differences of FK); each gauge shows that factor of det J."""
    from ur10teach.features.ellipsoids import LONGEST_SHARE, VELOCITY_METRES

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        arm, snapshot = session.arm, session.state.last
        await client.set_gui("Show at the tool", True)
        await until(lambda: session.ellipsoids.velocity.visible, what="the ellipsoids")
        J = jacobian_by_differences(arm, snapshot.q)
        held = {"pose": J[3:], "position and yaw": J[5:]}.get(arm.task, np.zeros((0, arm.n_joints)))
        _, singular, vt = np.linalg.svd(held) if len(held) else (None, np.zeros(0), np.zeros((0, arm.n_joints)))
        free = vt[int((singular > 1e-9).sum()):].T if len(held) else np.eye(arm.n_joints)  # rates that hold it still
        sigma = np.pad(np.linalg.svd(J[:3] @ free, compute_uv=False), (0, 3))[:3]
        expected = np.sort(np.maximum(VELOCITY_METRES * sigma, 1e-4))
        np.testing.assert_allclose(np.sort(session.ellipsoids.velocity.scale), expected, atol=1e-5)
        # a direction the tool cannot move in (the planar elbow's vertical) is one the joints hold any force along:
        # the force ellipsoid's longest axis there, not a flat one (drawn as zero until 2026-12-05)
        if (sigma < 1e-9).any():
            assert max(session.ellipsoids.force.scale) == pytest.approx(LONGEST_SHARE * session.drawing.size)
        # and a force ellipsoid a class can see: the KR210's was 2 % of its reach (9 cm of 3.9 m), the desktop arm's 3 %
        assert max(session.ellipsoids.force.scale) >= FORCE_SHARE * session.drawing.size
        np.testing.assert_allclose(session.ellipsoids.frame.position, snapshot.flange[:3, 3], atol=1e-9)
        # the units its joints' rates and efforts are in: "m/s per rad/s" was a false unit on a sliding joint
        await until(lambda: session.ellipsoids.lengths.visible and "semi-axes" in session.ellipsoids.lengths.content,
                    what="the semi-axes")
        lengths, key = session.ellipsoids.lengths.content, session.ellipsoids.key.content
        assert ("∞: the joints hold a force along that axis with no torque" in lengths) == (sigma < 1e-9).any()
        slides = "P" in arm.joint_types
        assert ("m/s per rad/s or m/s of joint rate" in lengths and "N per N·m or N of joint effort" in lengths) == slides
        assert ("m/s per rad/s of joint rate" in lengths and "N per N·m of joint torque" in lengths) == (not slides)
        assert ("its shape depends on those units" in key) == slides
        for value in arm.singularity_factors(snapshot.q):
            assert f"= {value:+.4f}".replace("-", "−") in session.singularities.gauges.content.replace("-", "−")
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", EVERY_ARM)
def test_every_arm_is_put_on_each_of_its_singularities_by_its_buttons(app, label):
    """Only the UR family had the buttons that put the arm on a singularity; every arm now has one per factor
    of its det J. The pose reached is singular by differences of FK (the rows of J the arm controls lose
    rank), and its gauge reads zero; the cylindrical arms' stroke keeps them off d3 = 0, and the browser says so.
    With the overlay on, no two 3D labels overlap there: until 2026-12-03 the Stanford arm's eight branches as one
    label ("arm: 1 = 2 = … = 8", on its stroke singularity) found no free spot and sat over "stroke · wrist"."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        arm = session.arm
        assert session.singularities.demo.options == arm.factor_names
        # every arm draws its factors (the desktop arm had gauges only until 2026-12-07)
        assert session.singularities.enabled is not None and session.drawing.overlay is not None
        await client.set_gui("Show singularity overlay", True)
        await until(lambda: session.drawing.overlay.enabled, what="the overlay")
        rows = {"pose": slice(0, 6), "position and yaw": [0, 1, 2, 5]}.get(arm.task, slice(0, 3))
        start_q = session.state.q
        before = np.linalg.svd(jacobian_by_differences(arm, start_q)[rows], compute_uv=False)[-1]
        for index, kind in enumerate(arm.factor_names):
            await client.set_gui("Put the arm on the", kind)
            if arm.name.startswith("cylindrical") and kind == "reach":
                line = session.singularities.refusal.line  # below the buttons (until 2026-12-05 a notice in a corner)
                await until(lambda: line.visible and "reach singularity" in line.content, what="the refusal")
                assert "no pose near this one puts this arm on its reach singularity" in line.content  # not "the cylindrical_wrist arm"
                assert np.array_equal(session.state.q, start_q)
                continue
            await until(lambda: not session.singularities.refusal.line.visible, what="the refusal gone")
            await until(lambda: session.state.last.cause == "singularity"
                        and abs(session.state.last.factors[index]) < 1e-12, what=f"the arm on its {kind} singularity")
            q = session.state.q
            assert arm.within_limits(q)
            after = np.linalg.svd(jacobian_by_differences(arm, q)[rows], compute_uv=False)[-1]
            assert after < 1e-6 * before, (kind, after, before)
            await until(lambda: f"<b>{kind}</b>" in session.singularities.gauges.content
                        and "width:0.0%" in session.singularities.gauges.content, what="its gauge at zero")
            placed, clashes = await overlapping_labels(session)  # the panel drawn for this pose: the drawing's first
            assert placed and not clashes, f"on the {kind} singularity, overlapping: {clashes}"
        await client.close()

    asyncio.run(scenario())


def test_a_challenge_begun_between_a_press_and_its_move_keeps_the_arm_off_its_answer(app, monkeypatch):
    """The KR210's singularities are searched for, a slow job. A singularity challenge begun meanwhile: the arm stays
    where it was, and the browser is told why (until 2026-12-07 the search's pose was put, the answer given). So with
    a branch chosen as a challenge asking θ1 begins: the press is refused, not the branch's θ1 shown."""
    from ur10teach.features import singularity
    from ur10teach.view import HELD_BACK

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, next(label for label, name in ARM_CHOICES.items() if name == "kr210"))
        heavy, q = singularity.HEAVY, session.state.q

        class ChallengeMeanwhile:
            def run(self, *args, **kwargs):
                session.hold_back("singularity")
                return heavy.run(*args, **kwargs)

        monkeypatch.setattr(singularity, "HEAVY", ChallengeMeanwhile())
        await client.set_gui("Put the arm on the", session.arm.factor_names[0])
        line = session.singularities.refusal.line
        await until(lambda: line.visible and HELD_BACK[:40] in line.content, what="the refusal")
        assert np.array_equal(session.state.q, q) and session.state.last.cause != "singularity"
        session.hold_back(None)
        await until(lambda: session.ik_target.branch_buttons.visible, what="the branch buttons back")
        slot = next(k for k in np.flatnonzero(session.state.last.solution.valid) if k != session.state.last.slot)
        apply = session.apply

        def challenge_then_apply(change, *args, **kwargs):
            session.apply = apply
            session.hold_back("theta1")
            return apply(change, *args, **kwargs)

        session.apply = challenge_then_apply
        await client.set_gui("Use branch", str(slot + 1))
        line = session.ik_target.branch_refusal.line
        await until(lambda: line.visible and HELD_BACK[:40] in line.content, what="the branch refused")
        assert np.array_equal(session.state.q, q) and session.apply == apply
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", EVERY_ARM)
def test_each_branch_of_every_arm_has_a_number_of_its_own_where_it_parts_from_the_others(app, label):
    """At the arm's first pose, each pose of its branches carries its own number ("3 = 4" where two coincide), by
    the joint where they part. Until 2026-12-03 the SCARA's went by its wrist, which both its branches share:
    one label "arm: 1 · 2" there, and the other branch's elbow had none."""
    from ur10teach.features.ik_target import same_pose_groups

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        numbers, snapshot = session.drawing.label_sets[-1], session.state.last
        poses = same_pose_groups(snapshot.ghost_frames, snapshot.solution.valid)
        await until(lambda: len(numbers.placed) == len(poses), what="a number for each pose")
        for members, text, _ in numbers.placed:
            assert len(members) == 1, f"{text!r}: branches of different poses in one label"
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", ["UR10 (the app's arm)", "3-DOF desktop arm"])
def test_each_view_is_named_for_the_plane_it_shows_in_the_arms_own_axes(app, label):
    """The desktop arm's base frame has y up (its x0, y0, z0 named in 3D); "Top (x–y plane)" showed its x–z plane,
    named in the world's axes. Each "(a–b plane)" view now looks along the arm's third axis."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        camera, world = session.camera, session.drawing.world
        for name in camera.direction.options[1:]:
            before = camera._framed_at
            await client.set_gui("Look from", name)
            await until(lambda: camera.direction.value == name and camera._framed_at is not before, what=name)
            position, look_at = camera._framed_at
            along = world[:3, :3].T @ (position - look_at)  # the viewing direction, in the arm's base frame
            along /= np.linalg.norm(along)
            a, b = name.split("(")[1].split(" plane")[0].split("–")
            normal = ({"x", "y", "z"} - {a, b}).pop()
            assert abs(along["xyz".index(normal)]) > 0.99, (name, along)
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", EVERY_ARM)
def test_the_course_figure_sees_an_arm_in_one_plane_from_high_above_it(app, label):
    """From the course figure's three-quarter view, 18° above the floor, the planar elbow, flat in it, was seen
    nearly edge-on: its joints spread 66 px high by 499 px wide on a class's smallest canvas. An arm that moves in
    one horizontal plane is now seen from 45° above it, in the browser's own camera and in the view a class's
    labels are placed for; every other arm keeps the figure's view."""
    from ur10teach.features.camera import ClassView

    def elevation(position, look_at) -> float:  # the view's angle above the floor, in degrees
        along = np.asarray(position, dtype=float) - np.asarray(look_at, dtype=float)
        return math.degrees(math.asin(along[2] / np.linalg.norm(along)))

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        camera = session.camera
        await until(lambda: camera._framed_at is not None, what="the arm framed")
        seen, shared = elevation(*camera._framed_at), ClassView(session.drawing, session.state)()
        if session.arm.planar:
            assert seen > 40.0 and elevation(shared.position, shared.look_at) > 40.0
        else:
            assert 15.0 < seen < 25.0, seen
        await client.close()

    asyncio.run(scenario())


#: The IK target's longest arrow on the smallest canvas a class looks at, at the arm's home pose (px): a student
#: grabs it with a mouse, and a class sees it from the back of the room.
GIZMO_MIN_PX = 45


@pytest.mark.parametrize("label", EVERY_ARM)
def test_every_arms_gizmo_is_big_enough_to_grab_on_the_canvas(app, label):
    """Sized by the arm's reach, the desktop arm's gizmo was 20–25 px long (the others' 50–100): its camera frames
    the reach on every side of the shoulder, about twice what frames another arm. So was its force's handle."""
    from ur10teach.features.camera import arm_points, framed_view, views_for
    from ur10teach.features.statics import HANDLE_SCALE

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        drawing, snapshot, gizmo = session.drawing, session.state.last, session.ik_target.gizmo
        view = framed_view(arm_points(drawing.framed(snapshot), drawing.body_radius), views_for(session.arm)["Course figure"])
        arrows = np.asarray(gizmo.position) + gizmo.scale * np.eye(4)[:, :3] * [[1], [1], [1], [0]]  # tips, then the centre
        pixels, _ = view.to_screen(arrows @ drawing.world[:3, :3].T + drawing.world[:3, 3])
        longest = np.linalg.norm(pixels[:3] - pixels[3], axis=1).max()
        assert longest >= GIZMO_MIN_PX, f"the gizmo's longest arrow is {longest:.0f} px"
        # the force's handle, grabbed the same way, is sized the same way
        assert session.statics.handle.scale / gizmo.scale == pytest.approx(HANDLE_SCALE / GIZMO_SHARE)
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", EVERY_ARM)
def test_the_workspace_cloud_of_every_arm_is_its_own(app, label):
    """The cloud drawn is the arm's own sampled workspace, under the arm's own root."""
    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        await client.set_gui("Samples", "10 k")
        await client.set_gui("Show workspace cloud", True)
        await until(lambda: session.workspace._cloud is not None and len(session.workspace._cloud.points) == 10_000,
                    what="the cloud")
        points, _ = session.arm.sample_workspace(10_000, seed=0)
        np.testing.assert_allclose(session.workspace._cloud.points, points, atol=5e-3)  # float16 on the wire
        # its dots the same share of the arm's size as on the UR10 (a 3.9 m KR210's were a third as big on screen)
        assert session.workspace._cloud.point_size / session.drawing.size == pytest.approx(POINT_SIZE / UR10_SIZE)
        # the sections it lacks, said in the folder where a projector shows it (until 2026-12-05 only in a tooltip)
        note, hint = session.workspace.sections_missing, session.workspace.section.hint
        assert note.visible == (len(session.workspace.section.options) < 5) and note.content == (hint or "")
        await until(lambda: f"{session.drawing.root}/workspace" in client.received.nodes, what="the cloud on screen")
        # its top view, at the middle of the heights its tool reaches: the points of its own section, in the plane at
        # that height above its floor (the desktop arm's along its y), seen from above. Until 2026-12-07 the UR
        # family's alone, from its closed form, on a slider of the UR10's heights
        view, up = session.workspace, np.asarray(session.arm.up)
        if SECTIONS[2] not in view.section.options:
            assert session.arm.planar and "the whole cloud is already its top view" in note.content
        else:
            assert (view.height.min, view.height.max) == section_heights(session.arm)
            height = view.height.value
            assert view.height.min < height < view.height.max
            whole = view._cloud
            await client.set_gui("Section", SECTIONS[2])
            await until(lambda: view._cloud is not whole and view._cloud is not None and not view._clouds.busy,
                        what="the section")
            section = np.asarray(view._cloud.points, dtype=float)
            np.testing.assert_allclose(section @ up + session.arm.base_height, height / 1000.0, atol=4e-3)  # float16
            expected, _ = session.arm.sample_horizontal_section(height / 1000.0, 10_000, seed=0)
            np.testing.assert_allclose(section, expected, atol=4e-3)
            position, look_at = session.camera._framed_at
            assert (position - look_at) @ np.asarray(FROM_ABOVE) / np.linalg.norm(position - look_at) > 0.99
            # through the tool: the section at the tool's height (to 10 mm), with points about the tool's place in it
            tool = session.state.last.flange[:3, 3]
            at_tool = 10.0 * round(100.0 * float(tool @ up + session.arm.base_height))
            drawn = view._cloud
            await client.set_gui("Section through the tool", True)
            await until(lambda: view.height.value == at_tool and (view._cloud is not drawn or at_tool == height)
                        and not view._clouds.busy, what="the section through the tool")  # (drawn already: at its height)
            section = np.asarray(view._cloud.points, dtype=float)
            np.testing.assert_allclose(section @ up + session.arm.base_height, at_tool / 1000.0, atol=4e-3)
            across = np.linalg.norm(np.cross(section - tool, up), axis=1)  # each point's distance from the tool, seen from above
            assert across.min() < 0.05 * session.arm.reach_bound, (across.min(), session.arm.reach_bound)
        await client.close()

    asyncio.run(scenario())



@pytest.mark.parametrize("label", EVERY_ARM)
def test_the_branch_count_map_of_every_arm_is_its_ik_s(app, label):
    """The map shown counts, in each cell, the branches the arm's own IK finds within its limits, and it is drawn
    where those cells are: its plane in the scene, through every node above it. The planar elbow's is its own
    plane: until 2026-12-03 its map started in a vertical plane, where no cell is reached, and the camera turned
    to face it edge-on to the arm. Until 2026-12-04 an arm placed in the world by a node of its own had its map
    placed twice: the desktop arm's lay on its back 1.5 m above where it belonged (out of sight), and the Stanford
    arm's, once it stood on its pedestal, 0.41 m too high."""
    from ur10core.orientation import rotation_from_angle_axis
    from ur10core.workspace import branch_count_map
    from ur10teach.features.reach_map import PLANES, map_image

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        view = session.reach_map
        plane = "horizontal" if session.arm.name == "planar_elbow" else "vertical"  # its workspace is the plane z = 0
        assert PLANES[view.plane.value] == plane and (len(view.plane.options) == 1) == (plane == "horizontal")
        await client.set_gui("Show branch-count map", True)
        await until(lambda: view.image is not None and view.shown_key is not None and view.shown_key[1] == plane,
                    what="the map")
        expected = branch_count_map(session.arm, session.state.last.target, plane, view.resolution)
        assert expected.counts.max() > 0 and view.slots == len(session.arm.slot_labels)
        np.testing.assert_array_equal(view.image.image, map_image(expected.counts, view.slots))
        drawn = scene_pose(session.client.scene, view.image)
        world = session.drawing.world
        np.testing.assert_allclose(drawn[:3, 3], from_frame(world, expected.centre), atol=1e-6)
        np.testing.assert_allclose(drawn[:3, :2], world[:3, :3] @ np.stack([expected.u, expected.v], axis=1), atol=1e-6)
        # and one cell read back through the IK: its count is the number of branches that reach it within limits
        i, j = np.argwhere(expected.counts > 0)[0]
        T = session.state.last.target.copy()
        T[:3, 3] = expected.points()[i, j]
        solution = session.arm.ik(T)
        assert int(solution.within_limits.sum()) == int(expected.counts[i, j])
        # what the folder asks of the student holds for this arm: it says turning the gizmo changes the map only
        # where a turn the arm controls does (until 2026-12-05 also on arms whose gizmo does not turn, and on the
        # SCARA, whose yaw only turns its roll joint), and "tool turned as now" only where the arm keeps a turn
        question, arm = view.question.content, session.arm
        turns = {"pose": np.eye(3), "position and yaw": np.eye(3)[2:]}.get(arm.task, np.zeros((0, 3)))
        target = session.state.last.target
        coarse = branch_count_map(arm, target, plane, 40).counts

        def turned(axis):
            T = target.copy()
            T[:3, :3] = rotation_from_angle_axis(0.7, axis) @ T[:3, :3]
            return T

        changes = any((branch_count_map(arm, turned(axis), plane, 40).counts != coarse).any() for axis in turns)
        assert ("watch the rings change" in question) == changes, question
        assert ("its gizmo does not turn" in question) == session.ik_target.gizmo.disable_rotations == (arm.task == "position")
        title = "Reachable points" if arm.task == "position" else "Reachable with this orientation"
        assert client.gui[title]["type"] == "GuiFolderMessage"
        assert ("tool turned as now" in view.legend_text) == (arm.task == "pose")
        assert ("tool turned as now" in view.legend.content) == (arm.task == "pose")
        await client.close()

    asyncio.run(scenario())


async def overlapping_labels(session, also=()) -> tuple[list[str], list[tuple[str, str]]]:
    """Every placed 3D label of ``session`` (the names at the tool, then the drawing's pools), placed again in order
    as a camera move places them, and the pairs whose boxes overlap on the screen they are placed for; ``also``:
    labels that stay where they are, as (position (3,) in the scene, text, scale, anchor), checked against them."""
    from ur10teach.features.branch_labels import boxes, overlapping, place_in_order

    world = session.drawing.world
    pools = (session.names, *session.drawing.label_sets)
    placed, view = [], None
    camera = session.camera

    def framing() -> bool:  # a framing is under way: its position set, its look-at not yet (a view no one sees)
        return camera is not None and not camera._where_framed()

    # for one camera, the same before the placing and after the reading, and not one half-way through a framing:
    # a framing may still be arriving from the browser, and a camera move (a map turning the camera to face its
    # plane) places them again for the new one. It is waited for with the labels let go, since a framing's redraw
    # places them (on 2026-12-06, under load, a wait that held them never ended)
    deadline = time.monotonic() + HANG_TIMEOUT
    while True:
        assert time.monotonic() < deadline, "the camera never came to rest"
        await until(lambda: not framing(), what="the camera at rest")
        with session.names.placing:  # not placed again by the panel's refresher while they are read
            view, placed = pools[0].view(), []
            place_in_order(pools)
            for pool in pools:
                scale = pool.labels[0].font_screen_scale if pool.labels else 1.0
                for _, text, position in pool.placed:  # in the arm's base frame (the desktop arm's y is up)
                    seen = from_frame(world, position)
                    placed.append((text, boxes(view.to_screen(seen[None])[0], [text], scale)[0]))
            if view == pools[0].view() and not framing():
                break
    stay = [(text, boxes(view.to_screen(np.array([position], dtype=float))[0], [text], scale, anchor)[0])
            for position, text, scale, anchor in also]
    clashes = [(a, b) for k, (a, box_a) in enumerate(placed) for b, box_b in [*placed[k + 1:], *stay]
               if overlapping(box_a, box_b, gap=0.0)]
    return [text for text, _ in placed], clashes


@pytest.mark.parametrize("label", EVERY_ARM)
@pytest.mark.parametrize("rate", [0.1, 40.0])
def test_no_two_3d_labels_overlap_with_velocities_forces_and_ellipsoids_shown(app, label, rate):
    """The names of the velocity and force arrows and of the ellipsoids (which move with the arm) are placed apart,
    and then the DH axes' names, the branch numbers and the factors' names, keeping clear of them. Until
    2026-12-03 the names at the tool were drawn where they fell: "ω turning rate" over "z3" and "x3" on the
    cylindrical arm, "F = 50 N" over "x4" on the Stanford arm, "force" over "x5" on it, "force" over "v velocity"
    on the KR210, four names in one spot on the desktop arm, and for a slow joint (short arrows) "v velocity"
    over "ω turning rate" on every arm."""
    from ur10teach.features.branch_labels import JOIN

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        arm = session.arm
        for joint in (0, 1):
            await client.set_gui(rate_label(arm, joint), rate if arm.joint_types[joint] == "R" else 2.5 * rate)
        await client.set_gui("Show the torques", True)
        await client.set_gui(session.ellipsoids.enabled.label, True)  # both, named at the ends of their longest axes
        wanted = {"v velocity", "ω turning rate", "F = 50 N", "velocity", "force"}

        def named() -> set[str]:
            return {name for _, text, _ in session.names.placed for name in text.replace("\n", JOIN).split(JOIN)}

        await until(lambda: wanted <= named(), what="the names at the tool placed")
        placed, clashes = await overlapping_labels(session)
        assert len(placed) > len(wanted), "no labels to check"
        assert not clashes, f"overlapping: {clashes}"
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label, plane", [("SCARA (RRP + roll)", "horizontal, at the target's height"),
                                          ("UR10 (the app's arm)", "vertical, through the base axis and the target"),
                                          ("Cylindrical arm (RPP)", None), ("Planar elbow (2R)", None),
                                          ("3-DOF desktop arm", None)])
def test_the_branch_count_maps_legend_keeps_clear_of_the_clouds_and_of_every_placed_label(app, label, plane):
    """The map's legend names the top of the map, and the cloud's stands over the cloud: with both shown, on a
    projector. Until 2026-12-05 the map's was drawn where it fell, hanging from the map's top edge, and the cloud's
    over it on the cylindrical arm, the planar elbow and the desktop arm, unreadable (the tops of one reach); until
    2026-12-03 the placed labels did not keep clear of it ("x4" under it on the SCARA's horizontal map)."""

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        view, workspace = session.reach_map, session.workspace
        await client.set_gui("Lecture mode", True)
        if plane is not None:
            await client.set_gui("Plane", plane)
        await client.set_gui("Show branch-count map", True)
        await until(lambda: view.image is not None and view.shown_key is not None, what="the map")
        await client.set_gui(workspace.count.label, "10 k")
        await client.set_gui(workspace.enabled.label, True)  # framed last: the camera square-on to the cloud
        await until(lambda: workspace.legend_label is not None, what="the cloud")
        await until(lambda: view.legend_text in {text for _, text, _ in session.names.placed}, what="the map's legend")
        legend = workspace.legend_label
        cloud = (from_frame(session.drawing.world, legend.position), legend.text, legend.font_screen_scale, legend.anchor)
        placed, clashes = await overlapping_labels(session, also=[cloud])
        assert view.legend_text in placed and not clashes, f"overlapping: {clashes}"
        # the map gone, its legend goes with it
        await client.set_gui("Show branch-count map", False)
        await until(lambda: view.legend_text not in {text for _, text, _ in session.names.placed}, what="the legend gone")
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", EVERY_ARM)
def test_the_torque_map_and_the_cloud_are_framed_with_the_arm_and_the_legend_is_above_the_cloud(app, label):
    """The camera frames the arm with the torque map, as it does with the cloud, and the cloud's legend stands over
    it on the base axis. Until 2026-12-03 the torque map was not framed (the Stanford arm's camera sat inside it,
    its points drawn as blobs over the arm), and the desktop arm's cloud was framed, and its legend placed, as if
    its vertical were z (its y is up: the legend stood beside the cloud, over the arm's captions)."""
    from ur10teach.features.branch_labels import ScreenView, boxes, overlapping, screen_view
    from ur10teach.style import label_scale

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        world, statics, workspace = session.drawing.world, session.statics, session.workspace

        def seen(points):  # (n, 3) from the arm's base frame into the scene
            return from_frame(world, points)

        def in_view(points) -> bool:  # every one in front of this browser's camera and within its canvas
            view = ScreenView.of(session.client.camera)
            pixels, depth = view.to_screen(seen(points))
            return bool((depth > 0).all() and (np.abs(pixels[:, 0]) <= view.width / 2).all()
                        and (np.abs(pixels[:, 1]) <= view.height / 2).all())

        await client.set_gui("Lecture mode", True)
        await client.set_gui(workspace.count.label, "10 k")
        await client.set_gui(workspace.enabled.label, True)
        await until(lambda: workspace.legend_label is not None, what="the cloud")
        # sized for lecture mode as it comes (until 2026-12-03, only at the next change of the arm)
        await until(lambda: workspace.legend_label.font_screen_scale == label_scale(1.3, lecture=True), what="the big legend")
        cloud = seen(workspace._cloud.points.astype(float))
        legend, base = seen([workspace.legend_label.position, (0.0, 0.0, 0.0)])
        assert legend[2] > cloud[:, 2].max(), "the legend is not over the cloud"
        np.testing.assert_allclose(legend[:2], base[:2], atol=1e-9, err_msg="the legend is not on the base axis")
        def legend_in_view() -> bool:  # its whole box on the canvas (until 2026-12-03 the UR10's stood over its top)
            view, label = ScreenView.of(session.client.camera), workspace.legend_label
            box = boxes(view.to_screen(seen([label.position]))[0], [label.text], label.font_screen_scale, label.anchor)[0]
            return bool((np.abs(box[[0, 2]]) <= view.width / 2).all() and (np.abs(box[[1, 3]]) <= view.height / 2).all())

        await until(lambda: in_view(workspace._cloud.points[::20]) and legend_in_view(), what="the whole cloud and its legend in view")
        await client.set_gui(workspace.enabled.label, False)
        await client.set_gui("Show the torques", True)
        await client.set_gui(statics.mapped.label, True)
        # the map and its red ball, drawn one after the other on the map's own thread (until 2026-12-04 this read the
        # ball as soon as the map was there, and found None once in CI on a busy machine)
        seen_map: list = []

        def map_drawn() -> bool:  # the map and its ball from one moment (a second run may clear them between reads)
            both = statics._map, statics._worst
            seen_map[:] = [both] if None not in both else []
            return bool(seen_map)

        await until(map_drawn, what="the torque map and its largest ‖τ‖")
        drawn, (marker, name) = seen_map[0]
        assert drawn.point_size / session.drawing.size == pytest.approx(POINT_SIZE / UR10_SIZE)  # as the cloud's
        # its name stands on the red ball, up the arm's vertical: at its centre it hid the ball's upper half
        assert np.dot(name.position, session.arm.up) > marker.radius and np.cross(name.position, session.arm.up) == pytest.approx(0.0)
        await until(lambda: in_view(drawn.points[::20]), what="the whole torque map in view")
        # and the placed labels keep clear of its largest ‖τ‖ (hung under the map's red ball)
        view = screen_view(session.client)
        worst = boxes(view.to_screen(seen([np.add(marker.position, name.position)]))[0], [name.text], name.font_screen_scale,
                      name.anchor)[0]
        for pool in session.drawing.label_sets:
            pool.place()
        over = [text for pool in session.drawing.label_sets for _, text, position in pool.placed
                if overlapping(boxes(view.to_screen(seen([position]))[0], [text], pool.labels[0].font_screen_scale,
                                     "bottom-center")[0], worst, gap=0.0)]
        assert not over, f"over {name.text!r}: {over}"
        await client.close()

    asyncio.run(scenario())


@pytest.mark.parametrize("label", EVERY_ARM)
def test_no_3d_label_sits_in_the_gizmos_centre(app, label):
    """The desktop arm names its tool in 3D, and its IK gizmo stands there: "tool" was drawn under the gizmo's
    handles (until 2026-12-05). Every label placed keeps clear of the gizmo's centre, as of another label."""
    from ur10teach.features.branch_labels import boxes, overlapping

    async def scenario():
        client = await ViserClient(url(app)).connect()
        session = await pick(app, client, label)
        world = session.drawing.world
        await until(lambda: session.drawing.label_sets[-1].placed, what="the labels placed")
        centre = from_frame(world, np.asarray(session.ik_target.gizmo.position, dtype=float))
        for pool in session.drawing.label_sets:
            pool.place()
            view = pool.view()
            gizmo = np.tile(view.to_screen(centre[None])[0][0], 2) + [-15.0, -15.0, 15.0, 15.0]  # where its handles cross
            over = [label for _, label, position in pool.placed
                    if overlapping(boxes(view.to_screen(from_frame(world, position)[None])[0], [label],
                                         pool.labels[0].font_screen_scale, "bottom-center")[0], gizmo, gap=0.0)]
            assert not over, f"in the gizmo's centre: {over}"
        await client.close()

    asyncio.run(scenario())
