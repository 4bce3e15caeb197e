"""End to end in real headless Chromium: the page a student opens, driven by mouse and keyboard.

Each test checks both sides: what the server's state became, and what the page shows.
"""

from __future__ import annotations

import numpy as np
import pytest

from .browser_support import SMALL_VIEWPORT, canvas_pixels, changed, dom_id, project, set_checkbox, step_slider, text_field, wait_for

pytestmark = pytest.mark.browser


def test_page_shows_the_arm_and_its_panel(open_page, app):
    page, session = open_page()
    assert page.get_by_text("UR10 kinematics (course)").count() == 1
    assert page.get_by_text("shoulder right, elbow down, wrist not flipped").count() >= 1
    pixels = canvas_pixels(page)
    # the charcoal joint caps and the aluminium arm are on screen, not just the white page
    charcoal = (pixels.max(axis=-1) < 110) & (pixels.max(axis=-1) - pixels.min(axis=-1) < 20)
    assert charcoal.sum() > 500, "no charcoal joint caps rendered"
    np.testing.assert_allclose(np.degrees(session.state.q), [30, 45, 26, 50, 60, 80])


def test_moving_a_joint_slider(open_page, app):
    page, session = open_page()
    thumb = page.locator(f"{dom_id(session.joints.sliders[0])} [role=slider]")
    step_slider(page, session.joints.sliders[0], "ArrowRight", 35.0)  # 0.1° steps from 30°
    wait_for(lambda: abs(np.degrees(session.state.q[0]) - 35.0) < 1e-6, what="θ1 to reach 35°")
    # the IK target followed the flange (drawn a moment after the state changed), and the readout shows the new pose
    wait_for(lambda: np.allclose(session.ik_target.gizmo.position, session.state.last.flange[:3, 3], atol=1e-6),
             what="the gizmo on the new flange")
    assert thumb.get_attribute("aria-valuenow") == "35"
    wait_for(lambda: page.get_by_text("base 35.00°", exact=False).count() > 0, what="the joint summary")


def test_dragging_the_ik_target(open_page, app):
    page, session = open_page()
    session.ik_target.show_ghosts.value = False  # nothing between the mouse and the gizmo
    page.wait_for_timeout(300)
    before = session.state.q
    box = page.locator("canvas").first.bounding_box()
    flange = session.state.last.flange
    size = session.ik_target.gizmo.scale  # the arrows' length, sized to the arm
    for axis, share in [(0, 0.75), (0, 0.6), (1, 0.75), (2, 0.75), (0, 0.9)]:  # grab one of the arrows
        u, v = project(session.client.camera, flange[:3, 3] + share * size * flange[:3, axis], box)
        page.mouse.move(u, v)
        page.mouse.down()
        for step in range(1, 11):
            page.mouse.move(u - 3 * step, v + 2 * step)
            page.wait_for_timeout(60)
        page.mouse.up()
        page.wait_for_timeout(300)
        if session.state.last.cause == "target":
            break
    wait_for(lambda: session.state.last.cause == "target", what="the drag to reach the server")
    snapshot = session.state.last
    assert snapshot.reachable
    assert np.abs(snapshot.q - before).max() > 1e-3, "the arm did not follow the target"
    assert snapshot.slot == 4, "the arm jumped to another branch"
    np.testing.assert_allclose(session.arm.fk(snapshot.q), snapshot.target, atol=1e-9)
    # the ghosts of the new target's branches were posed from the same solution
    ghost = session.scene_views.branches.ghosts[5]  # link 6 (the ghosts start at link 1)
    snapshot = session.state.last
    valid = snapshot.solution.valid
    wait_for(lambda: np.allclose(ghost.batched_positions[valid], snapshot.ghost_frames[valid, 6, :3, 3], atol=1e-5),
             what="the ghosts drawn for the drag's last solution")


def test_switching_branch_from_the_list(open_page, app):
    page, session = open_page()
    page.get_by_role("button", name="3", exact=True).click()
    wait_for(lambda: session.state.last.slot == 2, what="branch 3")
    snapshot = session.state.last
    np.testing.assert_allclose(session.arm.fk(snapshot.q), snapshot.target, atol=1e-9)
    wait_for(lambda: page.get_by_text("3: shoulder left, elbow up, wrist flipped").count() > 0, what="the status line")


def test_singularity_overlay(open_page, app):
    page, session = open_page()
    set_checkbox(page, session.singularity.enabled, True)
    wait_for(lambda: session.singularity.enabled.value and session.scene_views.overlay.cylinder.visible, what="the overlay")
    wait_for(lambda: page.locator("math").count() > 0 and page.locator("math").first.is_visible(), what="det J as MathML")
    assert "234" in page.locator("math").first.text_content()
    page.get_by_role("button", name="wrist", exact=True).click()
    wait_for(lambda: session.singularity.levels[2] == 0.0, what="the wrist gauge to drop to zero")
    assert abs(session.state.last.factors[2]) < 1e-12
    assert session.singularity.colors[2] == (220, 38, 38)
    wait_for(lambda: page.get_by_text("s5 = +0.0000").count() > 0, what="the wrist factor readout")
    bar = page.locator(".gauge-wrist").first
    assert bar.evaluate("e => getComputedStyle(e).backgroundColor") == "rgb(220, 38, 38)"
    assert bar.evaluate("e => e.style.width") in ("0%", "0.0%")


def test_workspace_cloud(open_page, app):
    page, session = open_page()
    before = canvas_pixels(page)
    set_checkbox(page, session.workspace.enabled, True)
    wait_for(lambda: session.workspace._cloud is not None, timeout=30, what="the cloud")
    assert len(session.workspace._cloud.points) == 200_000
    page.wait_for_timeout(2500)
    after = canvas_pixels(page)
    assert changed(before, after) > 0.05, "the point cloud did not show up"
    wait_for(lambda: page.get_by_text("Colour = manipulability |det J|").count() > 0, what="the legend")
    set_checkbox(page, session.workspace.enabled, False)
    wait_for(lambda: session.workspace._cloud is None, what="the cloud to go")


def test_bad_typed_angles_are_refused_in_the_browser(open_page, app):
    page, session = open_page()
    before = session.state.q
    field = text_field(page, session.joints.typed)
    field.fill("30, 45, abc, 50, 60, 80")
    field.press("Enter")
    page.wait_for_timeout(200)
    page.locator(dom_id(session.joints.apply_typed)).click()
    wait_for(lambda: page.get_by_text("'abc' is not a number").count() > 0, what="the refusal message")
    assert page.get_by_text("Not accepted").count() > 0
    np.testing.assert_array_equal(session.state.q, before)
    # and the app still works for this student
    field.fill("10, 20, 30, 40, 50, 60")
    field.press("Enter")
    page.wait_for_timeout(200)
    page.locator(dom_id(session.joints.apply_typed)).click()
    wait_for(lambda: np.allclose(np.degrees(session.state.q), [10, 20, 30, 40, 50, 60]), what="the typed angles")


def test_two_students_have_their_own_arms(open_page, app):
    page_a, session_a = open_page(viewport=SMALL_VIEWPORT)
    page_b, session_b = open_page(known=1, viewport=SMALL_VIEWPORT)
    assert session_a is not session_b
    step_slider(page_a, session_a.joints.sliders[1], "ArrowLeft", 43.0)
    wait_for(lambda: abs(np.degrees(session_a.state.q[1]) - 43.0) < 1e-6, what="student A's shoulder")
    np.testing.assert_allclose(np.degrees(session_b.state.q), [30, 45, 26, 50, 60, 80])
    page_b.close()
    wait_for(lambda: len(app.sessions) == 1, what="student B's session to be freed")
    assert session_b.closed
